//! Figure 11's outputs (the figure itself is `endstop::paper::figures::fig11`): the numbers of
//! the summary, the book's tables (the levels, the claims) and the spectra of one run.

use anyhow::Result;
use endstop::paper::ensembles::WidthReading;
use endstop::paper::figures::fig11;
use endstop::paper::setups::ParamSet;

use crate::io::md::Table;
use crate::reports::record_io::{self, pm, sa_label, spread_str};
use crate::Experiment;

/// Writes everything of one run of Figure 11: the numbers of the summary, the book's tables
/// and the spectra (Parquet and plot).
pub fn write(mut exp: Experiment, run: &fig11::Run) -> Result<()> {
    let mut md = record_io::p1_tables_md(run, "");
    md.push_str("**Claims**\n\n");
    let mut t = Table::new([
        "set",
        "impacts in all records",
        "3 dB width ratio 3.49e-4 / 4.42e-6",
        "half-amplitude ratio",
        "single records: 3 dB ratio mean ± std [5 %, 95 %]",
    ]);
    exp.number("linear_theory_bw3db_hz", run.linear.bw3db_hz());
    exp.number("linear_theory_bw6db_hz", run.linear.bw6db_hz());
    for set in ParamSet::BOTH {
        let f = fig11::findings(run, set);
        t.row([
            set.to_string(),
            f.impacts.to_string(),
            pm(f.ratio.0, f.ratio.1),
            pm(f.ratio_half_amplitude.0, f.ratio_half_amplitude.1),
            spread_str(&f.single_ratio, 3),
        ]);
        exp.number(&format!("impacts_{set}"), f.impacts as f64);
        for l in run.set(set) {
            let tag = sa_label(l.sa());
            for r in WidthReading::ALL {
                let w = r.mean_width(&l.ens).estimate;
                exp.number(&format!("{}_{tag}_{set}_hz", r.tag()), w);
            }
            exp.number(&format!("efficiency_{tag}_{set}"), l.ens.efficiency.mean);
            exp.number(&format!("x_peak_{tag}_{set}_m"), l.ens.x_peak_m);
        }
    }
    md.push_str(&t.render());
    exp.write_numbers_md(&md)?;

    // As the paper: log y over 600-2000 Hz; the calibrated set is dashed.
    record_io::write_p1_spectra(
        &exp,
        "fig11",
        "Figure 11: prototype 1 at 30 V, output power PSD (both loads, one-sided)",
        run,
        (600.0, 2000.0),
        true,
    )?;
    exp.finish()
}

//! Figure 12: output power PSDs of prototype 1 at 30 V at 7.4e-3, 1.31e-2 and 2.85e-2 g²/Hz,
//! where the mass hits the stops, under the published and the calibrated parameter sets
//! (claim F12). The figure is stated in `endstop::paper::fig12`; this binary writes its
//! outputs.

use endstop_experiments as common;

use anyhow::Result;
use common::broadband_io::{self as bbio, pm, sa_label, spread_str};
use common::md::Table;
use common::Experiment;
use endstop::paper::claims::Claims;
use endstop::paper::ensembles::{level_key, WidthReading, P1_SETS};
use endstop::paper::fig12::{self, FIG12_LEVELS, HIGH, LOW};
use endstop::study::ensemble::DEFAULT_SEED;

fn main() {
    common::run_main("fig12", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig12");
    exp.seed = Some(DEFAULT_SEED);
    let claims = Claims::bundled()?;
    let (published, calibrated) = bbio::prototype1_sets(&mut exp)?;
    let total = 2 * FIG12_LEVELS.len() * fig12::FIG12_REALISATIONS;
    let run = common::with_progress(total, "fig12", |tick| {
        fig12::run(&published, &calibrated, tick)
    })?;
    exp.claims(fig12::claims(&run, &claims));

    let mut md = bbio::p1_tables_md(
        &run,
        " (fitted to Figure 8's onset by the narrowband calibration)",
    );
    md.push_str("**Claims and the two readings of \"3 dB\"**\n\n");
    let mut t = Table::new([
        "set",
        "reading",
        "width at 7.4e-3 (Hz)",
        "width at 2.85e-2 (Hz)",
        "ratio",
        "single records: ratio mean ± std [5 %, 95 %]",
    ]);
    exp.number("linear_theory_bw3db_hz", run.linear.bw3db_hz());
    exp.number("linear_theory_bw6db_hz", run.linear.bw6db_hz());
    let (lo, hi) = (level_key(FIG12_LEVELS[LOW]), level_key(FIG12_LEVELS[HIGH]));
    for (s, set) in P1_SETS.iter().enumerate() {
        for reading in WidthReading::ALL {
            let f = fig12::findings(&run, s, reading);
            t.row([
                set.to_string(),
                reading.label().to_string(),
                pm(f.low.estimate, f.low.ci95),
                pm(f.high.estimate, f.high.ci95),
                pm(f.ratio.0, f.ratio.1),
                spread_str(&f.single_ratio, 3),
            ]);
            let tag = reading.tag();
            exp.number(&format!("{tag}_{lo}_{set}_hz"), f.low.estimate);
            exp.number(&format!("{tag}_{hi}_{set}_hz"), f.high.estimate);
            exp.number(&format!("{tag}_ratio_{set}"), f.ratio.0);
        }
        for l in run.set(s) {
            let tag = sa_label(l.sa());
            exp.number(&format!("efficiency_{tag}_{set}"), l.ens.efficiency.mean);
            exp.number(
                &format!("contact_fraction_{tag}_{set}"),
                l.ens.contact_fraction.mean,
            );
        }
    }
    md.push_str(&t.render());
    exp.write_numbers_md(&md)?;

    // As the paper: log y over 500-3000 Hz; the calibrated set is dashed.
    bbio::write_p1_spectra(
        &exp,
        "fig12",
        "Figure 12: prototype 1 at 30 V, output power PSD (both loads, one-sided)",
        &run,
        (500.0, 3000.0),
        false,
    )?;
    exp.finish()
}

//! Figure 12's outputs (the figure itself is `endstop::paper::figures::fig12`): the numbers of
//! the summary, the book's tables (the levels, the claims under both readings of "3 dB", the
//! width against the Welch segment length) and the spectra of one run.

use anyhow::Result;
use endstop::paper::ensembles::{level_key, WidthReading};
use endstop::paper::figures::fig12::{self, FIG12_LEVELS, HIGH, LOW};
use endstop::paper::resolution::{self, LEVELS, LINEAR, NPERSEGS};
use endstop::paper::setups::ParamSet;

use crate::io::md::Table;
use crate::reports::record_io::{self, pm, sa_label, spread_str};
use crate::{fmt_sig, Experiment};

/// Writes everything of one run of Figure 12 with the width-resolution study of its published
/// set (`study`): the numbers of the summary, the book's tables and the spectra (Parquet and
/// plot).
pub fn write(mut exp: Experiment, run: &fig12::Run, study: &resolution::Study) -> Result<()> {
    let mut md = record_io::p1_tables_md(
        run,
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
    for set in ParamSet::BOTH {
        for reading in WidthReading::ALL {
            let f = fig12::findings(run, set, reading);
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
        for l in run.set(set) {
            let tag = sa_label(l.sa());
            exp.number(&format!("efficiency_{tag}_{set}"), l.ens.efficiency.mean);
            exp.number(
                &format!("contact_fraction_{tag}_{set}"),
                l.ens.contact_fraction.mean,
            );
        }
    }
    md.push_str(&t.render());
    md.push_str(&resolution_md(&mut exp, study));
    exp.write_numbers_md(&md)?;

    // As the paper: log y over 500-3000 Hz; the calibrated set is dashed.
    record_io::write_p1_spectra(
        &exp,
        "fig12",
        "Figure 12: prototype 1 at 30 V, output power PSD (both loads, one-sided)",
        run,
        (500.0, 3000.0),
        false,
    )?;
    exp.finish()
}

/// The width-resolution study `s` ([`resolution`]): the half-power width of the published
/// set at Figure 11's lowest (linear) level and at 7.4e-3 for every segment length, against
/// the linear theory's exact width.
fn resolution_md(exp: &mut Experiment, s: &resolution::Study) -> String {
    let fig = resolution::FIGURES_NPERSEG;
    exp.number("linear_width_exact_hz", s.exact_hz);
    exp.number("width_estimator_bias_hz", s.bias_hz(fig));
    let mut md = format!(
        "\n**The width and the Welch segment length** (published set, the first {} records of \
         each level; the linear theory's exact half-power width is {} Hz; bias = width at \
         {} g²/Hz, where no record touches a stop, less the exact width):\n\n",
        s.records,
        fmt_sig(s.exact_hz, 4),
        sa_label(LEVELS[LINEAR]),
    );
    let mut t = Table::new([
        "samples per segment",
        "bin (Hz)",
        "width, linear level (Hz)",
        "estimator bias (Hz)",
        "width at 7.4e-3 (Hz)",
        "7.4e-3 less the bias (Hz)",
    ]);
    for (n, &nperseg) in NPERSEGS.iter().enumerate() {
        let (lin, high) = (s.row(LINEAR, n), s.row(1, n));
        let mark = if n == fig { " (figures)" } else { "" };
        t.row([
            format!("{nperseg}{mark}"),
            fmt_sig(lin.bin_hz, 3),
            pm(lin.width.estimate, lin.width.ci95),
            fmt_sig(s.bias_hz(n), 2),
            pm(high.width.estimate, high.width.ci95),
            fmt_sig(high.width.estimate - s.bias_hz(n), 4),
        ]);
    }
    md.push_str(&t.render());
    md.push_str(&format!(
        "\nAt the figures' segment the estimator reads the linear width {} Hz ({} %) high; \
         the width at 7.4e-3 less that bias is {} Hz, {} Hz above the exact linear width.\n",
        fmt_sig(s.bias_hz(fig), 2),
        fmt_sig(100.0 * s.bias_hz(fig) / s.exact_hz, 2),
        fmt_sig(s.row(1, fig).width.estimate - s.bias_hz(fig), 4),
        fmt_sig(
            s.row(1, fig).width.estimate - s.bias_hz(fig) - s.exact_hz,
            2
        ),
    ));
    md
}

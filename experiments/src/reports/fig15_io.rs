//! Figure 15's outputs, written by its binary and by Figure 14's (whose run holds the same
//! records: `endstop::paper::prototype2_records`): the parquet files, plots, summary and the
//! book's numbers of one run of `endstop::paper::figures::fig15`.

use anyhow::Result;
use endstop::num::stats::{ecdf, pairwise_ratios, Spread};
use endstop::paper::claims::{keys, Claims};
use endstop::paper::ensembles::WidthReading;
use endstop::paper::figures::fig15::{self, Fig15, Findings, L034, L055, RATIO_CLAIM};
use endstop::paper::setups::ParamSet;
use endstop::paper::Figure;
use endstop::study::ensemble::DEFAULT_SEED;

use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::record_io::{self, pm, sa_label, spread_str, Level};
use crate::{fmt_sig, Experiment, LoadedDevice};

/// Writes Figure 15's outputs for `run`, made from the parameter file `prototype2`, as the
/// experiment `exp` (started by the caller: its time is the caller's to count).
pub fn write(
    mut exp: Experiment,
    prototype2: &LoadedDevice,
    run: &fig15::Run,
    claims: &Claims,
) -> Result<()> {
    exp.seed = Some(DEFAULT_SEED);
    exp.uses(prototype2, ParamSet::Published.label());
    exp.claims(Fig15::claims(run, claims)?);
    let f = fig15::findings(run, claims);
    let paper_ratio = claims
        .claim(RATIO_CLAIM)
        .map_or(f64::NAN, |c| c.paper.to_f64());
    let levels = &run.levels;
    let lin = &run.linear;

    exp.number("linear_theory_bw3db_hz", lin.bw3db_hz());
    exp.number("linear_theory_bw6db_hz", lin.bw6db_hz());
    exp.number(
        "linear_theory_peak_hz",
        lin.half_power.map_or(f64::NAN, |b| b.peak_hz),
    );
    exp.number("upper_edge_shift_1p69e-3_hz", f.upper_shift_hz);
    exp.number("lower_edge_shift_1p69e-3_hz", f.lower_shift_hz);
    exp.number("peak_single_record_mean_0p34e-3_hz", f.peak_single.mean);
    for (l, w) in levels.iter().zip(&f.widths) {
        let t = sa_label(l.sa());
        exp.number(&format!("bw3db_{t}_hz"), w.estimate);
        let w6 = WidthReading::HalfAmplitude.mean_width(&l.ens);
        exp.number(&format!("bw6db_{t}_hz"), w6.estimate);
        exp.number(&format!("efficiency_{t}"), l.ens.efficiency.mean);
        exp.number(
            &format!("contact_fraction_{t}"),
            l.ens.contact_fraction.mean,
        );
        let s = l.ens.single_bw3db_spread();
        exp.number(&format!("single_bw3db_{t}_mean_hz"), s.mean);
        exp.number(&format!("single_bw3db_{t}_std_hz"), s.std);
        exp.number(&format!("single_bw3db_{t}_p05_hz"), s.p05);
        exp.number(&format!("single_bw3db_{t}_p95_hz"), s.p95);
    }
    exp.number("bw6db_ratio_0p55e-3_over_0p34e-3", f.ratio_half_amplitude.0);
    exp.number("single_ratio_0p55_mean", f.single_ratio.mean);
    exp.number("single_ratio_0p55_p05", f.single_ratio.p05);
    exp.number("single_ratio_0p55_p95", f.single_ratio.p95);
    exp.number(
        "single_ratio_0p55_fraction_at_least_3p7",
        f.pairs_at_least_paper,
    );
    exp.number(
        "single_ratio_0p55_fraction_within_tolerance",
        f.pairs_within_tolerance,
    );
    exp.number(
        "single_ratio_0p55_matlab_fraction_at_least_3p7",
        f.pairs_at_least_paper_matlab,
    );

    exp.write_numbers_md(&numbers_md(run, &f, paper_ratio))?;
    // The widths the chapters' prose quotes (Figures 14 and 15), each a snippet included
    // inline: the linear theory's and the ensemble's at the lowest level.
    crate::write_atomic(
        &exp.book_dir.join("bw_linear.md"),
        format!("{} Hz", fmt_sig(lin.bw3db_hz(), 3)).as_bytes(),
    )?;
    if let Some(w) = f.widths.first() {
        crate::write_atomic(
            &exp.book_dir.join("bw_lowest.md"),
            format!(
                "{} Hz at {}",
                fmt_sig(w.estimate, 3),
                sa_label(levels[0].sa())
            )
            .as_bytes(),
        )?;
    }
    record_io::write_level_tables(
        &exp,
        Fig15::NAME,
        levels,
        Some((500.0, 1000.0)),
        ParamSet::Published.label(),
    )?;

    // Figure 15 as in the paper: 500-1000 Hz, log y.
    let plot = record_io::spectra_plot(
        "Figure 15: prototype 2 at 15 V, output power PSD (both loads, one-sided)",
        levels,
        (500.0, 1000.0),
        (1e-8, 1e-2),
        true,
    );
    exp.write_plot(&plot)?;
    write_single_record_plot(&exp, &levels[L034])?;
    let paper_bw_hz = claims
        .claim(keys::F15A_BW)
        .map_or(f64::NAN, |c| c.paper.to_f64());
    write_spread_plots(&exp, run, &f, paper_bw_hz, paper_ratio)?;
    exp.finish()
}

/// The book's numbers: settings, tables, claims and the single-record robustness table.
fn numbers_md(run: &fig15::Run, f: &Findings, paper_ratio: f64) -> String {
    let levels = &run.levels;
    let l34 = &levels[L034];
    let lin = &run.linear;
    let mut md = record_io::settings_md(l34);
    md.push_str(&format!(
        "The alternative segmenting (MATLAB's `pwelch` default) uses {} samples per segment \
         ({} Hz bins), 8 segments per record.\n\n",
        l34.ens.spec.alt_welch.map_or(0, |c| c.nperseg),
        fmt_sig(
            l34.ens.records[0]
                .alt
                .as_ref()
                .map_or(f64::NAN, |a| a.0.df()),
            3
        ),
    ));
    md.push_str("**Power and contact**\n\n");
    md.push_str(&record_io::power_table(levels).render());
    md.push_str("\n**Peak and widths of the ensemble-mean output PSD** (CI: delete-one jackknife over the records, 95 %), and the spread of the same widths read from single records\n\n");
    md.push_str(&record_io::width_table(levels).render());
    md.push_str(&format!(
        "\nLinearised theory (eqs 11-17, no end-stops; the same at every level): peak {} Hz, \
         3 dB width {} Hz, half-amplitude width {} Hz. Peak of single records at 0.34e-3: mean \
         {} Hz.\n",
        fmt_sig(lin.half_power.map_or(f64::NAN, |b| b.peak_hz), 4),
        fmt_sig(lin.bw3db_hz(), 3),
        fmt_sig(lin.bw6db_hz(), 3),
        pm(f.peak_single.mean, f.peak_single.ci95),
    ));
    let w34 = &f.widths[L034];
    md.push_str(&format!(
        "\n**Claims** (published set): F15-a peak {} Hz (uncertainty: half a bin with the CI of \
         the single-record peaks), 3 dB width {} Hz; F15-b ratio 0.55e-3 / 0.34e-3 of the \
         mean-PSD widths {} (half-amplitude reading: {}); F15-c: between 0.34e-3 and 1.69e-3 \
         the upper half-power edge moves up by {} Hz and the lower edge down by {} Hz, so the \
         widening is towards higher frequencies: **{}**.\n",
        fmt_sig(f.peak_hz, 4),
        pm(w34.estimate, w34.ci95),
        pm(f.ratio.0, f.ratio.1),
        pm(f.ratio_half_amplitude.0, f.ratio_half_amplitude.1),
        fmt_sig(f.upper_shift_hz, 3),
        fmt_sig(f.lower_shift_hz, 3),
        if f.widening_up { "yes" } else { "no" },
    ));
    md.push_str("\n**Robustness: what one 10 s record gives.** Each width is read from a single record's Welch estimate, as the paper did; the ratio is formed from one record at each level, over all 16 x 16 pairs of independent records.\n\n");
    let mut t = Table::new([
        "quantity",
        "ensemble-mean PSD",
        "single records (2^16 segments): mean ± std [5 %, 95 %]",
        "median",
        "single records, MATLAB default (8 segments)",
    ]);
    for (l, w) in levels.iter().zip(&f.widths) {
        let s = l.ens.single_bw3db_spread();
        t.row([
            format!("3 dB width at {} (Hz)", sa_label(l.sa())),
            fmt_sig(w.estimate, 3),
            spread_str(&s, 3),
            fmt_sig(s.median, 3),
            spread_str(&Spread::of(&l.ens.single_alt_bw3db_hz()), 3),
        ]);
    }
    let ratio_row = |what: &str, ratio: f64, s: &Spread, matlab: Option<&Spread>| {
        [
            what.to_string(),
            fmt_sig(ratio, 3),
            spread_str(s, 3),
            fmt_sig(s.median, 3),
            matlab.map_or(String::new(), |m| spread_str(m, 3)),
        ]
    };
    t.row(ratio_row(
        "3 dB ratio 0.55e-3 / 0.34e-3",
        f.ratio.0,
        &f.single_ratio,
        Some(&f.single_ratio_matlab),
    ));
    t.row(ratio_row(
        "3 dB ratio 1.69e-3 / 0.34e-3",
        f.ratio_169.0,
        &f.single_ratio_169,
        None,
    ));
    t.row(ratio_row(
        "half-amplitude ratio 0.55e-3 / 0.34e-3",
        f.ratio_half_amplitude.0,
        &f.single_ratio_half_amplitude,
        None,
    ));
    md.push_str(&t.render());
    // A share of the pairs in words: "none" rather than "a fraction 0".
    let share = |x: f64| {
        if x == 0.0 {
            "none".to_string()
        } else {
            format!("a fraction {}", fmt_sig(x, 2))
        }
    };
    md.push_str(&format!(
        "\nOf the single-record pairs, {} gives a 3 dB ratio of at least the paper's \
         {paper_ratio}, and {} falls within the claims file's tolerance of it; with MATLAB's \
         default segmenting {} reaches {paper_ratio}.\n",
        share(f.pairs_at_least_paper),
        share(f.pairs_within_tolerance),
        share(f.pairs_at_least_paper_matlab),
    ));
    md
}

/// One record at 0.34e-3 under both segmentings, against the ensemble mean and the theory.
fn write_single_record_plot(exp: &Experiment, l: &Level) -> Result<()> {
    let (lo, hi) = (630.0, 715.0);
    let pts = |p: &endstop::signal::Psd| -> Vec<(f64, f64)> {
        p.freq_hz
            .iter()
            .zip(&p.density)
            .filter(|(f, _)| (lo..=hi).contains(*f))
            .map(|(f, d)| (*f, d * 1e6))
            .collect()
    };
    let r0 = &l.ens.records[0];
    let mut series = vec![Series::new(
        &format!("mean of {} records, 2^16 segments", l.ens.records.len()),
        pts(&l.ens.mean_spectrum.total),
        PALETTE[0],
        Style::Line,
    )];
    series.push(Series::new(
        "record 0, 2^16 segments (29)",
        pts(&r0.spectrum.total),
        PALETTE[1],
        Style::LinePoints,
    ));
    if let Some((alt, _)) = &r0.alt {
        series.push(Series::new(
            "record 0, MATLAB default (8 segments)",
            pts(alt),
            PALETTE[2],
            Style::Line,
        ));
    }
    let f: Vec<f64> = (0..=850).map(|i| lo + 0.1 * i as f64).collect();
    let lin = l.linear_psd(&f);
    series.push(Series::new(
        "linear theory",
        f.iter()
            .zip(&lin.density)
            .map(|(f, d)| (*f, d * 1e6))
            .collect(),
        PALETTE[6],
        Style::Dashed,
    ));
    let plot = LinePlot::new(
        &format!(
            "Prototype 2 at {} g²/Hz: one 10 s record under two Welch segmentings",
            sa_label(l.sa())
        ),
        "frequency [Hz]",
        "output power PSD [uW/Hz]",
        series,
    )
    .x(lo, hi)
    .y(1e-6, 1e-2)
    .log(false, true)
    .legend(LegendPos::UpperRight);
    exp.write_extra_plot("fig15_single_record", &plot)
}

/// Empirical distributions of the single-record 3 dB widths and of the ratio.
fn write_spread_plots(
    exp: &Experiment,
    run: &fig15::Run,
    f: &Findings,
    paper_bw_hz: f64,
    paper_ratio: f64,
) -> Result<()> {
    let levels = &run.levels;
    let mut series = Vec::new();
    for ((i, l), w) in levels.iter().enumerate().zip(&f.widths) {
        series.push(Series::new(
            &format!("single records, {} g²/Hz", sa_label(l.sa())),
            ecdf(&l.ens.single_bw3db_hz()),
            PALETTE[i],
            Style::LinePoints,
        ));
        let w = w.estimate;
        series.push(Series::new(
            "",
            vec![(w, 0.0), (w, 1.0)],
            PALETTE[i],
            Style::Dashed,
        ));
    }
    series.push(Series::new(
        &format!("paper at 0.34e-3 ({paper_bw_hz} Hz)"),
        vec![(paper_bw_hz, 0.0), (paper_bw_hz, 1.0)],
        PALETTE[6],
        Style::Dashed,
    ));
    let xmax = levels
        .iter()
        .flat_map(|l| l.ens.single_bw3db_hz())
        .chain(f.widths.iter().map(|w| w.estimate))
        .filter(|x| x.is_finite())
        .fold(0.0, f64::max);
    let plot = LinePlot::new(
        "Prototype 2: 3 dB width read from one 10 s record (dashed: width of the ensemble mean)",
        "3 dB width of the output power PSD [Hz]",
        "fraction of records at or below",
        series,
    )
    .x(0.0, 1.05 * xmax)
    .y(0.0, 1.0)
    .legend(LegendPos::LowerRight);
    exp.write_extra_plot("fig15_width_spread", &plot)?;

    let (l34, l55) = (&levels[L034].ens, &levels[L055].ens);
    let r = pairwise_ratios(&l55.single_bw3db_hz(), &l34.single_bw3db_hz());
    let r_m = pairwise_ratios(&l55.single_alt_bw3db_hz(), &l34.single_alt_bw3db_hz());
    let mean_ratio = f.ratio.0;
    let xmax = r
        .iter()
        .chain(&r_m)
        .copied()
        .filter(|x| x.is_finite())
        .fold(paper_ratio, f64::max);
    let plot = LinePlot::new(
        "Prototype 2: 3 dB width at 0.55e-3 over that at 0.34e-3, one record at each level",
        "bandwidth ratio",
        "fraction of record pairs at or below",
        vec![
            Series::new("2^16 segments", ecdf(&r), PALETTE[0], Style::Line),
            Series::new(
                "MATLAB default (8 segments)",
                ecdf(&r_m),
                PALETTE[2],
                Style::Line,
            ),
            Series::new(
                "ensemble-mean PSDs",
                vec![(mean_ratio, 0.0), (mean_ratio, 1.0)],
                PALETTE[1],
                Style::Dashed,
            ),
            Series::new(
                &format!("paper ({paper_ratio})"),
                vec![(paper_ratio, 0.0), (paper_ratio, 1.0)],
                PALETTE[6],
                Style::Dashed,
            ),
        ],
    )
    .x(0.0, 1.05 * xmax)
    .y(0.0, 1.0)
    .legend(LegendPos::LowerRight);
    exp.write_extra_plot("fig15_ratio_spread", &plot)
}

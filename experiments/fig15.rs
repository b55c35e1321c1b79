//! Figure 15: output power PSDs of prototype 2 at 15 V (linear k_im of eq 19, b_im = 0.4 N s/m)
//! at Sa = 0.34e-3, 0.55e-3 and 1.69e-3 g²/Hz (claims F15-a, F15-b, F15-c), and the sampling
//! distribution of the bandwidths and of their ratio when each is read from one 10 s record.

use endstop_experiments as common;

use endstop_experiments::broadband_io as bbio;

use anyhow::Result;
use bbio::{ecdf, find, pm, sa_label, spread_str, Level};
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device, Experiment};
use endstop::num::stats::ratio_spread;
use endstop::num::stats::Spread;
use endstop::paper::ensembles::P2_BAND_HZ;
use endstop::paper::ensembles::P2_NPERSEG;
use endstop::study::ensemble::DEFAULT_SEED;

/// The paper's levels (g²/Hz) and records per level (see `endstop::broadband`).
const LEVELS: [f64; 3] = endstop::paper::fig15::FIG15_LEVELS;
const REALISATIONS: usize = endstop::paper::fig15::FIG15_REALISATIONS;

fn main() {
    common::run_main("fig15", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig15");
    exp.seed = Some(DEFAULT_SEED);
    let p2 = load_device("prototype2")?;
    exp.uses(&p2, "published");
    let dev = endstop::paper::setups::prototype2_setup(&p2.device);
    let paper_bw_hz = bbio::paper_value("F15-a", "bw_0p34e-3_hz");
    let ratio_claim = bbio::claim("F15-b", "bw_ratio_0p55e-3_over_0p34e-3");
    let (paper_ratio, ratio_tol) = (ratio_claim.paper, ratio_claim.tol_rel);

    let cases = LEVELS
        .iter()
        .map(|&sa| {
            let s = bbio::spec(&dev, sa, P2_NPERSEG, P2_BAND_HZ, REALISATIONS, true);
            ("published".to_string(), dev.clone(), s)
        })
        .collect();
    let levels = bbio::run(cases, "fig15")?;
    let (l34, l55, l169) = (
        find(&levels, "published", LEVELS[0]),
        find(&levels, "published", LEVELS[1]),
        find(&levels, "published", LEVELS[2]),
    );

    // F15-a: peak and 3 dB width of the ensemble-mean PSD at 0.34e-3.
    let peak = l34.ens.mean_spectrum.total.peak().0;
    let peak_single = endstop::num::stats::MeanCi::of(&l34.ens.single_peak_hz());
    let half_bin = 0.5 * l34.ens.mean_spectrum.total.df();
    let w34 = l34.ens.mean_width(0.5);
    let w55 = l55.ens.mean_width(0.5);
    let w169 = l169.ens.mean_width(0.5);
    exp.claim_with_uncertainty(
        "F15-a",
        "peak_0p34e-3_hz",
        "published",
        peak,
        Some(half_bin.hypot(peak_single.ci95)),
    );
    exp.claim_with_uncertainty(
        "F15-a",
        "bw_0p34e-3_hz",
        "published",
        w34.estimate,
        Some(w34.ci95),
    );
    // F15-b: ratio of the mean-PSD widths, CI propagated from the jackknife CIs.
    let (ratio, ratio_ci) = w55.ratio(&w34);
    exp.claim_with_uncertainty(
        "F15-b",
        "bw_ratio_0p55e-3_over_0p34e-3",
        "published",
        ratio,
        Some(ratio_ci),
    );
    // F15-c: at 1.69e-3 the half-power band has moved up more than down, relative to 0.34e-3.
    let (up, down) =
        endstop::paper::fig15::edge_shifts(&l34.ens, &l169.ens).unwrap_or((f64::NAN, f64::NAN));
    let widening_up = up > down && up > 0.0;
    exp.claim(
        "F15-c",
        "widening_up_1p69e-3",
        "published",
        if widening_up { 1.0 } else { 0.0 },
    );

    // Numbers for the summary.
    let lin = endstop::physics::two_port::linear_widths(&dev, P2_BAND_HZ.0, P2_BAND_HZ.1);
    exp.number("linear_theory_bw3db_hz", lin.bw3db_hz());
    exp.number("linear_theory_bw6db_hz", lin.bw6db_hz());
    exp.number(
        "linear_theory_peak_hz",
        lin.half_power.map_or(f64::NAN, |b| b.peak_hz),
    );
    exp.number("upper_edge_shift_1p69e-3_hz", up);
    exp.number("lower_edge_shift_1p69e-3_hz", down);
    exp.number("peak_single_record_mean_0p34e-3_hz", peak_single.mean);
    for l in &levels {
        let t = sa_label(l.sa());
        exp.number(&format!("bw3db_{t}_hz"), l.ens.mean_width(0.5).estimate);
        exp.number(&format!("bw6db_{t}_hz"), l.ens.mean_width(0.25).estimate);
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
    let w6r = l55.ens.mean_width(0.25).ratio(&l34.ens.mean_width(0.25));
    exp.number("bw6db_ratio_0p55e-3_over_0p34e-3", w6r.0);
    let r_single = ratio_spread(&l55.ens.single_bw3db_hz(), &l34.ens.single_bw3db_hz());
    let r_single_169 = ratio_spread(&l169.ens.single_bw3db_hz(), &l34.ens.single_bw3db_hz());
    let r_single6 = ratio_spread(&l55.ens.single_bw6db_hz(), &l34.ens.single_bw6db_hz());
    let r_matlab = ratio_spread(
        &l55.ens.single_alt_bw3db_hz(),
        &l34.ens.single_alt_bw3db_hz(),
    );
    let frac = |w_a: &[f64], w_b: &[f64], pred: &dyn Fn(f64) -> bool| {
        let mut n = 0usize;
        let mut k = 0usize;
        for a in w_a {
            for b in w_b {
                let r = a / b;
                if r.is_finite() {
                    n += 1;
                    if pred(r) {
                        k += 1;
                    }
                }
            }
        }
        k as f64 / n.max(1) as f64
    };
    let (wa, wb) = (l55.ens.single_bw3db_hz(), l34.ens.single_bw3db_hz());
    let at_least = frac(&wa, &wb, &|r| r >= paper_ratio);
    let within = frac(&wa, &wb, &|r| (r / paper_ratio - 1.0).abs() <= ratio_tol);
    let (wam, wbm) = (l55.ens.single_alt_bw3db_hz(), l34.ens.single_alt_bw3db_hz());
    let at_least_matlab = frac(&wam, &wbm, &|r| r >= paper_ratio);
    exp.number("single_ratio_0p55_mean", r_single.mean);
    exp.number("single_ratio_0p55_p05", r_single.p05);
    exp.number("single_ratio_0p55_p95", r_single.p95);
    exp.number("single_ratio_0p55_fraction_at_least_3p7", at_least);
    exp.number("single_ratio_0p55_fraction_within_tolerance", within);
    exp.number(
        "single_ratio_0p55_matlab_fraction_at_least_3p7",
        at_least_matlab,
    );

    // Markdown.
    let mut md = String::new();
    md.push_str(&bbio::settings_md(l34));
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
    md.push_str(&bbio::power_table_md(&levels));
    md.push_str("\n**Peak and widths of the ensemble-mean output PSD** (CI: delete-one jackknife over the records, 95 %), and the spread of the same widths read from single records\n\n");
    md.push_str(&bbio::width_table_md(&levels));
    md.push_str(&format!(
        "\nLinearised theory (eqs 11-17, no end-stops; the same at every level): peak {} Hz, \
         3 dB width {} Hz, half-amplitude width {} Hz. Peak of single records at 0.34e-3: mean \
         {} Hz.\n",
        fmt_sig(lin.half_power.map_or(f64::NAN, |b| b.peak_hz), 4),
        fmt_sig(lin.bw3db_hz(), 3),
        fmt_sig(lin.bw6db_hz(), 3),
        pm(peak_single.mean, peak_single.ci95),
    ));
    md.push_str(&format!(
        "\n**Claims** (published set): F15-a peak {} Hz (uncertainty: half a bin with the CI of \
         the single-record peaks), 3 dB width {} Hz; F15-b ratio 0.55e-3 / 0.34e-3 of the \
         mean-PSD widths {} (half-amplitude reading: {}); F15-c: between 0.34e-3 and 1.69e-3 \
         the upper half-power edge moves up by {} Hz and the lower edge down by {} Hz, so the \
         widening is towards higher frequencies: **{}**.\n",
        fmt_sig(peak, 4),
        pm(w34.estimate, w34.ci95),
        pm(ratio, ratio_ci),
        pm(w6r.0, w6r.1),
        fmt_sig(up, 3),
        fmt_sig(down, 3),
        if widening_up { "yes" } else { "no" },
    ));
    md.push_str("\n**Robustness: what one 10 s record gives.** Each width is read from a single record's Welch estimate, as the paper did; the ratio is formed from one record at each level, over all 16 x 16 pairs of independent records.\n\n| quantity | ensemble-mean PSD | single records (2^16 segments): mean ± std [5 %, 95 %] | median | single records, MATLAB default (8 segments) |\n|---|---|---|---|---|\n");
    for l in [l34, l55, l169] {
        let s = l.ens.single_bw3db_spread();
        md.push_str(&format!(
            "| 3 dB width at {} (Hz) | {} | {} | {} | {} |\n",
            sa_label(l.sa()),
            fmt_sig(l.ens.mean_width(0.5).estimate, 3),
            spread_str(&s, 3),
            fmt_sig(s.median, 3),
            spread_str(&Spread::of(&l.ens.single_alt_bw3db_hz()), 3),
        ));
    }
    md.push_str(&format!(
        "| 3 dB ratio 0.55e-3 / 0.34e-3 | {} | {} | {} | {} |\n",
        fmt_sig(ratio, 3),
        spread_str(&r_single, 3),
        fmt_sig(r_single.median, 3),
        spread_str(&r_matlab, 3),
    ));
    md.push_str(&format!(
        "| 3 dB ratio 1.69e-3 / 0.34e-3 | {} | {} | {} | |\n",
        fmt_sig(w169.estimate / w34.estimate, 3),
        spread_str(&r_single_169, 3),
        fmt_sig(r_single_169.median, 3),
    ));
    md.push_str(&format!(
        "| half-amplitude ratio 0.55e-3 / 0.34e-3 | {} | {} | {} | |\n",
        fmt_sig(w6r.0, 3),
        spread_str(&r_single6, 3),
        fmt_sig(r_single6.median, 3),
    ));
    md.push_str(&format!(
        "\nOf the single-record pairs, a fraction {} gives a 3 dB ratio of at least the paper's \
         {paper_ratio}, and {} falls within the claims file's tolerance of it; with MATLAB's \
         default segmenting a fraction {} reaches {paper_ratio}.\n",
        fmt_sig(at_least, 2),
        fmt_sig(within, 2),
        fmt_sig(at_least_matlab, 2),
    ));
    exp.write_numbers_md(&md)?;

    // Tables.
    exp.write_parquet(
        "fig15_summary",
        &mut bbio::summary_df(&levels)?,
        "published",
    )?;
    exp.write_parquet(
        "fig15_records",
        &mut bbio::records_df(&levels)?,
        "published",
    )?;
    exp.write_parquet(
        "fig15_spectra",
        &mut bbio::spectra_df(&levels, 500.0, 1000.0)?,
        "published",
    )?;

    // Figure 15 as in the paper: 500-1000 Hz, log y.
    let refs: Vec<&Level> = levels.iter().collect();
    let plot = bbio::spectra_plot(
        "Figure 15: prototype 2 at 15 V, output power PSD (both loads, one-sided)",
        &refs,
        (500.0, 1000.0),
        (1e-8, 1e-2),
        true,
    );
    exp.write_plot(&plot)?;
    write_single_record_plot(&exp, l34)?;
    write_spread_plots(&exp, &levels, paper_bw_hz, paper_ratio)?;
    exp.finish()
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
    let lin = endstop::physics::two_port::linear_output_psd(&l.device, l.sa(), &f);
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
    levels: &[Level],
    paper_bw_hz: f64,
    paper_ratio: f64,
) -> Result<()> {
    let mut series = Vec::new();
    for (i, l) in levels.iter().enumerate() {
        series.push(Series::new(
            &format!("single records, {} g²/Hz", sa_label(l.sa())),
            ecdf(&l.ens.single_bw3db_hz()),
            PALETTE[i],
            Style::LinePoints,
        ));
        let w = l.ens.mean_width(0.5).estimate;
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
        .chain(levels.iter().map(|l| l.ens.mean_width(0.5).estimate))
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

    let l34 = find(levels, "published", LEVELS[0]);
    let l55 = find(levels, "published", LEVELS[1]);
    let rat = |a: &[f64], b: &[f64]| -> Vec<f64> {
        a.iter()
            .flat_map(|x| b.iter().map(move |y| x / y))
            .collect()
    };
    let r = rat(&l55.ens.single_bw3db_hz(), &l34.ens.single_bw3db_hz());
    let r_m = rat(
        &l55.ens.single_alt_bw3db_hz(),
        &l34.ens.single_alt_bw3db_hz(),
    );
    let mean_ratio = l55.ens.mean_width(0.5).estimate / l34.ens.mean_width(0.5).estimate;
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

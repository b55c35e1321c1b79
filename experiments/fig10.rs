//! Figure 10: the random excitation. A band-limited white-noise acceleration at the paper's
//! example level Sa = 1e-2 g²/Hz (two-sided), 10 kHz band, 10 s at 100 kHz, and its Welch PSD
//! against the target (claim F10: level and band).

use endstop_experiments as common;

use endstop_experiments::broadband_io as bbio;

use anyhow::Result;
use bbio::{paper_value, pm};
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, Experiment};
use endstop::drive::noise::NoiseSpec;
use endstop::num::stats::MeanCi;
use endstop::signal::welch;
use endstop::signal::Psd;
use endstop::signal::WelchConfig;
use endstop::study::ensemble::DEFAULT_SEED;
use endstop::G;
use polars::prelude::*;
use rayon::prelude::*;

/// The paper's example level (g²/Hz, two-sided).
const SA: f64 = 1e-2;
/// Welch segment: 2^14 samples (6.1 Hz bins), 121 segments per 10 s record.
const NPERSEG: usize = 1 << 14;
/// Band over which the flat level is averaged (Hz): clear of DC and of the band edge.
const FLAT_BAND_HZ: (f64, f64) = (100.0, 9500.0);
/// Bottom of the plot's y axis (g²/Hz), as in the paper's Figure 10.
const Y_MIN: f64 = 1e-5;
/// Independent records (cheap: no integration), for the uncertainty of the level and edge.
const RECORDS: usize = 16;

fn main() {
    common::run_main("fig10", run);
}

fn run() -> Result<()> {
    let mut exp = Experiment::start("fig10");
    exp.seed = Some(DEFAULT_SEED);
    let spec = NoiseSpec::paper(SA);
    let first = endstop::study::ensemble::first_stream_for_level(SA);
    let cfg = WelchConfig::half_overlap(NPERSEG);
    let pb = common::progress(RECORDS as u64, "fig10");
    // Per record: the one-sided Welch PSD in g²/Hz and the sample mean square (g²).
    let recs: Vec<(Psd, f64)> = (0..RECORDS as u64)
        .into_par_iter()
        .map(|i| -> Result<(Psd, f64)> {
            let a = endstop::drive::noise::generate(&spec, DEFAULT_SEED, first + i)?;
            let g: Vec<f64> = a.iter().map(|x| x / G).collect();
            let ms = g.iter().map(|x| x * x).sum::<f64>() / g.len() as f64;
            let psd = welch(&g, spec.sample_rate_hz, &cfg)?;
            pb.inc(1);
            Ok((psd, ms))
        })
        .collect::<Result<_>>()?;
    pb.finish_and_clear();

    // Level: mean two-sided density over the flat band; edge: where the one-sided density
    // falls to half the flat level (the -3 dB edge), scanning down from the top.
    let level_of = |p: &Psd| p.two_sided_level_in_band(FLAT_BAND_HZ.0, FLAT_BAND_HZ.1);
    let edge_of =
        |p: &Psd| endstop::signal::bandwidth::upper_band_edge_hz(p, 2.0 * level_of(p), 0.5);
    let levels: Vec<f64> = recs.iter().map(|(p, _)| level_of(p)).collect();
    let edges: Vec<f64> = recs.iter().map(|(p, _)| edge_of(p)).collect();
    let ms: Vec<f64> = recs.iter().map(|(_, m)| *m).collect();
    let level = MeanCi::of(&levels);
    let edge = MeanCi::of(&edges);
    let mean_sq = MeanCi::of(&ms);
    let ex = &recs[0].0;
    // Flatness of the example record: relative scatter of its bins in the flat band.
    let flat: Vec<f64> = ex
        .freq_hz
        .iter()
        .zip(&ex.density)
        .filter(|(f, _)| (FLAT_BAND_HZ.0..=FLAT_BAND_HZ.1).contains(*f))
        .map(|(_, d)| d / 2.0)
        .collect();
    let flat_ci = MeanCi::of(&flat);
    // Above the band: the largest density beyond 10.5 kHz relative to the level.
    let leak = ex
        .freq_hz
        .iter()
        .zip(&ex.density)
        .filter(|(f, _)| **f >= 10.5e3)
        .map(|(_, d)| d / 2.0)
        .fold(0.0, f64::max)
        / level_of(ex);

    exp.claim_with_uncertainty(
        "F10",
        "excitation_psd_g2_per_hz",
        "published",
        level.mean,
        Some(level.ci95),
    );
    exp.claim_with_uncertainty(
        "F10",
        "excitation_band_hz",
        "published",
        edge.mean,
        Some(edge.ci95),
    );
    exp.number("level_example_record_g2_per_hz", level_of(ex));
    exp.number("edge_example_record_hz", edge_of(ex));
    exp.number("mean_square_g2", mean_sq.mean);
    exp.number("mean_square_target_g2", 2.0 * spec.bandwidth_hz * SA);
    exp.number("bin_relative_std_example", flat_ci.std / flat_ci.mean);
    exp.number("leakage_above_10p5khz_relative", leak);

    let mut md = format!(
        "Generator: `endstop::drive::noise::generate` (frequency-domain synthesis, flat to {} kHz and \
         empty above), {} records of {} s at {} kHz, ChaCha8 seed {}, streams {} to {}. Welch: \
         periodic Hann, {} samples per segment ({} Hz bins), 50 % overlap, {} segments per \
         record; the two-sided density is half the one-sided estimate. Level: mean two-sided \
         density over {} - {} Hz; edge: the highest frequency where the one-sided density is \
         still at least half of the one-sided flat level (the -3 dB edge), interpolated between \
         bins.\n\n",
        fmt_sig(spec.bandwidth_hz / 1e3, 3),
        RECORDS,
        fmt_sig(spec.duration_s, 3),
        fmt_sig(spec.sample_rate_hz / 1e3, 3),
        DEFAULT_SEED,
        first,
        first + RECORDS as u64 - 1,
        NPERSEG,
        fmt_sig(ex.df(), 3),
        ex.segments,
        FLAT_BAND_HZ.0,
        FLAT_BAND_HZ.1,
    );
    md.push_str(&format!(
        "| quantity | target | example record (stream {first}) | {RECORDS} records: mean ± 95 % CI |\n|---|---|---|---|\n\
         | flat-band level, two-sided (g²/Hz) | {} | {} | {} |\n\
         | -3 dB band edge (Hz) | {} | {} | {} |\n\
         | mean square acceleration (g²) | {} | {} | {} |\n\
         | RMS acceleration (g) | {} | {} | {} |\n",
        fmt_sig(SA, 3),
        fmt_sig(level_of(ex), 4),
        pm(level.mean, level.ci95),
        fmt_sig(spec.bandwidth_hz, 4),
        fmt_sig(edge_of(ex), 5),
        pm(edge.mean, edge.ci95),
        fmt_sig(2.0 * spec.bandwidth_hz * SA, 4),
        fmt_sig(ms[0], 4),
        pm(mean_sq.mean, mean_sq.ci95),
        fmt_sig((2.0 * spec.bandwidth_hz * SA).sqrt(), 4),
        fmt_sig(ms[0].sqrt(), 4),
        fmt_sig(mean_sq.mean.sqrt(), 4),
    ));
    md.push_str(&format!(
        "\nIn the example record the bins of the flat band scatter by {} (relative standard \
         deviation; expected about 1/sqrt(segments) for Welch with 50 % overlap), and nothing \
         above 10.5 kHz exceeds {leak:.1e} of the level (window leakage from the band edge).\n",
        fmt_sig(flat_ci.std / flat_ci.mean, 2),
    ));
    exp.write_numbers_md(&md)?;

    // Parquet: the example record's two-sided PSD, the ensemble mean and the target.
    let mean_density: Vec<f64> = (0..ex.density.len())
        .map(|k| recs.iter().map(|(p, _)| p.density[k]).sum::<f64>() / RECORDS as f64 / 2.0)
        .collect();
    let n = ex.freq_hz.len();
    let target: Vec<f64> = ex
        .freq_hz
        .iter()
        .map(|&f| {
            if f > 0.0 && f <= spec.bandwidth_hz {
                SA
            } else {
                0.0
            }
        })
        .collect();
    let mut df = df!(
        "freq_hz" => [ex.freq_hz.clone(), ex.freq_hz.clone(), ex.freq_hz.clone()].concat(),
        "psd_g2_per_hz" => [ex.density.iter().map(|d| d / 2.0).collect::<Vec<_>>(), mean_density.clone(), target.clone()].concat(),
        "series" => [vec!["example record"; n], vec!["mean of records"; n], vec!["target"; n]].concat(),
        "realisation" => [vec!["0".to_string(); n], vec!["mean".to_string(); n], vec!["target".to_string(); n]].concat(),
        "params" => vec!["none"; 3 * n],
    )?;
    exp.write_parquet("fig10_psd", &mut df, "none")?;

    // Figure 10 as in the paper: log-log, two-sided density.
    // Points from 10 Hz on; the line drops to the bottom of the axis at the first bin below
    // it (above the band the density is some twelve decades down) and stops there.
    let pts = |d: &[f64]| -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for (&f, &v) in ex.freq_hz.iter().zip(d).filter(|(f, _)| **f >= 10.0) {
            out.push((f, v.max(Y_MIN)));
            if v < Y_MIN {
                break;
            }
        }
        out
    };
    let example: Vec<f64> = ex.density.iter().map(|d| d / 2.0).collect();
    let paper = paper_value("F10", "excitation_psd_g2_per_hz");
    let plot = LinePlot::new(
        &format!(
            "Figure 10: generated acceleration, Sa = {} g²/Hz, 10 s at 100 kHz, band 10 kHz",
            bbio::sa_label(paper)
        ),
        "frequency [Hz]",
        "two-sided PSD of the acceleration [g²/Hz]",
        vec![
            Series::new(
                &format!("one record (Welch, {} Hz bins)", fmt_sig(ex.df(), 2)),
                pts(&example),
                PALETTE[0],
                Style::Line,
            ),
            Series::new(
                &format!("mean of {RECORDS} records"),
                pts(&mean_density),
                PALETTE[1],
                Style::Line,
            ),
            Series::new(
                "target: flat to 10 kHz",
                vec![(10.0, SA), (spec.bandwidth_hz, SA)],
                PALETTE[6],
                Style::Dashed,
            ),
        ],
    )
    .x(10.0, 5e4)
    .y(Y_MIN, 1e-1)
    .log(true, true)
    .legend(LegendPos::LowerLeft);
    exp.write_plot(&plot)?;
    exp.finish()
}

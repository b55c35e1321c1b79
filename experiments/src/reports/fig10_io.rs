//! Figure 10's outputs (the figure itself is `endstop::paper::figures::fig10`): the numbers of
//! the summary, the book's table of the generator's level, edge and mean square, the spectra
//! as Parquet and the plot of one run.

use anyhow::Result;
use endstop::paper::claims::{keys, Claims};
use endstop::paper::figures::fig10::{
    self, FIG10_SA, FLAT_BAND_HZ, LEAKAGE_FROM_HZ, NPERSEG, RECORDS,
};

use crate::io::frame::frame;
use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::reports::record_io::{pm, sa_label};
use crate::{fmt_sig, row, Experiment};

/// Bottom of the plot's y axis (g²/Hz), as in the paper's Figure 10.
const Y_MIN: f64 = 1e-5;

/// The parameter-set label of the spectra: they describe the generated excitation alone, and
/// no device's parameters enter them.
const NO_DEVICE: &str = "excitation only, no device parameters";

/// Writes everything of one run of Figure 10: the numbers of the summary, the book's table,
/// the spectra as Parquet and the plot.
pub fn write(mut exp: Experiment, run: &fig10::Run, claims: &Claims) -> Result<()> {
    exp.seed = Some(run.seed);
    let f = fig10::findings(run);
    let spec = &run.spec;

    exp.number("level_example_record_g2_per_hz", f.example_level);
    exp.number("edge_example_record_hz", f.example_edge_hz);
    exp.number("mean_square_g2", f.mean_square.mean);
    exp.number("mean_square_target_g2", spec.mean_square_g2());
    exp.number("bin_relative_std_example", f.example_bin_relative_std);
    exp.number("leakage_above_10p5khz_relative", f.example_leakage);

    exp.write_numbers_md(&numbers_md(run, &f))?;
    write_parquet(&exp, run, &f)?;
    exp.write_plot(&psd_plot(run, &f, claims))?;
    exp.finish()
}

/// The book's table of the generator's level, edge and mean square, with its method.
fn numbers_md(run: &fig10::Run, f: &fig10::Findings) -> String {
    let spec = &run.spec;
    let first = run.first_stream;
    let ex = &run.records[0];
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
        run.seed,
        first,
        first + RECORDS as u64 - 1,
        NPERSEG,
        fmt_sig(ex.psd.df(), 3),
        ex.psd.segments,
        FLAT_BAND_HZ.0,
        FLAT_BAND_HZ.1,
    );
    let mut t = Table::new([
        "quantity",
        "target",
        &format!("example record (stream {first})"),
        &format!("{RECORDS} records: mean ± 95 % CI"),
    ]);
    let ms_target = spec.mean_square_g2();
    t.row([
        "flat-band level, two-sided (g²/Hz)".into(),
        fmt_sig(FIG10_SA, 3),
        fmt_sig(f.example_level, 4),
        pm(f.level.mean, f.level.ci95),
    ]);
    t.row([
        "-3 dB band edge (Hz)".into(),
        fmt_sig(spec.bandwidth_hz, 4),
        fmt_sig(f.example_edge_hz, 5),
        pm(f.edge.mean, f.edge.ci95),
    ]);
    t.row([
        "mean square acceleration (g²)".into(),
        fmt_sig(ms_target, 4),
        fmt_sig(ex.mean_square_g2, 4),
        pm(f.mean_square.mean, f.mean_square.ci95),
    ]);
    t.row([
        "RMS acceleration (g)".into(),
        fmt_sig(ms_target.sqrt(), 4),
        fmt_sig(ex.mean_square_g2.sqrt(), 4),
        fmt_sig(f.mean_square.mean.sqrt(), 4),
    ]);
    md.push_str(&t.render());
    md.push_str(&format!(
        "\nIn the example record the bins of the flat band scatter by {} (relative standard \
         deviation; expected about 1/sqrt(segments) for Welch with 50 % overlap), and nothing \
         above {} kHz exceeds {:.1e} of the level (window leakage from the band edge).\n",
        fmt_sig(f.example_bin_relative_std, 2),
        LEAKAGE_FROM_HZ / 1e3,
        f.example_leakage,
    ));
    md
}

/// The example record's two-sided PSD, the mean of the records and the target, as Parquet.
fn write_parquet(exp: &Experiment, run: &fig10::Run, f: &fig10::Findings) -> Result<()> {
    let spec = &run.spec;
    let ex = &run.records[0];
    let mut rows = Vec::new();
    for (series, real, psd) in [
        ("example record", "0", &f.example_two_sided),
        ("mean of records", "mean", &f.mean_two_sided),
    ] {
        for (&fr, &d) in psd.freq_hz.iter().zip(&psd.density) {
            rows.push(row![
                "freq_hz" => fr,
                "psd_g2_per_hz" => d,
                "series" => series,
                "realisation" => real,
                "params" => NO_DEVICE,
            ]);
        }
    }
    for &fr in &ex.psd.freq_hz {
        rows.push(row![
            "freq_hz" => fr,
            "psd_g2_per_hz" => spec.ideal_psd_g2_per_hz(fr),
            "series" => "target",
            "realisation" => "target",
            "params" => NO_DEVICE,
        ]);
    }
    exp.write_parquet("fig10_psd", &mut frame(rows)?, NO_DEVICE)?;

    Ok(())
}

/// Figure 10 as in the paper: log-log, two-sided density. Points from 10 Hz on; the line
/// drops to the bottom of the axis at the first bin below it (above the band the density is
/// some twelve decades down) and stops there.
fn psd_plot(run: &fig10::Run, f: &fig10::Findings, claims: &Claims) -> LinePlot {
    let spec = &run.spec;
    let ex = &run.records[0];
    let pts = |p: &endstop::signal::Psd| -> Vec<(f64, f64)> {
        let mut out = Vec::new();
        for (&fr, &v) in p
            .freq_hz
            .iter()
            .zip(&p.density)
            .filter(|(fr, _)| **fr >= 10.0)
        {
            out.push((fr, v.max(Y_MIN)));
            if v < Y_MIN {
                break;
            }
        }
        out
    };
    let paper = claims
        .claim(keys::F10_LEVEL)
        .map_or(f64::NAN, |c| c.paper.to_f64());
    LinePlot::new(
        &format!(
            "Figure 10: generated acceleration, Sa = {} g²/Hz, 10 s at 100 kHz, band 10 kHz",
            sa_label(paper)
        ),
        "frequency [Hz]",
        "two-sided PSD of the acceleration [g²/Hz]",
        vec![
            Series::new(
                &format!("one record (Welch, {} Hz bins)", fmt_sig(ex.psd.df(), 2)),
                pts(&f.example_two_sided),
                PALETTE[0],
                Style::Line,
            ),
            Series::new(
                &format!("mean of {RECORDS} records"),
                pts(&f.mean_two_sided),
                PALETTE[1],
                Style::Line,
            ),
            Series::new(
                "target: flat to 10 kHz",
                vec![(10.0, FIG10_SA), (spec.bandwidth_hz, FIG10_SA)],
                PALETTE[6],
                Style::Dashed,
            ),
        ],
    )
    .x(10.0, 5e4)
    .y(Y_MIN, 1e-1)
    .log(true, true)
    .legend(LegendPos::LowerLeft)
}

//! Shared edge of the random-vibration (record) experiments (Figures 11, 12, 14, 15): the parameter sets of
//! prototype 1, Parquet rows, Markdown tables and spectra plots of analysed levels. Nothing
//! here computes a result: the ensembles and everything read from them come from
//! `endstop::paper` (`ensembles`, `fig11` ... `fig15`).

use anyhow::Result;

use crate::io::frame::{frame, Row};
use crate::io::md::Table;
use crate::io::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use crate::{fmt_sig, row, Experiment};
use endstop::num::stats::Spread;
use endstop::paper::ensembles::Prototype1Run;
use endstop::paper::ensembles::WidthReading::{HalfAmplitude, HalfPower};
use endstop::paper::setups::{comb, endstop, ParamSet, Prototype1Sets};
use endstop::study::record::{ring_up_time_s, TRANSIENT_RING_TIMES};

pub use endstop::paper::ensembles::{level_label as sa_label, Level};

/// Formats `x ± ci` with 3 significant digits (the CI with 2).
pub fn pm(x: f64, ci: f64) -> String {
    if ci.is_finite() {
        format!("{} ± {}", fmt_sig(x, 3), fmt_sig(ci, 2))
    } else {
        fmt_sig(x, 3)
    }
}

/// `mean ± std [p05, p95]` of a spread.
pub fn spread_str(s: &Spread, sig: usize) -> String {
    let mut out = format!(
        "{} ± {} [{}, {}]",
        fmt_sig(s.mean, sig),
        fmt_sig(s.std, 2),
        fmt_sig(s.p05, sig),
        fmt_sig(s.p95, sig)
    );
    if s.undetermined > 0 {
        out.push_str(&format!(" ({} undetermined)", s.undetermined));
    }
    out
}

/// One row per level: power, efficiency, displacement, contact, bandwidths and their spread.
pub fn summary_rows(levels: &[Level]) -> Vec<Row> {
    levels
        .iter()
        .map(|l| {
            let e = &l.ens;
            let (w3, w6) = (HalfPower.mean_width(e), HalfAmplitude.mean_width(e));
            let edge = |hi: bool| {
                e.mean_widths
                    .half_power
                    .map_or(f64::NAN, |b| if hi { b.f_hi_hz } else { b.f_lo_hz })
            };
            let (s3, s6) = (e.single_bw3db_spread(), e.single_bw6db_spread());
            row![
                "params" => l.set.label(),
                "psd_g2_per_hz" => l.sa(),
                "realisations" => e.records.len() as u32,
                "bias_v" => comb(&l.device).bias_v,
                "endstop_gap_m" => endstop(&l.device).gap_m,
                "p_mean_w" => e.power_w.mean,
                "p_ci95_w" => e.power_w.ci95,
                "p1_mean_w" => e.p1_w.mean,
                "p2_mean_w" => e.p2_w.mean,
                "p_eq21_w" => l.eq21_power_w(),
                "efficiency" => e.efficiency.mean,
                "efficiency_ci95" => e.efficiency.ci95,
                "efficiency_eq21" => l.eq21_efficiency(),
                "x_rms_m" => e.x_rms_m.mean,
                "x_rms_ci95_m" => e.x_rms_m.ci95,
                "x_peak_m" => e.x_peak_m,
                "contact_fraction" => e.contact_fraction.mean,
                "contact_fraction_ci95" => e.contact_fraction.ci95,
                "impacts" => e.impacts,
                "peak_hz" => e.mean_spectrum.total.peak().0,
                "bw3db_hz" => w3.estimate,
                "bw3db_ci95_hz" => w3.ci95,
                "f3db_lo_hz" => edge(false),
                "f3db_hi_hz" => edge(true),
                "bw6db_hz" => w6.estimate,
                "bw6db_ci95_hz" => w6.ci95,
                "single_bw3db_mean_hz" => s3.mean,
                "single_bw3db_std_hz" => s3.std,
                "single_bw3db_p05_hz" => s3.p05,
                "single_bw3db_p95_hz" => s3.p95,
                "single_bw6db_mean_hz" => s6.mean,
                "single_bw6db_std_hz" => s6.std,
                "nperseg" => e.spec.welch.nperseg as u32,
                "bin_hz" => e.mean_spectrum.total.df(),
                "transient_s" => e.spec.record.transient_s,
                "duration_s" => e.spec.record.noise.duration_s,
                "steps" => e.stats.accepted,
                "rejected_steps" => e.stats.rejected,
                "events" => e.stats.events,
            ]
        })
        .collect()
}

/// One row per record: its stream, power, efficiency, displacement, contact and widths.
pub fn record_rows(levels: &[Level]) -> Vec<Row> {
    let mut rows = Vec::new();
    for l in levels {
        for (i, r) in l.ens.records.iter().enumerate() {
            let s = &r.summary;
            rows.push(row![
                "params" => l.set.label(),
                "psd_g2_per_hz" => l.sa(),
                "realisation" => i as u32,
                "stream" => r.stream,
                "p1_w" => s.p1_w,
                "p2_w" => s.p2_w,
                "efficiency" => l.record_efficiency(r),
                "x_rms_m" => s.x_rms_m,
                "contact_fraction" => s.contact_fraction,
                "impacts" => s.impacts,
                "bw3db_hz" => r.widths.bw3db_hz(),
                "bw6db_hz" => r.widths.bw6db_hz(),
                "peak_hz" => r.spectrum.total.peak().0,
                "bw3db_matlab8_hz" => r.alt.as_ref().map_or(f64::NAN, |a| a.1.bw3db_hz()),
                "accel_rms_g" => s.accel_mean_square_si.sqrt() / endstop::G,
            ]);
        }
    }
    rows
}

/// Long-format spectra between `f_lo` and `f_hi`: the ensemble mean of both loads and of each
/// load, every single record (both loads), and the linearised theory, in uW/Hz.
pub fn spectra_rows(levels: &[Level], f_lo: f64, f_hi: f64) -> Vec<Row> {
    let mut rows = Vec::new();
    let mut push = |psd: &endstop::signal::Psd, l: &Level, series: &str, real: &str| {
        for (&f, &d) in psd.freq_hz.iter().zip(&psd.density) {
            if (f_lo..=f_hi).contains(&f) {
                rows.push(row![
                    "freq_hz" => f,
                    "out_psd_uw_per_hz" => d * 1e6,
                    "psd_g2_per_hz" => l.sa(),
                    "series" => series,
                    "params" => l.set.label(),
                    "realisation" => real,
                ]);
            }
        }
    };
    for l in levels {
        let m = &l.ens.mean_spectrum;
        push(&m.total, l, "both loads", "mean");
        push(&m.load1, l, "load 1", "mean");
        push(&m.load2, l, "load 2", "mean");
        let lin = l.linear_psd(&m.total.freq_hz);
        push(&lin, l, "linear theory (eqs 11-17)", "theory");
        for (i, r) in l.ens.records.iter().enumerate() {
            push(&r.spectrum.total, l, "both loads", &i.to_string());
        }
    }
    rows
}

/// Writes `<name>_summary` and `<name>_records` of `levels`, and `<name>_spectra` over
/// `spectra_hz` when given.
pub fn write_level_tables(
    exp: &Experiment,
    name: &str,
    levels: &[Level],
    spectra_hz: Option<(f64, f64)>,
    set_label: &str,
) -> Result<()> {
    exp.write_parquet(
        &format!("{name}_summary"),
        &mut frame(summary_rows(levels))?,
        set_label,
    )?;
    exp.write_parquet(
        &format!("{name}_records"),
        &mut frame(record_rows(levels))?,
        set_label,
    )?;
    if let Some((lo, hi)) = spectra_hz {
        exp.write_parquet(
            &format!("{name}_spectra"),
            &mut frame(spectra_rows(levels, lo, hi))?,
            set_label,
        )?;
    }
    Ok(())
}

/// Markdown: power, efficiency, displacement and contact per level.
pub fn power_table(levels: &[Level]) -> Table<10> {
    let mut t = Table::new([
        "set",
        "Sa (g²/Hz)",
        "records",
        "P, both loads (nW)",
        "eq 21 (nW)",
        "efficiency 2P/(m Sa) (%)",
        "x_rms (um)",
        "largest abs(x) (um)",
        "time in contact",
        "impacts per record",
    ]);
    for l in levels {
        let e = &l.ens;
        t.row([
            l.set.label().to_string(),
            sa_label(l.sa()),
            e.records.len().to_string(),
            pm(e.power_w.mean * 1e9, e.power_w.ci95 * 1e9),
            fmt_sig(l.eq21_power_w() * 1e9, 3),
            pm(e.efficiency.mean * 100.0, e.efficiency.ci95 * 100.0),
            pm(e.x_rms_m.mean * 1e6, e.x_rms_m.ci95 * 1e6),
            fmt_sig(e.x_peak_m * 1e6, 3),
            if e.contact_fraction.mean == 0.0 {
                "0".to_string()
            } else {
                format!("{:.2e}", e.contact_fraction.mean)
            },
            fmt_sig(l.impacts_per_record(), 3),
        ]);
    }
    t
}

/// Markdown: peak, widths of the ensemble-mean PSD (with jackknife CIs), the band edges, and
/// the spread of single-record widths.
pub fn width_table(levels: &[Level]) -> Table<8> {
    let mut t = Table::new([
        "set",
        "Sa (g²/Hz)",
        "peak (Hz)",
        "3 dB band (Hz)",
        "3 dB width (Hz)",
        "half-amplitude width (Hz)",
        "single record 3 dB: mean ± std [5 %, 95 %] (Hz)",
        "single record half-amplitude (Hz)",
    ]);
    for l in levels {
        let e = &l.ens;
        let (w3, w6) = (HalfPower.mean_width(e), HalfAmplitude.mean_width(e));
        let band = e
            .mean_widths
            .half_power
            .map_or("undetermined".to_string(), |b| {
                format!("{} - {}", fmt_sig(b.f_lo_hz, 4), fmt_sig(b.f_hi_hz, 4))
            });
        t.row([
            l.set.label().to_string(),
            sa_label(l.sa()),
            fmt_sig(e.mean_spectrum.total.peak().0, 4),
            band,
            pm(w3.estimate, w3.ci95),
            pm(w6.estimate, w6.ci95),
            spread_str(&e.single_bw3db_spread(), 3),
            spread_str(&e.single_bw6db_spread(), 3),
        ]);
    }
    t
}

/// Markdown: the estimator settings shared by a set of levels.
pub fn settings_md(l: &Level) -> String {
    let e = &l.ens;
    let r = &e.spec.record;
    let rec0 = &e.records[0];
    format!(
        "Records: {} per level, each {} s analysed at {} kHz after a discarded pre-roll of {} s \
         ({} ring-up times 2m/b = {} ms), excitation band {} kHz, ChaCha8 seed {}, realisation i \
         of level Sa on stream round(Sa 1e9) 1000 + i. Welch: periodic Hann, {} samples per \
         segment ({} Hz bins), 50 % overlap, {} segments per record, one-sided; the output power \
         PSD is (S_V1 + S_V2)/RL in uW/Hz. Integrator: {:?} scheme (the exponential free-flight \
         step between contacts, Dormand-Prince with event location near the stops), \
         Dormand-Prince relative tolerance {:e}.\n",
        e.records.len(),
        fmt_sig(r.noise.duration_s, 3),
        fmt_sig(r.noise.sample_rate_hz / 1e3, 3),
        fmt_sig(r.transient_s, 3),
        fmt_sig(TRANSIENT_RING_TIMES, 2),
        fmt_sig(ring_up_time_s(&l.device) * 1e3, 3),
        fmt_sig(r.noise.bandwidth_hz / 1e3, 3),
        e.spec.seed,
        e.spec.welch.nperseg,
        fmt_sig(rec0.spectrum.total.df(), 3),
        rec0.spectrum.total.segments,
        r.scheme,
        r.rtol,
    )
}

/// Output PSD plot (uW/Hz, log y) of the ensemble means of `levels`, one colour per level
/// (the calibrated set dashed in the colour of its level), with the linearised theory of the
/// first level dashed when `theory` is set.
pub fn spectra_plot(
    title: &str,
    levels: &[Level],
    x: (f64, f64),
    y: (f64, f64),
    theory: bool,
) -> LinePlot {
    let mut series = Vec::new();
    let two_sets = levels.iter().any(|o| o.set != levels[0].set);
    for l in levels {
        let m = &l.ens.mean_spectrum.total;
        let pts: Vec<(f64, f64)> = m
            .freq_hz
            .iter()
            .zip(&m.density)
            .filter(|(f, _)| (x.0..=x.1).contains(*f))
            .map(|(f, d)| (*f, d * 1e6))
            .collect();
        let label = if two_sets {
            format!("{} g²/Hz ({})", sa_label(l.sa()), l.set)
        } else {
            format!(
                "{} g²/Hz, mean of {} records",
                sa_label(l.sa()),
                l.ens.records.len()
            )
        };
        let style = if l.set == ParamSet::Calibrated {
            Style::Dashed
        } else {
            Style::Line
        };
        series.push(Series::new(&label, pts, PALETTE[l.index % 6], style));
    }
    if let (true, Some(l)) = (theory, levels.first()) {
        let n = 2000;
        let f: Vec<f64> = (0..=n)
            .map(|i| x.0 + (x.1 - x.0) * i as f64 / n as f64)
            .collect();
        let lin = l.linear_psd(&f);
        let pts = f
            .iter()
            .zip(&lin.density)
            .map(|(f, d)| (*f, d * 1e6))
            .collect();
        series.push(Series::new(
            &format!("linear theory at {} g²/Hz", sa_label(l.sa())),
            pts,
            PALETTE[6],
            Style::Dashed,
        ));
    }
    LinePlot::new(title, "frequency [Hz]", "output power PSD [uW/Hz]", series)
        .x(x.0, x.1)
        .y(y.0, y.1)
        .log(false, true)
        .legend(LegendPos::UpperRight)
}

/// Prototype 1's two parameter sets as Figures 11 and 12 take them: published (Tables 1 and
/// 2) and calibrated (the end-stop gap fitted to Figure 8's impact onset), as loaded devices.
/// Records both parameter files on the experiment ([`crate::prototype1_both_sets`]) and both
/// gaps as numbers.
pub fn prototype1_sets(exp: &mut Experiment) -> Result<Prototype1Sets> {
    let (p1, cal) = crate::prototype1_both_sets(exp)?;
    exp.number("calibrated_endstop_gap_m", cal.record.fitted_gap_m);
    exp.number("published_endstop_gap_m", endstop(&p1.published).gap_m);
    Ok(p1)
}

/// The Markdown of a prototype-1 spectra experiment (Figures 11 and 12) up to its claims:
/// settings, the two gaps (`gap_note` after them), power and width tables, and the linear
/// theory.
pub fn p1_tables_md(run: &Prototype1Run, gap_note: &str) -> String {
    let gap = |set| endstop(&run.level(set, 0).device).gap_m;
    let mut md = settings_md(&run.levels[0]);
    md.push_str(&format!(
        "\nEnd-stop gap xmax: published {} um, calibrated {} um{gap_note}.\n\n**Power and \
         contact**\n\n",
        fmt_sig(gap(ParamSet::Published) * 1e6, 3),
        fmt_sig(gap(ParamSet::Calibrated) * 1e6, 3),
    ));
    md.push_str(&power_table(&run.levels).render());
    md.push_str(
        "\n**Peak and widths of the ensemble-mean output PSD** (CI: delete-one jackknife over \
         the records, 95 %), and the spread of the same widths read from single records\n\n",
    );
    md.push_str(&width_table(&run.levels).render());
    let lin = &run.linear;
    md.push_str(&format!(
        "\nLinearised theory (eqs 11-17, no end-stops): 3 dB width {} Hz, half-amplitude width \
         {} Hz, peak {} Hz.\n\n",
        fmt_sig(lin.bw3db_hz(), 3),
        fmt_sig(lin.bw6db_hz(), 3),
        fmt_sig(lin.half_power.map_or(f64::NAN, |b| b.peak_hz), 4),
    ));
    md
}

/// Writes the three Parquet files of a prototype-1 spectra experiment (Figures 11 and 12):
/// `<name>_summary`, `<name>_records` and `<name>_spectra` over `band_hz`, and its plot of the
/// mean output PSDs on a log axis spanning four decades below the highest peak.
pub fn write_p1_spectra(
    exp: &Experiment,
    name: &str,
    title: &str,
    run: &Prototype1Run,
    band_hz: (f64, f64),
    theory: bool,
) -> Result<()> {
    write_level_tables(exp, name, &run.levels, Some(band_hz), ParamSet::BOTH_LABEL)?;
    let top = run
        .levels
        .iter()
        .map(|l| l.ens.mean_spectrum.total.peak().1 * 1e6)
        .fold(0.0, f64::max);
    let y_hi = 10f64.powf((2.0 * top).log10().ceil());
    let plot = spectra_plot(title, &run.levels, band_hz, (y_hi / 1e4, y_hi), theory);
    exp.write_plot(&plot)
}

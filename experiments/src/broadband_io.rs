//! Shared edge of the broadband experiments (Figures 11, 12, 14, 15): running ensembles with a
//! progress bar, and turning them into Parquet tables, Markdown for the book and spectra plots.
//! Included with `#[path]` by those binaries only; nothing here computes a result (the
//! numbers come from `endstop::broadband`).

use anyhow::Result;
use polars::prelude::*;

use crate::fmt_sig;
use crate::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use endstop::device::Device;
use endstop::num::stats::Spread;
use endstop::study::ensemble::Ensemble;
use endstop::study::ensemble::EnsembleCase;
use endstop::study::ensemble::EnsembleSpec;

/// One analysed level: parameter set label, the device and its ensemble.
pub struct Level {
    /// `published` or `calibrated`.
    pub set: String,
    /// The device as simulated.
    pub device: Device,
    /// The ensemble.
    pub ens: Ensemble,
}

impl Level {
    /// Two-sided acceleration PSD (g²/Hz).
    pub fn sa(&self) -> f64 {
        self.ens.psd_g2_per_hz()
    }
}

/// The ensemble settings of a level ([`endstop::paper::ensembles::protocol_spec`]).
pub fn spec(
    device: &Device,
    sa: f64,
    nperseg: usize,
    band_hz: (f64, f64),
    realisations: usize,
    matlab_alt: bool,
) -> EnsembleSpec {
    endstop::paper::ensembles::protocol_spec(device, sa, nperseg, band_hz, realisations, matlab_alt)
}

/// Runs all cases in parallel with a progress bar; returns the levels in the order given.
pub fn run(cases: Vec<(String, Device, EnsembleSpec)>, what: &str) -> Result<Vec<Level>> {
    let total: usize = cases.iter().map(|c| c.2.realisations).sum();
    let pb = crate::progress(total as u64, what);
    let ec: Vec<EnsembleCase> = cases
        .iter()
        .map(|(_, d, s)| EnsembleCase {
            device: d.clone(),
            spec: s.clone(),
        })
        .collect();
    let ens = endstop::study::ensemble::run_ensembles(&ec, || pb.inc(1))?;
    pb.finish_and_clear();
    Ok(cases
        .into_iter()
        .zip(ens)
        .map(|((set, device, _), ens)| Level { set, device, ens })
        .collect())
}

/// `3.49e-4` style label of a level.
pub fn sa_label(sa: f64) -> String {
    let e = sa.log10().floor() as i32;
    let m = sa / 10f64.powi(e);
    let m = format!("{}", (m * 100.0).round() / 100.0);
    format!("{m}e{e}")
}

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
pub fn summary_df(levels: &[Level]) -> Result<DataFrame> {
    let col = |f: &dyn Fn(&Level) -> f64| -> Vec<f64> { levels.iter().map(f).collect() };
    let w3 = |l: &Level| l.ens.mean_width(0.5);
    let w6 = |l: &Level| l.ens.mean_width(0.25);
    let edge = |l: &Level, hi: bool| {
        l.ens
            .mean_widths
            .half_power
            .map_or(f64::NAN, |b| if hi { b.f_hi_hz } else { b.f_lo_hz })
    };
    let df = df!(
        "params" => levels.iter().map(|l| l.set.clone()).collect::<Vec<_>>(),
        "psd_g2_per_hz" => col(&|l| l.sa()),
        "realisations" => levels.iter().map(|l| l.ens.records.len() as u32).collect::<Vec<_>>(),
        "bias_v" => col(&|l| l.device.electrical.bias_v),
        "endstop_gap_m" => col(&|l| l.device.geometry.endstop_gap_m),
        "p_mean_w" => col(&|l| l.ens.power_w.mean),
        "p_ci95_w" => col(&|l| l.ens.power_w.ci95),
        "p1_mean_w" => col(&|l| l.ens.p1_w.mean),
        "p2_mean_w" => col(&|l| l.ens.p2_w.mean),
        "p_eq21_w" => col(&|l| endstop::physics::two_port::eq21_power_w(&l.device, l.sa())),
        "efficiency" => col(&|l| l.ens.efficiency.mean),
        "efficiency_ci95" => col(&|l| l.ens.efficiency.ci95),
        "efficiency_eq21" => col(&|l| endstop::physics::two_port::eq21_efficiency(&l.device)),
        "x_rms_m" => col(&|l| l.ens.x_rms_m.mean),
        "x_rms_ci95_m" => col(&|l| l.ens.x_rms_m.ci95),
        "x_peak_m" => col(&|l| l.ens.x_peak_m),
        "contact_fraction" => col(&|l| l.ens.contact_fraction.mean),
        "contact_fraction_ci95" => col(&|l| l.ens.contact_fraction.ci95),
        "impacts" => levels.iter().map(|l| l.ens.impacts).collect::<Vec<_>>(),
        "peak_hz" => col(&|l| l.ens.mean_spectrum.total.peak().0),
        "bw3db_hz" => col(&|l| w3(l).estimate),
        "bw3db_ci95_hz" => col(&|l| w3(l).ci95),
        "f3db_lo_hz" => col(&|l| edge(l, false)),
        "f3db_hi_hz" => col(&|l| edge(l, true)),
        "bw6db_hz" => col(&|l| w6(l).estimate),
        "bw6db_ci95_hz" => col(&|l| w6(l).ci95),
        "single_bw3db_mean_hz" => col(&|l| l.ens.single_bw3db_spread().mean),
        "single_bw3db_std_hz" => col(&|l| l.ens.single_bw3db_spread().std),
        "single_bw3db_p05_hz" => col(&|l| l.ens.single_bw3db_spread().p05),
        "single_bw3db_p95_hz" => col(&|l| l.ens.single_bw3db_spread().p95),
        "single_bw6db_mean_hz" => col(&|l| l.ens.single_bw6db_spread().mean),
        "single_bw6db_std_hz" => col(&|l| l.ens.single_bw6db_spread().std),
        "nperseg" => levels.iter().map(|l| l.ens.spec.welch.nperseg as u32).collect::<Vec<_>>(),
        "bin_hz" => col(&|l| l.ens.mean_spectrum.total.df()),
        "transient_s" => col(&|l| l.ens.spec.record.transient_s),
        "duration_s" => col(&|l| l.ens.spec.record.noise.duration_s),
        "steps" => levels.iter().map(|l| l.ens.stats.accepted).collect::<Vec<_>>(),
        "rejected_steps" => levels.iter().map(|l| l.ens.stats.rejected).collect::<Vec<_>>(),
        "events" => levels.iter().map(|l| l.ens.stats.events).collect::<Vec<_>>(),
    )?;
    Ok(df)
}

/// One row per record: its stream, power, efficiency, displacement, contact and widths.
pub fn records_df(levels: &[Level]) -> Result<DataFrame> {
    let mut set = Vec::new();
    let mut sa = Vec::new();
    let mut real = Vec::new();
    let mut stream = Vec::new();
    let mut cols: [Vec<f64>; 10] = Default::default();
    let mut impacts = Vec::new();
    for l in levels {
        let m = l.device.mechanics.mass_kg;
        for (i, r) in l.ens.records.iter().enumerate() {
            let s = &r.summary;
            set.push(l.set.clone());
            sa.push(l.sa());
            real.push(i as u32);
            stream.push(r.stream);
            cols[0].push(s.p1_w);
            cols[1].push(s.p2_w);
            cols[2].push(2.0 * s.p_total_w() / (m * l.ens.spec.record.noise.psd_si()));
            cols[3].push(s.x_rms_m);
            cols[4].push(s.contact_fraction);
            cols[5].push(r.widths.bw3db_hz());
            cols[6].push(r.widths.bw6db_hz());
            cols[7].push(r.spectrum.total.peak().0);
            cols[8].push(r.alt.as_ref().map_or(f64::NAN, |a| a.1.bw3db_hz()));
            cols[9].push(s.accel_mean_square_si.sqrt() / endstop::G);
            impacts.push(s.impacts);
        }
    }
    let [p1, p2, eff, xrms, cf, bw3, bw6, peak, alt, arms] = cols;
    Ok(df!(
        "params" => set,
        "psd_g2_per_hz" => sa,
        "realisation" => real,
        "stream" => stream,
        "p1_w" => p1,
        "p2_w" => p2,
        "efficiency" => eff,
        "x_rms_m" => xrms,
        "contact_fraction" => cf,
        "impacts" => impacts,
        "bw3db_hz" => bw3,
        "bw6db_hz" => bw6,
        "peak_hz" => peak,
        "bw3db_matlab8_hz" => alt,
        "accel_rms_g" => arms,
    )?)
}

/// Long-format spectra between `f_lo` and `f_hi`: the ensemble mean of both loads and of each
/// load, every single record (both loads), and the linearised theory, in uW/Hz.
pub fn spectra_df(levels: &[Level], f_lo: f64, f_hi: f64) -> Result<DataFrame> {
    let mut f = Vec::new();
    let mut p = Vec::new();
    let mut sa = Vec::new();
    let mut series = Vec::new();
    let mut set = Vec::new();
    let mut real = Vec::new();
    let mut push = |psd: &endstop::signal::Psd, l: &Level, s: &str, r: &str| {
        for (&fr, &d) in psd.freq_hz.iter().zip(&psd.density) {
            if (f_lo..=f_hi).contains(&fr) {
                f.push(fr);
                p.push(d * 1e6);
                sa.push(l.sa());
                series.push(s.to_string());
                set.push(l.set.clone());
                real.push(r.to_string());
            }
        }
    };
    for l in levels {
        let m = &l.ens.mean_spectrum;
        push(&m.total, l, "both loads", "mean");
        push(&m.load1, l, "load 1", "mean");
        push(&m.load2, l, "load 2", "mean");
        let lin =
            endstop::physics::two_port::linear_output_psd(&l.device, l.sa(), &m.total.freq_hz);
        push(&lin, l, "linear theory (eqs 11-17)", "theory");
        for (i, r) in l.ens.records.iter().enumerate() {
            push(&r.spectrum.total, l, "both loads", &i.to_string());
        }
    }
    Ok(df!(
        "freq_hz" => f,
        "out_psd_uw_per_hz" => p,
        "psd_g2_per_hz" => sa,
        "series" => series,
        "params" => set,
        "realisation" => real,
    )?)
}

/// Markdown: power, efficiency, displacement and contact per level.
pub fn power_table_md(levels: &[Level]) -> String {
    let mut md = String::from(
        "| set | Sa (g²/Hz) | records | P, both loads (nW) | eq 21 (nW) | efficiency 2P/(m Sa) (%) | x_rms (um) | largest abs(x) (um) | time in contact | impacts per record |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for l in levels {
        let e = &l.ens;
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |\n",
            l.set,
            sa_label(l.sa()),
            e.records.len(),
            pm(e.power_w.mean * 1e9, e.power_w.ci95 * 1e9),
            fmt_sig(
                endstop::physics::two_port::eq21_power_w(&l.device, l.sa()) * 1e9,
                3
            ),
            pm(e.efficiency.mean * 100.0, e.efficiency.ci95 * 100.0),
            pm(e.x_rms_m.mean * 1e6, e.x_rms_m.ci95 * 1e6),
            fmt_sig(e.x_peak_m * 1e6, 3),
            if e.contact_fraction.mean == 0.0 {
                "0".to_string()
            } else {
                format!("{:.2e}", e.contact_fraction.mean)
            },
            fmt_sig(e.impacts as f64 / e.records.len() as f64, 3),
        ));
    }
    md
}

/// Markdown: peak, widths of the ensemble-mean PSD (with jackknife CIs), the band edges, and
/// the spread of single-record widths.
pub fn width_table_md(levels: &[Level]) -> String {
    let mut md = String::from(
        "| set | Sa (g²/Hz) | peak (Hz) | 3 dB band (Hz) | 3 dB width (Hz) | half-amplitude width (Hz) | single record 3 dB: mean ± std [5 %, 95 %] (Hz) | single record half-amplitude (Hz) |\n|---|---|---|---|---|---|---|---|\n",
    );
    for l in levels {
        let e = &l.ens;
        let w3 = e.mean_width(0.5);
        let w6 = e.mean_width(0.25);
        let band = e
            .mean_widths
            .half_power
            .map_or("undetermined".to_string(), |b| {
                format!("{} - {}", fmt_sig(b.f_lo_hz, 4), fmt_sig(b.f_hi_hz, 4))
            });
        md.push_str(&format!(
            "| {} | {} | {} | {} | {} | {} | {} | {} |\n",
            l.set,
            sa_label(l.sa()),
            fmt_sig(e.mean_spectrum.total.peak().0, 4),
            band,
            pm(w3.estimate, w3.ci95),
            pm(w6.estimate, w6.ci95),
            spread_str(&e.single_bw3db_spread(), 3),
            spread_str(&e.single_bw6db_spread(), 3),
        ));
    }
    md
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
         PSD is (S_V1 + S_V2)/RL in uW/Hz. Integrator relative tolerance {:e}.\n",
        e.records.len(),
        fmt_sig(r.noise.duration_s, 3),
        fmt_sig(r.noise.sample_rate_hz / 1e3, 3),
        fmt_sig(r.transient_s, 3),
        fmt_sig(endstop::study::record::TRANSIENT_RING_TIMES, 2),
        fmt_sig(endstop::study::record::ring_up_time_s(&l.device) * 1e3, 3),
        fmt_sig(r.noise.bandwidth_hz / 1e3, 3),
        e.spec.seed,
        e.spec.welch.nperseg,
        fmt_sig(rec0.spectrum.total.df(), 3),
        rec0.spectrum.total.segments,
        r.rtol,
    )
}

/// Output PSD plot (uW/Hz, log y) of the ensemble means of `levels`, with the linearised
/// theory of the lowest level dashed when `theory` is set.
pub fn spectra_plot(
    title: &str,
    levels: &[&Level],
    x: (f64, f64),
    y: (f64, f64),
    theory: bool,
) -> LinePlot {
    let mut series = Vec::new();
    // One colour per level; the calibrated set dashed in the same colour.
    let mut sas: Vec<f64> = Vec::new();
    for l in levels {
        if !sas.iter().any(|s| (s / l.sa() - 1.0).abs() < 1e-9) {
            sas.push(l.sa());
        }
    }
    for l in levels {
        let i = sas
            .iter()
            .position(|s| (s / l.sa() - 1.0).abs() < 1e-9)
            .unwrap_or(0);
        let m = &l.ens.mean_spectrum.total;
        let pts: Vec<(f64, f64)> = m
            .freq_hz
            .iter()
            .zip(&m.density)
            .filter(|(f, _)| (x.0..=x.1).contains(*f))
            .map(|(f, d)| (*f, d * 1e6))
            .collect();
        let label = if levels.iter().any(|o| o.set != l.set) {
            format!("{} g²/Hz ({})", sa_label(l.sa()), l.set)
        } else {
            format!(
                "{} g²/Hz, mean of {} records",
                sa_label(l.sa()),
                l.ens.records.len()
            )
        };
        let style = if l.set == "calibrated" {
            Style::Dashed
        } else {
            Style::Line
        };
        series.push(Series::new(&label, pts, PALETTE[i % 6], style));
    }
    if theory {
        if let Some(l) = levels.first() {
            let n = 2000;
            let f: Vec<f64> = (0..=n)
                .map(|i| x.0 + (x.1 - x.0) * i as f64 / n as f64)
                .collect();
            let lin = endstop::physics::two_port::linear_output_psd(&l.device, l.sa(), &f);
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
    }
    LinePlot::new(title, "frequency [Hz]", "output power PSD [uW/Hz]", series)
        .x(x.0, x.1)
        .y(y.0, y.1)
        .log(false, true)
        .legend(LegendPos::UpperRight)
}

/// Empirical distribution function of `values` as plot points (sorted value, rank fraction).
pub fn ecdf(values: &[f64]) -> Vec<(f64, f64)> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len() as f64;
    v.iter()
        .enumerate()
        .map(|(i, &x)| (x, (i as f64 + 0.5) / n))
        .collect()
}

/// Sums of `f` over the levels of one set (e.g. total impacts).
pub fn for_set<'a>(levels: &'a [Level], set: &'a str) -> impl Iterator<Item = &'a Level> {
    levels.iter().filter(move |l| l.set == set)
}

/// The level of `set` at `sa` (relative match 1e-9).
pub fn find<'a>(levels: &'a [Level], set: &str, sa: f64) -> &'a Level {
    levels
        .iter()
        .find(|l| l.set == set && (l.sa() / sa - 1.0).abs() < 1e-9)
        .expect("level was simulated")
}

/// A claim of `data/claims.toml` (for reference lines in plots and counts against its
/// tolerance; the scorecard does the comparison).
pub fn claim(id: &str, quantity: &str) -> endstop::paper::claims::Claim {
    let claims = endstop::paper::claims::Claims::bundled()
        .expect("data/claims.toml parses")
        .claims;
    claims
        .into_iter()
        .find(|c| c.id == id && c.quantity == quantity)
        .expect("the claim is in data/claims.toml")
}

/// The paper's value of a claim's quantity.
pub fn paper_value(id: &str, quantity: &str) -> f64 {
    claim(id, quantity).paper
}

/// Prototype 1 as Figures 11 and 12 simulate it (30 V, Hertz contact, b_im = 1.5 N s/m) under
/// both parameter sets: `published` (Tables 1 and 2) and `calibrated` (the end-stop gap fitted
/// to Figure 8's impact onset by `endstop::paper::calibration::calibrate_prototype1`). Records both
/// sets on the experiment and the fitted gap as a number.
pub fn prototype1_sets(exp: &mut crate::Experiment) -> Result<Vec<(String, Device)>> {
    let p1 = crate::load_device("prototype1")?;
    let (cal_loaded, cal) = crate::calibrated_prototype1(&p1)?;
    exp.uses(&p1, "published");
    exp.uses(&cal_loaded, "calibrated");
    let setup = endstop::paper::setups::prototype1_setup;
    exp.number("calibrated_endstop_gap_m", cal.fitted_gap_m);
    exp.number("published_endstop_gap_m", p1.device.geometry.endstop_gap_m);
    Ok(vec![
        ("published".to_string(), setup(&p1.device)),
        ("calibrated".to_string(), setup(&cal.device)),
    ])
}

/// Writes the three Parquet files of a prototype-1 spectra experiment (Figures 11 and 12):
/// `<name>_summary`, `<name>_records` and `<name>_spectra` over `band_hz`, and its plot of the
/// mean output PSDs on a log axis spanning four decades below the highest peak.
pub fn write_p1_spectra(
    exp: &crate::Experiment,
    name: &str,
    title: &str,
    levels: &[Level],
    band_hz: (f64, f64),
    theory: bool,
) -> Result<()> {
    let set_label = "published+calibrated";
    exp.write_parquet(
        &format!("{name}_summary"),
        &mut summary_df(levels)?,
        set_label,
    )?;
    exp.write_parquet(
        &format!("{name}_records"),
        &mut records_df(levels)?,
        set_label,
    )?;
    exp.write_parquet(
        &format!("{name}_spectra"),
        &mut spectra_df(levels, band_hz.0, band_hz.1)?,
        set_label,
    )?;
    let refs: Vec<&Level> = levels.iter().collect();
    let top = refs
        .iter()
        .map(|l| l.ens.mean_spectrum.total.peak().1 * 1e6)
        .fold(0.0, f64::max);
    let y_hi = 10f64.powf((2.0 * top).log10().ceil());
    let plot = spectra_plot(title, &refs, band_hz, (y_hi / 1e4, y_hi), theory);
    exp.write_plot(&plot)
}

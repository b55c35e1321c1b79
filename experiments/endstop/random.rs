//! `endstop random`: random vibration of any device, driven by band-limited white noise (an
//! ensemble of records) or by one measured acceleration record read from a file. Every record
//! is the one record engine's over the device's model (`endstop::study::record`); what is
//! reported follows the model's outputs (`endstop::study::random`, the one entry the Python
//! `ensemble` calls too): a transducer with its own loads gets the loads' power and its
//! spectrum (below), a model with a storage (behind an interface circuit) its DC power,
//! efficiency, storage voltage and energy ledger (written by `random_storage.rs`). A sine drive
//! adds the harvester effectiveness of its power, every drive its normalised power density
//! where the device gives its volume, and noise its power per unit density
//! ([`crate::merit`]).

use std::path::PathBuf;

use anyhow::{bail, Result};
use endstop::device::Device;
use endstop::paper::setups::paper_record;
use endstop::physics::linear::{white_noise_power_w, LinearResponse};
use endstop::physics::two_port::TwoPort;
use endstop::signal::bandwidth::{restrict, Widths};
use endstop::signal::{welch, Psd};
use endstop::study::ensemble::EnsembleSpec;
use endstop::study::random::{random_ensemble, random_record, RandomEnsemble, RandomRecord};
use endstop::study::record::{output_psd, FreeFlightPath, RecordSpec, SampledDrive};
use endstop::G;
use endstop_experiments as common;
use polars::prelude::*;

use common::fmt_sig;
use common::io::plot::Panels;
use common::io::plot::{LinePlot, Series, Style, PALETTE};

use crate::random_args::{read_measured, MeasuredDrive, RandomArgs};
use crate::shared::{describe, mass_peaks_md, start};
use common::reports::sweep_io::mass_columns;
use endstop::study::mass_peaks::MassPeaks;

/// Runs `endstop random`.
pub fn random(a: RandomArgs) -> Result<()> {
    let loaded = common::load_device_file(&a.device)?;
    match (&a.accel_file, a.sine_g, a.psd) {
        (Some(path), _, _) => measured(&a, &loaded.device, Some(path.clone())),
        (None, Some(_), _) => measured(&a, &loaded.device, None),
        (None, None, Some(psd)) => noise(&a, psd),
        (None, None, None) => {
            bail!("give --psd (white noise), --sine-g (a sine) or --accel-file (a measured record)")
        }
    }
}

/// How a record's free flight was integrated, for tables and text.
fn free_flight_label(p: FreeFlightPath) -> String {
    match p {
        FreeFlightPath::Exponential => "exponential".into(),
        FreeFlightPath::Affine => "exact affine modes".into(),
        FreeFlightPath::Dopri5(why) => format!("dormand-prince: {why}"),
    }
}

/// The linear theory the outputs are compared with: the one-mass model linearised about rest
/// with its stops away; none for a device of several masses, which it does not describe (its
/// linear columns are then NaN, and `numbers.md` and `summary.json` say nothing of it).
fn linear_theory(device: &Device) -> Option<LinearResponse> {
    device.masses.is_none().then(|| LinearResponse::of(device))
}

/// The linear theory's power (W), if there is a linear theory, for `numbers.md`.
fn linear_md(power_w: Option<f64>) -> String {
    match power_w {
        Some(p) => format!("{} nW", fmt_sig(p * 1e9, 4)),
        None => "not computed for a device of several masses".into(),
    }
}

/// The two panels: the output power PSD beside its linear theory, and the drive's PSD.
fn spectra_plot(device: &Device, title: &str, out: &Psd, linear: &[f64], drive: &Psd) -> Panels {
    let pts = |p: &[f64], f: &[f64], scale: f64| -> Vec<(f64, f64)> {
        f.iter()
            .zip(p)
            .filter(|(_, d)| **d > 0.0)
            .map(|(&f, &d)| (f, d * scale))
            .collect()
    };
    let out_pts = pts(&out.density, &out.freq_hz, 1e6);
    let ymax = out_pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let response = LinePlot::new(
        &format!("{title}: {}", device.name),
        "frequency [Hz]",
        "output power PSD [uW/Hz] (all loads, one-sided)",
        vec![
            Series::new("simulated", out_pts, PALETTE[0], Style::Line),
            Series::new(
                "linear theory (no stops)",
                pts(linear, &out.freq_hz, 1e6),
                PALETTE[1],
                Style::Dashed,
            ),
        ],
    )
    .log(false, true)
    .y((ymax * 1e-5).max(1e-30), ymax * 3.0);
    let drive_pts = pts(&drive.density, &drive.freq_hz, 1.0);
    let (dmin, dmax) = drive_pts
        .iter()
        .fold((f64::MAX, 0.0f64), |(lo, hi), p| (lo.min(p.1), hi.max(p.1)));
    let drive_plot = LinePlot::new(
        "The drive",
        "frequency [Hz]",
        "base acceleration PSD [g^2/Hz] (two-sided)",
        vec![Series::new("drive", drive_pts, PALETTE[2], Style::Line)],
    )
    .log(false, true)
    .y((dmin * 0.3).max(dmax * 1e-6).max(1e-30), dmax * 3.0)
    .x(out.freq_hz[0], *out.freq_hz.last().unwrap_or(&1.0));
    Panels::row(vec![response, drive_plot])
}

fn noise(a: &RandomArgs, psd: f64) -> Result<()> {
    a.check_noise(psd)?;
    let (mut exp, loaded, device) = start("endstop-random", &a.device, a.bias_v, a.out.clone())?;
    exp.seed = Some(a.seed);
    let mut record = paper_record(&device, psd);
    record.noise.duration_s = a.duration_s;
    let ens = match common::with_progress(a.records, "records", |tick| {
        random_ensemble(&device, &record, a.seed, a.records, tick)
    })? {
        RandomEnsemble::Output(ens) => ens,
        RandomEnsemble::Storage(records) => {
            return crate::random_storage::noise(a, exp, &loaded, &device, psd, &record, &records)
        }
    };
    let nperseg = ens.spec.welch.nperseg;

    let out = &ens.mean_spectrum.total;
    let m = out.freq_hz.len();
    let sa_si = psd * G * G;
    let lin = linear_theory(&device);
    let linear = match &lin {
        Some(l) => l.output_psd(sa_si, &out.freq_hz).density,
        None => vec![f64::NAN; m],
    };
    let mut df = df!(
        "freq_hz" => out.freq_hz.clone(),
        "out_psd_uw_per_hz" => out.density.iter().map(|d| d * 1e6).collect::<Vec<_>>(),
        "linear_psd_uw_per_hz" => linear.iter().map(|d| d * 1e6).collect::<Vec<_>>(),
        "psd_g2_per_hz" => vec![psd; m],
        "series" => vec![format!("mean of {} records", a.records); m],
        "params" => vec![device.params.clone(); m],
    )?;
    exp.write_parquet("output_psd", &mut df, &device.params)?;
    let recs = &ens.records;
    let mut per = df!(
        "realisation" => recs.iter().map(|r| r.stream).collect::<Vec<_>>(),
        "p_w" => recs.iter().map(|r| r.summary.p_total_w()).collect::<Vec<_>>(),
        "x_rms_m" => recs.iter().map(|r| r.summary.x_rms_m).collect::<Vec<_>>(),
        "contact_fraction" => recs.iter().map(|r| r.summary.contact_fraction).collect::<Vec<_>>(),
        "impacts" => recs.iter().map(|r| r.summary.impacts).collect::<Vec<_>>(),
        "bw3db_hz" => recs.iter().map(|r| r.widths.bw3db_hz()).collect::<Vec<_>>(),
        "free_flight" => recs.iter().map(|r| free_flight_label(r.summary.free_flight)).collect::<Vec<_>>(),
        "psd_g2_per_hz" => vec![psd; recs.len()],
        "params" => vec![device.params.clone(); recs.len()],
    )?;
    let masses = mass_columns(&device)?;
    let peaks: Vec<_> = recs.iter().map(|r| r.summary.mass_peaks).collect();
    with_mass_columns(&mut per, &masses, &peaks)?;
    exp.write_parquet("records", &mut per, &device.params)?;

    let disp = displacement(&mut exp, &device, &ens.spec.record, &ens, a)?;
    let band_hz = ens.spec.record.noise.bandwidth_hz;
    let linear_w = lin.map(|_| white_noise_power_w(&device, sa_si, 1e-3, band_hz));
    let eq21 =
        TwoPort::try_of(&device).map(|_| endstop::physics::two_port::eq21_power_w(&device, psd));
    exp.number("power_w", ens.power_w.mean);
    exp.number("power_ci95_w", ens.power_w.ci95);
    exp.number("efficiency", ens.efficiency.mean);
    if let Some(p) = linear_w {
        exp.number("linear_power_w", p);
    }
    if let Some(p) = eq21 {
        exp.number("eq21_power_w", p);
    }
    exp.number("bw3db_hz", ens.mean_widths.bw3db_hz());
    exp.number("contact_fraction", ens.contact_fraction.mean);
    exp.number("x_rms_m", ens.x_rms_m.mean);
    let paths: Vec<String> = recs
        .iter()
        .map(|r| free_flight_label(r.summary.free_flight))
        .collect();
    let mut md = format!(
        "Random vibration of `{}` ({} set; {}): two-sided Sa = {} g^2/Hz up to {} kHz, {} records \
         of {} s, seed {}, Welch segments of {} samples.\n\n\
         - power of the loads: {} nW ± {} nW (95 %); linear theory without stops: {}{}\n\
         - efficiency 2P/(m Sa): {} %{}\n\
         - 3 dB bandwidth of the mean output PSD: {} Hz\n\
         - RMS displacement: {} um; time in contact: {} %; impacts: {}\n\
         - free flight integrated by: {}\n",
        loaded.file,
        device.params,
        describe(&device),
        psd,
        band_hz / 1e3,
        a.records,
        a.duration_s,
        a.seed,
        nperseg,
        fmt_sig(ens.power_w.mean * 1e9, 4),
        fmt_sig(ens.power_w.ci95 * 1e9, 2),
        linear_md(linear_w),
        eq21.map(|p| format!(" (eq 21: {} nW)", fmt_sig(p * 1e9, 4)))
            .unwrap_or_default(),
        fmt_sig(ens.efficiency.mean * 100.0, 4),
        driven_mass_md(&device),
        fmt_sig(ens.mean_widths.bw3db_hz(), 4),
        fmt_sig(ens.x_rms_m.mean * 1e6, 3),
        fmt_sig(ens.contact_fraction.mean * 100.0, 3),
        ens.impacts,
        paths[0],
    );
    if paths.iter().any(|p| p != &paths[0]) {
        md.push_str("- (the records did not all take the same path; see records.parquet)\n");
    }
    md.push_str(&mass_peaks_md(
        &mut exp,
        &masses,
        &ens.mass_peaks,
        "over the records",
    ));
    md.push_str(&disp.md);
    md.push_str(&crate::merit::noise_merits(
        &mut exp,
        &device,
        ens.power_w.mean,
        psd,
        ens.spec.record.noise.mean_square_g2(),
    ));
    exp.write_numbers_md(&md)?;
    print!("{md}");
    let drive = Psd {
        freq_hz: out.freq_hz.clone(),
        density: vec![psd; m],
        segments: 0,
    };
    let mut panels = spectra_plot(
        &device,
        &format!("Output PSD at Sa = {psd} g^2/Hz"),
        out,
        &linear,
        &drive,
    )
    .plots;
    panels.push(disp.plot);
    let plot = Panels::row(panels);
    exp.write_plot(&plot)?;
    exp.finish()
}

/// Fine bins of the displacement histogram.
const DISPLACEMENT_BINS: usize = 80;

/// The displacement outputs of an ensemble: its table, its lines in the numbers and its panel.
struct Displacement {
    md: String,
    plot: LinePlot,
}

/// Reads the ensemble's displacement (a second pass over the same records, streams
/// `0..records` of the seed): the histogram with its 95 % interval across records, beside the
/// exact stationary density where it applies (viscous damping only, lossless stops), and for
/// a device with two wells the rate of passages from one well's bottom to the other's.
fn displacement(
    exp: &mut common::Experiment,
    device: &Device,
    record: &RecordSpec,
    ens: &endstop::study::ensemble::Ensemble,
    a: &RandomArgs,
) -> Result<Displacement> {
    use endstop::study::displacement::{displacement_ensemble, DisplacementBins};
    use endstop::validation::stationary_law::StationaryLaw;
    let reach = 1.02 * ens.x_peak_m.max(f64::MIN_POSITIVE);
    let bins = DisplacementBins::uniform(device, -reach, reach, DISPLACEMENT_BINS);
    let de = common::with_progress(1, "displacement pass over the records", |tick| {
        let r = displacement_ensemble(device, record, &bins, a.seed, a.records as u64);
        tick.tick();
        r
    })?;
    let law = StationaryLaw::of(device, record).ok();
    let dens = de.density();
    let n = dens.len();
    let exact: Vec<f64> = dens
        .iter()
        .map(|(x, _, _)| law.as_ref().map_or(f64::NAN, |l| l.density(*x)))
        .collect();
    let mut df = df!(
        "x_m" => dens.iter().map(|d| d.0).collect::<Vec<_>>(),
        "density_per_m" => dens.iter().map(|d| d.1).collect::<Vec<_>>(),
        "density_ci95_per_m" => dens.iter().map(|d| d.2).collect::<Vec<_>>(),
        "exact_density_per_m" => exact.clone(),
        "params" => vec![device.params.clone(); n],
    )?;
    exp.write_parquet("displacement_pdf", &mut df, &device.params)?;
    let mut md = String::new();
    let rate = de.transition_rate();
    if let Some(([lo, hi], _)) = bins.wells {
        exp.number("transition_rate_per_s", rate.mean);
        exp.number("transition_rate_ci95_per_s", rate.ci95);
        md.push_str(&format!(
            "- bottom-to-bottom passages (from one well's bottom, at {} or {} um, to the other's; \
             not escapes that settle: with light damping a mass above the barrier makes many \
             before it settles): {} per s ± {} (95 %), {} in all\n",
            fmt_sig(lo * 1e6, 4),
            fmt_sig(hi * 1e6, 4),
            fmt_sig(rate.mean, 4),
            fmt_sig(rate.ci95, 2),
            de.transitions()
        ));
        let share = de.stat(|r| r.upper_well_share);
        exp.number("upper_well_share", share.mean);
    }
    md.push_str(&format!(
        "- displacement density: {DISPLACEMENT_BINS} bins over ±{} um, with its 95 % interval \
         across records (displacement_pdf.parquet){}\n",
        fmt_sig(reach * 1e6, 4),
        if law.is_some() {
            "; beside the exact stationary density exp(-U/theta), which applies to this device"
        } else {
            ""
        }
    ));
    let um = |x: f64| x * 1e6;
    let mut series = vec![Series::new(
        "ensemble (bars: 95 %)",
        dens.iter().map(|d| (um(d.0), d.1 / 1e6)).collect(),
        PALETTE[0],
        Style::LinePoints,
    )];
    series.extend(common::io::plot::error_bars(
        dens.iter().map(|d| (um(d.0), d.1 / 1e6, d.2 / 1e6)),
        PALETTE[0],
    ));
    if law.is_some() {
        series.push(Series::new(
            "exact stationary law",
            dens.iter()
                .zip(&exact)
                .map(|(d, e)| (um(d.0), e / 1e6))
                .collect(),
            PALETTE[1],
            Style::Dashed,
        ));
    }
    let plot = LinePlot::new(
        "Displacement density",
        "displacement x [um]",
        "probability density [1/um]",
        series,
    );
    Ok(Displacement { md, plot })
}

/// The record of a measured drive (`path`) or of a sine (`--sine-g`, without a path).
fn measured(a: &RandomArgs, file_device: &Device, path: Option<PathBuf>) -> Result<()> {
    // The provenance's `git status` runs beside the reading and the integration.
    common::git_commit_in_background();
    let mut m = read_measured(a, file_device, path.as_deref())?;
    let (mut exp, loaded, device) = start("endstop-random", &a.device, a.bias_v, a.out.clone())?;
    let drive = SampledDrive {
        accel: m.accel.clone(),
        sample_rate_hz: m.fs,
        transient_samples: m.n_tr,
    };
    m.times.lap("setup");
    let out_rec = match random_record(&device, &drive)? {
        RandomRecord::Output(r) => r,
        RandomRecord::Storage(r) => {
            let file = path.map_or(m.rec.source_name.clone(), |p| p.display().to_string());
            return crate::random_storage::measured(a, exp, &loaded, &device, m, &file, *r);
        }
    };
    let MeasuredDrive {
        rec,
        accel,
        fs,
        n_tr,
        preroll_s,
        band_hz: (lo, hi),
        mut times,
    } = m;
    // The record's text needs its shape alone: its samples are the drive's (shared, or
    // resampled from them) and go with it.
    let rec = RecordRead::of(rec);
    eprintln!(
        "[endstop-random] {}: {} samples at {} Hz resampled to {} Hz ({} s, pre-roll {} s)",
        rec.name,
        rec.samples,
        fmt_sig(rec.rate_hz, 6),
        fs,
        fmt_sig(rec.duration_s, 4),
        preroll_s
    );
    times.lap("integrating");

    // The Welch segmenting and analysis band the noise ensembles use, for this length.
    let mut spec_rec = paper_record(&device, 1.0);
    spec_rec.noise.sample_rate_hz = fs;
    spec_rec.noise.duration_s = (accel.len() - n_tr) as f64 / fs;
    let spec = EnsembleSpec::for_device(&device, spec_rec, 0, 1);
    let rl = device.transducer.load_resistance_ohm();
    let full = output_psd(&out_rec, rl, &spec.welch)?;
    let out = restrict(&full.total, lo, hi);
    // Two-sided, in g^2/Hz, like --psd (in place).
    let mut drive_psd = welch(&accel[n_tr..], fs, &spec.welch)?;
    drive_psd
        .density
        .iter_mut()
        .for_each(|d| *d = *d / 2.0 / (G * G));
    let drive_band = restrict(&drive_psd, lo, hi);
    let lin = linear_theory(&device);
    // The drive's own two-sided density at each frequency, through the same linear PSD.
    let linear_full: Vec<f64> = drive_psd
        .freq_hz
        .iter()
        .zip(&drive_psd.density)
        .map(|(&f, &sa_g2)| match &lin {
            Some(l) => l.output_psd_w_per_hz(sa_g2 * G * G, f),
            None => f64::NAN,
        })
        .collect();
    let df_hz = drive_psd.df();
    let linear_w = lin.map(|_| linear_full.iter().sum::<f64>() * df_hz);
    let linear_band: Vec<f64> = drive_psd
        .freq_hz
        .iter()
        .zip(&linear_full)
        .filter(|(f, _)| (lo..=hi).contains(*f))
        .map(|(_, p)| *p)
        .collect();
    times.lap("spectra");
    // The drive and the record's per-sample outputs are done with: freed before the outputs
    // take their buffers (the figure's raster, the data frames), which reuse their pages
    // instead of fresh ones the kernel zeroes first.
    let summary = out_rec.summary;
    drop((out_rec, drive, accel));

    // The figure is drawn on a thread beside the data files' writing (it reads the spectra
    // alone) and written after them.
    std::thread::scope(|scope| {
        let figure = scope.spawn(|| {
            common::RenderedPlot::of(&spectra_plot(
                &device,
                "Output PSD under a measured record",
                &out,
                &linear_band,
                &drive_band,
            ))
        });
        let written = measured_outputs(
            a,
            &mut exp,
            &loaded.file,
            &device,
            &rec,
            &summary,
            &out,
            (&linear_band, linear_w),
            &drive_band,
            MeasuredShape {
                fs,
                preroll_s,
                band_hz: (lo, hi),
                nperseg: spec.welch.nperseg,
            },
        );
        let figure = figure
            .join()
            .map_err(|_| anyhow::anyhow!("drawing the figure failed (its thread panicked)"))?;
        written?;
        let stem = exp.name.clone();
        exp.write_rendered_plot(&stem, figure?)
    })?;
    times.lap("output");
    times.report("endstop-random", &mut exp);
    exp.finish()
}

/// A measured record as read, for the run's text: its name, its samples, its rate (Hz) and
/// its duration (s).
struct RecordRead {
    name: String,
    samples: usize,
    rate_hz: f64,
    duration_s: f64,
}

impl RecordRead {
    /// The shape of `rec`, which it drops (with its share of the samples).
    fn of(rec: endstop::drive::measured::MeasuredRecord) -> Self {
        Self {
            name: rec.source_name.clone(),
            samples: rec.accel_si.len(),
            rate_hz: rec.sample_rate_hz,
            duration_s: rec.duration_s(),
        }
    }
}

/// The sampling of a measured record's run, for its text: the integrator's rate (Hz), the
/// pre-roll (s), the analysis band (Hz) and the Welch segment length (samples).
struct MeasuredShape {
    fs: f64,
    preroll_s: f64,
    band_hz: (f64, f64),
    nperseg: usize,
}

/// Writes a measured record's data files and numbers (the figure is the caller's): its output
/// PSD beside the linear theory's (`linear`: the band's densities and the total power), the
/// record's row, and `numbers.md`.
#[allow(clippy::too_many_arguments)]
fn measured_outputs(
    a: &RandomArgs,
    exp: &mut common::Experiment,
    device_file: &str,
    device: &Device,
    rec: &RecordRead,
    s: &endstop::study::record::RecordSummary,
    out: &Psd,
    (linear_band, linear_w): (&[f64], Option<f64>),
    drive_band: &Psd,
    shape: MeasuredShape,
) -> Result<()> {
    let MeasuredShape {
        fs,
        preroll_s,
        band_hz: (lo, hi),
        nperseg,
    } = shape;
    let m = out.freq_hz.len();
    let file = rec.name.clone();
    let mut df = df!(
        "freq_hz" => out.freq_hz.clone(),
        "out_psd_uw_per_hz" => out.density.iter().map(|d| d * 1e6).collect::<Vec<_>>(),
        "linear_psd_uw_per_hz" => linear_band.iter().map(|d| d * 1e6).collect::<Vec<_>>(),
        "psd_g2_per_hz" => drive_band.density.clone(),
        "series" => vec![format!("measured record {file}"); m],
        "params" => vec![device.params.clone(); m],
    )?;
    exp.write_parquet("output_psd", &mut df, &device.params)?;
    let accel_rms_g = s.accel_mean_square_si.sqrt() / G;
    let widths = Widths::of(out);
    let mut per = df!(
        "realisation" => [0u64],
        "p_w" => [s.p_total_w()],
        "x_rms_m" => [s.x_rms_m],
        "contact_fraction" => [s.contact_fraction],
        "impacts" => [s.impacts],
        "bw3db_hz" => [widths.bw3db_hz()],
        "free_flight" => [free_flight_label(s.free_flight)],
        "accel_rms_g" => [accel_rms_g],
        "params" => [device.params.clone()],
    )?;
    let masses = mass_columns(device)?;
    with_mass_columns(&mut per, &masses, &[s.mass_peaks])?;
    exp.write_parquet("records", &mut per, &device.params)?;

    exp.number("power_w", s.p_total_w());
    if let Some(p) = linear_w {
        exp.number("linear_power_w", p);
    }
    exp.number("accel_rms_g", accel_rms_g);
    exp.number("bw3db_hz", widths.bw3db_hz());
    exp.number("contact_fraction", s.contact_fraction);
    exp.number("x_rms_m", s.x_rms_m);
    let mut md = format!(
        "Measured drive on `{}` ({} set; {}): record `{file}` ({} samples at {} Hz, {} s), \
         resampled to {} Hz; the first {} s (five ring-up times) discarded; spectra in the band \
         {} to {} Hz, Welch segments of {} samples.\n\n\
         - RMS acceleration of the analysed record: {} g\n\
         - power of the loads: {} nW; linear theory without stops under the same spectrum: {}\n\
         - RMS displacement: {} um; time in contact: {} %; impacts: {}\n\
         - free flight integrated by: {}\n",
        device_file,
        device.params,
        describe(device),
        rec.samples,
        fmt_sig(rec.rate_hz, 6),
        fmt_sig(rec.duration_s, 4),
        fs,
        preroll_s,
        fmt_sig(lo, 4),
        fmt_sig(hi, 4),
        nperseg,
        fmt_sig(accel_rms_g, 4),
        fmt_sig(s.p_total_w() * 1e9, 4),
        linear_md(linear_w),
        fmt_sig(s.x_rms_m * 1e6, 3),
        fmt_sig(s.contact_fraction * 100.0, 3),
        s.impacts,
        free_flight_label(s.free_flight),
    );
    md.push_str(&mass_peaks_md(
        exp,
        &masses,
        &s.mass_peaks,
        "over the analysed record",
    ));
    let md = md + &crate::merit::drive_merits(exp, a, device, s.p_total_w(), accel_rms_g);
    exp.write_numbers_md(&md)?;
    print!("{md}");
    Ok(())
}

/// Adds to `df` (one row per record) each mass's peaks of the records, under the per-mass
/// column names `names` (none for a device of one mass).
fn with_mass_columns(
    df: &mut DataFrame,
    names: &[&'static str],
    peaks: &[MassPeaks],
) -> Result<()> {
    let values: Vec<Vec<f64>> = peaks.iter().map(MassPeaks::values).collect();
    for (i, name) in names.iter().enumerate() {
        let col: Vec<Option<f64>> = values.iter().map(|v| v.get(i).copied()).collect();
        df.with_column(polars::prelude::Series::new((*name).into(), col))?;
    }
    Ok(())
}

/// What `m` of the efficiency is on a device of several masses (empty for one mass): the mass
/// the drive acts on, whose `m Sa / 2` is the power a white noise puts in.
fn driven_mass_md(device: &endstop::device::Device) -> String {
    match &device.masses {
        None => String::new(),
        Some(m) => format!(
            " (m = {} g, {}: the power the noise puts in is m Sa / 2 whatever the springs, \
             dampers and contacts)",
            fmt_sig(m.driven_mass_kg() * 1e3, 4),
            match m.drive_mass {
                Some(j) => format!("the driven mass `{}`", m.bodies[j].name),
                None => "the total mass, every mass driven by the frame".to_string(),
            }
        ),
    }
}

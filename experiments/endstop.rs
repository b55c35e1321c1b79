//! `endstop`: run the Le & Halvorsen (2012) harvester model on your own device file.
//!
//! ```text
//! endstop sweep  --device my.toml --from 500 --to 900 --accel-rms-g 0.3 [--out DIR]
//! endstop random --device my.toml --psd 1e-3 [--out DIR]
//! endstop response --device my.toml --from 600 --to 850 --accel-rms-g 0.31 [--out DIR]
//! ```
//!
//! Both write the same kinds of output as the figure experiments: Parquet data with
//! provenance metadata, an SVG and a PNG plot, `summary.json`, and `numbers.md`.

use endstop::paper::setups::comb;
use endstop_experiments as common;

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device_file, Experiment, LoadedDevice};
use endstop::device::Device;
use endstop::study::ensemble::EnsembleSpec;
use endstop::study::record::RecordSpec;
use endstop::study::stepped::linspace_step;
use endstop::study::sweep::{self, SweepSettings, REFINE_TOL_HZ};
use polars::prelude::*;

#[derive(Parser, Debug)]
#[command(
    name = "endstop",
    version,
    about = "Simulate a MEMS electrostatic energy harvester with end-stops on your own device",
    long_about = "Simulate a MEMS electrostatic energy harvester with end-stops (the model of \
Le & Halvorsen 2012, eqs 1-10) on a device described by a TOML file. Start from \
data/prototype1.toml or data/prototype2.toml: copy it, edit the values (SI units; the key names \
carry the unit), and pass it with --device. Every value is checked on load; an error names the \
field and its valid range.\n\nTwo studies:\n  sweep   stepped-sine up-sweep: RMS voltages, power, \
impact onset and jump\n  random  band-limited white-noise vibration: power, efficiency, \
output spectrum, bandwidth\n  response  the whole frequency response: up- and down-sweeps, periodic orbits continued \
in frequency with their stability, folds and grazing points"
)]
struct Cli {
    #[command(subcommand)]
    study: Study,
}

#[derive(Subcommand, Debug)]
enum Study {
    /// Stepped-sine up-sweep with continuation (each frequency starts from the previous
    /// steady state), with impact onset and jump refined by bisection.
    Sweep(RangeArgs),
    /// Random vibration: an ensemble of band-limited white-noise records (10 kHz band,
    /// 100 kHz sampling), with mean power, efficiency and output power spectrum.
    Random(RandomArgs),
    /// The whole frequency response: up- and down-sweeps, the periodic orbits continued in
    /// frequency (pseudo-arclength, through folds) with their Floquet multipliers, and the
    /// folds and grazing points on the branch.
    Response(RangeArgs),
}

/// The arguments of the two frequency studies (`sweep` and `response`).
#[derive(Parser, Debug)]
struct RangeArgs {
    /// Device file (TOML), e.g. a copy of data/prototype2.toml.
    #[arg(long)]
    device: PathBuf,
    /// Lowest frequency (Hz).
    #[arg(long)]
    from: f64,
    /// Highest frequency (Hz).
    #[arg(long)]
    to: f64,
    /// Frequency step of the sweeps, and largest step of the continuation (Hz).
    #[arg(long, default_value_t = 2.0)]
    step: f64,
    /// RMS base acceleration (g = 9.81 m/s^2); the sine's amplitude is sqrt(2) times this.
    #[arg(long)]
    accel_rms_g: f64,
    /// Bias voltage (V); default: the device file's.
    #[arg(long)]
    bias_v: Option<f64>,
    /// Output directory; default: data/results/endstop-<study>.
    #[arg(long)]
    out: Option<PathBuf>,
}

impl RangeArgs {
    /// Refuses a range, step or acceleration that no sweep can use
    /// ([`sweep::check_range`]), naming the option.
    fn check(&self) -> Result<()> {
        sweep::check_range(self.accel_rms_g, self.from, self.to, self.step).map_err(|e| {
            anyhow::anyhow!(match e {
                sweep::RangeError::Ends => {
                    "--from and --to must be positive frequencies with --to > --from"
                }
                sweep::RangeError::Step => "--step must be positive and not larger than the range",
                sweep::RangeError::Accel => "--accel-rms-g must be a finite positive number",
            })
        })
    }

    /// The sweep settings of the range ([`SweepSettings::for_device`]).
    fn sweep_settings(&self, device: &Device) -> SweepSettings {
        SweepSettings::for_device(
            device,
            linspace_step(self.from, self.to, self.step),
            REFINE_TOL_HZ,
        )
    }
}

#[derive(Parser, Debug)]
struct RandomArgs {
    /// Device file (TOML), e.g. a copy of data/prototype2.toml.
    #[arg(long)]
    device: PathBuf,
    /// Two-sided acceleration PSD in the flat band (g^2/Hz).
    #[arg(long)]
    psd: f64,
    /// Number of independent 10 s records (their mean and 95 % interval are reported).
    #[arg(long, default_value_t = 4)]
    records: usize,
    /// Length of each record (s).
    #[arg(long, default_value_t = 10.0)]
    duration_s: f64,
    /// Seed of the random streams (record i uses stream i).
    #[arg(long, default_value_t = 2012)]
    seed: u64,
    /// Bias voltage (V); default: the device file's.
    #[arg(long)]
    bias_v: Option<f64>,
    /// Output directory; default: data/results/endstop-random.
    #[arg(long)]
    out: Option<PathBuf>,
}

fn main() {
    common::run_main("endstop", || match Cli::parse().study {
        Study::Sweep(a) => sweep(a),
        Study::Random(a) => random(a),
        Study::Response(a) => response(a),
    });
}

fn out_dir(p: PathBuf) -> PathBuf {
    if p.is_absolute() {
        p
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    }
}

/// Loads the device file `path`, applies `--bias-v` if given (validated), and starts the
/// experiment `name` writing to `out`, with the device file recorded: the experiment, the file
/// as loaded, and the device to simulate.
fn start(
    name: &str,
    path: &Path,
    bias_v: Option<f64>,
    out: Option<PathBuf>,
) -> Result<(Experiment, LoadedDevice, Device)> {
    let loaded = load_device_file(path)?;
    let mut device = loaded.device.clone();
    if let Some(v) = bias_v {
        device = device.with_bias(v);
        device.validate("--bias-v")?;
    }
    let out = out.unwrap_or_else(|| PathBuf::from("data/results").join(name));
    let mut exp = Experiment::start_in(name, out_dir(out));
    exp.uses(&loaded, &device.params);
    Ok((exp, loaded, device))
}

fn sweep(a: RangeArgs) -> Result<()> {
    a.check()?;
    let (mut exp, loaded, device) = start("endstop-sweep", &a.device, a.bias_v, a.out.clone())?;
    let settings = a.sweep_settings(&device);
    let report = common::with_progress(settings.freqs_hz.len(), "sweep", |tick| {
        settings.run(&device, a.accel_rms_g, |_| tick())
    })?;

    let steps = &report.sweep.steps;
    let col = |f: &dyn Fn(&endstop::study::steady::Measurement) -> f64| -> Vec<f64> {
        steps.iter().map(|s| f(&s.measurement)).collect()
    };
    let rows = common::narrowband_io::sweep_rows(
        &format!("{} g rms up-sweep", a.accel_rms_g),
        &device,
        report.measurements(),
        report.extended_from,
    );
    let mut df = common::frame::frame(rows)?;
    exp.write_parquet("sweep", &mut df, &device.params)?;

    let mut md = format!(
        "Up-sweep of `{}` ({} set) from {} to {} Hz in {} Hz steps at {} g rms, Vb = {} V.\n\n",
        loaded.file,
        device.params,
        a.from,
        a.to,
        a.step,
        a.accel_rms_g,
        comb(&device).bias_v
    );
    let vmax = col(&|m| m.v1_rms_v).into_iter().fold(0.0, f64::max);
    exp.number("v1_rms_max_v", vmax);
    md.push_str(&format!(
        "- largest RMS voltage of one load: {} V\n",
        fmt_sig(vmax, 4)
    ));
    match report.onset {
        Some(t) => {
            exp.number("impact_onset_hz", t.value());
            md.push_str(&format!(
                "- impacts begin at {} Hz (bracket {}-{} Hz)\n",
                fmt_sig(t.value(), 5),
                fmt_sig(t.before, 5),
                fmt_sig(t.after, 5)
            ));
        }
        None if report.contact_at_start => md.push_str("- in contact from the first step\n"),
        None => md.push_str("- no impact in this range\n"),
    }
    if let Some(end) = report.branch_end() {
        exp.number("branch_end_hz", end.transition.value());
        md.push_str(&format!(
            "- the impacting branch ends at {} Hz ({})\n",
            fmt_sig(end.transition.value(), 5),
            end.kind.label()
        ));
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");

    let pts = |f: &dyn Fn(&endstop::study::steady::Measurement) -> f64| -> Vec<(f64, f64)> {
        steps
            .iter()
            .map(|s| (s.measurement.freq_hz, f(&s.measurement)))
            .collect()
    };
    let plot = LinePlot::new(
        &format!("Up-sweep at {} g rms: {}", a.accel_rms_g, device.name),
        "frequency [Hz]",
        "RMS output voltage [V]",
        vec![
            Series::new(
                "V1 (one load)",
                pts(&|m| m.v1_rms_v),
                PALETTE[0],
                Style::LinePoints,
            ),
            Series::new(
                "V2 - V1",
                pts(&|m| m.vdiff_rms_v),
                PALETTE[1],
                Style::Dashed,
            ),
        ],
    )
    .legend(LegendPos::UpperLeft);
    exp.write_plot(&plot)?;
    exp.finish()
}

fn random(a: RandomArgs) -> Result<()> {
    if !(a.psd.is_finite() && a.psd > 0.0) {
        bail!("--psd must be a positive two-sided PSD in g^2/Hz");
    }
    if a.records == 0 {
        bail!("--records must be at least 1");
    }
    let (mut exp, loaded, device) = start("endstop-random", &a.device, a.bias_v, a.out)?;
    exp.seed = Some(a.seed);
    let mut record = RecordSpec::paper(&device, a.psd);
    record.noise.duration_s = a.duration_s;
    let spec = EnsembleSpec::for_device(&device, record, a.seed, a.records);
    let nperseg = spec.welch.nperseg;
    let ens = common::with_progress(a.records, "records", |tick| {
        endstop::study::ensemble::run_ensemble(&device, &spec, tick)
    })?;

    let psd = &ens.mean_spectrum.total;
    let m = psd.freq_hz.len();
    let mut df = df!(
        "freq_hz" => psd.freq_hz.clone(),
        "out_psd_uw_per_hz" => psd.density.iter().map(|d| d * 1e6).collect::<Vec<_>>(),
        "psd_g2_per_hz" => vec![a.psd; m],
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
        "psd_g2_per_hz" => vec![a.psd; recs.len()],
        "params" => vec![device.params.clone(); recs.len()],
    )?;
    exp.write_parquet("records", &mut per, &device.params)?;

    let eq21 = endstop::physics::two_port::eq21_power_w(&device, a.psd);
    exp.number("power_w", ens.power_w.mean);
    exp.number("power_ci95_w", ens.power_w.ci95);
    exp.number("efficiency", ens.efficiency.mean);
    exp.number("eq21_power_w", eq21);
    exp.number("bw3db_hz", ens.mean_widths.bw3db_hz());
    exp.number("contact_fraction", ens.contact_fraction.mean);
    let md = format!(
        "Random vibration of `{}` ({} set): two-sided Sa = {} g^2/Hz up to 10 kHz, {} records of {} s, seed {}, Welch segments of {} samples.\n\n\
         - power of both loads: {} nW ± {} nW (95 %); linear theory (eq 21): {} nW\n\
         - efficiency 2P/(m Sa): {} %\n\
         - 3 dB bandwidth of the mean output PSD: {} Hz\n\
         - RMS displacement: {} um; time in contact: {} %; impacts: {}\n",
        loaded.file,
        device.params,
        a.psd,
        a.records,
        a.duration_s,
        a.seed,
        nperseg,
        fmt_sig(ens.power_w.mean * 1e9, 4),
        fmt_sig(ens.power_w.ci95 * 1e9, 2),
        fmt_sig(eq21 * 1e9, 4),
        fmt_sig(ens.efficiency.mean * 100.0, 4),
        fmt_sig(ens.mean_widths.bw3db_hz(), 4),
        fmt_sig(ens.x_rms_m.mean * 1e6, 3),
        fmt_sig(ens.contact_fraction.mean * 100.0, 3),
        ens.impacts
    );
    exp.write_numbers_md(&md)?;
    print!("{md}");
    let pts: Vec<(f64, f64)> = psd
        .freq_hz
        .iter()
        .zip(&psd.density)
        .map(|(&f, &d)| (f, d * 1e6))
        .collect();
    let ymax = pts.iter().map(|p| p.1).fold(0.0, f64::max);
    let plot = LinePlot::new(
        &format!("Output power PSD at Sa = {} g^2/Hz: {}", a.psd, device.name),
        "frequency [Hz]",
        "output power PSD [uW/Hz] (both loads, one-sided)",
        vec![Series::new(
            &format!("mean of {} records", a.records),
            pts,
            PALETTE[0],
            Style::Line,
        )],
    )
    .log(false, true)
    .y((ymax * 1e-5).max(1e-30), ymax * 2.0);
    exp.write_plot(&plot)?;
    exp.finish()
}

fn response(a: RangeArgs) -> Result<()> {
    use common::frame::frame;
    use common::response_io::{continuation_rows, response_figure};
    use common::row;
    use endstop::study::continuation::{frequency_branch, EventKind};

    a.check()?;
    let (mut exp, loaded, device) = start("endstop-response", &a.device, a.bias_v, a.out.clone())?;
    let settings = a.sweep_settings(&device);
    let freqs = &settings.freqs_hz;
    let (up, down) = common::with_progress(2 * freqs.len(), "sweeps", |tick| {
        rayon::join(
            || settings.run(&device, a.accel_rms_g, |_| tick()),
            || settings.run_down(&device, a.accel_rms_g, |_| tick()),
        )
    });
    let (up, down) = (up?, down?);
    eprintln!(
        "[endstop-response] continuing the periodic orbits from {} Hz",
        a.from
    );
    let branch = frequency_branch(&device, a.accel_rms_g, a.from, a.to, a.step, |_| {})?;

    let rows = continuation_rows(&device.name, &branch);
    exp.write_parquet("continuation", &mut frame(rows)?, &device.params)?;
    let mut rows = Vec::new();
    for (dir, ms) in [
        ("up", up.measurements().collect::<Vec<_>>()),
        ("down", down.measurements().collect()),
    ] {
        for m in ms {
            rows.push(row![
                "direction" => dir,
                "freq_hz" => m.freq_hz,
                "v1_rms_v" => m.v1_rms_v,
                "x_max_m" => m.x_peak_m,
                "contact_fraction" => m.contact_fraction,
            ]);
        }
    }
    exp.write_parquet("sweeps", &mut frame(rows)?, &device.params)?;

    let mut md = format!(
        "Whole response of `{}` ({} set) from {} to {} Hz at {} g rms, Vb = {} V: sweeps in {} Hz \
         steps (transitions refined to 0.1 Hz), periodic orbits continued in frequency \
         ({} points, largest residual {:.1e}).\n\n",
        loaded.file,
        device.params,
        a.from,
        a.to,
        a.accel_rms_g,
        comb(&device).bias_v,
        a.step,
        branch.points.len(),
        branch.max_residual()
    );
    if let Some(e) = up.branch_end() {
        exp.number("up_branch_end_hz", e.transition.value());
        md.push_str(&format!(
            "- the up-sweep leaves the impacting branch at {} Hz ({})\n",
            fmt_sig(e.transition.value(), 6),
            e.kind.label()
        ));
    }
    if let Some((kind, t)) = down.branch_end() {
        exp.number("down_branch_end_hz", t.value());
        md.push_str(&format!(
            "- the down-sweep leaves the lower branch at {} Hz ({})\n",
            fmt_sig(t.value(), 6),
            kind.label()
        ));
    }
    for (i, e) in branch.events.iter().enumerate() {
        let kind = if e.kind == EventKind::Fold && e.at_grazing {
            "fold at a grazing corner"
        } else {
            e.kind.label()
        };
        exp.number(&format!("event_{i}_hz"), e.param);
        md.push_str(&format!(
            "- {kind} at {} Hz (stable {} -> {})\n",
            fmt_sig(e.param, 7),
            e.stable_before,
            e.stable_after
        ));
    }
    if branch.events.is_empty() {
        md.push_str("- no fold, bifurcation or grazing in this range\n");
    }
    exp.write_numbers_md(&md)?;
    print!("{md}");

    let steps = |ms: Vec<&endstop::study::steady::Measurement>| -> Vec<(f64, f64)> {
        ms.into_iter().map(|m| (m.freq_hz, m.v1_rms_v)).collect()
    };
    let plot = response_figure(
        &format!(
            "Whole response at {} g rms: {} (orbits: solid stable, dashed unstable)",
            a.accel_rms_g, device.name
        ),
        &branch,
        steps(up.measurements().collect()),
        steps(down.measurements().collect()),
        (a.from, a.to),
    );
    exp.write_plot(&plot)?;
    exp.finish()
}

//! `endstop`: run the harvester model of Le & Halvorsen (2012), generalised to any
//! single-degree-of-freedom impact harvester, on your own device file.
//!
//! ```text
//! endstop sweep    --device my.toml --from 500 --to 900 --accel-rms-g 0.3 [--out DIR]
//! endstop random   --device my.toml --psd 1e-3 [--out DIR]
//! endstop random   --device my.toml --accel-file shaker.csv [--out DIR]
//! endstop response --device my.toml --from 600 --to 850 --accel-rms-g 0.31 [--out DIR]
//! endstop fit --device my.toml --up-sweep up.csv [--down-sweep down.csv] \
//!             --free stops.both.gap_m=7e-6..10e-6 [--free ...] [--out DIR]
//! ```
//!
//! Each writes the same kinds of output as the figure experiments: Parquet data with
//! provenance metadata, an SVG and a PNG plot, `summary.json`, and `numbers.md`. Any device
//! the description allows runs (any stops, any transducer); the column names are the same for
//! every device, and for a transducer with one load the second load's columns are zero.

mod random;

use endstop_experiments as common;

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device_file, Experiment, LoadedDevice};
use endstop::device::Device;
use endstop::study::stepped::linspace_step;
use endstop::study::sweep::{self, SweepSettings, REFINE_TOL_HZ};

#[derive(Parser, Debug)]
#[command(
    name = "endstop",
    version,
    about = "Simulate a vibration energy harvester with end-stops on your own device",
    long_about = "Simulate a vibration energy harvester with end-stops (the model of \
Le & Halvorsen 2012, eqs 1-10, with any stops and transducer) on a device described by a TOML \
file. Start from data/prototype1.toml, data/prototype2.toml or a file of data/examples/: copy \
it, edit the values (SI units; the key names carry the unit), and pass it with --device. Every \
value is checked on load; an error names the file, the field, the value and its valid \
range.\n\nThree studies:\n  sweep     stepped-sine up-sweep: RMS voltages, power, impact onset \
and jump\n  random    band-limited white noise or a measured acceleration record: power, \
efficiency, output spectrum, bandwidth\n  response  the whole frequency response: up- and \
down-sweeps, periodic orbits continued in frequency with their stability, folds and grazing \
points\n\nOutputs keep their column names for every device: v1_rms_v and p1_w are the load of a \
one-load transducer (piezoelectric, electromagnetic), and v2_rms_v, p2_w are then zero."
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
    /// 100 kHz sampling), or one measured acceleration record (--accel-file), with mean
    /// power, output power spectrum and the drive's spectrum.
    Random(random::RandomArgs),
    /// The whole frequency response: up- and down-sweeps, the periodic orbits continued in
    /// frequency (pseudo-arclength, through folds) with their Floquet multipliers, and the
    /// folds and grazing points on the branch.
    Response(RangeArgs),
    /// Fit free device parameters to measured sweeps (CSV with units in the header): the
    /// fitted device file with provenance, values with standard errors and 95 % intervals,
    /// their correlation, warnings for what the data do not determine, and plots of the data
    /// against the fitted model with residuals.
    Fit(common::fit_io::FitArgs),
}

/// The arguments of the two frequency studies (`sweep` and `response`): a sine drive (a
/// measured record drives `random` only, whose spectra it is analysed by).
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
    /// Bias voltage (V) of an electrostatic transducer; default: the device file's. Refused
    /// for a device without a bias (piezoelectric, electromagnetic, none).
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
                sweep::RangeError::Step => "--step must be positive, not larger than the range, and give at most 100000 steps",
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

fn main() {
    common::run_main("endstop", || match Cli::parse().study {
        Study::Sweep(a) => sweep(a),
        Study::Random(a) => random::random(a),
        Study::Response(a) => response(a),
        Study::Fit(a) => common::fit_io::run(a),
    });
}

pub(crate) fn out_dir(p: PathBuf) -> PathBuf {
    if p.is_absolute() {
        p
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    }
}

/// Loads the device file `path`, applies `--bias-v` if given (validated; refused for a
/// device without a bias voltage), and starts the experiment `name` writing to `out`, with the
/// device file recorded: the experiment, the file as loaded, and the device to simulate.
pub(crate) fn start(
    name: &str,
    path: &Path,
    bias_v: Option<f64>,
    out: Option<PathBuf>,
) -> Result<(Experiment, LoadedDevice, Device)> {
    let loaded = load_device_file(path)?;
    let mut device = loaded.device.clone();
    if let Some(v) = bias_v {
        if device.bias_v().is_none() {
            bail!(
                "--bias-v: device `{}` has a `{}` transducer, which has no bias voltage",
                device.name,
                device.transducer.key()
            );
        }
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
        "Up-sweep of `{}` ({} set; {}) from {} to {} Hz in {} Hz steps at {} g rms.\n\n",
        loaded.file,
        device.params,
        describe(&device),
        a.from,
        a.to,
        a.step,
        a.accel_rms_g,
    );
    let vmax = col(&|m| m.v1_rms_v).into_iter().fold(0.0, f64::max);
    let pmax = col(&|m| m.p_total_w()).into_iter().fold(0.0, f64::max);
    exp.number("v1_rms_max_v", vmax);
    exp.number("power_max_w", pmax);
    md.push_str(&format!(
        "- largest RMS voltage of load 1: {} V; largest power of the loads: {} uW\n",
        fmt_sig(vmax, 4),
        fmt_sig(pmax * 1e6, 4)
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
    let mut series = vec![Series::new(
        if device.transducer.loads() == 2 {
            "V1 (one load)"
        } else {
            "V (the load)"
        },
        pts(&|m| m.v1_rms_v),
        PALETTE[0],
        Style::LinePoints,
    )];
    if device.transducer.loads() == 2 {
        series.push(Series::new(
            "V2 - V1",
            pts(&|m| m.vdiff_rms_v),
            PALETTE[1],
            Style::Dashed,
        ));
    }
    let plot = LinePlot::new(
        &format!("Up-sweep at {} g rms: {}", a.accel_rms_g, device.name),
        "frequency [Hz]",
        "RMS output voltage [V]",
        series,
    )
    .legend(LegendPos::UpperLeft);
    exp.write_plot(&plot)?;
    exp.finish()
}

fn response(a: RangeArgs) -> Result<()> {
    use common::frame::frame;
    use common::response_io::{diagram_figure, diagram_rows, diagram_words};
    use common::row;
    use endstop::study::continuation::frequency_diagram;

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
    let diagram = frequency_diagram(&device, a.accel_rms_g, a.from, a.to, a.step, |b| {
        eprintln!("[endstop-response]   branch: {b}")
    })?;

    let rows = diagram_rows(&device.name, &diagram);
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

    let points: usize = diagram.branches.iter().map(|b| b.points.len()).sum();
    let residual = diagram
        .branches
        .iter()
        .flat_map(|b| &b.points)
        .map(|p| p.residual)
        .fold(0.0, f64::max);
    let mut md = format!(
        "Whole response of `{}` ({} set; {}) from {} to {} Hz at {} g rms: sweeps in {} Hz \
         steps (transitions refined to 0.1 Hz), periodic orbits continued in frequency \
         ({} branches, {} points, largest residual {:.1e}).\n\n",
        loaded.file,
        device.params,
        describe(&device),
        a.from,
        a.to,
        a.accel_rms_g,
        a.step,
        diagram.branches.len(),
        points,
        residual
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
    for (i, e) in diagram.events.iter().enumerate() {
        exp.number(&format!("event_{i}_hz"), e.param);
    }
    md.push_str(&diagram_words(&diagram));
    exp.write_numbers_md(&md)?;
    print!("{md}");

    let steps = |ms: Vec<&endstop::study::steady::Measurement>| -> Vec<(f64, f64)> {
        ms.into_iter().map(|m| (m.freq_hz, m.v1_rms_v)).collect()
    };
    let plot = diagram_figure(
        &format!(
            "Whole response at {} g rms: {} (orbits: solid stable, dashed unstable)",
            a.accel_rms_g, device.name
        ),
        &diagram,
        steps(up.measurements().collect()),
        steps(down.measurements().collect()),
        (a.from, a.to),
    );
    exp.write_plot(&plot)?;
    exp.finish()
}

/// One line on what a device is: its transducer (with its bias voltage, and a note where it
/// has one load) and each side's stop.
pub(crate) fn describe(device: &Device) -> String {
    let t = &device.transducer;
    let transducer = match (t.bias_v(), t.loads()) {
        (Some(vb), _) => format!("`{}` transducer at Vb = {vb} V", t.key()),
        (None, 1) => format!("`{}` transducer, one load (v2 is zero)", t.key()),
        (None, _) => format!("`{}` transducer", t.key()),
    };
    let side = |s: Option<&endstop::device::Stop>| match s {
        Some(s) => format!("`{}` at {} um", s.law.key(), fmt_sig(s.gap_m * 1e6, 4)),
        None => "none".to_string(),
    };
    let stops = match device.stops.symmetric() {
        Some(s) => format!("stops on both sides: {}", side(Some(s))),
        None => format!(
            "upper stop {}, lower stop {}",
            side(device.stops.upper.as_ref()),
            side(device.stops.lower.as_ref())
        ),
    };
    format!("{transducer}, {stops}")
}

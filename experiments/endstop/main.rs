//! `endstop`: run the harvester model of Le & Halvorsen (2012), generalised to any
//! single-degree-of-freedom impact harvester, on your own device file.
//!
//! ```text
//! endstop sweep    --device my.toml --from 500 --to 900 --accel-rms-g 0.3 [--out DIR]
//! endstop random   --device my.toml --psd 1e-3 [--out DIR]
//! endstop random   --device my.toml --accel-file shaker.csv [--out DIR]
//! endstop response --device my.toml --from 600 --to 850 --accel-rms-g 0.31 [--out DIR]
//! endstop basins   --device my.toml --freq 30 --accel-rms-g 0.5 [--cells 41] [--out DIR]
//! endstop fit --device my.toml --up-sweep up.csv [--down-sweep down.csv] \
//!             --free stops.both.gap_m=7e-6..10e-6 [--free ...] [--out DIR]
//! ```
//!
//! Each writes the same kinds of output as the figure experiments: Parquet data with
//! provenance metadata, an SVG and a PNG plot, `summary.json`, and `numbers.md`. Any device
//! the description allows runs (any stops, any transducer); the column names are the same for
//! every device, and for a transducer with one load the second load's columns are zero.

mod basins;
mod interface;
mod interface_response;
mod random;
mod response;

use endstop_experiments as common;

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::{Parser, Subcommand};
use common::plot::{LegendPos, LinePlot, Series, Style, PALETTE};
use common::{fmt_sig, load_device_file, Experiment, LoadedDevice};
use endstop::device::Device;
use endstop::study::chirp::{
    default_ramp_rate_hz_per_s, default_step_hz, half_power_band, HalfPowerBand,
};
use endstop::study::stepped::{linspace_step, Approach};
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
range.\n\nThe studies (besides charge and fit):\n  sweep     stepped-sine up-sweep: RMS \
voltages, power, impact onset and jump\n  random    band-limited white noise or a measured \
acceleration record: power, efficiency, output spectrum, bandwidth\n  response  the whole \
frequency response: up- and down-sweeps, periodic orbits continued in frequency with their \
stability, folds and grazing points\n  basins    which of the coexisting stable orbits each \
initial state ends on under a fixed sine (for a double well: in which well)\n\nOutputs keep \
their column names for every device: v1_rms_v and p1_w are the load of a one-load transducer \
(piezoelectric, electromagnetic), and v2_rms_v, p2_w are then zero."
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
    /// folds and grazing points on the branch. On a device with an interface circuit: the DC
    /// up- and down-sweeps and the steady state continued through its folds, with stability.
    Response(response::ResponseArgs),
    /// Basins of attraction under a fixed sine: the stable periodic orbits reached from a set
    /// of seeds (for a device with two wells, each placed in its well or across the barrier),
    /// and which of them each initial state of a grid ends on.
    Basins(basins::BasinArgs),
    /// Charge the storage of a device with an interface circuit: the time for its voltage to
    /// go from a start value to a target under a sine, with V_s(t).
    Charge(interface::ChargeArgs),
    /// Fit free device parameters to measured sweeps (CSV with units in the header): the
    /// fitted device file with provenance, values with standard errors and 95 % intervals,
    /// their correlation, warnings for what the data do not determine, and plots of the data
    /// against the fitted model with residuals.
    Fit(common::fit_io::FitArgs),
}

/// The arguments of the two frequency studies (`sweep` and `response`): a sine drive (a
/// measured record drives `random` only, whose spectra it is analysed by).
#[derive(Parser, Debug)]
pub(crate) struct RangeArgs {
    /// Device file (TOML), e.g. a copy of data/prototype2.toml.
    #[arg(long)]
    device: PathBuf,
    /// Lowest frequency (Hz).
    #[arg(long)]
    from: f64,
    /// Highest frequency (Hz).
    #[arg(long)]
    to: f64,
    /// Frequency step of the sweeps (Hz), and largest step of the continuation; default: a
    /// quarter of the device's linear half-power width rounded down to 1, 2 or 5 times a power
    /// of ten (the continuation's largest step is then a hundredth of the range).
    #[arg(long)]
    step: Option<f64>,
    /// Take each step of the sweeps at once (the drive's frequency jumps), as the paper's
    /// figures do, instead of by a phase-continuous ramp.
    #[arg(long)]
    steps_at_once: bool,
    /// The rate of the ramps between steps (Hz/s); default: pi w^2 / 50 for the linear
    /// half-power width w (the frequency moves a fiftieth of w per ring-up time 1/(pi w)).
    #[arg(long)]
    ramp_rate: Option<f64>,
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

/// How the sweeps of a range are run: the step and how each step is reached.
pub(crate) struct Protocol {
    /// The step (Hz).
    pub step_hz: f64,
    /// The continuation's largest step (Hz).
    pub max_step_hz: f64,
    /// The step was chosen from the half-power band.
    pub default_step: bool,
    /// The device's linear half-power band.
    pub band: Option<HalfPowerBand>,
    /// How each step is reached.
    pub approach: Approach,
}

impl Protocol {
    /// One sentence on the protocol, for the numbers.
    pub fn words(&self) -> String {
        let band = self.band.map_or(String::new(), |b| {
            format!(
                " (linear resonance {} Hz, half-power width {} Hz)",
                fmt_sig(b.peak_hz, 5),
                fmt_sig(b.width_hz, 3)
            )
        });
        let step = if self.default_step {
            format!(
                "steps of {} Hz, a quarter of the half-power width rounded down{band}",
                fmt_sig(self.step_hz, 3)
            )
        } else {
            format!("steps of {} Hz{band}", fmt_sig(self.step_hz, 3))
        };
        let how = match self.approach {
            Approach::Jump => "each taken at once (the drive's frequency jumps)".to_string(),
            Approach::Ramp { rate_per_s } => format!(
                "each reached by a phase-continuous ramp at {} Hz/s",
                fmt_sig(rate_per_s, 3)
            ),
        };
        format!("{step}, {how}")
    }
}

impl RangeArgs {
    /// Refuses a range, step or acceleration that no sweep can use
    /// ([`sweep::check_range`]), naming the option (without `--step`, a tenth of the range
    /// stands for the default step, which is never larger).
    fn check(&self) -> Result<()> {
        let step = self.step.unwrap_or(0.1 * (self.to - self.from).abs());
        sweep::check_range(self.accel_rms_g, self.from, self.to, step).map_err(|e| {
            anyhow::anyhow!(match e {
                sweep::RangeError::Ends => {
                    "--from and --to must be positive frequencies with --to > --from"
                }
                sweep::RangeError::Step => "--step must be positive, not larger than the range, and give at most 100000 steps",
                sweep::RangeError::Accel => "--accel-rms-g must be a finite positive number",
            })
        })?;
        if let Some(r) = self.ramp_rate {
            if !(r.is_finite() && r > 0.0) {
                bail!("--ramp-rate must be a finite positive rate in Hz/s, not {r}");
            }
        }
        Ok(())
    }

    /// The step and approach of the sweeps of `device`.
    fn protocol(&self, device: &Device) -> Protocol {
        let band = half_power_band(device);
        let step_hz = self
            .step
            .unwrap_or_else(|| default_step_hz(device, self.from, self.to));
        let rate = self
            .ramp_rate
            .or_else(|| default_ramp_rate_hz_per_s(device))
            .unwrap_or(step_hz);
        Protocol {
            step_hz,
            max_step_hz: self.step.unwrap_or(0.01 * (self.to - self.from)),
            default_step: self.step.is_none(),
            band,
            approach: if self.steps_at_once {
                Approach::Jump
            } else {
                Approach::Ramp { rate_per_s: rate }
            },
        }
    }

    /// The sweep settings of the range ([`SweepSettings::for_device`]).
    fn sweep_settings(&self, device: &Device, p: &Protocol) -> SweepSettings {
        SweepSettings::for_device(
            device,
            linspace_step(self.from, self.to, p.step_hz),
            REFINE_TOL_HZ,
        )
    }
}

/// A sentence on the step's effect on where a sweep leaves a branch: the end at the sweep's
/// step and at a quarter of it, and a warning when they differ by more than the refinement
/// tolerance.
pub(crate) fn step_effect(what: &str, at_step: f64, at_quarter: Option<f64>) -> String {
    match at_quarter {
        Some(q) if (q - at_step).abs() > REFINE_TOL_HZ => format!(
            "- **warning**: {what} moves from {} Hz to {} Hz with a quarter of the step, more \
             than the refinement tolerance of {REFINE_TOL_HZ} Hz: the step decides it; use a \
             smaller step or a slower ramp\n",
            fmt_sig(at_step, 6),
            fmt_sig(q, 6)
        ),
        Some(q) => format!(
            "- with a quarter of the step {what} is at {} Hz ({:.3} Hz from the step's, within \
             the refinement tolerance of {REFINE_TOL_HZ} Hz)\n",
            fmt_sig(q, 6),
            (q - at_step).abs()
        ),
        None => format!("- with a quarter of the step {what} is not found\n"),
    }
}

fn main() {
    common::run_main("endstop", || match Cli::parse().study {
        Study::Sweep(a) => sweep(a),
        Study::Charge(a) => interface::charge(a),
        Study::Random(a) => random::random(a),
        Study::Response(a) => response::response(a),
        Study::Basins(a) => basins::basins_study(a),
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
    if !device.interface.is_resistive()
        && !matches!(
            name,
            "endstop-sweep" | "endstop-charge" | "endstop-response"
        )
    {
        bail!(
            "device `{}` has an interface circuit (`{}`): `endstop sweep`, `endstop response` \
             and `endstop charge` take it; this study models resistive loads only",
            device.name,
            device.interface.key()
        );
    }
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
    if !load_device_file(&a.device)?.device.interface.is_resistive() {
        return interface::dc_sweep(a);
    }
    a.check()?;
    let (mut exp, loaded, device) = start("endstop-sweep", &a.device, a.bias_v, a.out.clone())?;
    let protocol = a.protocol(&device);
    let settings = a.sweep_settings(&device, &protocol);
    let report = common::with_progress(settings.freqs_hz.len(), "sweep", |tick| {
        settings.run_with(&device, a.accel_rms_g, protocol.approach, |_| tick())
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
        "Up-sweep of `{}` ({} set; {}) from {} to {} Hz at {} g rms: {}.\n\n",
        loaded.file,
        device.params,
        describe(&device),
        a.from,
        a.to,
        a.accel_rms_g,
        protocol.words(),
    );
    exp.number("step_hz", protocol.step_hz);
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
        let quarter = settings
            .up_end_with_step_divided(&device, a.accel_rms_g, protocol.approach, &report, 4.0)?
            .map(|e| e.transition.value());
        if let Some(q) = quarter {
            exp.number("branch_end_quarter_step_hz", q);
        }
        md.push_str(&step_effect(
            "the end of the impacting branch",
            end.transition.value(),
            quarter,
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
    format!("{transducer}, {stops}{}", suspension(device))
}

/// A nonlinear suspension's form and static equilibria, for [`describe`] (empty for a linear
/// one).
fn suspension(device: &Device) -> String {
    use endstop::physics::suspension::Place;
    if device.mechanics.suspension.is_linear() {
        return String::new();
    }
    let eq: Vec<String> = device
        .equilibria()
        .iter()
        .map(|e| {
            format!(
                "{} um {}{}",
                fmt_sig(e.x_m * 1e6, 4),
                if e.stable { "stable" } else { "unstable" },
                match e.place {
                    Place::Free => "",
                    Place::UpperStop => " on the upper stop",
                    Place::LowerStop => " on the lower stop",
                }
            )
        })
        .collect();
    format!(
        ", `{}` suspension (static equilibria: {}; small oscillations at the reference well: \
         {} Hz)",
        device.mechanics.suspension.key(),
        eq.join(", "),
        fmt_sig(
            device.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI),
            4
        )
    )
}

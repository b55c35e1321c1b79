//! What the `endstop` subcommands share: the frequency range's arguments and the sweeps'
//! protocol, the step's effect in words, starting an experiment on a device file, and the
//! one-line description of a device.

use std::path::{Path, PathBuf};

use anyhow::{bail, Result};
use clap::Parser;
use endstop::device::Device;
use endstop::physics::harvester::masses::natural_frequencies_hz;
use endstop::study::chirp::{
    default_ramp_rate_hz_per_s, default_step_hz, half_power_band, HalfPowerBand,
};
use endstop::study::stepped::{linspace_step, Approach};
use endstop::study::sweep::{self, SweepSettings, REFINE_TOL_HZ};

use endstop_experiments::{fmt_sig, load_device_file, Experiment, LoadedDevice};

/// The arguments of the two frequency studies (`sweep` and `response`): a sine drive (a
/// measured record drives `random` only, whose spectra it is analysed by).
#[derive(Parser, Debug)]
pub(crate) struct RangeArgs {
    /// Device file (TOML), e.g. a copy of data/prototype2.toml.
    #[arg(long)]
    pub(crate) device: PathBuf,
    /// Lowest frequency (Hz).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) from: f64,
    /// Highest frequency (Hz).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) to: f64,
    /// Frequency step of the sweeps (Hz), and largest step of the continuation; default: a
    /// quarter of the device's linear half-power width rounded down to 1, 2 or 5 times a power
    /// of ten (the continuation's largest step is then a hundredth of the range).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) step: Option<f64>,
    /// Take each step of the sweeps at once (the drive's frequency jumps), as the paper's
    /// figures do, instead of by a phase-continuous ramp.
    #[arg(long)]
    pub(crate) steps_at_once: bool,
    /// The rate of the ramps between steps (Hz/s); default: pi w^2 / 50 for the linear
    /// half-power width w (the frequency moves a fiftieth of w per ring-up time 1/(pi w)).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) ramp_rate: Option<f64>,
    /// RMS base acceleration (g = 9.81 m/s^2); the sine's amplitude is sqrt(2) times this.
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) accel_rms_g: f64,
    /// Bias voltage (V) of an electrostatic transducer; default: the device file's. Refused
    /// for a device without a bias (piezoelectric, electromagnetic, none).
    #[arg(long, allow_hyphen_values = true)]
    pub(crate) bias_v: Option<f64>,
    /// Output directory; default: data/results/endstop-STUDY, STUDY the subcommand.
    #[arg(long)]
    pub(crate) out: Option<PathBuf>,
}

/// How the sweeps of a range are run: the step and how each step is reached.
pub(crate) struct Protocol {
    /// The step (Hz).
    pub step_hz: f64,
    /// The continuation's largest step (Hz).
    pub max_step_hz: f64,
    /// The step was chosen from the half-power band.
    pub default_step: bool,
    /// The device's linear half-power band (of a device of several masses: of their total
    /// mass with the slowest mass's ring-up, which sets the default step and ramp).
    pub band: Option<HalfPowerBand>,
    /// The undamped natural frequencies of a device of several masses (Hz); empty for one.
    pub modes_hz: Vec<f64>,
    /// How each step is reached.
    pub approach: Approach,
}

impl Protocol {
    /// One sentence on the protocol, for the numbers.
    pub fn words(&self) -> String {
        let band = self.band.map_or(String::new(), |b| {
            if self.modes_hz.is_empty() {
                format!(
                    " (linear resonance {} Hz, half-power width {} Hz)",
                    fmt_sig(b.peak_hz, 5),
                    fmt_sig(b.width_hz, 3)
                )
            } else {
                let modes: Vec<String> = self.modes_hz.iter().map(|&f| fmt_sig(f, 5)).collect();
                format!(
                    " (undamped natural frequencies {} Hz; the step and the ramp set by the \
                     slowest mass's ring-up, a half-power width of {} Hz)",
                    modes.join(", "),
                    fmt_sig(b.width_hz, 3)
                )
            }
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
    pub(crate) fn check(&self) -> Result<()> {
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
    pub(crate) fn protocol(&self, device: &Device) -> Protocol {
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
            modes_hz: natural_frequencies_hz(device),
            approach: if self.steps_at_once {
                Approach::Jump
            } else {
                Approach::Ramp { rate_per_s: rate }
            },
        }
    }

    /// The sweep settings of the range ([`SweepSettings::for_device`]).
    pub(crate) fn sweep_settings(&self, device: &Device, p: &Protocol) -> SweepSettings {
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
            "- with a quarter of the step, {what} is at {} Hz ({:.3} Hz from the step's, within \
             the refinement tolerance of {REFINE_TOL_HZ} Hz)\n",
            fmt_sig(q, 6),
            (q - at_step).abs()
        ),
        None => format!("- with a quarter of the step, {what} is not found\n"),
    }
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

/// Times the largest stop gap that a displacement may reach before a run is called beyond
/// its model: a stop pressed in by more than ten gaps has left every contact law's range
/// (a Hertz contact's indentation is a small fraction of its bump radius, a rubber pad's of
/// its thickness), and such a displacement almost always comes from a drive in the wrong
/// unit.
pub(crate) const IMPLAUSIBLE_GAPS: f64 = 10.0;

/// A warning line when the largest displacement `x_peak_m` of a run of `device` exceeds
/// [`IMPLAUSIBLE_GAPS`] times its largest stop gap (None for a device without stops or a
/// plausible run); it is printed on stderr and belongs in the run's numbers.
pub(crate) fn implausible_drive(
    device: &Device,
    accel_rms_g: f64,
    x_peak_m: f64,
) -> Option<String> {
    let gap = device
        .stops
        .present()
        .map(|(_, s)| s.gap_m)
        .fold(0.0, f64::max);
    (gap > 0.0 && x_peak_m > IMPLAUSIBLE_GAPS * gap).then(|| {
        let line = format!(
            "- **warning**: the displacement reaches {} m, {} times the largest stop gap \
             ({} m): at {accel_rms_g} g rms the drive presses the mass through its stops, \
             beyond any contact law's range; check the drive (`--accel-rms-g` is in g)\n",
            fmt_sig(x_peak_m, 3),
            fmt_sig(x_peak_m / gap, 3),
            fmt_sig(gap, 3)
        );
        eprint!(
            "[endstop] {}",
            line.trim_start_matches("- ").replace("**", "")
        );
        line
    })
}

/// One line on what a device is: its transducer (with its bias voltage, and a note where it
/// has one load) and each side's stop; on a device of several masses, the transducer's mass,
/// every mass, spring, damper and stop (to the frame or between two masses) instead of the
/// stops.
pub(crate) fn describe(device: &Device) -> String {
    if let Some(m) = &device.masses {
        return describe_masses(device, m);
    }
    let transducer = transducer_words(device);
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

/// The transducer's words of [`describe`].
fn transducer_words(device: &Device) -> String {
    let t = &device.transducer;
    match (t.bias_v(), t.loads()) {
        (Some(vb), _) => format!("`{}` transducer at Vb = {vb} V", t.key()),
        (None, 1) => format!("`{}` transducer, one load (v2 is zero)", t.key()),
        (None, _) => format!("`{}` transducer", t.key()),
    }
}

/// [`describe`] of a device of several masses.
fn describe_masses(device: &Device, m: &endstop::device::Masses) -> String {
    use endstop::device::Side;
    let name = |i: usize| format!("`{}`", m.bodies[i].name);
    let ends = |mass: usize, other: Option<usize>| match other {
        Some(o) => format!("{}-{}", name(mass), name(o)),
        None => format!("{}-frame", name(mass)),
    };
    let list = |items: Vec<String>| {
        if items.is_empty() {
            "none".to_string()
        } else {
            items.join(", ")
        }
    };
    let links = |links: &[endstop::device::Link], unit: &str| {
        list(
            links
                .iter()
                .map(|l| format!("{} {} {unit}", ends(l.mass, l.other), fmt_sig(l.value, 4)))
                .collect(),
        )
    };
    let masses = list(
        m.bodies
            .iter()
            .map(|b| format!("`{}` {} g", b.name, fmt_sig(b.mass_kg * 1e3, 4)))
            .collect(),
    );
    let stops = list(
        m.stops
            .iter()
            .map(|s| {
                let side = match s.side {
                    Side::Upper => "upper",
                    Side::Lower => "lower",
                };
                format!(
                    "{} {side} `{}` at {} um",
                    ends(s.mass, s.other),
                    s.stop.law.key(),
                    fmt_sig(s.stop.gap_m * 1e6, 4)
                )
            })
            .collect(),
    );
    let transducer = transducer_words(device);
    let drive = m.drive_mass.map_or(String::new(), |j| {
        format!("; a force drive on {} alone", name(j))
    });
    format!(
        "{transducer} on {}; masses {masses}; springs {}; dampers {}; stops {stops}{drive}",
        name(m.transducer_mass),
        links(&m.springs, "N/m"),
        links(&m.dampers, "N s/m"),
    )
}

/// A nonlinear suspension's form and static equilibria, for [`describe`] (empty for a linear
/// one).
fn suspension(device: &Device) -> String {
    use endstop::physics::suspension::Place;
    if device.mechanics.suspension.is_linear() {
        return String::new();
    }
    let eq: Vec<String> = endstop::physics::statics::equilibria(device)
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

/// For a device of several masses, each mass's largest displacement and speed over `what`
/// (`peaks`, under the per-mass column names `names` of
/// [`endstop_experiments::reports::sweep_io::mass_columns`]): recorded as numbers under those
/// names, and returned as a line of the numbers (empty for one mass).
pub(crate) fn mass_peaks_md(
    exp: &mut Experiment,
    names: &[&'static str],
    peaks: &endstop::study::mass_peaks::MassPeaks,
    what: &str,
) -> String {
    let values = peaks.values();
    if names.is_empty() || values.len() != names.len() {
        return String::new();
    }
    for (n, v) in names.iter().zip(&values) {
        exp.number(n, *v);
    }
    let each: Vec<String> = names
        .chunks(2)
        .zip(values.chunks(2))
        .map(|(n, v)| {
            let mass = n[0]
                .strip_prefix("x_")
                .and_then(|s| s.strip_suffix("_peak_m"))
                .unwrap_or(n[0]);
            format!(
                "`{mass}` {} mm and {} m/s",
                fmt_sig(v[0] * 1e3, 4),
                fmt_sig(v[1], 4)
            )
        })
        .collect();
    format!(
        "- largest displacement and speed of each mass {what}: {}\n",
        each.join("; ")
    )
}

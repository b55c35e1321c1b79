//! The curves of an up-sweep figure (Figures 8 and 13): a drive level and an end-stop model
//! each, run in parallel on one device together with their repetition with refined numerics
//! ([`CurveSweeps`]), what the figures' tables report of each, and the convergence check
//! shared by both figures.
//!
//! A figure names its curves by an enum ([`FigureCurve`]) and keeps them in the enum's order,
//! so that a claim finds its curve by name and never by comparing drive levels or dampings (a
//! changed literal cannot make a claim vanish).

use std::marker::PhantomData;

use crate::device::{Device, StiffnessModel};
use crate::ode::SolverError;
use crate::paper::claims::{bool_value, Answer, ClaimKey, ClaimValue};
use crate::paper::setups::{endstop, with_endstop};
use crate::progress::Progress;
use crate::study::steady::SettleSettings;
use crate::study::sweep::{compare_sweeps, BranchEnd, SweepComparison, SweepReport, SweepSettings};

/// Convergence limit on the onsets and branch ends of an up-sweep: relative change when the
/// numerics are refined ([`SweepSettings::halved`]). A numerical requirement on our results,
/// not a tolerance of a claim (those come from the claims file).
pub const CONV_FREQ_REL: f64 = 0.005;

/// Convergence limit on the RMS voltages of an up-sweep (relative change), as
/// [`CONV_FREQ_REL`].
pub const CONV_RMS_REL: f64 = 0.01;

/// The key of a stiffness law in file names, summary keys and table columns.
pub fn law_key(s: StiffnessModel) -> &'static str {
    match s {
        StiffnessModel::Hertz => "hertz",
        StiffnessModel::Linear => "linear",
    }
}

/// One curve of an up-sweep figure: drive level and end-stop model.
#[derive(Debug, Clone, Copy)]
pub struct CurveSpec {
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Spring law of the stop.
    pub stiffness: StiffnessModel,
    /// End-stop damping b_im (N s/m).
    pub bim_n_s_per_m: f64,
    /// Tension-free contact (a reading of eq 1, see the book's "Readings of ambiguities")
    /// instead of eq 1 as written.
    pub tension_free: bool,
}

impl CurveSpec {
    /// A curve with eq 1 as written (the damper may pull).
    pub const fn new(accel_rms_g: f64, stiffness: StiffnessModel, bim_n_s_per_m: f64) -> Self {
        Self {
            accel_rms_g,
            stiffness,
            bim_n_s_per_m,
            tension_free: false,
        }
    }

    /// The same curve with a tension-free contact.
    pub const fn tension_free(mut self) -> Self {
        self.tension_free = true;
        self
    }

    /// Label, e.g. `5.5 g, Hertz, b_im=1.5`.
    pub fn label(&self) -> String {
        let law = match self.stiffness {
            StiffnessModel::Hertz => "Hertz",
            StiffnessModel::Linear => "linear",
        };
        format!(
            "{} g, {law}, b_im={}{}",
            self.accel_rms_g,
            self.bim_n_s_per_m,
            if self.tension_free {
                ", tension-free"
            } else {
                ""
            }
        )
    }

    /// Key of the curve in summary numbers, e.g. `5p5g_hertz_bim1p5_tf`.
    pub fn key(&self) -> String {
        format!(
            "{}g_{}_bim{}{}",
            self.accel_rms_g,
            law_key(self.stiffness),
            self.bim_n_s_per_m,
            if self.tension_free { "_tf" } else { "" }
        )
        .replace('.', "p")
    }

    /// The device with this curve's end-stop model.
    pub fn device(&self, base: &Device) -> Device {
        with_endstop(base, self.stiffness, self.bim_n_s_per_m).with_tension_free(self.tension_free)
    }
}

/// A curve and its sweep.
#[derive(Debug, Clone)]
pub struct Curve {
    /// What was swept.
    pub spec: CurveSpec,
    /// The report.
    pub report: SweepReport,
}

/// Runs the up-sweeps of `specs` on `device` in parallel (rayon), in the order of `specs`;
/// `on_step.tick()` is called after every coarse step of every sweep (from any thread).
pub fn run_curves(
    device: &Device,
    specs: &[CurveSpec],
    settings: &SweepSettings,
    on_step: &dyn Progress,
) -> Result<Vec<Curve>, SolverError> {
    use rayon::prelude::*;
    specs
        .par_iter()
        .map(|spec| {
            let report = settings.run(&spec.device(device), spec.accel_rms_g, on_step)?;
            Ok(Curve {
                spec: *spec,
                report,
            })
        })
        .collect()
}

/// The curves of one up-sweep figure, named by an enum.
pub trait FigureCurve: Copy + PartialEq + 'static {
    /// Every curve, in the order the figure runs and reports them.
    const ALL: &'static [Self];

    /// Drive level and end-stop model of the curve.
    fn spec(self) -> CurveSpec;
}

/// A figure's sweeps, one per curve of `K` in the order of [`FigureCurve::ALL`], and the same
/// sweeps with refined numerics.
#[derive(Debug, Clone)]
pub struct CurveSweeps<K> {
    /// The sweeps.
    pub curves: Vec<Curve>,
    /// The same sweeps with refined numerics ([`SweepSettings::halved`]).
    pub halved: Vec<Curve>,
    names: PhantomData<K>,
}

impl<K: FigureCurve> CurveSweeps<K> {
    /// Runs every curve of `K` on `device` with `settings` and again with `halved`, in
    /// parallel ([`run_curves`]); `on_step.tick()` is called after every coarse step of every sweep.
    pub fn run(
        device: &Device,
        settings: &SweepSettings,
        halved: &SweepSettings,
        on_step: &dyn Progress,
    ) -> Result<Self, SolverError> {
        let specs: Vec<CurveSpec> = K::ALL.iter().map(|c| c.spec()).collect();
        let (curves, halved) = rayon::join(
            || run_curves(device, &specs, settings, on_step),
            || run_curves(device, &specs, halved, on_step),
        );
        Ok(Self {
            curves: curves?,
            halved: halved?,
            names: PhantomData,
        })
    }

    /// Coarse steps of [`CurveSweeps::run`] with these settings, for a progress bar.
    pub fn coarse_steps(settings: &SweepSettings, halved: &SweepSettings) -> usize {
        K::ALL.len() * (settings.freqs_hz.len() + halved.freqs_hz.len())
    }

    /// One curve's sweep.
    pub fn curve(&self, which: K) -> &Curve {
        let i = K::ALL
            .iter()
            .position(|&c| c == which)
            .expect("every curve is in ALL");
        &self.curves[i]
    }

    /// Every sweep against its refined repetition, in the order of [`FigureCurve::ALL`].
    pub fn convergence(&self) -> Vec<CurveConvergence> {
        self.curves
            .iter()
            .zip(&self.halved)
            .map(|(c, f)| CurveConvergence::of(c, f))
            .collect()
    }
}

/// What the tables of Figures 8 and 13 report of one sweep.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveSummary {
    /// Refined impact onset (Hz).
    pub onset_hz: Option<f64>,
    /// Where and how the impacting branch ends.
    pub branch_end: Option<BranchEnd>,
    /// Refined jump (Hz).
    pub jump_hz: Option<f64>,
    /// Refined loss of contact (Hz).
    pub contact_lost_hz: Option<f64>,
    /// Total power just after over just before the refined jump.
    pub jump_power_ratio: Option<f64>,
    /// True if any coarse step is in contact.
    pub any_contact: bool,
    /// Largest RMS voltage of load 1 over the requested range (V).
    pub max_v1_rms_v: f64,
    /// Largest RMS differential voltage over the requested range (V).
    pub max_vdiff_rms_v: f64,
    /// Largest penetration of a stop over every coarse step (m, 0 without contact).
    pub max_penetration_m: f64,
    /// Coarse steps, the extension included.
    pub steps: usize,
    /// Coarse steps beyond the requested range.
    pub steps_beyond: usize,
    /// Coarse steps that met the steady-state criterion.
    pub steps_converged: usize,
    /// Mean measured blocks per coarse step.
    pub mean_blocks: f64,
    /// Simulated periods of the coarse steps: (settle + measured blocks) x block length.
    pub simulated_periods: usize,
    /// Integrator steps (accepted + rejected) of the sweep and all its refinements.
    pub integrator_steps: u64,
    /// Contact events of the sweep and all its refinements.
    pub contact_events: u64,
}

impl Curve {
    /// The table numbers of this sweep; `base` is the device the figure swept (for its gap)
    /// and `cfg` the steady-state criterion it used (for the block length).
    pub fn summary(&self, base: &Device, cfg: &SettleSettings) -> CurveSummary {
        let r = &self.report;
        let gap = endstop(&self.spec.device(base)).gap_m;
        let steps = r.sweep.steps.len();
        let blocks: usize = r.measurements().map(|m| m.blocks).sum();
        let stats = r.total_stats();
        CurveSummary {
            onset_hz: r.onset.map(|t| t.value()),
            branch_end: r.branch_end(),
            jump_hz: r.jump.map(|t| t.value()),
            contact_lost_hz: r.contact_lost.map(|t| t.value()),
            jump_power_ratio: r.jump_power_ratio,
            any_contact: r.any_contact(),
            max_v1_rms_v: r.max_v1_rms_v(),
            max_vdiff_rms_v: r
                .measurements_in_range()
                .map(|m| m.vdiff_rms_v)
                .fold(0.0, f64::max),
            max_penetration_m: r
                .measurements()
                .map(|m| m.x_peak_m - gap)
                .fold(0.0, f64::max),
            steps,
            steps_beyond: r.extended_from.map_or(0, |k| steps - k),
            steps_converged: r.measurements().filter(|m| m.converged).count(),
            mean_blocks: blocks as f64 / steps as f64,
            simulated_periods: r
                .measurements()
                .map(|m| (m.blocks + cfg.settle_blocks) * cfg.block_periods)
                .sum(),
            integrator_steps: stats.steps(),
            contact_events: stats.events,
        }
    }
}

/// A sweep against its repetition with refined numerics ([`SweepSettings::halved`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveConvergence {
    /// The differences.
    pub comparison: SweepComparison,
    /// Onset of the refined run (Hz).
    pub fine_onset_hz: Option<f64>,
    /// Branch end of the refined run (Hz).
    pub fine_branch_end_hz: Option<f64>,
    /// Onset and branch end within [`CONV_FREQ_REL`], the same kind of end, and RMS
    /// voltages within [`CONV_RMS_REL`].
    pub within_limits: bool,
}

impl CurveConvergence {
    /// Compares a sweep with its refined repetition.
    pub fn of(coarse: &Curve, fine: &Curve) -> Self {
        let c = compare_sweeps(&coarse.report, &fine.report);
        Self {
            comparison: c,
            fine_onset_hz: fine.report.onset.map(|t| t.value()),
            fine_branch_end_hz: fine.report.branch_end().map(|e| e.transition.value()),
            within_limits: c.onset_rel.unwrap_or(0.0) < CONV_FREQ_REL
                && c.end_rel.unwrap_or(0.0) < CONV_FREQ_REL
                && c.same_end_kind
                && c.max_v1_rel.max(c.max_v2_rel) < CONV_RMS_REL,
        }
    }
}

/// The value of a "no impact" claim: 1 if no coarse step of the sweep has contact.
pub(crate) fn no_impact_value(key: ClaimKey, c: &Curve) -> ClaimValue {
    let touched = c.report.any_contact();
    bool_value(
        key,
        !touched,
        if touched {
            "the mass reaches the stops".into()
        } else {
            "no step of the sweep has contact".into()
        },
    )
}

/// The value of a jump claim: the end of the impacting branch, labelled jump or loss of
/// contact (a gradual exit is never presented as a jump), `None` if the branch never ends.
pub(crate) fn branch_end_value(key: ClaimKey, curve: &Curve, stop_hz: f64) -> Option<ClaimValue> {
    let end = curve.report.branch_end()?;
    let v = end.transition.value();
    let mut note = end.kind.label().to_string();
    if v > stop_hz {
        note.push_str(&format!(
            ", beyond the paper's {stop_hz} Hz (extended sweep)"
        ));
    }
    Some(ClaimValue {
        key,
        value: Answer::Number(v),
        uncertainty: Some(end.transition.half_width()),
        note,
    })
}

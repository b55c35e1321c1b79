//! The curves of an up-sweep figure (Figures 8 and 13): a drive level and an end-stop model
//! each, run in parallel on one device.

use crate::device::{Device, StiffnessModel};
use crate::ode::SolverError;
use crate::paper::claims::ClaimValue;
use crate::study::sweep::{SweepReport, SweepSettings};

/// One curve of an up-sweep figure: drive level and end-stop model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CurveSpec {
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Spring law of the stop.
    pub stiffness: StiffnessModel,
    /// End-stop damping b_im (N s/m).
    pub bim_n_s_per_m: f64,
    /// Tension-free contact (a reading of eq 1, see the book's "Readings of ambiguities") instead of eq 1 as written.
    pub tension_free: bool,
}

impl CurveSpec {
    /// A curve with eq 1 as written (the damper may pull).
    pub fn new(accel_rms_g: f64, stiffness: StiffnessModel, bim_n_s_per_m: f64) -> Self {
        Self {
            accel_rms_g,
            stiffness,
            bim_n_s_per_m,
            tension_free: false,
        }
    }

    /// The same curve with a tension-free contact.
    pub fn tension_free(mut self) -> Self {
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

    /// The device with this curve's end-stop model.
    pub fn device(&self, base: &Device) -> Device {
        let mut d = base.with_endstop(self.stiffness, self.bim_n_s_per_m);
        d.endstop.tension_free = self.tension_free;
        d
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

/// Runs the up-sweeps of `specs` on `device` in parallel (rayon); `on_step()` is called after
/// every coarse step of every sweep (from any thread).
pub fn run_curves(
    device: &Device,
    specs: &[CurveSpec],
    settings: &SweepSettings,
    on_step: &(dyn Fn() + Sync),
) -> Result<Vec<Curve>, SolverError> {
    use rayon::prelude::*;
    specs
        .par_iter()
        .map(|spec| {
            let report = settings.run(&spec.device(device), spec.accel_rms_g, |_| on_step())?;
            Ok(Curve {
                spec: *spec,
                report,
            })
        })
        .collect()
}

/// Finds a curve by its spec.
pub fn find_curve<'a>(curves: &'a [Curve], spec: &CurveSpec) -> Option<&'a Curve> {
    curves.iter().find(|c| c.spec == *spec)
}

/// The value of a jump claim: the end of the impacting branch, labelled jump or loss of
/// contact (a gradual exit is never presented as a jump), `None` if the branch never ends.
pub(crate) fn branch_end_value(
    id: &'static str,
    quantity: &'static str,
    curve: &Curve,
    stop_hz: f64,
) -> Option<ClaimValue> {
    let end = curve.report.branch_end()?;
    let v = end.transition.value();
    let mut note = end.kind.label().to_string();
    if v > stop_hz {
        note.push_str(&format!(
            ", beyond the paper's {stop_hz} Hz (extended sweep)"
        ));
    }
    Some(ClaimValue {
        id,
        quantity,
        value: v,
        uncertainty: Some(end.transition.half_width()),
        note,
    })
}

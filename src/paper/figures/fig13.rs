//! Figure 13: prototype 2 at 10 V, up-sweeps from 600 to 850 Hz at 0.12 and 0.31 g rms
//! (claim F13), published parameters, with the convergence repetition of every sweep.

use crate::device::{Device, StiffnessModel};
use crate::ode::SolverError;
use crate::paper::claims::{bool_value, keys, Claims, ClaimsError, Value};
use crate::paper::curves::{no_impact_value, CurveSpec, CurveSweeps, FigureCurve};
use crate::paper::setups::{ParamSet, FIG13_BIAS_V};
use crate::paper::Figure;
use crate::progress::Progress;
use crate::study::steady::settle_settings_across_folds;
use crate::study::stepped;
use crate::study::sweep::{SweepSettings, REFINE_TOL_HZ};

/// Prototype 2, Figure 13: 600-850 Hz in 2 Hz steps (extended to 1200 Hz if needed),
/// [`settle_settings_across_folds`] at 700 Hz (the ring-up time, 68 periods, is already longer
/// than the fold rule's minimum), brackets of [`REFINE_TOL_HZ`].
pub fn sweep_settings(device: &Device) -> SweepSettings {
    SweepSettings {
        freqs_hz: stepped::linspace_step(600.0, 850.0, 2.0),
        extend_to_hz: 1200.0,
        cfg: settle_settings_across_folds(device, 700.0),
        refine_tol_hz: REFINE_TOL_HZ,
    }
}

/// The curves of Figure 13 (prototype 2, 10 V), in the order of [`Fig13Curve::ALL`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fig13Curve {
    /// 0.12 g, linear law of eq 19, b_im = 0.4 N s/m: no impacts.
    Low,
    /// 0.31 g, linear law, b_im = 0.4 N s/m: the paper's fit, impacts and a jump.
    Linear,
    /// 0.31 g, Hertz law, b_im = 0.34 N s/m: the paper's alternative fit.
    Hertz,
}

impl Fig13Curve {
    /// Every curve, in the order the figure runs and reports them.
    pub const ALL: [Fig13Curve; 3] = [Fig13Curve::Low, Fig13Curve::Linear, Fig13Curve::Hertz];

    /// Drive level and end-stop model of the curve.
    pub const fn spec(self) -> CurveSpec {
        match self {
            Fig13Curve::Low => CurveSpec::new(0.12, StiffnessModel::Linear, 0.4),
            Fig13Curve::Linear => CurveSpec::new(0.31, StiffnessModel::Linear, 0.4),
            Fig13Curve::Hertz => CurveSpec::new(0.31, StiffnessModel::Hertz, 0.34),
        }
    }
}

impl FigureCurve for Fig13Curve {
    const ALL: &'static [Self] = &Fig13Curve::ALL;

    fn spec(self) -> CurveSpec {
        Fig13Curve::spec(self)
    }
}

/// Everything Figure 13 computes.
#[derive(Debug, Clone)]
pub struct Run {
    /// Prototype 2 at 10 V (each curve applies its own end-stop model).
    pub device: Device,
    /// The figure's sweeps ([`sweep_settings`]).
    pub settings: SweepSettings,
    /// The repetition: half the step and the tolerances ([`SweepSettings::halved`]).
    pub halved_settings: SweepSettings,
    /// The sweeps of [`Fig13Curve::ALL`] and their repetition with `halved_settings`.
    pub sweeps: CurveSweeps<Fig13Curve>,
}

impl Run {
    /// The jump with the Hertz law relative to the jump with the linear law,
    /// (Hertz - linear) / linear; `None` unless both sweeps jump.
    pub fn jump_difference_rel(&self) -> Option<f64> {
        let jl = self.sweeps.curve(Fig13Curve::Linear).report.jump?.value();
        let jh = self.sweeps.curve(Fig13Curve::Hertz).report.jump?.value();
        Some((jh - jl) / jl)
    }
}

/// Figure 13: prototype 2's up-sweeps at 10 V.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig13;

impl Figure for Fig13 {
    const NAME: &'static str = "fig13";
    /// Prototype 2 as published.
    type Setup = Device;
    type Run = Run;
    type Error = SolverError;

    /// Coarse steps of a whole run (every curve, both repetitions).
    fn work(published: &Device) -> usize {
        let s = sweep_settings(&published.with_bias(FIG13_BIAS_V));
        CurveSweeps::<Fig13Curve>::coarse_steps(&s, &s.halved())
    }

    /// Runs Figure 13 on the published prototype 2 (as loaded; the bias is set here): every
    /// curve and its repetition with refined numerics, in parallel. `progress.tick()` is called
    /// after every coarse step of every sweep.
    fn run(published: &Device, progress: &dyn Progress) -> Result<Run, SolverError> {
        let device = published.with_bias(FIG13_BIAS_V);
        let settings = sweep_settings(&device);
        let halved_settings = settings.halved();
        let sweeps = CurveSweeps::run(&device, &settings, &halved_settings, progress)?;
        Ok(Run {
            device,
            settings,
            halved_settings,
            sweeps,
        })
    }

    /// Figure 13's claim values (published set).
    ///
    /// * no impact at 0.12 g: 1 if no step has contact;
    /// * jump at 0.31 g: 1 if the linear-law sweep has contact and a confirmed jump;
    /// * Hertz and linear agree: 1 if both 0.31 g sweeps jump and their jump frequencies
    ///   differ by no more than the claims file's `frequency` class allows about the linear
    ///   one.
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let class = claims.require_class("frequency")?;
        let mut out = vec![no_impact_value(
            keys::F13_NO_IMPACT,
            run.sweeps.curve(Fig13Curve::Low),
        )];
        let lin = &run.sweeps.curve(Fig13Curve::Linear).report;
        out.push(bool_value(
            keys::F13_JUMP,
            lin.any_contact() && lin.jump.is_some(),
            match lin.jump {
                Some(_) => "impacts and a confirmed jump".into(),
                None => "no confirmed jump".into(),
            },
        ));
        let her = &run.sweeps.curve(Fig13Curve::Hertz).report;
        let (agree, note) = match (lin.jump, her.jump) {
            (Some(jl), Some(jh)) => {
                let tol = class.tolerance(jl.value());
                (
                    (jh.value() - jl.value()).abs() <= tol,
                    format!("difference of the jumps vs {tol:.1} Hz (frequency class)"),
                )
            }
            _ => (false, "a sweep has no jump".to_string()),
        };
        out.push(bool_value(keys::F13_HERTZ_LINEAR_AGREE, agree, note));
        claims.known(
            out.into_iter()
                .map(|v| v.to_value(ParamSet::Published))
                .collect(),
        )
    }
}

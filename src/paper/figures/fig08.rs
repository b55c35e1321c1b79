//! Figure 8: prototype 1 at 30 V, stepped-sine up-sweeps from 900 to 1600 Hz at 4.1 and
//! 5.5 g rms with several end-stop models (claims F8-a to F8-f), under the published and the
//! calibrated parameter set; the paper's fit of b_im to the measured jump under both; and the
//! convergence repetition of every sweep with refined numerics.

use crate::device::{Device, StiffnessModel};
use crate::paper::calibration::{fit_bim_for_jump, BimFit, CalibrationError, BIM_FIT_TOL_HZ};
use crate::paper::claims::{
    bool_value, keys, Answer, ClaimKey, ClaimValue, Claims, ClaimsError, Value,
};
use crate::paper::curves::{
    branch_end_value, no_impact_value, CurveSpec, CurveSweeps, FigureCurve,
};
use crate::paper::measured::P1_MEASURED_JUMP_HZ;
use crate::paper::setups::{ParamSet, Prototype1Sets, P1_BIAS_V};
use crate::paper::Figure;
use crate::progress::Progress;
use crate::study::sweep::SweepSettings;

/// Figure 8's drive levels, frequency range and sweep settings, stated in
/// [`crate::paper::sweeps`] (the calibration fits the gap on the same sweep).
pub use crate::paper::sweeps::{
    sweep_settings, P1_HIGH_ACCEL_RMS_G, P1_LOW_ACCEL_RMS_G, P1_SWEEP_START_HZ, P1_SWEEP_STEP_HZ,
    P1_SWEEP_STOP_HZ,
};

/// The curves of Figure 8 (prototype 1, 30 V), in the order of [`Fig8Curve::ALL`].
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fig8Curve {
    /// 4.1 g, Hertz, b_im = 1.5 N s/m: no impacts (F8-a).
    Low,
    /// 5.5 g, Hertz, no end-stop damping (F8-d).
    Hertz0,
    /// 5.5 g, Hertz, b_im = 1.5 N s/m: the paper's fit (F8-b, F8-c).
    Hertz1p5,
    /// 5.5 g, Hertz, b_im = 10 N s/m (F8-e).
    Hertz10,
    /// 5.5 g, linear law of eq 19, b_im = 2 N s/m: the paper's other fit (F8-f).
    Linear2,
    /// 5.5 g, Hertz, b_im = 1.5 N s/m with a tension-free contact: a sensitivity.
    Hertz1p5TensionFree,
}

impl Fig8Curve {
    /// Every curve, in the order the figure runs and reports them.
    pub const ALL: [Fig8Curve; 6] = [
        Fig8Curve::Low,
        Fig8Curve::Hertz0,
        Fig8Curve::Hertz1p5,
        Fig8Curve::Hertz10,
        Fig8Curve::Linear2,
        Fig8Curve::Hertz1p5TensionFree,
    ];

    /// Drive level and end-stop model of the curve.
    pub const fn spec(self) -> CurveSpec {
        use StiffnessModel::{Hertz, Linear};
        let hi = P1_HIGH_ACCEL_RMS_G;
        match self {
            Fig8Curve::Low => CurveSpec::new(P1_LOW_ACCEL_RMS_G, Hertz, 1.5),
            Fig8Curve::Hertz0 => CurveSpec::new(hi, Hertz, 0.0),
            Fig8Curve::Hertz1p5 => CurveSpec::new(hi, Hertz, 1.5),
            Fig8Curve::Hertz10 => CurveSpec::new(hi, Hertz, 10.0),
            Fig8Curve::Linear2 => CurveSpec::new(hi, Linear, 2.0),
            Fig8Curve::Hertz1p5TensionFree => CurveSpec::new(hi, Hertz, 1.5).tension_free(),
        }
    }
}

impl FigureCurve for Fig8Curve {
    const ALL: &'static [Self] = &Fig8Curve::ALL;

    fn spec(self) -> CurveSpec {
        Fig8Curve::spec(self)
    }
}

/// The jump claims of Figure 8 and the curve each is read from.
pub const JUMP_CLAIMS: [(ClaimKey, Fig8Curve); 4] = [
    (keys::F8C_JUMP_HERTZ_BIM1P5, Fig8Curve::Hertz1p5),
    (keys::F8D_JUMP_HERTZ_BIM0, Fig8Curve::Hertz0),
    (keys::F8E_JUMP_HERTZ_BIM10, Fig8Curve::Hertz10),
    (keys::F8F_JUMP_LINEAR_BIM2, Fig8Curve::Linear2),
];

/// The paper's two fitted end-stop models, whose b_im is refitted to the measured jump
/// ([`fit_bim_for_jump`]): the fit starts from each curve's stiffness law.
pub const BIM_FITS: [Fig8Curve; 2] = [Fig8Curve::Hertz1p5, Fig8Curve::Linear2];

/// Figure 8's sweep settings and their convergence repetition.
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    /// The figure's sweeps ([`sweep_settings`]).
    pub settings: SweepSettings,
    /// The repetition: half the step and the tolerances ([`SweepSettings::halved`]).
    pub halved: SweepSettings,
}

impl Protocol {
    /// The protocol for prototype 1 (the settings depend on its mass and damping only, which
    /// the calibration leaves unchanged).
    pub fn new(published: &Device) -> Self {
        let settings = sweep_settings(published);
        let halved = settings.halved();
        Self { settings, halved }
    }

    /// Coarse steps of a whole run (both sets, every curve, both repetitions), for a
    /// progress bar.
    pub fn coarse_steps(&self) -> usize {
        ParamSet::BOTH.len() * CurveSweeps::<Fig8Curve>::coarse_steps(&self.settings, &self.halved)
    }
}

/// One parameter set's sweeps and b_im fits.
#[derive(Debug, Clone)]
pub struct SetRun {
    /// The set.
    pub set: ParamSet,
    /// Prototype 1 of this set at 30 V (each curve applies its own end-stop model).
    pub device: Device,
    /// The sweeps of [`Fig8Curve::ALL`] and their repetition with [`Protocol::halved`].
    pub sweeps: CurveSweeps<Fig8Curve>,
    /// The b_im fits, in the order of [`BIM_FITS`].
    pub fits: Vec<BimFit>,
}

/// Everything Figure 8 computes.
#[derive(Debug, Clone)]
pub struct Run {
    /// The settings used.
    pub protocol: Protocol,
    /// Published set, then calibrated set.
    pub sets: Vec<SetRun>,
}

impl Run {
    /// The largest relative changes over every sweep of both sets when the numerics are
    /// refined: (onset, branch end, RMS voltage of either load).
    pub fn largest_changes(&self) -> (f64, f64, f64) {
        let mut worst = (0.0f64, 0.0f64, 0.0f64);
        for v in self.sets.iter().flat_map(|r| r.sweeps.convergence()) {
            let c = v.comparison;
            worst.0 = worst.0.max(c.onset_rel.unwrap_or(0.0));
            worst.1 = worst.1.max(c.end_rel.unwrap_or(0.0));
            worst.2 = worst.2.max(c.max_v1_rel.max(c.max_v2_rel));
        }
        worst
    }

    /// The run of one parameter set.
    pub fn set(&self, set: ParamSet) -> &SetRun {
        self.sets
            .iter()
            .find(|r| r.set == set)
            .expect("a run holds both sets")
    }
}

/// Figure 8: prototype 1's up-sweeps under both parameter sets, and the b_im fits.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig08;

impl Figure for Fig08 {
    const NAME: &'static str = "fig08";
    type Setup = Prototype1Sets;
    type Run = Run;
    type Error = CalibrationError;

    fn work(setup: &Prototype1Sets) -> usize {
        Protocol::new(&setup.published).coarse_steps()
    }

    /// Runs Figure 8 for both parameter sets of prototype 1 (as loaded; the bias is set
    /// here): every curve, its repetition with refined numerics, and the b_im fits, in
    /// parallel. `progress.tick()` is called after every coarse step of every sweep.
    fn run(setup: &Prototype1Sets, progress: &dyn Progress) -> Result<Run, CalibrationError> {
        use rayon::prelude::*;
        let protocol = Protocol::new(&setup.published);
        let sets = setup
            .each()
            .into_iter()
            .map(|(set, d)| -> Result<SetRun, CalibrationError> {
                let device = d.with_bias(P1_BIAS_V);
                let p = &protocol;
                let (sweeps, fits) = rayon::join(
                    || CurveSweeps::run(&device, &p.settings, &p.halved, progress),
                    || {
                        BIM_FITS
                            .par_iter()
                            .map(|c| {
                                fit_bim_for_jump(
                                    &c.spec().device(&device),
                                    P1_MEASURED_JUMP_HZ,
                                    P1_HIGH_ACCEL_RMS_G,
                                    &p.settings,
                                    BIM_FIT_TOL_HZ,
                                )
                            })
                            .collect::<Result<Vec<_>, _>>()
                    },
                );
                Ok(SetRun {
                    set,
                    device,
                    sweeps: sweeps?,
                    fits: fits?,
                })
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Run { protocol, sets })
    }

    /// Figure 8's claim values, both sets (see [`set_claims`]).
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let stop_hz = *run
            .protocol
            .settings
            .freqs_hz
            .last()
            .expect("a sweep has frequencies");
        claims.known(
            run.sets
                .iter()
                .flat_map(|r| {
                    set_claims(r, stop_hz)
                        .into_iter()
                        .map(|v| v.to_value(r.set))
                })
                .collect(),
        )
    }
}

/// Claim F8-e's order: the jump frequencies (Hz) at b_im = 0, 1.5 and 10 N s/m fall
/// strictly as b_im grows.
pub fn jumps_fall_as_bim_grows(bim0_hz: f64, bim1p5_hz: f64, bim10_hz: f64) -> bool {
    bim0_hz > bim1p5_hz && bim1p5_hz > bim10_hz
}

/// One set's claim values; `stop_hz` is the end of the paper's range.
///
/// * F8-a: 1 if the 4.1 g sweep never touches a stop.
/// * F8-b: refined onset of the 5.5 g Hertz b_im = 1.5 sweep.
/// * F8-c, d, e, f: where the impacting branch of each 5.5 g sweep ends (jump, or loss of
///   contact when there is no jump; the note says which).
/// * F8-e order: 1 only if all three Hertz sweeps end with a confirmed jump and the jump
///   frequencies fall strictly as b_im grows.
pub fn set_claims(r: &SetRun, stop_hz: f64) -> Vec<ClaimValue> {
    use Fig8Curve::{Hertz0, Hertz10, Hertz1p5, Low};
    let curve = |c: Fig8Curve| r.sweeps.curve(c);
    let mut out = vec![no_impact_value(keys::F8A_NO_IMPACT, curve(Low))];
    if let Some(t) = curve(Hertz1p5).report.onset {
        out.push(ClaimValue {
            key: keys::F8B_ONSET,
            value: Answer::Number(t.value()),
            uncertainty: Some(t.half_width()),
            note: "first contact, refined".into(),
        });
    }
    for (key, c) in JUMP_CLAIMS {
        out.extend(branch_end_value(key, curve(c), stop_hz));
    }
    let jump = |c: Fig8Curve| curve(c).report.jump.map(|t| t.value());
    let (ordered, note) = match (jump(Hertz0), jump(Hertz1p5), jump(Hertz10)) {
        (Some(j0), Some(j1), Some(j10)) => (
            jumps_fall_as_bim_grows(j0, j1, j10),
            "all three sweeps jump; order of the jump frequencies".to_string(),
        ),
        _ => (
            false,
            "not every one of the three sweeps ends with a jump".to_string(),
        ),
    };
    out.push(bool_value(keys::F8E_JUMP_ORDER, ordered, note));
    out
}

//! The sine-sweep and analytic claims of the deviations study by their fast paths: Figures 8, 9 and 13
//! by continuation of the periodic orbits, Table 3 by eqs 15-18.

use rayon::prelude::*;

pub use super::quantity::P1_STOP_HZ;
use super::quantity::{ratio, Outcome};
use super::ranges::Variant;
use super::DeviationsError;
use crate::device::{Device, StiffnessModel};
use crate::ode::Stats;
use crate::paper::claims::{Claims, ToleranceClass};
use crate::paper::figures::fig09::{Fig9Bias, FIG9_EXTEND_G, FIG9_RANGE_G, FIG9_STEP_G};
use crate::paper::figures::{fig08, fig09};
use crate::paper::measured::P1_RESONANCE_HZ;
use crate::paper::qm::TABLE3_QM;
use crate::paper::setups::{endstop, with_endstop, FIG13_BIAS_V, P1_BIAS_V, P2_BIAS_V};
use crate::physics::harvester::Harvester;
use crate::physics::two_port::TwoPort;
use crate::progress::Silent;
use crate::study::continuation::{self, Branch, ContinuationSettings, EventKind};
use crate::study::orbit::{Forcing, Shooter};
use crate::study::sweep;

/// Figure 13's range (Hz) and largest continuation step (Hz): the figure's sweep grid.
pub const P2_RANGE_HZ: (f64, f64) = (600.0, 850.0);

/// Largest continuation step of prototype 2 (Hz): the sweep's 2 Hz grid.
pub const P2_STEP_HZ: f64 = 2.0;

/// Figure 13's drive levels (g rms): below and above the impact onset.
pub const P2_LEVELS_G: (f64, f64) = (0.12, 0.31);

/// Figure 13's alternative Hertz fit of b_im (N s/m), a claim-defined setting.
pub const P2_HERTZ_BIM: f64 = 0.34;

/// The frequency branch of `device` at `accel_rms_g` from `start` to `stop` (Hz), steps of at
/// most `step` (Hz) ([`continuation::frequency_branch`]), its failure named by `what`.
pub fn frequency_branch(
    device: &Device,
    accel_rms_g: f64,
    (start, stop): (f64, f64),
    step: f64,
    what: &'static str,
) -> Result<Branch, DeviationsError> {
    continuation::frequency_branch(device, accel_rms_g, start, stop, step, &Silent)
        .map_err(|source| DeviationsError::Orbit { what, source })
}

/// The upper branch's fold ([`Branch::upper_fold`], the rule of
/// [`crate::paper::response::CaseRun::fold_hz`]).
pub fn upper_fold(branch: &Result<Branch, DeviationsError>) -> Outcome {
    let Ok(branch) = branch else {
        return Outcome::Failed;
    };
    branch
        .upper_fold()
        .map_or(Outcome::NoFold, |e| Outcome::Value(e.param))
}

/// The relative drop of the total power where an up-sweep leaves the branch at its upper
/// fold ([`upper_fold`]): 1 - P(landing) / P(fold), where the landing orbit is the stable
/// orbit of the branch beyond the fold at the fold's frequency (linear in the parameter
/// between the branch's points); `None` without an upper fold or a stable landing orbit.
pub fn upper_fold_drop(branch: &Branch) -> Option<f64> {
    let fold = branch.upper_fold()?;
    let f = fold.param;
    let landing = branch.points[fold.after_point + 1..]
        .windows(2)
        .filter(|w| w[0].orbit.is_stable() && w[1].orbit.is_stable())
        .find_map(|w| {
            let (a, b) = (&w[0].orbit, &w[1].orbit);
            let (pa, pb) = (a.param(branch.parameter), b.param(branch.parameter));
            ((pa - f) * (pb - f) <= 0.0 && pa != pb).then(|| {
                let t = (f - pa) / (pb - pa);
                a.summary.p_total_w + t * (b.summary.p_total_w - a.summary.p_total_w)
            })
        })?;
    Some(1.0 - landing / fold.orbit.summary.p_total_w)
}

/// The first grazing point along the branch (a corner at grazing counts): where the
/// up-sweep's mass first reaches a stop, the branch starting in free flight below it.
pub fn first_grazing(branch: &Result<Branch, DeviationsError>) -> Outcome {
    let Ok(branch) = branch else {
        return Outcome::Failed;
    };
    branch
        .grazing_events()
        .next()
        .map_or(Outcome::NoGrazing, |e| Outcome::Value(e.param))
}

/// Whether any orbit of the branch reaches the stops (`None`: the continuation failed).
pub fn branch_impacts(branch: &Result<Branch, DeviationsError>) -> Option<bool> {
    let branch = branch.as_ref().ok()?;
    Some(
        branch.events.iter().any(|e| e.kind == EventKind::Grazing)
            || branch.points.iter().any(|p| p.orbit.is_impacting()),
    )
}

/// Figure 8 at 5.5 g by frequency continuation: the kink, the four jumps and their order.
pub(super) fn p1_fig8(variant: &Variant) -> [Outcome; 6] {
    let base = variant.device.with_bias(P1_BIAS_V);
    let fitted = endstop(&base).damping_n_s_per_m;
    let accel = fig08::P1_HIGH_ACCEL_RMS_G * variant.accel_scale;
    let cases: [(StiffnessModel, f64, &'static str); 4] = [
        (
            StiffnessModel::Hertz,
            fitted,
            "F8-c Hertz, the variant's b_im",
        ),
        (StiffnessModel::Hertz, 0.0, "F8-d Hertz, b_im 0"),
        (StiffnessModel::Hertz, 10.0, "F8-e Hertz, b_im 10"),
        (StiffnessModel::Linear, 2.0, "F8-f linear, b_im 2"),
    ];
    let branches = cases
        .par_iter()
        .map(|&(law, bim, what)| {
            frequency_branch(
                &with_endstop(&base, law, bim),
                accel,
                (fig08::P1_SWEEP_START_HZ, P1_STOP_HZ),
                fig08::P1_SWEEP_STEP_HZ,
                what,
            )
        })
        .collect::<Vec<_>>();
    let folds: Vec<Outcome> = branches.iter().map(upper_fold).collect();
    // The order claim compares jumps, as Figure 8's rule does: a fold counts only if the
    // up-sweep's power falls there by a jump's drop ([`sweep::JUMP_MIN_DROP`]).
    let jumps = |i: usize| {
        branches[i]
            .as_ref()
            .ok()
            .and_then(upper_fold_drop)
            .is_some_and(|d| d > sweep::JUMP_MIN_DROP)
    };
    let order = match (folds[1], folds[0], folds[2]) {
        (Outcome::Value(b0), Outcome::Value(b15), Outcome::Value(b10)) => Outcome::yes_no(
            fig08::jumps_fall_as_bim_grows(b0, b15, b10) && jumps(0) && jumps(1) && jumps(2),
        ),
        (Outcome::Failed, _, _) | (_, Outcome::Failed, _) | (_, _, Outcome::Failed) => {
            Outcome::Failed
        }
        _ => Outcome::Value(0.0),
    };
    // The grazing orbit is a free-flight orbit, the same for every contact law and b_im: the
    // first branch that reaches it gives the onset when the fitted case's continuation failed.
    let onset = branches
        .iter()
        .map(first_grazing)
        .find(|o| *o != Outcome::Failed)
        .unwrap_or(Outcome::Failed);
    [onset, folds[0], folds[1], folds[2], order, folds[3]]
}

/// One bias of Figure 9 by amplitude continuation at 1220 Hz from 0.5 g to the extension's
/// 8 g (stated g; the drive is `accel_scale` times it): the onset (first grazing point, in
/// stated g) and the power of one load at 5.5 g stated (W), on the first crossing of 5.5 g
/// along the branch (the up-sweep's orbit, the branch starting in free flight).
fn p1_fig9_bias(variant: &Variant, bias_v: f64) -> (Outcome, Outcome) {
    let device = variant.device.with_bias(bias_v);
    let s = variant.accel_scale;
    let settings =
        ContinuationSettings::amplitude(FIG9_RANGE_G.0 * s, FIG9_EXTEND_G * s, FIG9_STEP_G * s);
    let start = Forcing {
        freq_hz: P1_RESONANCE_HZ,
        accel_rms_g: FIG9_RANGE_G.0 * s,
    };
    let Ok(branch) = continuation::branch_from_rest(&device, start, &settings, 200, &Silent) else {
        return (Outcome::Failed, Outcome::Failed);
    };
    let onset = branch
        .grazing_events()
        .next()
        .map_or(Outcome::NoGrazing, |e| Outcome::Value(e.param / s));
    let Ok(h) = Harvester::<4>::new(&device) else {
        return (onset, Outcome::Failed);
    };
    let shooter = Shooter::new(&h, settings.shooting);
    let mut stats = Stats::default();
    let power = match branch.orbits_at(&shooter, FIG9_RANGE_G.1 * s, &mut stats) {
        Ok(orbits) => orbits.first().map_or(Outcome::Failed, |o| {
            Outcome::Value(o.summary.v1_rms_v.powi(2) / device.transducer.load_resistance_ohm())
        }),
        Err(_) => Outcome::Failed,
    };
    (onset, power)
}

/// Figure 9 by amplitude continuation ([`p1_fig9_bias`] at 20, 30 and 40 V): the three
/// onsets, whether they are the same (within the claims' `amplitude_threshold` class, the
/// rule of [`crate::paper::figures::fig09::onsets_agree`]), the powers at 20 and 40 V (nW) and
/// their ratio.
pub(super) fn p1_fig9(variant: &Variant, class: &ToleranceClass) -> [Outcome; 7] {
    let runs: Vec<(Outcome, Outcome)> = Fig9Bias::ALL
        .par_iter()
        .map(|b| p1_fig9_bias(variant, b.volts()))
        .collect();
    let onsets: Vec<Outcome> = runs.iter().map(|r| r.0).collect();
    let same = if onsets.contains(&Outcome::Failed) {
        Outcome::Failed
    } else {
        let all: Option<Vec<f64>> = onsets.iter().map(|o| o.value()).collect();
        Outcome::yes_no(all.is_some_and(|v| fig09::onsets_agree(&v, class).0))
    };
    let (p20, p40) = (runs[0].1, runs[2].1);
    let nw = |p: Outcome| p.value().map_or(p, |w| Outcome::Value(w * 1e9));
    [
        onsets[0],
        onsets[1],
        onsets[2],
        same,
        nw(p20),
        nw(p40),
        ratio(p40, p20),
    ]
}

/// Figure 13's yes/no claims by frequency continuation.
pub(super) fn p2_fig13(variant: &Variant, claims: &Claims) -> [Outcome; 3] {
    let base = variant.device.with_bias(FIG13_BIAS_V);
    let fitted = endstop(&base).damping_n_s_per_m;
    let cases: [(StiffnessModel, f64, f64, &'static str); 3] = [
        (StiffnessModel::Linear, fitted, P2_LEVELS_G.0, "F13 0.12 g"),
        (
            StiffnessModel::Linear,
            fitted,
            P2_LEVELS_G.1,
            "F13 0.31 g, linear",
        ),
        (
            StiffnessModel::Hertz,
            P2_HERTZ_BIM,
            P2_LEVELS_G.1,
            "F13 0.31 g, Hertz",
        ),
    ];
    let branches = cases
        .par_iter()
        .map(|&(law, bim, g, what)| {
            frequency_branch(
                &with_endstop(&base, law, bim),
                g * variant.accel_scale,
                P2_RANGE_HZ,
                P2_STEP_HZ,
                what,
            )
        })
        .collect::<Vec<_>>();
    let yes = |b: Option<bool>| b.map_or(Outcome::Failed, Outcome::yes_no);
    let failed = branches.iter().any(|b| b.is_err());
    let fold_linear = upper_fold(&branches[1]);
    let fold_hertz = upper_fold(&branches[2]);
    // Figure 13's rule: the two jumps agree within the frequency class.
    let agree = match (
        fold_linear.value(),
        fold_hertz.value(),
        claims.class("frequency"),
    ) {
        (Some(a), Some(b), Some(class)) => (a - b).abs() <= class.tolerance(a),
        _ => false,
    };
    [
        yes(branch_impacts(&branches[0]).map(|b| !b)),
        yes(branch_impacts(&branches[1]).map(|b| b && fold_linear.value().is_some())),
        yes((!failed).then_some(agree)),
    ]
}

/// Table 3's second column at a variant (eqs 15-18 at 15 V), in [`P2_QUANTITIES`] order.
pub(super) fn p2_table3(variant: &Variant) -> [Outcome; 3] {
    let tp = TwoPort::of(&variant.device.with_bias(P2_BIAS_V));
    let qm = TABLE3_QM.of(&tp);
    [
        Outcome::Value(tp.k2 * 100.0),
        Outcome::Value(qm),
        Outcome::Value(tp.k2 * qm),
    ]
}

/// Table 3's first column at a variant (eqs 15-18 at 30 V), in [`super::P1_QUANTITIES`]
/// order.
pub(super) fn p1_table3(variant: &Variant) -> [Outcome; 3] {
    let tp = TwoPort::of(&variant.device.with_bias(P1_BIAS_V));
    let qm = TABLE3_QM.of(&tp);
    [
        Outcome::Value(tp.k2 * 100.0),
        Outcome::Value(qm),
        Outcome::Value(tp.k2 * qm),
    ]
}

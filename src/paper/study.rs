//! The claim quantities of a [`Variant`] (a device with every uncertain factor set, and the
//! drive's scale) by the fast paths, for the global sensitivity study and the multi-claim
//! calibration ("Why the paper deviates").
//!
//! The fast path of a narrowband claim is the pseudo-arclength continuation of the periodic
//! orbits ([`crate::study::continuation`]) instead of the stepped sweep: Figure 8's kink (the
//! up-sweep's impact onset) is the branch's first grazing point, a jump down is the upper
//! fold (where the up-sweep leaves the impacting branch when its steady-state blocks are long
//! enough; the response study's table). Table 3's quantities are analytic (eqs 15-18).
//!
//! Every quantity is keyed by the claims file's `(id, quantity)` and normalised by the claim's
//! own tolerance ([`crate::paper::claims::Claim::tolerance`]). A quantity that does not exist at
//! a point is a named [`Outcome`]: no fold (the branch does not jump inside the continuation's
//! range) or no grazing (the mass never reaches the stops there). Where a number is needed
//! (Sobol indices, the minimax objective) the missing one is replaced by the end of the
//! continuation's range, the censored value ([`Quantity::substitute`]), and the share of
//! points where the substitute was used is reported beside every index.

use rayon::prelude::*;
use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::drive::Sine;
use crate::num::minimax::{Fit, MinimaxError, MinimaxSettings};
use crate::num::sensitivity::{Bootstrap, Indices, Saltelli, SensitivityError};
use crate::ode::Stats;
use crate::paper::claims::{Claim, Claims, ClaimsError, Kind, ToleranceClass};
use crate::paper::ensembles::{
    protocol_spec, WidthReading, P1_BAND_HZ, P1_NPERSEG, P2_BAND_HZ, P2_NPERSEG,
};
use crate::paper::fig09::{Fig9Bias, FIG9_EXTEND_G, FIG9_RANGE_G, FIG9_STEP_G};
use crate::paper::fig12::{self, FIG12_LEVELS};
use crate::paper::fig15::{self, FIG15_LEVELS};
use crate::paper::measured::P1_RESONANCE_HZ;
use crate::paper::sensitivity::{Factor, Ranges, RangesError, Variant};
use crate::paper::setups::{endstop, FIG13_BIAS_V, P1_BIAS_V, P2_BIAS_V};
use crate::paper::{fig08, fig09};
use crate::physics::harvester::Harvester;
use crate::physics::two_port::{efficiency, TwoPort, TABLE3_QM};
use crate::study::continuation::{self, Branch, ContinuationSettings, EventKind};
use crate::study::ensemble::{run_ensembles, Ensemble, EnsembleCase, EnsembleSpec};
use crate::study::orbit::{Forcing, OrbitError, Shooter};
use crate::study::sweep;

/// Upper end of prototype 1's frequency continuations (Hz): Figure 8's range extended to
/// 2000 Hz, as the response study's fold claims (without end-stop damping the impacting
/// branch reaches 1600 Hz).
pub const P1_STOP_HZ: f64 = 2000.0;

/// Figure 13's range (Hz) and largest continuation step (Hz): the figure's sweep grid.
pub const P2_RANGE_HZ: (f64, f64) = (600.0, 850.0);

/// Largest continuation step of prototype 2 (Hz): the sweep's 2 Hz grid.
pub const P2_STEP_HZ: f64 = 2.0;

/// Figure 13's drive levels (g rms): below and above the impact onset.
pub const P2_LEVELS_G: (f64, f64) = (0.12, 0.31);

/// Figure 13's alternative Hertz fit of b_im (N s/m), a claim-defined setting.
pub const P2_HERTZ_BIM: f64 = 0.34;

/// Scramble of the study's Saltelli design and of its calibration's Sobol starts.
pub const STUDY_SEED: u32 = 13;

/// Bootstrap resamples of the indices' 95 % intervals.
pub const STUDY_RESAMPLES: usize = 1000;

/// The study's bootstrap: [`STUDY_RESAMPLES`] resamples, 95 %, seeded by [`STUDY_SEED`].
pub const STUDY_BOOTSTRAP: Bootstrap = Bootstrap {
    resamples: STUDY_RESAMPLES,
    level: 0.95,
    seed: STUDY_SEED as u64,
};

/// The prototypes of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Prototype {
    /// Prototype 1 (Figures 8-12, Table 3's first column).
    P1,
    /// Prototype 2 (Figures 13-15, Table 3's second column).
    P2,
}

impl Prototype {
    /// Both, in order.
    pub const BOTH: [Prototype; 2] = [Prototype::P1, Prototype::P2];

    /// Key in files (`p1`, `p2`).
    pub fn key(self) -> &'static str {
        match self {
            Prototype::P1 => "p1",
            Prototype::P2 => "p2",
        }
    }

    /// Every quantity the study can evaluate, in output order.
    pub fn all_quantities(self) -> &'static [Quantity] {
        match self {
            Prototype::P1 => &P1_QUANTITIES,
            Prototype::P2 => &P2_QUANTITIES,
        }
    }

    /// The quantity of claim `claim` keyed `quantity`, if the study evaluates it.
    pub fn quantity(self, claim: &str, quantity: &str) -> Option<Quantity> {
        self.all_quantities()
            .iter()
            .find(|q| q.claim == claim && q.quantity == quantity)
            .copied()
    }

    /// The quantities an evaluation in `scope` computes, in output order.
    pub fn quantities(self, scope: Scope) -> Vec<Quantity> {
        self.all_quantities()
            .iter()
            .filter(|q| scope.ensemble_records.is_some() || !q.ensemble)
            .copied()
            .collect()
    }
}

/// What an evaluation computes: the narrowband and analytic claims by their fast paths
/// always; the ensemble claims (Figures 12, 14 and 15) only when given a number of records
/// per level (each costs tens of records of 10 s).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct Scope {
    /// Records per level of the ensemble claims (the first of the figures' own streams);
    /// `None` leaves the ensemble claims out.
    pub ensemble_records: Option<usize>,
}

/// One claim quantity of the study: its key in the claims file and what stands in for it when
/// it does not exist at a point.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Quantity {
    /// Claim id.
    pub claim: &'static str,
    /// Quantity key.
    pub quantity: &'static str,
    /// The value used where the quantity does not exist or its computation failed: for a
    /// frequency or an onset, the end of the continuation's range (a censored value: the event
    /// lies beyond it); for a yes/no claim, 0 (not shown); for a power, a width or a ratio, 0
    /// (only where its computation failed); `None` for an analytic quantity, which always
    /// exists.
    pub substitute: Option<f64>,
    /// Computed from ensembles of random-vibration records ([`Scope::ensemble_records`]).
    pub ensemble: bool,
}

const fn q(claim: &'static str, quantity: &'static str, substitute: Option<f64>) -> Quantity {
    Quantity {
        claim,
        quantity,
        substitute,
        ensemble: false,
    }
}

/// An ensemble quantity (substitute 0, used only where the ensemble failed or a width is
/// undetermined).
const fn qe(claim: &'static str, quantity: &'static str) -> Quantity {
    Quantity {
        claim,
        quantity,
        substitute: Some(0.0),
        ensemble: true,
    }
}

/// Prototype 1's quantities: Figure 8's kink and jumps and their order, Figure 9's onsets
/// and saturated powers, Figure 12's widths, Table 3's first column.
pub const P1_QUANTITIES: [Quantity; 19] = [
    q("F8-b", "impact_onset_5p5g_hz", Some(P1_STOP_HZ)),
    q("F8-c", "jump_hertz_bim1p5_hz", Some(P1_STOP_HZ)),
    q("F8-d", "jump_hertz_bim0_hz", Some(P1_STOP_HZ)),
    q("F8-e", "jump_hertz_bim10_hz", Some(P1_STOP_HZ)),
    q("F8-e", "jump_order_by_bim", Some(0.0)),
    q("F8-f", "jump_linear_bim2_hz", Some(P1_STOP_HZ)),
    q("F9-a", "onset_g_20v", Some(FIG9_EXTEND_G)),
    q("F9-a", "onset_g_30v", Some(FIG9_EXTEND_G)),
    q("F9-a", "onset_g_40v", Some(FIG9_EXTEND_G)),
    q("F9-a", "onset_same_all_vb", Some(0.0)),
    q("F9-b", "p_sat_20v_nw", Some(0.0)),
    q("F9-b", "p_sat_40v_nw", Some(0.0)),
    q("F9-b", "p_sat_ratio_40v_20v", Some(0.0)),
    qe("F12", "bw_7p4e-3_hz"),
    qe("F12", "bw_2p85e-2_hz"),
    qe("F12", "bw_ratio_2p85e-2_over_7p4e-3"),
    q("T3-a", "k2_pct_p1", None),
    q("T3-a", "qm_p1", None),
    q("T3-a", "k2qm_p1", None),
];

/// Prototype 2's quantities: Figure 13's yes/no claims, Figure 14's efficiency at 1.69e-3,
/// Figure 15's peak, width, width ratio and widening, Table 3's second column.
pub const P2_QUANTITIES: [Quantity; 11] = [
    q("F13", "no_impact_0p12g", Some(0.0)),
    q("F13", "jump_0p31g", Some(0.0)),
    q("F13", "hertz_linear_agree", Some(0.0)),
    qe("F14-b", "eff_1p69e-3_pct"),
    qe("F15-a", "peak_0p34e-3_hz"),
    qe("F15-a", "bw_0p34e-3_hz"),
    qe("F15-b", "bw_ratio_0p55e-3_over_0p34e-3"),
    qe("F15-c", "widening_up_1p69e-3"),
    q("T3-b", "k2_pct_p2", None),
    q("T3-b", "qm_p2", None),
    q("T3-b", "k2qm_p2", None),
];

/// The value of a quantity at a point, or why it has none.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Outcome {
    /// The quantity exists.
    Value(f64),
    /// The branch has no upper fold inside the range: no jump down.
    NoFold,
    /// The branch never grazes inside the range: no impacts.
    NoGrazing,
    /// The continuation failed at this point (Newton or the integrator; counted and reported).
    Failed,
}

impl Outcome {
    /// The value, if the quantity exists.
    pub fn value(self) -> Option<f64> {
        match self {
            Outcome::Value(v) => Some(v),
            _ => None,
        }
    }

    /// A yes/no quantity: 1 for yes, 0 for no.
    pub fn yes_no(yes: bool) -> Self {
        Outcome::Value(if yes { 1.0 } else { 0.0 })
    }

    /// The outcome of a [`Outcome::label`] (and the value, for `"value"`); `None` for an
    /// unknown label.
    pub fn from_label(label: &str, value: f64) -> Option<Self> {
        Some(match label {
            "value" => Outcome::Value(value),
            "no fold" => Outcome::NoFold,
            "no grazing" => Outcome::NoGrazing,
            "continuation failed" => Outcome::Failed,
            _ => return None,
        })
    }

    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Outcome::Value(_) => "value",
            Outcome::NoFold => "no fold",
            Outcome::NoGrazing => "no grazing",
            Outcome::Failed => "continuation failed",
        }
    }
}

/// One quantity evaluated at a point, normalised by its claim.
#[derive(Debug, Clone, PartialEq)]
pub struct Evaluation {
    /// The quantity.
    pub quantity: Quantity,
    /// Its value or absence.
    pub outcome: Outcome,
    /// The value, or the substitute where it does not exist.
    pub value: f64,
    /// (value - paper) / the claim's tolerance for a quantitative claim; for a yes/no claim
    /// ours - paper (0 when met, +-1 otherwise).
    pub deviation: f64,
    /// The claim's verdict on the value is `reproduced` (an absent quantity never is).
    pub meets: bool,
    /// Quantitative (normalised by a tolerance) or yes/no.
    pub kind: Kind,
}

/// Failures of an evaluation.
#[derive(Debug, Error)]
pub enum StudyError {
    /// Shooting or continuation failed.
    #[error("{what}: {source}")]
    Orbit {
        /// Which continuation.
        what: &'static str,
        /// The error.
        source: OrbitError,
    },
    /// A quantity matches no claim of the claims file.
    #[error("no claim ({0}, {1}) in the claims file")]
    UnknownClaim(&'static str, &'static str),
    /// A point outside the unit cube or a device that fails validation.
    #[error(transparent)]
    Ranges(#[from] RangesError),
    /// The design or the indices failed.
    #[error(transparent)]
    Sensitivity(#[from] SensitivityError),
    /// The minimax search failed.
    #[error(transparent)]
    Minimax(#[from] MinimaxError),
    /// The claims file lacks a class the study needs.
    #[error(transparent)]
    Claims(#[from] ClaimsError),
    /// A quantity that always exists came out absent.
    #[error("({0}, {1}) has no value and no substitute")]
    NoSubstitute(&'static str, &'static str),
    /// Evaluations or a start that do not belong to the design or the calibration they are
    /// given to.
    #[error("study: {0}")]
    Evaluations(String),
}

/// The frequency branch of `device` at `accel_rms_g` from `start` to `stop` (Hz), steps of at
/// most `step` (Hz) ([`continuation::frequency_branch`]), its failure named by `what`.
pub fn frequency_branch(
    device: &Device,
    accel_rms_g: f64,
    (start, stop): (f64, f64),
    step: f64,
    what: &'static str,
) -> Result<Branch, StudyError> {
    continuation::frequency_branch(device, accel_rms_g, start, stop, step, |_| {})
        .map_err(|source| StudyError::Orbit { what, source })
}

/// The upper branch's fold ([`Branch::upper_fold`], the rule of
/// [`crate::paper::response::CaseRun::fold_hz`]).
pub fn upper_fold(branch: &Result<Branch, StudyError>) -> Outcome {
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
pub fn first_grazing(branch: &Result<Branch, StudyError>) -> Outcome {
    let Ok(branch) = branch else {
        return Outcome::Failed;
    };
    branch
        .grazing_events()
        .next()
        .map_or(Outcome::NoGrazing, |e| Outcome::Value(e.param))
}

/// Whether any orbit of the branch reaches the stops (`None`: the continuation failed).
pub fn branch_impacts(branch: &Result<Branch, StudyError>) -> Option<bool> {
    let branch = branch.as_ref().ok()?;
    Some(
        branch.events.iter().any(|e| e.kind == EventKind::Grazing)
            || branch.points.iter().any(|p| p.orbit.is_impacting()),
    )
}

/// The raw quantities of prototype 1 at a variant (`variant.device` is prototype 1 with the
/// factors applied), in the order of [`Prototype::quantities`] in `scope`. The variant's own b_im and tension-free
/// setting enter the fitted cases (F8-b, F8-c, Figures 9 and 12); the other jump claims set b_im
/// and the law as the claims state them. Figures 8, 9 and 12 run in parallel.
pub fn evaluate_p1(
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Outcome>, StudyError> {
    let class = claims.require_class("amplitude_threshold")?;
    let ((fig8, fig9), fig12) = rayon::join(
        || rayon::join(|| p1_fig8(variant), || p1_fig9(variant, class)),
        || scope.ensemble_records.map(|r| p1_fig12(variant, r)),
    );
    let tp = TwoPort::of(&variant.device.with_bias(P1_BIAS_V));
    let qm = tp.qm(TABLE3_QM);
    let mut out = Vec::with_capacity(P1_QUANTITIES.len());
    out.extend(fig8);
    out.extend(fig9);
    out.extend(fig12.into_iter().flatten());
    out.extend([
        Outcome::Value(tp.k2 * 100.0),
        Outcome::Value(qm),
        Outcome::Value(tp.k2 * qm),
    ]);
    Ok(out)
}

/// Figure 8 at 5.5 g by frequency continuation: the kink, the four jumps and their order.
fn p1_fig8(variant: &Variant) -> [Outcome; 6] {
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
                &base.with_endstop(law, bim),
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
    let Ok(branch) = continuation::branch_from_rest(&device, start, &settings, 200, |_| {}) else {
        return (Outcome::Failed, Outcome::Failed);
    };
    let onset = branch
        .grazing_events()
        .next()
        .map_or(Outcome::NoGrazing, |e| Outcome::Value(e.param / s));
    let h = Harvester::new(
        &device,
        Sine::from_rms_g(FIG9_RANGE_G.1 * s, P1_RESONANCE_HZ),
    );
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
/// rule of [`crate::paper::fig09::claims`]), the powers at 20 and 40 V (nW) and their ratio.
fn p1_fig9(variant: &Variant, class: &ToleranceClass) -> [Outcome; 7] {
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

/// An ensemble of the study at the stated level `psd_g2_per_hz`: the figure's protocol
/// ([`protocol_spec`], without the second segmenting) with `records` records, the streams of
/// the stated level (the same at every point of the study: common random numbers) and the
/// drive scaled by `accel_scale` (the PSD by its square). With the figures' 32 records and
/// the published set it is the figure's ensemble.
pub fn study_ensemble_spec(
    device: &Device,
    psd_g2_per_hz: f64,
    (nperseg, band_hz): (usize, (f64, f64)),
    records: usize,
    accel_scale: f64,
) -> EnsembleSpec {
    let mut spec = protocol_spec(device, psd_g2_per_hz, nperseg, band_hz, records, false);
    spec.record.noise.psd_g2_per_hz *= accel_scale * accel_scale;
    spec
}

/// The half-power width of an ensemble-mean PSD (Hz), or failed where undetermined.
fn mean_width(e: &Ensemble) -> Outcome {
    let w = WidthReading::HalfPower.mean_width(e).estimate;
    if w.is_finite() {
        Outcome::Value(w)
    } else {
        Outcome::Failed
    }
}

/// The ratio of two outcomes, failed unless both exist.
fn ratio(a: Outcome, b: Outcome) -> Outcome {
    match (a.value(), b.value()) {
        (Some(a), Some(b)) => Outcome::Value(a / b),
        _ => Outcome::Failed,
    }
}

/// The study's ensembles of `device` at the stated `levels` ([`study_ensemble_spec`]), in
/// order; `None` if any failed.
fn study_ensembles(
    device: &Device,
    levels: &[f64],
    welch: (usize, (f64, f64)),
    records: usize,
    accel_scale: f64,
) -> Option<Vec<Ensemble>> {
    let cases: Vec<EnsembleCase> = levels
        .iter()
        .map(|&sa| EnsembleCase {
            device: device.clone(),
            spec: study_ensemble_spec(device, sa, welch, records, accel_scale),
        })
        .collect();
    run_ensembles(&cases, || {}).ok()
}

/// Figure 12 by `records` records at 7.4e-3 and 2.85e-2 g²/Hz: the two half-power widths and
/// their ratio.
fn p1_fig12(variant: &Variant, records: usize) -> [Outcome; 3] {
    let levels = [FIG12_LEVELS[fig12::LOW], FIG12_LEVELS[fig12::HIGH]];
    let device = variant.device.with_bias(P1_BIAS_V);
    let welch = (P1_NPERSEG, P1_BAND_HZ);
    let Some(ens) = study_ensembles(&device, &levels, welch, records, variant.accel_scale) else {
        return [Outcome::Failed; 3];
    };
    let (lo, hi) = (mean_width(&ens[0]), mean_width(&ens[1]));
    [lo, hi, ratio(hi, lo)]
}

/// Figures 14 and 15 by `records` records at 0.34e-3, 0.55e-3 and 1.69e-3 g²/Hz
/// (15 V): the efficiency at 1.69e-3 (%, of the **stated** level, as the paper divides by its
/// Sa), the peak and width at 0.34e-3, the width ratio 0.55e-3 over 0.34e-3, and the widening
/// towards higher frequencies at 1.69e-3 ([`fig15::widens_up`]).
fn p2_ensembles(variant: &Variant, records: usize) -> [Outcome; 5] {
    let device = variant.device.with_bias(P2_BIAS_V);
    let welch = (P2_NPERSEG, P2_BAND_HZ);
    let Some(ens) = study_ensembles(&device, &FIG15_LEVELS, welch, records, variant.accel_scale)
    else {
        return [Outcome::Failed; 5];
    };
    let (e34, e55, e169) = (&ens[fig15::L034], &ens[fig15::L055], &ens[fig15::L169]);
    let eff = efficiency(&device, e169.power_w.mean, FIG15_LEVELS[fig15::L169]) * 100.0;
    let w34 = mean_width(e34);
    let widening = fig15::widens_up(e34, e169).map_or(Outcome::Failed, Outcome::yes_no);
    [
        Outcome::Value(eff),
        Outcome::Value(e34.mean_spectrum.total.peak().0),
        w34,
        ratio(mean_width(e55), w34),
        widening,
    ]
}

/// The raw quantities of prototype 2 at a variant, in the order of [`Prototype::quantities`]
/// in `scope`: Figure 13 at 10 V with the linear law and the variant's b_im (the paper's fit),
/// the Hertz alternative with its claim-defined b_im; Figures 14 and 15 at 15 V
/// (`p2_ensembles`); Table 3 at 15 V.
pub fn evaluate_p2(
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Outcome>, StudyError> {
    let (fig13, ensembles) = rayon::join(
        || p2_fig13(variant, claims),
        || scope.ensemble_records.map(|r| p2_ensembles(variant, r)),
    );
    let mut out = Vec::with_capacity(P2_QUANTITIES.len());
    out.extend(fig13);
    out.extend(ensembles.into_iter().flatten());
    out.extend(p2_table3(variant));
    Ok(out)
}

/// Figure 13's yes/no claims by frequency continuation.
fn p2_fig13(variant: &Variant, claims: &Claims) -> [Outcome; 3] {
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
                &base.with_endstop(law, bim),
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
fn p2_table3(variant: &Variant) -> [Outcome; 3] {
    let tp = TwoPort::of(&variant.device.with_bias(P2_BIAS_V));
    let qm = tp.qm(TABLE3_QM);
    [
        Outcome::Value(tp.k2 * 100.0),
        Outcome::Value(qm),
        Outcome::Value(tp.k2 * qm),
    ]
}

/// The quantitative claims of a prototype at a variant (the calibration's objective): every
/// quantitative claim of [`evaluate`], computed without the continuations none of them needs
/// (prototype 2's come from the ensembles and Table 3).
pub fn evaluate_quantitative(
    prototype: Prototype,
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Evaluation>, StudyError> {
    match prototype {
        Prototype::P1 => Ok(evaluate(prototype, variant, claims, scope)?
            .into_iter()
            .filter(|e| e.kind == Kind::Quantitative)
            .collect()),
        // Everything but Figure 13 (whose claims are yes/no), in order: the ensembles and
        // Table 3, without the continuations.
        Prototype::P2 => prototype
            .quantities(scope)
            .iter()
            .filter(|q| q.claim != "F13")
            .zip(
                scope
                    .ensemble_records
                    .map(|r| p2_ensembles(variant, r))
                    .into_iter()
                    .flatten()
                    .chain(p2_table3(variant)),
            )
            .map(|(qty, outcome)| normalise(qty, outcome, claims))
            .filter(|e| !matches!(e, Ok(e) if e.kind != Kind::Quantitative))
            .collect(),
    }
}

/// Every quantity of a prototype at a variant, normalised by the claims file.
pub fn evaluate(
    prototype: Prototype,
    variant: &Variant,
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Evaluation>, StudyError> {
    let raw = match prototype {
        Prototype::P1 => evaluate_p1(variant, claims, scope)?,
        Prototype::P2 => evaluate_p2(variant, claims, scope)?,
    };
    prototype
        .quantities(scope)
        .iter()
        .zip(raw)
        .map(|(qty, outcome)| normalise(qty, outcome, claims))
        .collect()
}

/// A quantity's outcome normalised by its claim.
pub fn normalise(
    qty: &Quantity,
    outcome: Outcome,
    claims: &Claims,
) -> Result<Evaluation, StudyError> {
    let claim: &Claim = claims
        .get(qty.claim, qty.quantity)
        .ok_or(StudyError::UnknownClaim(qty.claim, qty.quantity))?;
    let value = match (outcome.value(), qty.substitute) {
        (Some(v), _) => v,
        (None, Some(s)) => s,
        (None, None) => return Err(StudyError::NoSubstitute(qty.claim, qty.quantity)),
    };
    let deviation = match claim.kind {
        Kind::Quantitative => (value - claim.paper) / claim.tolerance(),
        Kind::Qualitative => value - claim.paper,
    };
    let meets = outcome.value().is_some()
        && claim.verdict(Some(value)) == crate::paper::claims::Verdict::Reproduced;
    Ok(Evaluation {
        quantity: *qty,
        outcome,
        value,
        deviation,
        meets,
        kind: claim.kind,
    })
}

/// The unit-cube model of a prototype: the variant of `base` at a point, evaluated.
pub fn evaluate_at(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    point: &[f64],
    claims: &Claims,
    scope: Scope,
) -> Result<Vec<Evaluation>, StudyError> {
    let variant = ranges.variant(base, point)?;
    evaluate(prototype, &variant, claims, scope)
}

/// The Sobol indices of one quantity.
#[derive(Debug, Clone, PartialEq)]
pub struct QuantityIndices {
    /// The quantity.
    pub quantity: Quantity,
    /// First-order and total indices with their bootstrap intervals, in [`Factor::ALL`] order;
    /// `None` when the quantity does not vary over the design (every index is 0/0).
    pub indices: Option<Indices>,
    /// Share of the design's points where the quantity does not exist (its substitute is used):
    /// the sum of the three shares below.
    pub absent_share: f64,
    /// Share of points whose branch has no upper fold in the range (no jump down).
    pub no_fold_share: f64,
    /// Share of points whose branch never grazes in the range (no impacts).
    pub no_grazing_share: f64,
    /// Share of points whose continuation failed.
    pub failed_share: f64,
}

/// A Sobol study of one prototype.
#[derive(Debug, Clone, PartialEq)]
pub struct SobolRun {
    /// The prototype.
    pub prototype: Prototype,
    /// The design.
    pub design: Saltelli,
    /// The evaluations at every design point, in design order.
    pub evaluations: Vec<Vec<Evaluation>>,
    /// One entry per quantity of [`Prototype::quantities`].
    pub quantities: Vec<QuantityIndices>,
}

/// The design of a Sobol study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SobolDesign {
    /// Base rows of the Saltelli design (a power of two).
    pub base_rows: usize,
    /// Scramble of the design.
    pub seed: u32,
    /// The bootstrap of the intervals.
    pub bootstrap: Bootstrap,
    /// What each point evaluates.
    pub scope: Scope,
}

/// Sobol first-order and total indices of every quantity of `prototype` over `ranges`, from
/// the Saltelli design of `d`; `on_point()` after every design point (points run in
/// parallel, results in design order). The same as evaluating every point of
/// [`SobolDesign::design`] with [`evaluate_at`] (e.g. as tasks of a cluster) and passing the
/// evaluations to [`sobol_indices`].
pub fn sobol(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    d: SobolDesign,
    claims: &Claims,
    on_point: &(dyn Fn() + Sync),
) -> Result<SobolRun, StudyError> {
    let design = d.design()?;
    let evaluations = design
        .points()
        .par_iter()
        .map(|p| {
            let e = evaluate_at(prototype, ranges, base, p, claims, d.scope);
            on_point();
            e
        })
        .collect::<Result<Vec<_>, _>>()?;
    sobol_indices(prototype, d, evaluations)
}

impl SobolDesign {
    /// The Saltelli design over [`Factor::ALL`].
    pub fn design(&self) -> Result<Saltelli, StudyError> {
        Ok(Saltelli::new(self.base_rows, Factor::ALL.len(), self.seed)?)
    }
}

/// The indices of every quantity of `prototype` from its `evaluations` at the points of the
/// design of `d`, in design order (each one [`evaluate_at`]'s output in `d.scope`).
pub fn sobol_indices(
    prototype: Prototype,
    d: SobolDesign,
    evaluations: Vec<Vec<Evaluation>>,
) -> Result<SobolRun, StudyError> {
    let design = d.design()?;
    let wanted = prototype.quantities(d.scope);
    if evaluations.len() != design.len() {
        return Err(StudyError::Evaluations(format!(
            "{} evaluations for a design of {} points",
            evaluations.len(),
            design.len()
        )));
    }
    if let Some((k, _)) = evaluations.iter().enumerate().find(|(_, e)| {
        e.len() != wanted.len() || e.iter().zip(&wanted).any(|(e, q)| e.quantity != *q)
    }) {
        return Err(StudyError::Evaluations(format!(
            "the evaluation of point {k} does not hold the quantities of {} in this scope, in order",
            prototype.key()
        )));
    }
    let quantities = wanted
        .iter()
        .enumerate()
        .map(|(j, qty)| {
            let outputs: Vec<f64> = evaluations.iter().map(|e| e[j].deviation).collect();
            let share = |keep: &dyn Fn(Outcome) -> bool| {
                let n = evaluations.iter().filter(|e| keep(e[j].outcome)).count();
                n as f64 / evaluations.len() as f64
            };
            let indices = match design.indices(&outputs, d.bootstrap) {
                Ok(i) => Some(i),
                Err(SensitivityError::NoVariance) => None,
                Err(e) => return Err(StudyError::Sensitivity(e)),
            };
            Ok(QuantityIndices {
                quantity: *qty,
                indices,
                absent_share: share(&|o| o.value().is_none()),
                no_fold_share: share(&|o| o == Outcome::NoFold),
                no_grazing_share: share(&|o| o == Outcome::NoGrazing),
                failed_share: share(&|o| o == Outcome::Failed),
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SobolRun {
        prototype,
        design,
        evaluations,
        quantities,
    })
}

/// The Pareto front between two claims of a prototype over the points of a Sobol design:
/// the points no other point beats on both |normalised deviations|.
#[derive(Debug, Clone, PartialEq)]
pub struct Pareto {
    /// The prototype.
    pub prototype: Prototype,
    /// The two quantities (indices into the run's quantities).
    pub pair: (Quantity, Quantity),
    /// How much the pair conflicts: the least worst-of-two |deviation| over the points, less
    /// the larger of the two least single |deviations| (0: one point is best for both).
    pub conflict: f64,
    /// Every point's (|deviation a|, |deviation b|), in design order.
    pub points: Vec<(f64, f64)>,
    /// Indices of the front's points, by increasing |deviation a|.
    pub front: Vec<usize>,
}

/// Indices of the non-dominated points of `points` (minimising both coordinates; ties keep
/// the first), by increasing first coordinate.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&i, &j| {
        points[i]
            .0
            .total_cmp(&points[j].0)
            .then(points[i].1.total_cmp(&points[j].1))
            .then(i.cmp(&j))
    });
    let mut front = Vec::new();
    let mut best_b = f64::INFINITY;
    for i in order {
        if points[i].1 < best_b {
            best_b = points[i].1;
            front.push(i);
        }
    }
    front
}

/// The most conflicting pair of quantitative claims of a Sobol run ([`Pareto::conflict`],
/// the largest) with its front; `None` with fewer than two quantitative claims.
pub fn most_conflicting(run: &SobolRun) -> Option<Pareto> {
    let quant: Vec<usize> = (0..run.quantities.len())
        .filter(|&j| {
            run.evaluations
                .first()
                .is_some_and(|e| e[j].kind == Kind::Quantitative)
        })
        .collect();
    let abs = |j: usize| -> Vec<f64> {
        run.evaluations
            .iter()
            .map(|e| e[j].deviation.abs())
            .collect()
    };
    let mut best: Option<Pareto> = None;
    for (k, &a) in quant.iter().enumerate() {
        for &b in &quant[k + 1..] {
            let points: Vec<(f64, f64)> = abs(a).into_iter().zip(abs(b)).collect();
            let least =
                |f: &dyn Fn(&(f64, f64)) -> f64| points.iter().map(f).fold(f64::INFINITY, f64::min);
            let conflict = least(&|p| p.0.max(p.1)) - least(&|p| p.0).max(least(&|p| p.1));
            if best.as_ref().is_none_or(|p| conflict > p.conflict) {
                best = Some(Pareto {
                    prototype: run.prototype,
                    pair: (run.quantities[a].quantity, run.quantities[b].quantity),
                    conflict,
                    front: pareto_front(&points),
                    points,
                });
            }
        }
    }
    best
}

/// The multi-claim calibration of a prototype: the point of the ranges that minimises the
/// worst normalised deviation over its quantitative claims (the yes/no claims are reported,
/// not fitted: a step function gives the simplex no slope), by the minimax search of
/// [`crate::num::minimax`] from each of [`calibration_starts`].
#[derive(Debug, Clone, PartialEq)]
pub struct Calibration {
    /// The prototype.
    pub prototype: Prototype,
    /// Every start's fit, best first.
    pub fits: Vec<Fit>,
    /// The evaluations at the best point.
    pub best: Vec<Evaluation>,
    /// The best variant.
    pub variant: Variant,
    /// The evaluations at the published set (the first start).
    pub published: Vec<Evaluation>,
}

impl Calibration {
    /// The best fit's worst |normalised deviation| over the quantitative claims.
    pub fn worst(&self) -> f64 {
        self.fits[0].worst
    }

    /// The published set's worst |normalised deviation| over the quantitative claims.
    pub fn published_worst(&self) -> f64 {
        quantitative_deviations(&self.published)
            .iter()
            .fold(0.0, |m: f64, d| m.max(d.abs()))
    }

    /// True when the best set meets every claim of the prototype the study evaluates.
    pub fn meets_all(&self) -> bool {
        self.best.iter().all(|e| e.meets)
    }
}

/// The quantitative deviations of an evaluation (the minimax objective's components).
pub fn quantitative_deviations(e: &[Evaluation]) -> Vec<f64> {
    e.iter()
        .filter(|e| e.kind == Kind::Quantitative)
        .map(|e| e.deviation)
        .collect()
}

/// The calibration's objective at a unit-cube point: the quantitative deviations.
fn calibration_objective(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    claims: &Claims,
    scope: Scope,
    u: &[f64],
) -> Result<Vec<f64>, StudyError> {
    let v = ranges.variant(base, u)?;
    Ok(quantitative_deviations(&evaluate_quantitative(
        prototype, &v, claims, scope,
    )?))
}

/// The starts of the calibration, in start order: the published set (start 0: the search can
/// only improve on it), then `settings.starts` points of the scrambled Sobol sequence.
pub fn calibration_starts(
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
) -> Result<Vec<Vec<f64>>, StudyError> {
    let published = ranges.published_point(base)?;
    Ok(crate::num::minimax::starts(
        Factor::ALL.len(),
        settings,
        std::slice::from_ref(&published),
    )?)
}

/// One start of [`calibrate`]: the search from start `start` of [`calibration_starts`]
/// (e.g. as one task of a cluster).
pub fn calibrate_start(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
    claims: &Claims,
    scope: Scope,
    start: usize,
) -> Result<Fit, StudyError> {
    let x0 = calibration_starts(ranges, base, settings)?
        .into_iter()
        .nth(start)
        .ok_or_else(|| {
            StudyError::Evaluations(format!(
                "start {start} is not one of the {} starts",
                settings.starts + 1
            ))
        })?;
    let model = |u: &[f64]| calibration_objective(prototype, ranges, base, claims, scope, u);
    Ok(crate::num::minimax::minimise_from(
        model, settings, start, x0,
    )?)
}

/// Runs the multi-claim calibration of `prototype` over `ranges` with `settings`: every
/// start of [`calibration_starts`] in parallel, then [`calibration_of_fits`].
pub fn calibrate(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    settings: MinimaxSettings,
    claims: &Claims,
    scope: Scope,
    on_eval: &(dyn Fn() + Sync),
) -> Result<Calibration, StudyError> {
    let model = |u: &[f64]| {
        let d = calibration_objective(prototype, ranges, base, claims, scope, u);
        on_eval();
        d
    };
    let fits = calibration_starts(ranges, base, settings)?
        .into_par_iter()
        .enumerate()
        .map(|(start, x0)| crate::num::minimax::minimise_from(model, settings, start, x0))
        .collect::<Result<Vec<_>, _>>()?;
    calibration_of_fits(prototype, ranges, base, claims, scope, fits)
}

/// The calibration from its starts' fits (in any order): the best set, evaluated, beside the
/// published set.
pub fn calibration_of_fits(
    prototype: Prototype,
    ranges: &Ranges,
    base: &Device,
    claims: &Claims,
    scope: Scope,
    fits: Vec<Fit>,
) -> Result<Calibration, StudyError> {
    let fits = crate::num::minimax::best_first(fits)?;
    let variant = ranges.variant(base, &fits[0].point)?;
    let best = evaluate(prototype, &variant, claims, scope)?;
    let published = ranges.published_point(base)?;
    let published = evaluate(prototype, &ranges.variant(base, &published)?, claims, scope)?;
    Ok(Calibration {
        prototype,
        fits,
        best,
        variant,
        published,
    })
}

/// Summary key of a quantity's value at the best set of the calibration of its prototype
/// (`None`: the study does not evaluate the claim).
pub fn best_value_key(claim: &str, quantity: &str) -> Option<String> {
    Prototype::BOTH.iter().find_map(|p| {
        p.all_quantities()
            .iter()
            .any(|q| q.claim == claim && q.quantity == quantity)
            .then(|| format!("calibration_{}_{claim}_{quantity}_value", p.key()))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pareto_front_keeps_the_non_dominated_points() {
        let pts = [
            (3.0, 1.0),
            (1.0, 3.0),
            (2.0, 2.0),
            (2.5, 2.5),
            (1.0, 4.0),
            (4.0, 1.0),
        ];
        // (2.5, 2.5) is beaten by (2, 2); (1, 4) by (1, 3); (4, 1) by (3, 1).
        assert_eq!(pareto_front(&pts), vec![1, 2, 0]);
        assert!(pareto_front(&[]).is_empty());
    }
}

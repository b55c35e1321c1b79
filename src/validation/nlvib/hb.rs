//! NLvib's harmonic balance against our branch: its fold and its first-harmonic amplitudes at
//! its own points, for every harmonic truncation H, and the checks that the differences shrink
//! as H grows down to the floor of its sampled contact force.

use super::reference::{HbPoint, Reference};
use super::{Ours, TWO_PI};
use crate::study::continuation::Branch;
use crate::validation::{Check, Group, Measure, ValidationError};

/// The frequencies (rad/s) near which the harmonic-balance amplitudes are compared.
pub const OMEGAS_RAD_S: [f64; 5] = [1.1, 1.2, 1.3, 1.4, 1.5];

/// The amplitude points compared at each H ([`hb_convergence`]): both parts of the branch at
/// each of [`OMEGAS_RAD_S`], except at H = 1, whose branch folds at 1.42 rad/s and so has no
/// point within 0.05 rad/s of 1.5 rad/s on either part. A comparison with fewer points at any H
/// fails ([`hb_checks`]).
pub const HB_POINTS: [(usize, usize); 6] = [(1, 8), (3, 10), (5, 10), (10, 10), (20, 10), (40, 10)];

/// One harmonic truncation against ours: the fold and the amplitudes near [`OMEGAS_RAD_S`].
#[derive(Debug, Clone, PartialEq)]
pub struct HbComparison {
    /// H.
    pub harmonics: usize,
    /// NLvib's fold (rad/s).
    pub fold_rad_s: f64,
    /// Ours (rad/s).
    pub our_fold_rad_s: f64,
    /// Each compared point: (part, Omega, NLvib's amplitude, ours).
    pub amplitudes: Vec<(Part, f64, f64, f64)>,
}

impl HbComparison {
    /// `|NLvib - ours|` of the fold frequency (rad/s).
    pub fn fold_difference(&self) -> f64 {
        (self.fold_rad_s - self.our_fold_rad_s).abs()
    }

    /// The largest `|NLvib - ours|` of the amplitudes (m); NaN without a point (a largest
    /// difference of nothing would pass as zero).
    pub fn worst_amplitude_difference(&self) -> f64 {
        self.amplitudes
            .iter()
            .map(|(_, _, a, b)| (a - b).abs())
            .reduce(f64::max)
            .unwrap_or(f64::NAN)
    }
}

/// Which part of the branch a point is on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Part {
    /// From the start to the fold.
    Resonant,
    /// From the fold down to the grazing corner.
    Overhang,
}

impl Part {
    /// Label for tables.
    pub fn label(self) -> &'static str {
        match self {
            Part::Resonant => "resonant",
            Part::Overhang => "overhang",
        }
    }
}

/// NLvib's harmonic balance against our branch for every H: the fold, and at NLvib's own
/// point nearest each of [`OMEGAS_RAD_S`] on the resonant and the overhanging part, its
/// first-harmonic amplitude against ours at the same frequency on the same part (our branch
/// crosses such a frequency three times: resonant, overhang, then the non-impacting orbits).
/// A target without a point of NLvib's within 0.05 rad/s on the part, or beyond our fold, is
/// left out; [`hb_checks`] holds the points compared to [`HB_POINTS`].
pub fn hb_convergence(
    ours: &Ours<'_>,
    branch: &Branch,
    reference: &Reference,
) -> Result<Vec<HbComparison>, ValidationError> {
    let our_fold = branch
        .upper_fold()
        .ok_or_else(|| ValidationError::Device("our branch has no upper fold".into()))?
        .param
        * TWO_PI;
    let mut out = Vec::new();
    for (h, points) in &reference.hb {
        let (fold, i_top) = reference.hb_fold(*h)?;
        let i_low = reference.hb_lower_turn(*h)?;
        let mut amplitudes = Vec::new();
        for part in [Part::Resonant, Part::Overhang] {
            let on_part = |p: &&HbPoint| match part {
                Part::Resonant => p.point < i_top,
                Part::Overhang => p.point > i_top + 1 && p.point < i_low,
            };
            for target in OMEGAS_RAD_S {
                let Some(p) = points
                    .iter()
                    .filter(on_part)
                    .min_by(|a, b| {
                        (a.omega_rad_s - target)
                            .abs()
                            .total_cmp(&(b.omega_rad_s - target).abs())
                    })
                    .filter(|p| (p.omega_rad_s - target).abs() < 0.05)
                else {
                    continue;
                };
                let orbits = ours.orbits_at(branch, p.omega_rad_s)?;
                let k = match part {
                    Part::Resonant => 0,
                    Part::Overhang => 1,
                };
                // Beyond our fold the resonant and overhanging orbits do not exist.
                let Some(o) = orbits.get(k).filter(|_| orbits.len() == 3) else {
                    continue;
                };
                amplitudes.push((part, p.omega_rad_s, p.a1_amplitude_m, ours.a1(o)?));
            }
        }
        out.push(HbComparison {
            harmonics: *h,
            fold_rad_s: fold,
            our_fold_rad_s: our_fold,
            amplitudes,
        });
    }
    Ok(out)
}

/// The checks of the harmonic-balance convergence: from one H to the next, the fold's and the
/// amplitudes' largest difference from ours must not grow, except within the AFT sampling
/// floor (`floor_m` for amplitudes, `fold_floor_rad_s` for the fold, the micro turning points
/// of the sampled contact force); and at the largest H both must be within that floor.
pub fn hb_checks(hb: &[HbComparison], floor_m: f64, fold_floor_rad_s: f64) -> Vec<Check> {
    let mut g = Group::new("peer: harmonic balance");
    let src = "NLvib-py harmonic balance";
    // Every truncation of HB_POINTS, with every point it states: a comparison that skipped
    // points (or a whole H) would judge a smaller set than the table says.
    let short = HB_POINTS
        .iter()
        .filter(|(h, n)| {
            hb.iter()
                .find(|c| c.harmonics == *h)
                .is_none_or(|c| c.amplitudes.len() < *n)
        })
        .count();
    let stated: Vec<String> = HB_POINTS
        .iter()
        .map(|(h, n)| format!("{n} at H = {h}"))
        .collect();
    g.add(
        src,
        &format!(
            "truncations H compared at fewer amplitude points than stated ({})",
            stated.join(", ")
        ),
        0.0,
        short as f64,
        Measure::Absolute,
        0.0,
        "a count: every stated point is compared",
    );
    for w in hb.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        g.add(
            src,
            &format!(
                "|fold - ours| (rad/s), H = {} (reference: H = {})",
                b.harmonics, a.harmonics
            ),
            a.fold_difference(),
            b.fold_difference(),
            Measure::NotAbove,
            fold_floor_rad_s,
            "shrinks with H, down to the floor of the sampled contact force",
        );
        g.add(
            src,
            &format!(
                "largest |a1 - ours| (m), H = {} (reference: H = {})",
                b.harmonics, a.harmonics
            ),
            a.worst_amplitude_difference(),
            b.worst_amplitude_difference(),
            Measure::NotAbove,
            floor_m,
            "shrinks with H, down to the AFT sampling floor",
        );
    }
    if let Some(last) = hb.last() {
        g.add(
            src,
            &format!("|fold - ours| (rad/s), H = {}", last.harmonics),
            0.0,
            last.fold_difference(),
            Measure::Absolute,
            fold_floor_rad_s,
            "the micro turning points of the sampled contact force",
        );
        g.add(
            src,
            &format!("largest |a1 - ours| (m), H = {}", last.harmonics),
            0.0,
            last.worst_amplitude_difference(),
            Measure::Absolute,
            floor_m,
            "the AFT sampling floor (nlvib_aft_check_H40.csv)",
        );
    }
    g.into_checks()
}

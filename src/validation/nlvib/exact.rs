//! Against the exact shooting: our orbit through each stored exact orbit (first-harmonic
//! amplitude, largest Floquet multiplier, stability), and our continuation's fold against the
//! exact fold and its grazing points against the closed form.

use super::reference::{self, ExactPoint, Reference};
use super::{Ours, TWO_PI};
use crate::physics::closed_forms::Oscillator;
use crate::study::continuation::Branch;
use crate::validation::{Check, Group, Measure, ValidationError};

/// Accuracy of the stored multipliers: the exact shooting's difference and variational
/// multipliers agree to a few 1e-6 (`PROVENANCE.md`).
pub const MULTIPLIER_TOL: f64 = 1e-5;
/// Tolerance of our first-harmonic amplitude against the exact shooting's (relative): both
/// integrate to rtol 1e-10 and resolve the contact by events; the reference samples its orbit
/// at 4096 points per period for the Fourier coefficient, exact for a band-limited signal and
/// here good to about 1e-9.
pub const EXACT_A1_TOL: f64 = 1e-6;

/// The number of orbits the exact shooting stored (`shooting_branch.csv`, `PROVENANCE.md`):
/// the comparison must see every one of them (every `stride`-th, with a stride).
pub const EXACT_ORBITS: usize = 1161;

/// The point-by-point comparison with the exact shooting, over every `stride`-th stored orbit;
/// an error when the reference holds no orbit. A reference holding fewer than
/// [`EXACT_ORBITS`] fails its count check.
pub fn exact_point_checks(
    ours: &Ours<'_>,
    reference: &Reference,
    stride: usize,
) -> Result<(Vec<Check>, Vec<PointComparison>), ValidationError> {
    let stride = stride.max(1);
    if reference.exact.is_empty() {
        return Err(reference::missing(
            "shooting_branch.csv",
            "no orbit to compare",
        ));
    }
    let mut rows = Vec::new();
    for p in reference.exact.iter().step_by(stride) {
        let o = ours.through(p)?;
        rows.push(PointComparison {
            exact: *p,
            a1_amplitude_m: ours.a1(&o)?,
            max_multiplier: o.max_multiplier_abs(),
            stable: o.is_stable(),
        });
    }
    let src = "exact shooting (scipy, shooting_branch.csv)";
    let mut g = Group::new("peer: exact shooting");
    g.add(
        src,
        &if stride == 1 {
            format!("orbits compared (all {EXACT_ORBITS} stored)")
        } else {
            format!("orbits compared (every {stride}th of the {EXACT_ORBITS} stored)")
        },
        EXACT_ORBITS.div_ceil(stride) as f64,
        rows.len() as f64,
        Measure::Absolute,
        0.0,
        "a count: every stored orbit is compared",
    );
    let worst_a1 = rows
        .iter()
        .max_by(|a, b| a.a1_relative().total_cmp(&b.a1_relative()))
        .ok_or_else(|| reference::missing("shooting_branch.csv", "no orbit to compare"))?;
    g.add(
        src,
        &format!(
            "first-harmonic amplitude (m), worst of {} orbits (Omega = {:.6})",
            rows.len(),
            worst_a1.exact.omega_rad_s
        ),
        worst_a1.exact.a1_amplitude_m,
        worst_a1.a1_amplitude_m,
        Measure::Relative,
        EXACT_A1_TOL,
        "both integrate to rtol 1e-10 with located contact",
    );
    let worst_mu = rows
        .iter()
        .max_by(|a, b| a.mu_difference().total_cmp(&b.mu_difference()))
        .ok_or_else(|| reference::missing("shooting_branch.csv", "no orbit to compare"))?;
    g.add(
        src,
        &format!(
            "largest Floquet multiplier modulus, worst of {} orbits (Omega = {:.6})",
            rows.len(),
            worst_mu.exact.omega_rad_s
        ),
        worst_mu.exact.max_floquet_modulus_variational,
        worst_mu.max_multiplier,
        Measure::Absolute,
        MULTIPLIER_TOL,
        "the reference's two monodromies agree to a few 1e-6",
    );
    let decisive: Vec<&PointComparison> = rows.iter().filter(|r| r.decisive()).collect();
    // No decisive orbit would leave nothing to disagree: that fails rather than passes.
    let disagree = if decisive.is_empty() {
        f64::NAN
    } else {
        decisive
            .iter()
            .filter(|r| r.stable != r.exact.stable)
            .count() as f64
    };
    g.add(
        src,
        &format!(
            "stability verdicts that differ, of {} orbits with every multiplier farther than \
             {MULTIPLIER_TOL:e} from the unit circle",
            decisive.len()
        ),
        0.0,
        disagree,
        Measure::Absolute,
        0.0,
        "a verdict is exact away from the unit circle",
    );
    Ok((g.into_checks(), rows))
}

/// One stored exact orbit beside ours.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PointComparison {
    /// The stored orbit.
    pub exact: ExactPoint,
    /// Our first-harmonic amplitude (m).
    pub a1_amplitude_m: f64,
    /// Our largest multiplier modulus.
    pub max_multiplier: f64,
    /// Our verdict.
    pub stable: bool,
}

impl PointComparison {
    /// `|ours - theirs| / theirs` of the first-harmonic amplitude.
    pub fn a1_relative(&self) -> f64 {
        (self.a1_amplitude_m - self.exact.a1_amplitude_m).abs() / self.exact.a1_amplitude_m
    }

    /// `|ours - theirs|` of the largest multiplier modulus (theirs variational).
    pub fn mu_difference(&self) -> f64 {
        (self.max_multiplier - self.exact.max_floquet_modulus_variational).abs()
    }

    /// True when both verdicts are decisive: every largest modulus (ours and both of theirs)
    /// farther than [`MULTIPLIER_TOL`] from one.
    pub fn decisive(&self) -> bool {
        [
            self.max_multiplier,
            self.exact.max_floquet_modulus,
            self.exact.max_floquet_modulus_variational,
        ]
        .iter()
        .all(|m| (m - 1.0).abs() > MULTIPLIER_TOL)
    }
}

/// Our continuation's fold and grazing points against the exact fold and the closed form.
pub fn continuation_checks(
    ours: &Ours<'_>,
    branch: &Branch,
    reference: &Reference,
    locate_tol_rad_s: f64,
) -> Result<Vec<Check>, ValidationError> {
    let mut g = Group::new("peer: continuation");
    let fold = branch
        .upper_fold()
        .ok_or_else(|| ValidationError::Device("our branch has no upper fold".into()))?;
    let fold_rad_s = fold.param * TWO_PI;
    let exact = reference.exact_fold_rad_s()?;
    let why = "the event is located to its tolerance on the branch";
    g.add(
        "exact shooting: extended system P(y) = y, det(Phi - I) = 0",
        "fold frequency Omega (rad/s)",
        exact,
        fold_rad_s,
        Measure::Absolute,
        locate_tol_rad_s,
        why,
    );
    let m = &ours.device().mechanics;
    let osc = Oscillator {
        mass_kg: m.mass_kg,
        stiffness_n_per_m: m.stiffness_n_per_m,
        damping_n_s_per_m: m.damping_n_s_per_m,
    };
    let gap = ours
        .device()
        .stops
        .upper
        .as_ref()
        .ok_or_else(|| ValidationError::Device("the problem has an upper stop".into()))?
        .gap_m;
    let analytic = osc.grazing_rad_s(0.1 / m.mass_kg, gap);
    if analytic.len() != 2 {
        return Err(ValidationError::Device(format!(
            "the linear response reaches the gap at {} frequencies, not the two compared",
            analytic.len()
        )));
    }
    let grazing: Vec<f64> = branch.grazing_events().map(|e| e.param * TWO_PI).collect();
    for (i, w) in analytic.iter().enumerate() {
        let nearest = grazing
            .iter()
            .copied()
            .min_by(|a, b| (a - w).abs().total_cmp(&(b - w).abs()))
            .unwrap_or(f64::NAN);
        g.add(
            "closed form: F / |k - m w^2 + i d w| = gap",
            &format!(
                "{} grazing frequency Omega (rad/s)",
                if i == 0 { "lower" } else { "upper" }
            ),
            *w,
            nearest,
            Measure::Absolute,
            locate_tol_rad_s,
            why,
        );
    }
    Ok(g.into_checks())
}

//! A peer tool on a common problem: the one-sided spring oscillator
//! `m q'' + d q' + k q + kc max(q - gap, 0) = F cos(Omega t)` (m = 1 kg, k = 1 N/m, d = 0.03 N s/m,
//! kc = 100 N/m, gap = 1 m, F = 0.1 N) by NLvib-py's harmonic balance for H = 1 to 40 harmonics,
//! and by an exact (event-located, untruncated) shooting with scipy, both stored under
//! `data/references/nlvib/` with their provenance (`PROVENANCE.md` there: commits, commands,
//! columns and conventions).
//!
//! In our model the problem is a device with a linear upper stop and no transducer driven by
//! `m a(t)` with `a = sqrt(2) a_rms sin(2 pi f t + phi)`: `sqrt(2) a_rms = F / m` and the
//! cosine is the sine at drive phase `phi = pi/2`, so an orbit of theirs started at
//! `(q(0), q'(0))` is ours at that section phase. Frequencies here are `Omega` in rad/s, ours
//! `f = Omega / (2 pi)`.
//!
//! Compared:
//! * **The exact shooting, point by point** ([`exact_point_checks`]): from each stored orbit's
//!   initial state our shooting converges to the same orbit; its first-harmonic amplitude
//!   (`sqrt(Qc1^2 + Qs1^2)`, [`first_harmonic`] of x), its largest Floquet multiplier and its
//!   stability against theirs. A stability verdict counts as a disagreement only where both
//!   multipliers are farther from the unit circle than their accuracy (the reference's
//!   variational and difference multipliers agree to a few 1e-6; ours are good to 1e-8).
//! * **Our continuation** ([`continuation_checks`]): the branch from Omega = 0.5 up over the
//!   fold, down the overhang, across the grazing corner and up to 2.5 rad/s; its fold against
//!   the exact one (solved there as an extended system), its grazing points against the
//!   closed form ([`crate::physics::closed_forms::Oscillator::grazing_rad_s`]).
//! * **Harmonic balance** ([`hb_convergence`]): NLvib's fold frequency and first-harmonic
//!   amplitudes against ours at its own points (no interpolation of its branch) near Omega =
//!   1.1 to 1.5 on the resonant and overhanging parts. The differences are NLvib's harmonic
//!   truncation: they must shrink as H grows, down to the floor set by its sampled contact
//!   force (the AFT sampling floor of `nlvib_aft_check_H40.csv`).
//!
//! NLvib's own stability flag is a fold-parity flag, not a stability analysis, and is not
//! used as a verdict (the provenance explains why).

use crate::device::Device;
use crate::drive::Sine;
use crate::ode::Stats;
use crate::physics::closed_forms::Oscillator;
use crate::physics::harvester::{Harvester, State};
use crate::progress::Silent;
use crate::study::continuation::{continue_branch, first_orbit, Branch, ContinuationSettings};
use crate::study::orbit::{Forcing, Orbit, Parameter, Shooter, ShootingConfig};
use crate::validation::harmonics::first_harmonic;
use crate::validation::{Check, Group, Measure, ValidationError};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// The harmonic truncations NLvib-py was run with (the files `nlvib_hb_HNN.csv`).
pub const HARMONICS: [usize; 6] = [1, 3, 5, 10, 20, 40];

/// The frequencies (rad/s) near which the harmonic-balance amplitudes are compared.
pub const OMEGAS_RAD_S: [f64; 5] = [1.1, 1.2, 1.3, 1.4, 1.5];

/// The amplitude points compared at each H ([`hb_convergence`]): both parts of the branch at
/// each of [`OMEGAS_RAD_S`], except at H = 1, whose branch folds at 1.42 rad/s and so has no
/// point within 0.05 rad/s of 1.5 rad/s on either part. A comparison with fewer points at any H
/// fails ([`hb_checks`]).
pub const HB_POINTS: [(usize, usize); 6] = [(1, 8), (3, 10), (5, 10), (10, 10), (20, 10), (40, 10)];

mod reference;

pub use reference::*;

/// The problem's drive: `F / m = sqrt(2) a_rms` with `F = 0.1 N` on the unit mass, in g rms.
pub fn accel_rms_g(device: &Device) -> f64 {
    0.1 / device.mechanics.mass_kg / std::f64::consts::SQRT_2 / crate::G
}

/// Our model of the problem and its shooting settings.
pub struct Ours<'d> {
    device: &'d Device,
    model: Harvester<Sine>,
    accel_rms_g: f64,
}

impl<'d> Ours<'d> {
    /// The model of the problem's device (`data/validation/nlvib_sdof.toml`).
    pub fn new(device: &'d Device) -> Self {
        let a = accel_rms_g(device);
        Self {
            device,
            model: Harvester::new(device, Sine::from_rms_g(a, 0.1)),
            accel_rms_g: a,
        }
    }

    fn shooter(&self) -> Shooter<'_> {
        Shooter::new(&self.model, ShootingConfig::default())
    }

    fn forcing(&self, omega_rad_s: f64) -> Forcing {
        Forcing {
            freq_hz: omega_rad_s / TWO_PI,
            accel_rms_g: self.accel_rms_g,
        }
    }

    /// The first-harmonic amplitude of x over one period of an orbit (m).
    pub fn a1(&self, orbit: &Orbit) -> Result<f64, ValidationError> {
        Ok(first_harmonic(&self.shooter(), orbit, |y| y[0])
            .map_err(|e| orbit_err(orbit, e))?
            .norm())
    }

    /// Our orbit through a stored exact orbit: Newton from its state at the cosine's phase
    /// zero (our drive phase pi/2).
    pub fn through(&self, p: &ExactPoint) -> Result<Orbit, ValidationError> {
        let s = self.shooter();
        let mut stats = Stats::default();
        let o = s.solve(
            &self.forcing(p.omega_rad_s),
            Parameter::Frequency,
            std::f64::consts::FRAC_PI_2,
            State::new(p.x0_m, p.v0_m_s, 0.0, 0.0),
            &mut stats,
        )?;
        Ok(o)
    }

    /// Our branch from Omega = `from` to `to` (rad/s), started from rest, with parameter steps
    /// of at most `max_step_rad_s` and events located to `locate_tol_rad_s`.
    pub fn branch(
        &self,
        from: f64,
        to: f64,
        max_step_rad_s: f64,
        locate_tol_rad_s: f64,
    ) -> Result<Branch, ValidationError> {
        let mut settings =
            ContinuationSettings::frequency(from / TWO_PI, to / TWO_PI, max_step_rad_s / TWO_PI);
        settings.locate_tol = locate_tol_rad_s / TWO_PI;
        let s = self.shooter();
        let mut stats = Stats::default();
        let first = first_orbit(
            &s,
            &self.forcing(from),
            Parameter::Frequency,
            self.model.rest_state(),
            200,
            &mut stats,
        )?;
        Ok(continue_branch(&self.model, first, &settings, &Silent)?)
    }

    /// Our orbits at Omega on a branch, in branch order (m).
    pub fn orbits_at(
        &self,
        branch: &Branch,
        omega_rad_s: f64,
    ) -> Result<Vec<Orbit>, ValidationError> {
        let mut stats = Stats::default();
        Ok(branch.orbits_at(&self.shooter(), omega_rad_s / TWO_PI, &mut stats)?)
    }

    /// The device.
    pub fn device(&self) -> &Device {
        self.device
    }
}

fn orbit_err(orbit: &Orbit, e: crate::ode::SolverError) -> ValidationError {
    ValidationError::Orbit(crate::study::orbit::OrbitError::Solver {
        what: Parameter::Frequency.label(),
        param: orbit.forcing.freq_hz,
        source: e,
    })
}

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

/// One point of our branch, as the chapter plots and stores it.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchSample {
    /// Omega (rad/s).
    pub omega_rad_s: f64,
    /// First-harmonic amplitude of x (m).
    pub a1_amplitude_m: f64,
    /// Largest Floquet multiplier modulus.
    pub max_multiplier: f64,
    /// Every multiplier inside the unit circle.
    pub stable: bool,
    /// The orbit touches the stop.
    pub impacting: bool,
}

/// Every point of our branch with its first-harmonic amplitude.
pub fn branch_samples(
    ours: &Ours<'_>,
    branch: &Branch,
) -> Result<Vec<BranchSample>, ValidationError> {
    branch
        .points
        .iter()
        .map(|p| {
            let o = &p.orbit;
            Ok(BranchSample {
                omega_rad_s: o.forcing.freq_hz * TWO_PI,
                a1_amplitude_m: ours.a1(o)?,
                max_multiplier: o.max_multiplier_abs(),
                stable: o.is_stable(),
                impacting: o.is_impacting(),
            })
        })
        .collect()
}

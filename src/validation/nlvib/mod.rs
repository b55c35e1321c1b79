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
use crate::model::Model;
use crate::ode::Stats;
use crate::physics::harvester::Harvester;

/// The problem's state: one mass, no transducer.
type State = nalgebra::SVector<f64, 4>;
use crate::progress::Silent;
use crate::study::continuation::{continue_branch, first_orbit, Branch, ContinuationSettings};
use crate::study::orbit::{Forcing, Orbit, Parameter, Shooter, ShootingOptions};
use crate::validation::harmonics::first_harmonic;
use crate::validation::ValidationError;

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// The harmonic truncations NLvib-py was run with (the files `nlvib_hb_HNN.csv`).
pub const HARMONICS: [usize; 6] = [1, 3, 5, 10, 20, 40];

mod exact;
mod hb;
mod reference;

pub use exact::{
    continuation_checks, exact_point_checks, PointComparison, EXACT_A1_TOL, EXACT_ORBITS,
    MULTIPLIER_TOL,
};
pub use hb::{hb_checks, hb_convergence, HbComparison, Part, HB_POINTS, OMEGAS_RAD_S};
pub use reference::*;

/// The problem's drive: `F / m = sqrt(2) a_rms` with `F = 0.1 N` on the unit mass, in g rms.
pub fn accel_rms_g(device: &Device) -> f64 {
    0.1 / device.mechanics.mass_kg / std::f64::consts::SQRT_2 / crate::G
}

/// Our model of the problem and its shooting settings.
pub struct Ours<'d> {
    device: &'d Device,
    model: Harvester<4>,
    accel_rms_g: f64,
}

impl<'d> Ours<'d> {
    /// The model of the problem's device (`data/validation/nlvib_sdof.toml`).
    pub fn new(device: &'d Device) -> Result<Self, ValidationError> {
        let a = accel_rms_g(device);
        Ok(Self {
            device,
            model: Harvester::<4>::new(device)
                .map_err(|e| ValidationError::Device(e.to_string()))?,
            accel_rms_g: a,
        })
    }

    fn shooter(&self) -> Shooter<'_, Harvester<4>, 4> {
        Shooter::new(&self.model, ShootingOptions::default())
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

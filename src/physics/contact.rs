//! The end-stop contact of eqs 1-2: which stop, the contact modes the integrator switches
//! between, and the spring law of the stop (Hertz, eq 6, or linear, eq 19).
//!
//! For |x| > xmax the penetration is delta = |x| - xmax (eq 2) and the stop pushes back with
//! F_im = sign(x) (F_k(delta) + b_im d(delta)/dt) (eq 1).

use crate::physics::hertz::HertzLine;

/// Which stop: +1 the one at x = +xmax, -1 the one at x = -xmax.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Side {
    /// The stop at x = +xmax.
    Upper,
    /// The stop at x = -xmax.
    Lower,
}

impl Side {
    /// +1 or -1.
    #[inline]
    pub fn sign(self) -> f64 {
        match self {
            Side::Upper => 1.0,
            Side::Lower => -1.0,
        }
    }
}

/// Contact mode of the proof mass.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Mode {
    /// |x| <= xmax, no contact force.
    Free,
    /// In contact with a stop, the contact force acts.
    Contact(Side),
    /// Past the stop but the (tension-free) contact force is clipped to zero.
    Clipped(Side),
}

impl Mode {
    /// True while the mass is past a stop (delta > 0).
    pub fn in_contact(self) -> bool {
        !matches!(self, Mode::Free)
    }
}

/// The spring law of the stop, evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    /// Hertz line contact, eq 6.
    Hertz(HertzLine),
    /// Linear spring k_im (N/m), eq 19.
    Linear(f64),
}

impl ContactLaw {
    /// Spring force for a penetration delta >= 0 (N); zero for delta <= 0.
    #[inline]
    pub fn force(&self, delta_m: f64) -> f64 {
        if delta_m <= 0.0 {
            return 0.0;
        }
        match self {
            ContactLaw::Hertz(h) => h.force_of_delta(delta_m),
            ContactLaw::Linear(k) => k * delta_m,
        }
    }

    /// Spring stiffness dF/d(delta) at penetration delta >= 0 (N/m); zero for delta <= 0.
    #[inline]
    pub fn stiffness(&self, delta_m: f64) -> f64 {
        if delta_m <= 0.0 {
            return 0.0;
        }
        match self {
            ContactLaw::Hertz(h) => h.stiffness_of_delta(delta_m),
            ContactLaw::Linear(k) => *k,
        }
    }

    /// Elastic energy stored at penetration delta (J).
    pub fn energy(&self, delta_m: f64) -> f64 {
        if delta_m <= 0.0 {
            return 0.0;
        }
        match self {
            ContactLaw::Hertz(h) => h.energy_of_delta(delta_m),
            ContactLaw::Linear(k) => 0.5 * k * delta_m * delta_m,
        }
    }
}

//! The end-stop contact of eqs 1-2, generalised to any stop of [`crate::device::stops`]: which
//! stop, and each stop's force law, in plain physical parameters (a device builds them from its
//! stops' descriptions). The contact modes the integrator switches between are
//! [`crate::model::Contact`]'s.
//!
//! For a compliant stop on side `s` (`s = +1` upper, `-1` lower) the penetration is
//! `delta = s x - gap` (eq 2) and, while `delta > 0`, the stop pushes back with
//! `F_im = s B` (eq 1), where the bracket `B` is the spring force plus the contact damping:
//!
//! * eq 1's viscous damper: `B = F_k(delta) + b_im d(delta)/dt`;
//! * Hunt-Crossley: `B = F_k(delta) (1 + alpha d(delta)/dt)` with `F_k = K delta^n`.
//!
//! With a tension-free stop (always for Hunt-Crossley) the bracket is clipped at zero: the
//! mass is then [`Contact::Clipped`](crate::model::Contact::Clipped), past the stop but free
//! of its force.
//!
//! A rigid stop (restitution) has no contact phase: when the mass reaches it, its velocity is
//! reset to `-e` times itself (Newton's law), and where the rebounds would accumulate the mass
//! rests on the stop ([`Contact::Resting`](crate::model::Contact::Resting)) until the net
//! force pulls it away (see [`crate::physics::harvester`]).

use crate::laws::hertz::HertzLine;

/// Which stop: +1 the one at x = +gap, -1 the one at x = -gap. A device file spells it
/// `upper` or `lower`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Side {
    /// The stop at x = +gap.
    Upper,
    /// The stop at x = -gap.
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

    /// Both sides, upper first.
    pub const BOTH: [Side; 2] = [Side::Upper, Side::Lower];
}

/// The spring law of a compliant stop, evaluated.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactLaw {
    /// Hertz line contact, eq 6.
    Hertz(HertzLine),
    /// Linear spring k (N/m): eq 19, or a plain spring.
    Linear(f64),
    /// Power law `K delta^n` (Hertz point contact: n = 3/2).
    Power {
        /// K (N/m^n).
        k: f64,
        /// The exponent n.
        n: f64,
    },
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
            ContactLaw::Power { k, n } => k * power(delta_m, *n),
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
            ContactLaw::Power { k, n } => k * n * power(delta_m, n - 1.0),
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
            ContactLaw::Power { k, n } => k * delta_m.powf(n + 1.0) / (n + 1.0),
        }
    }
}

/// `delta^n` for `delta > 0`, Hertz's `n = 3/2` (and its stiffness's `1/2`) by a square root:
/// the right-hand side of a contact phase evaluates the force (and the variational equations
/// its stiffness) at every stage of every step, and a general power costs several times a
/// square root. A correctly rounded square root and one product differ from the power by at
/// most about one unit in the last place.
#[inline]
fn power(delta_m: f64, n: f64) -> f64 {
    if n == 1.5 {
        delta_m * delta_m.sqrt()
    } else if n == 0.5 {
        delta_m.sqrt()
    } else {
        delta_m.powf(n)
    }
}

/// How a compliant stop dissipates while in contact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ContactDamping {
    /// Eq 1's viscous damper b_im (N s/m).
    Viscous(f64),
    /// Hunt-Crossley's `alpha` (s/m): the damping force is `alpha F_k d(delta)/dt`.
    HuntCrossley(f64),
}

/// One stop of the model, evaluated from its description.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StopModel {
    /// A stop with a contact phase.
    Compliant {
        /// Gap (m).
        gap: f64,
        /// Spring law.
        law: ContactLaw,
        /// Contact damping.
        damping: ContactDamping,
        /// Clip the bracket at zero.
        tension_free: bool,
    },
    /// An instantaneous impact with restitution.
    Rigid {
        /// Gap (m).
        gap: f64,
        /// Coefficient of restitution e.
        restitution: f64,
    },
}

impl StopModel {
    /// The gap (m).
    #[inline(always)]
    pub fn gap(&self) -> f64 {
        match *self {
            StopModel::Compliant { gap, .. } | StopModel::Rigid { gap, .. } => gap,
        }
    }

    /// The bracket `B` of eq 1 (see the module docs) at penetration `delta` and penetration
    /// rate `delta_dot` (N); zero for a rigid stop.
    #[inline(always)]
    pub fn bracket(&self, delta: f64, delta_dot: f64) -> f64 {
        match *self {
            StopModel::Compliant {
                law,
                damping: ContactDamping::Viscous(b),
                ..
            } => law.force(delta) + b * delta_dot,
            StopModel::Compliant {
                law,
                damping: ContactDamping::HuntCrossley(alpha),
                ..
            } => {
                let f = law.force(delta);
                f + alpha * f * delta_dot
            }
            StopModel::Rigid { .. } => 0.0,
        }
    }

    /// The bracket's derivatives with respect to `delta` and `delta_dot`.
    #[inline]
    pub fn bracket_gradient(&self, delta: f64, delta_dot: f64) -> (f64, f64) {
        match *self {
            StopModel::Compliant {
                law,
                damping: ContactDamping::Viscous(b),
                ..
            } => (law.stiffness(delta), b),
            StopModel::Compliant {
                law,
                damping: ContactDamping::HuntCrossley(alpha),
                ..
            } => (
                law.stiffness(delta) * (1.0 + alpha * delta_dot),
                alpha * law.force(delta),
            ),
            StopModel::Rigid { .. } => (0.0, 0.0),
        }
    }

    /// Power dissipated by the contact damping at `delta`, `delta_dot` (W).
    #[inline]
    pub fn damping_power(&self, delta: f64, delta_dot: f64) -> f64 {
        match *self {
            StopModel::Compliant {
                damping: ContactDamping::Viscous(b),
                ..
            } => b * delta_dot * delta_dot,
            StopModel::Compliant {
                law,
                damping: ContactDamping::HuntCrossley(alpha),
                ..
            } => alpha * law.force(delta) * delta_dot * delta_dot,
            StopModel::Rigid { .. } => 0.0,
        }
    }

    /// The elastic energy of the contact at `delta` (J).
    pub fn energy(&self, delta: f64) -> f64 {
        match self {
            StopModel::Compliant { law, .. } => law.energy(delta),
            StopModel::Rigid { .. } => 0.0,
        }
    }

    /// True when the bracket is clipped at zero.
    #[inline(always)]
    pub fn tension_free(&self) -> bool {
        matches!(
            self,
            StopModel::Compliant {
                tension_free: true,
                ..
            }
        )
    }

    /// The largest stiffness of the contact over penetrations up to `delta_max` (N/m), for
    /// time scales: the spring's stiffness there (the laws stiffen with penetration).
    pub fn stiffness_at(&self, delta_max: f64) -> f64 {
        match self {
            StopModel::Compliant { law, .. } => law.stiffness(delta_max),
            StopModel::Rigid { .. } => 0.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Hertz's powers by square roots agree with the general power to a few units in the last
    /// place (each side rounds at most twice: 4 ulp relative, 1e-15, bounds both) over the
    /// penetrations a stop sees, from 1e-12 m to 1 m.
    #[test]
    fn hertz_powers_by_square_roots_match_the_general_power() {
        for i in 0..=1200 {
            let d = 10f64.powf(-12.0 + f64::from(i) / 100.0);
            for n in [1.5, 0.5] {
                let rel = (power(d, n) / d.powf(n) - 1.0).abs();
                assert!(rel <= 4.0 * f64::EPSILON, "d {d}, n {n}: {rel:e}");
            }
            assert_eq!(power(d, 2.0), d.powf(2.0));
        }
    }
}

//! Closed forms of the interface circuits for a piezoelectric element whose displacement is
//! imposed, `x = u_M sin(w t)` (or the coupling weak enough that the circuit does not change
//! it), with a storage capacitor large enough that its voltage `V` is constant over a period.
//! Each counts the charge the element delivers per half period. `V_F` is one diode's forward
//! drop (two conduct in series).
//!
//! * Standard bridge (Ottman et al., IEEE Trans. Power Electron. 17 (2002) 669; Shu and Lien,
//!   Smart Mater. Struct. 15 (2006) 1499): each half period the element's voltage swings from
//!   `-(V + 2 V_F)` to `V + 2 V_F` before the bridge conducts, so
//!   `V / R = (2 w / pi) (theta u_M - Cp (V + 2 V_F))`, i.e.
//!   `V = R w (theta u_M - 2 Cp V_F) / (R Cp w + pi / 2)`; without drops the optimal load is
//!   `pi / (2 w Cp)` and `P_max = theta^2 w u_M^2 / (2 pi Cp)`.
//! * Parallel SSHI (Guyomar et al., IEEE Trans. Ultrason. Ferroelectr. Freq. Control 52 (2005)
//!   584): the inversion leaves `-gamma (V + 2 V_F)`, so the swing is `(1 - gamma) (V + 2 V_F)`:
//!   `V = R w (2 theta u_M - 2 (1 - gamma) Cp V_F) / (pi + R Cp w (1 - gamma))`; without drops
//!   the optimal load is `pi / (w Cp (1 - gamma))` and `P_max = theta^2 w u_M^2 / (pi Cp (1 -
//!   gamma))`.
//! * Series SSHI (Lefeuvre et al., Sens. Actuators A 126 (2006) 405, with the same counting):
//!   the element is open between extrema and its voltage at an extremum, `V_M`, rings through
//!   the bridge to `V + 2 V_F - gamma (V_M - V - 2 V_F)`; the steady `V_M` and the charge moved,
//!   `Cp (1 + gamma) (V_M - V - 2 V_F)`, give
//!   `V = 2 R w (1 + gamma) (theta u_M - 2 Cp V_F) / (pi (1 - gamma) + 2 R Cp w (1 + gamma))`;
//!   without drops `P_max = (1 + gamma) theta^2 w u_M^2 / (2 pi Cp (1 - gamma))`.
//! * SECE (Lefeuvre et al. 2006, as above): the open element reaches `2 theta u_M / Cp` at each
//!   extremum, where `Cp V^2 / 2` moves to the storage with efficiency `eta`:
//!   `P = 2 eta theta^2 w u_M^2 / (pi Cp)` whatever the load.
//!
//! # Strong coupling ([`standard_coupled`])
//! With strong coupling the bridge changes the motion. Shu and Lien (2006) analyse this case by
//! keeping the displacement's fundamental; the form here is derived the same way (it is not
//! copied from their paper). Over a half period the element's voltage is the open-circuit ramp
//! until the bridge conducts at the phase `phi_1`, `cos phi_1 = 1 - 2 Cp V / (theta u_M)`
//! (`V` the clamped voltage, `V + 2 V_F` with drops), then constant. Its fundamental puts on the
//! mass an equivalent damping `c_e = (4 theta V / (pi w u_M)) (1 - Cp V / (theta u_M))` and an
//! equivalent stiffness `k_e = theta^2 (phi_1 - sin phi_1 cos phi_1) / (pi Cp)` (zero short,
//! `theta^2 / Cp` open), so that
//! `u_M = m A / |k + k_e - m w^2 + i w (b + c_e)|`, solved by fixed-point iteration together with
//! the charge balance above. Without drops, `c_e = 2 theta^2 R / (R Cp w + pi / 2)^2`.

use std::f64::consts::PI;

/// The piezoelectric element and the drive frequency of a closed form.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Element {
    /// theta (N/V).
    pub theta: f64,
    /// Cp (F).
    pub cp: f64,
    /// Angular frequency w (rad/s).
    pub w: f64,
    /// One diode's forward drop V_F (V).
    pub vf: f64,
}

impl Element {
    /// DC voltage of the standard bridge at displacement amplitude `u` (m) and load `r` (ohm).
    pub fn standard_vdc(&self, u: f64, r: f64) -> f64 {
        (r * self.w * (self.theta * u - 2.0 * self.cp * self.vf)
            / (r * self.cp * self.w + 0.5 * PI))
            .max(0.0)
    }

    /// DC voltage of parallel SSHI.
    pub fn parallel_sshi_vdc(&self, u: f64, r: f64, gamma: f64) -> f64 {
        let g1 = 1.0 - gamma;
        (r * self.w * (2.0 * self.theta * u - 2.0 * g1 * self.cp * self.vf)
            / (PI + r * self.cp * self.w * g1))
            .max(0.0)
    }

    /// DC voltage of series SSHI.
    pub fn series_sshi_vdc(&self, u: f64, r: f64, gamma: f64) -> f64 {
        (2.0 * r * self.w * (1.0 + gamma) * (self.theta * u - 2.0 * self.cp * self.vf)
            / (PI * (1.0 - gamma) + 2.0 * r * self.cp * self.w * (1.0 + gamma)))
            .max(0.0)
    }

    /// Power of SECE with efficiency `eta` (W), whatever the load.
    pub fn sece_power(&self, u: f64, eta: f64) -> f64 {
        2.0 * eta * self.theta * self.theta * self.w * u * u / (PI * self.cp)
    }

    /// The standard bridge's optimal load without drops, `pi / (2 w Cp)` (ohm).
    pub fn standard_optimal_load(&self) -> f64 {
        PI / (2.0 * self.w * self.cp)
    }

    /// The standard bridge's largest power without drops, `theta^2 w u^2 / (2 pi Cp)` (W).
    pub fn standard_max_power(&self, u: f64) -> f64 {
        self.theta * self.theta * self.w * u * u / (2.0 * PI * self.cp)
    }

    /// Parallel SSHI's optimal load without drops, `pi / (w Cp (1 - gamma))` (ohm).
    pub fn parallel_sshi_optimal_load(&self, gamma: f64) -> f64 {
        PI / (self.w * self.cp * (1.0 - gamma))
    }

    /// Series SSHI's optimal load without drops, `pi (1 - gamma) / (2 w Cp (1 + gamma))`.
    pub fn series_sshi_optimal_load(&self, gamma: f64) -> f64 {
        PI * (1.0 - gamma) / (2.0 * self.w * self.cp * (1.0 + gamma))
    }
}

/// The standard bridge with the coupling kept (see the module docs): the displacement
/// amplitude (m) and DC voltage (V) of a mass `m` on a suspension `k` with damping `b`, driven
/// by a base acceleration of amplitude `a` (m/s^2), for load `r`.
#[allow(clippy::too_many_arguments)]
pub fn standard_coupled(e: &Element, m: f64, k: f64, b: f64, a: f64, r: f64) -> (f64, f64) {
    let w = e.w;
    // Start from the short-circuit response and iterate u -> u(V(u)).
    let mut u = m * a / ((k - m * w * w).hypot(w * b));
    let mut v = 0.0;
    for _ in 0..500 {
        v = e.standard_vdc(u, r);
        let vc = v + 2.0 * e.vf;
        let oc = e.theta * u / e.cp;
        let (ce, ke) = if vc >= oc {
            (0.0, e.theta * e.theta / e.cp)
        } else {
            let c1 = 1.0 - 2.0 * vc / oc;
            let phi1 = c1.clamp(-1.0, 1.0).acos();
            (
                4.0 * e.theta * vc / (PI * w * u) * (1.0 - vc / oc),
                e.theta * e.theta * (phi1 - phi1.sin() * c1) / (PI * e.cp),
            )
        };
        let next = m * a / ((k + ke - m * w * w).hypot(w * (b + ce)));
        // Under-relaxed: the map can overshoot near resonance with strong coupling.
        let un = 0.5 * (u + next);
        if (un - u).abs() <= 1e-13 * u {
            u = un;
            break;
        }
        u = un;
    }
    (u, v)
}

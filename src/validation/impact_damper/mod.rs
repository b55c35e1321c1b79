//! The impact damper of Masri & Caughey ("On the stability of the impact damper", J. Appl.
//! Mech. 33(3), 1966, 586-592): its symmetric steady motion with two equispaced impacts per
//! cycle in closed form, and that motion's stability, against our shooting ([`checks`]).
//!
//! # The system
//! A primary mass `M` on a spring `K` and a damper `C` to the frame, under a force
//! `F0 sin(w t + tau)`; a particle `m` free inside a clearance of total width `d` in the
//! primary, meeting its walls where `z - x = +-d/2` (`x` the primary's, `z` the particle's
//! displacement) with restitution `e`, momentum conserved at each impact.
//!
//! # The base-excited device is this system
//! Our model drives every mass by the inertial force `m_i a(t)` in coordinates relative to the
//! frame, `a(t) = A sin(theta)`, `theta = w t + phase` the drive's phase
//! ([`crate::physics::harvester::masses`]): the frame moves by `y_b` with `y_b'' = -a`, so
//! `y_b = (A / w^2) sin(theta)`. In absolute coordinates `X = x_rel + y_b`, `Z = z_rel + y_b`
//! the primary obeys `M X'' + C X' + K X = K y_b + C y_b'` and the particle `m Z'' = 0`: the
//! harmonic force of amplitude `F0 = (A / w^2) sqrt(K^2 + (C w)^2)` at phase
//! `tau = theta + beta`, `beta = atan2(C w, K)`, on the primary only, and no force on the
//! free particle. The gap condition is on `Z - X = z_rel - x_rel`, the same in both frames.
//! So the drive phase at the upper impact is `theta_i = tau - beta`.
//!
//! # The closed form (derived here from Masri & Caughey's conditions, not copied)
//! The published expressions were not at hand; the closed form below is DERIVED from the same
//! assumptions as Masri & Caughey's: the flow between impacts is linear and exact, the motion
//! is symmetric, `s(t + T/2) = -s(t)` for the state `s = (X, X', Z, Z')`, `T = 2 pi / w`, with
//! one impact on the upper wall at `t = 0` and one on the lower at `t = T/2`, and each impact
//! conserves momentum and reverses the relative velocity times `e`.
//!
//! Let `P = M (v+ - v-)` be the impulse the particle gives the primary at `t = 0`, `v-+` and
//! `u-+` the primary's and the particle's velocities before and after it.
//! 1. Symmetry gives `u- = -u+` (the particle's velocity does not change in flight), so
//!    momentum gives `P = -2 m u+`.
//! 2. The particle flies from `z0` at `t = 0` to `-z0` at `T/2`: `z0 = -u+ T/4 = P pi / (4 m w)`;
//!    the gap gives the primary's position at impact, `x0 = z0 - d/2`.
//! 3. Restitution, `u+ - v+ = -e (u- - v-)`, gives `(1 - e) u+ = (1 + e) v+ - e P / M`.
//! 4. The primary between impacts: `s_p(t) = p(t) + Phi(t) (s_p(0+) - p(0))`, with `p` the
//!    harmonic steady state `X_a sin(w t + phi)`, `X_a = F0 / |K - M w^2 + i C w|`,
//!    `phi = tau - psi`, `psi = arg(K - M w^2 + i C w)`, and `Phi` the free oscillator's flow.
//!    Symmetry with the velocity jump `-P/M` at `T/2` gives
//!    `(Phi(T/2) + I)(s_p(0+) - p(0)) = (0, P/M)`, so `s_p(0+) = p(0) + (P/M) g`,
//!    `g = (Phi(T/2) + I)^-1 (0, 1)` (the steady response to alternating impulses; without
//!    damping `g = (-tan(pi w_n / (2 w)) / (2 w_n), 1/2)`, Masri & Caughey's tangent).
//! 5. Hence `X_a sin(phi) = alpha P - d/2` and `X_a cos(phi) = beta_p P` with
//!    `alpha = pi / (4 m w) - g_1 / M` and
//!    `beta_p = ((e / M - (1 - e) / (2 m)) / (1 + e) - g_2 / M) / w`, whose squares sum to
//!    the quadratic `(alpha^2 + beta_p^2) P^2 - alpha d P + d^2/4 - X_a^2 = 0`: two motions
//!    at most (`P > 0`), their impact phase from `phi = atan2(alpha P - d/2, beta_p P)`.
//!
//! A root is a motion of the system only if the particle stays inside the clearance in flight
//! and strikes the wall it is moving towards; [`SymmetricOrbit::admissible`] says so (checked
//! on a grid of the half period).
//!
//! # Its stability (derived, Masri & Caughey's perturbation of the impacts)
//! A perturbed motion is followed through the two impacts of a period: the monodromy from a
//! quarter period after the upper impact is
//! `Phi4(T/4) S_lower Phi4(T/2) S_upper Phi4(T/4)`, with `Phi4` the linear flow of the state
//! (the primary's `Phi` and the particle's free flight) and `S` the saltation matrix of each
//! impact, `S = G + (f+ - G f-) n^T / (n . f-)`: `G` the impact law's derivative, `n` the
//! wall's normal in the state, `f-+` the vector field before and after. Every factor is
//! explicit on the closed-form orbit; the motion is stable when the four eigenvalues lie
//! inside the unit circle, and the condition changes sign where the largest modulus crosses 1.

pub mod checks;

use nalgebra::{Complex, Matrix2, Matrix4, Vector2, Vector4};
use std::f64::consts::PI;

use crate::device::{Device, StopLaw, Transducer};
use crate::validation::ValidationError;

/// The impact damper's parameters (SI).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ImpactDamper {
    /// The primary's mass M (kg).
    pub primary_kg: f64,
    /// Its spring K (N/m).
    pub stiffness_n_per_m: f64,
    /// Its damper C (N s/m).
    pub damping_n_s_per_m: f64,
    /// The particle's mass m (kg).
    pub particle_kg: f64,
    /// The total clearance d (m): the particle moves between `-d/2` and `+d/2`.
    pub clearance_m: f64,
    /// The coefficient of restitution e.
    pub restitution: f64,
}

/// One symmetric motion with two equispaced impacts per cycle, in absolute coordinates, time
/// from the impact on the upper wall.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SymmetricOrbit {
    /// The angular frequency w (rad/s).
    pub omega_rad_s: f64,
    /// The force's amplitude F0 (N).
    pub force_n: f64,
    /// The force's phase at the upper impact, tau (rad, in [0, 2 pi)).
    pub force_phase_rad: f64,
    /// The impulse on the primary at the upper impact, P (N s).
    pub impulse_n_s: f64,
    /// The primary's position at the impact, x0 (m).
    pub x0_m: f64,
    /// The primary's velocity before the impact (m/s).
    pub v_before_m_s: f64,
    /// And after it (m/s).
    pub v_after_m_s: f64,
    /// The particle's position at the impact, z0 = x0 + d/2 (m).
    pub z0_m: f64,
    /// The particle's velocity after the impact, u+ (m/s); before it, -u+.
    pub u_after_m_s: f64,
    /// The harmonic part: amplitude X_a (m) and phase phi = tau - psi (rad).
    harmonic: (f64, f64),
    /// The particle stays inside the clearance in flight and meets each wall approaching it.
    pub admissible: bool,
}

impl ImpactDamper {
    /// The impact damper of a device: two masses, the first on a spring and a damper to the
    /// frame, the second joined to it only by an upper and a lower rigid stop of equal gap and
    /// restitution, no transducer.
    pub fn of(device: &Device) -> Result<Self, ValidationError> {
        let bad = |why: &str| ValidationError::Device(format!("{}: {why}", device.name));
        let m = device
            .masses
            .as_ref()
            .ok_or_else(|| bad("the impact damper needs [[masses]]"))?;
        if m.bodies.len() != 2 || device.transducer != Transducer::None {
            return Err(bad("the impact damper has two masses and no transducer"));
        }
        let frame_link = |links: &[crate::device::masses::Link]| -> Result<f64, ValidationError> {
            match links {
                [l] if l.mass == 0 && l.other.is_none() => Ok(l.value),
                [] => Ok(0.0),
                _ => Err(bad("only the primary (mass 0) is linked to the frame")),
            }
        };
        let stiffness = frame_link(&m.springs)?;
        let damping = frame_link(&m.dampers)?;
        let [a, b] = m.stops.as_slice() else {
            return Err(bad("the particle is held by exactly two stops"));
        };
        let pair = |s: &crate::device::masses::MassStop| {
            (s.mass, s.other) == (1, Some(0)) || (s.mass, s.other) == (0, Some(1))
        };
        let e_of = |s: &crate::device::masses::MassStop| match s.stop.law {
            StopLaw::Restitution { coefficient } => Some(coefficient),
            _ => None,
        };
        if !pair(a)
            || !pair(b)
            || a.side == b.side
            || a.stop.gap_m != b.stop.gap_m
            || e_of(a).is_none()
            || e_of(a) != e_of(b)
        {
            return Err(bad(
                "the two stops join the masses on opposite sides with one gap and one restitution",
            ));
        }
        let out = Self {
            primary_kg: m.bodies[0].mass_kg,
            stiffness_n_per_m: stiffness,
            damping_n_s_per_m: damping,
            particle_kg: m.bodies[1].mass_kg,
            clearance_m: 2.0 * a.stop.gap_m,
            restitution: e_of(a).unwrap_or(0.0),
        };
        if out.damping_ratio() >= 1.0 || stiffness <= 0.0 {
            return Err(bad("the primary is an underdamped oscillator"));
        }
        Ok(out)
    }

    fn natural_rad_s(&self) -> f64 {
        (self.stiffness_n_per_m / self.primary_kg).sqrt()
    }

    fn damping_ratio(&self) -> f64 {
        self.damping_n_s_per_m / (2.0 * (self.stiffness_n_per_m * self.primary_kg).sqrt())
    }

    /// The free primary's flow over `t` (s): `(x, v)(t) = Phi(t) (x, v)(0)`.
    pub fn free_flow(&self, t: f64) -> Matrix2<f64> {
        let wn = self.natural_rad_s();
        let sigma = self.damping_ratio() * wn;
        let wd = wn * (1.0 - self.damping_ratio().powi(2)).sqrt();
        let (s, c) = (wd * t).sin_cos();
        let k = (-sigma * t).exp();
        k * Matrix2::new(
            c + sigma / wd * s,
            s / wd,
            -wn * wn / wd * s,
            c - sigma / wd * s,
        )
    }

    /// The flow of the whole state `(X, X', Z, Z')` over `t` with the force off.
    fn free_flow4(&self, t: f64) -> Matrix4<f64> {
        let p = self.free_flow(t);
        let mut f = Matrix4::identity();
        f.fixed_view_mut::<2, 2>(0, 0).copy_from(&p);
        f[(2, 3)] = t;
        f
    }

    /// The force amplitude F0 (N) and its phase lead beta (rad) over the drive of a base
    /// acceleration of peak `accel_m_s2` at `omega_rad_s` (see the module docs).
    pub fn base_force(&self, accel_m_s2: f64, omega_rad_s: f64) -> (f64, f64) {
        let (k, cw) = (self.stiffness_n_per_m, self.damping_n_s_per_m * omega_rad_s);
        (accel_m_s2 / omega_rad_s.powi(2) * k.hypot(cw), cw.atan2(k))
    }

    /// The symmetric motions under `F0 sin(w t + tau)` (at most two, the larger impulse
    /// first): the roots with `P > 0` of the quadratic of the module docs.
    pub fn symmetric_orbits(&self, omega_rad_s: f64, force_n: f64) -> Vec<SymmetricOrbit> {
        let (mm, m, d, e, w) = (
            self.primary_kg,
            self.particle_kg,
            self.clearance_m,
            self.restitution,
            omega_rad_s,
        );
        let half = PI / w;
        let g = (self.free_flow(half) + Matrix2::identity())
            .lu()
            .solve(&Vector2::new(0.0, 1.0));
        let Some(g) = g else {
            return Vec::new();
        };
        let z = Complex::new(
            self.stiffness_n_per_m - mm * w * w,
            self.damping_n_s_per_m * w,
        );
        let (xa, psi) = (force_n / z.norm(), z.arg());
        let alpha = PI / (4.0 * m * w) - g[0] / mm;
        let beta = ((e / mm - (1.0 - e) / (2.0 * m)) / (1.0 + e) - g[1] / mm) / w;
        let a2 = alpha * alpha + beta * beta;
        let disc = (0.5 * alpha * d).powi(2) - a2 * (0.25 * d * d - xa * xa);
        if disc < 0.0 {
            return Vec::new();
        }
        [1.0, -1.0]
            .iter()
            .map(|sign| (0.5 * alpha * d + sign * disc.sqrt()) / a2)
            .filter(|p| *p > 0.0)
            .map(|p| {
                let phi = (alpha * p - 0.5 * d).atan2(beta * p);
                let u_after = -p / (2.0 * m);
                let z0 = p * PI / (4.0 * m * w);
                let v_after = xa * w * phi.cos() + p / mm * g[1];
                let mut o = SymmetricOrbit {
                    omega_rad_s: w,
                    force_n,
                    force_phase_rad: (phi + psi).rem_euclid(2.0 * PI),
                    impulse_n_s: p,
                    x0_m: z0 - 0.5 * d,
                    v_before_m_s: v_after - p / mm,
                    v_after_m_s: v_after,
                    z0_m: z0,
                    u_after_m_s: u_after,
                    harmonic: (xa, phi),
                    admissible: false,
                };
                o.admissible = self.admissible(&o);
                o
            })
            .collect()
    }

    /// The absolute state `(X, X', Z, Z')` of `orbit` at `t` (s) after its upper impact
    /// (right after the impact at multiples of the period; symmetric beyond half a period).
    pub fn state_at(&self, orbit: &SymmetricOrbit, t: f64) -> Vector4<f64> {
        let w = orbit.omega_rad_s;
        let period = 2.0 * PI / w;
        let t = t.rem_euclid(period);
        if t >= 0.5 * period {
            return -self.state_at(orbit, t - 0.5 * period);
        }
        let (xa, phi) = orbit.harmonic;
        let p = |t: f64| {
            let (s, c) = (w * t + phi).sin_cos();
            Vector2::new(xa * s, xa * w * c)
        };
        let start = Vector2::new(orbit.x0_m, orbit.v_after_m_s);
        let x = p(t) + self.free_flow(t) * (start - p(0.0));
        Vector4::new(
            x[0],
            x[1],
            orbit.z0_m + orbit.u_after_m_s * t,
            orbit.u_after_m_s,
        )
    }

    /// Inside the clearance in flight (on 1024 points of the half period, 1e-12 of d of room
    /// at the ends), approaching each wall at its impact.
    fn admissible(&self, o: &SymmetricOrbit) -> bool {
        let half = PI / o.omega_rad_s;
        let approach = -o.u_after_m_s - o.v_before_m_s;
        let n = 1024;
        approach > 0.0
            && (1..n).all(|k| {
                let s = self.state_at(o, half * k as f64 / n as f64);
                (s[2] - s[0]).abs() < 0.5 * self.clearance_m * (1.0 - 1e-12)
            })
    }

    /// The Floquet multipliers of `orbit` from the saltation matrices of its two impacts
    /// (module docs), largest modulus first.
    pub fn multipliers(&self, orbit: &SymmetricOrbit) -> Vec<Complex<f64>> {
        let (mm, m, e) = (self.primary_kg, self.particle_kg, self.restitution);
        let w = orbit.omega_rad_s;
        let period = 2.0 * PI / w;
        let k = (1.0 + e) / (mm + m);
        let mut g = Matrix4::identity();
        g[(1, 1)] = 1.0 - k * m;
        g[(1, 3)] = k * m;
        g[(3, 1)] = k * mm;
        g[(3, 3)] = 1.0 - k * mm;
        let field = |s: &Vector4<f64>, t: f64| {
            let f = orbit.force_n * (w * t + orbit.force_phase_rad).sin();
            let a = (f - self.damping_n_s_per_m * s[1] - self.stiffness_n_per_m * s[0]) / mm;
            Vector4::new(s[1], a, s[3], 0.0)
        };
        let saltation = |before: Vector4<f64>, after: Vector4<f64>, t: f64, n: Vector4<f64>| {
            let (fb, fa) = (field(&before, t), field(&after, t));
            g + (fa - g * fb) * n.transpose() / n.dot(&fb)
        };
        let before = Vector4::new(
            orbit.x0_m,
            orbit.v_before_m_s,
            orbit.z0_m,
            -orbit.u_after_m_s,
        );
        let after = self.state_at(orbit, 0.0);
        let upper = saltation(before, after, 0.0, Vector4::new(-1.0, 0.0, 1.0, 0.0));
        let lower = saltation(
            -before,
            -after,
            0.5 * period,
            Vector4::new(1.0, 0.0, -1.0, 0.0),
        );
        let quarter = self.free_flow4(0.25 * period);
        let mono = quarter * lower * self.free_flow4(0.5 * period) * upper * quarter;
        let mut mu: Vec<Complex<f64>> = mono.complex_eigenvalues().iter().copied().collect();
        mu.sort_by(|a, b| b.norm().total_cmp(&a.norm()));
        mu
    }

    /// The largest modulus of [`ImpactDamper::multipliers`].
    pub fn max_multiplier_abs(&self, orbit: &SymmetricOrbit) -> f64 {
        self.multipliers(orbit)
            .first()
            .map_or(f64::NAN, |m| m.norm())
    }

    /// The primary's largest |X| (m) over the `samples` times `k T / samples` after the upper
    /// impact.
    pub fn primary_amplitude_m(&self, orbit: &SymmetricOrbit, samples: usize) -> f64 {
        let period = 2.0 * PI / orbit.omega_rad_s;
        (0..samples)
            .map(|k| self.state_at(orbit, period * k as f64 / samples as f64)[0].abs())
            .fold(0.0, f64::max)
    }
}

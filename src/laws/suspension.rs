//! The suspension's restoring force and the device's static equilibria.
//!
//! The suspension pushes the mass back with `F_s(x) = k1 x + k2 x^2 + ... + k7 x^7` (eq 7's
//! `km x` when only `k1` is present), derived from the potential
//! `U_s(x) = k1 x^2 / 2 + k2 x^3 / 3 + ... + k7 x^8 / 8`. The model keeps `k1` as
//! [`crate::physics::harvester::Harvester::km`] and the higher terms here ([`Spring`]), so that
//! a linear device evaluates exactly the product it always did.
//!
//! Common forms (standard in the literature on nonlinear and bistable harvesters):
//! * hardening (Duffing): `k1 > 0`, `k3 > 0`;
//! * bistable (a double well): `U_s = -k x^2 / 2 + k3 x^4 / 4` with `k, k3 > 0`, wells at
//!   `x = +-sqrt(k / k3)`, barrier `k^2 / (4 k3)` above them, small oscillations in a well at
//!   `sqrt(2 k / m)` (e.g. Cottone, Vocca and Gammaitoni, Phys. Rev. Lett. 102, 080601, 2009;
//!   Stanton, McGehee and Mann, Physica D 239, 640, 2010).
//!
//! # Static equilibria ([`equilibria`])
//! The static force on the mass, with the stops' springs (their dampers do not act at rest),
//! is `G(x) = F_s(x) + F_stop(x)`; the mass rests where `G = 0` and the rest is stable where
//! `G' > 0`. A rigid stop holds the mass wherever the suspension pushes it outward at the stop
//! (`s F_s(s gap) < 0`). Between the stops the equilibria are the real roots of the polynomial
//! `F_s` (the eigenvalues of its companion matrix, polished by Newton's method); past a
//! compliant stop they are the sign changes of `G` on a fine grid, bisected.

use nalgebra::DMatrix;

use crate::laws::contact::{Side, StopModel};

/// The highest power of the suspension's polynomial.
pub const MAX_ORDER: usize = 7;

/// The suspension's terms beyond the linear one, `k2 x^2 + ... + k7 x^7`, and the well the
/// model is linearised about.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Spring {
    /// `k2 .. k7` (N/m^i).
    pub higher: [f64; MAX_ORDER - 1],
    /// True when any higher term is non-zero.
    pub nonlinear: bool,
    /// The reference well: the stable equilibrium a linearisation is taken about (m).
    pub well_m: f64,
    /// The small-oscillation stiffness there, `G'(well)` (N/m), which sets the model's time
    /// and displacement scales.
    pub well_stiffness_n_per_m: f64,
}

impl Spring {
    /// A linear suspension of stiffness `k` (N/m): no higher terms, the well at rest.
    pub fn linear(k: f64) -> Self {
        Self {
            higher: [0.0; MAX_ORDER - 1],
            nonlinear: false,
            well_m: 0.0,
            well_stiffness_n_per_m: k,
        }
    }

    /// The higher terms' force `k2 x^2 + ... + k7 x^7` (N).
    #[inline(always)]
    pub fn force(&self, x: f64) -> f64 {
        if !self.nonlinear {
            return 0.0;
        }
        let mut p = 0.0;
        for &k in self.higher.iter().rev() {
            p = p * x + k;
        }
        p * x * x
    }

    /// The higher terms' stiffness `2 k2 x + ... + 7 k7 x^6` (N/m).
    #[inline(always)]
    pub fn stiffness(&self, x: f64) -> f64 {
        if !self.nonlinear {
            return 0.0;
        }
        let mut p = 0.0;
        for (i, &k) in self.higher.iter().enumerate().rev() {
            p = p * x + (i + 2) as f64 * k;
        }
        p * x
    }

    /// The higher terms' potential `k2 x^3 / 3 + ... + k7 x^8 / 8` (J).
    pub fn energy(&self, x: f64) -> f64 {
        if !self.nonlinear {
            return 0.0;
        }
        let mut p = 0.0;
        for (i, &k) in self.higher.iter().enumerate().rev() {
            p = p * x + k / (i + 3) as f64;
        }
        p * x * x * x
    }
}

/// How far the stiffness of a nonlinear suspension may stray from its value at the reference
/// well, as `h^2 |F_s'(x) - k_well| / m` with `h` a record's sample interval, for the record's
/// exponential step ([`Spring::fast_path_reach_m`]). The step extrapolates the remainder
/// explicitly; its Lipschitz constant in these units is that number, and at 0.01 it is well
/// inside the stability region of the fifth-order exponential Adams method (whose local error
/// is then set by the remainder's smoothness along the path, not by the step).
pub const FAST_PATH_STIFFNESS_DRIFT: f64 = 0.01;

impl Spring {
    /// The largest distance `X` from rest such that every `|x| <= X` keeps
    /// `h^2 |km + F_higher'(x) - k_well| / m` within [`FAST_PATH_STIFFNESS_DRIFT`] (m): the
    /// reach of a record's exponential step with sample interval `h_s`. Infinite for a linear
    /// suspension.
    pub fn fast_path_reach_m(&self, km: f64, mass_kg: f64, h_s: f64) -> f64 {
        if !self.nonlinear {
            return f64::INFINITY;
        }
        let ok = |x: f64| {
            let drift = (km + self.stiffness(x) - self.well_stiffness_n_per_m).abs();
            h_s * h_s * drift / mass_kg <= FAST_PATH_STIFFNESS_DRIFT
        };
        // Outward on a geometric grid from a thousandth of the well's scale, then bisected.
        let mut x = 1e-3
            * self
                .well_m
                .abs()
                .max((self.well_stiffness_n_per_m / mass_kg).sqrt() * h_s);
        if x <= 0.0 || !x.is_finite() {
            return 0.0;
        }
        let mut last_ok = 0.0;
        for _ in 0..400 {
            if !(ok(x) && ok(-x)) {
                let (mut lo, mut hi) = (last_ok, x);
                for _ in 0..60 {
                    let mid = 0.5 * (lo + hi);
                    if ok(mid) && ok(-mid) {
                        lo = mid;
                    } else {
                        hi = mid;
                    }
                }
                return lo;
            }
            last_ok = x;
            x *= 1.05;
        }
        f64::INFINITY
    }
}

/// The full restoring polynomial `k1 .. k7` (N/m^i) as a function set.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polynomial(pub [f64; MAX_ORDER]);

impl Polynomial {
    /// `F_s(x)` (N).
    pub fn force(&self, x: f64) -> f64 {
        self.0.iter().rev().fold(0.0, |p, &k| p * x + k) * x
    }

    /// `F_s'(x)` (N/m).
    pub fn stiffness(&self, x: f64) -> f64 {
        self.0
            .iter()
            .enumerate()
            .rev()
            .fold(0.0, |p, (i, &k)| p * x + (i + 1) as f64 * k)
    }

    /// `U_s(x)` with `U_s(0) = 0` (J).
    pub fn energy(&self, x: f64) -> f64 {
        self.0
            .iter()
            .enumerate()
            .rev()
            .fold(0.0, |p, (i, &k)| p * x + k / (i + 2) as f64)
            * x
            * x
    }

    /// The highest power with a non-zero coefficient and that coefficient (0 when all vanish).
    pub fn leading(&self) -> (usize, f64) {
        (1..=MAX_ORDER)
            .rev()
            .find(|&i| self.0[i - 1] != 0.0)
            .map_or((0, 0.0), |i| (i, self.0[i - 1]))
    }

    /// True when the force grows without bound away from rest on `side` (`s F_s(s x) -> +inf`
    /// as `x -> +inf`): the suspension alone confines the mass there.
    pub fn confines(&self, side: Side) -> bool {
        let (n, k) = self.leading();
        match side {
            Side::Upper => n >= 1 && k > 0.0,
            // -F_s(-x) ~ -k (-1)^n x^n.
            Side::Lower => n >= 1 && k * if n % 2 == 1 { 1.0 } else { -1.0 } > 0.0,
        }
    }

    /// The real roots of `F_s` (sorted), from the eigenvalues of the companion matrix of
    /// `F_s(x) / x` with `x = 0` added, each polished by Newton's method.
    pub fn real_roots(&self) -> Vec<f64> {
        let (n, lead) = self.leading();
        let mut roots = vec![0.0];
        if n >= 2 {
            // F_s(x) / x = k1 + k2 x + ... + kn x^(n-1): degree n - 1.
            let d = n - 1;
            let mut c = DMatrix::<f64>::zeros(d, d);
            for i in 1..d {
                c[(i, i - 1)] = 1.0;
            }
            for i in 0..d {
                c[(i, d - 1)] = -self.0[i] / lead;
            }
            // A bounded Schur iteration: coefficients of wildly different sizes may not
            // converge, and then no root is reported rather than the loop running on.
            let eig = nalgebra::linalg::Schur::try_new(c, f64::EPSILON, 10_000)
                .map(|s| s.complex_eigenvalues())
                .unwrap_or_else(|| nalgebra::DVector::zeros(0));
            for z in eig.iter() {
                let scale = z.norm().max(f64::MIN_POSITIVE);
                if z.im.abs() > 1e-6 * scale {
                    continue;
                }
                let mut x = z.re;
                for _ in 0..50 {
                    let (f, df) = (self.force(x), self.stiffness(x));
                    if df == 0.0 {
                        break;
                    }
                    let dx = f / df;
                    x -= dx;
                    if dx.abs() <= 1e-15 * x.abs().max(f64::MIN_POSITIVE) {
                        break;
                    }
                }
                if x.is_finite() {
                    roots.push(x);
                }
            }
        }
        roots.sort_by(f64::total_cmp);
        let tol = 1e-9 * roots.iter().fold(0.0f64, |a, r| a.max(r.abs())).max(1e-300);
        roots.dedup_by(|a, b| (*a - *b).abs() <= tol);
        roots
    }
}

/// Where a static equilibrium is.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Place {
    /// Between the stops, held by the suspension alone.
    Free,
    /// Pressed into (compliant) or onto (rigid) the upper stop.
    UpperStop,
    /// Pressed into or onto the lower stop.
    LowerStop,
}

/// One static equilibrium of a device.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Equilibrium {
    /// Position (m).
    pub x_m: f64,
    /// `G'(x)` (N/m): the static stiffness there (infinite on a rigid stop).
    pub stiffness_n_per_m: f64,
    /// True when a small displacement is pushed back (`G' > 0`, or held on a rigid stop).
    pub stable: bool,
    /// Potential energy of the suspension and the stops' springs, `U(x)` with `U(0) = 0` (J).
    pub energy_j: f64,
    /// Where it is.
    pub place: Place,
}

/// The potential of the suspension and the stops' springs, `U(x)` (J); infinite beyond a
/// rigid stop.
pub fn potential_j(
    spring: &Polynomial,
    upper: Option<&StopModel>,
    lower: Option<&StopModel>,
    x: f64,
) -> f64 {
    let mut u = spring.energy(x);
    for (side, stop) in [(Side::Upper, upper), (Side::Lower, lower)] {
        if let Some(s) = stop {
            let delta = side.sign() * x - s.gap();
            if delta > 0.0 {
                u += match s {
                    StopModel::Rigid { .. } => f64::INFINITY,
                    StopModel::Compliant { .. } => s.energy(delta),
                };
            }
        }
    }
    u
}

/// The static force `G(x)` of the suspension and the stops' springs (N, along +x as a
/// restoring force).
pub fn static_force_n(
    spring: &Polynomial,
    upper: Option<&StopModel>,
    lower: Option<&StopModel>,
    x: f64,
) -> f64 {
    let mut g = spring.force(x);
    for (side, stop) in [(Side::Upper, upper), (Side::Lower, lower)] {
        if let Some(s @ StopModel::Compliant { .. }) = stop {
            g += side.sign() * s.bracket(side.sign() * x - s.gap(), 0.0);
        }
    }
    g
}

/// Every static equilibrium of a suspension with its stops, sorted by position (see the
/// module docs). Empty only for a device that does not confine the mass.
pub fn equilibria(
    spring: &Polynomial,
    upper: Option<&StopModel>,
    lower: Option<&StopModel>,
) -> Vec<Equilibrium> {
    let gap = |s: Option<&StopModel>| s.map_or(f64::INFINITY, StopModel::gap);
    let (gu, gl) = (gap(upper), gap(lower));
    let u = |x| potential_j(spring, upper, lower, x);
    let mut out: Vec<Equilibrium> = spring
        .real_roots()
        .into_iter()
        .filter(|&x| x < gu && x > -gl)
        .map(|x| {
            let k = spring.stiffness(x);
            Equilibrium {
                x_m: x,
                stiffness_n_per_m: k,
                stable: k > 0.0,
                energy_j: u(x),
                place: Place::Free,
            }
        })
        .collect();
    let roots = spring.real_roots();
    let span = roots.iter().fold(0.0f64, |a, r| a.max(r.abs()));
    for (side, stop, g) in [(Side::Upper, upper, gu), (Side::Lower, lower, gl)] {
        let Some(stop) = stop else { continue };
        let s = side.sign();
        let place = if s > 0.0 {
            Place::UpperStop
        } else {
            Place::LowerStop
        };
        match stop {
            StopModel::Rigid { .. } => {
                if s * spring.force(s * g) < 0.0 {
                    out.push(Equilibrium {
                        x_m: s * g,
                        stiffness_n_per_m: f64::INFINITY,
                        stable: true,
                        energy_j: spring.energy(s * g),
                        place,
                    });
                }
            }
            StopModel::Compliant { .. } => {
                // Past the stop: sign changes of s G(s x) on a grid out to well beyond the
                // suspension's roots and the gap, bisected.
                let reach = 10.0 * span.max(g);
                let n = 4000;
                let f = |x: f64| {
                    s * static_force_n(
                        spring,
                        Some(stop).filter(|_| s > 0.0),
                        Some(stop).filter(|_| s < 0.0),
                        s * x,
                    )
                };
                let mut a = g;
                let mut fa = f(a);
                for i in 1..=n {
                    let b = g + (reach - g) * (i as f64 / n as f64).powi(3);
                    let fb = f(b);
                    if fa < 0.0 && fb >= 0.0 || fa > 0.0 && fb <= 0.0 {
                        let (mut lo, mut hi, mut flo) = (a, b, fa);
                        for _ in 0..200 {
                            let mid = 0.5 * (lo + hi);
                            let fm = f(mid);
                            if (fm < 0.0) == (flo < 0.0) {
                                lo = mid;
                                flo = fm;
                            } else {
                                hi = mid;
                            }
                            if hi - lo <= 1e-15 * hi.abs() {
                                break;
                            }
                        }
                        let x = s * 0.5 * (lo + hi);
                        let k = spring.stiffness(x) + stop.bracket_gradient(s * x - g, 0.0).0;
                        out.push(Equilibrium {
                            x_m: x,
                            stiffness_n_per_m: k,
                            stable: fa < 0.0,
                            energy_j: u(x),
                            place,
                        });
                    }
                    a = b;
                    fa = fb;
                }
            }
        }
    }
    out.sort_by(|a, b| a.x_m.total_cmp(&b.x_m));
    out
}

/// The reference well: the stable equilibrium nearest rest (the upper one of two at equal
/// distance), if any.
pub fn reference_well(eq: &[Equilibrium]) -> Option<Equilibrium> {
    eq.iter()
        .filter(|e| e.stable)
        .min_by(|a, b| {
            a.x_m
                .abs()
                .total_cmp(&b.x_m.abs())
                .then(b.x_m.total_cmp(&a.x_m))
        })
        .copied()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The double well `-k x^2/2 + k3 x^4/4` has its wells at `+-sqrt(k/k3)` with stiffness
    /// `2k` and the barrier `k^2/(4 k3)` (exact up to rounding: the roots are polished).
    #[test]
    fn double_well_has_the_closed_form_wells_and_barrier() {
        let (k, k3) = (4.0, 1e6);
        let p = Polynomial([-k, 0.0, k3, 0.0, 0.0, 0.0, 0.0]);
        let eq = equilibria(&p, None, None);
        assert_eq!(eq.len(), 3);
        let xw = (k / k3).sqrt();
        assert!((eq[2].x_m - xw).abs() < 1e-12 * xw);
        assert!((eq[0].x_m + xw).abs() < 1e-12 * xw);
        assert!(eq[0].stable && !eq[1].stable && eq[2].stable);
        assert!((eq[2].stiffness_n_per_m - 2.0 * k).abs() < 1e-9 * k);
        let barrier = eq[1].energy_j - eq[2].energy_j;
        assert!((barrier - k * k / (4.0 * k3)).abs() < 1e-9 * barrier);
        assert_eq!(reference_well(&eq).unwrap().x_m, eq[2].x_m);
    }

    /// The higher terms' force, stiffness and energy are consistent: central differences of
    /// the energy give the force, of the force the stiffness (relative 1e-7: steps of 1e-5 of
    /// x, truncation ~1e-10).
    #[test]
    fn spring_terms_are_derivatives_of_each_other() {
        let s = Spring {
            higher: [0.3, -2.0, 0.7, 5.0, -1.0, 0.25],
            nonlinear: true,
            well_m: 0.0,
            well_stiffness_n_per_m: 1.0,
        };
        for x in [-1.3, -0.2, 0.4, 1.1] {
            let e = 1e-5;
            let f = (s.energy(x + e) - s.energy(x - e)) / (2.0 * e);
            let k = (s.force(x + e) - s.force(x - e)) / (2.0 * e);
            assert!(
                (f - s.force(x)).abs() <= 1e-7 * s.force(x).abs().max(1.0),
                "{x}"
            );
            assert!(
                (k - s.stiffness(x)).abs() <= 1e-7 * s.stiffness(x).abs().max(1.0),
                "{x}"
            );
        }
    }
}

//! The modes in which a sine-driven harvester is affine, `y' = L y + c a(t) + d`, with their
//! closed-form forced response and their guards as affine functions of the state.
//!
//! A mode is affine when the transducer is linear (piezoelectric, electromagnetic, or none), the
//! suspension is linear, and the mode adds no nonlinear force: free flight, a tension-free
//! stop's clipped phase when its bracket is linear, and contact with a linear spring and a
//! viscous damper. For
//! `a(t) = A sin(w t + phi)` the periodic particular solution is
//!
//! `p(t) = A Im[z e^{i(w t + phi)}] + y_s`, with `z = (i w - L)^-1 c` and `L y_s + d = 0`,
//!
//! and every solution is `y(t0 + s) = e^{sL} (y(t0) - p(t0)) + p(t0 + s)`. Its derivatives
//! with respect to the drive's frequency and amplitude, the particular solutions of the
//! variational equations' parameter column, are
//! `dp/df = 2 pi A Im[(z' + i t z) e^{i(w t + phi)}]` with `z' = dz/dw = -i (i w - L)^-1 z`,
//! and `dp/da_rms = sqrt(2) g Im[z e^{i(w t + phi)}]`.

use nalgebra::{Complex, Matrix4, Vector4};

use crate::drive::Sine;
use crate::physics::contact::{ContactDamping, ContactLaw, Mode, Side, StopModel};
use crate::physics::harvester::{Harvester, State};
use crate::physics::transducer::TransducerModel;
use crate::study::orbit::Parameter;

/// An affine guard `n . y + g0` (it fires when it turns positive), with its index among the
/// mode's guards ([`crate::ode::HybridSystem::guards`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct AffineGuard {
    /// Index among the mode's guards.
    pub(crate) index: usize,
    /// Gradient.
    pub(crate) n: State,
    /// Offset.
    pub(crate) g0: f64,
}

impl AffineGuard {
    /// The guard at a state.
    #[inline(always)]
    pub(crate) fn at(&self, y: &State) -> f64 {
        self.n.dot(y) + self.g0
    }
}

/// One affine mode under one sine drive (see the module docs).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AffineMode {
    /// The mode.
    pub(crate) mode: Mode,
    /// `L`.
    pub(crate) l: Matrix4<f64>,
    /// `d`, the constant term.
    pub(crate) d: State,
    /// The static part of the particular solution, `y_s`.
    y_s: State,
    /// `z = (i w - L)^-1 c`.
    z: Vector4<Complex<f64>>,
    /// `dz/dw`.
    dz_dw: Vector4<Complex<f64>>,
    /// The drive: peak amplitude (m/s^2), angular frequency (rad/s), phase (rad).
    amplitude: f64,
    omega: f64,
    phase: f64,
    /// The guards that can fire (those of absent stops are left out).
    pub(crate) guards: [Option<AffineGuard>; 2],
}

impl AffineMode {
    /// The affine dynamics of `mode` under the model's drive, or `None` when the mode is not
    /// affine (a nonlinear transducer, suspension or contact law, a rigid stop's stuck phase)
    /// or its static solution is not unique.
    pub(crate) fn of(model: &Harvester<Sine>, mode: Mode) -> Option<Self> {
        // The Jacobian at rest below is the dynamics only where no force is nonlinear.
        if matches!(model.transducer, TransducerModel::Pair(_)) || model.spring.nonlinear {
            return None;
        }
        let m = model.mass_kg;
        let free = model.jacobian(Mode::Free, &model.rest_state());
        let gap_guard = |index: usize, side: Side, sign: f64| {
            model.stop(side).map(|s| AffineGuard {
                index,
                // sign * (side.sign() x - gap)
                n: State::new(sign * side.sign(), 0.0, 0.0, 0.0),
                g0: -sign * s.gap(),
            })
        };
        let (l, d, guards) = match mode {
            Mode::Free => (
                free,
                State::zeros(),
                [
                    gap_guard(0, Side::Upper, 1.0),
                    gap_guard(1, Side::Lower, 1.0),
                ],
            ),
            Mode::Contact(side) | Mode::Clipped(side) => {
                let Some(&StopModel::Compliant {
                    gap,
                    law: ContactLaw::Linear(k),
                    damping: ContactDamping::Viscous(b),
                    tension_free,
                }) = model.stop(side)
                else {
                    return None;
                };
                let s = side.sign();
                // The bracket k delta + b delta' = k (s x - gap) + b s v as an affine function.
                let bracket = |sign: f64| AffineGuard {
                    index: 1,
                    n: State::new(sign * k * s, sign * b * s, 0.0, 0.0),
                    g0: -sign * k * gap,
                };
                let leave = gap_guard(0, side, -1.0);
                if let Mode::Contact(_) = mode {
                    let mut l = free;
                    l[(1, 0)] -= k / m;
                    l[(1, 1)] -= b / m;
                    let d = State::new(0.0, s * k * gap / m, 0.0, 0.0);
                    (l, d, [leave, tension_free.then(|| bracket(-1.0))])
                } else {
                    (free, State::zeros(), [leave, Some(bracket(1.0))])
                }
            }
            Mode::Stuck(_) => return None,
        };
        let active = model.active_states();
        let y_s = static_solution(&l, &d, active)?;
        let sine = &model.excitation;
        let omega = 2.0 * std::f64::consts::PI * sine.freq_hz;
        let c = Vector4::new(0.0, 1.0, 0.0, 0.0).map(|v| Complex::new(v, 0.0));
        let a = Matrix4::<Complex<f64>>::from_fn(|i, j| {
            let diag = if i == j { omega } else { 0.0 };
            Complex::new(-l[(i, j)], diag)
        });
        let lu = a.lu();
        let z = lu.solve(&c)?;
        // dz/dw = -(i w - L)^-1 i z.
        let dz_dw = lu.solve(&z.map(|v| -Complex::<f64>::i() * v))?;
        if !(z
            .iter()
            .chain(dz_dw.iter())
            .all(|v| v.re.is_finite() && v.im.is_finite()))
        {
            return None;
        }
        Some(Self {
            mode,
            l,
            d,
            y_s,
            z,
            dz_dw,
            amplitude: sine.amplitude_m_s2,
            omega,
            phase: sine.phase_rad,
            guards,
        })
    }

    /// The drive's phase at time `t` as (sin, cos).
    #[inline(always)]
    fn phase_at(&self, t: f64) -> (f64, f64) {
        (self.omega * t + self.phase).sin_cos()
    }

    /// The periodic particular solution `p(t)`.
    #[inline(always)]
    pub(crate) fn particular(&self, t: f64) -> State {
        self.forced(t).0
    }

    /// The periodic particular solution `p(t)` and the drive `a(t)`.
    #[inline(always)]
    pub(crate) fn forced(&self, t: f64) -> (State, f64) {
        let (s, c) = self.phase_at(t);
        let mut p = self.y_s;
        for i in 0..4 {
            p[i] += self.amplitude * (self.z[i].re * s + self.z[i].im * c);
        }
        (p, self.amplitude * s)
    }

    /// The right-hand side `L y + c a + d` under the drive `a`.
    #[inline(always)]
    pub(crate) fn rhs_with(&self, a: f64, y: &State) -> State {
        let mut f = self.l * y + self.d;
        f[1] += a;
        f
    }

    /// The right-hand side at time `t`.
    #[inline(always)]
    pub(crate) fn rhs(&self, t: f64, y: &State) -> State {
        self.rhs_with(self.amplitude * self.phase_at(t).0, y)
    }

    /// The particular solution of the variational equations' parameter column: `dp/dp` at
    /// time `t` (see the module docs).
    pub(crate) fn sensitivity(&self, param: Parameter, t: f64) -> State {
        let (s, c) = self.phase_at(t);
        let e = Complex::new(c, s);
        let mut q = State::zeros();
        match param {
            Parameter::Frequency => {
                let k = 2.0 * std::f64::consts::PI * self.amplitude;
                for i in 0..4 {
                    q[i] = k * ((self.dz_dw[i] + Complex::<f64>::i() * t * self.z[i]) * e).im;
                }
            }
            Parameter::Amplitude => {
                let k = std::f64::consts::SQRT_2 * crate::G;
                for i in 0..4 {
                    q[i] = k * (self.z[i] * e).im;
                }
            }
        }
        q
    }
}

/// The solution of `L y + d = 0` on the first `active` components (the others are held at
/// zero and their rows and columns of `L` vanish); `None` when that block is singular.
fn static_solution(l: &Matrix4<f64>, d: &State, active: usize) -> Option<State> {
    if d.iter().all(|v| *v == 0.0) {
        return Some(State::zeros());
    }
    let block = l.view((0, 0), (active, active)).clone_owned();
    let rhs = -d.rows(0, active).clone_owned();
    let sol = block.lu().solve(&rhs)?;
    let mut y = State::zeros();
    for i in 0..active {
        y[i] = sol[i];
    }
    y.iter().all(|v| v.is_finite()).then_some(y)
}

/// The affine modes of a model under its drive: free flight and, where the stops allow, the
/// contact and clipped phases of each side.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct AffineModes {
    modes: Vec<AffineMode>,
}

impl AffineModes {
    /// The affine modes of `model`, or `None` when its free flight is not affine (a capacitor
    /// pair): the whole integration then goes to Dormand-Prince.
    pub(crate) fn of(model: &Harvester<Sine>) -> Option<Self> {
        let free = AffineMode::of(model, Mode::Free)?;
        let mut modes = vec![free];
        for side in Side::BOTH {
            for mode in [Mode::Contact(side), Mode::Clipped(side)] {
                if let Some(m) = AffineMode::of(model, mode) {
                    modes.push(m);
                }
            }
        }
        Some(Self { modes })
    }

    /// Index of `mode` among the affine modes.
    #[inline]
    pub(crate) fn index(&self, mode: Mode) -> Option<usize> {
        self.modes.iter().position(|m| m.mode == mode)
    }

    /// The affine mode at an index of [`AffineModes::index`].
    #[inline]
    pub(crate) fn at(&self, i: usize) -> &AffineMode {
        &self.modes[i]
    }

    /// Number of affine modes.
    pub(crate) fn len(&self) -> usize {
        self.modes.len()
    }
}

//! The whole response of a device with an interface: pseudo-arclength continuation of its
//! periodic steady state in the drive frequency, through folds, with each point's Floquet
//! multipliers from the exact monodromy ([`super::monodromy`]).
//!
//! # The branch
//! The unknowns are `u = (z, q)`: the state at the section (phase zero) in scaled coordinates
//! `z = y / scales` and the frequency `q = f / f_scale` ([`IfContinuationSettings::freq_scale_hz`]).
//! From a point `u_k` with unit tangent `t_k`, the predictor `u_k + ds t_k` is corrected by
//! Newton's method on
//!
//! `P(z, q) - z = 0`,   `t_k . (u - u_k) = ds`,
//!
//! whose Jacobian is `[M - I | dP/dq]` bordered by `t_k` (Keller's pseudo-arclength), with `M`
//! and `dP/dq` from the variational equations and saltation matrices. The new tangent spans the
//! kernel of `[M - I | dP/dq]`, oriented along `t_k`; a fold is where its frequency component
//! changes sign, located by linear interpolation between the two points. A step is halved when
//! Newton fails in [`IfContinuationSettings::max_newton`] iterations, when it moves the
//! frequency by more than [`IfContinuationSettings::max_freq_step_hz`] or when the tangent
//! turns by more than 0.5 rad; it grows by 1.5 after a correction of at most two iterations.
//!
//! # The storage capacitor's slow mode
//! The storage and its DC load relax with a time constant of order `R_L C_s` (with the element
//! in parallel while the bridge conducts), so one Floquet multiplier is real and close to 1,
//! about `exp(-T / (R_L C_s))`. It is kept as it is: `M - I` is then nearly singular along the
//! storage voltage, but `M` is exact to the integrator's tolerance (`rtol` = 1e-9 against a gap
//! `1 - mu` of `T / (R_L C_s)`, 2e-2 for the example cantilever, 4e-4 for the validation
//! device), so the Newton step along it is well determined; the bordered matrix stays regular
//! since the slow multiplier never reaches 1 for a positive load. Stability counts it like any
//! other multiplier (inside the unit circle: stable), and folds are told by the tangent, not by
//! a multiplier crossing +1, so the slow multiplier's nearness to 1 cannot pass for a fold.

use nalgebra::{Complex, Matrix4, SMatrix, SVector, Vector4};

use crate::device::Device;
use crate::drive::Sine;
use crate::physics::harvester::State;
use crate::progress::{share, Progress};
use crate::study::orbit::multipliers;

use super::monodromy::{linearise, IfLinearised};
use super::{measure, steady_model, steady_state, IfSteady, InterfaceError, SteadySettings};

type Vector5 = SVector<f64, 5>;
type Matrix5 = SMatrix<f64, 5, 5>;

/// Largest angle between successive tangents (rad).
const MAX_TURN_RAD: f64 = 0.5;

/// Settings of a frequency continuation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IfContinuationSettings {
    /// Frequency of the first point (Hz): its steady state is found by shooting from rest.
    pub start_hz: f64,
    /// The branch ends once the frequency passes this (Hz), either way from the start.
    pub stop_hz: f64,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// Frequency unit of the unknowns (Hz): a step `ds` moves the frequency by at most
    /// `ds freq_scale_hz`.
    pub freq_scale_hz: f64,
    /// First arclength step.
    pub ds: f64,
    /// Smallest arclength step: below it the branch ends as stalled.
    pub ds_min: f64,
    /// Largest arclength step.
    pub ds_max: f64,
    /// Largest frequency change in one step (Hz).
    pub max_freq_step_hz: f64,
    /// Most points.
    pub max_points: usize,
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Convergence: the largest scaled component of `P(y) - y`.
    pub tol: f64,
    /// Most Newton iterations of one correction.
    pub max_newton: usize,
}

impl IfContinuationSettings {
    /// Settings from `start_hz` to `stop_hz` at `accel_rms_g`: frequency unit 1 Hz, steps of
    /// 0.05 to 0.5 (at most 0.5 Hz), 2000 points, the steady state's tolerances.
    pub fn new(start_hz: f64, stop_hz: f64, accel_rms_g: f64) -> Self {
        let s = SteadySettings::default();
        Self {
            start_hz,
            stop_hz,
            accel_rms_g,
            freq_scale_hz: 1.0,
            ds: 0.05,
            ds_min: 1e-5,
            ds_max: 0.5,
            max_freq_step_hz: 0.5,
            max_points: 2000,
            rtol: s.rtol,
            tol: s.tol,
            max_newton: 6,
        }
    }
}

/// One point of a continued branch.
#[derive(Debug, Clone, PartialEq)]
pub struct IfBranchPoint {
    /// The steady state and its measures (`max_multiplier` from the exact monodromy).
    pub steady: IfSteady,
    /// Floquet multipliers, largest modulus first.
    pub multipliers: [Complex<f64>; 4],
    /// The tangent's frequency component (its sign changes at a fold).
    pub tangent_freq: f64,
}

impl IfBranchPoint {
    /// True when every multiplier is inside the unit circle (to 1e-6).
    pub fn is_stable(&self) -> bool {
        self.steady.is_stable()
    }
}

/// How a branch ended.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum IfBranchEnd {
    /// The frequency passed the stop.
    Reached,
    /// The step fell below its minimum at this frequency (Hz).
    Stalled(f64),
    /// The budget of points ran out.
    MaxPoints,
}

/// A continued branch of steady states.
#[derive(Debug, Clone, PartialEq)]
pub struct IfBranch {
    /// The points, in arclength order.
    pub points: Vec<IfBranchPoint>,
    /// Folds: the frequency (Hz) where the tangent's frequency component vanishes, linearly
    /// interpolated between the two points around it, and the index of the later point.
    pub folds: Vec<(f64, usize)>,
    /// How the branch ended.
    pub end: IfBranchEnd,
    /// Newton iterations over all corrections.
    pub newton_iterations: usize,
    /// Rejected steps.
    pub rejected_steps: usize,
}

struct Cont<'a> {
    device: &'a Device,
    set: IfContinuationSettings,
    scales: State,
}

/// A corrected point: its unknowns and the linearisation there.
struct Corrected {
    u: Vector5,
    lin: IfLinearised,
    iterations: usize,
}

impl Cont<'_> {
    fn freq(&self, u: &Vector5) -> f64 {
        u[4] * self.set.freq_scale_hz
    }

    fn state(&self, u: &Vector5) -> State {
        Vector4::new(u[0], u[1], u[2], u[3]).component_mul(&self.scales)
    }

    /// P, M and dP/dq in scaled coordinates at `u`: (P(z) - z, [M - I | dP/dq]).
    fn evaluate(
        &self,
        u: &Vector5,
    ) -> Result<(Vector4<f64>, SMatrix<f64, 4, 5>, IfLinearised), InterfaceError> {
        let f = self.freq(u);
        if !(f.is_finite() && f > 0.0) {
            return Err(InterfaceError::Drive(format!(
                "frequency {f} Hz on the branch"
            )));
        }
        let model = steady_model(self.device, Sine::from_rms_g(self.set.accel_rms_g, f))?;
        let y = self.state(u);
        let lin = linearise(&model, &y, self.set.rtol)?;
        let sc = &self.scales;
        let r = (lin.end - y).component_div(sc);
        let s = Matrix4::from_diagonal(sc);
        let si = Matrix4::from_diagonal(&sc.map(|v| 1.0 / v));
        let m = si * lin.monodromy * s - Matrix4::identity();
        let dq = lin.dp_dfreq.component_div(sc) * self.set.freq_scale_hz;
        let mut a = SMatrix::<f64, 4, 5>::zeros();
        a.fixed_view_mut::<4, 4>(0, 0).copy_from(&m);
        a.set_column(4, &dq);
        Ok((r, a, lin))
    }

    /// The unit tangent: the kernel of `a`, oriented along `prev`.
    fn tangent(a: &SMatrix<f64, 4, 5>, prev: &Vector5) -> Option<Vector5> {
        let mut b = Matrix5::zeros();
        b.fixed_view_mut::<4, 5>(0, 0).copy_from(a);
        b.set_row(4, &prev.transpose());
        let mut rhs = Vector5::zeros();
        rhs[4] = 1.0;
        let t = b.lu().solve(&rhs)?;
        let t = t.normalize();
        Some(if t.dot(prev) < 0.0 { -t } else { t })
    }

    /// Newton on the bordered system from `anchor + ds t`.
    fn correct(&self, anchor: &Vector5, t: &Vector5, ds: f64) -> Option<Corrected> {
        let mut u = anchor + t * ds;
        for it in 0..=self.set.max_newton {
            let (r, a, lin) = self.evaluate(&u).ok()?;
            if !r.iter().all(|v| v.is_finite()) {
                return None;
            }
            if r.amax() < self.set.tol {
                return Some(Corrected {
                    u,
                    lin,
                    iterations: it,
                });
            }
            if it == self.set.max_newton {
                return None;
            }
            let mut b = Matrix5::zeros();
            b.fixed_view_mut::<4, 5>(0, 0).copy_from(&a);
            b.set_row(4, &t.transpose());
            let mut f = Vector5::zeros();
            f.fixed_rows_mut::<4>(0).copy_from(&r);
            f[4] = t.dot(&(u - anchor)) - ds;
            u -= b.lu().solve(&f)?;
        }
        None
    }

    fn point(
        &self,
        u: &Vector5,
        lin: &IfLinearised,
        tangent_q: f64,
        iterations: usize,
    ) -> Result<IfBranchPoint, InterfaceError> {
        let f = self.freq(u);
        let model = steady_model(self.device, Sine::from_rms_g(self.set.accel_rms_g, f))?;
        let y = self.state(u);
        let mut steady = measure(&model, &y, self.set.rtol)?;
        let mu = multipliers(&lin.monodromy).ok_or(InterfaceError::NoConvergence {
            iterations,
            residual: f64::NAN,
            tol: self.set.tol,
        })?;
        steady.max_multiplier = mu[0].norm();
        steady.newton_steps = iterations;
        steady.residual = (lin.end - y).component_div(&self.scales).amax();
        Ok(IfBranchPoint {
            steady,
            multipliers: mu,
            tangent_freq: tangent_q,
        })
    }
}

/// Continues the steady state of `device` (with an interface and a load) in the drive
/// frequency from `settings.start_hz` towards `settings.stop_hz` (see the module docs);
/// `progress` is told of every accepted point's frequency as the share of the way from the
/// start to the stop.
pub fn continue_frequency(
    device: &Device,
    settings: &IfContinuationSettings,
    progress: &dyn Progress,
) -> Result<IfBranch, InterfaceError> {
    let set = *settings;
    let first_sine = Sine::from_rms_g(set.accel_rms_g, set.start_hz);
    let steady_set = SteadySettings {
        rtol: set.rtol,
        tol: set.tol,
        ..SteadySettings::default()
    };
    let first = steady_state(device, first_sine, &State::zeros(), &steady_set)?;
    let scales = steady_model(device, first_sine)?.scales();
    let c = Cont {
        device,
        set,
        scales,
    };
    let direction = (set.stop_hz - set.start_hz).signum();
    let y0 = State::from(first.state);
    let z0 = y0.component_div(&scales);
    let mut u = Vector5::new(z0[0], z0[1], z0[2], z0[3], set.start_hz / set.freq_scale_hz);
    let (_, a, lin) = c.evaluate(&u)?;
    let mut seed = Vector5::zeros();
    seed[4] = direction;
    let mut t = Cont::tangent(&a, &seed).ok_or(InterfaceError::NoConvergence {
        iterations: 0,
        residual: f64::NAN,
        tol: set.tol,
    })?;
    let p0 = c.point(&u, &lin, t[4], first.newton_steps)?;
    progress.fraction(share(set.start_hz, set.stop_hz, p0.steady.freq_hz));
    let mut branch = IfBranch {
        points: vec![p0],
        folds: Vec::new(),
        end: IfBranchEnd::MaxPoints,
        newton_iterations: first.newton_steps,
        rejected_steps: 0,
    };
    let (lo, hi) = (set.start_hz.min(set.stop_hz), set.start_hz.max(set.stop_hz));
    let mut ds = set.ds;
    while branch.points.len() < set.max_points {
        // A step is accepted when the corrector converges, the tangent turns by at most
        // MAX_TURN_RAD and the frequency moves by at most the largest step; otherwise it is
        // halved, down to ds_min.
        let accepted = match c.correct(&u, &t, ds) {
            Some(cor) => {
                branch.newton_iterations += cor.iterations;
                let (_, a, _) = c.evaluate(&cor.u)?;
                let df = (c.freq(&cor.u) - c.freq(&u)).abs();
                Cont::tangent(&a, &t)
                    .filter(|tn| {
                        tn.dot(&t).clamp(-1.0, 1.0).acos() <= MAX_TURN_RAD
                            && df <= set.max_freq_step_hz
                    })
                    .map(|tn| (cor, tn))
            }
            None => None,
        };
        let Some((cor, tn)) = accepted else {
            branch.rejected_steps += 1;
            ds *= 0.5;
            if ds < set.ds_min {
                branch.end = IfBranchEnd::Stalled(c.freq(&u));
                return Ok(branch);
            }
            continue;
        };
        if tn[4] * t[4] < 0.0 {
            // Linear interpolation of the tangent's frequency component to zero.
            let (f0, f1) = (c.freq(&u), c.freq(&cor.u));
            let w = t[4] / (t[4] - tn[4]);
            branch.folds.push((f0 + w * (f1 - f0), branch.points.len()));
        }
        let p = c.point(&cor.u, &cor.lin, tn[4], cor.iterations)?;
        progress.fraction(share(set.start_hz, set.stop_hz, p.steady.freq_hz));
        branch.points.push(p);
        u = cor.u;
        t = tn;
        if cor.iterations <= 2 {
            ds = (ds * 1.5).min(set.ds_max);
        }
        let f = c.freq(&u);
        if f < lo || f > hi {
            branch.end = IfBranchEnd::Reached;
            return Ok(branch);
        }
    }
    Ok(branch)
}

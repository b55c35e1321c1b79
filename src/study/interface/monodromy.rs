//! The period map of a harvester with an interface and its exact linearisation: the monodromy
//! `M = dP/dy` and the frequency sensitivity `dP/df`, by the variational equations integrated
//! along the orbit with a saltation matrix at every event.
//!
//! Between events the variational equations are `Phi' = J Phi`, with `J` the mode's Jacobian
//! ([`Interfaced::jacobian`]; for piecewise-linear diodes the circuit is linear between
//! switchings, and `J` is constant in its variables). At an event of guard `g` with gradient
//! `n` the columns jump by the saltation matrix (di Bernardo et al., *Piecewise-smooth
//! Dynamical Systems*, 2008, section 2.5):
//!
//! * a diode's conduction change, or a contact with a compliant stop (the state is continuous,
//!   the vector field switches from `f-` to `f+`): `S = I + (f+ - f-) n^T / (n . f-)`;
//! * an SSHI inversion or SECE transfer at an extremum, or a rebound off a rigid stop (a reset
//!   `y+ = R(y-)` with Jacobian `G`): `S = G + (f+ - G f-) n^T / (n . f-)`.
//!
//! The projections the integrator makes at an event (the velocity put at exactly zero at an
//! extremum, the element's voltage onto a conducting mode's constraint) are within the event
//! tolerance and are not part of `G`: the saltation itself carries a perturbation onto the new
//! mode's constraint (e.g. `d(Vp - s Vs) = 0` after an ideal bridge starts to conduct).
//!
//! The guard's gradient is taken by central differences of the guard (the circuit's guards
//! and the stops' are linear or smooth in the state, so this is exact to rounding), as for the
//! resistive harvester's orbits ([`crate::study::orbit`]). The formula breaks down where
//! `n . f-` vanishes: an event reached tangentially (a conduction that starts exactly at an
//! extremum, a grazing contact), where the period map is not differentiable.

use nalgebra::{Matrix4, SVector, Vector4};

use crate::drive::Sine;
use crate::ode::{Dopri5, HybridSystem, SolverError, Stats};
use crate::physics::contact::Mode;
use crate::physics::harvester::{head, reset_jacobian, State, SwitchKind};
use crate::physics::interface::{IfMode, Interfaced};

/// The state, the monodromy's 16 entries (column-major) and `dP/df`.
const DIM: usize = 24;
type Aug = SVector<f64, DIM>;

/// The period map at one state with its derivatives (physical units).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IfLinearised {
    /// P(y).
    pub end: State,
    /// dP/dy.
    pub monodromy: Matrix4<f64>,
    /// dP/df (per Hz), with the end time's share `-f(P(y)) / f^2`.
    pub dp_dfreq: Vector4<f64>,
    /// Events passed over the period (conduction changes, extrema, contacts).
    pub events: usize,
    /// The smallest `|n . f-|` met at an event, relative to the guard's scale rate (the
    /// guard's gradient times the state scales, times the suspension's angular frequency):
    /// near zero the event is nearly tangential and the map nearly not differentiable.
    pub min_transversality: f64,
    /// Integrator counters.
    pub stats: Stats,
}

struct Variational<'a> {
    model: &'a Interfaced<Sine>,
    w0: f64,
    events: std::cell::Cell<usize>,
    min_transversality: std::cell::Cell<f64>,
}

impl Variational<'_> {
    /// d a / d f at time t (m/s^2 per Hz).
    fn drive_sensitivity(&self, t: f64) -> f64 {
        let s = &self.model.h.excitation;
        let w = 2.0 * std::f64::consts::PI * s.freq_hz;
        s.amplitude_m_s2 * (w * t + s.phase_rad).cos() * 2.0 * std::f64::consts::PI * t
    }

    /// Gradient of guard `index` of `mode` and its explicit time derivative (nonzero only for
    /// a mass stuck to a stop, whose guard is the holding force).
    fn guard_gradient(&self, mode: IfMode, index: usize, t: f64, y: &State) -> (Vector4<f64>, f64) {
        let m = self.model;
        let sc = m.scales();
        let mut n = Vector4::zeros();
        for c in 0..4 {
            let h = 1e-6 * sc[c];
            let (mut yp, mut ym) = (*y, *y);
            yp[c] += h;
            ym[c] -= h;
            n[c] = (m.guard_values(mode, t, &yp)[index] - m.guard_values(mode, t, &ym)[index])
                / (2.0 * h);
        }
        let g_t = if let Mode::Stuck(_) = mode.contact {
            let ht = 1e-6 / self.w0;
            (m.guard_values(mode, t + ht, y)[index] - m.guard_values(mode, t - ht, y)[index])
                / (2.0 * ht)
        } else {
            0.0
        };
        (n, g_t)
    }
}

impl HybridSystem for Variational<'_> {
    type State = Aug;
    type Mode = IfMode;

    fn guard_count(&self) -> usize {
        self.model.guard_count()
    }

    #[inline]
    fn rhs(&self, mode: IfMode, t: f64, z: &Aug) -> Aug {
        let y = head(z);
        let f = self.model.rhs(mode, t, &y);
        let j = self.model.jacobian(mode, &y);
        let mut out = Aug::zeros();
        out.fixed_rows_mut::<4>(0).copy_from(&f);
        for c in 0..5 {
            let b = 4 + 4 * c;
            let col = Vector4::new(z[b], z[b + 1], z[b + 2], z[b + 3]);
            out.fixed_rows_mut::<4>(b).copy_from(&(j * col));
        }
        if !matches!(mode.contact, Mode::Stuck(_)) {
            out[21] += self.drive_sensitivity(t);
        }
        out
    }

    fn guards(&self, mode: IfMode, t: f64, z: &Aug, g: &mut [f64]) {
        self.model.guards(mode, t, &head(z), g)
    }

    fn switch(&self, mode: IfMode, index: usize, t: f64, z: &mut Aug) -> IfMode {
        let m = self.model;
        let y = head(z);
        let f_old = m.rhs(mode, t, &y);
        let (n, g_t) = self.guard_gradient(mode, index, t, &y);
        // The reset's Jacobian: the stops' (a rebound, sticking) or the switch's at an
        // extremum; the identity for a conduction change or a compliant contact.
        let g = if index < 2 {
            let to = m.h.switch(mode.contact, index, t, &mut y.clone());
            match SwitchKind::of(mode.contact, to) {
                SwitchKind::Rebound | SwitchKind::Stick => {
                    reset_jacobian(mode.contact, to, m.h.restitution(index))
                }
                _ => Matrix4::identity(),
            }
        } else if m.fires_extremum(mode, &y) {
            m.circuit.reset_jacobian(&y)
        } else {
            Matrix4::identity()
        };
        let mut y_new = y;
        let new_mode = m.switch(mode, index, t, &mut y_new);
        let f_new = m.rhs(new_mode, t, &y_new);
        let denom = n.dot(&f_old) + g_t;
        let rate_scale = n.component_mul(&m.scales()).abs().sum() * self.w0;
        self.events.set(self.events.get() + 1);
        self.min_transversality
            .set(self.min_transversality.get().min(denom.abs() / rate_scale));
        z.fixed_rows_mut::<4>(0).copy_from(&y_new);
        if denom != 0.0 && denom.is_finite() {
            let df = (f_new - g * f_old) / denom;
            for c in 0..5 {
                let b = 4 + 4 * c;
                let col = Vector4::new(z[b], z[b + 1], z[b + 2], z[b + 3]);
                let upd = g * col + df * n.dot(&col);
                z.fixed_rows_mut::<4>(b).copy_from(&upd);
            }
        }
        new_mode
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.model.next_breakpoint(t)
    }
}

/// P(y), dP/dy and dP/df over one drive period from `y` at t = 0 (the drive's phase zero), by
/// the variational equations with saltation matrices (see the module docs), at relative
/// tolerance `rtol` (absolute tolerances `rtol` times the state scales, their ratios for the
/// derivatives).
pub fn linearise(
    model: &Interfaced<Sine>,
    y: &State,
    rtol: f64,
) -> Result<IfLinearised, SolverError> {
    let period = model.h.excitation.period_s();
    let freq = model.h.excitation.freq_hz;
    let sc = model.scales();
    let mut atol = Aug::zeros();
    let mut z0 = Aug::zeros();
    for i in 0..4 {
        z0[i] = y[i];
        for j in 0..4 {
            atol[4 + i + 4 * j] = rtol * sc[i] / sc[j];
        }
        z0[4 + 5 * i] = 1.0;
        atol[20 + i] = rtol * sc[i] / freq;
    }
    let sys = Variational {
        model,
        w0: (model.h.km / model.h.mass_kg).sqrt(),
        events: std::cell::Cell::new(0),
        min_transversality: std::cell::Cell::new(f64::INFINITY),
    };
    let opts = model.solver_options(rtol).augmented(atol);
    let mut ode = Dopri5::new(0.0, z0, model.mode_of(y), opts);
    ode.integrate(&sys, period, |_, _| {})?;
    let z = ode.y();
    let end = head(&z);
    let monodromy = Matrix4::from_column_slice(&z.as_slice()[4..20]);
    let f_end = model.rhs(ode.mode(), period, &end);
    let dp_dfreq = Vector4::new(z[20], z[21], z[22], z[23]) - f_end / (freq * freq);
    Ok(IfLinearised {
        end,
        monodromy,
        dp_dfreq,
        events: sys.events.get(),
        min_transversality: sys.min_transversality.get(),
        stats: ode.stats(),
    })
}

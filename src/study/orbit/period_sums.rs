//! The sums over one period of an orbit (RMS voltages, extreme displacements, time in
//! contact, impacts, the first upward zero crossing) that make its [`super::OrbitSummary`].

use crate::drive::Sine;
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{Observer, Step};
use crate::physics::contact::Mode;
use crate::physics::harvester::{Harvester, State, SwitchKind};

/// Whole-period sums over the accepted steps of one period.
#[derive(Debug)]
pub(super) struct Sums {
    pub(super) v1sq: f64,
    pub(super) v2sq: f64,
    pub(super) x_upper: f64,
    pub(super) x_lower: f64,
    pub(super) contact_time: f64,
    pub(super) impacts: u32,
    was_contact: Option<bool>,
    pub(super) upcrossing: Option<f64>,
    /// The velocity at the end of the last step (before a switch, the impact velocity).
    last_v: f64,
    pub(super) impact_speed: [f64; 2],
}

impl Default for Sums {
    /// Nothing summed; the extremes start empty (an orbit in a well off x = 0 never reaches
    /// zero, so zero is no bound on its extremes).
    fn default() -> Self {
        Self {
            v1sq: 0.0,
            v2sq: 0.0,
            x_upper: f64::NEG_INFINITY,
            x_lower: f64::INFINITY,
            contact_time: 0.0,
            impacts: 0,
            was_contact: None,
            upcrossing: None,
            last_v: 0.0,
            impact_speed: [0.0; 2],
        }
    }
}

/// Observes one period: the sums over its steps, and the rebounds off rigid stops (impacts
/// without a contact phase, seen only as switches).
pub(super) struct Accumulator<'m> {
    pub(super) model: &'m Harvester<Sine>,
    pub(super) sums: Sums,
}

impl Observer<State, Mode> for Accumulator<'_> {
    fn step(&mut self, st: &Step<State>, mode: Mode) {
        self.sums.add(self.model, st, mode);
    }

    fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
        let kind = SwitchKind::of(from, to);
        if kind == SwitchKind::Rebound {
            self.sums.impacts += 1;
        }
        if matches!(kind, SwitchKind::Rebound | SwitchKind::Stick) {
            let v = self.sums.last_v;
            let side = usize::from(v < 0.0);
            self.sums.impact_speed[side] = self.sums.impact_speed[side].max(v.abs());
        }
    }
}

impl Sums {
    fn add(&mut self, model: &Harvester<Sine>, st: &Step<State>, mode: Mode) {
        let [v1sq, v2sq] = st.integrate_each(|y: &State| {
            let v = model.electrical(y).v;
            [v[0].powi(2), v[1].powi(2)]
        });
        self.v1sq += v1sq;
        self.v2sq += v2sq;
        for x in [st.y0[0], st.y1[0]] {
            self.x_upper = self.x_upper.max(x);
            self.x_lower = self.x_lower.min(x);
        }
        // An extremum of x inside the step: a zero of v on the dense output.
        if (st.y0[1] > 0.0) != (st.y1[1] > 0.0) {
            if let Some(th) = root_on_step(st, 1) {
                let x = st.at_theta(th)[0];
                self.x_upper = self.x_upper.max(x);
                self.x_lower = self.x_lower.min(x);
            }
        }
        if self.upcrossing.is_none() && st.y0[0] <= 0.0 && st.y1[0] > 0.0 {
            self.upcrossing = root_on_step(st, 0).map(|th| st.t0 + th * st.h);
        }
        self.last_v = st.y1[1];
        let contact = mode.in_contact();
        if contact {
            self.contact_time += st.h;
            if self.was_contact == Some(false) {
                self.impacts += 1;
            }
        }
        self.was_contact = Some(contact);
    }
}

/// theta in [0, 1] where component `c` of the dense output of `st` changes sign (the upper
/// end of the final bracket), located by the crate's root finder to 1e-12 of the step.
fn root_on_step(st: &Step<State>, c: usize) -> Option<f64> {
    let f =
        |th: f64| -> Result<(f64, ()), std::convert::Infallible> { Ok((st.at_theta(th)[c], ())) };
    let (a, b) = (
        Sample::new(0.0, st.y0[c], ()),
        Sample::new(1.0, st.y1[c], ()),
    );
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-12,
        x_tol_rel: 0.0,
        max_iter: 100,
    };
    illinois(f, a, b, &opts).ok().map(|r| r.positive.x)
}

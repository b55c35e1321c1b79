//! The sums over one period of an orbit (the outputs' means and mean squares, extreme
//! displacements, time in contact, impacts, the first upward zero crossing) that make its
//! [`super::OrbitSummary`].

use nalgebra::SVector;

use crate::model::{ContactGeometry, Mode, Model, SwitchKind, MAX_CONTACTS, MAX_OUTPUTS};
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{Observer, Step};
use crate::study::mass_peaks::MassPeaks;

use super::reach::ContactReach;

/// Whole-period sums over the accepted steps of one period.
#[derive(Debug)]
pub(super) struct Sums {
    /// Per output, the integrals of its square and of itself.
    pub(super) squares: Vec<f64>,
    pub(super) integrals: Vec<f64>,
    pub(super) x_upper: f64,
    pub(super) x_lower: f64,
    pub(super) mass_peaks: MassPeaks,
    pub(super) contact_time: f64,
    pub(super) impacts: u32,
    was_contact: Option<bool>,
    pub(super) upcrossing: Option<f64>,
    /// The velocity at the end of the last step (before a switch, the impact velocity).
    last_v: f64,
    pub(super) impact_speed: Vec<f64>,
    /// How far each of the model's contacts is reached.
    pub(super) reach: ContactReach,
    /// The state at the end of the last step (before a switch, the state at the impact).
    last_y: Vec<f64>,
}

impl Sums {
    /// Nothing summed for `outputs` outputs and `contacts` contacts; the extremes start empty
    /// (an orbit in a well off x = 0 never reaches zero, so zero is no bound on its extremes).
    pub(super) fn new(
        outputs: usize,
        contacts: usize,
        mass_peaks: MassPeaks,
        reach: ContactReach,
    ) -> Self {
        Self {
            squares: vec![0.0; outputs],
            integrals: vec![0.0; outputs],
            x_upper: f64::NEG_INFINITY,
            x_lower: f64::INFINITY,
            mass_peaks,
            contact_time: 0.0,
            impacts: 0,
            was_contact: None,
            upcrossing: None,
            last_v: 0.0,
            impact_speed: vec![0.0; contacts],
            reach,
            last_y: Vec::new(),
        }
    }
}

/// Observes one period: the sums over its steps, and the rebounds off rigid stops (impacts
/// without a contact phase, seen only as switches).
pub(super) struct Accumulator<'m, M> {
    pub(super) model: &'m M,
    pub(super) sums: Sums,
    /// One evaluation of the outputs.
    buf: Vec<f64>,
    /// The model's contacts.
    contacts: Vec<ContactGeometry>,
}

impl<'m, M> Accumulator<'m, M> {
    /// Sums of a model's period, for `outputs` outputs, the masses of `mass_peaks`
    /// ([`MassPeaks::of`] the model's layout) and the reach of `contacts`.
    pub(super) fn new(
        model: &'m M,
        outputs: usize,
        mass_peaks: MassPeaks,
        contacts: Vec<ContactGeometry>,
    ) -> Self {
        let reach = ContactReach::new(contacts.len());
        Self {
            model,
            sums: Sums::new(outputs, MAX_CONTACTS, mass_peaks, reach),
            buf: vec![0.0; outputs],
            contacts,
        }
    }
}

impl<M: Model<N>, const N: usize> Observer<SVector<f64, N>, Mode> for Accumulator<'_, M> {
    fn step(&mut self, st: &Step<SVector<f64, N>>, mode: Mode) {
        self.sums.add(self.model, st, mode, &mut self.buf);
        let layout = self.model.layout();
        self.sums
            .reach
            .see_step(&self.contacts, layout, st, |f| root_on_step_of(st, f));
    }

    fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
        let kind = SwitchKind::between(from, to);
        if kind == SwitchKind::Rebound {
            self.sums.impacts += 1;
        }
        // A switch at the period's first instant comes before any step: there is no state
        // before it to measure, and the same strike ends the period.
        if matches!(kind, SwitchKind::Rebound | SwitchKind::Stick) && !self.sums.last_y.is_empty() {
            let v = self.sums.last_v;
            let side = usize::from(v < 0.0);
            self.sums.impact_speed[side] = self.sums.impact_speed[side].max(v.abs());
            let layout = self.model.layout();
            self.sums
                .reach
                .strike(&self.contacts, layout, &self.sums.last_y);
        }
    }
}

impl Sums {
    fn add<M: Model<N>, const N: usize>(
        &mut self,
        model: &M,
        st: &Step<SVector<f64, N>>,
        mode: Mode,
        buf: &mut [f64],
    ) {
        // The outputs' squares and values by 3-point Gauss-Legendre on the dense output, as
        // `Step::integrate_each` sums them.
        let k = buf.len();
        let mut sq = [0.0f64; MAX_OUTPUTS];
        let mut lin = [0.0f64; MAX_OUTPUTS];
        let peaks = self.mass_peaks.len > 0;
        for (x, w) in crate::ode::GAUSS_LEGENDRE_3 {
            let y = st.at_theta(x);
            if peaks {
                self.mass_peaks.see(model.layout(), y.as_slice());
            }
            model.outputs(mode, &y, buf);
            for i in 0..k {
                sq[i] += w * buf[i].powi(2);
                lin[i] += w * buf[i];
            }
        }
        for i in 0..k {
            self.squares[i] += sq[i] * st.h;
            self.integrals[i] += lin[i] * st.h;
        }
        if peaks {
            self.mass_peaks.see(model.layout(), st.y0.as_slice());
            self.mass_peaks.see(model.layout(), st.y1.as_slice());
        }
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
        self.last_y.clear();
        self.last_y.extend_from_slice(st.y1.as_slice());
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
fn root_on_step<const N: usize>(st: &Step<SVector<f64, N>>, c: usize) -> Option<f64> {
    root_on_step_of(st, &|y: &SVector<f64, N>| y[c])
}

/// theta in [0, 1] where `g` of the dense output of `st` changes sign, as [`root_on_step`].
fn root_on_step_of<const N: usize>(
    st: &Step<SVector<f64, N>>,
    g: &dyn Fn(&SVector<f64, N>) -> f64,
) -> Option<f64> {
    let f =
        |th: f64| -> Result<(f64, ()), std::convert::Infallible> { Ok((g(&st.at_theta(th)), ())) };
    let (a, b) = (
        Sample::new(0.0, g(&st.y0), ()),
        Sample::new(1.0, g(&st.y1), ()),
    );
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-12,
        x_tol_rel: 0.0,
        max_iter: 100,
    };
    illinois(f, a, b, &opts).ok().map(|r| r.positive.x)
}

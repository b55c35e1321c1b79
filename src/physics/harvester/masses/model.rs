//! The [`Model`] of several masses: right-hand side, Jacobian, guards, switches and their
//! resets, and the energy ledger per element (the drive, each damper, each contact, the
//! projections, the port's terms).

use nalgebra::{SMatrix, SVector};

use crate::laws::contact::StopModel;
use crate::model::{Contact, ContactGeometry, Flow, LedgerTerm, Mode, Model, SwitchKind};

use super::super::ledger::PROJECTIONS as INNER_PROJECTIONS;
use super::super::stops::OFF;
use super::super::STOP_GUARDS;
use super::{MassChain, TermIndex, MAX_MASSES};

/// The index of the port's first ledger term in the one-mass harvester's list.
const INNER_PORT_TERMS: usize = INNER_PROJECTIONS + 1;

/// Room for the one-mass harvester's guards and ledger terms.
const SCRATCH: usize = 16;

fn term(name: String, flow: Flow) -> LedgerTerm {
    LedgerTerm { name, flow }
}

impl<const N: usize> MassChain<N> {
    pub(super) fn make_terms(&mut self) {
        let mut t = vec![term("drive".into(), Flow::In)];
        let name = |i: usize| self.bodies[i].name.clone();
        let dampers = t.len();
        for d in &self.dampers {
            t.push(term(
                match d.other {
                    None => format!("damping_{}", name(d.mass)),
                    Some(o) => format!("damping_{}_{}", name(d.mass), name(o)),
                },
                Flow::Out,
            ));
        }
        let contacts = t.len();
        for c in &self.contacts {
            let what = if c.stop.tension_free() || matches!(c.stop, StopModel::Compliant { .. }) {
                "damping"
            } else {
                "impacts"
            };
            t.push(term(format!("{}_{what}", c.name), Flow::Out));
        }
        let clip = self
            .contacts
            .iter()
            .any(|c| c.stop.tension_free())
            .then(|| {
                t.push(term("clip_losses".into(), Flow::Out));
                t.push(term("reengagement_gains".into(), Flow::In));
                t.len() - 2
            });
        let projections = t.len();
        t.push(term("projections".into(), Flow::Out));
        let port = t.len();
        t.extend(self.inner.terms[INNER_PORT_TERMS..].iter().cloned());
        self.terms = t;
        self.term_at = TermIndex {
            dampers,
            contacts,
            clip,
            projections,
            port,
        };
    }

    /// The stored energy (J): kinetic, springs, pressed contacts and the port's.
    fn energy_of(&self, mode: Mode, y: &SVector<f64, N>) -> f64 {
        // The inner harvester holds the transducer's mass's kinetic energy and the port's.
        let mut e = self.inner.energy(mode.without_contacts(), y);
        for b in &self.bodies[1..] {
            e += 0.5 * b.mass_kg * y[b.ix + 1] * y[b.ix + 1];
        }
        for s in &self.springs {
            let d = y[self.bodies[s.mass].ix] - s.other.map_or(0.0, |o| y[self.bodies[o].ix]);
            e += 0.5 * s.value * d * d;
            if s.cubic_n_per_m3 != 0.0 {
                e += 0.25 * s.cubic_n_per_m3 * d * d * d * d;
            }
        }
        for (k, c) in self.contacts.iter().enumerate() {
            if mode.contact(k) == Contact::Pressed {
                e += c.stop.energy(self.penetration(c, y).0);
            }
        }
        e
    }

    /// The rigid contact whose surface a state is nearest (the one a rebound that left the
    /// mode unchanged went through).
    fn nearest_rigid(&self, y: &SVector<f64, N>) -> Option<usize> {
        (0..self.contacts.len())
            .filter(|&k| matches!(self.contacts[k].stop, StopModel::Rigid { .. }))
            .min_by(|&a, &b| {
                let da = self.penetration(&self.contacts[a], y).0.abs();
                let db = self.penetration(&self.contacts[b], y).0.abs();
                da.total_cmp(&db)
            })
    }
}

impl<const N: usize> Model<N> for MassChain<N> {
    fn layout(&self) -> &crate::model::Layout {
        &self.layout
    }

    fn scales(&self) -> SVector<f64, N> {
        self.scales
    }

    fn omega_rad_s(&self) -> f64 {
        self.omega
    }

    fn guard_count(&self) -> usize {
        2 * self.contacts.len() + self.inner.port.guard_count()
    }

    fn contact_guards(&self) -> usize {
        2 * self.contacts.len()
    }

    fn rhs(&self, mode: Mode, y: &SVector<f64, N>, a: f64) -> SVector<f64, N> {
        let mut d = SVector::<f64, N>::zeros();
        let fe = self.inner.port.force_and_rates(mode.circuit(0), y, &mut d);
        let f = self.forces(mode, y, a, fe);
        let acc = self.accelerations(mode, &f);
        for (i, b) in self.bodies.iter().enumerate() {
            d[b.ix] = y[b.ix + 1];
            d[b.ix + 1] = acc[i];
        }
        if let Some(k) = self.resting(mode) {
            let c = &self.contacts[k];
            if c.other.is_none() {
                d[self.bodies[c.mass].ix] = 0.0;
            }
        }
        d
    }

    fn drive_column(&self, mode: Mode) -> SVector<f64, N> {
        // The accelerations are linear in the forces: those of the drive's forces per unit
        // acceleration, a resting contact's constraint applied.
        let acc = self.accelerations(mode, &self.drive_masses());
        let mut c = SVector::<f64, N>::zeros();
        for (i, b) in self.bodies.iter().enumerate() {
            c[b.ix + 1] = acc[i];
        }
        c
    }

    fn jacobian(&self, mode: Mode, y: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        let mut j = self.inner.linearised(mode.without_contacts(), y);
        // d F / d y for each mass, its force's gradient.
        let mut df = [SVector::<f64, N>::zeros(); MAX_MASSES];
        df[0] = j.row(1).transpose() * self.bodies[0].mass_kg;
        let ix = |i: usize| self.bodies[i].ix;
        let pair = |df: &mut [SVector<f64, N>; MAX_MASSES],
                    a: usize,
                    b: Option<usize>,
                    col: usize,
                    k: f64| {
            df[a][ix(a) + col] -= k;
            if let Some(b) = b {
                df[a][ix(b) + col] += k;
                df[b][ix(a) + col] += k;
                df[b][ix(b) + col] -= k;
            }
        };
        for s in &self.springs {
            let mut k = s.value;
            if s.cubic_n_per_m3 != 0.0 {
                let d = y[ix(s.mass)] - s.other.map_or(0.0, |o| y[ix(o)]);
                k += 3.0 * s.cubic_n_per_m3 * d * d;
            }
            pair(&mut df, s.mass, s.other, 0, k);
        }
        for s in &self.dampers {
            pair(&mut df, s.mass, s.other, 1, s.value);
        }
        for (k, c) in self.contacts.iter().enumerate() {
            if mode.contact(k) != Contact::Pressed {
                continue;
            }
            let (d, dd) = self.penetration(c, y);
            if c.stop.tension_free() && c.stop.bracket(d, dd) < 0.0 {
                continue;
            }
            let (gx, gv) = c.stop.bracket_gradient(d, dd);
            pair(&mut df, c.mass, c.other, 0, gx);
            pair(&mut df, c.mass, c.other, 1, gv);
        }
        for b in &self.bodies {
            for col in 0..N {
                j[(b.ix, col)] = 0.0;
                j[(b.ix + 1, col)] = 0.0;
            }
            j[(b.ix, b.ix + 1)] = 1.0;
        }
        for (i, b) in self.bodies.iter().enumerate() {
            j.set_row(b.ix + 1, &(df[i] / b.mass_kg).transpose());
        }
        if let Some(k) = self.resting(mode) {
            let c = &self.contacts[k];
            let i = c.mass;
            match c.other {
                None => {
                    for col in 0..N {
                        j[(ix(i), col)] = 0.0;
                        j[(ix(i) + 1, col)] = 0.0;
                    }
                }
                Some(o) => {
                    let total = self.bodies[i].mass_kg + self.bodies[o].mass_kg;
                    let common = ((df[i] + df[o]) / total).transpose();
                    j.set_row(ix(i) + 1, &common);
                    j.set_row(ix(o) + 1, &common);
                }
            }
        }
        j
    }

    fn guards(&self, mode: Mode, y: &SVector<f64, N>, a: impl Fn() -> f64, g: &mut [f64]) {
        let mut held = None;
        for (k, c) in self.contacts.iter().enumerate() {
            let (d, dd) = self.penetration(c, y);
            let (boundary, bracket) = match mode.contact(k) {
                Contact::Apart => (d, OFF),
                Contact::Pressed if c.stop.tension_free() => (-d, -c.stop.bracket(d, dd)),
                Contact::Pressed => (-d, OFF),
                Contact::Clipped => (-d, c.stop.bracket(d, dd)),
                Contact::Resting => {
                    let f = *held.get_or_insert_with(|| {
                        let fe = self.inner.port.force(mode.circuit(0), y);
                        self.forces(mode, y, a(), fe)
                    });
                    (OFF, -self.holding(k, &f))
                }
            };
            g[2 * k] = boundary;
            g[2 * k + 1] = bracket;
        }
        if self.inner.port.guard_count() > 0 {
            let mut inner = [OFF; SCRATCH];
            self.inner
                .guards(mode.without_contacts(), y, a, &mut inner[..STOP_GUARDS + 1]);
            g[2 * self.contacts.len()] = inner[STOP_GUARDS];
        }
    }

    fn switch(&self, mode: Mode, index: usize, y: &mut SVector<f64, N>, a: f64) -> Mode {
        let kk = 2 * self.contacts.len();
        if index >= kk {
            let next = self
                .inner
                .switch(mode.without_contacts(), index - kk + STOP_GUARDS, y, a);
            return mode.with_circuits_of(next);
        }
        let k = index / 2;
        let c = &self.contacts[k];
        match (mode.contact(k), index % 2) {
            (Contact::Apart, _) => {
                self.project(c, y);
                match c.stop {
                    StopModel::Rigid { restitution, .. } => {
                        if self.rebound(mode, k, restitution, y, a) {
                            mode.with_contact(k, Contact::Resting)
                        } else {
                            mode
                        }
                    }
                    StopModel::Compliant { .. } => mode.with_contact(k, Contact::Pressed),
                }
            }
            (Contact::Pressed | Contact::Clipped, 0) => {
                self.project(c, y);
                mode.with_contact(k, Contact::Apart)
            }
            (Contact::Pressed, _) => mode.with_contact(k, Contact::Clipped),
            (Contact::Clipped, _) => mode.with_contact(k, Contact::Pressed),
            (Contact::Resting, _) => {
                // The pair leaves the surface it rested on: an integrator that moves both
                // masses keeps their separation only to rounding, and a separation left past
                // the gap would read as a strike at zero relative speed at the release.
                self.project(c, y);
                mode.with_contact(k, Contact::Apart)
            }
        }
    }

    fn switch_kind(&self, from: Mode, index: usize, to: Mode) -> SwitchKind {
        if index >= 2 * self.contacts.len() {
            return SwitchKind::Circuit;
        }
        let k = index / 2;
        SwitchKind::of_contact(from.contact(k), to.contact(k))
    }

    fn reset_jacobian(
        &self,
        from: Mode,
        index: usize,
        to: Mode,
        y: &SVector<f64, N>,
    ) -> Option<SMatrix<f64, N, N>> {
        let kk = 2 * self.contacts.len();
        if index >= kk {
            return self.inner.reset_jacobian(
                from.without_contacts(),
                index - kk + STOP_GUARDS,
                to.without_contacts(),
                y,
            );
        }
        let c = &self.contacts[index / 2];
        let e = match c.stop {
            StopModel::Rigid { restitution, .. } => restitution,
            StopModel::Compliant { .. } => 0.0,
        };
        let ii = self.bodies[c.mass].ix + 1;
        let mi = self.bodies[c.mass].mass_kg;
        let mut d = SMatrix::<f64, N, N>::identity();
        let kind = self.switch_kind(from, index, to);
        match (kind, c.other) {
            (SwitchKind::Rebound, None) => d[(ii, ii)] = -e,
            (SwitchKind::Stick, None) => d[(ii, ii)] = 0.0,
            (SwitchKind::Rebound | SwitchKind::Stick, Some(o)) => {
                let jj = self.bodies[o].ix + 1;
                let mj = self.bodies[o].mass_kg;
                let total = mi + mj;
                if kind == SwitchKind::Rebound {
                    let (p, q) = ((1.0 + e) * mj / total, (1.0 + e) * mi / total);
                    d[(ii, ii)] = 1.0 - p;
                    d[(ii, jj)] = p;
                    d[(jj, ii)] = q;
                    d[(jj, jj)] = 1.0 - q;
                } else {
                    for row in [ii, jj] {
                        d[(row, ii)] = mi / total;
                        d[(row, jj)] = mj / total;
                    }
                }
            }
            _ => return None,
        }
        Some(d)
    }

    fn affine(&self, mode: Mode) -> Option<crate::model::Affine<N>> {
        self.affine_form(mode)
    }

    fn driven_affine(&self, mode: Mode) -> Option<crate::model::DrivenAffine<N>> {
        match self.resting(mode) {
            Some(k) => self.resting_form(mode, k),
            None => self.affine_form(mode).map(Into::into),
        }
    }

    fn without_contacts(&self) -> Self {
        self.without_stops()
    }

    fn contacts(&self) -> Vec<ContactGeometry> {
        self.contacts
            .iter()
            .map(|c| {
                let restitution = match c.stop {
                    StopModel::Rigid { restitution, .. } => Some(restitution),
                    StopModel::Compliant { .. } => None,
                };
                // Between two masses the geometry's `mass` is the struck one and its `other`
                // the one that moves into the contact (`x_other - x_mass` grows towards it).
                let (mass, other) = match c.other {
                    None => (c.mass, None),
                    Some(o) => (o, Some(c.mass)),
                };
                ContactGeometry {
                    mass,
                    other,
                    side: c.sign,
                    gap: c.stop.gap(),
                    restitution,
                }
            })
            .collect()
    }

    fn modes(&self) -> Vec<Mode> {
        let mut contacts = vec![Mode::FREE];
        for (k, c) in self.contacts.iter().enumerate() {
            match c.stop {
                StopModel::Compliant { .. } => {
                    contacts.push(Mode::FREE.with_contact(k, Contact::Pressed));
                    if c.stop.tension_free() {
                        contacts.push(Mode::FREE.with_contact(k, Contact::Clipped));
                    }
                }
                StopModel::Rigid { .. } => {
                    contacts.push(Mode::FREE.with_contact(k, Contact::Resting))
                }
            }
        }
        let circuits = self.inner.modes();
        let mut out = Vec::with_capacity(contacts.len() * circuits.len());
        for m in &circuits {
            for c in &contacts {
                out.push(c.with_circuits_of(*m));
            }
        }
        out
    }

    fn mode_of(&self, y: &SVector<f64, N>) -> Mode {
        let mut mode = Mode::FREE.with_circuits_of(self.inner.mode_of(y));
        for (k, c) in self.contacts.iter().enumerate() {
            if matches!(c.stop, StopModel::Compliant { .. }) && self.penetration(c, y).0 > 0.0 {
                mode = mode.with_contact(k, Contact::Pressed);
            }
        }
        mode
    }

    fn static_state(&self, x: f64, v: f64) -> SVector<f64, N> {
        self.inner.static_state_at(x, v)
    }

    fn check_state(&self, mode: Mode, y: &SVector<f64, N>) -> Result<(), String> {
        self.inner.check_state(mode.without_contacts(), y)
    }

    fn unused(&self) -> &[usize] {
        self.inner.unused()
    }

    fn slow_time_constant_s(&self) -> Option<f64> {
        self.inner.slow_time_constant_s()
    }

    fn ledger_terms(&self) -> &[LedgerTerm] {
        &self.terms
    }

    fn powers(&self, mode: Mode, y: &SVector<f64, N>, a: f64, p: &mut [f64]) {
        p.iter_mut().for_each(|x| *x = 0.0);
        let at = self.term_at;
        p[0] = self
            .bodies
            .iter()
            .zip(self.drive_masses())
            .map(|(b, m)| m * a * y[b.ix + 1])
            .sum();
        let vel = |i: usize| y[self.bodies[i].ix + 1];
        for (n, d) in self.dampers.iter().enumerate() {
            let w = vel(d.mass) - d.other.map_or(0.0, vel);
            p[at.dampers + n] = d.value * w * w;
        }
        for (k, c) in self.contacts.iter().enumerate() {
            if mode.contact(k) == Contact::Pressed {
                let (d, dd) = self.penetration(c, y);
                if !(c.stop.tension_free() && c.stop.bracket(d, dd) < 0.0) {
                    p[at.contacts + k] = c.stop.damping_power(d, dd);
                }
            }
        }
        let mut inner = [0.0; SCRATCH];
        let n = self.inner.terms.len();
        self.inner
            .power_terms(mode.without_contacts(), y, a, &mut inner[..n]);
        p[at.port..].copy_from_slice(&inner[INNER_PORT_TERMS..n]);
    }

    fn stored_energy(&self, mode: Mode, y: &SVector<f64, N>) -> f64 {
        self.energy_of(mode, y)
    }

    fn source_work(&self, y: &SVector<f64, N>) -> f64 {
        self.inner.bias_work(y)
    }

    fn book_switch(
        &self,
        from: Mode,
        to: Mode,
        before: &SVector<f64, N>,
        after: &SVector<f64, N>,
        book: &mut [f64],
    ) {
        let at = self.term_at;
        let same_contacts = (0..self.contacts.len()).all(|k| from.contact(k) == to.contact(k));
        if same_contacts && from.without_contacts() != to.without_contacts() {
            // A circuit's switch: the port's books.
            let mut inner = [0.0; SCRATCH];
            let n = self.inner.terms.len();
            self.inner.book(
                from.without_contacts(),
                to.without_contacts(),
                before,
                after,
                &mut inner[..n],
            );
            book[at.projections] += inner[INNER_PROJECTIONS];
            for (b, i) in book[at.port..].iter_mut().zip(&inner[INNER_PORT_TERMS..n]) {
                *b += i;
            }
            return;
        }
        let dropped = self.energy_of(from, before) - self.energy_of(to, after);
        if from == to {
            match self.nearest_rigid(before) {
                Some(k) => book[at.contacts + k] += dropped,
                None => book[at.projections] += dropped,
            }
            return;
        }
        let k = (0..self.contacts.len())
            .find(|&k| from.contact(k) != to.contact(k))
            .unwrap_or(0);
        match SwitchKind::of_contact(from.contact(k), to.contact(k)) {
            SwitchKind::Clip => match at.clip {
                Some(i) if from.contact(k) == Contact::Pressed => book[i] += dropped,
                Some(i) => book[i + 1] -= dropped,
                None => book[at.projections] += dropped,
            },
            SwitchKind::Stick => book[at.contacts + k] += dropped,
            _ => book[at.projections] += dropped,
        }
    }

    fn outputs(&self, mode: Mode, y: &SVector<f64, N>, out: &mut [f64]) {
        self.inner.outputs(mode.without_contacts(), y, out);
        let first = self.inner.layout.outputs.len();
        for (i, b) in self.bodies.iter().enumerate() {
            if first + i < out.len() && first + i < crate::model::MAX_OUTPUTS {
                out[first + i] = y[b.ix];
            }
        }
    }
}

//! What the circuit reads of its element's port ([`super::element`]): the port's voltage that
//! drives the bridge, its elastance and its voltage's rate with no current, the projection a
//! conduction holds it at, the energy it stores, the charge the bias source has moved, and the
//! scales of its state components.

use nalgebra::SVector;

use super::bridge::{Circuit, CircuitKind};
use super::element::{Element, PairState};
use crate::laws::pair::CapacitorPair;

impl Circuit {
    /// A pair's node voltages and capacitances.
    #[inline(always)]
    pub(super) fn pair<const N: usize>(&self, p: &CapacitorPair, y: &SVector<f64, N>) -> PairState {
        let z = SVector::<f64, 4>::new(y[0], y[1], y[self.e], y[self.e + 1]);
        let el = p.electrical(&z);
        let a = p.capacitance_slopes(y[0]);
        PairState {
            v: el.v,
            d: [el.c[0] + p.cp + p.cl, el.c[1] + p.cp + p.cl],
            a,
        }
    }

    /// The port's voltage that drives the bridge: `Vp`, `V1 - V2`, or the coil's EMF `Phi v`.
    #[inline(always)]
    pub fn drive_voltage<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        match self.element {
            Element::Piezo { .. } => y[self.e],
            Element::Coil { phi, .. } => phi * y[1],
            Element::Pair(p) => {
                let ps = self.pair(&p, y);
                ps.v[0] - ps.v[1]
            }
        }
    }

    /// A capacitive port's elastance `S` (V/C) and its voltage's rate with no port current
    /// (V/s; a pair's node loads still drain it), for the ideal bridge's constraint (see the
    /// module docs).
    #[inline]
    pub(super) fn elastance_and_open_rate<const N: usize>(
        &self,
        y: &SVector<f64, N>,
    ) -> (f64, f64) {
        match self.element {
            Element::Piezo { theta, cp } => (1.0 / cp, -theta * y[1] / cp),
            Element::Pair(p) => {
                let ps = self.pair(&p, y);
                // dV_i/dt with no port current: the motion's -a_i v (V_i - Vb) / D_i and the
                // node's own load draining it, -(V_i / R_L) / D_i.
                let r1 = -(ps.a[0] * y[1] * (ps.v[0] - p.vb) + ps.v[0] / p.rl) / ps.d[0];
                let r2 = -(ps.a[1] * y[1] * (ps.v[1] - p.vb) + ps.v[1] / p.rl) / ps.d[1];
                (1.0 / ps.d[0] + 1.0 / ps.d[1], r1 - r2)
            }
            Element::Coil { .. } => (0.0, 0.0),
        }
    }

    /// Puts a capacitive port's voltage at the conduction threshold `s (Vs + 2 V_F)` (a
    /// projection within the event tolerance): the piezo's voltage is set, the pair's charge
    /// moved from one electrode to the other.
    pub(super) fn project<const N: usize>(&self, s: f64, y: &mut SVector<f64, N>) {
        let target = s * (y[self.vs] + self.path_drop());
        match self.element {
            Element::Piezo { .. } => y[self.e] = target,
            Element::Pair(_) => {
                let (el, _) = self.elastance_and_open_rate(y);
                let dq = (self.drive_voltage(y) - target) / el;
                y[self.e] -= dq;
                y[self.e + 1] += dq;
            }
            Element::Coil { .. } => {}
        }
    }

    /// Energy on the element's capacitance (against a pair's bias) or in the coil (J).
    pub(super) fn element_energy<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        match self.element {
            Element::Piezo { cp, .. } => 0.5 * cp * y[self.e] * y[self.e],
            Element::Coil { l, .. } => 0.5 * l * y[self.e] * y[self.e],
            Element::Pair(p) => {
                let z = SVector::<f64, 4>::new(y[0], y[1], y[self.e], y[self.e + 1]);
                let el = p.electrical(&z);
                let mut e = 0.0;
                for i in 0..2 {
                    let u = el.v[i] - p.vb;
                    e += 0.5 * (el.c[i] + p.cp) * u * u + 0.5 * p.cl * el.v[i] * el.v[i];
                }
                e
            }
        }
    }

    /// The charge a pair's bias source has delivered (C); zero for the others.
    pub fn source_charge<const N: usize>(&self, y: &SVector<f64, N>) -> f64 {
        match self.element {
            Element::Pair(p) => {
                let z = SVector::<f64, 4>::new(y[0], y[1], y[self.e], y[self.e + 1]);
                let el = p.electrical(&z);
                (0..2).map(|i| (el.c[i] + p.cp) * (p.vb - el.v[i])).sum()
            }
            _ => 0.0,
        }
    }

    /// The bias voltage of a pair (V); zero otherwise.
    pub fn bias_v(&self) -> f64 {
        match self.element {
            Element::Pair(p) => p.vb,
            _ => 0.0,
        }
    }

    /// The scales of the element's components and of the storage voltage, for a displacement
    /// scale `x` and velocity scale `v`, written into `sc`.
    pub fn scales<const N: usize>(&self, x: f64, v: f64, sc: &mut SVector<f64, N>) {
        match self.element {
            Element::Piezo { theta, cp } => {
                sc[self.e] = theta * x / cp;
                sc[self.vs] = theta * x / cp;
                if let Some(inductor) = self.kind.inductor() {
                    inductor.scale(cp, sc[self.e], sc);
                }
            }
            Element::Coil { phi, rc, l } => {
                let w = v / x;
                sc[self.e] = phi * v / (rc + 2.0 * self.ron() + w * l);
                sc[self.vs] = phi * v;
            }
            Element::Pair(p) => {
                let q = p.c0 * p.vb.max(1.0) * x / p.length_scale();
                sc[self.e] = q;
                sc[self.e + 1] = q;
                sc[self.vs] = q / (p.c0 + p.cp + p.cl);
            }
        }
    }
}

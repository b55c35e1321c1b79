//! How far an orbit reaches towards each of its model's contacts over a period: the largest
//! approach coordinate of each contact (the position of the mass towards a stop to the frame,
//! or the relative position of two masses towards a stop between them, signed so that it
//! grows towards the contact) and the speed at which each rigid contact is struck. The
//! grazing distance of contact `k` is its reach less its gap; for a rigid contact struck, its
//! impact speed says how deep the orbit is past grazing (a rigid contact is never
//! penetrated).
//!
//! An orbit that strikes a rigid contact can approach it again between its strikes without
//! touching it: the highest such approach (a local maximum of the approach coordinate short of
//! the gap, its free peak) less the gap reaches zero where one more strike per period begins,
//! a grazing bifurcation that changes the number of impacts and not the set of contacts
//! touched (Nordmark, J. Sound Vib. 145, 1991). The reach counts the strikes of each rigid
//! contact and keeps the slowest, the measure of how deep the newest strike is past that
//! grazing.

use nalgebra::SVector;

use crate::model::{ContactGeometry, Layout, MAX_CONTACTS};
use crate::ode::Step;

/// The approach coordinate of a contact and its rate at a state: `side * x_mass` for a stop
/// to the frame, `side * (x_other - x_mass)` for a stop between two masses (m, m/s).
fn approach(c: &ContactGeometry, layout: &Layout, y: &[f64]) -> (f64, f64) {
    let (x, v) = relative(c, layout, y);
    (c.side * x, c.side * v)
}

/// The unsigned relative position and velocity of a contact's masses (the mass's own to the
/// frame): the quantities whose extrema bound the approach coordinate.
fn relative(c: &ContactGeometry, layout: &Layout, y: &[f64]) -> (f64, f64) {
    let (ix, iv) = layout.masses[c.mass];
    match c.other {
        None => (y[ix], y[iv]),
        Some(o) => {
            let (ox, ov) = layout.masses[o];
            (y[ox] - y[ix], y[ov] - y[iv])
        }
    }
}

/// The reach of each contact of a model over a period (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactReach {
    /// How many contacts are measured (the first `len` entries, in the order of
    /// [`crate::model::Model::contacts`]).
    pub len: usize,
    /// Largest approach coordinate of each contact over the period (m).
    pub reach_m: [f64; MAX_CONTACTS],
    /// Largest speed at which each rigid contact is struck (m/s), zero where it is not.
    pub impact_speed_m_s: [f64; MAX_CONTACTS],
    /// Highest local maximum of each contact's approach coordinate short of its gap (m): the
    /// highest approach that does not touch it; negative infinity where there is none.
    pub free_peak_m: [f64; MAX_CONTACTS],
    /// Strikes of each rigid contact over the period.
    pub strikes: [u32; MAX_CONTACTS],
    /// Smallest speed at which each rigid contact is struck (m/s), infinite where it is not.
    pub slowest_strike_m_s: [f64; MAX_CONTACTS],
}

impl Default for ContactReach {
    fn default() -> Self {
        Self::new(0)
    }
}

impl ContactReach {
    /// Nothing seen yet for `len` contacts (at most [`MAX_CONTACTS`]).
    pub fn new(len: usize) -> Self {
        Self {
            len: len.min(MAX_CONTACTS),
            reach_m: [f64::NEG_INFINITY; MAX_CONTACTS],
            impact_speed_m_s: [0.0; MAX_CONTACTS],
            free_peak_m: [f64::NEG_INFINITY; MAX_CONTACTS],
            strikes: [0; MAX_CONTACTS],
            slowest_strike_m_s: [f64::INFINITY; MAX_CONTACTS],
        }
    }

    /// Takes the state `y` (laid out as `layout`) into the reach of `contacts`.
    pub(crate) fn see(&mut self, contacts: &[ContactGeometry], layout: &Layout, y: &[f64]) {
        for (k, c) in contacts.iter().take(self.len).enumerate() {
            self.reach_m[k] = self.reach_m[k].max(approach(c, layout, y).0);
        }
    }

    /// Takes one step into the reach: its ends and, where a contact's relative velocity
    /// changes sign inside it, the extremum located on the dense output by `root` (which
    /// returns the fraction of the step at which the given function of the state vanishes);
    /// a maximum of the approach short of the gap is a free peak. A strike ends a step (the
    /// velocity jumps between two steps), so that it is never taken for a free peak.
    pub(crate) fn see_step<const N: usize>(
        &mut self,
        contacts: &[ContactGeometry],
        layout: &Layout,
        st: &Step<SVector<f64, N>>,
        root: impl Fn(&dyn Fn(&SVector<f64, N>) -> f64) -> Option<f64>,
    ) {
        self.see(contacts, layout, st.y0.as_slice());
        self.see(contacts, layout, st.y1.as_slice());
        for (k, c) in contacts.iter().take(self.len).enumerate() {
            let v0 = relative(c, layout, st.y0.as_slice()).1;
            let v1 = relative(c, layout, st.y1.as_slice()).1;
            if (v0 > 0.0) != (v1 > 0.0) {
                if let Some(th) = root(&|y| relative(c, layout, y.as_slice()).1) {
                    let x = approach(c, layout, st.at_theta(th).as_slice()).0;
                    self.reach_m[k] = self.reach_m[k].max(x);
                    let maximum = c.side * v0 > 0.0;
                    if maximum && x < c.gap {
                        self.free_peak_m[k] = self.free_peak_m[k].max(x);
                    }
                }
            }
        }
    }

    /// Books a strike of a rigid contact at the state `y` just before it: the rigid contact
    /// nearest its gap that the state approaches.
    pub(crate) fn strike(&mut self, contacts: &[ContactGeometry], layout: &Layout, y: &[f64]) {
        let struck = contacts
            .iter()
            .take(self.len)
            .enumerate()
            .filter(|(_, c)| c.rigid())
            .map(|(k, c)| (k, approach(c, layout, y)))
            .filter(|(_, (_, rate))| *rate > 0.0)
            .max_by(|(ka, (xa, _)), (kb, (xb, _))| {
                (xa - contacts[*ka].gap).total_cmp(&(xb - contacts[*kb].gap))
            });
        if let Some((k, (_, rate))) = struck {
            self.impact_speed_m_s[k] = self.impact_speed_m_s[k].max(rate);
            self.slowest_strike_m_s[k] = self.slowest_strike_m_s[k].min(rate);
            self.strikes[k] += 1;
        }
    }

    /// How far past grazing each contact is (m), for the contacts' gaps `gap_m` (in the
    /// order of the reach): its reach less its gap, or for a rigid contact struck, its impact
    /// speed over `w0_rad_s` (both vanish at grazing and are positive while the orbit touches
    /// it); negative infinity past the measured contacts.
    pub fn grazing_m(&self, gap_m: &[f64], w0_rad_s: f64) -> [f64; MAX_CONTACTS] {
        let mut out = [f64::NEG_INFINITY; MAX_CONTACTS];
        for (k, gap) in gap_m.iter().take(self.len).enumerate() {
            let speed = self.impact_speed_m_s[k];
            out[k] = if speed > 0.0 {
                speed / w0_rad_s
            } else {
                self.reach_m[k] - gap
            };
        }
        out
    }

    /// How far an orbit's newest strike of contact `k` is past the grazing at which it begins,
    /// for an orbit that strikes it `strikes` times a period on the side before that grazing:
    /// its free peak less the gap `gap_m` (negative, zero at the grazing) while it strikes it
    /// `strikes` times, the slowest strike's speed over `w0_rad_s` (positive, zero at the grazing)
    /// once it strikes it once more; `None` for any other count of strikes.
    pub fn strike_grazing_m(
        &self,
        k: usize,
        strikes: u32,
        gap_m: f64,
        w0_rad_s: f64,
    ) -> Option<f64> {
        let n = *self.strikes.get(k)?;
        if n == strikes {
            Some(self.free_peak_m[k] - gap_m)
        } else if n == strikes + 1 {
            Some(self.slowest_strike_m_s[k] / w0_rad_s)
        } else {
            None
        }
    }
}

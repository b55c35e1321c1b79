//! The harvester of several masses: a [`Model`](crate::model::Model) of a device file with
//! `[[masses]]` ([`crate::device::masses`]).
//!
//! Mechanics: each mass `i` obeys `m_i x_i'' = m_i a(t) - sum springs - sum dampers - sum
//! contact forces (+ F_e on the transducer's mass)`, every displacement relative to the frame,
//! a spring's force `k d + k3 d^3` on its extension `d` (`k3` zero for a linear spring).
//! A device with a `drive_mass` ([`crate::device::Masses::drive_mass`]) is driven by a force
//! `m_j a(t)` on that mass alone, the frame still: the drive term `m_i a` is then mass `j`'s.
//! A spring or damper between masses `i` and `j` acts on `x_i - x_j`; a stop between them is
//! met where `s (x_i - x_j) = gap` (`s` = +1 upper, -1 lower), a stop to the frame where
//! `s x_i = gap`.
//!
//! # State
//! The transducer's mass comes first (its position and velocity at 0 and 1), then the port's
//! components exactly as in the one-mass [`Harvester`] (so that the port's code is the one
//! mass's, unchanged), then each other mass's position and velocity in file order. The layout
//! names each component after its mass (`x_driver`, `v_driver`); the outputs are the port's
//! (`v1`, `v2` with their loads, or `vs`, `v_element`) followed by each mass's position.
//!
//! # Contacts
//! Each stop is one contact of the [`Mode`], with guards `2k` (its
//! boundary) and `2k + 1` (a tension-free bracket, or the holding force while resting) as a
//! one-mass stop's; every contact is watched at once. An impact on a rigid stop between two
//! masses conserves momentum and sets the relative velocity to `-e` times itself:
//! `v_i+ = v_i - (1 + e) m_j / (m_i + m_j) w`, `v_j+ = v_j + (1 + e) m_i / (m_i + m_j) w`,
//! `w = v_i - v_j`. Impacts that accumulate (chattering) end as a one-mass stop's do: when the
//! relative rebound could rise no higher than [`STICK_HEIGHT_REL`] of the displacement scale
//! under the relative acceleration pressing the contact shut, the contact rests
//! (`Contact::Resting`): a mass on a frame stop stands still, two masses move as one body (their
//! common velocity the momentum's) until the force that holds them together changes sign, when
//! they leave from the contact's surface (projected onto it, as an impact is). One
//! contact rests at a time: a second contact that chatters while another rests rebounds on
//! (the integrator then ends with its smallest step, a named error).
//!
//! The transducer's port (its loads, or an interface circuit) is the one-mass harvester's
//! [`Port`], evaluated through an inner [`Harvester`] of the transducer's mass with no
//! suspension and no stops: its forces, rates, Jacobian, guards, switches, ledger terms and
//! stored energy are that harvester's.

mod affine;
mod model;

use nalgebra::SVector;

use crate::device::Device;
use crate::laws::contact::StopModel;
use crate::laws::suspension::Spring;
use crate::model::{Contact, Layout, LedgerTerm, Load, Mode};

use super::port::Port;
use super::stops::FrameStops;
use super::{AssemblyError, Harvester};

pub use super::STICK_HEIGHT_REL;

/// Most masses a model has (the device file's bound).
pub const MAX_MASSES: usize = crate::device::masses::MAX_MASSES;

/// One mass in the state.
#[derive(Debug, Clone, PartialEq)]
pub struct ChainBody {
    /// Its name in the device file.
    pub name: String,
    /// Its mass (kg).
    pub mass_kg: f64,
    /// The index of its position in the state (its velocity's is the next).
    pub ix: usize,
}

/// A spring or damper between masses of the state (indices in state order).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChainLink {
    /// The mass.
    pub mass: usize,
    /// The other mass, if any.
    pub other: Option<usize>,
    /// Stiffness (N/m) or damping (N s/m).
    pub value: f64,
    /// A spring's cubic stiffness (N/m^3), zero for a linear spring and a damper.
    pub cubic_n_per_m3: f64,
    /// Its name (ledger terms).
    pub(crate) label: usize,
}

/// A stop of the model (masses in state order).
#[derive(Debug, Clone, PartialEq)]
pub struct ChainContact {
    /// The mass that meets the stop.
    pub mass: usize,
    /// The other mass, if the stop is between two.
    pub other: Option<usize>,
    /// +1 upper, -1 lower.
    pub sign: f64,
    /// The stop.
    pub stop: StopModel,
    /// Its name, e.g. `stop_driver_generator_upper`.
    pub name: String,
}

/// The model of a device of several masses (see the module docs), with a state of `N`
/// components.
#[derive(Debug, Clone, PartialEq)]
pub struct MassChain<const N: usize> {
    /// The masses, in state order (the transducer's first).
    pub bodies: Vec<ChainBody>,
    /// The springs.
    pub springs: Vec<ChainLink>,
    /// The dampers.
    pub dampers: Vec<ChainLink>,
    /// The stops.
    pub contacts: Vec<ChainContact>,
    /// The mass a force drive acts on (state order); `None`: the frame's acceleration drives
    /// every mass.
    pub driven: Option<usize>,
    /// The transducer's mass with the port, no suspension and no stops.
    inner: Harvester<N>,
    /// The number of the port's components after the transducer's mass's two.
    port_dim: usize,
    /// The smallest positive natural frequency of the undamped masses and springs (rad/s),
    /// or 1 rad/s without any.
    omega: f64,
    /// The displacement scale (m): the smallest gap, or the static deflection under 1 g at
    /// `omega`.
    pub x_scale_m: f64,
    /// Relative rebounds that could rise no higher than this end at rest (m).
    pub stick_height_m: f64,
    layout: Layout,
    terms: Vec<LedgerTerm>,
    /// Index of the first contact term, of the projections' and of the port's first term.
    term_at: TermIndex,
    scales: SVector<f64, N>,
}

#[derive(Debug, Clone, Copy, PartialEq)]
struct TermIndex {
    dampers: usize,
    contacts: usize,
    clip: Option<usize>,
    projections: usize,
    port: usize,
}

/// The dimension of the state of a device of several masses.
pub fn chain_dimension(device: &Device, port: &Port) -> usize {
    let n = device.masses.as_ref().map_or(1, |m| m.bodies.len());
    port.dimension() + 2 * (n - 1)
}

impl<const N: usize> MassChain<N> {
    /// The model of a device of several masses; errs when the device has one mass or its
    /// parts need another dimension than `N`.
    pub fn new(device: &Device) -> Result<Self, AssemblyError> {
        let Some(m) = &device.masses else {
            return Err(AssemblyError::Unsupported {
                device: device.name.clone(),
                transducer: device.transducer.key().to_string(),
                interface: device.interface.key().to_string(),
                why: "a device of one mass assembles into `Harvester`".into(),
            });
        };
        let port = super::port_of(device)?;
        let needs = chain_dimension(device, &port);
        if needs != N {
            return Err(AssemblyError::Dimension {
                device: device.name.clone(),
                needs,
                asked: N,
            });
        }
        let n = m.bodies.len();
        let t = m.transducer_mass;
        // File index -> state order: the transducer's mass first, the others in file order.
        let order = |f: usize| match f.cmp(&t) {
            std::cmp::Ordering::Equal => 0,
            std::cmp::Ordering::Less => f + 1,
            std::cmp::Ordering::Greater => f,
        };
        let port_dim = port.dimension() - 2;
        let mut bodies: Vec<ChainBody> = Vec::with_capacity(n);
        for k in 0..n {
            let f = (0..n).find(|&f| order(f) == k).unwrap_or(0);
            bodies.push(ChainBody {
                name: m.bodies[f].name.clone(),
                mass_kg: m.bodies[f].mass_kg,
                ix: if k == 0 {
                    0
                } else {
                    2 + port_dim + 2 * (k - 1)
                },
            });
        }
        let links = |v: &[crate::device::Link]| -> Vec<ChainLink> {
            v.iter()
                .enumerate()
                .map(|(label, l)| ChainLink {
                    mass: order(l.mass),
                    other: l.other.map(order),
                    value: l.value,
                    cubic_n_per_m3: l.cubic_n_per_m3,
                    label,
                })
                .collect()
        };
        let springs = links(&m.springs);
        let dampers = links(&m.dampers);
        let contacts: Vec<ChainContact> = m
            .stops
            .iter()
            .map(|s| {
                let sign = s.side.sign();
                let side = if sign > 0.0 { "upper" } else { "lower" };
                let name = match s.other {
                    None => format!("stop_{}_{side}", m.bodies[s.mass].name),
                    Some(o) => {
                        format!("stop_{}_{}_{side}", m.bodies[s.mass].name, m.bodies[o].name)
                    }
                };
                ChainContact {
                    mass: order(s.mass),
                    other: s.other.map(order),
                    sign,
                    stop: StopModel::of(&s.stop),
                    name,
                }
            })
            .collect();
        let driven = m.drive_mass.map(order);
        let omega = slowest_frequency(&bodies, &springs);
        let x_scale_m = m.smallest_gap_m().unwrap_or(crate::G / (omega * omega));
        let mt = bodies[0].mass_kg;
        let mut inner = Harvester::<N> {
            mass_kg: mt,
            damping: 0.0,
            km: omega * omega * mt,
            spring: Spring::linear(omega * omega * mt),
            stops: FrameStops {
                upper: None,
                lower: None,
            },
            port,
            stick_height_m: STICK_HEIGHT_REL * x_scale_m,
            x_scale_m,
            layout: Layout::default(),
            terms: Vec::new(),
            scales: SVector::zeros(),
        };
        // The port's scales at the slowest frequency; the inner model has no suspension.
        inner.layout = inner.make_layout();
        inner.terms = inner.make_terms();
        inner.scales = inner.make_scales();
        inner.km = 0.0;
        inner.spring = Spring::linear(0.0);
        let mut h = Self {
            bodies,
            springs,
            dampers,
            contacts,
            driven,
            inner,
            port_dim,
            omega,
            x_scale_m,
            stick_height_m: STICK_HEIGHT_REL * x_scale_m,
            layout: Layout::default(),
            terms: Vec::new(),
            term_at: TermIndex {
                dampers: 1,
                contacts: 1,
                clip: None,
                projections: 1,
                port: 1,
            },
            scales: SVector::zeros(),
        };
        h.layout = h.make_layout();
        h.make_terms();
        let mut sc = h.inner.scales;
        for b in &h.bodies[1..] {
            sc[b.ix] = x_scale_m;
            sc[b.ix + 1] = omega * x_scale_m;
        }
        h.scales = sc;
        Ok(h)
    }

    /// The same model without stops.
    #[must_use]
    pub fn without_stops(&self) -> Self {
        let mut h = self.clone();
        h.contacts.clear();
        h
    }

    /// The inner one-mass harvester of the transducer's mass and its port.
    pub fn port_model(&self) -> &Harvester<N> {
        &self.inner
    }

    fn make_layout(&self) -> Layout {
        let inner = &self.inner.layout;
        let b0 = &self.bodies[0].name;
        let mut comps: Vec<(String, String)> = vec![
            (format!("x_{b0}"), "m".into()),
            (format!("v_{b0}"), "m/s".into()),
        ];
        for s in &inner.components[2..2 + self.port_dim] {
            comps.push((s.name.clone(), s.unit.clone()));
        }
        for b in &self.bodies[1..] {
            comps.push((format!("x_{}", b.name), "m".into()));
            comps.push((format!("v_{}", b.name), "m/s".into()));
        }
        let refs: Vec<(&str, &str)> = comps
            .iter()
            .map(|(a, b)| (a.as_str(), b.as_str()))
            .collect();
        let mut layout = Layout::new(&refs);
        layout.masses = self.bodies.iter().map(|b| (b.ix, b.ix + 1)).collect();
        let xs: Vec<String> = self
            .bodies
            .iter()
            .map(|b| format!("x_{}", b.name))
            .collect();
        let mut outputs: Vec<(&str, &str, Option<Load>)> = inner
            .outputs
            .iter()
            .map(|s| (s.name.as_str(), s.unit.as_str(), s.load))
            .collect();
        for x in &xs {
            if outputs.len() < crate::model::MAX_OUTPUTS {
                outputs.push((x.as_str(), "m", None));
            }
        }
        let mut layout = layout.with_outputs(&outputs);
        // The inner model's outputs come first, at the same indices.
        layout.zero_outputs = inner.zero_outputs.clone();
        layout
    }

    /// Relative position and velocity of a contact (`x_i - x_j`, `v_i - v_j`; the frame's at
    /// zero).
    #[inline(always)]
    fn relative(&self, c: &ChainContact, y: &SVector<f64, N>) -> (f64, f64) {
        let i = self.bodies[c.mass].ix;
        let (xj, vj) = c.other.map_or((0.0, 0.0), |o| {
            (y[self.bodies[o].ix], y[self.bodies[o].ix + 1])
        });
        (y[i] - xj, y[i + 1] - vj)
    }

    /// A contact's penetration and its rate (m, m/s).
    #[inline(always)]
    fn penetration(&self, c: &ChainContact, y: &SVector<f64, N>) -> (f64, f64) {
        let (u, w) = self.relative(c, y);
        (c.sign * u - c.stop.gap(), c.sign * w)
    }

    /// The bracket of a pressed compliant contact (N), clipped at zero when tension-free; zero
    /// in any other state.
    #[inline(always)]
    fn bracket(&self, c: &ChainContact, state: Contact, y: &SVector<f64, N>) -> f64 {
        if state != Contact::Pressed {
            return 0.0;
        }
        let (d, dd) = self.penetration(c, y);
        let b = c.stop.bracket(d, dd);
        if c.stop.tension_free() {
            b.max(0.0)
        } else {
            b
        }
    }

    /// The drive's force on each mass per unit drive acceleration (kg): `m_i` on every mass,
    /// or on the driven mass alone.
    pub(super) fn drive_masses(&self) -> [f64; MAX_MASSES] {
        let mut f = [0.0; MAX_MASSES];
        for (i, b) in self.bodies.iter().enumerate() {
            if self.driven.is_none_or(|j| j == i) {
                f[i] = b.mass_kg;
            }
        }
        f
    }

    /// The force on each mass (N) without the constraint of a resting contact: the drive
    /// ([`Self::drive_masses`] times `a`), the springs, the dampers, the pressed contacts and the port's force `fe` on the
    /// transducer's mass.
    fn forces(&self, mode: Mode, y: &SVector<f64, N>, a: f64, fe: f64) -> [f64; MAX_MASSES] {
        let mut f = self.drive_masses();
        f.iter_mut().for_each(|x| *x *= a);
        f[0] += fe;
        let pos = |i: usize| y[self.bodies[i].ix];
        let vel = |i: usize| y[self.bodies[i].ix + 1];
        for s in &self.springs {
            let d = pos(s.mass) - s.other.map_or(0.0, pos);
            let mut fs = s.value * d;
            if s.cubic_n_per_m3 != 0.0 {
                fs += s.cubic_n_per_m3 * d * d * d;
            }
            f[s.mass] -= fs;
            if let Some(o) = s.other {
                f[o] += fs;
            }
        }
        for s in &self.dampers {
            let d = vel(s.mass) - s.other.map_or(0.0, vel);
            f[s.mass] -= s.value * d;
            if let Some(o) = s.other {
                f[o] += s.value * d;
            }
        }
        for (k, c) in self.contacts.iter().enumerate() {
            let b = self.bracket(c, mode.contact(k), y);
            if b != 0.0 {
                f[c.mass] -= c.sign * b;
                if let Some(o) = c.other {
                    f[o] += c.sign * b;
                }
            }
        }
        f
    }

    /// The resting contact of a mode, if any.
    #[inline(always)]
    pub(super) fn resting(&self, mode: Mode) -> Option<usize> {
        if !mode.in_contact() {
            return None;
        }
        (0..self.contacts.len()).find(|&k| mode.contact(k) == Contact::Resting)
    }

    /// The force that holds a resting contact shut (N, positive while it holds), from the
    /// free forces `f`.
    fn holding(&self, k: usize, f: &[f64; MAX_MASSES]) -> f64 {
        let c = &self.contacts[k];
        let i = c.mass;
        match c.other {
            None => c.sign * f[i],
            Some(j) => {
                let (mi, mj) = (self.bodies[i].mass_kg, self.bodies[j].mass_kg);
                c.sign * (mj * f[i] - mi * f[j]) / (mi + mj)
            }
        }
    }

    /// The accelerations of the masses from their forces, a resting contact's constraint
    /// applied.
    pub(super) fn accelerations(&self, mode: Mode, f: &[f64; MAX_MASSES]) -> [f64; MAX_MASSES] {
        let mut acc = [0.0; MAX_MASSES];
        for (i, b) in self.bodies.iter().enumerate() {
            acc[i] = f[i] / b.mass_kg;
        }
        if let Some(k) = self.resting(mode) {
            let c = &self.contacts[k];
            match c.other {
                None => acc[c.mass] = 0.0,
                Some(j) => {
                    let i = c.mass;
                    let common = (f[i] + f[j]) / (self.bodies[i].mass_kg + self.bodies[j].mass_kg);
                    acc[i] = common;
                    acc[j] = common;
                }
            }
        }
        acc
    }

    /// Puts a contact's masses on its surface (the mass `mass` moves).
    fn project(&self, c: &ChainContact, y: &mut SVector<f64, N>) {
        let xj = c.other.map_or(0.0, |o| y[self.bodies[o].ix]);
        let ix = self.bodies[c.mass].ix;
        y[ix] = xj + c.sign * c.stop.gap();
        // Between two masses `(x_j + s gap) - x_j` may exceed the gap by a rounding: a
        // penetration left positive would fire the guard again at once and rebound the pair
        // back into the wall (chattering at one instant). Step inside by ulps until it is not.
        while self.penetration(c, y).0 > 0.0 {
            y[ix] = if c.sign > 0.0 {
                y[ix].next_down()
            } else {
                y[ix].next_up()
            };
        }
    }

    /// The rebound off rigid contact `k` with restitution `e`, and whether the contact then
    /// rests (see the module docs).
    fn rebound(&self, mode: Mode, k: usize, e: f64, y: &mut SVector<f64, N>, a: f64) -> bool {
        let c = &self.contacts[k];
        let (ii, mi) = (self.bodies[c.mass].ix + 1, self.bodies[c.mass].mass_kg);
        let other = c
            .other
            .map(|o| (self.bodies[o].ix + 1, self.bodies[o].mass_kg));
        match other {
            None => y[ii] *= -e,
            Some((jj, mj)) => {
                let w = y[ii] - y[jj];
                let total = mi + mj;
                y[ii] -= (1.0 + e) * mj / total * w;
                y[jj] += (1.0 + e) * mi / total * w;
            }
        }
        if self.resting(mode).is_some() {
            return false;
        }
        let fe = self.inner.port.force(mode.circuit(0), y);
        let f = self.forces(mode, y, a, fe);
        let (u, pressing) = match other {
            None => (y[ii].abs(), c.sign * f[c.mass] / mi),
            Some((jj, mj)) => {
                let j = c.other.unwrap_or(0);
                ((y[ii] - y[jj]).abs(), c.sign * (f[c.mass] / mi - f[j] / mj))
            }
        };
        if pressing > 0.0 && u * u <= 2.0 * pressing * self.stick_height_m {
            match other {
                None => y[ii] = 0.0,
                Some((jj, mj)) => {
                    let common = (mi * y[ii] + mj * y[jj]) / (mi + mj);
                    y[ii] = common;
                    y[jj] = common;
                }
            }
            true
        } else {
            false
        }
    }
}

/// The natural frequencies of a device's undamped masses on their linear springs (Hz,
/// increasing): the square roots of the positive eigenvalues of `M^-1/2 K M^-1/2`, over
/// `2 pi`. The stops and the transducer are left out (open contacts, no electrical
/// stiffness). Empty for a device of one mass, whose resonance is
/// [`crate::physics::linear::open_circuit_resonance_hz`].
///
/// ```
/// use endstop::device::Device;
/// use endstop::physics::harvester::masses::natural_frequencies_hz;
/// let d = Device::from_toml_str(
///     include_str!("../../../../data/examples/upconverter.toml"),
///     "upconverter.toml",
/// )?;
/// // A 20 Hz driver and a 200 Hz generator joined by nothing but a stop.
/// let f = natural_frequencies_hz(&d);
/// assert_eq!(f.len(), 2);
/// assert!((f[0] - 20.0).abs() < 0.01 && (f[1] - 200.0).abs() < 0.1);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn natural_frequencies_hz(device: &Device) -> Vec<f64> {
    let Some(m) = &device.masses else {
        return Vec::new();
    };
    let masses: Vec<f64> = m.bodies.iter().map(|b| b.mass_kg).collect();
    let springs: Vec<(usize, Option<usize>, f64)> = m
        .springs
        .iter()
        .map(|l| (l.mass, l.other, l.value))
        .collect();
    squared_frequencies(&masses, &springs)
        .into_iter()
        .map(|w2| w2.sqrt() / (2.0 * std::f64::consts::PI))
        .collect()
}

/// The smallest positive natural frequency of undamped masses on springs (rad/s)
/// ([`squared_frequencies`]); 1 rad/s when no spring holds any mode.
fn slowest_frequency(bodies: &[ChainBody], springs: &[ChainLink]) -> f64 {
    let masses: Vec<f64> = bodies.iter().map(|b| b.mass_kg).collect();
    let springs: Vec<(usize, Option<usize>, f64)> =
        springs.iter().map(|l| (l.mass, l.other, l.value)).collect();
    squared_frequencies(&masses, &springs)
        .first()
        .map_or(1.0, |w2| w2.sqrt())
}

/// The positive eigenvalues (increasing, (rad/s)^2) of `M^-1/2 K M^-1/2` for masses
/// `masses_kg` and springs `(mass, other mass or the frame, stiffness)`: the squared natural
/// frequencies of the undamped chain. Eigenvalues below `1e-12` of the matrix's largest entry
/// are the rigid-body modes of masses no spring holds, and are left out.
fn squared_frequencies(masses_kg: &[f64], springs: &[(usize, Option<usize>, f64)]) -> Vec<f64> {
    let n = masses_kg.len();
    let mut k = nalgebra::DMatrix::<f64>::zeros(n, n);
    for &(i, other, value) in springs {
        k[(i, i)] += value;
        if let Some(o) = other {
            k[(o, o)] += value;
            k[(i, o)] -= value;
            k[(o, i)] -= value;
        }
    }
    for i in 0..n {
        for j in 0..n {
            k[(i, j)] /= (masses_kg[i] * masses_kg[j]).sqrt();
        }
    }
    let scale = k.amax();
    let mut w2: Vec<f64> = k
        .symmetric_eigen()
        .eigenvalues
        .iter()
        .copied()
        .filter(|&l| l > 1e-12 * scale)
        .collect();
    w2.sort_by(f64::total_cmp);
    w2
}

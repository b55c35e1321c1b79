//! The harvester assembled from a device's parts: a [`Model`] whose state the parts decide.
//!
//! Mechanics (eq 7): `m x'' + b x' + F_s(x) + F_e + F_im = m a(t)`, where `F_s` is the
//! suspension's restoring force ([`crate::laws::suspension`]), `F_e` the transducer's
//! reaction through its port ([`port`]: the transducer's own loads, eqs 8-10 for the paper's
//! pair, or an interface circuit) and `F_im` the end-stop force ([`stops`], eqs 1-2). The state
//! is `(x, v)` followed by the port's components: two for a transducer with its loads (unused
//! ones held at zero), the element's and the storage voltage behind a circuit.
//!
//! The file reads better whole than split, although it is longer than most: most of it is the
//! one `impl Model for Harvester<N>`, whose methods each make the same three-way split
//! (mechanics, stops, port) over the harvester's private fields, and a reader checks each
//! method against its siblings (the guards against the switches, the Jacobian against the
//! right-hand side) on one page; splitting the impl across files would scatter that
//! comparison. The parts themselves live in the submodules.
//!
//! # Modes
//! Each stop is one contact of the [`Mode`] (see [`stops`]); a circuit owns the mode's bits of
//! circuit 0 (its bridge's conduction and the velocity's sign since the last extremum). The
//! guards are the contacts' four, then the circuit's one.
//!
//! # Rigid stops: impacts that accumulate
//! At a rigid stop the velocity is reset to `v+ = -e v-`. Under a net force `A m` pressing the
//! mass onto the stop, a rebound of speed `u` flies for `2u/A` and rises `u^2/(2A)`, so the
//! rebounds shrink geometrically and accumulate in finite time (chattering, `2 u /(A (1-e))`
//! for a constant force). The model ends such a sequence as the literature does (e.g. Nordmark
//! and Piiroinen, Nonlinear Dyn. 58, 2009, on complete chattering): when the rebound could rise
//! no higher than [`Harvester::stick_height_m`], the mass rests on the stop
//! ([`Contact::Resting`]) until the holding force changes sign. The position error of this
//! shortcut is below that height; the sequence it replaces would have lasted `2u/(A(1 - e))`.

/// The interface circuits the harvester's transducer can sit behind, reached from here too.
pub use crate::circuits;
mod flight;
mod ledger;
mod linearisation;
pub mod masses;
pub mod port;
pub mod stops;

use nalgebra::{SMatrix, SVector};

use crate::device::Device;
use crate::laws::contact::{Side, StopModel};
use crate::laws::suspension::{self, Spring};
use crate::model::{Contact, Layout, LedgerTerm, Load, Mode, Model, SwitchKind};
use crate::physics::transducer::TransducerModel;

use port::Port;
use stops::{contact_of, side_of, FrameStops};

/// The rebound height below which impacts on a rigid stop end at rest, relative to the
/// displacement scale ([`Harvester::x_scale_m`]).
pub const STICK_HEIGHT_REL: f64 = 1e-9;

/// The smallest time constant of an interface circuit accepted (a conduction mode's, the
/// storage's through its load), relative to the suspension's period.
pub const STIFF_LIMIT: f64 = 1e-5;

/// The guards of the stops: two for each of the two sides.
const STOP_GUARDS: usize = 4;

/// The harvester assembled from its parts (see the module docs), with a state of `N`
/// components.
#[derive(Debug, Clone, PartialEq)]
pub struct Harvester<const N: usize> {
    /// Proof mass m (kg).
    pub mass_kg: f64,
    /// Mechanical damping b (N s/m).
    pub damping: f64,
    /// Suspension stiffness km (N/m): the linear term `k1` of the restoring force (negative
    /// for a double well).
    pub km: f64,
    /// The restoring force's terms beyond `km x` and the reference well.
    pub spring: Spring,
    /// The stops.
    pub stops: FrameStops,
    /// The transducer and what it drives.
    pub port: Port,
    /// Rebounds on a rigid stop that could rise no higher than this end at rest (m).
    pub stick_height_m: f64,
    /// The displacement scale of tolerances and scaled coordinates (m): the smallest gap of
    /// the device's stops, or without stops the static deflection under 1 g, `g / w0^2`.
    pub x_scale_m: f64,
    layout: Layout,
    terms: Vec<LedgerTerm>,
    scales: SVector<f64, N>,
}

/// Why a device's parts do not assemble into a model.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum AssemblyError {
    /// The parts need a state of another dimension than the one asked for.
    #[error("device `{device}`: its parts need a state of {needs} components, not {asked}")]
    Dimension {
        /// The device.
        device: String,
        /// What the parts need.
        needs: usize,
        /// What was asked.
        asked: usize,
    },
    /// A conduction mode of the interface circuit is too stiff for the explicit integrator.
    #[error(
        "device `{device}`: a conduction mode's time constant {tau_s:e} s is below {limit:e} of \
         the suspension's period {period_s:e} s: the integrator would take more than 1e5 steps a \
         period; use interface.diode.on_resistance_ohm = 0 (ideal with a drop) or a larger one"
    )]
    Stiff {
        /// The device.
        device: String,
        /// The time constant (s).
        tau_s: f64,
        /// The suspension's period (s).
        period_s: f64,
        /// The smallest ratio accepted ([`STIFF_LIMIT`]).
        limit: f64,
    },
    /// The storage capacitor discharges through its DC load faster than the explicit
    /// integrator can follow.
    #[error(
        "device `{device}`: the storage's time constant through its load {tau_s:e} s \
         (interface.storage_capacitance_f times the load's resistance) is below {limit:e} of the \
         suspension's period {period_s:e} s: the integrator would take more than 1e5 steps a \
         period; use a larger storage capacitance or load resistance"
    )]
    StiffStorage {
        /// The device.
        device: String,
        /// The storage's time constant through its load (s).
        tau_s: f64,
        /// The suspension's period (s).
        period_s: f64,
        /// The smallest ratio accepted ([`STIFF_LIMIT`]).
        limit: f64,
    },
    /// A device of several masses asked of the one-mass model.
    #[error(
        "device `{device}` has {masses} masses: a model of one mass cannot take it (it \
         assembles into a chain of masses, `masses::MassChain`)"
    )]
    SeveralMasses {
        /// The device.
        device: String,
        /// Its number of masses.
        masses: usize,
    },
    /// A combination of parts that is not supported yet.
    #[error("device `{device}`: {transducer} behind {interface} is not supported yet ({why})")]
    Unsupported {
        /// The device.
        device: String,
        /// The transducer's kind.
        transducer: String,
        /// The interface's kind.
        interface: String,
        /// What is missing.
        why: String,
    },
}

impl From<AssemblyError> for crate::ode::SolverError {
    fn from(e: AssemblyError) -> Self {
        crate::ode::SolverError::Model(e.to_string())
    }
}

impl Harvester<4> {
    /// The model of a device's transducer with its own loads, its interface circuit left out:
    /// the linear theory's model ([`crate::physics::linear`]). A loaded transducer's state has
    /// four components, so this assembly cannot fail.
    pub fn with_own_loads(device: &Device) -> Self {
        Self::assemble(
            device,
            Port::Loaded(TransducerModel::of(&device.transducer)),
        )
    }
}

impl<const N: usize> Harvester<N> {
    /// The model of a device (at its bias voltage and end-stop options); errs when its parts
    /// need another dimension than `N` ([`dimension`] says which) or do not combine.
    pub fn new(device: &Device) -> Result<Self, AssemblyError> {
        if let Some(m) = &device.masses {
            return Err(AssemblyError::SeveralMasses {
                device: device.name.clone(),
                masses: m.bodies.len(),
            });
        }
        let port = port_of(device)?;
        if let Port::Circuit(c) = &port {
            let period_s = 2.0 * std::f64::consts::PI / device.suspension_omega_rad_s();
            let tau_s = c.conduction_time_constant_s();
            if tau_s < STIFF_LIMIT * period_s {
                return Err(AssemblyError::Stiff {
                    device: device.name.clone(),
                    tau_s,
                    period_s,
                    limit: STIFF_LIMIT,
                });
            }
            if let Some(tau_s) = c.storage_time_constant_s() {
                if tau_s.is_nan() || tau_s < STIFF_LIMIT * period_s {
                    return Err(AssemblyError::StiffStorage {
                        device: device.name.clone(),
                        tau_s,
                        period_s,
                        limit: STIFF_LIMIT,
                    });
                }
            }
        }
        if port.dimension() != N {
            return Err(AssemblyError::Dimension {
                device: device.name.clone(),
                needs: port.dimension(),
                asked: N,
            });
        }
        Ok(Self::assemble(device, port))
    }

    /// The model of a device's mechanics and stops with the port `port`, whose dimension is
    /// `N`.
    fn assemble(device: &Device, port: Port) -> Self {
        let m = &device.mechanics;
        let (km, spring) = if m.suspension.is_linear() {
            (m.stiffness_n_per_m, Spring::linear(m.stiffness_n_per_m))
        } else {
            let k = device.restoring_polynomial().0;
            let mut higher = [0.0; suspension::MAX_ORDER - 1];
            higher.copy_from_slice(&k[1..]);
            let well = super::statics::reference_well(device).map_or(0.0, |w| w.x_m);
            let s = Spring {
                higher,
                nonlinear: true,
                well_m: well,
                well_stiffness_n_per_m: m.stiffness_n_per_m,
            };
            (k[0], s)
        };
        // Without stops: the static deflection under 1 g, or a well's distance from rest.
        let x_scale_m = device
            .stops
            .smallest_gap_m()
            .unwrap_or((crate::G * m.mass_kg / m.stiffness_n_per_m).max(spring.well_m.abs()));
        let mut h = Self {
            mass_kg: m.mass_kg,
            damping: m.damping_n_s_per_m,
            km,
            spring,
            stops: FrameStops {
                upper: device.stops.upper.as_ref().map(StopModel::of),
                lower: device.stops.lower.as_ref().map(StopModel::of),
            },
            port,
            stick_height_m: STICK_HEIGHT_REL * x_scale_m,
            x_scale_m,
            layout: Layout::default(),
            terms: Vec::new(),
            scales: SVector::zeros(),
        };
        h.layout = h.make_layout();
        h.terms = h.make_terms();
        h.scales = h.make_scales();
        h
    }

    /// The same model without stops (its scales unchanged).
    #[must_use]
    pub fn without_stops(&self) -> Self {
        let mut h = self.clone();
        h.stops = FrameStops {
            upper: None,
            lower: None,
        };
        h
    }

    /// The stop on a side, if any.
    #[inline(always)]
    pub fn stop(&self, side: Side) -> Option<&StopModel> {
        self.stops.stop(side)
    }

    /// The gap on a side (m); infinite without a stop.
    #[inline(always)]
    pub fn gap(&self, side: Side) -> f64 {
        self.stops.gap(side)
    }

    /// Penetration delta into the stop on `side` (m; negative when not touching).
    #[inline(always)]
    pub fn penetration(&self, side: Side, x: f64) -> f64 {
        self.stops.penetration(side, x)
    }

    /// True when the device has a rigid (restitution) stop.
    pub fn has_rigid_stop(&self) -> bool {
        [self.stops.upper, self.stops.lower]
            .iter()
            .flatten()
            .any(|s| matches!(s, StopModel::Rigid { .. }))
    }

    /// The loaded transducer, if the port is one.
    pub fn transducer(&self) -> Option<&TransducerModel> {
        match &self.port {
            Port::Loaded(t) => Some(t),
            Port::Circuit(_) => None,
        }
    }

    /// The interface circuit, if the port is one.
    pub fn circuit(&self) -> Option<&circuits::Circuit> {
        match &self.port {
            Port::Circuit(c) => Some(c),
            Port::Loaded(_) => None,
        }
    }

    /// The suspension's restoring force `km x + F_higher(x)` (N, along +x on eq 7's left).
    #[inline(always)]
    pub fn restoring_force(&self, x: f64) -> f64 {
        self.km * x + self.spring.force(x)
    }

    /// The suspension's stiffness at `x` (N/m).
    #[inline(always)]
    pub fn restoring_stiffness(&self, x: f64) -> f64 {
        self.km + self.spring.stiffness(x)
    }

    /// The suspension's potential energy at `x` (J), zero at rest.
    #[inline]
    pub fn suspension_energy(&self, x: f64) -> f64 {
        0.5 * self.km * x * x + self.spring.energy(x)
    }

    /// The small-oscillation stiffness at the reference well (N/m): `km` for a linear
    /// suspension.
    #[inline]
    pub fn well_stiffness(&self) -> f64 {
        if self.spring.nonlinear {
            self.spring.well_stiffness_n_per_m
        } else {
            self.km
        }
    }

    /// The state at position `x` and velocity `v` with the transducer at its static
    /// equilibrium: a pair's node voltages zero (s_i = -(C_i - C0) Vb), a piezoelectric
    /// voltage, a coil current or a storage voltage zero.
    pub fn static_state_at(&self, x: f64, v: f64) -> SVector<f64, N> {
        let mut y = SVector::<f64, N>::zeros();
        y[0] = x;
        y[1] = v;
        let pair = match &self.port {
            Port::Loaded(TransducerModel::Pair(p)) => Some(*p),
            Port::Circuit(c) => match c.element {
                circuits::Element::Pair(p) => Some(p),
                _ => None,
            },
            Port::Loaded(_) => None,
        };
        if let Some(p) = pair {
            let el = p.electrical(&port::head(&y));
            y[2] = -(el.c[0] - p.c0) * p.vb;
            y[3] = -(el.c[1] - p.c0) * p.vb;
        }
        y
    }

    /// The state at rest in the reference well: the point the free flight is linearised
    /// about.
    pub fn well_state(&self) -> SVector<f64, N> {
        self.static_state_at(self.spring.well_m, 0.0)
    }

    /// The force that presses the mass onto the stop on `side` when it rests there (N, along
    /// the stop's outward direction): the drive, the suspension and the transducer.
    #[inline]
    pub fn holding_force(&self, side: Side, bits: u8, y: &SVector<f64, N>, a: f64) -> f64 {
        let fe = self.port.force(bits, y);
        side.sign() * (self.mass_kg * a - self.damping * y[1] - self.restoring_force(y[0]) + fe)
    }

    /// Where a rebound off the rigid stop on `side` (at the stop, with the velocity before the
    /// impact `y[1]`) leads: the state after, and whether the mass rests on the stop.
    fn rebound(
        &self,
        side: Side,
        restitution: f64,
        bits: u8,
        y: &mut SVector<f64, N>,
        a: f64,
    ) -> bool {
        y[1] *= -restitution;
        let u = y[1].abs();
        // The acceleration that presses the mass onto the stop.
        let acc = self.holding_force(side, bits, y, a) / self.mass_kg;
        if acc > 0.0 && u * u <= 2.0 * acc * self.stick_height_m {
            y[1] = 0.0;
            true
        } else {
            false
        }
    }

    fn make_layout(&self) -> Layout {
        let mut names: Vec<(&str, &str)> = vec![("x", "m"), ("v", "m/s")];
        let outputs: Vec<(&str, &str, Option<Load>)> = match &self.port {
            Port::Loaded(t) => {
                let (a, b) = match t {
                    TransducerModel::Pair(_) => (("s1", "C"), ("s2", "C")),
                    TransducerModel::Piezo { .. } => (("v", "V"), ("unused", "")),
                    TransducerModel::Electromagnetic { .. } => (("i", "A"), ("unused", "")),
                    TransducerModel::None => (("unused", ""), ("unused", "")),
                };
                names.push(a);
                names.push(b);
                let r = Some(Load::Resistor(t.load_resistance()));
                vec![("v1", "V", r), ("v2", "V", r)]
            }
            Port::Circuit(c) => {
                match c.element {
                    circuits::Element::Pair(_) => {
                        names.push(("s1", "C"));
                        names.push(("s2", "C"));
                    }
                    circuits::Element::Piezo { .. } => names.push(("vp", "V")),
                    circuits::Element::Coil { .. } => names.push(("i", "A")),
                }
                names.push(("vs", "V"));
                if circuits::CircuitKind::inductor(&c.kind).is_some() {
                    names.push(("i_inductor", "A"));
                }
                let load = match c.sink {
                    circuits::Sink::Resistor(r) => Some(Load::Resistor(r)),
                    circuits::Sink::Battery(vb, r) => Some(Load::Battery(vb, r)),
                    circuits::Sink::Open => None,
                };
                vec![("vs", "V", load), ("v_element", "V", None)]
            }
        };
        let mut layout = Layout::new(&names);
        layout.components[1].name = "v_mass".into();
        let mut layout = layout.with_outputs(&outputs);
        // Without a transducer both load voltages are zero whatever the state.
        if matches!(&self.port, Port::Loaded(TransducerModel::None)) {
            layout.zero_outputs = vec![0, 1];
        }
        layout
    }

    fn make_scales(&self) -> SVector<f64, N> {
        let w0 = self.omega_rad_s();
        let x = self.x_scale_m;
        let mut sc = SVector::<f64, N>::repeat(1.0);
        sc[0] = x;
        sc[1] = w0 * x;
        match &self.port {
            Port::Loaded(t) => {
                let [e1, e2] = t.scales(x, w0 * x);
                sc[2] = e1;
                sc[3] = e2;
            }
            Port::Circuit(c) => {
                // The circuit's scales use the suspension's linear frequency.
                let w = (self.km / self.mass_kg).sqrt();
                sc[1] = w * x;
                c.scales(x, w * x, &mut sc);
            }
        }
        sc
    }
}

impl<const N: usize> Harvester<N> {
    /// The involution of the state under x -> -x (see [`Model::mirror`]): equal stops on both
    /// sides (or none), and a transducer odd in x: a pair's capacitors trade places (and so do
    /// its node charges), a piezoelectric voltage or coil current changes sign; behind a
    /// circuit the storage voltage keeps its sign.
    pub fn mirror_map(&self) -> Option<SMatrix<f64, N, N>> {
        if self.stops.upper != self.stops.lower {
            return None;
        }
        if self.spring.higher.iter().step_by(2).any(|k| *k != 0.0) {
            // An even power of the suspension (k2, k4, k6) breaks the symmetry.
            return None;
        }
        let mut s = SMatrix::<f64, N, N>::zeros();
        s[(0, 0)] = -1.0;
        s[(1, 1)] = -1.0;
        match &self.port {
            Port::Loaded(TransducerModel::Pair(_)) => {
                s[(2, 3)] = 1.0;
                s[(3, 2)] = 1.0;
            }
            Port::Loaded(
                TransducerModel::Piezo { .. } | TransducerModel::Electromagnetic { .. },
            ) => {
                s[(2, 2)] = -1.0;
                s[(3, 3)] = 1.0;
            }
            Port::Loaded(TransducerModel::None) => {
                s[(2, 2)] = 1.0;
                s[(3, 3)] = 1.0;
            }
            Port::Circuit(c) => match c.element {
                circuits::Element::Pair(_) => {
                    s[(c.e, c.e + 1)] = 1.0;
                    s[(c.e + 1, c.e)] = 1.0;
                    s[(c.vs, c.vs)] = 1.0;
                }
                _ => {
                    s[(c.e, c.e)] = -1.0;
                    s[(c.vs, c.vs)] = 1.0;
                    circuits::CircuitKind::mirror(&c.kind, &mut s);
                }
            },
        }
        Some(s)
    }
}

/// The dimensions a device's parts may need; a study is compiled for each.
pub const DIMENSIONS: [usize; 2] = [4, 5];

/// The dimensions a device of several masses may need ([`masses::MassChain`]): two masses
/// with a transducer and its own loads.
pub const CHAIN_DIMENSIONS: [usize; 1] = [6];

/// Evaluates `$body` with `$h` bound to the harvester assembled from `$device`, of the
/// dimension its parts need (one of [`DIMENSIONS`], or for a device of several masses one of
/// [`CHAIN_DIMENSIONS`], whose model is a [`masses::MassChain`]); the body's `Result` error
/// type must take an [`AssemblyError`] (`From`). A study written once over [`Model`] is called
/// on any device this way.
#[macro_export]
macro_rules! with_harvester {
    ($device:expr, |$h:ident| $body:expr) => {{
        let device: &$crate::device::Device = $device;
        match $crate::physics::harvester::dimension(device) {
            Ok(4) => match $crate::physics::harvester::Harvester::<4>::new(device) {
                Ok($h) => $body,
                Err(e) => Err(e.into()),
            },
            Ok(5) => match $crate::physics::harvester::Harvester::<5>::new(device) {
                Ok($h) => $body,
                Err(e) => Err(e.into()),
            },
            Ok(6) => match $crate::physics::harvester::masses::MassChain::<6>::new(device) {
                Ok($h) => $body,
                Err(e) => Err(e.into()),
            },
            Ok(n) => Err($crate::physics::harvester::AssemblyError::Dimension {
                device: device.name.clone(),
                needs: n,
                asked: 0,
            }
            .into()),
            Err(e) => Err(e.into()),
        }
    }};
}

/// The state's dimension a device's parts need.
pub fn dimension(device: &Device) -> Result<usize, AssemblyError> {
    let port = port_of(device)?;
    Ok(masses::chain_dimension(device, &port))
}

/// The port of a device: its transducer with its loads, or behind its interface circuit.
fn port_of(device: &Device) -> Result<Port, AssemblyError> {
    match circuit_of(device)? {
        Some(c) => Ok(Port::Circuit(c)),
        None => Ok(Port::Loaded(TransducerModel::of(&device.transducer))),
    }
}

/// The interface circuit of a device, if its interface names a kind: the kind's model from
/// its description (registered in [`circuits`]), refused where the kind cannot act on the
/// element.
fn circuit_of(device: &Device) -> Result<Option<circuits::Circuit>, AssemblyError> {
    use circuits::CircuitKind;
    let Some(kind) = device.interface.kind() else {
        return Ok(None);
    };
    let unsupported = |why: &str| AssemblyError::Unsupported {
        device: device.name.clone(),
        transducer: device.transducer.key().to_string(),
        interface: device.interface.key().to_string(),
        why: why.to_string(),
    };
    let (element, e_slots) = match TransducerModel::of(&device.transducer) {
        TransducerModel::Piezo { theta, cp, .. } => (circuits::Element::Piezo { theta, cp }, 1),
        TransducerModel::Electromagnetic { phi, rc, l, .. } => {
            (circuits::Element::Coil { phi, rc, l }, 1)
        }
        TransducerModel::Pair(p) => (circuits::Element::Pair(p), 2),
        TransducerModel::None => return Err(unsupported("there is no transducer to connect")),
    };
    let d = kind
        .model(&device.interface, 3 + e_slots)
        .map_err(unsupported)?;
    if let Some(why) = d.kind.refuses(&element) {
        return Err(unsupported(why));
    }
    Ok(Some(circuits::Circuit {
        element,
        diode: d.diode,
        cs: d.cs,
        sink: circuits::Sink::of(d.load),
        kind: d.kind,
        e: 2,
        vs: 2 + e_slots,
    }))
}

impl<const N: usize> Model<N> for Harvester<N> {
    fn layout(&self) -> &Layout {
        &self.layout
    }

    #[inline(always)]
    fn scales(&self) -> SVector<f64, N> {
        self.scales
    }

    /// The small-oscillation angular frequency at the reference well, `sqrt(k_well / m)`:
    /// `sqrt(km / m)` for a linear suspension.
    #[inline]
    fn omega_rad_s(&self) -> f64 {
        (self.well_stiffness() / self.mass_kg).sqrt()
    }

    #[inline(always)]
    fn guard_count(&self) -> usize {
        STOP_GUARDS + self.port.guard_count()
    }

    fn contact_guards(&self) -> usize {
        STOP_GUARDS
    }

    #[inline(always)]
    fn rhs(&self, mode: Mode, y: &SVector<f64, N>, a: f64) -> SVector<f64, N> {
        let mut d = SVector::<f64, N>::zeros();
        let fe = self.port.force_and_rates(mode.circuit(0), y, &mut d);
        if FrameStops::resting(mode).is_some() {
            return d;
        }
        let f = self.mass_kg * a - self.damping * y[1] - self.restoring_force(y[0]) + fe
            - self.stops.force(mode, y[0], y[1]);
        d[0] = y[1];
        d[1] = f / self.mass_kg;
        d
    }

    #[inline(always)]
    fn drive_column(&self, mode: Mode) -> SVector<f64, N> {
        let mut c = SVector::<f64, N>::zeros();
        if FrameStops::resting(mode).is_none() {
            c[1] = 1.0;
        }
        c
    }

    fn jacobian(&self, mode: Mode, y: &SVector<f64, N>) -> SMatrix<f64, N, N> {
        self.linearised(mode, y)
    }

    #[inline(always)]
    fn guards(&self, mode: Mode, y: &SVector<f64, N>, a: impl Fn() -> f64, g: &mut [f64]) {
        let bits = mode.circuit(0);
        self.stops.guards(
            mode,
            y[0],
            y[1],
            |side| self.holding_force(side, bits, y, a()),
            g,
        );
        if let Port::Circuit(c) = &self.port {
            let [p, q] = c.guards(circuits::CircuitMode::of(bits), y, &self.scales);
            g[STOP_GUARDS] = p.max(q);
        }
    }

    fn switch(&self, mode: Mode, index: usize, y: &mut SVector<f64, N>, a: f64) -> Mode {
        let bits = mode.circuit(0);
        if index >= STOP_GUARDS {
            let Port::Circuit(c) = &self.port else {
                return mode;
            };
            let (next, _) = c.switch(circuits::CircuitMode::of(bits), y, &self.scales);
            return mode.with_circuit(0, next.bits());
        }
        let k = index / 2;
        let side = side_of(k);
        match (mode.contact(k), index % 2) {
            (Contact::Apart, _) => {
                y[0] = side.sign() * self.gap(side);
                match self.stop(side) {
                    Some(&StopModel::Rigid { restitution, .. }) => {
                        if self.rebound(side, restitution, bits, y, a) {
                            mode.with_contact(k, Contact::Resting)
                        } else {
                            mode
                        }
                    }
                    _ => mode.with_contact(k, Contact::Pressed),
                }
            }
            (Contact::Pressed | Contact::Clipped, 0) => {
                y[0] = side.sign() * self.gap(side);
                mode.with_contact(k, Contact::Apart)
            }
            (Contact::Pressed, _) => mode.with_contact(k, Contact::Clipped),
            (Contact::Clipped, _) => mode.with_contact(k, Contact::Pressed),
            (Contact::Resting, _) => mode.with_contact(k, Contact::Apart),
        }
    }

    fn switch_kind(&self, from: Mode, index: usize, to: Mode) -> SwitchKind {
        if index >= STOP_GUARDS {
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
        if index >= STOP_GUARDS {
            let Port::Circuit(c) = &self.port else {
                return None;
            };
            let [conduction, extremum] =
                c.guards(circuits::CircuitMode::of(from.circuit(0)), y, &self.scales);
            if extremum < conduction {
                return None;
            }
            let mut g = SMatrix::<f64, N, N>::identity();
            c.reset_jacobian(y, &mut g);
            return Some(g);
        }
        let mut d = SMatrix::<f64, N, N>::identity();
        match self.switch_kind(from, index, to) {
            SwitchKind::Rebound => d[(1, 1)] = -self.stops.restitution(index),
            SwitchKind::Stick => d[(1, 1)] = 0.0,
            _ => return None,
        }
        Some(d)
    }

    fn without_contacts(&self) -> Self {
        self.without_stops()
    }

    fn contacts(&self) -> Vec<crate::model::ContactGeometry> {
        Side::BOTH
            .iter()
            .map(|&side| crate::model::ContactGeometry {
                mass: 0,
                other: None,
                side: side.sign(),
                gap: self.gap(side),
                restitution: match self.stop(side) {
                    Some(StopModel::Rigid { restitution, .. }) => Some(*restitution),
                    _ => None,
                },
            })
            .collect()
    }

    fn modes(&self) -> Vec<Mode> {
        let mut contacts = vec![Mode::FREE];
        for side in Side::BOTH {
            let k = contact_of(side);
            match self.stop(side) {
                Some(StopModel::Compliant { .. }) => {
                    contacts.push(Mode::FREE.with_contact(k, Contact::Pressed));
                    contacts.push(Mode::FREE.with_contact(k, Contact::Clipped));
                }
                Some(StopModel::Rigid { .. }) => {
                    contacts.push(Mode::FREE.with_contact(k, Contact::Resting))
                }
                None => {}
            }
        }
        let circuits: Vec<u8> = match &self.port {
            Port::Loaded(_) => vec![0],
            Port::Circuit(c) => {
                let mut v = Vec::new();
                for &bridge in c.bridges() {
                    for heading in [circuits::Heading::Up, circuits::Heading::Down] {
                        v.push(circuits::CircuitMode { bridge, heading }.bits());
                    }
                }
                v
            }
        };
        let mut out = Vec::with_capacity(contacts.len() * circuits.len());
        for &b in &circuits {
            for &c in &contacts {
                out.push(c.with_circuit(0, b));
            }
        }
        out
    }

    fn mode_of(&self, y: &SVector<f64, N>) -> Mode {
        let mut mode = Mode::FREE.with_circuit(0, self.port.mode_bits(y));
        for side in Side::BOTH {
            if self.penetration(side, y[0]) > 0.0
                && matches!(self.stop(side), Some(StopModel::Compliant { .. }))
            {
                mode = mode.with_contact(contact_of(side), Contact::Pressed);
            }
        }
        mode
    }

    fn check_state(&self, _mode: Mode, y: &SVector<f64, N>) -> Result<(), String> {
        match &self.port {
            Port::Loaded(t) => t.check(y[0], &port::head(y)),
            Port::Circuit(c) => match c.element {
                circuits::Element::Pair(p) => TransducerModel::Pair(p).check(y[0], &port::head(y)),
                _ => Ok(()),
            },
        }
    }

    fn unused(&self) -> &[usize] {
        self.port.unused()
    }

    fn mirror(&self) -> Option<SMatrix<f64, N, N>> {
        self.mirror_map()
    }

    fn ledger_terms(&self) -> &[LedgerTerm] {
        &self.terms
    }

    fn powers(&self, mode: Mode, y: &SVector<f64, N>, a: f64, p: &mut [f64]) {
        self.power_terms(mode, y, a, p)
    }

    fn stored_energy(&self, mode: Mode, y: &SVector<f64, N>) -> f64 {
        self.energy(mode, y)
    }

    fn source_work(&self, y: &SVector<f64, N>) -> f64 {
        self.bias_work(y)
    }

    fn book_switch(
        &self,
        from: Mode,
        to: Mode,
        before: &SVector<f64, N>,
        after: &SVector<f64, N>,
        book: &mut [f64],
    ) {
        self.book(from, to, before, after, book)
    }

    fn outputs(&self, mode: Mode, y: &SVector<f64, N>, out: &mut [f64]) {
        match &self.port {
            Port::Loaded(t) => {
                let el = t.electrical(&port::head(y));
                out[0] = el.v[0];
                out[1] = el.v[1];
            }
            Port::Circuit(c) => {
                out[0] = y[c.vs];
                out[1] = c.drive_voltage(y);
            }
        }
        let _ = mode;
    }

    fn rest_state(&self) -> SVector<f64, N> {
        SVector::zeros()
    }

    fn static_state(&self, x: f64, v: f64) -> SVector<f64, N> {
        self.static_state_at(x, v)
    }

    fn free_flight_is_linear(&self) -> bool {
        !self.spring.nonlinear
            && matches!(&self.port, Port::Loaded(t) if !matches!(t, TransducerModel::Pair(_)))
    }

    fn affine(&self, mode: Mode) -> Option<crate::model::Affine<N>> {
        self.affine_form(mode)
    }

    fn slow_time_constant_s(&self) -> Option<f64> {
        match &self.port {
            Port::Circuit(c) => c.storage_time_constant_s(),
            Port::Loaded(_) => None,
        }
    }

    fn flight<V: crate::model::FlightVisitor<N>>(&self, dt_s: f64, visitor: V) -> V::Output {
        self.visit_flight(dt_s, visitor)
    }
}

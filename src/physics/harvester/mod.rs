//! The lumped model of an impact-limited harvester (eqs 1-2 and 7-10, generalised).
//!
//! Mechanics (eq 7): `m x'' + b x' + km x + F_e + F_im = m a(t)`, where `F_e` is the
//! transducer's reaction ([`crate::physics::transducer`]; for the paper's comb pair, eqs 8-10)
//! and `F_im` the end-stop force ([`crate::physics::contact`]; eqs 1-2 for the paper's stops).
//! The state is `(x, v, e1, e2)` for every device; the transducer says which electrical
//! components are live.
//!
//! # Modes ([`Mode`])
//! * `Free`: between the stops. Its guards are the penetrations of the present stops.
//! * `Contact(side)`: pressed into a compliant stop. It leaves when the penetration returns
//!   to zero, or (tension-free) when the bracket of eq 1 turns negative (to `Clipped`).
//! * `Clipped(side)`: past a tension-free stop with its force clipped to zero; it re-engages
//!   when the bracket turns positive, and leaves when the penetration returns to zero.
//! * `Stuck(side)`: resting on a rigid stop. It leaves when the force that holds the mass
//!   there, `F_s = m a - km x + F_e` along the stop's direction, turns away from the stop.
//!
//! # Rigid stops: impacts that accumulate
//! At a rigid stop the velocity is reset to `v+ = -e v-`. Under a net force `A m` pressing the
//! mass onto the stop, a rebound of speed `u` flies for `2u/A` and rises `u^2/(2A)`, so the
//! rebounds shrink geometrically and accumulate in finite time (chattering, `2 u /(A (1-e))`
//! for a constant force). The model ends such a sequence as the literature does (e.g. Nordmark
//! and Piiroinen, Nonlinear Dyn. 58, 2009, on complete chattering): when the rebound could rise
//! no higher than [`Harvester::stick_height_m`], the mass sticks to the stop (`Stuck`) until
//! the holding force changes sign. The position error of this shortcut is below that height;
//! the sequence it replaces would have lasted `2u/(A(1 - e))`.
//!
//! The model's linearisation for the variational equations ([`Harvester::jacobian`],
//! [`reset_jacobian`]) is the submodule `linearisation`.

use nalgebra::SVector;

use crate::device::Device;
use crate::drive::Excitation;
use crate::ode::{HybridSystem, Options};
use crate::physics::contact::{Mode, Side, StopModel};
use crate::physics::suspension::{self, Spring};
use crate::physics::transducer::TransducerModel;
pub use crate::physics::transducer::{Electrical, State};

mod linearisation;
pub use linearisation::reset_jacobian;

/// The rebound height below which impacts on a rigid stop end in sticking, relative to the
/// displacement scale ([`Harvester::x_scale`]).
pub const STICK_HEIGHT_REL: f64 = 1e-9;

/// Guards of every mode: a stop's two in free flight, or a contact's leaving and clipping.
pub const GUARDS: usize = 3;

/// The harvester driven by an excitation: a [`HybridSystem`] of dimension 4.
#[derive(Debug, Clone)]
pub struct Harvester<E: Excitation> {
    /// Proof mass m (kg).
    pub mass_kg: f64,
    /// Mechanical damping b (N s/m).
    pub damping: f64,
    /// Suspension stiffness km (N/m): the linear term `k1` of the restoring force (negative
    /// for a double well).
    pub km: f64,
    /// The restoring force's terms beyond `km x` and the reference well
    /// ([`crate::physics::suspension`]).
    pub spring: Spring,
    /// The stop at x = +gap, if any.
    pub upper: Option<StopModel>,
    /// The stop at x = -gap, if any.
    pub lower: Option<StopModel>,
    /// The transducer.
    pub transducer: TransducerModel,
    /// Rebounds on a rigid stop that could rise no higher than this end in sticking (m).
    pub stick_height_m: f64,
    /// The displacement scale of tolerances and scaled coordinates (m): the smallest gap of
    /// the device's stops, or without stops the static deflection under 1 g, `g / w0^2`. It
    /// stays with the model when its stops are removed ([`Harvester::without_stops`]).
    pub x_scale_m: f64,
    /// The base acceleration.
    pub excitation: E,
}

/// What a mode switch is, for counting impacts and booking energy.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SwitchKind {
    /// The mass reaches a compliant stop (an impact begins).
    Impact,
    /// The mass bounces off a rigid stop (an impact).
    Rebound,
    /// The mass reaches a rigid stop and sticks to it (an impact).
    Stick,
    /// A tension-free contact unloads or re-engages.
    Clip,
    /// The mass leaves a stop.
    Release,
}

impl SwitchKind {
    /// True for the switches that are impacts.
    pub fn is_impact(self) -> bool {
        matches!(
            self,
            SwitchKind::Impact | SwitchKind::Rebound | SwitchKind::Stick
        )
    }

    /// The kind of a switch from `from` to `to`.
    pub fn of(from: Mode, to: Mode) -> Self {
        match (from, to) {
            (Mode::Free, Mode::Contact(_)) => SwitchKind::Impact,
            (Mode::Free, Mode::Free) => SwitchKind::Rebound,
            (Mode::Free, Mode::Stuck(_)) => SwitchKind::Stick,
            (Mode::Contact(_), Mode::Clipped(_)) | (Mode::Clipped(_), Mode::Contact(_)) => {
                SwitchKind::Clip
            }
            _ => SwitchKind::Release,
        }
    }
}

impl<E: Excitation> Harvester<E> {
    /// Builds the model of a device (at its bias voltage and end-stop options).
    pub fn new(device: &Device, excitation: E) -> Self {
        let m = &device.mechanics;
        let (km, spring) = if m.suspension.is_linear() {
            (m.stiffness_n_per_m, Spring::linear(m.stiffness_n_per_m))
        } else {
            let k = device.restoring_polynomial().0;
            let mut higher = [0.0; suspension::MAX_ORDER - 1];
            higher.copy_from_slice(&k[1..]);
            let well = device.reference_well().map_or(0.0, |w| w.x_m);
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
        Self {
            mass_kg: m.mass_kg,
            damping: m.damping_n_s_per_m,
            km,
            spring,
            upper: device.stops.upper.as_ref().map(StopModel::of),
            lower: device.stops.lower.as_ref().map(StopModel::of),
            transducer: TransducerModel::of(&device.transducer),
            stick_height_m: STICK_HEIGHT_REL * x_scale_m,
            x_scale_m,
            excitation,
        }
    }

    /// Replaces the excitation, keeping the device.
    pub fn with_excitation<F: Excitation>(&self, excitation: F) -> Harvester<F> {
        Harvester {
            mass_kg: self.mass_kg,
            damping: self.damping,
            km: self.km,
            spring: self.spring,
            upper: self.upper,
            lower: self.lower,
            transducer: self.transducer,
            stick_height_m: self.stick_height_m,
            x_scale_m: self.x_scale_m,
            excitation,
        }
    }

    /// The same model without stops (its scales unchanged).
    pub fn without_stops(&self) -> Self
    where
        E: Clone,
    {
        let mut h = self.clone();
        h.upper = None;
        h.lower = None;
        h
    }

    /// The stop on a side, if any.
    #[inline(always)]
    pub fn stop(&self, side: Side) -> Option<&StopModel> {
        match side {
            Side::Upper => self.upper.as_ref(),
            Side::Lower => self.lower.as_ref(),
        }
    }

    /// The gap on a side (m); infinite without a stop.
    #[inline(always)]
    pub fn gap(&self, side: Side) -> f64 {
        self.stop(side).map_or(f64::INFINITY, StopModel::gap)
    }

    /// True when the device has a rigid (restitution) stop.
    pub fn has_rigid_stop(&self) -> bool {
        [self.upper, self.lower]
            .iter()
            .flatten()
            .any(|s| matches!(s, StopModel::Rigid { .. }))
    }

    /// The rest state: x = v = 0 and every electrical component zero.
    pub fn rest_state(&self) -> State {
        State::zeros()
    }

    /// The state at position `x` and velocity `v` with the transducer at its static
    /// equilibrium: a pair's node voltages zero (s_i = -(C_i - C0) Vb), a piezoelectric
    /// voltage or a coil current zero.
    pub fn static_state(&self, x: f64, v: f64) -> State {
        match self.transducer {
            TransducerModel::Pair(p) => {
                let el = p.electrical(&State::new(x, v, 0.0, 0.0));
                State::new(x, v, -(el.c[0] - p.c0) * p.vb, -(el.c[1] - p.c0) * p.vb)
            }
            _ => State::new(x, v, 0.0, 0.0),
        }
    }

    /// Load voltages (and a pair's capacitances) at a state.
    #[inline]
    pub fn electrical(&self, y: &State) -> Electrical {
        self.transducer.electrical(y)
    }

    /// Load resistance (ohm; of each load for a pair).
    pub fn load_resistance(&self) -> f64 {
        self.transducer.load_resistance()
    }

    /// Penetration delta into the stop on `side` (m; negative when not touching, -inf
    /// without a stop).
    #[inline(always)]
    pub fn penetration(&self, side: Side, x: f64) -> f64 {
        side.sign() * x - self.gap(side)
    }

    /// The bracket of eq 1 for a side (N): the spring force plus the contact damping.
    #[inline(always)]
    pub fn contact_bracket(&self, side: Side, y: &State) -> f64 {
        match self.stop(side) {
            Some(s) => s.bracket(self.penetration(side, y[0]), side.sign() * y[1]),
            None => 0.0,
        }
    }

    /// End-stop force F_im of eq 1 in a mode (N, along +x, as in eq 7's left-hand side).
    #[inline(always)]
    pub fn endstop_force(&self, mode: Mode, y: &State) -> f64 {
        match mode {
            Mode::Contact(side) => {
                let b = self.contact_bracket(side, y);
                let tension_free = self.stop(side).is_some_and(StopModel::tension_free);
                let b = if tension_free { b.max(0.0) } else { b };
                side.sign() * b
            }
            _ => 0.0,
        }
    }

    /// The force that presses the mass onto the stop on `side` when it rests there (N, along
    /// the stop's outward direction): the drive, the suspension and the transducer.
    pub fn holding_force(&self, side: Side, t: f64, y: &State) -> f64 {
        let (fe, _) = self.transducer.force_and_rates(y);
        side.sign()
            * (self.mass_kg * self.excitation.accel(t)
                - self.damping * y[1]
                - self.restoring_force(y[0])
                + fe)
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

    /// The small-oscillation angular frequency at the reference well, `sqrt(k_well / m)`
    /// (rad/s): `sqrt(km / m)` for a linear suspension. It sets the model's time scales.
    #[inline]
    pub fn well_omega_rad_s(&self) -> f64 {
        (self.well_stiffness() / self.mass_kg).sqrt()
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

    /// The state at rest in the reference well (the transducer at its static equilibrium
    /// there): the point the free flight is linearised about.
    pub fn well_state(&self) -> State {
        self.static_state(self.spring.well_m, 0.0)
    }

    /// The displacement scale (m); see [`Harvester::x_scale_m`].
    pub fn x_scale(&self) -> f64 {
        self.x_scale_m
    }

    /// Characteristic scales of (x, v, e1, e2), used for absolute tolerances and Newton's
    /// scaled coordinates.
    pub fn scales(&self) -> State {
        let w0 = self.well_omega_rad_s();
        let x = self.x_scale();
        let [e1, e2] = self.transducer.scales(x, w0 * x);
        State::new(x, w0 * x, e1, e2)
    }

    /// Number of live state components (2 to 4): the rest stay zero.
    pub fn active_states(&self) -> usize {
        self.transducer.active_states()
    }

    /// Integrator options with relative tolerance `rtol` and absolute tolerances
    /// `rtol` times [`Harvester::scales`].
    pub fn solver_options(&self, rtol: f64) -> Options<State> {
        let w0 = self.well_omega_rad_s();
        Options {
            rtol,
            atol: self.scales() * rtol,
            h_max: 0.02 * 2.0 * std::f64::consts::PI / w0,
            // Absolute floor; the smallest step grows with |t| (`Options::min_step`).
            h_min: 1e-16,
            h_init: 1e-7,
            max_steps: 50_000_000,
            event_time_tol: 1e-14,
        }
    }

    /// Where a rebound off the rigid stop on `side` (at the stop, with the velocity before
    /// the impact `y[1]`) leads: the state after and the new mode.
    fn rebound(&self, side: Side, restitution: f64, t: f64, y: &mut State) -> Mode {
        y[1] *= -restitution;
        let u = y[1].abs();
        // The acceleration that presses the mass onto the stop.
        let a = self.holding_force(side, t, y) / self.mass_kg;
        if a > 0.0 && u * u <= 2.0 * a * self.stick_height_m {
            y[1] = 0.0;
            Mode::Stuck(side)
        } else {
            Mode::Free
        }
    }
}

impl<E: Excitation> HybridSystem for Harvester<E> {
    type State = State;
    type Mode = Mode;

    #[inline(always)]
    fn guard_count(&self) -> usize {
        GUARDS
    }

    #[inline]
    fn rhs(&self, mode: Mode, t: f64, y: &State) -> State {
        let (fe, rates) = self.transducer.force_and_rates(y);
        if let Mode::Stuck(_) = mode {
            return State::new(0.0, 0.0, rates[0], rates[1]);
        }
        let f = self.mass_kg * self.excitation.accel(t)
            - self.damping * y[1]
            - self.restoring_force(y[0])
            + fe
            - self.endstop_force(mode, y);
        State::new(y[1], f / self.mass_kg, rates[0], rates[1])
    }

    #[inline]
    fn guards(&self, mode: Mode, t: f64, y: &State, g: &mut [f64]) {
        g[..GUARDS].copy_from_slice(&self.guard_values(mode, t, y));
    }

    fn switch(&self, mode: Mode, index: usize, t: f64, y: &mut State) -> Mode {
        match (mode, index) {
            (Mode::Free, i) => {
                let side = if i == 0 { Side::Upper } else { Side::Lower };
                y[0] = side.sign() * self.gap(side);
                match self.stop(side) {
                    Some(&StopModel::Rigid { restitution, .. }) => {
                        self.rebound(side, restitution, t, y)
                    }
                    _ => Mode::Contact(side),
                }
            }
            (Mode::Contact(side), 0) | (Mode::Clipped(side), 0) => {
                y[0] = side.sign() * self.gap(side);
                Mode::Free
            }
            (Mode::Contact(side), _) => Mode::Clipped(side),
            (Mode::Clipped(side), _) => Mode::Contact(side),
            (Mode::Stuck(_), _) => Mode::Free,
        }
    }

    fn next_breakpoint(&self, t: f64) -> f64 {
        self.excitation.next_breakpoint(t)
    }

    fn check_state(&self, _mode: Mode, t: f64, y: &State) -> Result<(), String> {
        self.transducer
            .check(y[0], y)
            .map_err(|m| format!("at t = {t:e} s: {m}"))
    }
}

impl<E: Excitation> Harvester<E> {
    /// The guards of a mode (see the module docs); unused ones are `f64::NEG_INFINITY`.
    #[inline]
    pub fn guard_values(&self, mode: Mode, t: f64, y: &State) -> [f64; GUARDS] {
        const OFF: f64 = f64::NEG_INFINITY;
        match mode {
            Mode::Free => [
                self.penetration(Side::Upper, y[0]),
                self.penetration(Side::Lower, y[0]),
                OFF,
            ],
            Mode::Contact(side) => [
                -self.penetration(side, y[0]),
                if self.stop(side).is_some_and(StopModel::tension_free) {
                    -self.contact_bracket(side, y)
                } else {
                    OFF
                },
                OFF,
            ],
            Mode::Clipped(side) => [
                -self.penetration(side, y[0]),
                self.contact_bracket(side, y),
                OFF,
            ],
            Mode::Stuck(side) => [-self.holding_force(side, t, y), OFF, OFF],
        }
    }
}

impl<E: Excitation> Harvester<E> {
    /// The coefficient of restitution of the stop a switch out of free flight reaches
    /// through guard `index` (0 upper, 1 lower); zero for a compliant stop.
    pub fn restitution(&self, index: usize) -> f64 {
        let side = if index == 0 { Side::Upper } else { Side::Lower };
        match self.stop(side) {
            Some(&StopModel::Rigid { restitution, .. }) => restitution,
            _ => 0.0,
        }
    }
}

/// A state vector of any dimension with the model's state at its head, for the augmented
/// systems (variational equations, energy accumulators).
pub fn head<const M: usize>(z: &SVector<f64, M>) -> State {
    State::new(z[0], z[1], z[2], z[3])
}

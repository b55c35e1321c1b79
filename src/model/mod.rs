//! The model abstraction: one piecewise-smooth model of a harvester, which every study takes.
//!
//! A [`Model`] of dimension `N` is what a device's parts assemble into (mechanics, stops and
//! their contact laws, transducers, interface circuits; see
//! [`crate::physics::harvester::Harvester`]): it states the layout of its state ([`Layout`]),
//! its modes ([`Mode`]), its right-hand side and Jacobian in each mode, its guards (as many as
//! its parts need) and the resets at its switches with their Jacobians, the affine form of
//! every mode that is linear (for the exact propagators of [`crate::study::flow`] and the
//! records), the terms of its energy ledger, its state scales and its named outputs. Studies
//! are written once over it: a new part is a new implementation inside the model, never a fork
//! in a study.
//!
//! # The drive
//! A model is autonomous but for the base acceleration `a`, which every method that needs it
//! takes as an argument: the drive is the study's ([`crate::drive`]), and [`Driven`] joins a
//! model and a drive into the [`HybridSystem`](crate::ode::HybridSystem) the integrators step.
//! The drive enters the right-hand side linearly, through [`Model::drive_column`].
//!
//! # The state's dimension
//! `N` is a constant of the type: a study is compiled for the dimensions the device files
//! use, and the state, its Jacobian and its tangent map live on the stack. A state sized at
//! run time was measured on the hot path (Dormand-Prince on the paper's capacitor pair, four
//! components, the same steps and bits): 14 % more processor time (the performance chapter),
//! so the dimension is a constant.
//!
//! # Example
//! A bare oscillator with a rigid stop at `x = 1e-3` m, as a model of its own (the harvester
//! assembled from a device file is the usual one):
//!
//! ```
//! use endstop::model::{Contact, Driven, Layout, Mode, Model, SwitchKind};
//! use endstop::drive::Sine;
//! use endstop::ode::Dopri5;
//! use nalgebra::{SMatrix, SVector};
//!
//! struct Bouncer {
//!     layout: Layout,
//! }
//!
//! impl Model<2> for Bouncer {
//!     fn layout(&self) -> &Layout {
//!         &self.layout
//!     }
//!     fn scales(&self) -> SVector<f64, 2> {
//!         SVector::<f64, 2>::new(1e-3, 1.0)
//!     }
//!     fn omega_rad_s(&self) -> f64 {
//!         1000.0
//!     }
//!     fn guard_count(&self) -> usize {
//!         1
//!     }
//!     fn rhs(&self, _: Mode, y: &SVector<f64, 2>, a: f64) -> SVector<f64, 2> {
//!         SVector::<f64, 2>::new(y[1], a - 1e6 * y[0])
//!     }
//!     fn drive_column(&self, _: Mode) -> SVector<f64, 2> {
//!         SVector::<f64, 2>::new(0.0, 1.0)
//!     }
//!     fn jacobian(&self, _: Mode, _: &SVector<f64, 2>) -> SMatrix<f64, 2, 2> {
//!         SMatrix::<f64, 2, 2>::new(0.0, 1.0, -1e6, 0.0)
//!     }
//!     fn guards(&self, _: Mode, y: &SVector<f64, 2>, _a: impl Fn() -> f64, g: &mut [f64]) {
//!         g[0] = y[0] - 1e-3;
//!     }
//!     fn switch(&self, mode: Mode, _: usize, y: &mut SVector<f64, 2>, _a: f64) -> Mode {
//!         y[0] = 1e-3;
//!         y[1] *= -0.5;
//!         mode
//!     }
//!     fn switch_kind(&self, _: Mode, _: usize, _: Mode) -> SwitchKind {
//!         SwitchKind::Rebound
//!     }
//! }
//!
//! let model = Bouncer { layout: Layout::new(&[("x", "m"), ("v", "m/s")]) };
//! // 2 g at 200 Hz from rest: the mass reaches the stop and rebounds.
//! let sys = Driven::new(&model, Sine::from_rms_g(2.0 * 0.5f64.sqrt() * 1e3 / 9.81, 200.0));
//! let mut ode = Dopri5::new(0.0, SVector::zeros(), Mode::FREE, model.solver_options(1e-9));
//! ode.integrate(&sys, 0.05, |_, _| {})?;
//! assert!(ode.stats().events > 0);
//! assert!(ode.y()[0] <= 1e-3 + 1e-12);
//! assert_eq!(Mode::FREE.contact(0), Contact::Apart);
//! # Ok::<(), endstop::ode::SolverError>(())
//! ```
//!
//! The model of a device file is assembled by [`crate::with_harvester!`], which picks the
//! state's dimension the device's parts need and hands the body the model as `h`:
//!
//! ```
//! use endstop::device::Device;
//! use endstop::model::{Mode, Model};
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
//! let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
//! endstop::with_harvester!(&device, |h| {
//!     // The mass's position and velocity come first, then the piezoelectric voltage.
//!     let names: Vec<&str> = h.layout().components.iter().map(|c| c.name.as_str()).collect();
//!     assert_eq!(&names[..3], ["x", "v_mass", "v"]);
//!     let rest = h.rest_state();
//!     assert!(rest.iter().all(|c| *c == 0.0));
//!     // At rest the base acceleration alone accelerates the mass: dv/dt = a (eq 7).
//!     let a = 3.0;
//!     let dydt = h.rhs(Mode::FREE, &rest, a);
//!     assert_eq!((dydt[0], dydt[1], dydt[2]), (0.0, a, 0.0));
//!     // Moving at 1 mm/s with the element discharged, the voltage changes at -theta v / Cp
//!     // (2.67e-3 N/V and 50 nF in the file; Cp V' = -theta v - V / R, the force on the
//!     // mass being +theta V); the rounding of a few products bounds the relative error far
//!     // below 1e-12.
//!     let mut y = rest;
//!     y[1] = 1e-3;
//!     let dv_dt = h.rhs(Mode::FREE, &y, 0.0)[2];
//!     assert!((dv_dt / (-2.67e-3 * 1e-3 / 50e-9) - 1.0).abs() < 1e-12);
//!     Ok::<(), Box<dyn std::error::Error>>(())
//! })?;
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

mod driven;
mod flight;
mod layout;
pub mod ledger;
mod mode;
pub mod tangent;

use nalgebra::{SMatrix, SVector};

use crate::ode::Options;

pub use driven::Driven;
pub use flight::{FlightSplit, FlightVisitor, NoFlight, Remainder};
pub use layout::{Layout, Load, Slot, MAX_OUTPUTS};
pub use ledger::{Books, Ledger};
pub use mode::{Contact, Mode, SwitchKind, MAX_CIRCUITS, MAX_CONTACTS};

/// The state of a model of dimension `N`.
pub type StateN<const N: usize> = SVector<f64, N>;

/// An affine guard `n . y + g0` of an affine mode: it fires when it turns positive, as the
/// model's guard `index` (several pieces may stand for one guard, e.g. the two signs of a
/// bridge's conduction threshold).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AffineGuard<const N: usize> {
    /// The model's guard this piece stands for.
    pub index: usize,
    /// Gradient.
    pub n: SVector<f64, N>,
    /// Offset.
    pub g0: f64,
}

impl<const N: usize> AffineGuard<N> {
    /// The guard at a state.
    #[inline(always)]
    pub fn at(&self, y: &SVector<f64, N>) -> f64 {
        self.n.dot(y) + self.g0
    }

    /// Whether the guard is positive at `y` beyond the rounding of its own evaluation: the
    /// sum `n . y + g0` carries an error of at most `(N + 1) eps (sum |n_i y_i| + |g0|)`
    /// (Higham, Accuracy and Stability of Numerical Algorithms, 2nd ed., eq. 3.5), so a value
    /// within that bound of zero is zero. A state a switch has put exactly on the guard's
    /// threshold (a bridge's port voltage projected onto `Vs + 2 V_F`) then does not read as
    /// past it by a rounding error and switch back at once.
    #[inline]
    pub fn positive_beyond_rounding(&self, y: &SVector<f64, N>) -> bool {
        let g = self.at(y);
        if g <= 0.0 {
            return false;
        }
        let size: f64 = self
            .n
            .iter()
            .zip(y.iter())
            .map(|(n, y)| (n * y).abs())
            .sum();
        g > (N + 1) as f64 * f64::EPSILON * (size + self.g0.abs())
    }
}

/// A mode in which the model is affine: `y' = L y + c a + d`, with guards affine in the state.
#[derive(Debug, Clone, PartialEq)]
pub struct Affine<const N: usize> {
    /// `L`.
    pub l: SMatrix<f64, N, N>,
    /// `c`, the drive's column.
    pub c: SVector<f64, N>,
    /// `d`, the constant term.
    pub d: SVector<f64, N>,
    /// The guards that can fire in the mode.
    pub guards: Vec<AffineGuard<N>>,
}

/// A mode that is affine in the state and the drive together: `y' = L y + c a + d` as in
/// [`Affine`], with guards `n . y + drive[j] a + g0` (guard `j` of `affine.guards` plus
/// `drive[j]` times the drive). A resting contact's holding force is one: the drive's inertial
/// force presses a mass onto a frame stop or pulls it off, so its release depends on the drive
/// as well as on the state.
#[derive(Debug, Clone, PartialEq)]
pub struct DrivenAffine<const N: usize> {
    /// The mode's dynamics and the state's part of each guard.
    pub affine: Affine<N>,
    /// Each guard's coefficient on the drive (s^2 per m times the guard's unit).
    pub drive: Vec<f64>,
}

impl<const N: usize> From<Affine<N>> for DrivenAffine<N> {
    /// An affine mode whose guards do not depend on the drive.
    fn from(affine: Affine<N>) -> Self {
        let drive = vec![0.0; affine.guards.len()];
        Self { affine, drive }
    }
}

/// Where a contact is: between a mass and the frame (`other` none) or between two masses,
/// on the side `side` (+1: the mass's displacement, or `x_other - x_mass`, grows towards it;
/// -1: it shrinks towards it), `gap` away (m); a rigid contact (an instantaneous impact) has
/// its coefficient of restitution.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactGeometry {
    /// The mass (its index in [`Layout::masses`]).
    pub mass: usize,
    /// The other mass of a contact between two masses.
    pub other: Option<usize>,
    /// +1 or -1 (see the type's docs).
    pub side: f64,
    /// The gap (m).
    pub gap: f64,
    /// The coefficient of restitution of an instantaneous impact (never penetrated); `None`
    /// for a compliant contact.
    pub restitution: Option<f64>,
}

impl ContactGeometry {
    /// True for an instantaneous impact.
    pub fn rigid(&self) -> bool {
        self.restitution.is_some()
    }
}

/// What one energy-ledger term is (see [`Model::ledger_terms`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub enum Flow {
    /// Energy into the model (the drive's work, a bias source's).
    In,
    /// Energy out of it (dissipated, or delivered to a load).
    Out,
}

/// One term of a model's energy ledger: its name (a column name, in J when integrated) and
/// which way it flows.
#[derive(Debug, Clone, PartialEq, Eq, serde::Serialize)]
pub struct LedgerTerm {
    /// Name, e.g. `"drive"`, `"mech_damping"`, `"stop_upper_damping"`, `"load"`.
    pub name: String,
    /// In or out.
    pub flow: Flow,
}

/// A piecewise-smooth model of a harvester (see the module docs).
///
/// Every method is evaluated at a state `y` in a `mode`, with the base acceleration `a`
/// (m/s^2) where the drive matters. Guard `i` of a mode asks to leave it when it turns
/// positive; a mode that uses fewer guards than [`Model::guard_count`] fills the rest with
/// `f64::NEG_INFINITY`.
pub trait Model<const N: usize>: Send + Sync {
    /// The state's layout: each component's name and unit, the masses, the outputs.
    fn layout(&self) -> &Layout;

    /// Characteristic scales of the state's components: absolute tolerances are `rtol`
    /// times these, and Newton's method works in the coordinates `y / scales`.
    fn scales(&self) -> SVector<f64, N>;

    /// The angular frequency of the model's slowest small oscillation about its reference
    /// state (rad/s): it bounds the integrator's step.
    fn omega_rad_s(&self) -> f64;

    /// Number of guards (the same in every mode).
    fn guard_count(&self) -> usize;

    /// Number of the contacts' guards, which come first (the circuits' follow).
    fn contact_guards(&self) -> usize {
        self.guard_count()
    }

    /// The right-hand side in `mode` under the base acceleration `a`.
    fn rhs(&self, mode: Mode, y: &SVector<f64, N>, a: f64) -> SVector<f64, N>;

    /// `d rhs / d a` in `mode`: the drive's column (one on each moving mass's velocity).
    fn drive_column(&self, mode: Mode) -> SVector<f64, N>;

    /// The Jacobian `d rhs / d y` in `mode` (the drive enters additively and does not appear).
    fn jacobian(&self, mode: Mode, y: &SVector<f64, N>) -> SMatrix<f64, N, N>;

    /// The guards of `mode`, written into `g` (length [`Model::guard_count`]). The base
    /// acceleration comes from `a`, called only by a guard that depends on it (a mass resting
    /// on a stop), so that the drive is not evaluated at every probe of every step.
    fn guards(&self, mode: Mode, y: &SVector<f64, N>, a: impl Fn() -> f64, g: &mut [f64]);

    /// The switch when guard `index` of `mode` fires: the new mode, with `y` reset (and
    /// projected onto the guard's surface within the event tolerance).
    fn switch(&self, mode: Mode, index: usize, y: &mut SVector<f64, N>, a: f64) -> Mode;

    /// What the switch through guard `index` from `from` to `to` is.
    fn switch_kind(&self, from: Mode, index: usize, to: Mode) -> SwitchKind;

    /// The Jacobian of the switch's reset, `d y+ / d y-`, at the state `y` just before it;
    /// `None` when the state is continuous across it (a projection within the event
    /// tolerance is not differentiated).
    fn reset_jacobian(
        &self,
        _from: Mode,
        _index: usize,
        _to: Mode,
        _y: &SVector<f64, N>,
    ) -> Option<SMatrix<f64, N, N>> {
        None
    }

    /// True when the model off its contacts is linear and smooth (a linear transducer with its
    /// loads on a linear suspension): its free flight then has one periodic orbit under a
    /// sine, which attracts every state.
    fn free_flight_is_linear(&self) -> bool {
        false
    }

    /// A time constant of the model far longer than its mechanics' ring-up (s), such as a
    /// storage capacitor charging through its load, or `None`. A study that settles by
    /// integrating block after block cannot see such an approach end (two blocks differ by
    /// little while the state is still far from the orbit), so it first puts the state on the
    /// periodic orbit by shooting ([`crate::study::steady`]).
    fn slow_time_constant_s(&self) -> Option<f64> {
        None
    }

    /// The free flight split for the exponential integrator over steps of `dt_s`
    /// ([`FlightSplit`]), handed to `visitor` with its remainder's own type, so that the
    /// visitor's loop is compiled for it ([`FlightVisitor`]); the default offers none.
    fn flight<V: FlightVisitor<N>>(&self, _dt_s: f64, visitor: V) -> V::Output {
        visitor.refused(NoFlight::Unavailable)
    }

    /// The affine form of `mode`, or `None` where the mode is not affine (a nonlinear force, a
    /// guard that depends on the drive) or the model leaves it to the adaptive integrator.
    fn affine(&self, _mode: Mode) -> Option<Affine<N>> {
        None
    }

    /// The affine form of `mode` with guards that may depend on the drive ([`DrivenAffine`]):
    /// every mode of [`Model::affine`], and where the model has them modes such as a resting
    /// contact, whose release depends on the drive; the default is [`Model::affine`].
    fn driven_affine(&self, mode: Mode) -> Option<DrivenAffine<N>> {
        self.affine(mode).map(DrivenAffine::from)
    }

    /// The model's contacts, in the order of [`Mode::contact`] (contact `k` is the `k`-th; a
    /// slot the model does not use is absent from its modes and reported with an infinite
    /// gap).
    fn contacts(&self) -> Vec<ContactGeometry> {
        Vec::new()
    }

    /// The same model with its contacts removed (the smooth flow a grazing is located on);
    /// a model without contacts returns itself.
    fn without_contacts(&self) -> Self
    where
        Self: Sized + Clone,
    {
        self.clone()
    }

    /// Every mode the model can be in (for the exact propagators, which prepare each affine
    /// one before they start).
    fn modes(&self) -> Vec<Mode> {
        vec![Mode::FREE]
    }

    /// The mode a state starts in (contact past a compliant stop, a circuit's conduction).
    fn mode_of(&self, _y: &SVector<f64, N>) -> Mode {
        Mode::FREE
    }

    /// The state with the first mass at position `x` (m) and velocity `v` (m/s) and every
    /// other part at its static equilibrium there (a capacitor pair's node voltages zero, an
    /// element's voltage or current zero).
    fn static_state(&self, x: f64, v: f64) -> SVector<f64, N> {
        let mut y = SVector::zeros();
        y[0] = x;
        y[1] = v;
        y
    }

    /// The state at rest with every part at its static equilibrium.
    fn rest_state(&self) -> SVector<f64, N> {
        SVector::zeros()
    }

    /// Checks that a state is admissible (a capacitance positive, a gap open); the message
    /// says what failed.
    fn check_state(&self, _mode: Mode, _y: &SVector<f64, N>) -> Result<(), String> {
        Ok(())
    }

    /// The involution `S` of the state under the mirror `x -> -x` when the model has that
    /// symmetry (equal stops on both sides, a transducer odd in x): with the half-period shift
    /// of a sine, `a(t + T/2) = -a(t)`, it maps orbits to orbits. `None` without it.
    fn mirror(&self) -> Option<SMatrix<f64, N, N>> {
        None
    }

    /// Components the model holds at zero (a transducer's unused slot): their multipliers are
    /// trivial and studies drop them.
    fn unused(&self) -> &[usize] {
        &[]
    }

    /// The terms of the energy ledger, in the order [`Model::powers`] and
    /// [`Model::book_switch`] fill them.
    fn ledger_terms(&self) -> &[LedgerTerm] {
        &[]
    }

    /// The power of each continuous ledger term at a state (W, each as its term flows).
    fn powers(&self, _mode: Mode, _y: &SVector<f64, N>, _a: f64, _p: &mut [f64]) {}

    /// The energy stored in the model (J): kinetic, elastic, electric and magnetic.
    fn stored_energy(&self, _mode: Mode, _y: &SVector<f64, N>) -> f64 {
        0.0
    }

    /// The work of sources that are functions of the state (a bias source's `Vb q`) (J).
    fn source_work(&self, _y: &SVector<f64, N>) -> f64 {
        0.0
    }

    /// Books what a switch from `from` to `to` moved, `before` and `after` the states around
    /// it (the reset's losses and any change of the stored energy by a projection), added into
    /// `book` (J, each as its term flows; [`SwitchKind::between`] tells what the switch was).
    fn book_switch(
        &self,
        _from: Mode,
        _to: Mode,
        _before: &SVector<f64, N>,
        _after: &SVector<f64, N>,
        _book: &mut [f64],
    ) {
    }

    /// The model's named outputs at a state (their names in [`Layout::outputs`]).
    fn outputs(&self, _mode: Mode, _y: &SVector<f64, N>, _out: &mut [f64]) {}

    /// Integrator options with relative tolerance `rtol`: absolute tolerances `rtol` times
    /// [`Model::scales`], the largest step a fiftieth of the period of
    /// [`Model::omega_rad_s`].
    fn solver_options(&self, rtol: f64) -> Options<SVector<f64, N>> {
        Options {
            rtol,
            atol: self.scales() * rtol,
            h_max: 0.02 * 2.0 * std::f64::consts::PI / self.omega_rad_s(),
            // Absolute floor; the smallest step grows with |t| (`Options::min_step`).
            h_min: 1e-16,
            h_init: 1e-7,
            max_steps: 50_000_000,
            event_time_tol: 1e-14,
        }
    }
}

//! The interface circuits a transducer's port can sit behind: a diode bridge into a storage
//! capacitor and DC load ([`bridge`], its element [`element`] and what it reads of it [`port`], its modes [`mode`], its
//! linearisation [`jacobian`], its parts [`parts`]), and the kinds of circuit built on it,
//! each one file implementing [`CircuitKind`]:
//!
//! * [`instant`]: the plain bridge, and the synchronous switches acting in an instant at the
//!   displacement extrema (parallel and series SSHI, SECE);
//! * [`sece_inductor`]: a SECE whose transfer runs through its buck-boost inductor, the
//!   inductor current a state of its own;
//! * [`sshi_inductor`]: a parallel SSHI whose inversion rings through its inductor, the
//!   inductor current a state of its own.
//!
//! Each kind's file holds its description as well: its keys in the device's `[interface]`,
//! their checks and its model (`InterfaceKind`), in the words all kinds share
//! ([`description`]: the diodes, the DC load, the inversion). The device's description
//! ([`crate::device`]) holds an [`Interface`] and reads it through these; no circuit reads the
//! device. This file is the one registration point:
//! [`Interface`] names every description (a variant and the `InterfaceKind` that reads it)
//! and [`Kind`] every model. A new kind is a new file implementing [`CircuitKind`] and
//! `InterfaceKind`, and its line in each of the two lists below.

pub mod bridge;
pub mod description;
pub mod element;
pub mod instant;
pub mod jacobian;
pub mod mode;
pub mod parts;
pub mod port;
pub mod sece_inductor;
pub mod sshi_inductor;

use nalgebra::{SMatrix, SVector};

pub use bridge::{Circuit, CircuitKind};
pub use element::Element;
pub use instant::{FullBridge, ParallelSshi, Sece, SeriesSshi};
pub use mode::{Bridge, CircuitMode, Heading, ResetLoss};
pub use parts::{DiodeLaw, Inductor, Sink};
pub use sece_inductor::{BuckBoost, SeceInductor};
pub use sshi_inductor::Inverter;

pub use description::{DcLoad, Diode, Inversion, Rectifier};

use crate::check::{Checker, ParamError};
use crate::model::AffineGuard;
use description::{Keys, RESISTIVE};

/// Declares [`Interface`], a variant per registered description, each variant read, checked
/// and modelled by the [`InterfaceKind`] after its arrow.
macro_rules! descriptions {
    ($($(#[$doc:meta])* $variant:ident $shape:tt => $described:expr,)*) => {
        /// The interface circuit of a device's `[interface]` (see [`crate::device::interface`]).
        #[derive(Debug, Clone, PartialEq, Default)]
        pub enum Interface {
            /// The transducer's own resistive load.
            #[default]
            Resistive,
            $($(#[$doc])* $variant $shape,)*
        }

        impl Interface {
            /// Every registered kind's description, in the order of registration.
            pub(crate) const KINDS: &'static [&'static dyn InterfaceKind] = &[$(&$described),*];

            /// The description of this interface's kind; `None` for the resistive default.
            pub(crate) fn kind(&self) -> Option<&'static dyn InterfaceKind> {
                match self {
                    Interface::Resistive => None,
                    $(Interface::$variant { .. } => Some(&$described as &'static dyn InterfaceKind),)*
                }
            }
        }
    };
}

/// Declares [`Kind`], a variant per circuit model, and `each_kind!`, which evaluates a body
/// with the kind inside a [`Kind`] bound to a name (`$d` is a `$`, for the inner macro).
macro_rules! models {
    ($d:tt $($(#[$doc:meta])* $variant:ident($model:ty),)*) => {
        /// Every kind of interface circuit, each delegating to its own file's [`CircuitKind`].
        #[derive(Debug, Clone, Copy, PartialEq)]
        pub enum Kind {
            $($(#[$doc])* $variant($model),)*
        }

        /// Evaluates `$body` with `$k` bound to the kind inside `$kind` (a [`Kind`]).
        macro_rules! each_kind {
            ($d kind:expr, $d k:ident => $d body:expr) => {
                match $d kind {
                    $(Kind::$variant($d k) => $d body,)*
                }
            };
        }
    };
}

descriptions! {
    /// A full-wave diode bridge into a storage capacitor and a DC load.
    FullBridge(Rectifier) => instant::FullBridgeFile,
    /// The bridge with a parallel inverting switch.
    ParallelSshi(Rectifier, Inversion) => instant::ParallelSshiFile,
    /// The bridge behind a series inverting switch.
    SeriesSshi(Rectifier, Inversion) => instant::SeriesSshiFile,
    /// Synchronous electric charge extraction.
    Sece {
        /// Storage capacitance (F).
        storage_capacitance_f: f64,
        /// The DC load.
        load: DcLoad,
        /// Fraction of the extracted energy that reaches the storage.
        efficiency: f64,
    } => instant::SeceFile,
    /// Synchronous electric charge extraction through its buck-boost inductor (`kind =
    /// "sece"` with `inductance_h`).
    SeceInductor(SeceInductor) => sece_inductor::SeceInductorFile,
}

models! {
    $
    /// A plain full bridge.
    FullBridge(FullBridge),
    /// Parallel SSHI with an instantaneous inversion.
    ParallelSshi(ParallelSshi),
    /// Series SSHI with an instantaneous inversion.
    SeriesSshi(SeriesSshi),
    /// SECE with an instantaneous transfer.
    Sece(Sece),
    /// SECE through its buck-boost inductor.
    SeceInductor(BuckBoost),
    /// Parallel SSHI whose inversion rings through its inductor.
    SshiInductor(Inverter),
}

/// One kind of interface circuit as a device file describes it: the keys of its
/// `[interface]` table, their checks (each error naming its field), and the circuit model
/// they give. A kind's own file implements it; the registration point,
/// [`crate::circuits`], pairs it with its [`Interface`] variant.
pub(crate) trait InterfaceKind: Sync {
    /// The `kind` key.
    fn key(&self) -> &'static str;

    /// Whether a table with this kind's `kind` key describes this kind (kinds sharing a key
    /// are told apart by their other keys).
    fn claims(&self, _keys: &toml::Table) -> bool {
        true
    }

    /// That the kind takes `key` in the table `keys` (the error names the field).
    fn check_key(&self, keys: &toml::Table, key: &str, c: &Checker) -> Result<(), ParamError>;

    /// The interface the table describes, its keys checked by [`InterfaceKind::check_key`].
    fn parse(&self, keys: &toml::Table, c: &Checker) -> Result<Interface, ParamError>;

    /// The file keys of `i`, in the order the file writes them.
    fn write(&self, i: &Interface, keys: &mut Keys);

    /// The storage capacitance (F) and the DC load of `i`.
    fn storage<'a>(&self, i: &'a Interface) -> Option<(f64, &'a DcLoad)>;

    /// The DC load of `i`, to change.
    fn load_mut<'a>(&self, i: &'a mut Interface) -> Option<&'a mut DcLoad>;

    /// The rectifier of `i`, for a kind whose bridge has the file's diodes.
    fn rectifier<'a>(&self, _i: &'a Interface) -> Option<&'a Rectifier> {
        None
    }

    /// True for a kind whose switch acts on a piezoelectric element's clamped capacitance,
    /// which a coil or an electrostatic pair does not have.
    fn piezo_only(&self) -> bool {
        true
    }

    /// Checks the kind's own values of `i`, against the clamped capacitance (F) of a
    /// piezoelectric element where they depend on it (`None` for another transducer).
    fn validate(
        &self,
        _i: &Interface,
        _clamped_capacitance_f: Option<f64>,
        _c: &Checker,
    ) -> Result<(), ParamError> {
        Ok(())
    }

    /// Checks the diodes against the kind, after the checks every bridge's diodes take.
    fn check_diode(&self, _diode: &Diode, _c: &Checker) -> Result<(), ParamError> {
        Ok(())
    }

    /// The circuit model of `i`, the kind's own state component (an inductor's current) at
    /// `slot`, or why the description has none.
    fn model<'a>(&self, i: &'a Interface, slot: usize) -> Result<Described<'a>, &'static str>;
}

impl Interface {
    /// The `kind` key.
    pub fn key(&self) -> &'static str {
        self.kind().map_or(RESISTIVE, |k| k.key())
    }

    /// The device path of the load resistance behind this interface: the transducer's own
    /// `transducer.load_resistance_ohm` where no circuit kind stands between, the DC load's
    /// `interface.load.resistance_ohm` behind a circuit.
    pub fn load_resistance_path(&self) -> &'static str {
        self.kind().map_or("transducer.load_resistance_ohm", |_| {
            "interface.load.resistance_ohm"
        })
    }

    /// The storage capacitance (F), for every kind but `resistive`.
    pub fn storage_capacitance_f(&self) -> Option<f64> {
        self.kind()?.storage(self).map(|(cs, _)| cs)
    }

    /// The DC load, for every kind but `resistive`.
    pub fn load(&self) -> Option<&DcLoad> {
        self.kind()?.storage(self).map(|(_, load)| load)
    }

    /// The DC load to change, for every kind but `resistive`.
    pub fn load_mut(&mut self) -> Option<&mut DcLoad> {
        self.kind()?.load_mut(self)
    }

    /// A copy with another DC load resistance (a battery or open load becomes a resistor);
    /// the resistive interface is returned unchanged.
    pub fn with_load_resistance(&self, resistance_ohm: f64) -> Self {
        let mut i = self.clone();
        if let Some(load) = i.load_mut() {
            *load = DcLoad::Resistor { resistance_ohm };
        }
        i
    }
}

/// The circuit a device's `[interface]` describes, before its element is attached.
#[derive(Debug, Clone, Copy)]
pub struct Described<'a> {
    /// The bridge's diodes.
    pub diode: DiodeLaw,
    /// Storage capacitance Cs (F).
    pub cs: f64,
    /// The DC load.
    pub load: &'a DcLoad,
    /// The kind.
    pub kind: Kind,
}

impl CircuitKind for Kind {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        each_kind!(self, k => k.refuses(element))
    }

    fn inductor(&self) -> Option<Inductor> {
        each_kind!(self, k => k.inductor())
    }

    fn phases(&self) -> &'static [Bridge] {
        each_kind!(self, k => k.phases())
    }

    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        each_kind!(self, k => k.bridge_between_extrema())
    }

    #[inline(always)]
    fn acts_at_extrema(&self) -> bool {
        each_kind!(self, k => k.acts_at_extrema())
    }

    #[inline(always)]
    fn force_and_rates<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        rates: &mut SVector<f64, N>,
    ) -> f64 {
        each_kind!(self, k => k.force_and_rates(c, bridge, y, rates))
    }

    #[inline(always)]
    fn jacobian<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        m: f64,
        sc: &SVector<f64, N>,
        j: &mut SMatrix<f64, N, N>,
    ) {
        each_kind!(self, k => k.jacobian(c, bridge, y, m, sc, j))
    }

    #[inline(always)]
    fn diode_power<const N: usize>(&self, c: &Circuit, bridge: Bridge, y: &SVector<f64, N>) -> f64 {
        each_kind!(self, k => k.diode_power(c, bridge, y))
    }

    #[inline(always)]
    fn element_loss<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
    ) -> f64 {
        each_kind!(self, k => k.element_loss(c, bridge, y))
    }

    fn time_constant_s(&self, c: &Circuit) -> f64 {
        each_kind!(self, k => k.time_constant_s(c))
    }

    #[inline(always)]
    fn conduction_guard<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        y: &SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> f64 {
        each_kind!(self, k => k.conduction_guard(c, bridge, y, sc))
    }

    fn guard_piece<const N: usize>(
        &self,
        c: &Circuit,
        bridge: Bridge,
        index: usize,
    ) -> Option<AffineGuard<N>> {
        each_kind!(self, k => k.guard_piece(c, bridge, index))
    }

    fn switch<const N: usize>(
        &self,
        c: &Circuit,
        mode: CircuitMode,
        extremum: bool,
        y: &mut SVector<f64, N>,
        sc: &SVector<f64, N>,
    ) -> (CircuitMode, ResetLoss) {
        each_kind!(self, k => k.switch(c, mode, extremum, y, sc))
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        each_kind!(self, k => k.reset(c, cp, y))
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        cp: f64,
        y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        each_kind!(self, k => k.reset_jacobian(c, cp, y, g))
    }

    fn phase_of<const N: usize>(&self, c: &Circuit, y: &SVector<f64, N>) -> Bridge {
        each_kind!(self, k => k.phase_of(c, y))
    }

    fn mirror<const N: usize>(&self, s: &mut SMatrix<f64, N, N>) {
        each_kind!(self, k => k.mirror(s))
    }
}

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
//! This file is the one registration point: [`Kind`] names every kind and [`Kind::of`] maps a
//! device's `[interface]` to one. A new kind is a new file implementing [`CircuitKind`], a
//! variant here with its line in `each_kind!`, and its arm in [`Kind::of`].

pub mod bridge;
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
pub use sece_inductor::BuckBoost;
pub use sshi_inductor::Inverter;

use crate::device::{DcLoad, Interface, Inversion};
use crate::model::AffineGuard;

/// Every kind of interface circuit, each delegating to its own file's [`CircuitKind`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Kind {
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

/// Evaluates `$body` with `$k` bound to the kind inside `$kind` (a [`Kind`]).
macro_rules! each_kind {
    ($kind:expr, $k:ident => $body:expr) => {
        match $kind {
            Kind::FullBridge($k) => $body,
            Kind::ParallelSshi($k) => $body,
            Kind::SeriesSshi($k) => $body,
            Kind::Sece($k) => $body,
            Kind::SeceInductor($k) => $body,
            Kind::SshiInductor($k) => $body,
        }
    };
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

impl Kind {
    /// The circuit an interface describes, with a kind's own state component (an inductor's
    /// current) at `slot`; `None` for a resistive interface, or why the description has no
    /// model.
    pub fn of(interface: &Interface, slot: usize) -> Result<Option<Described<'_>>, &'static str> {
        /// The one inversion without a factor of its own: a series SSHI through its inductor.
        const RING: &str = "a series SSHI's inversion through its inductor is not modelled; \
                            give `inversion_factor` or `quality_factor`";
        /// The ideal rectifier of a SECE.
        const IDEAL: DiodeLaw = DiodeLaw::PiecewiseLinear { vf: 0.0, ron: 0.0 };
        let inductor = |l: f64, rl: f64| Inductor { l, rl, i: slot };
        let (diode, cs, load, kind) = match interface {
            Interface::Resistive => return Ok(None),
            Interface::FullBridge(r) => (
                DiodeLaw::of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Kind::FullBridge(FullBridge),
            ),
            Interface::ParallelSshi(
                r,
                Inversion::Inductor {
                    inductance_h,
                    resistance_ohm,
                },
            ) => (
                DiodeLaw::of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Kind::SshiInductor(Inverter {
                    inductor: inductor(*inductance_h, *resistance_ohm),
                }),
            ),
            Interface::ParallelSshi(r, g) => (
                DiodeLaw::of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Kind::ParallelSshi(ParallelSshi {
                    gamma: g.gamma().ok_or(RING)?,
                }),
            ),
            Interface::SeriesSshi(r, g) => (
                DiodeLaw::of(&r.diode),
                r.storage_capacitance_f,
                &r.load,
                Kind::SeriesSshi(SeriesSshi {
                    gamma: g.gamma().ok_or(RING)?,
                }),
            ),
            Interface::Sece {
                storage_capacitance_f,
                load,
                efficiency,
            } => (
                IDEAL,
                *storage_capacitance_f,
                load,
                Kind::Sece(Sece { eta: *efficiency }),
            ),
            Interface::SeceInductor(s) => (
                IDEAL,
                s.storage_capacitance_f,
                &s.load,
                Kind::SeceInductor(BuckBoost {
                    inductor: inductor(s.inductance_h, s.inductor_resistance_ohm),
                    vf: s.flyback_drop_v,
                }),
            ),
        };
        Ok(Some(Described {
            diode,
            cs,
            load,
            kind,
        }))
    }
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

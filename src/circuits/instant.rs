//! The circuit kinds whose switch acts in an instant: the plain full bridge, and the
//! synchronous switches at the displacement extrema on a piezoelectric element (Guyomar et
//! al. 2005, IEEE TUFFC 52 584; Lefeuvre et al. 2006, Sens. Actuators A 126 405):
//!
//! * parallel SSHI: `Vp -> -gamma Vp` (the LC half-cycle is instantaneous; its loss
//!   `(1 - gamma^2) Cp Vp^2 / 2` is a switching loss); the bridge conducts between extrema;
//! * series SSHI: the loop of `Cp`, the inductor, the bridge and `Cs` rings for half a cycle:
//!   its voltage `u = |Vp| - Vs - 2 V_F` (when positive) becomes `-gamma u`, moving the charge
//!   `q = (1 + gamma) u Cp Cs / (Cp + Cs)` from the element to the storage (`2 V_F q` is lost
//!   in the diodes, the rest of the drop is a switching loss); the element is open between
//!   extrema;
//! * SECE: `Vp -> 0` and `Cs Vs^2 / 2` gains `eta Cp Vp^2 / 2`; the element is open between
//!   extrema (its transfer resolved through the inductor in time is
//!   [`super::sece_inductor`]).
//!
//! A synchronous switch refuses the electrostatic pair: it acts on a piezoelectric element's
//! voltage only.
//!
//! Their descriptions (`full_bridge`, `parallel_sshi`, `series_sshi`, `sece` in a device's
//! `[interface]`) are here too: the keys each takes, their checks and the model they give. A
//! `parallel_sshi` with `inductance_h` rings through its inductor ([`super::sshi_inductor`]).

use nalgebra::{SMatrix, SVector};

use super::bridge::{Circuit, CircuitKind};
use super::description::{
    number, put, put_storage, rectifier, storage_and_load, takes, DcLoad, Diode, Inversion, Keys,
    Rectifier, SHOCKLEY_SCOPE,
};
use super::element::Element;
use super::mode::ResetLoss;
use super::parts::{DiodeLaw, Inductor};
use super::sshi_inductor::{self, Inverter};
use super::{Described, Interface, InterfaceKind, Kind};
use crate::check::{Checker, ParamError};

/// Why a synchronous switch refuses an element.
const PIEZO_ONLY: &str = "a synchronous switch acts on a piezoelectric element's voltage only";

/// The refusal of a synchronous switch.
fn piezo_only(element: &Element) -> Option<&'static str> {
    matches!(element, Element::Pair(_)).then_some(PIEZO_ONLY)
}

/// A plain full bridge: no switch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FullBridge;

impl CircuitKind for FullBridge {
    #[inline(always)]
    fn acts_at_extrema(&self) -> bool {
        false
    }
}

/// A parallel SSHI with its inversion factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParallelSshi {
    /// gamma.
    pub gamma: f64,
}

impl CircuitKind for ParallelSshi {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        piezo_only(element)
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let e = c.e;
        let en = 0.5 * cp * y[e] * y[e];
        y[e] *= -self.gamma;
        ResetLoss {
            diode: 0.0,
            switching: en * (1.0 - self.gamma * self.gamma),
        }
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        _cp: f64,
        _y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        g[(c.e, c.e)] = -self.gamma;
    }
}

/// A series SSHI with its inversion factor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SeriesSshi {
    /// gamma.
    pub gamma: f64,
}

impl CircuitKind for SeriesSshi {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        piezo_only(element)
    }

    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        false
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let (e, ivs, gamma) = (c.e, c.vs, self.gamma);
        let s = y[e].signum();
        let u = s * y[e] - y[ivs] - c.path_drop();
        if u <= 0.0 {
            return ResetLoss::default();
        }
        let ceff = cp * c.cs / (cp + c.cs);
        let q = (1.0 + gamma) * u * ceff;
        y[e] -= s * q / cp;
        y[ivs] += q / c.cs;
        ResetLoss {
            diode: c.path_drop() * q,
            switching: 0.5 * ceff * u * u * (1.0 - gamma * gamma),
        }
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        cp: f64,
        y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        let (e, ivs) = (c.e, c.vs);
        let s = y[e].signum();
        if s * y[e] - y[ivs] - c.path_drop() > 0.0 {
            // q = (1 + gamma) ceff (s Vp - Vs - 2 V_F); Vp -= s q / Cp, Vs += q / Cs.
            let k = (1.0 + self.gamma) * cp * c.cs / (cp + c.cs);
            g[(e, e)] = 1.0 - k / cp;
            g[(e, ivs)] = s * k / cp;
            g[(ivs, e)] = s * k / c.cs;
            g[(ivs, ivs)] = 1.0 - k / c.cs;
        }
    }
}

/// A SECE with its efficiency.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sece {
    /// eta.
    pub eta: f64,
}

impl CircuitKind for Sece {
    fn refuses(&self, element: &Element) -> Option<&'static str> {
        piezo_only(element)
    }

    #[inline(always)]
    fn bridge_between_extrema(&self) -> bool {
        false
    }

    fn reset<const N: usize>(&self, c: &Circuit, cp: f64, y: &mut SVector<f64, N>) -> ResetLoss {
        let (e, ivs) = (c.e, c.vs);
        let en = 0.5 * cp * y[e] * y[e];
        y[ivs] = (y[ivs] * y[ivs] + 2.0 * self.eta * en / c.cs).sqrt();
        y[e] = 0.0;
        ResetLoss {
            diode: 0.0,
            switching: (1.0 - self.eta) * en,
        }
    }

    fn reset_jacobian<const N: usize>(
        &self,
        c: &Circuit,
        cp: f64,
        y: &SVector<f64, N>,
        g: &mut SMatrix<f64, N, N>,
    ) {
        let (e, ivs, eta) = (c.e, c.vs, self.eta);
        let vs = (y[ivs] * y[ivs] + eta * cp * y[e] * y[e] / c.cs).sqrt();
        g[(e, e)] = 0.0;
        if vs > 0.0 {
            g[(ivs, e)] = eta * cp * y[e] / (c.cs * vs);
            g[(ivs, ivs)] = y[ivs] / vs;
        }
    }
}

/// The ideal rectifier of a converter whose losses its own keys state (a SECE).
pub(super) const IDEAL: DiodeLaw = DiodeLaw::PiecewiseLinear { vf: 0.0, ron: 0.0 };

/// The keys of a bridge: storage, diodes and DC load.
const BRIDGE_KEYS: [&str; 3] = ["storage_capacitance_f", "diode", "load"];

/// Appends a rectifier's diodes and load (its storage written before).
fn put_bridge(keys: &mut Keys, r: &Rectifier) {
    put(keys, "diode", &r.diode);
    put(keys, "load", &r.load);
}

/// The model of a bridge's description.
fn bridge_model(r: &Rectifier, kind: Kind) -> Described<'_> {
    Described {
        diode: DiodeLaw::of(&r.diode),
        cs: r.storage_capacitance_f,
        load: &r.load,
        kind,
    }
}

/// The rectifier of a bridge kind's variant.
fn rect(i: &Interface) -> Option<&Rectifier> {
    match i {
        Interface::FullBridge(r) | Interface::ParallelSshi(r, _) | Interface::SeriesSshi(r, _) => {
            Some(r)
        }
        _ => None,
    }
}

/// The rectifier of a bridge kind's variant, to change.
fn rect_mut(i: &mut Interface) -> Option<&mut Rectifier> {
    match i {
        Interface::FullBridge(r) | Interface::ParallelSshi(r, _) | Interface::SeriesSshi(r, _) => {
            Some(r)
        }
        _ => None,
    }
}

/// The description of `full_bridge`: a bridge, no switch; any transducer.
pub struct FullBridgeFile;

impl InterfaceKind for FullBridgeFile {
    fn key(&self) -> &'static str {
        "full_bridge"
    }

    fn check_key(&self, _keys: &toml::Table, key: &str, c: &Checker) -> Result<(), ParamError> {
        takes(self.key(), &BRIDGE_KEYS, key, c)
    }

    fn parse(&self, keys: &toml::Table, c: &Checker) -> Result<Interface, ParamError> {
        Ok(Interface::FullBridge(rectifier(keys, c)?))
    }

    fn write(&self, i: &Interface, keys: &mut Keys) {
        if let Some(r) = rect(i) {
            put_storage(keys, r.storage_capacitance_f);
            put_bridge(keys, r);
        }
    }

    fn storage<'a>(&self, i: &'a Interface) -> Option<(f64, &'a DcLoad)> {
        rect(i).map(|r| (r.storage_capacitance_f, &r.load))
    }

    fn load_mut<'a>(&self, i: &'a mut Interface) -> Option<&'a mut DcLoad> {
        rect_mut(i).map(|r| &mut r.load)
    }

    fn rectifier<'a>(&self, i: &'a Interface) -> Option<&'a Rectifier> {
        rect(i)
    }

    fn piezo_only(&self) -> bool {
        false
    }

    fn model<'a>(&self, i: &'a Interface, _slot: usize) -> Result<Described<'a>, &'static str> {
        let r = rect(i).ok_or(NOT_THIS)?;
        Ok(bridge_model(r, Kind::FullBridge(FullBridge)))
    }
}

/// Why a description does not read a variant of another kind.
const NOT_THIS: &str = "the interface is not of the kind its description reads";

/// The keys of an instantaneous inversion.
const INVERSION_KEYS: [&str; 2] = ["inversion_factor", "quality_factor"];

/// The instantaneous inversion of an SSHI's keys: its factor or its quality factor.
fn inversion(keys: &toml::Table, c: &Checker) -> Result<Inversion, ParamError> {
    match (
        number(keys, "inversion_factor", c)?,
        number(keys, "quality_factor", c)?,
    ) {
        (Some(g), None) => Ok(Inversion::Factor(g)),
        (None, Some(q)) => Ok(Inversion::QualityFactor(q)),
        (Some(_), Some(_)) => Err(c.message(
            "interface.quality_factor",
            "give `inversion_factor` or `quality_factor`, not both",
        )),
        (None, None) => Err(c.missing(
            "interface.inversion_factor",
            "the switch's inversion factor gamma (or `quality_factor`)",
        )),
    }
}

/// Appends an SSHI's keys: storage, inversion (or inductor), diodes, load.
fn put_sshi(keys: &mut Keys, r: &Rectifier, v: Inversion) {
    put_storage(keys, r.storage_capacitance_f);
    match v {
        Inversion::Factor(g) => put(keys, "inversion_factor", g),
        Inversion::QualityFactor(q) => put(keys, "quality_factor", q),
        Inversion::Inductor { .. } => {}
    }
    put_bridge(keys, r);
    if let Inversion::Inductor {
        inductance_h,
        resistance_ohm,
    } = v
    {
        put(keys, "inductance_h", inductance_h);
        put(keys, "inductor_resistance_ohm", resistance_ohm);
    }
}

/// Checks an instantaneous inversion's factor.
fn check_inversion(v: Inversion, c: &Checker) -> Result<(), ParamError> {
    match v {
        Inversion::Factor(g) => c.within_closed(
            "interface.inversion_factor",
            g,
            0.0,
            1.0 - f64::EPSILON,
            "in [0, 1)",
        ),
        Inversion::QualityFactor(q) => c.positive("interface.quality_factor", q),
        Inversion::Inductor { .. } => Ok(()),
    }
}

/// The description of `parallel_sshi`: a bridge and a parallel inverting switch, whose
/// inversion is instantaneous (`inversion_factor` or `quality_factor`) or rings through its
/// inductor (`inductance_h`, optional `inductor_resistance_ohm`).
pub struct ParallelSshiFile;

impl ParallelSshiFile {
    /// The variant's rectifier and inversion.
    fn of(i: &Interface) -> Option<(&Rectifier, Inversion)> {
        match i {
            Interface::ParallelSshi(r, v) => Some((r, *v)),
            _ => None,
        }
    }
}

impl InterfaceKind for ParallelSshiFile {
    fn key(&self) -> &'static str {
        "parallel_sshi"
    }

    fn check_key(&self, keys: &toml::Table, key: &str, c: &Checker) -> Result<(), ParamError> {
        if !keys.contains_key("inductance_h") {
            return takes(
                self.key(),
                &[&BRIDGE_KEYS[..], &INVERSION_KEYS[..]].concat(),
                key,
                c,
            );
        }
        if matches!(
            key,
            "inversion_factor" | "quality_factor" | "flyback_drop_v"
        ) {
            return Err(c.message(
                &format!("interface.{key}"),
                &format!(
                    "interface kind `parallel_sshi` with `inductance_h` takes no `{key}`: the \
                     inversion rings through the inductor"
                ),
            ));
        }
        takes(
            self.key(),
            &[&BRIDGE_KEYS[..], &sshi_inductor::KEYS[..]].concat(),
            key,
            c,
        )
    }

    fn parse(&self, keys: &toml::Table, c: &Checker) -> Result<Interface, ParamError> {
        let r = rectifier(keys, c)?;
        let v = match sshi_inductor::inversion(keys, c)? {
            Some(ring) => ring,
            None => inversion(keys, c)?,
        };
        Ok(Interface::ParallelSshi(r, v))
    }

    fn write(&self, i: &Interface, keys: &mut Keys) {
        if let Some((r, v)) = Self::of(i) {
            put_sshi(keys, r, v);
        }
    }

    fn storage<'a>(&self, i: &'a Interface) -> Option<(f64, &'a DcLoad)> {
        rect(i).map(|r| (r.storage_capacitance_f, &r.load))
    }

    fn load_mut<'a>(&self, i: &'a mut Interface) -> Option<&'a mut DcLoad> {
        rect_mut(i).map(|r| &mut r.load)
    }

    fn rectifier<'a>(&self, i: &'a Interface) -> Option<&'a Rectifier> {
        rect(i)
    }

    fn validate(
        &self,
        i: &Interface,
        clamped_capacitance_f: Option<f64>,
        c: &Checker,
    ) -> Result<(), ParamError> {
        match Self::of(i) {
            Some((
                _,
                Inversion::Inductor {
                    inductance_h,
                    resistance_ohm,
                },
            )) => sshi_inductor::check_ring(inductance_h, resistance_ohm, clamped_capacitance_f, c),
            Some((_, v)) => check_inversion(v, c),
            None => Ok(()),
        }
    }

    fn model<'a>(&self, i: &'a Interface, slot: usize) -> Result<Described<'a>, &'static str> {
        let (r, v) = Self::of(i).ok_or(NOT_THIS)?;
        let kind = match v {
            Inversion::Inductor {
                inductance_h,
                resistance_ohm,
            } => Kind::SshiInductor(Inverter {
                inductor: Inductor {
                    l: inductance_h,
                    rl: resistance_ohm,
                    i: slot,
                },
            }),
            v => Kind::ParallelSshi(ParallelSshi {
                gamma: v.gamma().ok_or(NOT_THIS)?,
            }),
        };
        Ok(bridge_model(r, kind))
    }
}

/// The description of `series_sshi`: the bridge behind a series inverting switch, its
/// inversion instantaneous (`inversion_factor` or `quality_factor`).
pub struct SeriesSshiFile;

impl SeriesSshiFile {
    /// The variant's rectifier and inversion.
    fn of(i: &Interface) -> Option<(&Rectifier, Inversion)> {
        match i {
            Interface::SeriesSshi(r, v) => Some((r, *v)),
            _ => None,
        }
    }
}

impl InterfaceKind for SeriesSshiFile {
    fn key(&self) -> &'static str {
        "series_sshi"
    }

    fn check_key(&self, _keys: &toml::Table, key: &str, c: &Checker) -> Result<(), ParamError> {
        takes(
            self.key(),
            &[&BRIDGE_KEYS[..], &INVERSION_KEYS[..]].concat(),
            key,
            c,
        )
    }

    fn parse(&self, keys: &toml::Table, c: &Checker) -> Result<Interface, ParamError> {
        Ok(Interface::SeriesSshi(
            rectifier(keys, c)?,
            inversion(keys, c)?,
        ))
    }

    fn write(&self, i: &Interface, keys: &mut Keys) {
        if let Some((r, v)) = Self::of(i) {
            put_sshi(keys, r, v);
        }
    }

    fn storage<'a>(&self, i: &'a Interface) -> Option<(f64, &'a DcLoad)> {
        rect(i).map(|r| (r.storage_capacitance_f, &r.load))
    }

    fn load_mut<'a>(&self, i: &'a mut Interface) -> Option<&'a mut DcLoad> {
        rect_mut(i).map(|r| &mut r.load)
    }

    fn rectifier<'a>(&self, i: &'a Interface) -> Option<&'a Rectifier> {
        rect(i)
    }

    fn validate(&self, i: &Interface, _cp: Option<f64>, c: &Checker) -> Result<(), ParamError> {
        match Self::of(i) {
            Some((_, Inversion::Inductor { .. })) => Err(c.message(
                "interface.inductance_h",
                "only `parallel_sshi` rings its inversion through `inductance_h`",
            )),
            Some((_, v)) => check_inversion(v, c),
            None => Ok(()),
        }
    }

    fn check_diode(&self, diode: &Diode, c: &Checker) -> Result<(), ParamError> {
        match *diode {
            Diode::PiecewiseLinear {
                on_resistance_ohm, ..
            } if on_resistance_ohm != 0.0 => Err(c.err(
                "interface.diode.on_resistance_ohm",
                on_resistance_ohm,
                "0 for `series_sshi` (its diodes conduct only during the inversion, whose \
                 losses the inversion factor covers)",
            )),
            Diode::Shockley { .. } => Err(c.message("interface.diode.law", SHOCKLEY_SCOPE)),
            _ => Ok(()),
        }
    }

    fn model<'a>(&self, i: &'a Interface, _slot: usize) -> Result<Described<'a>, &'static str> {
        /// The one inversion without a factor of its own.
        const RING: &str = "a series SSHI's inversion through its inductor is not modelled; \
                            give `inversion_factor` or `quality_factor`";
        let (r, v) = Self::of(i).ok_or(NOT_THIS)?;
        let gamma = v.gamma().ok_or(RING)?;
        Ok(bridge_model(r, Kind::SeriesSshi(SeriesSshi { gamma })))
    }
}

/// Why a SECE takes no diodes.
pub(super) const SECE_DIODE: &str = "interface kind `sece` takes no `diode`: its `efficiency` \
     covers the converter's rectifier";

/// The description of `sece` without `inductance_h`: an instantaneous transfer with an
/// `efficiency`.
pub struct SeceFile;

impl InterfaceKind for SeceFile {
    fn key(&self) -> &'static str {
        "sece"
    }

    fn claims(&self, keys: &toml::Table) -> bool {
        !keys.contains_key("inductance_h")
    }

    fn check_key(&self, _keys: &toml::Table, key: &str, c: &Checker) -> Result<(), ParamError> {
        match key {
            "diode" => Err(c.message("interface.diode", SECE_DIODE)),
            "inductor_resistance_ohm" | "flyback_drop_v" => Err(c.missing(
                "interface.inductance_h",
                &format!("the inductor that `{key}` belongs to"),
            )),
            _ => takes(
                self.key(),
                &["storage_capacitance_f", "load", "efficiency"],
                key,
                c,
            ),
        }
    }

    fn parse(&self, keys: &toml::Table, c: &Checker) -> Result<Interface, ParamError> {
        let (storage_capacitance_f, load) = storage_and_load(keys, c)?;
        let efficiency = number(keys, "efficiency", c)?.ok_or_else(|| {
            c.missing(
                "interface.efficiency",
                "the fraction of the extracted energy that reaches the storage",
            )
        })?;
        Ok(Interface::Sece {
            storage_capacitance_f,
            load,
            efficiency,
        })
    }

    fn write(&self, i: &Interface, keys: &mut Keys) {
        if let Interface::Sece {
            storage_capacitance_f,
            load,
            efficiency,
        } = i
        {
            put_storage(keys, *storage_capacitance_f);
            put(keys, "efficiency", efficiency);
            put(keys, "load", load);
        }
    }

    fn storage<'a>(&self, i: &'a Interface) -> Option<(f64, &'a DcLoad)> {
        match i {
            Interface::Sece {
                storage_capacitance_f,
                load,
                ..
            } => Some((*storage_capacitance_f, load)),
            _ => None,
        }
    }

    fn load_mut<'a>(&self, i: &'a mut Interface) -> Option<&'a mut DcLoad> {
        match i {
            Interface::Sece { load, .. } => Some(load),
            _ => None,
        }
    }

    fn validate(&self, i: &Interface, _cp: Option<f64>, c: &Checker) -> Result<(), ParamError> {
        match i {
            Interface::Sece { efficiency, .. } => {
                c.within_closed("interface.efficiency", *efficiency, 0.0, 1.0, "in [0, 1]")
            }
            _ => Ok(()),
        }
    }

    fn model<'a>(&self, i: &'a Interface, _slot: usize) -> Result<Described<'a>, &'static str> {
        let Interface::Sece {
            storage_capacitance_f,
            load,
            efficiency,
        } = i
        else {
            return Err(NOT_THIS);
        };
        Ok(Described {
            diode: IDEAL,
            cs: *storage_capacitance_f,
            load,
            kind: Kind::Sece(Sece { eta: *efficiency }),
        })
    }
}

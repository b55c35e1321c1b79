//! The interface circuit between a one-load transducer (piezoelectric or electromagnetic) and
//! what it powers: the optional `[interface]` table of a device file.
//!
//! This file reads the table and holds the checks every kind shares: the file form, the
//! storage, the load, the diodes, and which transducers a kind takes. The words every kind
//! shares (the diodes, the DC load, the inversion) are [`crate::circuits::description`]'s;
//! what one kind adds (its keys, their checks with errors naming the field, and its model) is
//! the kind's own file in [`crate::circuits`], which implements `InterfaceKind` and is
//! registered there, where [`Interface`] is declared.
//!
//! | `kind` | circuit | transducer |
//! |---|---|---|
//! | `resistive` (the default, and the meaning of a file without the table) | the transducer's own `load_resistance_ohm` | any |
//! | `full_bridge` | a full-wave diode bridge into a storage capacitor `storage_capacitance_f` with a DC load | piezoelectric, electromagnetic, an electrostatic pair (across its two electrodes) |
//! | `parallel_sshi` | the bridge, plus an inductive switch across the piezoelectric element that inverts its voltage, `V -> -gamma V`, at each displacement extremum | piezoelectric |
//! | `series_sshi` | the switch in series with the bridge: the element is open but at each displacement extremum, when it discharges through the inductor and the bridge into the storage | piezoelectric |
//! | `sece` | synchronous electric charge extraction: the element is open but at each displacement extremum, when the energy on its clamped capacitance moves to the storage with an `efficiency`; or, given `inductance_h`, through a buck-boost inductor in time ([`SeceInductor`]) | piezoelectric |
//!
//! The bridge's diodes (`[interface.diode]`) are either piecewise linear, a forward drop
//! `forward_drop_v` and an on-resistance `on_resistance_ohm` **per diode** (two conduct in
//! series, so the conducting path has `2 V_F` and `2 R_on`), or follow the Shockley law
//! `I = I_s (exp(V / (n V_T)) - 1)` (for comparison with a circuit simulator). The DC load
//! (`[interface.load]`) is a resistor, a battery (a constant voltage with a series resistance),
//! or `open` (nothing: for charging a capacitor).
//!
//! The switch's inversion factor is given either as `inversion_factor` (gamma in [0, 1)) or
//! as the inductor branch's `quality_factor` Q, gamma = exp(-pi / (2 Q)) (Guyomar et al.,
//! IEEE Trans. Ultrason. Ferroelectr. Freq. Control 52 (2005) 584). The inversion is
//! instantaneous: the LC half-cycle, pi sqrt(L Cp), is taken as short beside the vibration's
//! period, and its losses are what gamma says.
//!
//! ```toml
//! [interface]
//! kind = "parallel_sshi"
//! storage_capacitance_f = 10e-6
//! quality_factor = 3.0
//! [interface.diode]
//! law = "piecewise_linear"
//! forward_drop_v = 0.2
//! on_resistance_ohm = 0.0
//! [interface.load]
//! kind = "resistor"
//! resistance_ohm = 100e3
//! ```
//!
//! An electrostatic pair feeds the bridge from its two electrodes (the bias stays on the proof
//! mass): the bridge's input is `V1 - V2`, which swings twice as far as either node. The pair's
//! `load_resistance_ohm` is then a bleed resistor from each electrode to ground (a probe's
//! input, say), and its `load_capacitance_f` the capacitance of each electrode's node. The
//! synchronous switches act on a piezoelectric element's clamped capacitance and refuse a pair
//! with a named error.
//!
//! A `sece` with `inductance_h` resolves its transfer through the inductor (optional
//! `inductor_resistance_ohm` and the flyback diode's `flyback_drop_v`, both 0 by default) and
//! takes no `efficiency`: what the transfer loses follows from them. A `parallel_sshi` with
//! `inductance_h` (and optional `inductor_resistance_ohm`, 0 by default) rings its inversion
//! through the inductor in time and takes no `inversion_factor` or `quality_factor`.

use serde::{Deserialize, Serialize};

use super::{Checker, ParamError, Transducer};
use crate::circuits::description::{not_taken, Keys, RESISTIVE, SHOCKLEY_SCOPE};
use crate::circuits::InterfaceKind;

pub use crate::circuits::description::THERMAL_VOLTAGE_V;
pub use crate::circuits::sece_inductor::SeceInductor;
pub use crate::circuits::{DcLoad, Diode, Interface, Inversion, Rectifier};

/// The order in which a table's keys are checked, so that of two keys a kind does not take
/// the same one is named whatever the file's order: the bridge's, the switches', the
/// inductors', then any other key in alphabetical order.
const CHECK_ORDER: [&str; 9] = [
    "storage_capacitance_f",
    "diode",
    "load",
    "inversion_factor",
    "quality_factor",
    "efficiency",
    "inductance_h",
    "inductor_resistance_ohm",
    "flyback_drop_v",
];

/// The keys of `keys` in [`CHECK_ORDER`].
fn check_order(keys: &toml::Table) -> impl Iterator<Item = &str> {
    let known = CHECK_ORDER
        .iter()
        .filter_map(|k| keys.get_key_value(*k).map(|(k, _)| k.as_str()));
    let other = keys
        .keys()
        .map(String::as_str)
        .filter(|k| !CHECK_ORDER.iter().any(|o| o == k));
    known.chain(other)
}

/// The `kind` keys, the resistive default first, then the registered kinds'.
pub fn interface_kinds() -> Vec<&'static str> {
    let mut out = vec![RESISTIVE];
    for k in Interface::KINDS {
        if !out.contains(&k.key()) {
            out.push(k.key());
        }
    }
    out
}

/// The file form of `[interface]`: its keys in their order (`kind` first), each read and
/// checked by the kind the `kind` key names.
#[derive(Debug, Clone, Default)]
pub(crate) struct RawInterface(Vec<(String, toml::Value)>);

impl Serialize for RawInterface {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        use serde::ser::SerializeMap;
        let mut m = s.serialize_map(Some(self.0.len()))?;
        for (k, v) in &self.0 {
            m.serialize_entry(k, v)?;
        }
        m.end()
    }
}

impl<'de> Deserialize<'de> for RawInterface {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        Ok(RawInterface(
            toml::Table::deserialize(d)?.into_iter().collect(),
        ))
    }
}

impl RawInterface {
    /// The file form of an interface (`None` for the default, resistive).
    pub(crate) fn of(i: &Interface) -> Option<Self> {
        let kind = i.kind()?;
        let mut keys: Keys = vec![("kind", toml::Value::String(kind.key().to_string()))];
        kind.write(i, &mut keys);
        Some(RawInterface(
            keys.into_iter().map(|(k, v)| (k.to_string(), v)).collect(),
        ))
    }

    /// Converts the file form, naming any key that does not belong to the kind.
    pub(crate) fn parse(self, c: &Checker) -> Result<Interface, ParamError> {
        let mut keys: toml::Table = self.0.into_iter().collect();
        let kind = match keys.remove("kind") {
            Some(toml::Value::String(k)) => k,
            Some(v) => {
                return Err(c.message("interface.kind", &format!("`{v}` is not a kind's name")))
            }
            None => return Err(c.missing("interface.kind", "the kind of interface circuit")),
        };
        if kind == RESISTIVE {
            return match keys.keys().next() {
                Some(key) => Err(not_taken(&kind, key, c)),
                None => Ok(Interface::Resistive),
            };
        }
        let Some(described) = Interface::KINDS
            .iter()
            .find(|k| k.key() == kind && k.claims(&keys))
        else {
            return Err(c.message(
                "interface.kind",
                &format!(
                    "unknown kind `{kind}`; the kinds are: {}",
                    interface_kinds().join(", ")
                ),
            ));
        };
        for key in check_order(&keys) {
            described.check_key(&keys, key, c)?;
        }
        described.parse(&keys, c)
    }
}

impl Interface {
    /// Checks the values and that the transducer takes this interface.
    pub(crate) fn validate(&self, transducer: &Transducer, c: &Checker) -> Result<(), ParamError> {
        let Some(kind) = self.kind() else {
            return Ok(());
        };
        let rect = kind.rectifier(self);
        self.validate_transducer(kind, transducer, rect, c)?;
        self.validate_values(c)?;
        let clamped_capacitance_f = match transducer {
            Transducer::Piezoelectric(p) => Some(p.capacitance_f),
            _ => None,
        };
        kind.validate(self, clamped_capacitance_f, c)?;
        if let Some(r) = rect {
            validate_diode(kind, r, transducer, c)?;
        }
        Ok(())
    }

    /// That the transducer takes this interface, and leaves the DC load to it.
    fn validate_transducer(
        &self,
        kind: &dyn InterfaceKind,
        transducer: &Transducer,
        rect: Option<&Rectifier>,
        c: &Checker,
    ) -> Result<(), ParamError> {
        match transducer {
            Transducer::Piezoelectric(_) => {}
            Transducer::Electromagnetic(em) => {
                if kind.piezo_only() {
                    return Err(c.message(
                        "interface.kind",
                        &format!(
                            "interface kind `{}` takes a piezoelectric transducer (its switch acts \
                             on the clamped capacitance, which a coil does not have); an \
                             electromagnetic transducer takes `resistive` or `full_bridge`",
                            self.key()
                        ),
                    ));
                }
                let ron = match rect.map(|r| &r.diode) {
                    Some(Diode::PiecewiseLinear {
                        on_resistance_ohm, ..
                    }) => *on_resistance_ohm,
                    _ => 0.0,
                };
                if em.coil_inductance_h == 0.0 && em.coil_resistance_ohm + 2.0 * ron <= 0.0 {
                    return Err(c.message(
                        "transducer.coil_resistance_ohm",
                        "a coil without inductance needs a resistance (or diodes with an \
                         on-resistance) in front of a bridge: the current would be unbounded",
                    ));
                }
            }
            Transducer::AreaOverlapPair(_) | Transducer::GapClosingPair(_) => {
                if kind.piezo_only() {
                    return Err(c.message(
                        "interface.kind",
                        &format!(
                            "interface kind `{}` takes a piezoelectric transducer (its switch \
                             acts on the clamped capacitance); transducer kind `{}` takes \
                             `resistive` or `full_bridge` (across its two electrodes)",
                            self.key(),
                            transducer.key()
                        ),
                    ));
                }
            }
            Transducer::None => {
                return Err(c.message(
                    "interface.kind",
                    &format!(
                        "interface kind `{}` needs a transducer to connect; transducer kind \
                         `none` takes `resistive` only",
                        self.key()
                    ),
                ))
            }
        }
        let pair = matches!(
            transducer,
            Transducer::AreaOverlapPair(_) | Transducer::GapClosingPair(_)
        );
        if !pair && transducer.load_resistance_ohm().is_finite() {
            return Err(c.message(
                "transducer.load_resistance_ohm",
                &format!(
                    "with interface kind `{}` the DC load is `interface.load`; remove the \
                     transducer's resistive load",
                    self.key()
                ),
            ));
        }
        Ok(())
    }

    /// The storage and the load, which every kind has.
    fn validate_values(&self, c: &Checker) -> Result<(), ParamError> {
        c.positive(
            "interface.storage_capacitance_f",
            self.storage_capacitance_f().unwrap_or(f64::NAN),
        )?;
        match self.load() {
            Some(DcLoad::Resistor { resistance_ohm }) => {
                c.positive("interface.load.resistance_ohm", *resistance_ohm)?
            }
            Some(DcLoad::Battery {
                voltage_v,
                series_resistance_ohm,
            }) => {
                c.positive("interface.load.voltage_v", *voltage_v)?;
                c.positive(
                    "interface.load.series_resistance_ohm",
                    *series_resistance_ohm,
                )?;
            }
            _ => {}
        }
        Ok(())
    }
}

/// The rectifier's diodes, and that their law suits the transducer and the kind.
fn validate_diode(
    kind: &dyn InterfaceKind,
    r: &Rectifier,
    transducer: &Transducer,
    c: &Checker,
) -> Result<(), ParamError> {
    match r.diode {
        Diode::PiecewiseLinear {
            forward_drop_v,
            on_resistance_ohm,
        } => {
            c.non_negative("interface.diode.forward_drop_v", forward_drop_v)?;
            c.non_negative("interface.diode.on_resistance_ohm", on_resistance_ohm)?;
        }
        Diode::Shockley {
            saturation_current_a,
            ideality,
            thermal_voltage_v,
        } => {
            c.positive("interface.diode.saturation_current_a", saturation_current_a)?;
            c.within_closed(
                "interface.diode.ideality",
                ideality,
                0.5,
                10.0,
                "in [0.5, 10]",
            )?;
            c.positive("interface.diode.thermal_voltage_v", thermal_voltage_v)?;
            let capacitive = matches!(
                transducer,
                Transducer::Piezoelectric(_)
                    | Transducer::AreaOverlapPair(_)
                    | Transducer::GapClosingPair(_)
            );
            if !capacitive {
                return Err(c.message("interface.diode.law", SHOCKLEY_SCOPE));
            }
        }
    }
    kind.check_diode(&r.diode, c)
}

impl super::Device {
    /// This device behind `interface`; behind a circuit its transducer's own resistive load is
    /// removed (the circuit's DC load replaces it, and the device's check refuses both).
    #[must_use]
    pub fn behind(&self, interface: Interface) -> Self {
        let mut d = self.clone();
        if interface.kind().is_some() {
            if let Some(r) = d.own_load_mut() {
                *r = f64::INFINITY;
            }
        }
        d.interface = interface;
        d
    }

    /// The transducer's own resistive load (ohm, infinite where it has none), for a
    /// one-load transducer (piezoelectric or electromagnetic); `None` for the others.
    pub fn own_load_mut(&mut self) -> Option<&mut f64> {
        match &mut self.transducer {
            Transducer::Piezoelectric(p) => Some(&mut p.load_resistance_ohm),
            Transducer::Electromagnetic(e) => Some(&mut e.load_resistance_ohm),
            _ => None,
        }
    }
}

//! The interface circuit between a one-load transducer (piezoelectric or electromagnetic) and
//! what it powers: the optional `[interface]` table of a device file.
//!
//! This file holds what every kind shares: the diodes, the DC load, the inversion, the file
//! form and the checks of the storage, the load and the diodes. What one kind adds (its keys,
//! their checks with errors naming the field, and its model) is the kind's own file in
//! [`crate::physics::harvester::circuits`], which implements `InterfaceKind` and is
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

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use super::{Checker, ParamError, Transducer};
use crate::physics::harvester::circuits::Described;

pub use crate::physics::harvester::circuits::sece_inductor::SeceInductor;
pub use crate::physics::harvester::circuits::Interface;

/// The bridge's diodes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case", deny_unknown_fields)]
pub enum Diode {
    /// A forward drop and an on-resistance (per diode); conduction starts and stops at
    /// located events.
    PiecewiseLinear {
        /// Forward drop V_F of one diode (V).
        forward_drop_v: f64,
        /// On-resistance of one diode (ohm); zero: ideal with a drop.
        on_resistance_ohm: f64,
    },
    /// The Shockley law `I = I_s (exp(V / (n V_T)) - 1)`, smooth (no events).
    Shockley {
        /// Saturation current I_s (A).
        saturation_current_a: f64,
        /// Ideality factor n.
        ideality: f64,
        /// Thermal voltage V_T (V); 25.85 mV (300.15 K) when not given.
        #[serde(default = "thermal_voltage_default")]
        thermal_voltage_v: f64,
    },
}

fn thermal_voltage_default() -> f64 {
    THERMAL_VOLTAGE_V
}

/// k T / q at 27 degrees C (300.15 K), ngspice's default temperature (V).
pub const THERMAL_VOLTAGE_V: f64 = 1.380_649e-23 * 300.15 / 1.602_176_634e-19;

impl Default for Diode {
    fn default() -> Self {
        Diode::PiecewiseLinear {
            forward_drop_v: 0.0,
            on_resistance_ohm: 0.0,
        }
    }
}

/// What the storage capacitor feeds.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case", deny_unknown_fields)]
pub enum DcLoad {
    /// A resistor.
    Resistor {
        /// Resistance (ohm).
        resistance_ohm: f64,
    },
    /// A battery: a constant voltage behind a series resistance.
    Battery {
        /// Its voltage (V).
        voltage_v: f64,
        /// Its series resistance (ohm).
        series_resistance_ohm: f64,
    },
    /// Nothing: the storage only charges.
    Open,
}

/// The switch's inversion: a factor, the quality factor of the inductor branch, or the
/// inductor itself, through which the inversion rings in time (`parallel_sshi` only).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Inversion {
    /// gamma, in [0, 1).
    Factor(f64),
    /// Q > 0: gamma = exp(-pi / (2 Q)).
    QualityFactor(f64),
    /// The inductor L (H) and its series resistance R_L (ohm): the element rings through
    /// it at each extremum (see `physics::harvester::circuits::sshi_inductor`).
    Inductor {
        /// L (H).
        inductance_h: f64,
        /// R_L (ohm).
        resistance_ohm: f64,
    },
}

impl Inversion {
    /// The inversion factor gamma of an instantaneous inversion; `None` for one through the
    /// inductor, whose factor follows from the element's capacitance as well.
    pub fn gamma(self) -> Option<f64> {
        match self {
            Inversion::Factor(g) => Some(g),
            Inversion::QualityFactor(q) => Some((-std::f64::consts::PI / (2.0 * q)).exp()),
            Inversion::Inductor { .. } => None,
        }
    }
}

/// A diode bridge into a storage capacitor with a DC load.
#[derive(Debug, Clone, PartialEq)]
pub struct Rectifier {
    /// Storage capacitance C_s (F).
    pub storage_capacitance_f: f64,
    /// The diodes.
    pub diode: Diode,
    /// The DC load.
    pub load: DcLoad,
}

/// One kind of interface circuit as a device file describes it: the keys of its
/// `[interface]` table, their checks (each error naming its field), and the circuit model
/// they give. A kind's own file implements it; the registration point,
/// [`crate::physics::harvester::circuits`], pairs it with its [`Interface`] variant.
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

    /// Checks the kind's own values of `i`, against the transducer where they depend on it.
    fn validate(&self, _i: &Interface, _t: &Transducer, _c: &Checker) -> Result<(), ParamError> {
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

/// The `kind` key of the transducer's own resistive load.
const RESISTIVE: &str = "resistive";

/// Why the `shockley` law is refused.
pub(crate) const SHOCKLEY_SCOPE: &str = "the `shockley` law is modelled for a piezoelectric \
     element or an electrostatic pair with `full_bridge` (and a piezoelectric element with \
     `parallel_sshi`); use `piecewise_linear`";

/// The keys of an interface in the order its file form writes them.
pub(crate) type Keys = Vec<(&'static str, toml::Value)>;

/// Appends `key = value` to a file form.
pub(crate) fn put(keys: &mut Keys, key: &'static str, value: impl Serialize) {
    if let Ok(v) = toml::Value::try_from(value) {
        keys.push((key, v));
    }
}

/// Appends the storage capacitance and the DC load, the keys every kind has.
pub(crate) fn put_storage(keys: &mut Keys, storage_capacitance_f: f64) {
    put(keys, "storage_capacitance_f", storage_capacitance_f);
}

/// The value of `key` in the table, if given.
pub(crate) fn value<T: DeserializeOwned>(
    keys: &toml::Table,
    key: &str,
    c: &Checker,
) -> Result<Option<T>, ParamError> {
    keys.get(key)
        .map(|v| {
            v.clone().try_into().map_err(|e: toml::de::Error| {
                c.message(&format!("interface.{key}"), e.to_string().trim())
            })
        })
        .transpose()
}

/// The number `key` of the table, if given.
pub(crate) fn number(
    keys: &toml::Table,
    key: &str,
    c: &Checker,
) -> Result<Option<f64>, ParamError> {
    value(keys, key, c)
}

/// The storage capacitance (F) and the DC load, which every kind needs.
pub(crate) fn storage_and_load(
    keys: &toml::Table,
    c: &Checker,
) -> Result<(f64, DcLoad), ParamError> {
    let cs = number(keys, "storage_capacitance_f", c)?
        .ok_or_else(|| c.missing("interface.storage_capacitance_f", "the storage capacitor"))?;
    let load = value(keys, "load", c)?
        .ok_or_else(|| c.missing("interface.load", "the DC load (resistor, battery or open)"))?;
    Ok((cs, load))
}

/// The rectifier: storage, load and diodes (ideal when not given).
pub(crate) fn rectifier(keys: &toml::Table, c: &Checker) -> Result<Rectifier, ParamError> {
    let (storage_capacitance_f, load) = storage_and_load(keys, c)?;
    Ok(Rectifier {
        storage_capacitance_f,
        diode: value(keys, "diode", c)?.unwrap_or_default(),
        load,
    })
}

/// That interface kind `kind` takes no `key`.
pub(crate) fn not_taken(kind: &str, key: &str, c: &Checker) -> ParamError {
    c.message(
        &format!("interface.{key}"),
        &format!("interface kind `{kind}` takes no `{key}`"),
    )
}

/// That `key` is one of `taken`, the keys of interface kind `kind`.
pub(crate) fn takes(kind: &str, taken: &[&str], key: &str, c: &Checker) -> Result<(), ParamError> {
    if taken.contains(&key) {
        Ok(())
    } else {
        Err(not_taken(kind, key, c))
    }
}

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
    /// The `kind` key.
    pub fn key(&self) -> &'static str {
        self.kind().map_or(RESISTIVE, |k| k.key())
    }

    /// True for the default, the transducer's own resistive load.
    pub fn is_resistive(&self) -> bool {
        matches!(self, Interface::Resistive)
    }

    /// The device path of the load resistance behind this interface: the transducer's own
    /// `transducer.load_resistance_ohm` for `resistive`, the DC load's
    /// `interface.load.resistance_ohm` behind a circuit.
    pub fn load_resistance_path(&self) -> &'static str {
        if self.is_resistive() {
            "transducer.load_resistance_ohm"
        } else {
            "interface.load.resistance_ohm"
        }
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

    /// Checks the values and that the transducer takes this interface.
    pub(crate) fn validate(&self, transducer: &Transducer, c: &Checker) -> Result<(), ParamError> {
        let Some(kind) = self.kind() else {
            return Ok(());
        };
        let rect = kind.rectifier(self);
        self.validate_transducer(kind, transducer, rect, c)?;
        self.validate_values(c)?;
        kind.validate(self, transducer, c)?;
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
        if !interface.is_resistive() {
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

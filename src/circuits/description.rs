//! What a device's `[interface]` says, in the words every kind shares: the bridge's diodes,
//! the DC load, the switch's inversion, the rectifier they make, and the helpers with which a
//! kind reads and writes its keys, each error naming the field.
//!
//! The description layer ([`crate::device`]) reads the table and checks what every kind
//! shares; the kinds, one file each beside this one, read their own keys with these words.

use serde::de::DeserializeOwned;
use serde::{Deserialize, Serialize};

use crate::check::{Checker, ParamError};

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
    /// it at each extremum (see `circuits::sshi_inductor`).
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

/// The `kind` key of the transducer's own resistive load.
pub(crate) const RESISTIVE: &str = "resistive";

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

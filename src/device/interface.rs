//! The interface circuit between a one-load transducer (piezoelectric or electromagnetic) and
//! what it powers: the optional `[interface]` table of a device file.
//!
//! The module reads better whole: the table's raw keys, their parse into [`Interface`], the
//! write-back to TOML and the checks are one format, a key read, written and checked side by
//! side (the inductor's own keys and checks are in `sece_inductor`).
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

mod sece_inductor;
pub use sece_inductor::SeceInductor;

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

/// The interface circuit (see the module docs).
#[derive(Debug, Clone, PartialEq, Default)]
pub enum Interface {
    /// The transducer's own resistive load.
    #[default]
    Resistive,
    /// A full-wave diode bridge into a storage capacitor and a DC load.
    FullBridge(Rectifier),
    /// The bridge with a parallel inverting switch.
    ParallelSshi(Rectifier, Inversion),
    /// The bridge behind a series inverting switch.
    SeriesSshi(Rectifier, Inversion),
    /// Synchronous electric charge extraction.
    Sece {
        /// Storage capacitance (F).
        storage_capacitance_f: f64,
        /// The DC load.
        load: DcLoad,
        /// Fraction of the extracted energy that reaches the storage.
        efficiency: f64,
    },
    /// Synchronous electric charge extraction through its buck-boost inductor (`kind =
    /// "sece"` with `inductance_h`).
    SeceInductor(SeceInductor),
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

/// The file form of `[interface]`: every key any kind takes, checked against the kind on
/// conversion, so that a key of another kind is named in the error.
#[derive(Debug, Clone, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct RawInterface {
    kind: String,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    storage_capacitance_f: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    inversion_factor: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    quality_factor: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    efficiency: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    diode: Option<Diode>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    load: Option<DcLoad>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    inductance_h: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    inductor_resistance_ohm: Option<f64>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    flyback_drop_v: Option<f64>,
}

/// The kinds, in the order of the module docs.
pub const INTERFACE_KINDS: [&str; 5] = [
    "resistive",
    "full_bridge",
    "parallel_sshi",
    "series_sshi",
    "sece",
];

impl RawInterface {
    /// The file form of an interface (`None` for the default, resistive).
    pub(crate) fn of(i: &Interface) -> Option<Self> {
        let mut raw = RawInterface {
            kind: i.key().to_string(),
            ..Default::default()
        };
        let rect = |raw: &mut RawInterface, r: &Rectifier| {
            raw.storage_capacitance_f = Some(r.storage_capacitance_f);
            raw.diode = Some(r.diode.clone());
            raw.load = Some(r.load.clone());
        };
        let inv = |raw: &mut RawInterface, v: &Inversion| match *v {
            Inversion::Factor(g) => raw.inversion_factor = Some(g),
            Inversion::QualityFactor(q) => raw.quality_factor = Some(q),
            Inversion::Inductor {
                inductance_h,
                resistance_ohm,
            } => {
                raw.inductance_h = Some(inductance_h);
                raw.inductor_resistance_ohm = Some(resistance_ohm);
            }
        };
        match i {
            Interface::Resistive => return None,
            Interface::FullBridge(r) => rect(&mut raw, r),
            Interface::ParallelSshi(r, v) | Interface::SeriesSshi(r, v) => {
                rect(&mut raw, r);
                inv(&mut raw, v);
            }
            Interface::Sece {
                storage_capacitance_f,
                load,
                efficiency,
            } => {
                raw.storage_capacitance_f = Some(*storage_capacitance_f);
                raw.load = Some(load.clone());
                raw.efficiency = Some(*efficiency);
            }
            Interface::SeceInductor(s) => {
                raw.storage_capacitance_f = Some(s.storage_capacitance_f);
                raw.load = Some(s.load.clone());
                raw.inductance_h = Some(s.inductance_h);
                raw.inductor_resistance_ohm = Some(s.inductor_resistance_ohm);
                raw.flyback_drop_v = Some(s.flyback_drop_v);
            }
        }
        Some(raw)
    }

    /// Converts the file form, naming any key that does not belong to the kind.
    pub(crate) fn parse(self, c: &Checker) -> Result<Interface, ParamError> {
        let kind = self.kind.as_str();
        if !INTERFACE_KINDS.contains(&kind) {
            return Err(c.message(
                "interface.kind",
                &format!(
                    "unknown kind `{kind}`; the kinds are: {}",
                    INTERFACE_KINDS.join(", ")
                ),
            ));
        }
        let takes_switch = matches!(kind, "parallel_sshi" | "series_sshi");
        let not_taken = |field: &str| {
            c.message(
                &format!("interface.{field}"),
                &format!("interface kind `{kind}` takes no `{field}`"),
            )
        };
        if kind == "resistive" {
            for (present, f) in [
                (
                    self.storage_capacitance_f.is_some(),
                    "storage_capacitance_f",
                ),
                (self.diode.is_some(), "diode"),
                (self.load.is_some(), "load"),
            ] {
                if present {
                    return Err(not_taken(f));
                }
            }
        }
        if !takes_switch {
            if self.inversion_factor.is_some() {
                return Err(not_taken("inversion_factor"));
            }
            if self.quality_factor.is_some() {
                return Err(not_taken("quality_factor"));
            }
        }
        if kind != "sece" && self.efficiency.is_some() {
            return Err(not_taken("efficiency"));
        }
        let ring = kind == "parallel_sshi" && self.inductance_h.is_some();
        if ring {
            for (present, f) in [
                (self.inversion_factor.is_some(), "inversion_factor"),
                (self.quality_factor.is_some(), "quality_factor"),
                (self.flyback_drop_v.is_some(), "flyback_drop_v"),
            ] {
                if present {
                    return Err(c.message(
                        &format!("interface.{f}"),
                        &format!(
                            "interface kind `parallel_sshi` with `inductance_h` takes no `{f}`: \
                             the inversion rings through the inductor"
                        ),
                    ));
                }
            }
        } else {
            SeceInductor::check_keys(
                kind,
                [
                    self.inductance_h,
                    self.inductor_resistance_ohm,
                    self.flyback_drop_v,
                ],
                self.efficiency.is_some(),
                c,
            )?;
        }
        if kind == "sece" && self.diode.is_some() {
            return Err(c.message(
                "interface.diode",
                "interface kind `sece` takes no `diode`: its `efficiency` covers the converter's \
                 rectifier",
            ));
        }
        if kind == "resistive" {
            return Ok(Interface::Resistive);
        }
        let cs = self
            .storage_capacitance_f
            .ok_or_else(|| c.missing("interface.storage_capacitance_f", "the storage capacitor"))?;
        let load = self.load.ok_or_else(|| {
            c.missing("interface.load", "the DC load (resistor, battery or open)")
        })?;
        if let (true, Some(inductance_h)) = (kind == "sece", self.inductance_h) {
            return Ok(Interface::SeceInductor(SeceInductor {
                storage_capacitance_f: cs,
                load,
                inductance_h,
                inductor_resistance_ohm: self.inductor_resistance_ohm.unwrap_or(0.0),
                flyback_drop_v: self.flyback_drop_v.unwrap_or(0.0),
            }));
        }
        if kind == "sece" {
            let efficiency = self.efficiency.ok_or_else(|| {
                c.missing(
                    "interface.efficiency",
                    "the fraction of the extracted energy that reaches the storage",
                )
            })?;
            return Ok(Interface::Sece {
                storage_capacitance_f: cs,
                load,
                efficiency,
            });
        }
        let rect = Rectifier {
            storage_capacitance_f: cs,
            diode: self.diode.unwrap_or_default(),
            load,
        };
        if kind == "full_bridge" {
            return Ok(Interface::FullBridge(rect));
        }
        let inversion = match (
            self.inversion_factor,
            self.quality_factor,
            self.inductance_h,
        ) {
            (_, _, Some(inductance_h)) if ring => Inversion::Inductor {
                inductance_h,
                resistance_ohm: self.inductor_resistance_ohm.unwrap_or(0.0),
            },
            (Some(g), None, _) => Inversion::Factor(g),
            (None, Some(q), _) => Inversion::QualityFactor(q),
            (Some(_), Some(_), _) => {
                return Err(c.message(
                    "interface.quality_factor",
                    "give `inversion_factor` or `quality_factor`, not both",
                ))
            }
            (None, None, _) => {
                return Err(c.missing(
                    "interface.inversion_factor",
                    "the switch's inversion factor gamma (or `quality_factor`)",
                ))
            }
        };
        Ok(if kind == "parallel_sshi" {
            Interface::ParallelSshi(rect, inversion)
        } else {
            Interface::SeriesSshi(rect, inversion)
        })
    }
}

impl Interface {
    /// The `kind` key.
    pub fn key(&self) -> &'static str {
        match self {
            Interface::Resistive => "resistive",
            Interface::FullBridge(_) => "full_bridge",
            Interface::ParallelSshi(..) => "parallel_sshi",
            Interface::SeriesSshi(..) => "series_sshi",
            Interface::Sece { .. } | Interface::SeceInductor(_) => "sece",
        }
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
        match self {
            Interface::Resistive => None,
            Interface::FullBridge(r)
            | Interface::ParallelSshi(r, _)
            | Interface::SeriesSshi(r, _) => Some(r.storage_capacitance_f),
            Interface::Sece {
                storage_capacitance_f,
                ..
            } => Some(*storage_capacitance_f),
            Interface::SeceInductor(s) => Some(s.storage_capacitance_f),
        }
    }

    /// The DC load, for every kind but `resistive`.
    pub fn load(&self) -> Option<&DcLoad> {
        match self {
            Interface::Resistive => None,
            Interface::FullBridge(r)
            | Interface::ParallelSshi(r, _)
            | Interface::SeriesSshi(r, _) => Some(&r.load),
            Interface::Sece { load, .. } => Some(load),
            Interface::SeceInductor(s) => Some(&s.load),
        }
    }

    /// The DC load to change, for every kind but `resistive`.
    pub fn load_mut(&mut self) -> Option<&mut DcLoad> {
        match self {
            Interface::Resistive => None,
            Interface::FullBridge(r)
            | Interface::ParallelSshi(r, _)
            | Interface::SeriesSshi(r, _) => Some(&mut r.load),
            Interface::Sece { load, .. } => Some(load),
            Interface::SeceInductor(s) => Some(&mut s.load),
        }
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
        let rect = match self {
            Interface::Resistive => return Ok(()),
            Interface::FullBridge(r)
            | Interface::ParallelSshi(r, _)
            | Interface::SeriesSshi(r, _) => Some(r),
            Interface::Sece { .. } | Interface::SeceInductor(_) => None,
        };
        self.validate_transducer(transducer, rect, c)?;
        self.validate_values(transducer, c)?;
        if let Some(r) = rect {
            self.validate_diode(r, transducer, c)?;
        }
        Ok(())
    }

    /// That the transducer takes this interface, and leaves the DC load to it.
    fn validate_transducer(
        &self,
        transducer: &Transducer,
        rect: Option<&Rectifier>,
        c: &Checker,
    ) -> Result<(), ParamError> {
        match transducer {
            Transducer::Piezoelectric(_) => {}
            Transducer::Electromagnetic(em) => {
                if !matches!(self, Interface::FullBridge(_)) {
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
                if !matches!(self, Interface::FullBridge(_)) {
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

    /// The storage, the load, and the inversion, the SECE's efficiency or its inductor.
    fn validate_values(&self, transducer: &Transducer, c: &Checker) -> Result<(), ParamError> {
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
        match self {
            Interface::ParallelSshi(_, inv) | Interface::SeriesSshi(_, inv) => match *inv {
                Inversion::Factor(g) => c.within_closed(
                    "interface.inversion_factor",
                    g,
                    0.0,
                    1.0 - f64::EPSILON,
                    "in [0, 1)",
                )?,
                Inversion::QualityFactor(q) => c.positive("interface.quality_factor", q)?,
                Inversion::Inductor {
                    inductance_h,
                    resistance_ohm,
                } => ringing_inductor(self, inductance_h, resistance_ohm, transducer, c)?,
            },
            Interface::Sece { efficiency, .. } => {
                c.within_closed("interface.efficiency", *efficiency, 0.0, 1.0, "in [0, 1]")?
            }
            Interface::SeceInductor(s) => s.validate(transducer, c)?,
            _ => {}
        }
        Ok(())
    }

    /// The rectifier's diodes, and that their law suits the transducer and the interface.
    fn validate_diode(
        &self,
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
                if matches!(self, Interface::SeriesSshi(..)) && on_resistance_ohm != 0.0 {
                    return Err(c.err(
                        "interface.diode.on_resistance_ohm",
                        on_resistance_ohm,
                        "0 for `series_sshi` (its diodes conduct only during the \
                         inversion, whose losses the inversion factor covers)",
                    ));
                }
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
                if !capacitive || matches!(self, Interface::SeriesSshi(..)) {
                    return Err(c.message(
                        "interface.diode.law",
                        "the `shockley` law is modelled for a piezoelectric element or an \
                         electrostatic pair with `full_bridge` (and a piezoelectric element \
                         with `parallel_sshi`); use `piecewise_linear`",
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Checks an SSHI's inverting inductor: a parallel SSHI's, positive, with a resistance that
/// leaves the ring with the element's clamped capacitance underdamped, `R_L < 2 sqrt(L / Cp)`
/// (with more, the element's voltage never swings through zero and nothing is inverted).
fn ringing_inductor(
    interface: &Interface,
    inductance_h: f64,
    resistance_ohm: f64,
    transducer: &Transducer,
    c: &Checker,
) -> Result<(), ParamError> {
    if !matches!(interface, Interface::ParallelSshi(..)) {
        return Err(c.message(
            "interface.inductance_h",
            "only `parallel_sshi` rings its inversion through `inductance_h`",
        ));
    }
    c.positive("interface.inductance_h", inductance_h)?;
    c.non_negative("interface.inductor_resistance_ohm", resistance_ohm)?;
    if let Transducer::Piezoelectric(p) = transducer {
        let critical = 2.0 * (inductance_h / p.capacitance_f).sqrt();
        if resistance_ohm >= critical {
            return Err(c.err(
                "interface.inductor_resistance_ohm",
                resistance_ohm,
                &format!(
                    "below 2 sqrt(L / Cp) = {critical:e} ohm (an overdamped ring inverts \
                     nothing)"
                ),
            ));
        }
    }
    Ok(())
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

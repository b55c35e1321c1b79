//! The description of a device: its mechanics, each side's end-stop and its transducer.
//!
//! A device is a TOML file (see `data/prototype1.toml` for the paper's prototype 1 and
//! `data/examples/` for devices of other kinds). Every value is in SI units and the key names
//! carry the unit (`mass_kg`, `gap_m`). Parsing is strict: unknown keys are rejected, every key
//! is checked against the choice it belongs to (a stop's `law`, the transducer's `kind`), and
//! every value against its valid range, in a [`ParamError`] that names the file, the field, the
//! value and the range.
//!
//! ```toml
//! name = "prototype1"
//! params = "published"
//! description = "..."
//!
//! [mechanics]                  # eq 7: m x'' + b x' + km x + F_e + F_im = m a(t)
//! mass_kg = 2.8e-6
//! stiffness_n_per_m = 166.5
//! damping_n_s_per_m = 3.75e-3
//!
//! [stops.both]                 # or [stops.upper] and [stops.lower]; no table, no stop
//! gap_m = 7e-6
//! law = "hertz_line"           # see `stops`
//! # ...
//!
//! [transducer]
//! kind = "area_overlap_pair"   # see `transducer`
//! # ...
//! ```
//!
//! A device of two masses or more (a driver that strikes a generator, an impact pair) has
//! `[[masses]]`, `[[springs]]`, `[[dampers]]` and `[[stops]]` arrays in place of `[mechanics]`
//! and `[stops]` (see [`masses`]; `data/examples/upconverter.toml`); its model is
//! [`crate::physics::harvester::masses::MassChain`].
//!
//! Files of the earlier format, which had sections `[geometry]`, `[electrical]`, `[material]`
//! and `[endstop]` for the paper's topology, still load (converted on load; see the `legacy` module).
//!
//! Any numeric field can be read and changed by its dotted path ([`Device::param`],
//! [`Device::with_param`]), which is how studies name the parameters they vary.
//!
//! This module parses text it is given; reading the file is the caller's job (no I/O here).

pub mod interface;
mod laws;
mod legacy;
pub mod masses;
mod paths;
mod range;
pub mod size;
pub mod stops;
pub mod suspension;
pub mod transducer;

use serde::{Deserialize, Serialize};

pub(crate) use crate::check::Checker;
pub use crate::check::ParamError;
pub use crate::laws::contact::Side;
pub use interface::{DcLoad, Diode, Interface, Inversion, Rectifier, SeceInductor};
pub use masses::{Body, Link, MassStop, Masses};
pub use range::{at_unit, own_value, with_values, ParamRange, Spacing, ACCEL_SCALE_PATH};
pub use size::Size;
pub use stops::{HertzLineStop, HertzPointStiffness, Stop, StopLaw, Stops};
pub use suspension::Suspension;
pub use transducer::{AreaOverlapPair, Electromagnetic, GapClosingPair, Piezoelectric, Transducer};

/// Which force law a Hertz line stop follows: the paper's eq 6, or its linear fit of eq 19.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StiffnessModel {
    /// Hertz line contact, eq 6, inverted with the lower Lambert W branch.
    Hertz,
    /// Linear spring with the stiffness of eq 19.
    Linear,
}

/// Lumped mechanical parameters (the left-hand side of eq 7 without the transducer and the
/// stops).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mechanics {
    /// Proof mass m (kg).
    pub mass_kg: f64,
    /// Suspension stiffness km (N/m). With a nonlinear [`Mechanics::suspension`] it is derived
    /// on load: the small-oscillation stiffness at the reference well (see [`suspension`]).
    pub stiffness_n_per_m: f64,
    /// Mechanical damping b (N s/m).
    pub damping_n_s_per_m: f64,
    /// A measured resonance frequency (Hz), where one is known; the paper quotes one per
    /// prototype, used only for the `m w0 / b` reading of Qm in Table 3.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub measured_resonance_hz: Option<f64>,
    /// The restoring force: linear (`stiffness_n_per_m`), a polynomial or a double well.
    #[serde(skip)]
    pub suspension: Suspension,
}

/// A complete device description.
#[derive(Debug, Clone, PartialEq)]
pub struct Device {
    /// Short name, e.g. `prototype1`.
    pub name: String,
    /// Which parameter set this is (`published`, `calibrated`, or a user label).
    pub params: String,
    /// One-line description and provenance of the numbers.
    pub description: String,
    /// Mass, suspension and its damping.
    pub mechanics: Mechanics,
    /// The end-stops.
    pub stops: Stops,
    /// The transducer.
    pub transducer: Transducer,
    /// The interface circuit between a one-load transducer and its load (resistive by
    /// default; see [`interface`]).
    pub interface: Interface,
    /// The masses, springs, dampers and stops of a device of several masses ([`masses`]);
    /// `None` for one mass. With several, [`Device::mechanics`] summarises them (the total
    /// mass, the springs to the frame, and the damping whose ring-up time `2 m / b`, which
    /// the studies settle over, is the slowest mass's) and [`Device::stops`] is empty.
    pub masses: Option<Masses>,
    /// The device's volume, where the file gives one (`[size]`, [`size`]).
    pub size: Option<Size>,
}

/// The file form of a device.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawDevice {
    name: String,
    params: String,
    description: String,
    mechanics: suspension::RawMechanics,
    #[serde(default)]
    stops: stops::RawStops,
    transducer: Transducer,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    interface: Option<interface::RawInterface>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    size: Option<Size>,
}

impl RawDevice {
    /// The device of one mass this file form describes, before [`Device::validate`].
    fn parse(self, c: &Checker) -> Result<Device, ParamError> {
        let mut dev = Device {
            interface: match self.interface {
                Some(i) => i.parse(c)?,
                None => Interface::Resistive,
            },
            stops: self.stops.parse(c)?,
            name: self.name,
            params: self.params,
            description: self.description,
            mechanics: self.mechanics.parse(c)?,
            transducer: self.transducer,
            masses: None,
            size: self.size,
        };
        dev.derive_well_stiffness();
        Ok(dev)
    }
}

impl Device {
    /// Parses and validates a device from TOML text; `source_name` (a file name) is quoted in
    /// every error message. Files of the earlier format load too (see the module docs).
    ///
    /// ```
    /// use endstop::device::{Device, StopLaw, Transducer};
    /// let text = r#"
    /// name = "cantilever"
    /// params = "example"
    /// description = "a piezoelectric cantilever against a one-sided stop"
    /// [mechanics]
    /// mass_kg = 1e-3
    /// stiffness_n_per_m = 400.0
    /// damping_n_s_per_m = 2e-3
    /// [stops.upper]
    /// gap_m = 1e-3
    /// law = "restitution"
    /// coefficient = 0.7
    /// [transducer]
    /// kind = "piezoelectric"
    /// coupling_n_per_v = 1e-4
    /// capacitance_f = 20e-9
    /// load_resistance_ohm = 100e3
    /// "#;
    /// let dev = Device::from_toml_str(text, "cantilever.toml").unwrap();
    /// assert!(dev.stops.lower.is_none());
    /// assert!(matches!(dev.stops.upper.unwrap().law, StopLaw::Restitution { .. }));
    /// assert_eq!(dev.transducer.key(), "piezoelectric");
    /// ```
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Self, ParamError> {
        let parse_err = |message: String| ParamError::Parse {
            source_name: source_name.to_string(),
            message,
        };
        let table: toml::Table = toml::from_str(text).map_err(|e| parse_err(e.to_string()))?;
        let dev = if table.contains_key("masses") {
            Self::several_masses(table, source_name)?
        } else if legacy::LEGACY_SECTIONS
            .iter()
            .any(|s| table.contains_key(*s))
        {
            let old: legacy::LegacyDevice = toml::from_str(text)
                .map_err(|e| parse_err(format!("{e}\n({})", legacy::MAPPING)))?;
            old.convert()
        } else {
            let raw: RawDevice = toml::from_str(text).map_err(|e| parse_err(e.to_string()))?;
            raw.parse(&Checker {
                source: source_name,
            })?
        };
        dev.validate(source_name)?;
        Ok(dev)
    }

    fn raw(&self) -> RawDevice {
        RawDevice {
            name: self.name.clone(),
            params: self.params.clone(),
            description: self.description.clone(),
            mechanics: suspension::RawMechanics::of(&self.mechanics),
            stops: stops::RawStops::of(&self.stops),
            transducer: self.transducer.clone(),
            interface: interface::RawInterface::of(&self.interface),
            size: self.size,
        }
    }

    /// A device of several masses from its file's table ([`masses`]).
    fn several_masses(mut table: toml::Table, source_name: &str) -> Result<Self, ParamError> {
        let c = Checker {
            source: source_name,
        };
        if table.contains_key("mechanics") {
            return Err(c.message(
                "mechanics",
                "a file of several masses describes its mechanics in `[[masses]]`, \
                 `[[springs]]` and `[[dampers]]`",
            ));
        }
        let m = masses::RawMasses::take(&mut table, &c)?.parse(&c)?;
        // The common part: a one-mass file's keys less its mechanics and stops.
        table.insert("mechanics".into(), toml::Value::Table(toml::Table::new()));
        #[derive(Deserialize)]
        #[serde(deny_unknown_fields)]
        struct Common {
            name: String,
            params: String,
            description: String,
            #[allow(dead_code)]
            mechanics: toml::Table,
            transducer: Transducer,
            #[serde(default)]
            interface: Option<interface::RawInterface>,
            #[serde(default)]
            size: Option<Size>,
        }
        let raw: Common = toml::Value::Table(table)
            .try_into()
            .map_err(|e: toml::de::Error| ParamError::Parse {
                source_name: source_name.to_string(),
                message: e.to_string(),
            })?;
        Ok(Device {
            interface: match raw.interface {
                Some(i) => i.parse(&c)?,
                None => Interface::Resistive,
            },
            name: raw.name,
            params: raw.params,
            description: raw.description,
            mechanics: Mechanics {
                mass_kg: m.total_mass_kg(),
                stiffness_n_per_m: m.frame_stiffness_n_per_m(),
                damping_n_s_per_m: m.ring_damping_n_s_per_m(),
                measured_resonance_hz: None,
                suspension: Suspension::default(),
            },
            stops: Stops::default(),
            transducer: raw.transducer,
            masses: Some(m),
            size: raw.size,
        })
    }

    /// Serialises the device to TOML in the general format (for provenance records and
    /// fitted devices); [`Device::from_toml_str`] reads it back to an equal device.
    pub fn to_toml_string(&self) -> String {
        let Some(m) = &self.masses else {
            return toml::to_string(&self.raw()).expect("a validated device always serialises");
        };
        let mut t = match toml::Value::try_from(self.raw()) {
            Ok(toml::Value::Table(t)) => t,
            _ => toml::Table::new(),
        };
        t.remove("mechanics");
        t.remove("stops");
        masses::RawMasses::write(m, &mut t);
        toml::to_string(&t).expect("a validated device always serialises")
    }

    /// A one-load transducer (piezoelectric, electromagnetic) with no interface circuit needs
    /// its own resistive load.
    fn check_own_load(&self, c: &Checker) -> Result<(), ParamError> {
        if self.interface.kind().is_none()
            && matches!(
                self.transducer,
                Transducer::Piezoelectric(_) | Transducer::Electromagnetic(_)
            )
            && self.transducer.load_resistance_ohm() == f64::INFINITY
        {
            return Err(c.missing(
                "transducer.load_resistance_ohm",
                "the resistive load (or an [interface] table with another kind)",
            ));
        }
        Ok(())
    }

    /// Checks every field against its valid range, and the stops against the transducer.
    pub fn validate(&self, source_name: &str) -> Result<(), ParamError> {
        let c = Checker {
            source: source_name,
        };
        if self.name.trim().is_empty() {
            return Err(c.message("name", "must not be empty"));
        }
        if let Some(size) = &self.size {
            size.validate(&c)?;
        }
        if self.masses.is_some() {
            // The masses were checked on load ([`masses`]); the transducer and the interface
            // are checked as a one-mass file's.
            self.transducer.validate(&c)?;
            self.interface.validate(&self.transducer, &c)?;
            return self.check_own_load(&c);
        }
        let m = &self.mechanics;
        c.positive("mechanics.mass_kg", m.mass_kg)?;
        if m.suspension.is_linear() {
            c.positive("mechanics.stiffness_n_per_m", m.stiffness_n_per_m)?;
        }
        c.positive("mechanics.damping_n_s_per_m", m.damping_n_s_per_m)?;
        // The natural frequency sqrt(k/m) sets the integrator's scales and largest step: it
        // must be a normal positive number, not an overflow or an underflow of k/m.
        let w2 = m.stiffness_n_per_m / m.mass_kg;
        if m.stiffness_n_per_m.is_finite() && !(w2.is_normal() && w2 > 0.0) {
            return Err(c.message(
                "mechanics.stiffness_n_per_m",
                &format!(
                    "over mechanics.mass_kg gives k/m = {w2:e} (1/s^2): the natural frequency \
                     sqrt(k/m) must be a finite positive number"
                ),
            ));
        }
        if let Some(f) = m.measured_resonance_hz {
            c.positive("mechanics.measured_resonance_hz", f)?;
        }
        self.transducer.validate(&c)?;
        // The interface circuit: which transducers take it, and the resistive load it replaces.
        self.interface.validate(&self.transducer, &c)?;
        self.check_own_load(&c)?;
        for (side, stop) in self.stops.present() {
            let field = |key: &str| format!("{}.{key}", self.stop_path(side));
            c.positive(&field("gap_m"), stop.gap_m)?;
            c.non_negative(&field("damping_n_s_per_m"), stop.damping_n_s_per_m)?;
            if !stop.law.takes_viscous_damper() && stop.damping_n_s_per_m != 0.0 {
                return Err(c.message(
                    &field("damping_n_s_per_m"),
                    &format!("law `{}` takes no viscous damper", stop.law.key()),
                ));
            }
            match &self.transducer {
                Transducer::AreaOverlapPair(p) if stop.gap_m > p.finger_overlap_m => {
                    return Err(c.err(
                        &field("gap_m"),
                        stop.gap_m,
                        &format!(
                            "<= transducer.finger_overlap_m = {:e} (the fingers must not \
                             disengage)",
                            p.finger_overlap_m
                        ),
                    ));
                }
                Transducer::GapClosingPair(p) if stop.gap_m >= p.electrode_gap_m => {
                    return Err(c.err(
                        &field("gap_m"),
                        stop.gap_m,
                        &format!(
                            "< transducer.electrode_gap_m = {:e} (the electrodes must not touch)",
                            p.electrode_gap_m
                        ),
                    ));
                }
                _ => {}
            }
        }
        self.validate_suspension(&c)?;
        if let Transducer::GapClosingPair(p) = &self.transducer {
            let k = m.stiffness_n_per_m + p.electrostatic_stiffness_n_per_m();
            if k <= 0.0 {
                let limit = (m.stiffness_n_per_m * p.electrode_gap_m * p.electrode_gap_m
                    / (2.0 * p.c0_f))
                    .sqrt();
                return Err(c.err(
                    "transducer.bias_v",
                    p.bias_v,
                    &format!(
                        "< {limit:e} V (pull-in: the electrostatic spring -2 C0 Vb^2/d0^2 \
                         must not exceed mechanics.stiffness_n_per_m)"
                    ),
                ));
            }
        }
        Ok(())
    }

    /// The dotted path of a side's stop in this device's file form (`stops.both` for a
    /// symmetric pair).
    pub fn stop_path(&self, side: Side) -> &'static str {
        match (self.stops.symmetric().is_some(), side) {
            (true, _) => "stops.both",
            (false, Side::Upper) => "stops.upper",
            (false, Side::Lower) => "stops.lower",
        }
    }

    /// The bias voltage of an electrostatic transducer (V), if it has one.
    pub fn bias_v(&self) -> Option<f64> {
        self.transducer.bias_v()
    }

    /// A copy with another bias voltage (a device without an electrostatic transducer is
    /// returned unchanged).
    pub fn with_bias(&self, bias_v: f64) -> Self {
        let mut d = self.clone();
        match &mut d.transducer {
            Transducer::AreaOverlapPair(p) => p.bias_v = bias_v,
            Transducer::GapClosingPair(p) => p.bias_v = bias_v,
            _ => {}
        }
        d
    }

    /// A copy whose stops (those that take eq 1's damper) are tension-free or not.
    pub fn with_tension_free(&self, tension_free: bool) -> Self {
        let mut d = self.clone();
        d.stops.for_each_mut(|s| {
            if s.law.takes_viscous_damper() {
                s.tension_free = tension_free;
            }
        });
        d
    }

    /// A copy with every present stop at `gap_m`.
    pub fn with_stop_gap(&self, gap_m: f64) -> Self {
        let mut d = self.clone();
        d.stops.for_each_mut(|s| s.gap_m = gap_m);
        d
    }

    /// A copy without stops (a device of several masses loses its stops too).
    pub fn without_stops(&self) -> Self {
        let mut d = self.clone();
        d.stops = Stops::default();
        if let Some(m) = &mut d.masses {
            m.stops.clear();
        }
        d
    }

    /// The undamped natural frequency of the suspension alone, sqrt(km/m) (rad/s).
    pub fn suspension_omega_rad_s(&self) -> f64 {
        (self.mechanics.stiffness_n_per_m / self.mechanics.mass_kg).sqrt()
    }

    /// The mass the drive acts on (kg): the proof mass of a device of one mass; of several,
    /// [`Masses::driven_mass_kg`] (the total under the frame's acceleration). White noise of
    /// two-sided density `Sa` puts the mean power `M Sa / 2` into the device with this `M`.
    pub fn driven_mass_kg(&self) -> f64 {
        self.masses
            .as_ref()
            .map_or(self.mechanics.mass_kg, Masses::driven_mass_kg)
    }
}

/// A device serialises as its TOML text (the file form), so that any serde format can carry
/// it and reading it back validates it like a file.
impl Serialize for Device {
    fn serialize<S: serde::Serializer>(&self, s: S) -> Result<S::Ok, S::Error> {
        s.serialize_str(&self.to_toml_string())
    }
}

impl<'de> Deserialize<'de> for Device {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        let text = String::deserialize(d)?;
        Device::from_toml_str(&text, "serialised device").map_err(serde::de::Error::custom)
    }
}

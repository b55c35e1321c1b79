//! Device parameters (paper Tables 1 and 2, plus the material and end-stop options).
//!
//! A device is described by a TOML file in `data/` (see `data/prototype1.toml`). Every value is
//! in SI units, and the key names carry the unit (`mass_kg`, `c0_f`). Parsing is strict: unknown
//! keys are rejected, and [`Device::validate`] checks every field against its valid range,
//! returning a [`ParamError`] that names the field, the value and the range.
//!
//! This module parses text it is given; reading the file is the caller's job (no I/O here).

use serde::{Deserialize, Serialize};
use thiserror::Error;

/// A parameter that failed to load or validate.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum ParamError {
    /// The text is not valid TOML for a device, or has unknown or missing keys.
    #[error("{source_name}: {message}")]
    Parse {
        /// Where the text came from (a file name).
        source_name: String,
        /// The TOML parser's message.
        message: String,
    },
    /// A field is outside its valid range.
    #[error("{source_name}: field `{field}` = {value:e} is out of range: must be {range}")]
    OutOfRange {
        /// Where the text came from (a file name).
        source_name: String,
        /// Dotted path of the field, e.g. `mechanics.mass_kg`.
        field: String,
        /// The offending value.
        value: f64,
        /// Human-readable valid range.
        range: String,
    },
}

/// Which force law the end-stop spring follows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum StiffnessModel {
    /// Hertz line contact, eq 6, inverted with the lower Lambert W branch.
    Hertz,
    /// Linear spring with the stiffness of eq 19.
    Linear,
}

/// Device geometry (Table 1).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Geometry {
    /// Device layer thickness t (m); also the length of the contact line.
    pub thickness_m: f64,
    /// Gap between capacitor fingers g0 (m).
    pub finger_gap_m: f64,
    /// Number of capacitor fingers on each electrode Nf.
    pub fingers_per_electrode: u32,
    /// Initial finger overlap x0 (m).
    pub finger_overlap_m: f64,
    /// End-stop position xmax (m): contact starts when |x| > xmax.
    pub endstop_gap_m: f64,
    /// Radius R of the cylindrical end-stop bump (m).
    pub bump_radius_m: f64,
}

/// Lumped mechanical parameters (Table 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Mechanics {
    /// Proof mass m (kg).
    pub mass_kg: f64,
    /// Suspension stiffness km (N/m).
    pub stiffness_n_per_m: f64,
    /// Mechanical damping b (N s/m).
    pub damping_n_s_per_m: f64,
    /// Measured resonance frequency (Hz) quoted in the paper, used only for the
    /// `m w0 / b` reading of Qm in Table 3.
    pub measured_resonance_hz: f64,
}

/// Electrical parameters (Table 2).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Electrical {
    /// Nominal transducer capacitance C0 (F).
    pub c0_f: f64,
    /// Parasitic capacitance Cp in parallel with each transducer (F).
    pub cp_f: f64,
    /// Load resistance RL on each electrode (ohm).
    pub load_resistance_ohm: f64,
    /// Load capacitance CL on each electrode (F).
    pub load_capacitance_f: f64,
    /// Default bias voltage Vb (V); experiments may override it.
    pub bias_v: f64,
}

/// Elastic constants of the contacting bodies (not given in the paper).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Material {
    /// Young's modulus E (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson's ratio nu.
    pub poisson_ratio: f64,
}

/// End-stop model options (eq 1, eq 19).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct EndStop {
    /// Spring law of the stop.
    pub stiffness: StiffnessModel,
    /// End-stop damping b_im (N s/m).
    pub damping_n_s_per_m: f64,
    /// Coefficient c of eq 19, k_im = c pi E t / (1 - nu^2); the paper prints 0.058.
    pub linear_coefficient: f64,
    /// If true the contact force is clipped at zero, so the damper cannot pull the mass back
    /// while it leaves the stop (the paper is silent; eq 1 read literally allows tension).
    pub tension_free: bool,
}

/// A complete device description.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Device {
    /// Short name, e.g. `prototype1`.
    pub name: String,
    /// Which parameter set this is (`published`, `calibrated`, or a user label).
    pub params: String,
    /// One-line description and provenance.
    pub description: String,
    /// Table 1.
    pub geometry: Geometry,
    /// Table 2 (mechanical part).
    pub mechanics: Mechanics,
    /// Table 2 (electrical part).
    pub electrical: Electrical,
    /// Material constants.
    pub material: Material,
    /// End-stop options.
    pub endstop: EndStop,
}

struct Checker<'a> {
    source: &'a str,
}

impl Checker<'_> {
    fn err(&self, field: &str, value: f64, range: &str) -> ParamError {
        ParamError::OutOfRange {
            source_name: self.source.to_string(),
            field: field.to_string(),
            value,
            range: range.to_string(),
        }
    }
    fn positive(&self, field: &str, v: f64) -> Result<(), ParamError> {
        if v.is_finite() && v > 0.0 {
            Ok(())
        } else {
            Err(self.err(field, v, "finite and > 0"))
        }
    }
    fn non_negative(&self, field: &str, v: f64) -> Result<(), ParamError> {
        if v.is_finite() && v >= 0.0 {
            Ok(())
        } else {
            Err(self.err(field, v, "finite and >= 0"))
        }
    }
    fn within(&self, field: &str, v: f64, lo: f64, hi: f64, range: &str) -> Result<(), ParamError> {
        if v.is_finite() && v > lo && v < hi {
            Ok(())
        } else {
            Err(self.err(field, v, range))
        }
    }
}

impl Device {
    /// Parses and validates a device from TOML text; `source_name` (a file name) is quoted in
    /// every error message.
    pub fn from_toml_str(text: &str, source_name: &str) -> Result<Self, ParamError> {
        let dev: Device = toml::from_str(text).map_err(|e| ParamError::Parse {
            source_name: source_name.to_string(),
            message: e.to_string(),
        })?;
        dev.validate(source_name)?;
        Ok(dev)
    }

    /// Serialises the device back to TOML (for provenance records).
    pub fn to_toml_string(&self) -> String {
        toml::to_string(self).expect("a validated device always serialises")
    }

    /// Checks every field against its valid range.
    pub fn validate(&self, source_name: &str) -> Result<(), ParamError> {
        let c = Checker {
            source: source_name,
        };
        let g = &self.geometry;
        c.positive("geometry.thickness_m", g.thickness_m)?;
        c.positive("geometry.finger_gap_m", g.finger_gap_m)?;
        if g.fingers_per_electrode == 0 {
            return Err(c.err("geometry.fingers_per_electrode", 0.0, "an integer >= 1"));
        }
        c.positive("geometry.finger_overlap_m", g.finger_overlap_m)?;
        c.positive("geometry.endstop_gap_m", g.endstop_gap_m)?;
        if g.endstop_gap_m > g.finger_overlap_m {
            return Err(c.err(
                "geometry.endstop_gap_m",
                g.endstop_gap_m,
                &format!(
                    "<= geometry.finger_overlap_m = {:e} (the fingers must not disengage)",
                    g.finger_overlap_m
                ),
            ));
        }
        c.positive("geometry.bump_radius_m", g.bump_radius_m)?;
        let m = &self.mechanics;
        c.positive("mechanics.mass_kg", m.mass_kg)?;
        c.positive("mechanics.stiffness_n_per_m", m.stiffness_n_per_m)?;
        c.positive("mechanics.damping_n_s_per_m", m.damping_n_s_per_m)?;
        c.positive("mechanics.measured_resonance_hz", m.measured_resonance_hz)?;
        let e = &self.electrical;
        c.positive("electrical.c0_f", e.c0_f)?;
        c.non_negative("electrical.cp_f", e.cp_f)?;
        c.positive("electrical.load_resistance_ohm", e.load_resistance_ohm)?;
        c.non_negative("electrical.load_capacitance_f", e.load_capacitance_f)?;
        c.non_negative("electrical.bias_v", e.bias_v)?;
        let mat = &self.material;
        c.within(
            "material.youngs_modulus_pa",
            mat.youngs_modulus_pa,
            1e6,
            1e13,
            "between 1e6 and 1e13 Pa",
        )?;
        c.within(
            "material.poisson_ratio",
            mat.poisson_ratio,
            -1.0,
            0.5,
            "between -1 and 0.5 (exclusive)",
        )?;
        let s = &self.endstop;
        c.non_negative("endstop.damping_n_s_per_m", s.damping_n_s_per_m)?;
        c.positive("endstop.linear_coefficient", s.linear_coefficient)?;
        if self.name.trim().is_empty() {
            return Err(ParamError::Parse {
                source_name: source_name.to_string(),
                message: "field `name` must not be empty".into(),
            });
        }
        Ok(())
    }

    /// A copy with another bias voltage.
    pub fn with_bias(&self, bias_v: f64) -> Self {
        let mut d = self.clone();
        d.electrical.bias_v = bias_v;
        d
    }

    /// A copy with another end-stop law and damping.
    pub fn with_endstop(&self, stiffness: StiffnessModel, damping_n_s_per_m: f64) -> Self {
        let mut d = self.clone();
        d.endstop.stiffness = stiffness;
        d.endstop.damping_n_s_per_m = damping_n_s_per_m;
        d
    }

    /// Nominal capacitance evaluated from the finger geometry, eq 10:
    /// C0 = 2 Nf eps0 x0 t / g0 (it differs from Table 2's C0; see the book).
    pub fn c0_from_geometry_f(&self) -> f64 {
        const EPS0: f64 = 8.854_187_812_8e-12;
        let g = &self.geometry;
        2.0 * g.fingers_per_electrode as f64 * EPS0 * g.finger_overlap_m * g.thickness_m
            / g.finger_gap_m
    }

    /// Stiffness of the linear end-stop law, eq 19: k_im = c pi E t / (1 - nu^2).
    pub fn linear_endstop_stiffness_n_per_m(&self) -> f64 {
        let mat = &self.material;
        self.endstop.linear_coefficient
            * std::f64::consts::PI
            * mat.youngs_modulus_pa
            * self.geometry.thickness_m
            / (1.0 - mat.poisson_ratio * mat.poisson_ratio)
    }
}

//! The earlier device format, which described only the paper's topology: sections
//! `[geometry]`, `[mechanics]`, `[electrical]`, `[material]` and `[endstop]`. It still loads,
//! and is read as the general description: one Hertz line stop for both sides
//! (`[stops.both]`, law `hertz_line`) and the area-overlap comb pair (`[transducer]`, kind
//! `area_overlap_pair`).

use serde::Deserialize;

use super::stops::{HertzLineStop, Stop, StopLaw, Stops};
use super::transducer::{AreaOverlapPair, Transducer};
use super::{Device, Mechanics, StiffnessModel};

/// The sections that mark a file of the earlier format.
pub(super) const LEGACY_SECTIONS: [&str; 4] = ["geometry", "electrical", "material", "endstop"];

/// How the earlier format maps onto the general one, for error messages.
pub(super) const MAPPING: &str = "the earlier format ([geometry], [electrical], [material], \
[endstop]) is read as [stops.both] (law = \"hertz_line\": gap_m, contact_length_m, \
bump_radius_m, youngs_modulus_pa, poisson_ratio, linear_fit, linear_coefficient, \
damping_n_s_per_m, tension_free) and [transducer] (kind = \"area_overlap_pair\": c0_f, cp_f, \
finger_overlap_m, load_resistance_ohm, load_capacitance_f, bias_v, thickness_m, finger_gap_m, \
fingers_per_electrode)";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub(super) struct LegacyDevice {
    name: String,
    params: String,
    description: String,
    geometry: Geometry,
    mechanics: LegacyMechanics,
    electrical: Electrical,
    material: Material,
    endstop: EndStop,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Geometry {
    thickness_m: f64,
    finger_gap_m: f64,
    fingers_per_electrode: u32,
    finger_overlap_m: f64,
    endstop_gap_m: f64,
    bump_radius_m: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct LegacyMechanics {
    mass_kg: f64,
    stiffness_n_per_m: f64,
    damping_n_s_per_m: f64,
    measured_resonance_hz: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Electrical {
    c0_f: f64,
    cp_f: f64,
    load_resistance_ohm: f64,
    load_capacitance_f: f64,
    bias_v: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct Material {
    youngs_modulus_pa: f64,
    poisson_ratio: f64,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct EndStop {
    stiffness: StiffnessModel,
    damping_n_s_per_m: f64,
    linear_coefficient: f64,
    tension_free: bool,
}

impl LegacyDevice {
    /// The same device in the general description (not yet validated).
    pub(super) fn convert(self) -> Device {
        let g = self.geometry;
        let e = self.electrical;
        let stop = Stop {
            gap_m: g.endstop_gap_m,
            law: StopLaw::HertzLine(HertzLineStop {
                contact_length_m: g.thickness_m,
                bump_radius_m: g.bump_radius_m,
                youngs_modulus_pa: self.material.youngs_modulus_pa,
                poisson_ratio: self.material.poisson_ratio,
                linear_fit: self.endstop.stiffness == StiffnessModel::Linear,
                linear_coefficient: self.endstop.linear_coefficient,
            }),
            damping_n_s_per_m: self.endstop.damping_n_s_per_m,
            tension_free: self.endstop.tension_free,
        };
        Device {
            name: self.name,
            params: self.params,
            description: self.description,
            mechanics: Mechanics {
                mass_kg: self.mechanics.mass_kg,
                stiffness_n_per_m: self.mechanics.stiffness_n_per_m,
                suspension: super::Suspension::Linear,
                damping_n_s_per_m: self.mechanics.damping_n_s_per_m,
                measured_resonance_hz: Some(self.mechanics.measured_resonance_hz),
            },
            stops: Stops {
                upper: Some(stop.clone()),
                lower: Some(stop),
            },
            transducer: Transducer::AreaOverlapPair(AreaOverlapPair {
                c0_f: e.c0_f,
                cp_f: e.cp_f,
                finger_overlap_m: g.finger_overlap_m,
                load_resistance_ohm: e.load_resistance_ohm,
                load_capacitance_f: e.load_capacitance_f,
                bias_v: e.bias_v,
                thickness_m: Some(g.thickness_m),
                finger_gap_m: Some(g.finger_gap_m),
                fingers_per_electrode: Some(g.fingers_per_electrode),
            }),
            interface: super::Interface::Resistive,
            masses: None,
            size: None,
        }
    }
}

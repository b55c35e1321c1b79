//! The transducer of a device: how the proof mass's motion becomes electrical power.
//!
//! | `kind` | model | state beside (x, v) |
//! |---|---|---|
//! | `area_overlap_pair` | the paper's two anti-phase comb capacitors `C = C0 (1 +- x/x0)` (eq 10), bias on the proof mass, each electrode loaded by `RL` parallel `CL` (eqs 7-9) | both node charges |
//! | `gap_closing_pair` | two parallel-plate capacitors `C = C0 d0 / (d0 -+ x)`, wired as the paper's pair | both node charges |
//! | `piezoelectric` | the lumped single-mode model, `m x'' + ... - theta V = m a`, `Cp V' + V / R + theta x' = 0` | the load voltage V |
//! | `electromagnetic` | a coil in a magnet's field, `m x'' + ... + Phi I = m a`, `L I' + (Rc + R) I = Phi x'` | the coil current I (none when L = 0) |
//! | `none` | no transducer | none |
//!
//! The sign conventions are the project's (eq 7 with `+ m a(t)` on the right); the textbook
//! forms (Erturk and Inman 2011 for the piezoelectric model, Williams and Yates 1996 for the
//! electromagnetic one) write `- m a`, which only flips the phase of the response.

use serde::{Deserialize, Serialize};

use super::{Checker, ParamError};

/// The vacuum permittivity (F/m).
pub const EPS0_F_PER_M: f64 = 8.854_187_812_8e-12;

/// The paper's area-overlap comb pair (eqs 7-10).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct AreaOverlapPair {
    /// Nominal capacitance C0 of each transducer (F).
    pub c0_f: f64,
    /// Parasitic capacitance Cp in parallel with each transducer (F).
    pub cp_f: f64,
    /// Initial finger overlap x0 (m): `C = C0 (1 +- x/x0)`.
    pub finger_overlap_m: f64,
    /// Load resistance RL on each electrode (ohm).
    pub load_resistance_ohm: f64,
    /// Load capacitance CL on each electrode (F).
    pub load_capacitance_f: f64,
    /// Bias voltage Vb on the proof mass (V).
    pub bias_v: f64,
    /// Finger length along the motion's normal, the device layer thickness t (m); with
    /// `finger_gap_m` and `fingers_per_electrode` it gives eq 10's C0 from geometry.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub thickness_m: Option<f64>,
    /// Gap between fingers g0 (m).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub finger_gap_m: Option<f64>,
    /// Fingers per electrode Nf.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub fingers_per_electrode: Option<u32>,
}

impl AreaOverlapPair {
    /// C0 from the finger geometry, eq 10: `2 Nf eps0 x0 t / g0` (F), when the geometry is
    /// given.
    pub fn c0_from_geometry_f(&self) -> Option<f64> {
        Some(
            2.0 * self.fingers_per_electrode? as f64
                * EPS0_F_PER_M
                * self.finger_overlap_m
                * self.thickness_m?
                / self.finger_gap_m?,
        )
    }
}

/// Two parallel-plate (gap-closing) capacitors wired as the paper's pair.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct GapClosingPair {
    /// Capacitance C0 of each transducer at rest (F).
    pub c0_f: f64,
    /// Electrode gap d0 at rest (m): `C = C0 d0 / (d0 -+ x)`.
    pub electrode_gap_m: f64,
    /// Parasitic capacitance Cp in parallel with each transducer (F).
    pub cp_f: f64,
    /// Load resistance on each electrode (ohm).
    pub load_resistance_ohm: f64,
    /// Load capacitance on each electrode (F).
    pub load_capacitance_f: f64,
    /// Bias voltage on the proof mass (V).
    pub bias_v: f64,
}

impl GapClosingPair {
    /// The electrostatic spring at rest with both loads short at DC, `-2 C0 Vb^2 / d0^2`
    /// (N/m): the suspension must be stiffer, or the rest position is unstable (pull-in).
    pub fn electrostatic_stiffness_n_per_m(&self) -> f64 {
        -2.0 * self.c0_f * self.bias_v * self.bias_v / (self.electrode_gap_m * self.electrode_gap_m)
    }
}

/// The lumped single-mode piezoelectric harvester with a resistive load.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Piezoelectric {
    /// Electromechanical coupling theta (N/V, equivalently C/m).
    pub coupling_n_per_v: f64,
    /// Clamped capacitance of the piezoelectric layer Cp (F).
    pub capacitance_f: f64,
    /// Load resistance R (ohm); absent (infinite: no resistive load) when an `[interface]` circuit is the load.
    #[serde(default = "absent", skip_serializing_if = "is_absent")]
    pub load_resistance_ohm: f64,
}

/// The value of a resistive load left out because an interface circuit replaces it.
fn absent() -> f64 {
    f64::INFINITY
}

fn is_absent(v: &f64) -> bool {
    *v == f64::INFINITY
}

/// A coil moving in a magnet's field, with a resistive load.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Electromagnetic {
    /// Transduction factor Phi (N/A, equivalently V s/m): B l for a coil of length l.
    pub transduction_n_per_a: f64,
    /// Coil resistance Rc (ohm).
    pub coil_resistance_ohm: f64,
    /// Coil inductance L (H); zero makes the current follow the velocity at once.
    pub coil_inductance_h: f64,
    /// Load resistance R (ohm); absent (infinite: no resistive load) when an `[interface]` circuit is the load.
    #[serde(default = "absent", skip_serializing_if = "is_absent")]
    pub load_resistance_ohm: f64,
}

/// The transducer of a device (see the module docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "snake_case")]
pub enum Transducer {
    /// No transducer.
    None,
    /// The paper's area-overlap comb pair.
    AreaOverlapPair(AreaOverlapPair),
    /// Two gap-closing capacitors.
    GapClosingPair(GapClosingPair),
    /// Single-mode piezoelectric.
    Piezoelectric(Piezoelectric),
    /// Electromagnetic.
    Electromagnetic(Electromagnetic),
}

impl Transducer {
    /// The `kind` key.
    pub fn key(&self) -> &'static str {
        match self {
            Transducer::None => "none",
            Transducer::AreaOverlapPair(_) => "area_overlap_pair",
            Transducer::GapClosingPair(_) => "gap_closing_pair",
            Transducer::Piezoelectric(_) => "piezoelectric",
            Transducer::Electromagnetic(_) => "electromagnetic",
        }
    }

    /// The bias voltage of an electrostatic transducer (V).
    pub fn bias_v(&self) -> Option<f64> {
        match self {
            Transducer::AreaOverlapPair(p) => Some(p.bias_v),
            Transducer::GapClosingPair(p) => Some(p.bias_v),
            _ => None,
        }
    }

    /// The load resistance (ohm): of each electrode for a pair; infinite without a
    /// transducer.
    pub fn load_resistance_ohm(&self) -> f64 {
        match self {
            Transducer::None => f64::INFINITY,
            Transducer::AreaOverlapPair(p) => p.load_resistance_ohm,
            Transducer::GapClosingPair(p) => p.load_resistance_ohm,
            Transducer::Piezoelectric(p) => p.load_resistance_ohm,
            Transducer::Electromagnetic(p) => p.load_resistance_ohm,
        }
    }

    /// Number of loads (two for a pair).
    pub fn loads(&self) -> usize {
        match self {
            Transducer::None => 0,
            Transducer::AreaOverlapPair(_) | Transducer::GapClosingPair(_) => 2,
            Transducer::Piezoelectric(_) | Transducer::Electromagnetic(_) => 1,
        }
    }

    pub(super) fn validate(&self, c: &Checker) -> Result<(), ParamError> {
        match self {
            Transducer::None => Ok(()),
            Transducer::AreaOverlapPair(p) => {
                c.positive("transducer.c0_f", p.c0_f)?;
                c.non_negative("transducer.cp_f", p.cp_f)?;
                c.positive("transducer.finger_overlap_m", p.finger_overlap_m)?;
                c.positive("transducer.load_resistance_ohm", p.load_resistance_ohm)?;
                c.non_negative("transducer.load_capacitance_f", p.load_capacitance_f)?;
                c.non_negative("transducer.bias_v", p.bias_v)?;
                if let Some(t) = p.thickness_m {
                    c.positive("transducer.thickness_m", t)?;
                }
                if let Some(g) = p.finger_gap_m {
                    c.positive("transducer.finger_gap_m", g)?;
                }
                if p.fingers_per_electrode == Some(0) {
                    return Err(c.err("transducer.fingers_per_electrode", 0.0, "an integer >= 1"));
                }
                Ok(())
            }
            Transducer::GapClosingPair(p) => {
                c.positive("transducer.c0_f", p.c0_f)?;
                c.positive("transducer.electrode_gap_m", p.electrode_gap_m)?;
                c.non_negative("transducer.cp_f", p.cp_f)?;
                c.positive("transducer.load_resistance_ohm", p.load_resistance_ohm)?;
                c.non_negative("transducer.load_capacitance_f", p.load_capacitance_f)?;
                c.non_negative("transducer.bias_v", p.bias_v)
            }
            Transducer::Piezoelectric(p) => {
                c.positive("transducer.coupling_n_per_v", p.coupling_n_per_v)?;
                c.positive("transducer.capacitance_f", p.capacitance_f)?;
                // Absent (infinite) with an interface circuit: `Device::validate` checks which.
                if p.load_resistance_ohm == f64::INFINITY {
                    return Ok(());
                }
                c.positive("transducer.load_resistance_ohm", p.load_resistance_ohm)
            }
            Transducer::Electromagnetic(p) => {
                c.positive("transducer.transduction_n_per_a", p.transduction_n_per_a)?;
                c.non_negative("transducer.coil_resistance_ohm", p.coil_resistance_ohm)?;
                c.non_negative("transducer.coil_inductance_h", p.coil_inductance_h)?;
                if p.load_resistance_ohm == f64::INFINITY {
                    return Ok(());
                }
                c.positive("transducer.load_resistance_ohm", p.load_resistance_ohm)
            }
        }
    }
}

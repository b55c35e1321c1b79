//! What the paper measured on its prototypes, as the simulations use it (targets and
//! reference frequencies). The paper's claimed numbers themselves are in `data/claims.toml`.

/// Prototype 1, Figure 8: the measured kink (impact onset) at 5.5 g, section 3.2 (Hz).
pub const P1_MEASURED_ONSET_HZ: f64 = 1135.0;

/// Prototype 1, Figure 8: the measured jump at 5.5 g, section 3.2 (Hz).
pub const P1_MEASURED_JUMP_HZ: f64 = 1425.0;

/// Figure 9's measured resonance frequency (Hz).
pub const P1_RESONANCE_HZ: f64 = 1220.0;

//! # endstop
//!
//! Reference reproduction of C. P. Le and E. Halvorsen, "MEMS electrostatic energy harvesters
//! with end-stop effects", J. Micromech. Microeng. 22 (2012) 074013.
//!
//! The crate holds the physics and numerics only (no file I/O); the experiment binaries in
//! `experiments/` load parameters, call it, and write Parquet, plots and summaries.
//!
//! | module | paper |
//! |---|---|
//! | [`params`] | Tables 1 and 2, validated device parameters |
//! | [`hertz`] | eqs 3-6 (Hertz line contact), Figure 5, eq 19 (linear fit) |
//! | [`linear`] | eqs 11-18, 21-22 (two-port, coupling, broadband efficiency) |
//! | [`model`] | eqs 1-2 and 7-10 (lumped time-domain model with end-stops) |
//! | [`integrator`] | Dormand-Prince 5(4) with dense output and event location |
//! | [`excitation`] | sinusoidal and sampled (random) accelerations |
//! | [`noise`] | band-limited white-noise generation (Figure 10) |
//! | [`spectral`] | Welch PSD estimation, bandwidths |
//! | [`spice`] | section 2.3, Figure 6: ngspice netlist export for cross-validation |
//! | [`sweep`] | stepped-sine sweeps with continuation, jump and onset detection |
//! | [`narrowband`] | Figures 8, 9, 13: sweeps, onsets, jumps, calibration, b_im fits |
//! | [`broadband`] | Figures 10-15: random-vibration records, ensembles, spectra |
//! | [`scorecard`] | claims, tolerances and verdicts |
//!
//! Units are SI throughout unless a name says otherwise (`accel_rms_g`, `freq_hz`).

pub mod broadband;
pub mod excitation;
pub mod hertz;
pub mod integrator;
pub mod linear;
pub mod model;
pub mod narrowband;
pub mod noise;
pub mod params;
pub mod scorecard;
pub mod spectral;
pub mod spice;
pub mod sweep;

/// Standard gravity used to convert accelerations quoted in g (SPEC 5: g = 9.81 m/s^2).
pub const G: f64 = 9.81;

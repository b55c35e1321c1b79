//! # endstop
//!
//! The lumped model of a MEMS electrostatic vibration energy harvester whose proof mass strikes
//! end-stops, and the numerics to simulate it, after C. P. Le and E. Halvorsen, "MEMS
//! electrostatic energy harvesters with end-stop effects", J. Micromech. Microeng. 22 (2012)
//! 074013. Equation numbers are the paper's.
//!
//! The crate holds the model and numerics only: it does no file I/O. The reproduction of the
//! paper's figures is one module apart ([`paper`]), which no model module imports; the
//! experiment binaries (the `endstop-experiments` package) load parameter files, call it, and
//! write Parquet, plots and the book's numbers.
//!
//! | module | what | paper |
//! |---|---|---|
//! | [`device`] | validated device parameters | Tables 1 and 2 |
//! | [`physics::hertz`] | Hertz line contact and its linear fit | eqs 3-6, 19, Figure 5 |
//! | [`physics::contact`] | end-stop modes and spring laws | eqs 1-2 |
//! | [`physics::harvester`] | the lumped time-domain model | eqs 7-10 |
//! | [`physics::energy`] | power terms and the energy audit | |
//! | [`physics::two_port`] | linear two-port, coupling, broadband efficiency | eqs 11-18, 21-22 |
//! | [`drive`] | sine, sampled and band-limited noise accelerations | Figure 10 |
//! | [`ode`] | Dormand-Prince 5(4) with dense output and event location | |
//! | [`num`] | root finding, sample statistics | |
//! | [`signal`] | Welch PSD, bandwidths | |
//! | [`study`] | steady states, frequency and amplitude sweeps, random records, ensembles | |
//! | [`spice`] | ngspice netlist export for cross-validation | section 2.3, Figure 6 |
//! | [`paper`] | the paper's setups, measurements, calibration, figures and claims | |
//! | [`validation`] | checks against closed forms, an exact law and a peer tool | |
//!
//! Units are SI throughout unless a name says otherwise (`accel_rms_g`, `freq_hz`).

pub mod device;
pub mod drive;
pub mod num;
pub mod ode;
pub mod paper;
pub mod physics;
pub mod signal;
pub mod spice;
pub mod study;
pub mod validation;

/// Standard gravity used to convert accelerations quoted in g (g = 9.81 m/s^2).
pub const G: f64 = 9.81;

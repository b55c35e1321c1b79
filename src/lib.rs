//! # endstop
//!
//! Lumped models of vibration energy harvesters whose proof mass strikes end-stops, and the
//! numerics to simulate and analyse them.
//!
//! # Conventions
//! Read these first; every function of the crate keeps them.
//!
//! * **Units.** SI throughout (m, s, kg, N, V, A, W, ohm, F), except where a name says
//!   otherwise: `accel_rms_g` is in g, `freq_hz` in Hz (frequencies are in Hz unless a name
//!   ends in `_rad_s`), `psd_g2_per_hz` in g^2/Hz. One g is [`G`] = 9.81 m/s^2 (not
//!   9.80665).
//! * **Axis and stops.** `x` is the proof mass's displacement from rest relative to the frame.
//!   The upper stop (`stops.upper`) touches at `x = +gap`, the lower one (`stops.lower`) at
//!   `x = -gap`; a stop's spring pushes the mass back towards rest.
//! * **The drive's sign.** The base acceleration `a(t)` enters the mechanics as
//!   `m x'' + b x' + km x + F_e + F_im = m a(t)` (eq 7): a positive `a` pushes the mass towards
//!   `+x`. It is the frame's own acceleration with the sign reversed (the inertial force
//!   `-m a_frame`); levels, densities and powers do not depend on the sign, phases do.
//! * **Sines by RMS.** A sine is given by its RMS acceleration: `a(t) = sqrt(2) a_rms
//!   sin(2 pi f t + phi)` ([`drive::Sine`]). RMS voltages are RMS too (`v1_rms_v`); powers are
//!   means over time.
//! * **Two-sided drive, one-sided outputs.** A random drive's level `Sa` is **two-sided**: the
//!   density per Hz over `-B..B`, so its mean square is `2 B Sa` ([`drive::noise`]); white
//!   noise of level `Sa` delivers the power `m Sa / 2` to a mass. Every density the crate
//!   estimates or predicts from a signal is **one-sided** (Welch's, [`signal::welch()`], and
//!   the linear theory's output PSD, [`physics::linear`]): over `f > 0`, twice the two-sided
//!   level, so that its integral is the variance or the mean power.
//! * **Randomness.** Every random record is a pure function of its settings, a seed and a
//!   stream ([`drive::noise::generate`]): runs are deterministic and do not depend on the
//!   number of threads.
//!
//! ## Words
//! The crate uses these words in one sense each, in names and in prose:
//!
//! * **device**: a validated description of a harvester's parts ([`device::Device`]: mechanics,
//!   stops, transducer, interface circuit), in the units its keys carry (`gap_m`,
//!   `load_resistance_ohm`), as a parameter file states it.
//! * **model**: the equations a device's parts assemble ([`model::Model`]): its state, modes,
//!   right-hand side and Jacobian, guards and switches, energy ledger and named outputs. The
//!   model's quantities use the paper's symbols (`km`, `b`, `vb`, `cp`) in SI units.
//! * **state layout**: the model's state components in order and their names and units
//!   ([`model::Layout`]): the mass's `x` and `v` first, then the transducer's or the circuit's
//!   (node charges `s1`, `s2`; a voltage `v` or `vp`; a coil current `i`; the storage `vs`).
//! * **study**: a computation over any model ([`study`]): a steady state, a sweep, a
//!   continuation, a record, an ensemble, basins, a fit, charging. A study never names a
//!   concrete device type.
//! * **sweep**: steady states at a sequence of drive frequencies or levels, each started from
//!   the last (stepped, ramped or chirped).
//! * **record**: one time series of a model under a sampled drive, with its outputs, spectra
//!   and energy ledger; an **ensemble** is several records of independent realisations of one
//!   random drive, with means and intervals.
//! * **run**: one invocation of a binary or command, writing one output directory.
//! * **setup**: a paper figure's device, drive and protocol ([`paper`]); a **claim** is a
//!   number or statement the paper makes about it, checked by a run; **deviations** are the
//!   claims the published parameters do not reproduce, with their causes.
//! * **Settings**: what a study is asked to do (ranges, tolerances, step sizes), one struct
//!   per study; a solver's (an integrator's, a root finder's, the shooting method's, an
//!   estimator's) are its `Options` ([`ode::Options`], [`num::roots::RootOptions`],
//!   [`study::orbit::ShootingOptions`], [`signal::WelchOptions`]). No type is a `Config`.
//!
//! Naming rule: descriptions carry units in their names (`freq_hz`, `accel_rms_g`), the
//! model uses the paper's symbols, and a unit is named wherever it is not SI or not obvious.
//!
//! The model began as that of C. P. Le and E. Halvorsen, "MEMS electrostatic energy
//! harvesters with end-stop effects", J. Micromech. Microeng. 22 (2012) 074013 (equation numbers are the paper's), and describes any
//! single-degree-of-freedom impact harvester: each side's stop absent or a gap and a contact
//! law, and an electrostatic, piezoelectric or electromagnetic transducer or none.
//!
//! The crate holds the model and numerics only: it does no file I/O. The reproduction of the
//! paper's figures is one module apart ([`paper`]), which no model module imports; the
//! experiment binaries (the `endstop-experiments` package) load parameter files, call it, and
//! write Parquet, plots and the book's numbers.
//!
//! | module | what | paper |
//! |---|---|---|
//! | [`device`] | validated device descriptions: mechanics, stops, transducer, interface | Tables 1 and 2 |
//! | [`circuits`] | the interface circuits behind a transducer, each kind one file: its keys, checks and model | |
//! | [`laws::hertz`] | Hertz line contact and its linear fit | eqs 3-6, 19, Figure 5 |
//! | [`laws::contact`] | contact modes and the stops' force laws | eqs 1-2 |
//! | [`laws::pair`] | the electrostatic pair's capacitances, node voltages and force | eqs 7-10 |
//! | [`physics::transducer`] | the transducers' forces, rates and loads | eqs 8-10 |
//! | [`model`] | the one model every study takes: modes, guards, switches, free flight split, energy ledger | |
//! | [`physics::harvester`] | the harvester assembled from a device's parts as a [`model::Model`], behind its interface circuit | eqs 7-10 |
//! | [`physics::linear`] | linear frequency response of any device | |
//! | [`physics::two_port`] | linear two-port, coupling, broadband efficiency | eqs 11-18, 21-22 |
//! | [`drive`] | sine, sampled and band-limited noise accelerations | Figure 10 |
//! | [`ode`] | Runge-Kutta stepping with dense output and event location | |
//! | [`fit`] | fitting a device to measured sweeps, with uncertainty | section 3.2 |
//! | [`num`] | root finding, sample statistics, comparisons with their verdicts, sensitivity designs | |
//! | [`progress`] | how far a long computation has come (shown as a bar by the binaries) | |
//! | [`signal`] | Welch PSD, bandwidths | |
//! | [`study`] | steady states, sweeps, periodic orbits and continuation, basins, random records, ensembles | |
//! | [`spice`] | ngspice netlist export for cross-validation | section 2.3, Figure 6 |
//! | [`paper`] | the paper's setups, measurements, calibration, figures and claims | |
//! | [`validation`] | checks against closed forms, an exact law and a peer tool | |
//!
//! # Start here
//! A device is a TOML file ([`device`]); the caller reads it, the library parses and validates
//! it. A stepped-sine sweep ([`study::sweep`]) then gives the steady state at each frequency:
//!
//! ```
//! use endstop::device::Device;
//! use endstop::progress::Silent;
//! use endstop::study::sweep::SweepSettings;
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype1.toml"));
//! let device = Device::from_toml_str(text, "prototype1.toml")?;
//!
//! // Three frequencies below the resonance at 0.02 g rms: the mass stays clear of the stops.
//! let sweep = SweepSettings::for_device(&device, vec![1000.0, 1100.0, 1200.0], 1.0);
//! let report = sweep.run(&device, 0.02, &Silent)?;
//! assert!(!report.any_contact());
//! let v1: Vec<f64> = report.measurements().map(|m| m.v1_rms_v).collect();
//! assert!(v1[0] < v1[1] && v1[1] < v1[2], "the response grows towards the resonance");
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```
//!
//! The periodic orbits themselves, stable and unstable, come from continuation
//! ([`study::continuation::frequency_branch`]); random vibration from records
//! ([`study::record::simulate_record`]) and ensembles of them
//! ([`study::ensemble::run_ensemble`]).

#![warn(missing_docs)]

mod check;
pub mod circuits;
pub mod design;
pub mod device;
pub mod drive;
pub mod fit;
pub mod laws;
pub mod model;
pub mod num;
pub mod ode;
pub mod paper;
pub mod physics;
pub mod progress;
pub mod signal;
pub mod spice;
pub mod study;
pub mod validation;

/// Standard gravity used to convert accelerations quoted in g (g = 9.81 m/s^2).
pub const G: f64 = 9.81;

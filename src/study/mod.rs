//! Studies built on the model and the integrator: the exact integration of a sine-driven
//! harvester's affine modes ([`flow`]), steady states under a sine ([`steady`]), the stepped-drive
//! engine ([`stepped`]) behind frequency sweeps ([`sweep`], up and down) and amplitude sweeps
//! ([`amplitude`]), the ramps ([`ramp`]) and swept sines ([`chirp`]) that make sweeps independent
//! of their step, periodic orbits by shooting with their Floquet multipliers ([`orbit`]), their
//! pseudo-arclength continuation with folds, branch points and grazing ([`continuation`]), basins
//! of attraction ([`basins`]) with the attractors found by settling seeds and placed by well
//! ([`attractors`]), and random-vibration records ([`record`]) and their ensembles ([`ensemble`];
//! one entry for any model, [`random`]), with the fixed-step RK4 record that is the benchmark's
//! yardstick ([`rk4_record`]), and Sobol indices of any quantity over device parameters the user
//! names ([`sensitivity`]). Every study takes any model, a device behind an interface circuit (a
//! diode bridge, SSHI, SECE) as well; such a device's storage has its periodic steady states
//! ([`periodic`]) and its charging runs ([`charging`]).

pub mod amplitude;
pub mod attractors;
pub mod basins;
pub mod charging;
pub mod chirp;
pub mod continuation;
pub mod displacement;
pub mod ensemble;
pub mod flow;
pub mod mass_peaks;
pub mod orbit;
pub mod periodic;
pub mod ramp;
pub mod random;
pub mod record;
pub mod record_ledger;
pub mod rk4_record;
pub mod sensitivity;
pub mod steady;
pub mod stepped;
pub mod sweep;

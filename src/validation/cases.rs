//! The cases of the book's "Validation against references" chapter: which drive, frequencies,
//! load range, ensemble and continuation settings each check runs with. The chapter's
//! experiment (`experiments/validation.rs`) and `tests/validation.rs` both call these, so that
//! every row the chapter prints is the row a test asserts.

use crate::device::{Device, Transducer};
use crate::drive::noise::NoiseSpec;
use crate::study::record::RecordSpec;
use crate::validation::linear_harvesters::{
    frequency_response_checks, optimal_load_checks, ClosedForm,
};
use crate::validation::random_law::{law_ensemble, LawEnsemble};
use crate::validation::{grazing, nlvib, Check, ValidationError};

/// The sine of the linear harvesters' checks (g rms); the responses are linear in it.
pub const LINEAR_ACCEL_RMS_G: f64 = 0.1;

/// The load range searched for a piezoelectric device's time-domain optimum (ohm).
pub const PIEZO_LOAD_RANGE_OHM: (f64, f64) = (1e2, 1e8);
/// The load range searched for an electromagnetic device's (ohm): a load far above the coil's
/// resistance makes the coil's time constant `L / (R + Rc)` far shorter than the period, and
/// the explicit integrator's steps with it.
pub const EM_LOAD_RANGE_OHM: (f64, f64) = (1.0, 1e4);
/// Points of the load scan per decade (logarithmically spaced) before Brent's method.
pub const LOAD_SCAN_PER_DECADE: usize = 5;

/// The random records: two-sided level (g^2/Hz), and each record's analysed length (s).
pub const RANDOM_PSD_G2_PER_HZ: f64 = 1e-3;
/// Analysed length of one record (s).
pub const RANDOM_RECORD_S: f64 = 5.0;
/// The band of the records' noise (Hz): the paper's.
pub const RANDOM_BANDWIDTH_HZ: f64 = 10e3;
/// The records' sample rate (Hz): the paper's.
pub const RANDOM_SAMPLE_RATE_HZ: f64 = 100e3;
/// Records per ensemble.
pub const RANDOM_RECORDS: u64 = 32;
/// Seed of the ensembles' noise (stream i is record i).
pub const RANDOM_SEED: u64 = 2012;

/// The frequencies of a linear harvester's frequency response (Hz): below its resonances, at
/// the short-circuit (mechanical) resonance, at the open-circuit one for a piezoelectric device,
/// and above.
pub fn response_frequencies_hz(device: &Device) -> Result<Vec<f64>, ValidationError> {
    let to_hz = |w: f64| w / (2.0 * std::f64::consts::PI);
    Ok(match ClosedForm::of(device)? {
        ClosedForm::Piezoelectric(p) => {
            let (sc, oc) = (
                to_hz(p.short_circuit_rad_s()),
                to_hz(p.open_circuit_rad_s()),
            );
            vec![0.9 * sc, sc, oc, 1.15 * oc]
        }
        ClosedForm::Electromagnetic(e) => {
            let r = to_hz(e.resonance_rad_s());
            vec![0.9 * r, r, 1.15 * r]
        }
    })
}

/// The frequency-response checks of a linear harvester.
pub fn frequency_response(device: &Device) -> Result<Vec<Check>, ValidationError> {
    frequency_response_checks(
        device,
        LINEAR_ACCEL_RMS_G,
        &response_frequencies_hz(device)?,
    )
}

/// The optimal-load checks of a linear harvester at its mechanical (short-circuit) resonance;
/// Stephen's form too for an electromagnetic device without inductance.
pub fn optimal_load(device: &Device) -> Result<Vec<Check>, ValidationError> {
    let f = device.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let stephen = matches!(
        &device.transducer,
        Transducer::Electromagnetic(e) if e.coil_inductance_h == 0.0
    );
    let range = match &device.transducer {
        Transducer::Electromagnetic(_) => EM_LOAD_RANGE_OHM,
        _ => PIEZO_LOAD_RANGE_OHM,
    };
    let decades = (range.1 / range.0).log10().round() as usize;
    optimal_load_checks(
        device,
        LINEAR_ACCEL_RMS_G,
        f,
        range,
        decades * LOAD_SCAN_PER_DECADE + 1,
        stephen,
    )
}

/// The drive of the NLvib problem and of the grazing case: `F = 0.1 N` on the mass.
pub fn unit_force_accel_rms_g(device: &Device) -> f64 {
    nlvib::accel_rms_g(device)
}

/// Largest parameter step of the grazing continuations (Hz).
pub const GRAZING_MAX_STEP_HZ: f64 = 2e-3;
/// Tolerance to which the grazing events are located (Hz).
pub const GRAZING_LOCATE_TOL_HZ: f64 = 1e-9;

/// The grazing checks of the rigid-stop oscillator (`data/validation/grazing_rigid.toml`):
/// continued up from Omega = 0.5 rad/s and down from 2.5 rad/s.
pub fn grazing(device: &Device) -> Result<Vec<Check>, ValidationError> {
    let to_hz = |w: f64| w / (2.0 * std::f64::consts::PI);
    grazing::grazing_checks(
        device,
        unit_force_accel_rms_g(device),
        (to_hz(0.5), to_hz(2.5)),
        GRAZING_MAX_STEP_HZ,
        GRAZING_LOCATE_TOL_HZ,
    )
}

/// The random records of the law's ensembles for a device: the project's band-limited noise
/// ([`RANDOM_BANDWIDTH_HZ`] sampled at [`RANDOM_SAMPLE_RATE_HZ`]) at [`RANDOM_PSD_G2_PER_HZ`],
/// [`RANDOM_RECORD_S`] analysed after the device's pre-roll of five ring-up times.
pub fn random_spec(device: &Device) -> RecordSpec {
    RecordSpec::of(
        device,
        NoiseSpec {
            psd_g2_per_hz: RANDOM_PSD_G2_PER_HZ,
            bandwidth_hz: RANDOM_BANDWIDTH_HZ,
            sample_rate_hz: RANDOM_SAMPLE_RATE_HZ,
            duration_s: RANDOM_RECORD_S,
        },
    )
}

/// The law's ensemble of a device ([`RANDOM_RECORDS`] records).
pub fn random_law(device: &Device) -> Result<LawEnsemble, ValidationError> {
    law_ensemble(device, &random_spec(device), RANDOM_SEED, RANDOM_RECORDS)
}

/// Largest parameter step of our continuation of the NLvib problem (rad/s).
pub const NLVIB_MAX_STEP_RAD_S: f64 = 0.01;
/// Tolerance to which its events are located (rad/s).
pub const NLVIB_LOCATE_TOL_RAD_S: f64 = 1e-8;
/// Every how many stored exact orbits ours is solved.
pub const NLVIB_EXACT_STRIDE: usize = 1;

//! The cases of the validation chapter's nonlinear-spring rows: which devices, levels, record
//! lengths and ensembles the exact stationary law ([`crate::validation::stationary_law`]) and
//! the escape over a double well's barrier ([`crate::validation::kramers`]) are checked with. The chapter's experiment and
//! the tests both call these, so that every row the chapter prints is a row a test asserts.

use crate::device::{Device, Suspension};
use crate::drive::noise::NoiseSpec;
use crate::study::displacement::{displacement_ensemble, DisplacementBins, DisplacementEnsemble};
use crate::study::record::{transient_s, RecordSpec, Scheme, DEFAULT_RTOL};
use crate::validation::escapes::escape_ensemble;
use crate::validation::kramers::{self, EscapeLevel, EscapeTheory};
use crate::validation::stationary_law::{self, StationaryLaw};
use crate::validation::{Check, ValidationError};

/// The exact-law devices (files under `data/validation/`) and their two-sided levels (g^2/Hz):
/// each level puts the linear RMS displacement, `sqrt(theta / k)`, near the nonlinearity's or
/// the stops' scale (about 0.1 mm), and the double well's `theta` at 2/3 of its barrier.
pub const STATIONARY_CASES: [(&str, f64); 3] = [
    ("random_duffing_em", 6e-3),
    ("random_bistable_stops_em", 4.5e-4),
    ("random_linear_asym_stops_em", 6e-3),
];

/// Analysed length of one record of the exact-law ensembles (s).
pub const STATIONARY_RECORD_S: f64 = 10.0;
/// Records per exact-law ensemble (more than [`stationary_law::GOF_BINS`]).
pub const STATIONARY_RECORDS: u64 = 40;
/// Fine histogram bins over the law's support (regrouped for the goodness of fit).
pub const HISTOGRAM_BINS: usize = 120;
/// Seed of the ensembles' noise (stream i is record i).
pub const SEED: u64 = 2012;

/// A double well's escape case: the device file under `data/validation/`, its levels as
/// `dU / theta` (white noise's `theta`, the displacement's; the band's deficit lowers only the
/// velocity's), and the records per level.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EscapeCase {
    /// The device file (without `.toml`).
    pub file: &'static str,
    /// `dU / theta` of the levels.
    pub ratios: &'static [f64],
    /// Records per level.
    pub records: u64,
}

/// The escape cases: moderate damping (20 % of critical in the well; `Delta` about 15 and 18:
/// Kramers' rate) and light damping (0.27 %; `Delta` 0.2: the energy-diffusion limit). The
/// levels put the barrier five and six temperatures high, where the settled states (within
/// `theta` of a well's bottom) lie four and more temperatures below the barrier; the records
/// give each settled count a few thousand escapes.
pub const ESCAPE_CASES: [EscapeCase; 2] = [
    EscapeCase {
        file: "kramers_bistable_em",
        ratios: &[5.0, 6.0],
        records: 192,
    },
    EscapeCase {
        file: "kramers_light_em",
        ratios: &[5.0],
        records: 384,
    },
];
/// Analysed length of one escape record (s).
pub const KRAMERS_RECORD_S: f64 = 10.0;

/// The records of an ensemble: the project's band-limited noise (10 kHz band at 100 kHz) at
/// `psd_g2_per_hz`, `duration_s` analysed after the device's pre-roll.
pub fn spec(device: &Device, psd_g2_per_hz: f64, duration_s: f64) -> RecordSpec {
    RecordSpec {
        noise: NoiseSpec {
            psd_g2_per_hz,
            bandwidth_hz: 10e3,
            sample_rate_hz: 100e3,
            duration_s,
        },
        transient_s: transient_s(device),
        rtol: DEFAULT_RTOL,
        scheme: Scheme::Exponential,
    }
}

/// The histogram bins of a device under a level: [`HISTOGRAM_BINS`] over the law's support.
pub fn bins(device: &Device, spec: &RecordSpec) -> Result<DisplacementBins, ValidationError> {
    let law = StationaryLaw::of(device, spec)?;
    let (lo, hi) = law.support_m();
    Ok(DisplacementBins::uniform(device, lo, hi, HISTOGRAM_BINS))
}

/// One exact-law case: its ensemble and checks.
pub fn stationary(
    device: &Device,
    psd_g2_per_hz: f64,
) -> Result<(DisplacementEnsemble, Vec<Check>), ValidationError> {
    let spec = spec(device, psd_g2_per_hz, STATIONARY_RECORD_S);
    let bins = bins(device, &spec)?;
    let e = displacement_ensemble(device, &spec, &bins, SEED, STATIONARY_RECORDS)?;
    let checks = stationary_law::checks(device, &spec, &e, &bins)?;
    Ok((e, checks))
}

/// The two-sided level (g^2/Hz) at which a double well's barrier is `ratio` times `theta`
/// (white noise: `S = 2 c theta / m^2`).
pub fn kramers_psd_g2_per_hz(device: &Device, ratio: f64) -> Result<f64, ValidationError> {
    let Suspension::Bistable { barrier_j, .. } = device.mechanics.suspension else {
        return Err(ValidationError::Device(
            "Kramers' law needs a bistable device".into(),
        ));
    };
    let probe = spec(device, 1.0, KRAMERS_RECORD_S);
    let c = StationaryLaw::of(device, &probe)?.damping_n_s_per_m;
    let m = device.mechanics.mass_kg;
    Ok(2.0 * c * (barrier_j / ratio) / (m * m * crate::G * crate::G))
}

/// One escape case on its device: each level's counts beside its theories, and the checks.
pub fn escapes(
    device: &Device,
    case: &EscapeCase,
) -> Result<(Vec<EscapeLevel>, Vec<Check>), ValidationError> {
    let mut levels = Vec::new();
    for &ratio in case.ratios {
        let spec = spec(
            device,
            kramers_psd_g2_per_hz(device, ratio)?,
            KRAMERS_RECORD_S,
        );
        let theory = EscapeTheory::of(device, &spec)?;
        let theta = StationaryLaw::of(device, &spec)?.theta_j;
        let ensemble = escape_ensemble(device, &spec, theta, SEED, case.records)?;
        levels.push(EscapeLevel { theory, ensemble });
    }
    let checks = kramers::checks(device, &levels);
    Ok((levels, checks))
}

/// Largest parameter step of our continuation of NLvib's Duffing example (rad/s).
pub const NLVIB_DUFFING_MAX_STEP_RAD_S: f64 = 0.01;

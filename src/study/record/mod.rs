//! One random-vibration record: band-limited white noise (or a measured record) drives a model
//! from rest, and its outputs are sampled: the load voltages, turned into an output power
//! spectral density, or behind an interface circuit the storage voltage, with the DC power and
//! the drive's power.
//!
//! # One record
//! [`simulate_record`] drives a device's model ([`crate::physics::harvester`]; the lumped model
//! of eq 7 for the paper's devices) with one realisation of band-limited white noise from
//! [`crate::drive::noise::generate`] (two-sided level `Sa`, 10 kHz band, 100 kHz, the paper's
//! section 4), read between samples by linear interpolation ([`crate::drive::Sampled`]), and
//! integrates it from rest one sample interval at a time, so the outputs (the node voltages V1,
//! V2 for the paper's pair) are collected at the sample instants without interpolation. An
//! interval goes the fast way where one applies ([`Scheme::Exponential`]):
//!
//! * a model whose free flight splits into a linear part and a small remainder (a transducer
//!   with its own loads, [`crate::model::FlightSplit`]): between contacts an interval is one
//!   step of the exponential Adams-Bashforth method ([`crate::ode::exponential`]); a linear
//!   free flight between rigid stops is one product with the propagator, with its rebounds
//!   located on the exact solution (`impacts.rs`), and where the model holds every component
//!   past `(x, v)` at zero (no transducer) on `(x, v)` alone (`mechanical.rs`);
//! * a model without that split whose modes are affine (an interface circuit with
//!   piecewise-linear diodes, [`crate::model::Model::affine`]): an interval in an affine mode is
//!   advanced exactly by the mode's propagator of the state augmented with the interpolated
//!   drive (`affine.rs`), and its guards are checked as affine functions with their rates; the
//!   rebounds off rigid stops (of the frame or between two masses) inside an interval, a
//!   contact that comes to rest and a resting contact's release (whose holding force takes the
//!   drive) are located on the modes' exact solutions (`crossings.rs`).
//!
//! Any other interval that may come near a stop or where a guard may fire, every contact and
//! the samples just after it, and every interval of a mode that is not affine go to
//! [`crate::ode::Dopri5`], for which every sample instant is a breakpoint and every switch an
//! event located on its dense output. [`simulate_on`] runs any model.
//!
//! **Transient.** The model starts at rest, so its response needs a few mechanical ring-up
//! times `2m/b` (the amplitude decay time of the unloaded resonator, an upper bound on that of
//! the loaded one) to become stationary. The record is therefore preceded by a pre-roll of
//! [`TRANSIENT_RING_TIMES`] ring-up times (rounded up to a whole millisecond) drawn from the
//! same noise realisation and discarded: 0.48 s for prototype 2 (`2m/b` = 96 ms), 8 ms for
//! prototype 1 (1.5 ms); behind an interface circuit at least the storage's settling
//! ([`storage_settling_s`]). The *analysed* record that follows has the paper's length (10 s),
//! so a single-record estimate has the same statistics as the paper's. After five ring-up times
//! the remaining amplitude deficit is below e^-5 = 0.7 %.
//!
//! # The continuous books
//! Where a record keeps them (a model with a storage output [`STORAGE`], or a caller that asks,
//! [`crate::study::record_ledger`]), the integral over time of each energy-ledger power, of each
//! output and of its square is booked interval by interval (`books.rs`): over the analysed
//! window, from its first sample instant to its last, they give the drive's mean power, the
//! storage's mean voltage and the DC power its load takes ([`RecordSummary::p_dc_w`]), and the
//! window's [`crate::model::Ledger`].
//!
//! # Output power spectral density
//! [`output_psd`] is the one-sided Welch estimate ([`crate::signal::welch()`], periodic Hann,
//! 50 % overlap, density scaling) of both load voltages, divided by the load:
//! `S_P(f) = (S_V1(f) + S_V2(f)) / RL` in W/Hz, so that its integral over `f >= 0` is the mean
//! power of **both loads** (the power of eq 21). The per-load densities are kept beside it.
//!
//! # Efficiency
//! `2P/(m Sa)` with `P` the mean power of both loads and `Sa` the **two-sided** acceleration PSD
//! in SI units (`Sa_g2 * 9.81^2`), the input power being `m Sa / 2` (eq 21 and its reference).
//! [`eq21_power_w`](crate::physics::two_port::eq21_power_w) gives the linear theory with
//! `Qm = sqrt(K m)/b` ([`crate::physics::two_port::TwoPort::qm_open_circuit`]), the reading
//! eq 21 is derived with. Behind an interface circuit the efficiency is the DC power over the
//! drive's ([`RecordSummary::efficiency`]).

use std::sync::Arc;

use thiserror::Error;

use crate::device::Device;
use crate::drive::noise::{self, NoiseError, NoiseSpec};
use crate::drive::Sampled;
use crate::model::{FlightSplit, FlightVisitor, Ledger, Mode, Model, NoFlight, Remainder, Slot};
use crate::ode::{SolverError, Stats};
use crate::physics::harvester::AssemblyError;
use crate::signal::SpectralError;
use crate::study::mass_peaks::MassPeaks;

mod affine;
mod books;
mod crossings;
mod exponential;
mod impacts;
mod mechanical;
mod outputs;
mod spectrum;
mod stepping;
mod storage;

use books::Books;
pub(crate) use books::Found;
use exponential::ExpFlight;
use stepping::{run, NoFast};

pub use spectrum::{output_psd, OutputSpectrum};
pub use storage::{
    check_steady_mean, has_storage, storage_ensemble, storage_record, storage_settling_s,
    StorageRecord, StorageSummary, STORAGE_SETTLING_TIMES,
};

/// Length of the discarded pre-roll in mechanical ring-up times `2m/b` (see the module docs).
pub const TRANSIENT_RING_TIMES: f64 = 5.0;

/// Default relative tolerance of the Dormand-Prince integrator for random records (the
/// intervals near and in contact). In free flight the step is bounded by the 10 us sample
/// interval, not by this tolerance; the tests show that the mean power changes by far less
/// than the ensemble error when it is tightened.
pub const DEFAULT_RTOL: f64 = 1e-7;

/// The name of a model's storage output (the voltage across an interface circuit's storage
/// capacitor): a record of a model that has one keeps its continuous books and reports the
/// storage's mean voltage and DC power.
pub const STORAGE: &str = "vs";

/// Errors of a record (a random-vibration simulation).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RecordError {
    /// The excitation could not be generated.
    #[error("excitation: {0}")]
    Noise(#[from] NoiseError),
    /// The device's parts do not assemble into a model.
    #[error("model: {0}")]
    Assembly(#[from] AssemblyError),
    /// The integrator failed.
    #[error("integration: {0}")]
    Solver(#[from] SolverError),
    /// The spectral estimate could not be formed.
    #[error("spectrum: {0}")]
    Spectral(#[from] SpectralError),
    /// A storage study of a device without a storage (no interface circuit).
    #[error("device `{0}` has no storage: it drives resistive loads, not an interface circuit")]
    NoStorage(String),
    /// A storage study of a storage without a load: it only charges, with no steady mean.
    #[error(
        "device `{0}`: the storage has an open load (interface.load.kind = \"open\"), so it \
         charges towards the open-circuit limit and has no steady mean; use the charging study"
    )]
    OpenLoad(String),
    /// A setting is out of range.
    #[error("record spec: {field} = {value} is invalid; expected {expected}")]
    InvalidSpec {
        /// Name of the setting.
        field: &'static str,
        /// Its value.
        value: f64,
        /// The valid range.
        expected: &'static str,
    },
}
/// Mechanical ring-up time `2m/b` of a device (s): the amplitude decay time of the unloaded
/// resonator (about 0.1 s for prototype 2).
pub fn ring_up_time_s(device: &Device) -> f64 {
    2.0 * device.mechanics.mass_kg / device.mechanics.damping_n_s_per_m
}

/// The discarded pre-roll of a device: [`TRANSIENT_RING_TIMES`] ring-up times, rounded up to a
/// whole millisecond (s); behind an interface circuit at least the storage's settling
/// ([`storage_settling_s`], rounded up likewise), which is often the longer.
pub fn transient_s(device: &Device) -> f64 {
    // Up to a whole millisecond; a time already whole to rounding stays as it is.
    let up_to_ms = |t: f64| (t * 1e3 - 1e-9).ceil() / 1e3;
    let ring = up_to_ms(TRANSIENT_RING_TIMES * ring_up_time_s(device));
    storage_settling_s(device).map_or(ring, |s| ring.max(up_to_ms(s)))
}

/// Settings of one random-vibration record.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordSpec {
    /// The analysed excitation: two-sided level `Sa` (g²/Hz), band, sample rate and the
    /// **analysed** duration (the paper: 10 s).
    pub noise: NoiseSpec,
    /// Pre-roll simulated from rest before the analysed record and discarded (s); it is
    /// rounded to a whole number of samples.
    pub transient_s: f64,
    /// Relative tolerance of the Dormand-Prince integrator.
    pub rtol: f64,
    /// How the free flight between contacts is integrated.
    pub scheme: Scheme,
}

/// How a record's intervals are integrated where no switch is near (contacts, switches and
/// their neighbourhood always go to [`Dopri5`](crate::ode::Dopri5) with event location).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Scheme {
    /// The fast paths (see the module docs). A model that splits its free flight: the
    /// exponential Adams-Bashforth method of order [`EXPONENTIAL_ORDER`] on the sample grid
    /// ([`crate::ode::exponential`]): the linearised model and the linearly interpolated input
    /// exactly, the small remainder (eq 10's capacitances) by extrapolation; one remainder
    /// evaluation per sample. A step is taken only when the mass is in free flight, the
    /// remainder has [`EXPONENTIAL_ORDER`] values since the last contact, and the cubic through
    /// the positions and velocities at the step's ends stays [`STOP_MARGIN`] clear of the stops.
    /// A model with affine modes and no split: each interval of an affine mode exactly, unless
    /// a guard may fire in it. Any other interval goes to [`Dopri5`](crate::ode::Dopri5).
    Exponential,
    /// [`Dopri5`](crate::ode::Dopri5) everywhere, one sample interval (a breakpoint of the input)
    /// at a time: the reference the fast paths are checked against.
    Dopri5,
}

/// Order of the exponential Adams-Bashforth method of [`Scheme::Exponential`]: the number of
/// past remainder values its polynomial passes through.
pub const EXPONENTIAL_ORDER: usize = 5;

/// Relative clearance from the stops that an exponential step must keep (as a fraction of the
/// end-stop gap): the cubic Hermite interpolant of x between two samples is within
/// `h^4 max|x''''| / 384` of the trajectory, a few picometres for prototype 1 at the highest
/// level (1e-6 of the gap), so a clearance of 1e-4 of the gap cannot be crossed unseen; an
/// interval that comes closer goes to [`Dopri5`](crate::ode::Dopri5) with its event location.
pub const STOP_MARGIN: f64 = 1e-4;

impl RecordSpec {
    /// A record of `noise` analysed after the device's pre-roll ([`transient_s`]), with
    /// [`DEFAULT_RTOL`] and the exponential free flight.
    pub fn of(device: &Device, noise: NoiseSpec) -> Self {
        Self {
            noise,
            transient_s: transient_s(device),
            rtol: DEFAULT_RTOL,
            scheme: Scheme::Exponential,
        }
    }

    /// Samples of the pre-roll, `round(transient_s * fs)`.
    pub fn transient_samples(&self) -> usize {
        (self.transient_s * self.noise.sample_rate_hz).round() as usize
    }

    /// Samples of the analysed record, `round(duration_s * fs)`.
    pub fn analysed_samples(&self) -> usize {
        self.noise.n_samples()
    }

    /// The generated excitation: pre-roll plus analysed record, one noise realisation.
    pub fn generated_noise(&self) -> NoiseSpec {
        let n = self.transient_samples() + self.analysed_samples();
        NoiseSpec {
            duration_s: n as f64 / self.noise.sample_rate_hz,
            ..self.noise
        }
    }

    pub(crate) fn validate(&self) -> Result<(), RecordError> {
        self.noise.validate()?;
        if !(self.transient_s.is_finite() && self.transient_s >= 0.0) {
            return Err(RecordError::InvalidSpec {
                field: "transient_s",
                value: self.transient_s,
                expected: "a finite number >= 0",
            });
        }
        if !(self.rtol.is_finite() && self.rtol > 0.0 && self.rtol < 1.0) {
            return Err(RecordError::InvalidSpec {
                field: "rtol",
                value: self.rtol,
                expected: "0 < rtol < 1",
            });
        }
        Ok(())
    }
}

/// Scalar results of one record, over the analysed window (after the pre-roll).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordSummary {
    /// Mean power in the load of the model's first output over the samples (W): `<V1²>/RL`
    /// for a resistor, `(<V²> - V_b <V>)/R` for a battery, zero without a load.
    pub p1_w: f64,
    /// Mean power in the load of the second output (W).
    pub p2_w: f64,
    /// RMS displacement of the first mass over the samples (m).
    pub x_rms_m: f64,
    /// Largest |x| at the ends of the integrator's steps (which include every contact event) (m).
    pub x_peak_m: f64,
    /// Each mass's largest |x| and |v| in the analysed window for a model of several masses,
    /// at the ends of the integrator's steps as `x_peak_m`; none for one mass.
    #[serde(default)]
    pub mass_peaks: MassPeaks,
    /// Fraction of the analysed time spent past a stop (eq 2: delta > 0).
    pub contact_fraction: f64,
    /// Contact entries (impacts) in the analysed window.
    pub impacts: u64,
    /// Mean square of the applied acceleration over the analysed samples (m²/s⁴); its
    /// expectation is `2 B Sa` for a two-sided level `Sa` over the band `B`.
    pub accel_mean_square_si: f64,
    /// Integrator counters for the whole record (pre-roll included); a fast step counts as an
    /// accepted step (with one right-hand-side evaluation for an exponential step's remainder).
    pub stats: Stats,
    /// Sample intervals advanced by a fast step, exponential or an affine mode's exact one (the
    /// rest went to [`Dopri5`](crate::ode::Dopri5)).
    pub exponential_steps: u64,
    /// How the free flight was integrated, with the reason where it fell back to
    /// [`Dopri5`](crate::ode::Dopri5).
    pub free_flight: FreeFlightPath,
    /// Mean power of the drive over the analysed window (W): the ledger's `drive` term over the
    /// window's length; `None` where the record kept no books (see the module docs).
    pub p_drive_w: Option<f64>,
    /// Mean power the load of the storage output [`STORAGE`] takes over the window (W), from
    /// the storage voltage's mean and mean square over time; `None` without a storage or its
    /// load.
    pub p_dc_w: Option<f64>,
    /// Mean storage voltage over the window (V); `None` without a storage.
    pub vdc_v: Option<f64>,
}

/// How a record's free flight was integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FreeFlightPath {
    /// By the exponential step between contacts ([`Scheme::Exponential`]).
    Exponential,
    /// By the affine modes' exact steps ([`Scheme::Exponential`] for a model without a
    /// free-flight split).
    Affine,
    /// By [`Dopri5`](crate::ode::Dopri5) throughout, for the stated reason.
    Dopri5(Fallback),
}

/// Why a record's free flight went to [`Dopri5`](crate::ode::Dopri5) instead of a fast path.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Fallback {
    /// The record's scheme asked for it ([`Scheme::Dopri5`]).
    Requested,
    /// A capacitor pair has no stop on one side, so its free flight is not bounded and could reach
    /// a state only [`Dopri5`](crate::ode::Dopri5)'s checks catch (a vanishing capacitance, an
    /// electrode).
    UnboundedPair,
    /// A capacitance plus Cp of an area-overlap pair vanishes before a stop is reached.
    CapacitanceVanishes,
    /// The free flight is nonlinear and the sample interval does not resolve the device's
    /// linearised dynamics (the scaled `h L` exceeds
    /// [`RESOLVED_NORM`](crate::ode::exponential::RESOLVED_NORM)): the exponential step
    /// extrapolates the remainder from its values at past samples, which must resolve the
    /// motion. A linear free flight (piezoelectric, electromagnetic) is exact at any step and
    /// never falls back for this reason.
    Unresolved,
    /// The suspension's stiffness strays so fast from its value at the well that the
    /// exponential step could not reach the well itself
    /// ([`Spring::fast_path_reach_m`](crate::laws::suspension::Spring::fast_path_reach_m)).
    StiffSuspension,
    /// The model has neither a free-flight split nor an affine mode (an interface circuit with
    /// Shockley diodes, a nonlinear suspension or an electrostatic pair behind it).
    NoExactMode,
}

impl std::fmt::Display for Fallback {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Fallback::Requested => "Dormand-Prince was requested",
            Fallback::UnboundedPair => {
                "the capacitor pair has no stop on one side, so its free flight is unbounded"
            }
            Fallback::CapacitanceVanishes => {
                "a transducer capacitance plus Cp vanishes before the stop is reached"
            }
            Fallback::Unresolved => {
                "the sample interval does not resolve the nonlinear free flight's dynamics"
            }
            Fallback::StiffSuspension => {
                "the suspension's stiffness departs from its value at the well within the well's \
                 distance from rest at this sample interval"
            }
            Fallback::NoExactMode => {
                "the model has neither a free-flight split nor a mode that is affine"
            }
        })
    }
}

impl RecordSummary {
    /// Mean power of both loads (W), the `P` of eq 21.
    pub fn p_total_w(&self) -> f64 {
        self.p1_w + self.p2_w
    }

    /// The DC power over the drive's power, where the record has both.
    pub fn efficiency(&self) -> Option<f64> {
        Some(self.p_dc_w? / self.p_drive_w?)
    }
}

/// One simulated record: the model's outputs at the analysed sample instants and its summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Sample rate of the outputs (Hz).
    pub sample_rate_hz: f64,
    /// The number of analysed sample instants (the length of each output kept).
    pub samples: usize,
    /// The model's first output (V1 of the paper's pair; the storage voltage behind an
    /// interface circuit) at `t = transient + k / fs`, `k = 0 .. N` (V); empty for a model
    /// without outputs, and for an output the model holds at zero (a load voltage without a
    /// transducer, [`crate::model::Layout::zero_outputs`]), whose samples
    /// [`Record::output_samples`] gives.
    pub v1_v: Vec<f64>,
    /// Its second output (V2; the element's voltage behind a circuit) at the same instants (V);
    /// empty where `v1_v` is.
    pub v2_v: Vec<f64>,
    /// Its further outputs, in order, at the same instants.
    pub more_v: Vec<Vec<f64>>,
    /// The outputs' names, units and loads ([`crate::model::Layout::outputs`]).
    pub outputs: Vec<Slot>,
    /// The energy ledger over the analysed window, where the record kept its books (see the
    /// module docs).
    pub ledger: Option<Ledger>,
    /// Scalar results.
    pub summary: RecordSummary,
}

/// Simulates one record: realisation `stream` of seed `seed` of the excitation `spec` drives
/// `device` (for the paper's devices, eq 7 with the end-stop of eq 1) from rest; see the module
/// docs.
///
/// The only allocations are the excitation and the output vectors (and the books, where the
/// record keeps them). The loop advances from one sample instant to the next and stores the
/// outputs there: by a fast step where one applies ([`Scheme::Exponential`]), else by the
/// Dormand-Prince integrator up to the next sample instant (a breakpoint).
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::noise::NoiseSpec;
/// use endstop::study::record::{simulate_record, RecordSpec};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype1.toml"));
/// let device = Device::from_toml_str(text, "prototype1.toml")?;
/// // Noise at 1e-6 g^2/Hz flat to 10 kHz, sampled at 100 kHz: 20 ms after 10 ms of pre-roll.
/// let noise = NoiseSpec {
///     psd_g2_per_hz: 1e-6,
///     bandwidth_hz: 10e3,
///     sample_rate_hz: 100e3,
///     duration_s: 0.02,
/// };
/// let mut spec = RecordSpec::of(&device, noise);
/// spec.transient_s = 0.01;
/// let record = simulate_record(&device, &spec, 2012, 0)?;
/// assert_eq!(record.v1_v.len(), spec.analysed_samples());
/// assert!(record.summary.p_total_w() > 0.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn simulate_record(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<Record, RecordError> {
    simulate_observed(device, spec, seed, stream, &mut ())
}

/// What [`simulate_observed`] shows of a record: the state and mode at each analysed sample
/// instant, and whether the record keeps its continuous books whatever the model (see the
/// module docs). The unit observer `()` does nothing (and costs nothing);
/// [`crate::study::record_ledger`] asks for the books, [`crate::study::displacement`] reads
/// the samples.
pub(crate) trait RecordObserver {
    /// True when the record keeps its books for this observer.
    const BOOKS: bool = false;

    /// The state and mode at an analysed sample instant.
    #[inline(always)]
    fn sample(&mut self, _y: &[f64], _mode: Mode) {}
}

impl RecordObserver for () {}

/// [`simulate_record`], showing every analysed sample to `observer`.
pub(crate) fn simulate_observed<O: RecordObserver>(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
    observer: &mut O,
) -> Result<Record, RecordError> {
    Ok(simulate_found(device, spec, seed, stream, observer)?.0)
}

/// [`simulate_observed`], with what the record's books found where it kept them.
pub(crate) fn simulate_found<O: RecordObserver>(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
    observer: &mut O,
) -> Result<(Record, Option<Found>), RecordError> {
    spec.validate()?;
    let drive = SampledDrive::noise(spec, seed, stream)?;
    drive_found(device, &drive, spec.rtol, spec.scheme, observer)
}

/// A sampled base acceleration to drive a record with: a generated noise realisation or a
/// measured record resampled to the integrator's sample rate, of which the first
/// `transient_samples` are a discarded pre-roll.
#[derive(Debug, Clone, PartialEq)]
pub struct SampledDrive {
    /// The acceleration at `t = k / fs` (m/s^2), read between samples by linear interpolation.
    pub accel: Arc<[f64]>,
    /// The sample rate fs (Hz).
    pub sample_rate_hz: f64,
    /// Leading samples simulated and discarded.
    pub transient_samples: usize,
}

impl SampledDrive {
    /// Realisation `stream` of seed `seed` of a record's excitation: its pre-roll and analysed
    /// samples.
    pub fn noise(spec: &RecordSpec, seed: u64, stream: u64) -> Result<Self, RecordError> {
        let gen = spec.generated_noise();
        Ok(Self {
            accel: noise::generate_shared(&gen, seed, stream)?,
            sample_rate_hz: gen.sample_rate_hz,
            transient_samples: spec.transient_samples(),
        })
    }

    /// Refuses a drive no longer than its pre-roll and one more sample, or a sample rate that
    /// is not positive, and a tolerance outside (0, 1).
    fn check(&self, rtol: f64) -> Result<(), RecordError> {
        if self.accel.len() <= self.transient_samples + 1
            || !(self.sample_rate_hz.is_finite() && self.sample_rate_hz > 0.0)
        {
            return Err(RecordError::InvalidSpec {
                field: "drive",
                value: self.accel.len() as f64,
                expected: "more samples than the pre-roll and a positive sample rate",
            });
        }
        if !(rtol.is_finite() && rtol > 0.0 && rtol < 1.0) {
            return Err(RecordError::InvalidSpec {
                field: "rtol",
                value: rtol,
                expected: "0 < rtol < 1",
            });
        }
        Ok(())
    }
}

/// One record of `device` under a sampled drive (see [`simulate_record`], which draws the
/// drive from band-limited noise); `rtol` and `scheme` as in [`RecordSpec`].
pub fn simulate_drive(
    device: &Device,
    drive: &SampledDrive,
    rtol: f64,
    scheme: Scheme,
) -> Result<Record, RecordError> {
    Ok(drive_found(device, drive, rtol, scheme, &mut ())?.0)
}

/// One record of any model under a sampled drive (see [`simulate_drive`]).
pub fn simulate_on<M: Model<N>, const N: usize>(
    model: &M,
    drive: &SampledDrive,
    rtol: f64,
    scheme: Scheme,
) -> Result<Record, RecordError> {
    drive.check(rtol)?;
    Ok(model_found(model, drive, rtol, scheme, &mut ())?.0)
}

/// [`simulate_drive`], showing every analysed sample to `observer`: assembles the device's
/// model and runs the record on it.
pub(crate) fn drive_found<O: RecordObserver>(
    device: &Device,
    drive: &SampledDrive,
    rtol: f64,
    scheme: Scheme,
    observer: &mut O,
) -> Result<(Record, Option<Found>), RecordError> {
    drive.check(rtol)?;
    crate::with_harvester!(device, |h| model_found(&h, drive, rtol, scheme, observer))
}

/// The record of a model: its loop compiled for the model's fast path (see the module docs).
fn model_found<M: Model<N>, O: RecordObserver, const N: usize>(
    model: &M,
    drive: &SampledDrive,
    rtol: f64,
    scheme: Scheme,
    observer: &mut O,
) -> Result<(Record, Option<Found>), RecordError> {
    let sampled = Sampled::new(drive.accel.clone(), drive.sample_rate_hz);
    let books = (O::BOOKS || model.layout().output(STORAGE).is_some())
        .then(|| Books::new(model, sampled.clone()));
    if scheme == Scheme::Dopri5 {
        let fast = NoFast(Fallback::Requested);
        return run(model, drive, rtol, fast, observer, books);
    }
    let visit = Visit {
        model,
        drive,
        rtol,
        observer,
        books,
    };
    model.flight(sampled.dt_s, visit)
}

/// Runs a record on the fast path a model's free flight split allows (see
/// [`crate::model::FlightVisitor`]).
struct Visit<'a, M, O, const N: usize> {
    model: &'a M,
    drive: &'a SampledDrive,
    rtol: f64,
    observer: &'a mut O,
    books: Option<Books<N>>,
}

impl<M: Model<N>, O: RecordObserver, const N: usize> FlightVisitor<N> for Visit<'_, M, O, N> {
    type Output = Result<(Record, Option<Found>), RecordError>;

    fn visit<R: Remainder<N>>(self, split: FlightSplit<N>, remainder: R) -> Self::Output {
        let dt = 1.0 / self.drive.sample_rate_hz;
        let Self {
            model,
            drive,
            rtol,
            observer,
            books,
        } = self;
        match ExpFlight::new(model, dt, split, remainder) {
            Ok(fast) => match fast.mechanical(model, books.is_some()) {
                Some(mech) => run(model, drive, rtol, mech, observer, books),
                None => run(model, drive, rtol, fast, observer, books),
            },
            Err(why) => run(model, drive, rtol, NoFast(why), observer, books),
        }
    }

    fn refused(self, why: NoFlight) -> Self::Output {
        let fallback = match why {
            NoFlight::Unavailable => {
                return affine::run(self.model, self.drive, self.rtol, self.observer, self.books)
            }
            NoFlight::UnboundedPair => Fallback::UnboundedPair,
            NoFlight::CapacitanceVanishes => Fallback::CapacitanceVanishes,
        };
        run(
            self.model,
            self.drive,
            self.rtol,
            NoFast(fallback),
            self.observer,
            self.books,
        )
    }
}

#[cfg(test)]
mod tests;

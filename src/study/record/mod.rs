//! One random-vibration record: band-limited white noise drives the harvester from rest, and
//! the load voltages are sampled and turned into an output power spectral density.
//!
//! # One record
//! [`simulate_record`] drives the lumped model of eq 7 with one realisation of band-limited
//! white noise from [`crate::drive::noise::generate`] (two-sided level `Sa`, 10 kHz band, 100 kHz,
//! the paper's section 4), read between samples by linear interpolation ([`crate::drive::Sampled`]), and
//! integrates it from rest one sample interval at a time, so the node voltages V1, V2 are
//! collected at the sample instants without interpolation. Between contacts an interval is one
//! step of the exponential Adams-Bashforth method ([`crate::ode::exponential`], see
//! [`Scheme::Exponential`]); an interval that may come near a stop, every contact and the
//! samples just after it go to [`crate::ode::Dopri5`], for which every sample instant is a
//! breakpoint and every contact an event located on its dense output.
//!
//! **Transient.** The model starts at rest, so its response needs a few mechanical ring-up
//! times `2m/b` (the amplitude decay time of the unloaded resonator, an upper bound on that of
//! the loaded one) to become stationary. The record is therefore preceded by a pre-roll of
//! [`TRANSIENT_RING_TIMES`] ring-up times (rounded up to a whole millisecond) drawn from the
//! same noise realisation and discarded: 0.48 s for prototype 2 (`2m/b` = 96 ms), 8 ms for
//! prototype 1 (1.5 ms). The *analysed* record that follows has the paper's length (10 s), so a
//! single-record estimate has the same statistics as the paper's. After five ring-up times the
//! remaining amplitude deficit is below e^-5 = 0.7 %.
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
//! eq 21 is derived with.
//!

use std::sync::Arc;

use thiserror::Error;

use crate::device::Device;
use crate::drive::noise::{self, NoiseError, NoiseSpec};
use crate::drive::Sampled;
use crate::ode::exponential::History;
use crate::ode::{SolverError, Stats, Step};
use crate::physics::contact::Mode;
use crate::physics::free_flight::{FlightKind, GeneralFlight};
use crate::physics::harvester::{Harvester, State};
use crate::signal::bandwidth::restrict;
use crate::signal::{self, Psd, SpectralError, WelchConfig};
use crate::study::interface::record::storage_settling_s;

mod stepping;

use stepping::{run, FastFlight};

/// Length of the discarded pre-roll in mechanical ring-up times `2m/b` (see the module docs).
pub const TRANSIENT_RING_TIMES: f64 = 5.0;

/// Default relative tolerance of the Dormand-Prince integrator for random records (the
/// intervals near and in contact). In free flight the step is bounded by the 10 us sample
/// interval, not by this tolerance; the tests show that the mean power changes by far less
/// than the ensemble error when it is tightened.
pub const DEFAULT_RTOL: f64 = 1e-7;

/// Errors of a record (a random-vibration simulation).
#[derive(Debug, Clone, PartialEq, Error)]
pub enum RecordError {
    /// The excitation could not be generated.
    #[error("excitation: {0}")]
    Noise(#[from] NoiseError),
    /// The integrator failed.
    #[error("integration: {0}")]
    Solver(#[from] SolverError),
    /// The spectral estimate could not be formed.
    #[error("spectrum: {0}")]
    Spectral(#[from] SpectralError),
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

/// How a record's free flight is integrated (contacts and their neighbourhood always go to
/// [`Dopri5`](crate::ode::Dopri5) with event location).
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Scheme {
    /// The exponential Adams-Bashforth method of order [`EXPONENTIAL_ORDER`] on the sample grid
    /// ([`crate::ode::exponential`]): the linearised model and the linearly interpolated input
    /// exactly, the small remainder of eq 10's capacitances by extrapolation; one remainder
    /// evaluation per sample. A step is taken only when the mass is in free flight, the remainder
    /// has [`EXPONENTIAL_ORDER`] values since the last contact, and the cubic through the positions
    /// and velocities at the step's ends stays [`STOP_MARGIN`] clear of the stops; any other
    /// interval goes to [`Dopri5`](crate::ode::Dopri5).
    Exponential,
    /// [`Dopri5`](crate::ode::Dopri5) everywhere, one sample interval (a breakpoint of the input)
    /// at a time: the reference the exponential scheme is checked against.
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
    /// Mean power in load 1, `<V1²>/RL` over the samples (W).
    pub p1_w: f64,
    /// Mean power in load 2 (W).
    pub p2_w: f64,
    /// RMS displacement over the samples (m).
    pub x_rms_m: f64,
    /// Largest |x| at the ends of the integrator's steps (which include every contact event) (m).
    pub x_peak_m: f64,
    /// Fraction of the analysed time spent past a stop (eq 2: delta > 0).
    pub contact_fraction: f64,
    /// Contact entries (impacts) in the analysed window.
    pub impacts: u64,
    /// Mean square of the applied acceleration over the analysed samples (m²/s⁴); its
    /// expectation is `2 B Sa` for a two-sided level `Sa` over the band `B`.
    pub accel_mean_square_si: f64,
    /// Integrator counters for the whole record (pre-roll included); an exponential step
    /// counts as an accepted step with one right-hand-side evaluation.
    pub stats: Stats,
    /// Sample intervals advanced by the exponential integrator (the rest went to
    /// [`Dopri5`](crate::ode::Dopri5)).
    pub exponential_steps: u64,
    /// How the free flight was integrated, with the reason where it fell back to
    /// [`Dopri5`](crate::ode::Dopri5).
    pub free_flight: FreeFlightPath,
}

/// How a record's free flight was integrated.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum FreeFlightPath {
    /// By the exponential step between contacts ([`Scheme::Exponential`]).
    Exponential,
    /// By [`Dopri5`](crate::ode::Dopri5) throughout, for the stated reason.
    Dopri5(Fallback),
}

/// Why a record's free flight went to [`Dopri5`](crate::ode::Dopri5) instead of the exponential
/// step.
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
    /// ([`Spring::fast_path_reach_m`](crate::physics::suspension::Spring::fast_path_reach_m)).
    StiffSuspension,
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
        })
    }
}

impl RecordSummary {
    /// Mean power of both loads (W), the `P` of eq 21.
    pub fn p_total_w(&self) -> f64 {
        self.p1_w + self.p2_w
    }
}

/// One simulated record: the node voltages at the analysed sample instants and its summary.
#[derive(Debug, Clone, PartialEq)]
pub struct Record {
    /// Sample rate of `v1_v`, `v2_v` (Hz).
    pub sample_rate_hz: f64,
    /// V1 at `t = transient + k / fs`, `k = 0 .. N` (V).
    pub v1_v: Vec<f64>,
    /// V2 at the same instants (V).
    pub v2_v: Vec<f64>,
    /// Scalar results.
    pub summary: RecordSummary,
}

/// Simulates one record: realisation `stream` of seed `seed` of the excitation `spec` drives
/// `device` (eq 7 with the end-stop of eq 1) from rest; see the module docs.
///
/// The only allocations are the excitation and the two output vectors. The loop advances
/// from one sample instant to the next and stores V1, V2 there: by one step of the
/// exponential integrator where the mass flies free ([`Scheme::Exponential`]), else by the
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

/// What [`simulate_observed`] shows of each sample interval it integrates, in time order:
/// an exponential step or the accepted Dormand-Prince steps of the interval. The unit
/// observer `()` does nothing (and costs nothing); [`crate::study::record_ledger`] books the
/// energy balance.
pub(crate) trait RecordObserver {
    /// An exponential step from `t0`: state `y0` to `y1`, input samples `a0` and `a1`, and
    /// the remainder's history the step used.
    #[allow(clippy::too_many_arguments)]
    fn exponential(
        &mut self,
        _model: &Harvester<Sampled>,
        _t0: f64,
        _y0: &State,
        _y1: &State,
        _a0: f64,
        _a1: f64,
        _history: &History<4, EXPONENTIAL_ORDER>,
    ) {
    }

    /// An accepted Dormand-Prince step, in its mode.
    fn dopri(&mut self, _model: &Harvester<Sampled>, _step: &Step<State>, _mode: Mode) {}

    /// The state and mode at an analysed sample instant.
    #[inline(always)]
    fn sample(&mut self, _y: &State, _mode: Mode) {}
}

impl RecordObserver for () {}

/// [`simulate_record`], showing every interval to `observer`.
pub(crate) fn simulate_observed<O: RecordObserver>(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
    observer: &mut O,
) -> Result<Record, RecordError> {
    spec.validate()?;
    let gen = spec.generated_noise();
    let drive = SampledDrive {
        accel: noise::generate_shared(&gen, seed, stream)?,
        sample_rate_hz: gen.sample_rate_hz,
        transient_samples: spec.transient_samples(),
    };
    simulate_drive_observed(device, &drive, spec.rtol, spec.scheme, observer)
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

/// One record of `device` under a sampled drive (see [`simulate_record`], which draws the
/// drive from band-limited noise); `rtol` and `scheme` as in [`RecordSpec`].
pub fn simulate_drive(
    device: &Device,
    drive: &SampledDrive,
    rtol: f64,
    scheme: Scheme,
) -> Result<Record, RecordError> {
    simulate_drive_observed(device, drive, rtol, scheme, &mut ())
}

/// [`simulate_drive`], showing every interval to `observer`: builds the model and runs the
/// record's loop compiled for the device's kind of free flight.
pub(crate) fn simulate_drive_observed<O: RecordObserver>(
    device: &Device,
    drive: &SampledDrive,
    rtol: f64,
    scheme: Scheme,
    observer: &mut O,
) -> Result<Record, RecordError> {
    if drive.accel.len() <= drive.transient_samples + 1
        || !(drive.sample_rate_hz.is_finite() && drive.sample_rate_hz > 0.0)
    {
        return Err(RecordError::InvalidSpec {
            field: "drive",
            value: drive.accel.len() as f64,
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
    let model = Harvester::new(
        device,
        Sampled::new(drive.accel.clone(), drive.sample_rate_hz),
    );
    let dt = model.excitation.dt_s;
    let ff = model.free_flight();
    match (scheme, ff.kind()) {
        (Scheme::Dopri5, _) => run(
            &model,
            drive,
            rtol,
            Err::<FastFlight<GeneralFlight>, _>(Fallback::Requested),
            observer,
        ),
        (Scheme::Exponential, FlightKind::AreaOverlap(r)) => run(
            &model,
            drive,
            rtol,
            FastFlight::new(&model, dt, &ff, r),
            observer,
        ),
        (Scheme::Exponential, FlightKind::General(r)) => run(
            &model,
            drive,
            rtol,
            FastFlight::new(&model, dt, &ff, r),
            observer,
        ),
    }
}

/// Output power spectral density of both loads and of each, one-sided, W/Hz.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OutputSpectrum {
    /// `(S_V1 + S_V2) / RL`: its integral is the mean power of both loads.
    pub total: Psd,
    /// `S_V1 / RL`.
    pub load1: Psd,
    /// `S_V2 / RL`.
    pub load2: Psd,
}

impl OutputSpectrum {
    /// The bins with `f_lo <= f <= f_hi` of each density.
    pub fn restrict(&self, f_lo: f64, f_hi: f64) -> Self {
        Self {
            total: restrict(&self.total, f_lo, f_hi),
            load1: restrict(&self.load1, f_lo, f_hi),
            load2: restrict(&self.load2, f_lo, f_hi),
        }
    }
}

/// One-sided Welch estimate of the output power PSD of both loads, `(S_V1 + S_V2)/RL` (W/Hz),
/// and of each load (see the module docs).
pub fn output_psd(
    v1_v: &[f64],
    v2_v: &[f64],
    sample_rate_hz: f64,
    load_resistance_ohm: f64,
    cfg: &WelchConfig,
) -> Result<OutputSpectrum, SpectralError> {
    let scale = |mut p: Psd| {
        p.density.iter_mut().for_each(|d| *d /= load_resistance_ohm);
        p
    };
    let load1 = scale(signal::welch(v1_v, sample_rate_hz, cfg)?);
    let load2 = scale(signal::welch(v2_v, sample_rate_hz, cfg)?);
    let total = Psd {
        freq_hz: load1.freq_hz.clone(),
        density: load1
            .density
            .iter()
            .zip(&load2.density)
            .map(|(a, b)| a + b)
            .collect(),
        segments: load1.segments,
    };
    Ok(OutputSpectrum {
        total,
        load1,
        load2,
    })
}

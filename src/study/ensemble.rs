//! Ensembles of random-vibration records at one or more excitation levels.
//!
//! # Ensembles
//! Every excitation level is an ensemble of independent records: realisation `i` uses ChaCha8
//! stream `first_stream + i` of a fixed seed (so results do not depend on thread scheduling),
//! and [`run_ensembles`] runs all records of all levels in parallel with rayon. Means carry a
//! 95 % confidence interval from Student's t with `n - 1` degrees of freedom ([`MeanCi`]).
//!
//! # Bandwidths
//! [`Widths`] holds the width of the output power PSD at half its peak (3 dB, half power; the
//! default reading of "3 dB bandwidth") and at a quarter of its peak (half amplitude, -6 dB of
//! power), both from [`crate::signal::width_at_fraction`] searched inside the ensemble's
//! analysis band. They are computed on the ensemble-averaged PSD and on every single record;
//! [`Spread`] summarises the sampling distribution of a single-record estimate (the paper
//! used one 10 s record per level), and [`ratio_spread`](crate::num::stats::ratio_spread)
//! that of a ratio of two of them. The
//! width of the ensemble-mean PSD carries a delete-one jackknife interval
//! ([`Ensemble::mean_width`], [`Jackknife`]).
//!
//! # Linear theory
//! The ensembles are compared with the linear theory of [`crate::physics::linear`]:
//! [`LinearResponse::output_psd_w_per_hz`](crate::physics::linear::LinearResponse::output_psd_w_per_hz)
//! is the small-signal output PSD of the same model (for the paper's pair eqs 7-17 in the
//! frequency domain, no end-stops); it integrates to eq 21 and gives the bandwidth the device
//! has without impacts ([`linear_widths`](crate::physics::linear::linear_widths)).

use rayon::prelude::*;

use crate::device::Device;
use crate::num::stats::{Jackknife, MeanCi, Spread};
use crate::ode::Stats;
use crate::progress::Progress;
use crate::signal::bandwidth::{mean_psd, restrict, Widths};
use crate::signal::{self, Psd, WelchOptions};
use crate::study::mass_peaks::MassPeaks;
use crate::study::record::{
    output_psd, simulate_record, OutputSpectrum, RecordError, RecordSpec, RecordSummary,
};

/// Settings of an ensemble at one excitation level.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EnsembleSpec {
    /// The record.
    pub record: RecordSpec,
    /// Welch segmenting of the output PSD.
    pub welch: WelchOptions,
    /// A second segmenting whose single-record widths are reported beside (e.g. MATLAB's
    /// default of eight segments,
    /// [`matlab_default_nperseg`](crate::signal::welch::matlab_default_nperseg)).
    pub alt_welch: Option<WelchOptions>,
    /// Band (Hz) in which spectra are kept and bandwidths are searched.
    pub analysis_band_hz: (f64, f64),
    /// ChaCha8 seed of the excitation.
    pub seed: u64,
    /// Stream of realisation 0; realisation `i` uses `first_stream + i`.
    pub first_stream: u64,
    /// Number of independent records.
    pub realisations: usize,
}

impl EnsembleSpec {
    /// The ensemble of `realisations` records for any device (streams `0..realisations` of
    /// `seed`): Welch segments with bins of about a tenth of the device's linear half-power
    /// width (a power of two, at least 2^10 and at most an eighth of the record), half
    /// overlap, and the analysis band from a quarter to four times the open-circuit resonance
    /// (below 0.45 of the sample rate).
    pub fn for_device(device: &Device, record: RecordSpec, seed: u64, realisations: usize) -> Self {
        let f0 = crate::physics::linear::open_circuit_resonance_hz(device);
        let fs = record.noise.sample_rate_hz;
        let n = record.analysed_samples();
        let width = f0 / crate::physics::linear::open_circuit_qm(device).max(0.5);
        let target = fs / (0.1 * width);
        let mut nperseg = 1usize << 10;
        while (nperseg as f64) < target && nperseg * 2 <= n / 8 {
            nperseg *= 2;
        }
        Self {
            record,
            welch: WelchOptions::half_overlap(nperseg),
            alt_welch: None,
            analysis_band_hz: (0.25 * f0, (4.0 * f0).min(0.45 * fs)),
            seed,
            first_stream: 0,
            realisations,
        }
    }
}

impl EnsembleSpec {
    /// Refuses an analysis band with no bin of a Welch estimate in it (bins lie `fs / nperseg`
    /// apart from 0 Hz): its spectra would be empty and its widths undefined, as for a device
    /// whose resonance lies far below the record's frequency resolution.
    fn check_band_holds_a_bin(&self) -> Result<(), RecordError> {
        let (lo, hi) = self.analysis_band_hz;
        let fs = self.record.noise.sample_rate_hz;
        let holds = |w: &WelchOptions| {
            let df = fs / w.nperseg as f64;
            (lo / df).ceil() * df <= hi
        };
        let alt_holds = self.alt_welch.as_ref().is_none_or(holds);
        if !(lo.is_finite() && hi.is_finite() && lo <= hi && holds(&self.welch) && alt_holds) {
            return Err(RecordError::InvalidSpec {
                field: "analysis_band_hz",
                value: hi,
                expected:
                    "a band holding at least one bin of the Welch estimate: the resonance lies \
                           below the record's frequency resolution (lengthen the record or \
                           lower its sample rate)",
            });
        }
        Ok(())
    }
}

/// One record of an ensemble, analysed (the voltages themselves are not kept).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordResult {
    /// Its ChaCha8 stream.
    pub stream: u64,
    /// Scalar results.
    pub summary: RecordSummary,
    /// Output power PSD restricted to the analysis band (W/Hz).
    pub spectrum: OutputSpectrum,
    /// Widths of `spectrum.total`.
    pub widths: Widths,
    /// Output power PSD of both loads with the alternative segmenting, restricted to the
    /// analysis band, and its widths.
    pub alt: Option<(Psd, Widths)>,
}

/// An ensemble at one excitation level, analysed.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Ensemble {
    /// The settings.
    pub spec: EnsembleSpec,
    /// Every record, in stream order.
    pub records: Vec<RecordResult>,
    /// Ensemble average of the records' Welch estimates (analysis band, W/Hz).
    pub mean_spectrum: OutputSpectrum,
    /// Widths of the ensemble-averaged PSD of both loads.
    pub mean_widths: Widths,
    /// Mean power of both loads (W).
    pub power_w: MeanCi,
    /// Mean power of load 1 (W).
    pub p1_w: MeanCi,
    /// Mean power of load 2 (W).
    pub p2_w: MeanCi,
    /// Efficiency `2P/(m Sa)` per record (fraction): the power over the mean power the white
    /// noise puts in, `m Sa / 2`; on a device of several masses `m` is the driven mass
    /// ([`Device::driven_mass_kg`]: the total under the frame's acceleration).
    pub efficiency: MeanCi,
    /// RMS displacement (m).
    pub x_rms_m: MeanCi,
    /// Fraction of time in contact.
    pub contact_fraction: MeanCi,
    /// Largest |x| over all records (m).
    pub x_peak_m: f64,
    /// Each mass's largest |x| and |v| over all records (a model of several masses; none for
    /// one).
    #[serde(default)]
    pub mass_peaks: MassPeaks,
    /// Impacts over all records.
    pub impacts: u64,
    /// Integrator counters summed over the records.
    pub stats: Stats,
}

impl Ensemble {
    /// Two-sided acceleration PSD of the level (g²/Hz).
    pub fn psd_g2_per_hz(&self) -> f64 {
        self.spec.record.noise.psd_g2_per_hz
    }

    /// Single-record 3 dB widths (Hz; NaN where undetermined), in stream order.
    pub fn single_bw3db_hz(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.widths.bw3db_hz()).collect()
    }

    /// Single-record half-amplitude widths (Hz).
    pub fn single_bw6db_hz(&self) -> Vec<f64> {
        self.records.iter().map(|r| r.widths.bw6db_hz()).collect()
    }

    /// Single-record 3 dB widths with the alternative segmenting (Hz).
    pub fn single_alt_bw3db_hz(&self) -> Vec<f64> {
        self.records
            .iter()
            .map(|r| r.alt.as_ref().map_or(f64::NAN, |a| a.1.bw3db_hz()))
            .collect()
    }

    /// Sampling distribution of the single-record 3 dB width.
    pub fn single_bw3db_spread(&self) -> Spread {
        Spread::of(&self.single_bw3db_hz())
    }

    /// Sampling distribution of the single-record half-amplitude width.
    pub fn single_bw6db_spread(&self) -> Spread {
        Spread::of(&self.single_bw6db_hz())
    }

    /// Single-record peak frequencies of the output PSD of both loads (Hz).
    pub fn single_peak_hz(&self) -> Vec<f64> {
        self.records
            .iter()
            .map(|r| r.spectrum.total.peak().0)
            .collect()
    }

    /// Width of the ensemble-averaged PSD of both loads at `fraction` of its peak (0.5: 3 dB),
    /// with its delete-one jackknife uncertainty over the records (Hz).
    pub fn mean_width(&self, fraction: f64) -> Jackknife {
        let width =
            |p: &Psd| signal::width_at_fraction(p, fraction).map_or(f64::NAN, |b| b.width_hz);
        let sum = &self.mean_spectrum.total;
        let n = self.records.len();
        let mut p = sum.clone();
        Jackknife::of(n, width(sum), |i| {
            let x = &self.records[i].spectrum.total.density;
            for ((d, m), x) in p.density.iter_mut().zip(&sum.density).zip(x) {
                *d = (n as f64 * m - x) / (n - 1) as f64;
            }
            width(&p)
        })
    }

    /// True if no record of the ensemble touched a stop.
    pub fn no_impact(&self) -> bool {
        self.impacts == 0
    }
}

/// One level of one device, for [`run_ensembles`].
#[derive(Debug, Clone, PartialEq)]
pub struct EnsembleCase {
    /// The device (bias voltage and end-stop options included).
    pub device: Device,
    /// The ensemble.
    pub spec: EnsembleSpec,
}

/// Simulates and analyses one record of an ensemble (realisation `i`).
pub fn run_record(
    device: &Device,
    spec: &EnsembleSpec,
    i: usize,
) -> Result<RecordResult, RecordError> {
    let stream = spec.first_stream + i as u64;
    let rec = simulate_record(device, &spec.record, spec.seed, stream)?;
    let rl = device.transducer.load_resistance_ohm();
    let (lo, hi) = spec.analysis_band_hz;
    let spectrum = output_psd(&rec, rl, &spec.welch)?.restrict(lo, hi);
    let widths = Widths::of(&spectrum.total);
    let alt = match &spec.alt_welch {
        Some(cfg) => {
            let s = output_psd(&rec, rl, cfg)?;
            let t = restrict(&s.total, lo, hi);
            let w = Widths::of(&t);
            Some((t, w))
        }
        None => None,
    };
    Ok(RecordResult {
        stream,
        summary: rec.summary,
        spectrum,
        widths,
        alt,
    })
}

/// Runs every record of every case in parallel (rayon; one task per record, so that the
/// cores stay busy across levels of very different cost), calling `on_record` after each,
/// and analyses each case into an [`Ensemble`] (in the order of `cases`).
pub fn run_ensembles(
    cases: &[EnsembleCase],
    on_record: &dyn Progress,
) -> Result<Vec<Ensemble>, RecordError> {
    for c in cases {
        if c.spec.realisations == 0 {
            return Err(RecordError::InvalidSpec {
                field: "realisations",
                value: 0.0,
                expected: "at least 1",
            });
        }
        c.spec.record.validate()?;
        c.spec.check_band_holds_a_bin()?;
    }
    let jobs: Vec<(usize, usize)> = cases
        .iter()
        .enumerate()
        .flat_map(|(c, case)| (0..case.spec.realisations).map(move |i| (c, i)))
        .collect();
    let results: Vec<RecordResult> = jobs
        .par_iter()
        .map(|&(c, i)| {
            let r = run_record(&cases[c].device, &cases[c].spec, i);
            on_record.tick();
            r
        })
        .collect::<Result<_, _>>()?;
    let mut it = results.into_iter();
    Ok(cases
        .iter()
        .map(|case| {
            let recs: Vec<RecordResult> = it.by_ref().take(case.spec.realisations).collect();
            analyse(case, recs)
        })
        .collect())
}

/// Runs one ensemble (see [`run_ensembles`]).
///
/// ```
/// use endstop::device::Device;
/// use endstop::progress::Silent;
/// use endstop::study::ensemble::{run_ensemble, EnsembleSpec};
/// use endstop::drive::noise::NoiseSpec;
/// use endstop::study::record::RecordSpec;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype1.toml"));
/// let device = Device::from_toml_str(text, "prototype1.toml")?;
/// // Two short records (50 ms each) of noise at 1e-6 g^2/Hz flat to 10 kHz, seed 2012.
/// let noise = NoiseSpec {
///     psd_g2_per_hz: 1e-6,
///     bandwidth_hz: 10e3,
///     sample_rate_hz: 100e3,
///     duration_s: 0.05,
/// };
/// let mut record = RecordSpec::of(&device, noise);
/// record.transient_s = 0.01;
/// let spec = EnsembleSpec::for_device(&device, record, 2012, 2);
/// let ensemble = run_ensemble(&device, &spec, &Silent)?;
/// assert_eq!(ensemble.records.len(), 2);
/// assert!(ensemble.power_w.mean > 0.0);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn run_ensemble(
    device: &Device,
    spec: &EnsembleSpec,
    on_record: &dyn Progress,
) -> Result<Ensemble, RecordError> {
    let case = EnsembleCase {
        device: device.clone(),
        spec: spec.clone(),
    };
    Ok(run_ensembles(std::slice::from_ref(&case), on_record)?.remove(0))
}

fn analyse(case: &EnsembleCase, records: Vec<RecordResult>) -> Ensemble {
    let mean_spectrum = OutputSpectrum {
        total: mean_psd(records.iter().map(|r| &r.spectrum.total)),
        load1: mean_psd(records.iter().map(|r| &r.spectrum.load1)),
        load2: mean_psd(records.iter().map(|r| &r.spectrum.load2)),
    };
    let mean_widths = Widths::of(&mean_spectrum.total);
    let col = |f: &dyn Fn(&RecordSummary) -> f64| -> Vec<f64> {
        records.iter().map(|r| f(&r.summary)).collect()
    };
    let m = case.device.driven_mass_kg();
    let sa_si = case.spec.record.noise.psd_si();
    let mut stats = Stats::default();
    for r in &records {
        stats += r.summary.stats;
    }
    Ensemble {
        spec: case.spec.clone(),
        mean_widths,
        power_w: MeanCi::of(&col(&|s| s.p_total_w())),
        p1_w: MeanCi::of(&col(&|s| s.p1_w)),
        p2_w: MeanCi::of(&col(&|s| s.p2_w)),
        efficiency: MeanCi::of(&col(&|s| 2.0 * s.p_total_w() / (m * sa_si))),
        x_rms_m: MeanCi::of(&col(&|s| s.x_rms_m)),
        contact_fraction: MeanCi::of(&col(&|s| s.contact_fraction)),
        x_peak_m: records
            .iter()
            .map(|r| r.summary.x_peak_m)
            .fold(0.0, f64::max),
        mass_peaks: records
            .iter()
            .fold(MassPeaks::none(), |p, r| p.max(&r.summary.mass_peaks)),
        impacts: records.iter().map(|r| r.summary.impacts).sum(),
        stats,
        mean_spectrum,
        records,
    }
}

/// Seed of the ChaCha8 streams of every random-vibration (record) experiment (a named constant, so that runs
/// are deterministic).
pub const DEFAULT_SEED: u64 = 20_120_704;

/// First ChaCha8 stream of the ensemble at level `psd_g2_per_hz`: `round(Sa * 1e9) * 1000`.
///
/// Keying the streams by the level makes ensembles at different levels independent, and makes
/// the same level in two experiments (Figures 14 and 15) reuse the same records.
pub fn first_stream_for_level(psd_g2_per_hz: f64) -> u64 {
    (psd_g2_per_hz * 1e9).round() as u64 * 1000
}

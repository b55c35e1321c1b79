//! Fitting a device to a measured output spectrum under random vibration: each evaluation of
//! the model is an ensemble of records, so the fit runs on emulators. The measured spectrum is
//! reduced to three features that move smoothly with the parameters and average the noise of
//! the bins, and each feature is emulated over the free parameters from a design of ensembles
//! ([`crate::num::history::Emulator`]: a Gaussian process with each ensemble's jackknife
//! variance as its nugget, and a model of that variance).
//!
//! # Features
//! Over the measured band, of the output power PSD `S(f)` of both loads (W/Hz): the logarithm
//! of the band power `P = int S df`, the centroid `fc = int f S df / P` (Hz) and the spread
//! `sqrt(int (f - fc)^2 S df / P)` (Hz), by the trapezoid rule on each spectrum's own grid.
//!
//! # Fit and uncertainty
//! With `m_k` the measured features and `mu_k(theta)` the emulators' means, the likelihood is
//! Gaussian with variance `V_k = Var_emulator,k(theta) + Var_sampling,k(theta) R / R_meas`: the
//! emulator's own uncertainty, and the measured spectrum's sampling variance, taken as the
//! model ensemble's (of `R` records) scaled to the measured record count `R_meas`. The
//! posterior under a flat prior on the free parameters' box is sampled by importance sampling
//! from uniform points in a box that shrinks, three times, to the points of non-negligible
//! weight: the estimate is the posterior mean, the interval its 2.5 and 97.5 % weighted
//! quantiles, and the maximum-posterior point is reported beside.
//!
//! The recovery test (`tests/spectrum_fit.rs`) fits synthetic spectra of a known device and
//! states how often the intervals hold the truth.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;
use thiserror::Error;

use super::params::{apply, check_free};
use super::FitError;
use crate::device::{Device, ParamRange};
use crate::drive::noise::NoiseSpec;
use crate::num::gp::GpSettings;
use crate::num::history::{maximin_lhs, Emulator, HistoryError};
use crate::num::stats::Jackknife;
use crate::progress::{Progress, Silent};
use crate::study::ensemble::{run_ensemble, EnsembleSpec};
use crate::study::record::RecordSpec;

/// The features' names, in order.
pub const FEATURES: [&str; 3] = ["ln_band_power", "centroid_hz", "spread_hz"];

/// Why a spectrum fit failed.
#[derive(Debug, Error)]
pub enum SpectrumFitError {
    /// The free parameters or the device.
    #[error(transparent)]
    Fit(#[from] FitError),
    /// The measured spectrum is unusable.
    #[error("measured spectrum: {0}")]
    Data(String),
    /// An ensemble of the design failed.
    #[error("ensemble at design point {point}: {why}")]
    Ensemble {
        /// The design point.
        point: usize,
        /// Why.
        why: String,
    },
    /// An emulator could not be fitted.
    #[error(transparent)]
    Emulator(#[from] HistoryError),
}

/// A measured output spectrum.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredSpectrum {
    /// Frequencies (Hz), increasing.
    pub freq_hz: Vec<f64>,
    /// Output power PSD of both loads (W/Hz).
    pub psd_w_per_hz: Vec<f64>,
    /// The stated two-sided acceleration PSD of the drive (g²/Hz).
    pub accel_psd_g2_per_hz: f64,
    /// How many 10 s records the measured PSD averages (its sampling variance).
    pub records: usize,
}

impl MeasuredSpectrum {
    /// Checks the spectrum: at least 8 bins, increasing frequencies, finite non-negative
    /// densities with a positive band power, a positive level and record count.
    pub fn validate(&self) -> Result<(), SpectrumFitError> {
        let e = |w: String| Err(SpectrumFitError::Data(w));
        if self.freq_hz.len() != self.psd_w_per_hz.len() || self.freq_hz.len() < 8 {
            return e(format!(
                "{} frequencies and {} densities: at least 8 bins of both",
                self.freq_hz.len(),
                self.psd_w_per_hz.len()
            ));
        }
        if self
            .freq_hz
            .windows(2)
            .any(|w| w[1] <= w[0] || w[1].is_nan())
            || self.freq_hz[0] <= 0.0
        {
            return e("frequencies must be positive and increasing".into());
        }
        if let Some((i, v)) = self
            .psd_w_per_hz
            .iter()
            .enumerate()
            .find(|(_, v)| !v.is_finite() || **v < 0.0)
        {
            return e(format!(
                "density {v} at row {} is not finite and >= 0",
                i + 1
            ));
        }
        if self.accel_psd_g2_per_hz.is_nan()
            || self.accel_psd_g2_per_hz <= 0.0
            || self.accel_psd_g2_per_hz.is_infinite()
        {
            return e(format!(
                "acceleration PSD {} g²/Hz must be positive",
                self.accel_psd_g2_per_hz
            ));
        }
        if self.records == 0 {
            return e("the record count must be at least 1".into());
        }
        if features(&self.freq_hz, &self.psd_w_per_hz, self.band()).is_none() {
            return e("the band power is zero".into());
        }
        Ok(())
    }

    /// The measured band (Hz).
    pub fn band(&self) -> (f64, f64) {
        (self.freq_hz[0], *self.freq_hz.last().expect("validated"))
    }

    /// The measured features.
    pub fn features(&self) -> Option<[f64; 3]> {
        features(&self.freq_hz, &self.psd_w_per_hz, self.band())
    }
}

/// The features of a spectrum over `band` (bins inside it, trapezoid rule); `None` when it
/// has fewer than two bins there or no power.
pub fn features(freq: &[f64], psd: &[f64], band: (f64, f64)) -> Option<[f64; 3]> {
    let pts: Vec<(f64, f64)> = freq
        .iter()
        .zip(psd)
        .filter(|(f, _)| **f >= band.0 && **f <= band.1)
        .map(|(f, s)| (*f, *s))
        .collect();
    let trap = |g: &dyn Fn(f64, f64) -> f64| {
        pts.windows(2)
            .map(|w| 0.5 * (w[1].0 - w[0].0) * (g(w[0].0, w[0].1) + g(w[1].0, w[1].1)))
            .sum::<f64>()
    };
    let p = trap(&|_, s| s);
    if pts.len() < 2 || p.is_nan() || p <= 0.0 {
        return None;
    }
    let fc = trap(&|f, s| f * s) / p;
    let spread = (trap(&|f, s| (f - fc).powi(2) * s) / p).sqrt();
    Some([p.ln(), fc, spread])
}

/// The model's record at level `psd_g2_per_hz`: band-limited white noise with a 10 kHz band
/// sampled at 100 kHz, 10 s analysed after the device's pre-roll, the excitation that a
/// [`MeasuredSpectrum`]'s records are taken to share.
pub fn model_record(device: &Device, psd_g2_per_hz: f64) -> RecordSpec {
    RecordSpec::of(
        device,
        NoiseSpec {
            psd_g2_per_hz,
            bandwidth_hz: 10e3,
            sample_rate_hz: 100e3,
            duration_s: 10.0,
        },
    )
}

/// The model's features and their sampling variances (delete-one jackknife over the records)
/// for `device` at `accel_psd` (g²/Hz, the drive scaled by `scale`), over `band`, by an ensemble
/// of `records` records on streams `first_stream..` of `seed`.
pub fn model_features(
    device: &Device,
    accel_psd: f64,
    scale: f64,
    band: (f64, f64),
    records: usize,
    (seed, first_stream): (u64, u64),
) -> Result<([f64; 3], [f64; 3]), String> {
    let psd = accel_psd * scale * scale;
    let mut spec = EnsembleSpec::for_device(device, model_record(device, psd), seed, records);
    spec.analysis_band_hz = band;
    spec.first_stream = first_stream;
    let e = run_ensemble(device, &spec, &Silent).map_err(|e| e.to_string())?;
    let mean = &e.mean_spectrum.total;
    let all = features(&mean.freq_hz, &mean.density, band).ok_or("no power in the band")?;
    let n = e.records.len();
    let mut vars = [0.0; 3];
    for (k, var) in vars.iter_mut().enumerate() {
        let mut d = mean.density.clone();
        let jack = Jackknife::of(n, all[k], |i| {
            let x = &e.records[i].spectrum.total.density;
            for ((d, m), x) in d.iter_mut().zip(&mean.density).zip(x) {
                *d = (n as f64 * m - x) / (n - 1) as f64;
            }
            features(&mean.freq_hz, &d, band).map_or(f64::NAN, |f| f[k])
        });
        *var = if jack.se.is_finite() {
            jack.se * jack.se
        } else {
            0.0
        };
    }
    Ok((all, vars))
}

/// The settings of a spectrum fit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SpectrumSettings {
    /// Design points per free parameter.
    pub per_param: usize,
    /// Records per design ensemble.
    pub records: usize,
    /// Seed of the design and of the ensembles' streams.
    pub seed: u64,
    /// Uniform points per stage of the posterior's importance sampling.
    pub samples: usize,
    /// The emulators' hyperparameter search.
    pub gp: GpSettings,
}

impl Default for SpectrumSettings {
    /// Ten points per parameter, 16 records each, 4096 samples per stage.
    fn default() -> Self {
        Self {
            per_param: 10,
            records: 16,
            seed: 17,
            samples: 4096,
            gp: GpSettings::default(),
        }
    }
}

/// The emulators of the features over the free parameters' box.
#[derive(Debug, Clone)]
pub struct SpectrumEmulator {
    /// The free parameters.
    pub free: Vec<ParamRange>,
    /// The settings.
    pub settings: SpectrumSettings,
    /// The design (unit cube of the free parameters).
    pub design: Vec<Vec<f64>>,
    /// The features at each design point.
    pub values: Vec<[f64; 3]>,
    /// Their sampling variances.
    pub variances: Vec<[f64; 3]>,
    /// One emulator per feature.
    pub emulators: Vec<Emulator>,
}

/// The device and the drive's scale at a unit-cube point.
fn at(base: &Device, free: &[ParamRange], u: &[f64]) -> Result<(Device, f64), FitError> {
    let p: Vec<f64> = free.iter().zip(u).map(|(f, s)| f.at(*s)).collect();
    apply(base, free, &p)
}

/// Runs the design of ensembles of `base` with `free` over `band` at the stated level and fits
/// the emulators; `on_point.tick()` after each design point.
pub fn build_emulator(
    base: &Device,
    free: &[ParamRange],
    accel_psd: f64,
    band: (f64, f64),
    settings: SpectrumSettings,
    on_point: &dyn Progress,
) -> Result<SpectrumEmulator, SpectrumFitError> {
    check_free(base, free)?;
    let n = settings.per_param * free.len();
    let mut rng = ChaCha8Rng::seed_from_u64(settings.seed);
    let design = maximin_lhs(n, free.len(), &mut rng);
    let runs = design
        .par_iter()
        .enumerate()
        .map(|(k, u)| {
            let (dev, scale) = at(base, free, u)?;
            // Every design point draws the same streams (common random numbers).
            let r = model_features(
                &dev,
                accel_psd,
                scale,
                band,
                settings.records,
                (settings.seed, 0),
            )
            .map_err(|why| SpectrumFitError::Ensemble { point: k, why });
            on_point.tick();
            r
        })
        .collect::<Result<Vec<_>, _>>()?;
    let values: Vec<[f64; 3]> = runs.iter().map(|r| r.0).collect();
    let variances: Vec<[f64; 3]> = runs.iter().map(|r| r.1).collect();
    let emulators = (0..3)
        .map(|k| {
            let y: Vec<f64> = values.iter().map(|v| v[k]).collect();
            let v: Vec<f64> = variances.iter().map(|v| v[k]).collect();
            Emulator::fit(&design, &y, &v, settings.gp).map_err(|source| {
                SpectrumFitError::Emulator(HistoryError::Emulator {
                    output: FEATURES[k].into(),
                    source,
                })
            })
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(SpectrumEmulator {
        free: free.to_vec(),
        settings,
        design,
        values,
        variances,
        emulators,
    })
}

/// One fitted parameter.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumParam {
    /// Its path.
    pub path: String,
    /// Posterior mean.
    pub mean: f64,
    /// Maximum-posterior value.
    pub best: f64,
    /// 95 % interval (2.5 and 97.5 % posterior quantiles).
    pub interval: (f64, f64),
}

/// A spectrum fit.
#[derive(Debug, Clone, PartialEq)]
pub struct SpectrumEstimate {
    /// Each free parameter.
    pub params: Vec<SpectrumParam>,
    /// The measured features.
    pub measured: [f64; 3],
    /// The emulated features at the maximum-posterior point.
    pub predicted: [f64; 3],
    /// |measured - predicted| / sqrt(V) of each feature there: above 3 the model does not
    /// reach the measurement inside the box.
    pub implausibility: [f64; 3],
    /// Effective sample size of the last stage's weights.
    pub effective_samples: f64,
}

impl SpectrumEmulator {
    /// The log-likelihood of `measured` at unit point `u`, with each feature's prediction and
    /// variance.
    fn log_likelihood(&self, m: &[f64; 3], ratio: f64, u: &[f64]) -> (f64, [f64; 3], [f64; 3]) {
        let mut ll = 0.0;
        let mut mu = [0.0; 3];
        let mut var = [0.0; 3];
        for (k, e) in self.emulators.iter().enumerate() {
            let p = e.predict(u);
            let v = p.emulator_var + p.sampling_var * ratio;
            ll -= 0.5 * ((m[k] - p.mean).powi(2) / v + v.ln());
            mu[k] = p.mean;
            var[k] = v;
        }
        (ll, mu, var)
    }

    /// Fits the measured spectrum (see the module docs).
    pub fn fit(&self, measured: &MeasuredSpectrum) -> Result<SpectrumEstimate, SpectrumFitError> {
        measured.validate()?;
        let m = measured.features().expect("validated");
        let ratio = self.settings.records as f64 / measured.records as f64;
        let d = self.free.len();
        let mut lo = vec![0.0; d];
        let mut hi = vec![1.0; d];
        let mut rng = ChaCha8Rng::seed_from_u64(self.settings.seed + 1);
        let mut last: Vec<(Vec<f64>, f64)> = Vec::new();
        for stage in 0..4 {
            let pts: Vec<Vec<f64>> = (0..self.settings.samples)
                .map(|_| {
                    (0..d)
                        .map(|j| lo[j] + (hi[j] - lo[j]) * rng.random::<f64>())
                        .collect()
                })
                .collect();
            let ll: Vec<f64> = pts
                .par_iter()
                .map(|u| self.log_likelihood(&m, ratio, u).0)
                .collect();
            let top = ll.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            last = pts
                .into_iter()
                .zip(&ll)
                .map(|(u, l)| (u, (l - top).exp()))
                .collect();
            if stage == 3 {
                break;
            }
            // The next box: the points of weight above 1e-4 of the largest, widened by a
            // quarter of their span each side (and a hundredth of the cube at least).
            for j in 0..d {
                let (a, b) = last
                    .iter()
                    .filter(|(_, w)| *w > 1e-4)
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), (u, _)| {
                        (a.min(u[j]), b.max(u[j]))
                    });
                let pad = (0.25 * (b - a)).max(0.01);
                lo[j] = (a - pad).max(lo[j]);
                hi[j] = (b + pad).min(hi[j]);
            }
        }
        let total: f64 = last.iter().map(|p| p.1).sum();
        let ess = total * total / last.iter().map(|p| p.1 * p.1).sum::<f64>();
        let (best_u, _) = last
            .iter()
            .max_by(|a, b| a.1.total_cmp(&b.1))
            .expect("samples");
        let params = self
            .free
            .iter()
            .enumerate()
            .map(|(j, f)| {
                let mut v: Vec<(f64, f64)> = last.iter().map(|(u, w)| (f.at(u[j]), *w)).collect();
                v.sort_by(|a, b| a.0.total_cmp(&b.0));
                let q = |p: f64| {
                    let mut acc = 0.0;
                    for (x, w) in &v {
                        acc += w / total;
                        if acc >= p {
                            return *x;
                        }
                    }
                    v.last().expect("samples").0
                };
                SpectrumParam {
                    path: f.path.clone(),
                    mean: v.iter().map(|(x, w)| x * w).sum::<f64>() / total,
                    best: f.at(best_u[j]),
                    interval: (q(0.025), q(0.975)),
                }
            })
            .collect();
        let (_, predicted, var) = self.log_likelihood(&m, ratio, best_u);
        let implausibility: [f64; 3] =
            std::array::from_fn(|k| (m[k] - predicted[k]).abs() / var[k].sqrt());
        Ok(SpectrumEstimate {
            params,
            measured: m,
            predicted,
            implausibility,
            effective_samples: ess,
        })
    }
}

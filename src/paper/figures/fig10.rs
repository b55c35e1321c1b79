//! Figure 10: the random excitation. Band-limited white-noise acceleration at the paper's
//! example level Sa = 1e-2 g²/Hz (two-sided), 10 kHz band, 10 s at 100 kHz, and its Welch PSD
//! against the target (claim F10: level and band).

use rayon::prelude::*;

use crate::drive::noise::{generate, NoiseSpec};
use crate::num::stats::MeanCi;
use crate::paper::claims::{keys, Claims, ClaimsError, Value};
use crate::paper::setups::{paper_noise, ParamSet};
use crate::paper::Figure;
use crate::progress::Progress;
use crate::signal::bandwidth::{mean_psd, upper_band_edge_hz};
use crate::signal::{welch, Psd, WelchOptions};
use crate::study::ensemble::{first_stream_for_level, DEFAULT_SEED};
use crate::study::record::RecordError;
use crate::G;

/// The paper's example level (g²/Hz, two-sided).
pub const FIG10_SA: f64 = 1e-2;

/// Welch segment: 2^14 samples (6.1 Hz bins), 121 segments per 10 s record.
pub const NPERSEG: usize = 1 << 14;

/// Band over which the flat level is averaged (Hz): clear of DC and of the band edge.
pub const FLAT_BAND_HZ: (f64, f64) = (100.0, 9500.0);

/// Independent records (cheap: no integration), for the uncertainty of the level and edge.
pub const RECORDS: usize = 16;

/// Above this frequency (Hz) the generated density is compared with the level, as a measure
/// of the window's leakage from the band edge.
pub const LEAKAGE_FROM_HZ: f64 = 10.5e3;

/// The band edge is where the one-sided density falls to this fraction of the one-sided flat
/// level (-3 dB).
pub const EDGE_FRACTION: f64 = 0.5;

/// One generated record: its one-sided Welch PSD (g²/Hz) and its sample mean square (g²).
#[derive(Debug, Clone, PartialEq)]
pub struct NoiseRecord {
    /// One-sided Welch PSD of the acceleration in g (g²/Hz).
    pub psd: Psd,
    /// Sample mean square of the acceleration (g²).
    pub mean_square_g2: f64,
}

/// The records of Figure 10.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// The excitation ([`paper_noise`] at [`FIG10_SA`]).
    pub spec: NoiseSpec,
    /// ChaCha8 seed.
    pub seed: u64,
    /// Stream of record 0; record `i` uses `first_stream + i`.
    pub first_stream: u64,
    /// Welch segmenting.
    pub welch: WelchOptions,
    /// The records, in stream order.
    pub records: Vec<NoiseRecord>,
}

/// Mean two-sided level of a one-sided PSD over [`FLAT_BAND_HZ`] (g²/Hz).
pub fn flat_level(p: &Psd) -> f64 {
    p.two_sided_level_in_band(FLAT_BAND_HZ.0, FLAT_BAND_HZ.1)
}

/// The -3 dB band edge of a one-sided PSD: the highest frequency where it is still at least
/// [`EDGE_FRACTION`] of its one-sided flat level, scanning down from the top (Hz).
pub fn band_edge_hz(p: &Psd) -> f64 {
    upper_band_edge_hz(p, 2.0 * flat_level(p), EDGE_FRACTION)
}

/// What Figure 10 shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Findings {
    /// Flat-band level over the records (g²/Hz, two-sided).
    pub level: MeanCi,
    /// Band edge over the records (Hz).
    pub edge: MeanCi,
    /// Mean square over the records (g²).
    pub mean_square: MeanCi,
    /// Flat-band level of record 0 (g²/Hz).
    pub example_level: f64,
    /// Band edge of record 0 (Hz).
    pub example_edge_hz: f64,
    /// Relative standard deviation of record 0's bins in the flat band.
    pub example_bin_relative_std: f64,
    /// Largest density of record 0 above [`LEAKAGE_FROM_HZ`] over its flat level.
    pub example_leakage: f64,
    /// Record 0's two-sided PSD (g²/Hz).
    pub example_two_sided: Psd,
    /// The records' mean two-sided PSD (g²/Hz).
    pub mean_two_sided: Psd,
}

/// Figure 10's findings.
pub fn findings(run: &Run) -> Findings {
    let psds = || run.records.iter().map(|r| &r.psd);
    let ex = &run.records[0].psd;
    let example_two_sided = ex.scaled(0.5);
    let flat = MeanCi::of(&example_two_sided.densities_in_band(FLAT_BAND_HZ.0, FLAT_BAND_HZ.1));
    let levels: Vec<f64> = psds().map(flat_level).collect();
    let edges: Vec<f64> = psds().map(band_edge_hz).collect();
    let ms: Vec<f64> = run.records.iter().map(|r| r.mean_square_g2).collect();
    Findings {
        level: MeanCi::of(&levels),
        edge: MeanCi::of(&edges),
        mean_square: MeanCi::of(&ms),
        example_level: flat_level(ex),
        example_edge_hz: band_edge_hz(ex),
        example_bin_relative_std: flat.std / flat.mean,
        example_leakage: example_two_sided.max_density_from(LEAKAGE_FROM_HZ) / flat_level(ex),
        mean_two_sided: mean_psd(psds()).scaled(0.5),
        example_two_sided,
    }
}

/// Figure 10: the band-limited white-noise excitation and its PSD.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig10;

impl Figure for Fig10 {
    const NAME: &'static str = "fig10";
    /// The excitation depends on no device.
    type Setup = ();
    type Run = Run;
    type Error = RecordError;

    fn work(_: &()) -> usize {
        RECORDS
    }

    /// Generates and analyses the [`RECORDS`] records in parallel, calling `progress` after
    /// each.
    fn run(_: &(), progress: &dyn Progress) -> Result<Run, RecordError> {
        let spec = paper_noise(FIG10_SA);
        let first_stream = first_stream_for_level(FIG10_SA);
        let cfg = WelchOptions::half_overlap(NPERSEG);
        let records = (0..RECORDS as u64)
            .into_par_iter()
            .map(|i| -> Result<NoiseRecord, RecordError> {
                let a = generate(&spec, DEFAULT_SEED, first_stream + i)?;
                let g: Vec<f64> = a.iter().map(|x| x / G).collect();
                let mean_square_g2 = g.iter().map(|x| x * x).sum::<f64>() / g.len() as f64;
                let psd = welch(&g, spec.sample_rate_hz, &cfg)?;
                progress.tick();
                Ok(NoiseRecord {
                    psd,
                    mean_square_g2,
                })
            })
            .collect::<Result<_, _>>()?;
        Ok(Run {
            spec,
            seed: DEFAULT_SEED,
            first_stream,
            welch: cfg,
            records,
        })
    }

    /// Claim F10: the generated level over the flat band and the band edge, means over the
    /// records with their 95 % CIs.
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let f = findings(run);
        let n = run.records.len();
        claims.known(vec![
            Value::new(
                keys::F10_LEVEL,
                ParamSet::Published,
                f.level.mean,
                Some(f.level.ci95),
                format!(
                    "mean two-sided density over {}-{} Hz, {n} records; CI: Student t",
                    FLAT_BAND_HZ.0, FLAT_BAND_HZ.1
                ),
            ),
            Value::new(
                keys::F10_BAND,
                ParamSet::Published,
                f.edge.mean,
                Some(f.edge.ci95),
                format!("-3 dB edge, {n} records; CI: Student t"),
            ),
        ])
    }
}

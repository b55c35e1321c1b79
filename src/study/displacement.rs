//! What a random ensemble says about where the mass is: the displacement's histogram with its
//! sampling uncertainty, its mean square, the share of time in contact with each stop and in
//! each well, and for a device with two wells the rate of passages from one well's bottom to
//! the other's.
//!
//! Each record ([`crate::study::record`]) is read at its analysed sample instants
//! ([`record_displacement`]). The records of an ensemble are independent realisations, so the
//! sampling uncertainty of every ensemble quantity is taken across records (one value per
//! record, Student's t, [`MeanCi`]): the samples within one record are correlated over the
//! device's correlation time, and counting them as independent would understate it.
//!
//! **Wells and passages.** The wells are the device's stable equilibria between its stops
//! ([`crate::physics::statics::equilibria`]); the region of a well reaches to the barrier (the unstable
//! equilibrium) between it and the next. With two wells a passage is counted when the mass,
//! last at the bottom of one well, reaches the bottom of the other (a crossing of the other
//! well's position): a passage over the barrier that falls back before the other well's bottom
//! is not counted. These are not escapes that settle in the other well: with light damping a
//! mass above the barrier swings through both bottoms many times before it loses the energy to
//! settle in either, and each swing counts (the validation chapter's escape rows,
//! [`crate::validation::escapes`], count both and hold each to its theory). The rate
//! ([`DisplacementEnsemble::transition_rate`]) is such passages per second of the analysed
//! record; with moderate damping, where a mass that reaches the other bottom settles there, it
//! estimates the escape rate from one well.

use rayon::prelude::*;

use crate::device::Device;
use crate::laws::suspension::Place;
use crate::model::Mode;
use crate::num::stats::MeanCi;
use crate::study::record::{
    simulate_observed, RecordError, RecordObserver, RecordSpec, RecordSummary,
};

/// The wells of a device for the transition count: positions (m) and the barrier between
/// them (m). `None` unless the device has exactly two stable equilibria between its stops.
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::noise::NoiseSpec;
/// use endstop::study::displacement::{record_displacement, two_wells, DisplacementBins};
/// use endstop::study::record::RecordSpec;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/bistable_stops_em.toml"));
/// let device = Device::from_toml_str(text, "bistable_stops_em.toml")?;
/// // The file's double well has its wells at +-0.5 mm and its barrier at 0; the equilibria
/// // are found numerically, to far better than 1e-9 m.
/// let ([left, right], barrier) = two_wells(&device).unwrap();
/// assert!((left + 5e-4).abs() < 1e-9 && (right - 5e-4).abs() < 1e-9 && barrier.abs() < 1e-9);
///
/// // A short noise record read into 20 bins over +-1 mm. The stops at +-0.8 mm (20 kN/m)
/// // would need 4 N, 80 g on the 5 g mass, to be pressed to 1 mm, so every sample is binned.
/// let noise = NoiseSpec { psd_g2_per_hz: 1e-4, bandwidth_hz: 200.0, sample_rate_hz: 2e3, duration_s: 0.5 };
/// let mut spec = RecordSpec::of(&device, noise);
/// spec.transient_s = 0.0;
/// let bins = DisplacementBins::uniform(&device, -1e-3, 1e-3, 20);
/// let rec = record_displacement(&device, &spec, &bins, 2012, 0)?;
/// assert_eq!(rec.counts.iter().sum::<u64>(), rec.samples);
/// assert!(rec.x2_mean_m2 < 1e-6);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn two_wells(device: &Device) -> Option<([f64; 2], f64)> {
    let eq = crate::physics::statics::equilibria(device);
    let wells: Vec<f64> = eq
        .iter()
        .filter(|e| e.stable && e.place == Place::Free)
        .map(|e| e.x_m)
        .collect();
    if wells.len() != 2 {
        return None;
    }
    let barrier = eq
        .iter()
        .filter(|e| !e.stable && e.x_m > wells[0] && e.x_m < wells[1])
        .map(|e| e.x_m)
        .next()?;
    Some(([wells[0], wells[1]], barrier))
}

/// How a record's displacement is read: histogram bins and the wells.
#[derive(Debug, Clone, PartialEq)]
pub struct DisplacementBins {
    /// Bin edges (m), increasing; samples outside them count in neither bin.
    pub edges_m: Vec<f64>,
    /// The upper and lower stops' gaps (m; infinite without a stop).
    pub gaps_m: [f64; 2],
    /// The two wells and the barrier between them, if the device has two wells.
    pub wells: Option<([f64; 2], f64)>,
}

impl DisplacementBins {
    /// `n` equal bins over `[lo, hi]` for a device.
    pub fn uniform(device: &Device, lo: f64, hi: f64, n: usize) -> Self {
        let gap = |s: &Option<crate::device::Stop>| s.as_ref().map_or(f64::INFINITY, |s| s.gap_m);
        Self {
            edges_m: (0..=n)
                .map(|i| lo + (hi - lo) * i as f64 / n as f64)
                .collect(),
            gaps_m: [gap(&device.stops.upper), gap(&device.stops.lower)],
            wells: two_wells(device),
        }
    }

    fn bin(&self, x: f64) -> Option<usize> {
        let e = &self.edges_m;
        if !(x >= e[0] && x < e[e.len() - 1]) {
            return None;
        }
        // Equal bins in every use here; a search keeps it right for any edges.
        Some(e.partition_point(|&b| b <= x) - 1)
    }
}

/// One record's displacement statistics over its analysed samples.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordDisplacement {
    /// Realisation (noise stream).
    pub stream: u64,
    /// Samples in each bin.
    pub counts: Vec<u64>,
    /// Analysed samples.
    pub samples: u64,
    /// Mean of x^2 over the samples (m^2).
    pub x2_mean_m2: f64,
    /// Mean of v^2 over the samples (m^2/s^2).
    pub v2_mean_m2_s2: f64,
    /// Share of samples past the upper stop (x > gap).
    pub upper_contact_share: f64,
    /// Share of samples past the lower stop (x < -gap).
    pub lower_contact_share: f64,
    /// Share of samples on the upper well's side of the barrier (NaN without two wells).
    pub upper_well_share: f64,
    /// Passages from one well's bottom to the other's (see the module docs).
    pub transitions: u64,
    /// Analysed duration (s).
    pub duration_s: f64,
    /// The record's scalar results (powers, impacts, integrator counters).
    pub summary: RecordSummary,
}

impl RecordDisplacement {
    /// Bottom-to-bottom passages per second.
    pub fn transition_rate_per_s(&self) -> f64 {
        self.transitions as f64 / self.duration_s
    }
}

struct Reader<'a> {
    bins: &'a DisplacementBins,
    counts: Vec<u64>,
    samples: u64,
    sx2: f64,
    sv2: f64,
    upper: u64,
    lower: u64,
    upper_well: u64,
    /// The well whose bottom the mass last reached (0 lower, 1 upper).
    last_well: Option<usize>,
    transitions: u64,
}

impl RecordObserver for Reader<'_> {
    #[inline(always)]
    fn sample(&mut self, y: &[f64], _mode: Mode) {
        let x = y[0];
        if let Some(i) = self.bins.bin(x) {
            self.counts[i] += 1;
        }
        self.samples += 1;
        self.sx2 += x * x;
        self.sv2 += y[1] * y[1];
        self.upper += u64::from(x > self.bins.gaps_m[0]);
        self.lower += u64::from(x < -self.bins.gaps_m[1]);
        if let Some(([lo, hi], barrier)) = self.bins.wells {
            self.upper_well += u64::from(x > barrier);
            let at = if x >= hi {
                Some(1)
            } else if x <= lo {
                Some(0)
            } else {
                None
            };
            if let Some(w) = at {
                if self.last_well.is_some_and(|l| l != w) {
                    self.transitions += 1;
                }
                self.last_well = Some(w);
            }
        }
    }
}

/// One record of `spec` (realisation `stream` of `seed`) on `device`, read into `bins`.
pub fn record_displacement(
    device: &Device,
    spec: &RecordSpec,
    bins: &DisplacementBins,
    seed: u64,
    stream: u64,
) -> Result<RecordDisplacement, RecordError> {
    let mut r = Reader {
        bins,
        counts: vec![0; bins.edges_m.len().saturating_sub(1)],
        samples: 0,
        sx2: 0.0,
        sv2: 0.0,
        upper: 0,
        lower: 0,
        upper_well: 0,
        last_well: None,
        transitions: 0,
    };
    let rec = simulate_observed(device, spec, seed, stream, &mut r)?;
    let n = r.samples.max(1) as f64;
    Ok(RecordDisplacement {
        stream,
        counts: r.counts,
        samples: r.samples,
        x2_mean_m2: r.sx2 / n,
        v2_mean_m2_s2: r.sv2 / n,
        upper_contact_share: r.upper as f64 / n,
        lower_contact_share: r.lower as f64 / n,
        upper_well_share: if bins.wells.is_some() {
            r.upper_well as f64 / n
        } else {
            f64::NAN
        },
        transitions: r.transitions,
        duration_s: r.samples as f64 / spec.noise.sample_rate_hz,
        summary: rec.summary,
    })
}

/// An ensemble's displacement statistics: one [`RecordDisplacement`] per record.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct DisplacementEnsemble {
    /// Bin edges (m).
    pub edges_m: Vec<f64>,
    /// The records.
    pub records: Vec<RecordDisplacement>,
}

/// Runs `records` records (streams `0..records` of `seed`, in parallel) and reads each.
pub fn displacement_ensemble(
    device: &Device,
    spec: &RecordSpec,
    bins: &DisplacementBins,
    seed: u64,
    records: u64,
) -> Result<DisplacementEnsemble, RecordError> {
    let recs = (0..records)
        .into_par_iter()
        .map(|s| record_displacement(device, spec, bins, seed, s))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(DisplacementEnsemble {
        edges_m: bins.edges_m.clone(),
        records: recs,
    })
}

impl DisplacementEnsemble {
    /// Mean over records of one quantity with its 95 % interval.
    pub fn stat(&self, f: impl Fn(&RecordDisplacement) -> f64) -> MeanCi {
        MeanCi::of(&self.records.iter().map(f).collect::<Vec<_>>())
    }

    /// Each record's share of samples per bin (rows: records).
    pub fn shares(&self) -> Vec<Vec<f64>> {
        self.records
            .iter()
            .map(|r| {
                let n = r.samples.max(1) as f64;
                r.counts.iter().map(|&c| c as f64 / n).collect()
            })
            .collect()
    }

    /// The density per bin (1/m), the ensemble mean of the records' densities with its 95 %
    /// interval across records: `(centre_m, density, ci95)`.
    pub fn density(&self) -> Vec<(f64, f64, f64)> {
        let shares = self.shares();
        (0..self.edges_m.len() - 1)
            .map(|i| {
                let w = self.edges_m[i + 1] - self.edges_m[i];
                let ci = MeanCi::of(&shares.iter().map(|s| s[i] / w).collect::<Vec<_>>());
                (
                    0.5 * (self.edges_m[i] + self.edges_m[i + 1]),
                    ci.mean,
                    ci.ci95,
                )
            })
            .collect()
    }

    /// The rate of bottom-to-bottom passages (1/s) with its 95 % interval across records.
    pub fn transition_rate(&self) -> MeanCi {
        self.stat(RecordDisplacement::transition_rate_per_s)
    }

    /// Bottom-to-bottom passages over the ensemble.
    pub fn transitions(&self) -> u64 {
        self.records.iter().map(|r| r.transitions).sum()
    }
}

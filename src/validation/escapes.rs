//! The two counts of a double well's hopping in a random record, each named for what it
//! counts ([`crate::validation::kramers`] holds the theories they are held to):
//!
//! - **barrier passages**: every crossing of the barrier's position between consecutive
//!   samples, whichever way and however soon the mass turns back;
//! - **settled escapes**: a mass is *settled* in a well while its energy `m v^2 / 2 + U(x)` is
//!   within `theta` of that well's bottom ([`SETTLED_WITHIN_THETA`]); an escape is counted when
//!   a mass last settled in one well settles in the other.
//!
//! They differ by the passages that do not end in the other well: near the barrier a mass
//! turns back over it (Kramers' recrossings), and with light damping a mass above the barrier
//! swings over both wells many times before it loses the energy to settle in either.
//!
//! Each record ([`crate::study::record`]) is read at its analysed sample instants; the records
//! of an ensemble are independent realisations, so each count's rate carries its interval
//! across records ([`MeanCi`]).

use rayon::prelude::*;

use crate::device::{Device, Suspension};
use crate::laws::suspension::{potential_j, Polynomial};
use crate::model::Mode;
use crate::num::stats::MeanCi;
use crate::study::record::{simulate_observed, RecordObserver, RecordSpec};
use crate::validation::ValidationError;

/// A mass is settled in a well while its energy is within this many `theta` of the well's
/// bottom: deep in the well (four `theta` below the barrier at `dU / theta = 5`), where
/// nearly every mass relaxes before it could be carried back over the barrier, and where a
/// mass in the well spends most of its time (63 % of it in a harmonic well), so that it
/// settles soon after it arrives.
pub const SETTLED_WITHIN_THETA: f64 = 1.0;

/// One record's counts.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordEscapes {
    /// Realisation (noise stream).
    pub stream: u64,
    /// Crossings of the barrier's position.
    pub passages: u64,
    /// Escapes that settled in the other well.
    pub settled: u64,
    /// Analysed duration (s).
    pub duration_s: f64,
}

struct Counter {
    mass_kg: f64,
    poly: Polynomial,
    barrier_m: f64,
    /// Energy at or below which the mass is settled (J, with `U` of the device).
    settled_j: f64,
    side: Option<bool>,
    settled_in: Option<bool>,
    passages: u64,
    settled: u64,
    samples: u64,
}

impl RecordObserver for Counter {
    #[inline(always)]
    fn sample(&mut self, y: &[f64], _mode: Mode) {
        let (x, v) = (y[0], y[1]);
        let side = x > self.barrier_m;
        if self.side.is_some_and(|s| s != side) {
            self.passages += 1;
        }
        self.side = Some(side);
        let e = 0.5 * self.mass_kg * v * v + potential_j(&self.poly, None, None, x);
        if e <= self.settled_j {
            if self.settled_in.is_some_and(|s| s != side) {
                self.settled += 1;
            }
            self.settled_in = Some(side);
        }
        self.samples += 1;
    }
}

/// An ensemble's counts: one [`RecordEscapes`] per record.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct EscapeEnsemble {
    /// The records.
    pub records: Vec<RecordEscapes>,
}

impl EscapeEnsemble {
    /// Barrier passages per second with their interval across records.
    pub fn passage_rate(&self) -> MeanCi {
        MeanCi::of(
            &self
                .records
                .iter()
                .map(|r| r.passages as f64 / r.duration_s)
                .collect::<Vec<_>>(),
        )
    }

    /// Settled escapes per second with their interval across records.
    pub fn settled_rate(&self) -> MeanCi {
        MeanCi::of(
            &self
                .records
                .iter()
                .map(|r| r.settled as f64 / r.duration_s)
                .collect::<Vec<_>>(),
        )
    }

    /// Barrier passages over the ensemble.
    pub fn passages(&self) -> u64 {
        self.records.iter().map(|r| r.passages).sum()
    }

    /// Settled escapes over the ensemble.
    pub fn settled(&self) -> u64 {
        self.records.iter().map(|r| r.settled).sum()
    }
}

/// The double well of a `bistable` device without stops: well position (m) and barrier (J).
pub fn double_well(device: &Device) -> Result<(f64, f64), ValidationError> {
    match device.mechanics.suspension {
        Suspension::Bistable { well_m, barrier_j } if device.stops.present().next().is_none() => {
            Ok((well_m, barrier_j))
        }
        _ => Err(ValidationError::Device(
            "the escape counts take a `bistable` suspension without stops".into(),
        )),
    }
}

/// Runs `records` records of `spec` (streams `0..records` of `seed`, in parallel) on a
/// double-well `device` and counts each one's passages and settled escapes at the
/// temperature `theta_j` (J) of its stationary law.
pub fn escape_ensemble(
    device: &Device,
    spec: &RecordSpec,
    theta_j: f64,
    seed: u64,
    records: u64,
) -> Result<EscapeEnsemble, ValidationError> {
    let (_, barrier_j) = double_well(device)?;
    let poly = device.restoring_polynomial();
    // U(0) = 0 at the barrier's top, -dU at the wells' bottoms.
    let settled_j = -barrier_j + SETTLED_WITHIN_THETA * theta_j;
    let recs = (0..records)
        .into_par_iter()
        .map(|stream| {
            let mut c = Counter {
                mass_kg: device.mechanics.mass_kg,
                poly,
                barrier_m: 0.0,
                settled_j,
                side: None,
                settled_in: None,
                passages: 0,
                settled: 0,
                samples: 0,
            };
            simulate_observed(device, spec, seed, stream, &mut c)?;
            Ok(RecordEscapes {
                stream,
                passages: c.passages,
                settled: c.settled,
                duration_s: c.samples as f64 / spec.noise.sample_rate_hz,
            })
        })
        .collect::<Result<Vec<_>, ValidationError>>()?;
    Ok(EscapeEnsemble { records: recs })
}

//! The energy balance of a random-vibration record as
//! [`simulate_record`](crate::study::record::simulate_record) integrates it.
//!
//! A record is integrated mostly by fast steps (the exponential Adams-Bashforth step,
//! [`crate::ode::exponential`], or an affine mode's exact step), which advance the state only,
//! so the record keeps its books interval by interval beside it (the record's module docs, "The
//! continuous books"): the power of each of the model's ledger terms
//! ([`crate::model::Model::ledger_terms`]) by 3-point Gauss-Legendre (degree 5) on each
//! scheme's own interpolant (an exponential step's dense output, which continues the step's own
//! formula inside the interval; a Dormand-Prince step's), or exactly by an affine mode's Gram
//! sums, and what each switch moved ([`crate::model::Model::book_switch`]). The residual of the
//! [`Ledger`] then measures the integration of the record and the quadrature. The rule's
//! relative error on a power oscillating at 2f (a motion at f) is about 5e-7 (4πf h)^6: 1e-11
//! at prototype 1's 1.3 kHz resonance sampled every 10 us.
//!
//! The ledger's terms are the model's, by name; the accessors on [`Ledger`] below read the
//! terms of a harvester with its own loads under the names the energy audit gave them
//! (`excitation` for the term `drive`, `internal` for `coil`).

use crate::device::Device;
use crate::model::{Ledger, Mode};
use crate::study::record::{simulate_found, Record, RecordError, RecordObserver, RecordSpec};

/// Asks a record for its books.
struct Booked;

impl RecordObserver for Booked {
    const BOOKS: bool = true;

    #[inline(always)]
    fn sample(&mut self, _y: &[f64], _mode: Mode) {}
}

/// Simulates a record exactly as [`crate::study::record::simulate_record`] does (the same
/// samples) and books its energy balance from rest to the record's end (pre-roll included).
pub fn record_ledger(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<(Record, Ledger), RecordError> {
    let (record, books) = record_ledgers(device, spec, seed, stream)?;
    Ok((record, books.whole))
}

/// The energy balance of a record from rest to its end ([`record_ledger`]'s) and over its
/// analysed window alone, from the first analysed sample instant (the end of the pre-roll) to
/// the last: the window's terms are the whole record's less those booked before the window,
/// and its stored-energy change and source work are counted from the state at the window's
/// start. Over a stationary window the drive's work and the dissipation grow with its length
/// while the stored energy only fluctuates, so the window's mean powers estimate the
/// stationary ones without the ring-up's bias.
#[derive(Debug, Clone, PartialEq)]
pub struct RecordLedgers {
    /// From rest to the record's end (pre-roll included).
    pub whole: Ledger,
    /// Over the analysed window.
    pub analysed: Ledger,
    /// Length of the analysed window (s).
    pub analysed_s: f64,
}

/// Simulates a record exactly as [`crate::study::record::simulate_record`] does and books its
/// energy balance from rest and over its analysed window ([`RecordLedgers`]).
pub fn record_ledgers(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<(Record, RecordLedgers), RecordError> {
    let (record, found) = simulate_found(device, spec, seed, stream, &mut Booked)?;
    let analysed_s = (record.samples.saturating_sub(1)) as f64 / record.sample_rate_hz;
    // The observer asks for the books, so the record kept them.
    let found = found.unwrap_or_default();
    Ok((
        record,
        RecordLedgers {
            whole: found.whole,
            analysed: found.analysed,
            analysed_s,
        },
    ))
}

/// The terms of a harvester's ledger under the names of its energy audit (zero for a term the
/// model does not have; see the module docs).
impl Ledger {
    /// Work of the inertial force (the term `drive`) (J).
    pub fn excitation(&self) -> f64 {
        self.get("drive")
    }

    /// Work of the bias source, Vb times the charge it delivered (J).
    pub fn source(&self) -> f64 {
        self.source_j
    }

    /// Mechanical damper (J).
    pub fn mech_damping(&self) -> f64 {
        self.get("mech_damping")
    }

    /// End-stop damper (J).
    pub fn stop_damping(&self) -> f64 {
        self.get("stop_damping")
    }

    /// Load resistors (J).
    pub fn loads(&self) -> f64 {
        self.get("loads")
    }

    /// Contact spring energy dropped at clips (tension-free contact only) (J).
    pub fn clip_losses(&self) -> f64 {
        self.get("clip_losses")
    }

    /// Contact spring energy restored at re-engagements (tension-free contact only) (J).
    pub fn reengagement_gains(&self) -> f64 {
        self.get("reengagement_gains")
    }

    /// Stored energy removed by the projections at switches (J).
    pub fn projections(&self) -> f64 {
        self.get("projections")
    }

    /// Kinetic energy lost at impacts on rigid stops (J).
    pub fn impact_losses(&self) -> f64 {
        self.get("impact_losses")
    }

    /// Dissipated inside the transducer: a coil's resistance (the term `coil`) (J).
    pub fn internal(&self) -> f64 {
        self.get("coil")
    }

    /// Change of the stored energy (J).
    pub fn stored_change(&self) -> f64 {
        self.stored_change_j
    }

    /// Net energy absorbed by the end stops: their dampers plus the clip losses minus the
    /// re-engagement gains (J).
    pub fn stop_absorbed(&self) -> f64 {
        self.stop_damping() + self.clip_losses() - self.reengagement_gains()
    }
}

//! Records of a device behind an interface circuit: its storage's settling (which a record's
//! pre-roll covers), whether its records have a steady mean, and ensembles of their DC power,
//! drive power, efficiency and storage voltage (see the parent module's continuous books).

use rayon::prelude::*;

use crate::device::{DcLoad, Device};
use crate::model::Ledger;
use crate::num::stats::MeanCi;

use super::{simulate_record, Record, RecordError, RecordSpec, RecordSummary, STORAGE};
use crate::model::Model;

/// Storage time constants a record's pre-roll covers ([`storage_settling_s`]).
pub const STORAGE_SETTLING_TIMES: f64 = 5.0;

/// [`STORAGE_SETTLING_TIMES`] discharge time constants of the storage through its DC load,
/// `R C_s` (s), with a battery's series resistance for `R`: the time over which the storage's
/// mean settles from rest (to `e^-5`, 0.7 %), which a record's pre-roll must cover as well as
/// the mass's ring-up. `None` for an open load (the storage then only charges, with no steady
/// mean) or a device without an interface.
///
/// ```
/// use endstop::device::Device;
/// use endstop::study::record::storage_settling_s;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_bridge.toml"));
/// let device = Device::from_toml_str(text, "piezo_bridge.toml")?;
/// // 41.7 kOhm on 10 uF: five time constants of 0.417 s.
/// assert!((storage_settling_s(&device).unwrap() - 2.085).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn storage_settling_s(device: &Device) -> Option<f64> {
    let cs = device.interface.storage_capacitance_f()?;
    let r = match device.interface.load()? {
        DcLoad::Resistor { resistance_ohm } => *resistance_ohm,
        DcLoad::Battery {
            series_resistance_ohm,
            ..
        } => *series_resistance_ohm,
        DcLoad::Open => return None,
    };
    Some(STORAGE_SETTLING_TIMES * r * cs)
}

/// Whether the model `device` assembles has a storage: an output and state component
/// [`STORAGE`] (false where it does not assemble; its records then fail with the reason).
pub fn has_storage(device: &Device) -> bool {
    let found: Result<bool, crate::physics::harvester::AssemblyError> =
        crate::with_harvester!(device, |h| Ok(h.layout().output(STORAGE).is_some()));
    found.unwrap_or(false)
}

/// Whether the records of `device` have a steady mean to study: an interface circuit whose
/// storage feeds a load ([`RecordError::OpenLoad`] where it feeds nothing and only charges;
/// [`RecordError::NoStorage`] without an interface). Their pre-roll
/// ([`super::transient_s`]) covers the storage's settling.
pub fn check_steady_mean(device: &Device) -> Result<(), RecordError> {
    if !has_storage(device) {
        return Err(RecordError::NoStorage(device.name.clone()));
    }
    storage_settling_s(device)
        .map(|_| ())
        .ok_or_else(|| RecordError::OpenLoad(device.name.clone()))
}

/// One record of a model with a storage, its samples dropped: the means over its analysed
/// window and its ledger there.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct StorageRecord {
    /// The noise stream.
    pub stream: u64,
    /// Mean DC power (W; zero for a storage without a load).
    pub p_dc_w: f64,
    /// Mean power the drive delivered (W).
    pub p_drive_w: f64,
    /// Mean storage voltage (V).
    pub vdc_v: f64,
    /// The energy ledger of the analysed window (J).
    pub ledger: Ledger,
    /// The record's scalar results.
    pub summary: RecordSummary,
}

impl StorageRecord {
    /// The storage record of `record` (realisation `stream`), or `None` when the record kept
    /// no books or its model has no storage output ([`super::STORAGE`]).
    pub fn of(record: Record, stream: u64) -> Option<Self> {
        let s = record.summary;
        Some(Self {
            stream,
            p_dc_w: s.p_dc_w.unwrap_or(0.0),
            p_drive_w: s.p_drive_w?,
            vdc_v: s.vdc_v?,
            ledger: record.ledger?,
            summary: s,
        })
    }

    /// DC power over the drive's power.
    pub fn efficiency(&self) -> f64 {
        self.p_dc_w / self.p_drive_w
    }
}

/// The means over an ensemble's storage records, each with its 95 % interval (Student t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct StorageSummary {
    /// DC power (W).
    pub p_dc_w: MeanCi,
    /// The drive's power (W).
    pub p_drive_w: MeanCi,
    /// Each record's efficiency ([`StorageRecord::efficiency`]).
    pub efficiency: MeanCi,
    /// Storage voltage (V).
    pub vdc_v: MeanCi,
}

impl StorageSummary {
    /// The summary of `records`.
    pub fn of(records: &[StorageRecord]) -> Self {
        let stat =
            |f: fn(&StorageRecord) -> f64| MeanCi::of(&records.iter().map(f).collect::<Vec<_>>());
        Self {
            p_dc_w: stat(|r| r.p_dc_w),
            p_drive_w: stat(|r| r.p_drive_w),
            efficiency: stat(StorageRecord::efficiency),
            vdc_v: stat(|r| r.vdc_v),
        }
    }
}

/// Record `stream` of `seed` of `spec` on a device with a storage, its samples dropped; a
/// device without one is [`RecordError::NoStorage`].
pub fn storage_record(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<StorageRecord, RecordError> {
    let record = simulate_record(device, spec, seed, stream)?;
    StorageRecord::of(record, stream).ok_or_else(|| RecordError::NoStorage(device.name.clone()))
}

/// An ensemble of `records` storage records (streams `0..records` of `seed`), in parallel.
pub fn storage_ensemble(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    records: u64,
) -> Result<Vec<StorageRecord>, RecordError> {
    (0..records)
        .into_par_iter()
        .map(|k| storage_record(device, spec, seed, k))
        .collect()
}

//! Random vibration on any model, through one entry: [`random_ensemble`] runs an ensemble of
//! band-limited white-noise records and [`random_record`] one record of a sampled drive (a
//! measured acceleration or a sine), and each says what the model's outputs make of them.
//!
//! A model whose outputs are its transducer's loads reports the output power spectrum, its
//! power, efficiency and bandwidths ([`Ensemble`]); a model with a storage output
//! ([`STORAGE`](super::record::STORAGE)) reports, record by record, its DC power, the drive's
//! power, their ratio, the storage voltage and the energy ledger ([`StorageRecord`]). The
//! records are the one record engine's either way; which report a model gets is read from
//! its outputs, not from the description of its parts.
//!
//! A storage's records are studied only where they have a steady mean: its DC load draws
//! from it ([`check_steady_mean`]). An open load only charges, and is refused with
//! [`RecordError::OpenLoad`] before any record runs; the pre-roll covers the storage's
//! settling as well as the mass's ring-up ([`super::record::transient_s`]).

use crate::device::Device;
use crate::progress::Progress;
use crate::study::ensemble::{run_ensemble, Ensemble, EnsembleSpec};
use crate::study::record::{
    check_steady_mean, has_storage, simulate_drive, storage_ensemble, Record, RecordError,
    RecordSpec, SampledDrive, Scheme, StorageRecord, DEFAULT_RTOL,
};

/// What an ensemble of random-vibration records reports for a model.
#[derive(Debug, Clone, PartialEq)]
pub enum RandomEnsemble {
    /// A model whose outputs are its transducer's loads: the analysed ensemble.
    Output(Box<Ensemble>),
    /// A model with a storage output: its records in stream order.
    Storage(Vec<StorageRecord>),
}

/// The ensemble of `records` records `record` of `device` (record `i` uses ChaCha8 stream `i`
/// of `seed`), in parallel (see the module docs for what each model reports); `on_record` is
/// called after each record of a model whose outputs are its loads.
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::noise::NoiseSpec;
/// use endstop::progress::Silent;
/// use endstop::study::random::{random_ensemble, RandomEnsemble};
/// use endstop::study::record::RecordSpec;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_bridge.toml"));
/// let device = Device::from_toml_str(text, "piezo_bridge.toml")?;
/// // Two short records (50 ms after a 10 ms pre-roll) at 1e-4 g^2/Hz, seed 2012.
/// let noise = NoiseSpec {
///     psd_g2_per_hz: 1e-4,
///     bandwidth_hz: 2e3,
///     sample_rate_hz: 20e3,
///     duration_s: 0.05,
/// };
/// let mut record = RecordSpec::of(&device, noise);
/// record.transient_s = 0.01;
/// let RandomEnsemble::Storage(records) = random_ensemble(&device, &record, 2012, 2, &Silent)?
/// else {
///     panic!("a bridge into a storage reports its storage");
/// };
/// assert_eq!(records.len(), 2);
/// assert!(records.iter().all(|r| r.p_drive_w > 0.0 && r.p_dc_w >= 0.0));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn random_ensemble(
    device: &Device,
    record: &RecordSpec,
    seed: u64,
    records: usize,
    on_record: &dyn Progress,
) -> Result<RandomEnsemble, RecordError> {
    if !has_storage(device) {
        let spec = EnsembleSpec::for_device(device, *record, seed, records);
        return Ok(RandomEnsemble::Output(Box::new(run_ensemble(
            device, &spec, on_record,
        )?)));
    }
    check_steady_mean(device)?;
    if records == 0 {
        return Err(RecordError::InvalidSpec {
            field: "realisations",
            value: 0.0,
            expected: "at least 1",
        });
    }
    Ok(RandomEnsemble::Storage(storage_ensemble(
        device,
        record,
        seed,
        records as u64,
    )?))
}

/// What one record of a sampled drive reports for a model.
#[derive(Debug, Clone, PartialEq)]
pub enum RandomRecord {
    /// A model whose outputs are its transducer's loads: the record with its samples.
    Output(Box<Record>),
    /// A model with a storage output: the record's means and ledger.
    Storage(Box<StorageRecord>),
}

/// The record of `device` under the sampled drive `drive` (exact propagation of the affine
/// modes, Dormand-Prince elsewhere, at the default tolerance); a storage without a steady
/// mean is refused before it runs (see the module docs).
pub fn random_record(device: &Device, drive: &SampledDrive) -> Result<RandomRecord, RecordError> {
    let storage = has_storage(device);
    if storage {
        check_steady_mean(device)?;
    }
    let record = simulate_drive(device, drive, DEFAULT_RTOL, Scheme::Exponential)?;
    if !storage {
        return Ok(RandomRecord::Output(Box::new(record)));
    }
    StorageRecord::of(record, 0)
        .map(|r| RandomRecord::Storage(Box::new(r)))
        .ok_or_else(|| RecordError::NoStorage(device.name.clone()))
}

//! Random records and ensembles of a device with an interface circuit: the DC power, the drive's
//! power and their ratio (the efficiency), from band-limited noise or a measured record.
//!
//! Each record is integrated by Dormand-Prince with the circuit's events located, over the
//! pre-roll and the analysed part of [`RecordSpec`]; the linear modes between conduction
//! events are not yet propagated by the exponential step of resistive records (the modes are
//! linear, see [`crate::physics::interface`], so that step applies to each; it is not wired
//! in), so a record with an interface costs what the adaptive integrator costs.

use rayon::prelude::*;

use crate::device::Device;
use crate::drive::noise::generate_shared;
use crate::drive::Excitation;
use crate::drive::Sampled;
use crate::ode::{Dopri5, SolverError};
use crate::physics::harvester::State;
use crate::physics::interface::{audit_start, InterfaceAudit, InterfaceLedger, Interfaced};
use crate::study::record::RecordSpec;

use super::InterfaceError;

/// One record's result over its analysed part.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct DcRecord {
    /// Mean DC power (W).
    pub p_dc_w: f64,
    /// Mean power the drive delivered (W).
    pub p_drive_w: f64,
    /// Mean storage voltage (V).
    pub vdc_v: f64,
    /// The energy ledger of the analysed part (J).
    pub ledger: InterfaceLedger,
    /// Accepted steps.
    pub steps: u64,
}

impl DcRecord {
    /// DC power over the drive's power.
    pub fn efficiency(&self) -> f64 {
        self.p_dc_w / self.p_drive_w
    }
}

/// Runs a device with an interface under any drive from rest: `transient_s` discarded, then
/// `duration_s` analysed.
pub fn dc_record<E: Excitation + Clone>(
    device: &Device,
    drive: E,
    transient_s: f64,
    duration_s: f64,
    rtol: f64,
) -> Result<DcRecord, InterfaceError> {
    let model = Interfaced::new(device, drive)
        .ok_or_else(|| InterfaceError::Resistive(device.name.clone()))?;
    super::check_stiffness(device, &model)?;
    let audit = InterfaceAudit(model.clone());
    let y0 = State::zeros();
    let z0 = audit_start(&y0);
    let mut ode = Dopri5::new(0.0, z0, model.mode_of(&y0), audit.solver_options(rtol));
    ode.integrate(&audit, transient_s, |_, _| {})?;
    let (za, ma) = (ode.y(), ode.mode());
    let mut vs = 0.0;
    ode.integrate(&audit, transient_s + duration_s, |st, _| {
        vs += st.integrate(|z| z[3]);
    })
    .map_err(|e: SolverError| InterfaceError::Solver(e))?;
    let ledger = audit.ledger(ma, &za, ode.mode(), &ode.y());
    Ok(DcRecord {
        p_dc_w: ledger.dc_load / duration_s,
        p_drive_w: ledger.excitation / duration_s,
        vdc_v: vs / duration_s,
        ledger,
        steps: ode.stats().accepted,
    })
}

/// One noise record of `spec` (seed, stream) through the interface.
pub fn noise_record(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    stream: u64,
) -> Result<DcRecord, InterfaceError> {
    let noise = spec.generated_noise();
    let samples =
        generate_shared(&noise, seed, stream).map_err(|e| InterfaceError::Drive(e.to_string()))?;
    let drive = Sampled::new(samples, noise.sample_rate_hz);
    let t0 = spec.transient_samples() as f64 / noise.sample_rate_hz;
    let t1 = spec.analysed_samples() as f64 / noise.sample_rate_hz;
    dc_record(device, drive, t0, t1, spec.rtol)
}

/// An ensemble of `records` noise records (streams 0..records), in parallel.
pub fn noise_ensemble(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    records: u64,
) -> Result<Vec<DcRecord>, InterfaceError> {
    (0..records)
        .into_par_iter()
        .map(|k| noise_record(device, spec, seed, k))
        .collect()
}

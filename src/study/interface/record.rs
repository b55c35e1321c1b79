//! Random records and ensembles of a device with an interface circuit: the DC power, the drive's
//! power and their ratio (the efficiency), from band-limited noise or a measured record.
//!
//! # How a sampled record is integrated
//! A record of a sampled drive ([`sampled_record`], [`noise_record`]) honours its
//! [`RecordSpec::scheme`]:
//!
//! * [`Scheme::Exponential`]: each sample interval is advanced **exactly** in the current mode
//!   when that mode is linear (`linear_modes.rs` beside this file: the interval's propagator
//!   of the state augmented with the linearly interpolated drive, once per mode and sample
//!   rate), and the energy ledger and the mean storage voltage are summed exactly over it (its
//!   Gram sums).
//!   An interval in which a guard may fire (bridge conduction starting or stopping, a
//!   velocity zero of SSHI or SECE, a contact: the cubic Hermite estimate of a guard, from its
//!   exact values and rates at both ends, comes within
//!   [`GRAZE_MARGIN`](crate::study::flow::GRAZE_MARGIN) of zero, and so does the estimate on
//!   one of eight parts of the interval, from the exact values there, within the margin's
//!   4096th) is handed to [`Dopri5`] with its event location, as the resistive record hands
//!   its contacts over: the events are located on Dormand-Prince's dense output, not on the
//!   exact solution, which is simpler and meets the cost the exact steps aim at (under 1 % of
//!   the example bridge's intervals go to Dormand-Prince, `tests/interface_records.rs`). So is every interval of a
//!   mode that is not linear (a Hertz or Hunt-Crossley contact, a mass stuck on a rigid stop),
//!   and a device without linear modes (a nonlinear suspension, Shockley diodes, which have
//!   no modes) runs [`dc_record`] throughout.
//! * [`Scheme::Dopri5`]: [`dc_record`], [`Dopri5`] throughout, the reference the exact path
//!   is checked against.
//!
//! [`dc_record`] runs any excitation (not only a sampled one) by [`Dopri5`] with the circuit's
//! events located, over the pre-roll and the analysed part.

use rayon::prelude::*;

use crate::device::{DcLoad, Device};
use crate::drive::noise::generate_shared;
use crate::drive::Excitation;
use crate::drive::Sampled;
use crate::num::stats::MeanCi;
use crate::ode::{Dopri5, SolverError};
use crate::physics::harvester::State;
use crate::physics::interface::{audit_start, InterfaceAudit, InterfaceLedger, Interfaced};
use crate::study::record::{RecordSpec, Scheme};

use super::linear_modes::{has_linear_modes, LinearMode, LinearModes, INTEGRALS};
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
    /// Accepted steps, an exact step over a sample interval counting as one.
    pub steps: u64,
    /// Sample intervals advanced exactly in a linear mode (the rest went to [`Dopri5`]).
    pub exact_steps: u64,
}

impl DcRecord {
    /// DC power over the drive's power.
    pub fn efficiency(&self) -> f64 {
        self.p_dc_w / self.p_drive_w
    }
}

/// The means over an ensemble's records, each with its 95 % interval (Student t).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DcSummary {
    /// DC power (W).
    pub p_dc_w: MeanCi,
    /// The drive's power (W).
    pub p_drive_w: MeanCi,
    /// Each record's efficiency ([`DcRecord::efficiency`]).
    pub efficiency: MeanCi,
    /// Storage voltage (V).
    pub vdc_v: MeanCi,
}

impl DcSummary {
    /// The summary of `records`.
    pub fn of(records: &[DcRecord]) -> Self {
        let stat = |f: fn(&DcRecord) -> f64| MeanCi::of(&records.iter().map(f).collect::<Vec<_>>());
        Self {
            p_dc_w: stat(|r| r.p_dc_w),
            p_drive_w: stat(|r| r.p_drive_w),
            efficiency: stat(DcRecord::efficiency),
            vdc_v: stat(|r| r.vdc_v),
        }
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
        exact_steps: 0,
    })
}

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
/// use endstop::study::interface::record::storage_settling_s;
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

/// Whether the records of `device` have a steady mean to study: an interface circuit whose
/// storage feeds a load ([`InterfaceError::OpenLoad`] where it feeds nothing and only charges;
/// [`InterfaceError::Resistive`] without an interface). Their pre-roll
/// ([`crate::study::record::transient_s`]) covers the storage's settling.
pub fn check_steady_mean(device: &Device) -> Result<(), InterfaceError> {
    if device.interface.is_resistive() {
        return Err(InterfaceError::Resistive(device.name.clone()));
    }
    storage_settling_s(device)
        .map(|_| ())
        .ok_or_else(|| InterfaceError::OpenLoad(device.name.clone()))
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
    sampled_record(
        device,
        &drive,
        spec.transient_samples(),
        spec.rtol,
        spec.scheme,
    )
}

/// A device with an interface under a sampled drive from rest: the first `transient_samples`
/// intervals discarded, the rest analysed up to one interval past the last sample (over
/// which the last sample holds), by `scheme` (see the module docs).
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::Sampled;
/// use endstop::study::interface::record::sampled_record;
/// use endstop::study::record::{Scheme, DEFAULT_RTOL};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_bridge.toml"));
/// let device = Device::from_toml_str(text, "piezo_bridge.toml")?;
/// // 50 ms of a 120 Hz sine of 5 m/s^2 sampled at 100 kHz; the first 20 ms discarded.
/// let fs = 100e3;
/// let samples: Vec<f64> = (0..5000)
///     .map(|k| 5.0 * (2.0 * std::f64::consts::PI * 120.0 * k as f64 / fs).sin())
///     .collect();
/// let drive = Sampled::new(samples.into(), fs);
/// let exact = sampled_record(&device, &drive, 2000, DEFAULT_RTOL, Scheme::Exponential)?;
/// let dopri = sampled_record(&device, &drive, 2000, DEFAULT_RTOL, Scheme::Dopri5)?;
/// assert!(exact.exact_steps > 4000);
/// assert!((exact.p_drive_w - dopri.p_drive_w).abs() < 1e-6 * dopri.p_drive_w.abs());
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn sampled_record(
    device: &Device,
    drive: &Sampled,
    transient_samples: usize,
    rtol: f64,
    scheme: Scheme,
) -> Result<DcRecord, InterfaceError> {
    let n = drive.samples.len();
    let t0 = drive.time_of(transient_samples);
    let t1 = drive.time_of(n.saturating_sub(transient_samples));
    let model = Interfaced::new(device, drive.clone())
        .ok_or_else(|| InterfaceError::Resistive(device.name.clone()))?;
    if scheme == Scheme::Dopri5 || !has_linear_modes(&model) {
        return dc_record(device, drive.clone(), t0, t1, rtol);
    }
    super::check_stiffness(device, &model)?;
    let audit = InterfaceAudit(model.clone());
    let dt = drive.dt_s;
    let accel = |k: usize| drive.samples[k.min(n - 1)];
    let y0 = State::zeros();
    let mut z = audit_start(&y0);
    let (mut y, mut mode) = (y0, model.mode_of(&y0));
    let mut ode = Dopri5::new(0.0, z, mode, audit.solver_options(rtol));
    // Whether `ode` holds the current state (after a Dormand-Prince interval).
    let mut ode_current = true;
    let mut modes = LinearModes::new(&audit, dt);
    // The current mode's index and its guards at the current sample, once known.
    let mut current = (mode, modes.index(mode), None);
    let mut start = (mode, z);
    let (mut vs_dopri, mut exact_steps) = (0.0, 0u64);
    for k in 1..=n {
        let analysed = k > transient_samples;
        if k - 1 == transient_samples {
            z.fixed_rows_mut::<4>(0).copy_from(&y);
            start = (mode, z);
        }
        let (a0, a1) = (accel(k - 1), accel(k));
        if current.0 != mode {
            current = (mode, modes.index(mode), None);
        }
        let (linear, gram) = modes.get(current.1);
        if let Some(lm) = linear {
            let u0 = LinearMode::augment(&y, a0, (a1 - a0) / dt);
            let g0 = current.2.unwrap_or_else(|| lm.guards_at(&u0));
            if let Some((y1, g1)) = lm.step(&u0, &g0) {
                if analysed {
                    gram.add(&u0);
                }
                y = y1;
                current.2 = Some(g1);
                ode_current = false;
                exact_steps += 1;
                continue;
            }
        }
        if !ode_current {
            z.fixed_rows_mut::<4>(0).copy_from(&y);
            ode.restart_with_step(drive.time_of(k - 1), z, mode, dt);
            ode_current = true;
        }
        ode.integrate(&audit, drive.time_of(k), |st, _| {
            if analysed {
                vs_dopri += st.integrate(|z| z[3]);
            }
        })?;
        z = ode.y();
        (y, mode) = (State::new(z[0], z[1], z[2], z[3]), ode.mode());
        current.2 = None;
    }
    // The exact intervals' integrals join the Dormand-Prince ones in the accumulators.
    let exact: [f64; INTEGRALS] = modes.integrals();
    let mut end = z;
    end.fixed_rows_mut::<4>(0).copy_from(&y);
    for (i, v) in exact.iter().take(INTEGRALS - 1).enumerate() {
        end[4 + i] += v;
    }
    let ledger = audit.ledger(start.0, &start.1, mode, &end);
    Ok(DcRecord {
        p_dc_w: ledger.dc_load / t1,
        p_drive_w: ledger.excitation / t1,
        vdc_v: (vs_dopri + exact[INTEGRALS - 1]) / t1,
        ledger,
        steps: ode.stats().accepted + exact_steps,
        exact_steps,
    })
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

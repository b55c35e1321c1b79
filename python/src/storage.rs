//! The studies of a model with a storage output (a device behind an interface circuit: a
//! bridge, SSHI or SECE into a storage capacitor): the charging of the storage
//! (`endstop.study.charge`), and the report of an ensemble of noise records on such a model,
//! which `endstop.study.ensemble` gives for it as the `endstop random` command does. Each runs
//! with the GIL released.

use endstop::drive::Sine;
use endstop::progress::Silent;
use endstop::study::charging::{charge, ChargeSettings};
use endstop::study::record::{StorageRecord, StorageSummary};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{arg_err, array, solver_err, PyDevice};

fn positive(name: &str, v: f64) -> PyResult<()> {
    if v.is_finite() && v > 0.0 {
        Ok(())
    } else {
        Err(arg_err(format!(
            "{name} must be a finite positive number, not {v}"
        )))
    }
}

/// Charges the storage of a device (a model with a storage output) from `start_v` to
/// `target_v` under a sine at `freq_hz`, `accel_rms_g`, from rest at phase zero, ramped up over
/// `ramp_periods` periods (0: at once): the library's `charging::charge`, with the
/// `endstop charge` command's settings (blocks of 200 periods, samples every
/// `max(t_max_s / 20000, period / 8)`). Keys: `time_to_target_s`, `stored_j`, arrays `t_s` and
/// `vs_v`. A target out of reach raises `SolverError`.
#[pyfunction]
#[pyo3(signature = (device, freq_hz, accel_rms_g, target_v, start_v = 0.0, ramp_periods = 0.0, t_max_s = 600.0))]
#[allow(clippy::too_many_arguments)]
fn charge_storage<'py>(
    py: Python<'py>,
    device: &PyDevice,
    freq_hz: f64,
    accel_rms_g: f64,
    target_v: f64,
    start_v: f64,
    ramp_periods: f64,
    t_max_s: f64,
) -> PyResult<Bound<'py, PyDict>> {
    for (n, v) in [
        ("freq_hz", freq_hz),
        ("accel_rms_g", accel_rms_g),
        ("target_v", target_v),
        ("t_max_s", t_max_s),
    ] {
        positive(n, v)?;
    }
    if !(start_v.is_finite() && start_v >= 0.0 && ramp_periods.is_finite() && ramp_periods >= 0.0) {
        return Err(arg_err("start_v and ramp_periods must be finite and >= 0"));
    }
    let period = 1.0 / freq_hz;
    let settings = ChargeSettings {
        start_v,
        target_v,
        ramp_s: ramp_periods * period,
        t_max_s,
        sample_s: (t_max_s / 20_000.0).max(period / 8.0),
        block_s: (200.0 * period).min(t_max_s / 10.0),
        rtol: 1e-8,
    };
    let dev = device.inner.clone();
    let run = py
        .detach(move || {
            charge(
                &dev,
                Sine::from_rms_g(accel_rms_g, freq_hz),
                &settings,
                &Silent,
            )
        })
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    d.set_item("time_to_target_s", run.time_to_target_s)?;
    d.set_item("stored_j", run.stored_j)?;
    d.set_item("t_s", array(py, run.t_s))?;
    d.set_item("vs_v", array(py, run.vs_v))?;
    Ok(d)
}

/// The report of an ensemble of storage records (pre-roll `preroll_s`), summarised over the
/// records (the library's `StorageSummary`), as the `endstop random` command reports such a
/// model. Keys: `p_dc_w`, `p_dc_ci95_w`, `p_drive_w`, `efficiency`, `efficiency_ci95`,
/// `vdc_v`, `preroll_s`, and per-record arrays `p_dc_w_each`, `p_drive_w_each`, `vdc_v_each`,
/// `ledger_relative_residual_each`. (An open DC load, with no steady mean, is refused by the
/// library before the records run, as `SolverError`.)
pub(crate) fn storage_ensemble_dict<'py>(
    py: Python<'py>,
    ens: &[StorageRecord],
    preroll_s: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let each = |f: fn(&StorageRecord) -> f64| ens.iter().map(f).collect::<Vec<f64>>();
    let sum = StorageSummary::of(ens);
    let d = PyDict::new(py);
    d.set_item("p_dc_w", sum.p_dc_w.mean)?;
    d.set_item("p_dc_ci95_w", sum.p_dc_w.ci95)?;
    d.set_item("p_drive_w", sum.p_drive_w.mean)?;
    d.set_item("efficiency", sum.efficiency.mean)?;
    d.set_item("efficiency_ci95", sum.efficiency.ci95)?;
    d.set_item("vdc_v", sum.vdc_v.mean)?;
    d.set_item("preroll_s", preroll_s)?;
    d.set_item("p_dc_w_each", array(py, each(|r| r.p_dc_w)))?;
    d.set_item("p_drive_w_each", array(py, each(|r| r.p_drive_w)))?;
    d.set_item("vdc_v_each", array(py, each(|r| r.vdc_v)))?;
    d.set_item(
        "ledger_relative_residual_each",
        array(py, each(|r| r.ledger.relative_residual())),
    )?;
    Ok(d)
}

/// Adds the module's functions to `_native`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(charge_storage, m)?)
}

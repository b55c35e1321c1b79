//! `endstop.study` for a model with a storage output (a device behind an interface circuit: a
//! bridge, SSHI or SECE into a storage capacitor), each function one path through the library's
//! studies written over any model: the periodic steady states by shooting at each frequency,
//! the steady state continued in frequency through folds with its stability, the charging of
//! the storage, and the storage ensemble of noise records. Each returns a dict of numbers and
//! numpy arrays with the GIL released while it runs.

use endstop::drive::Sine;
use endstop::paper::setups::paper_record;
use endstop::progress::Silent;
use endstop::study::charging::{charge, ChargeSettings};
use endstop::study::continuation::{frequency_branch, EventKind};
use endstop::study::orbit::Orbit;
use endstop::study::periodic::{frequency_sweep, PeriodicState, SteadySettings};
use endstop::study::record::{check_steady_mean, storage_ensemble, StorageRecord, StorageSummary};
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

/// The periodic orbit of a device continued in frequency from `start_hz` to `stop_hz` through
/// folds (the library's generic pseudo-arclength continuation, `frequency_branch`: from the
/// orbit reached from rest at `start_hz`, parameter steps of at most `max_step_hz`). Keys:
/// per-point arrays `freq_hz`, `vdc_v` (the mean of the model's first output over the period:
/// behind a circuit, the storage voltage), `p_dc_w` (the mean power of the loads on the
/// outputs: behind a circuit, the DC load's), `x_peak_m` (largest |x|), `multiplier_max_abs`,
/// the lists `stable` and `method` (every point is a Newton solution of the bordered period
/// map, so "newton"); `folds_hz` and `end` ("reached" when the branch passes `stop_hz`,
/// "turned back past the start at <f> Hz" when it returns past `start_hz` after a fold; a
/// branch that stalls or runs out of points raises `SolverError` naming the last frequency
/// reached).
#[pyfunction]
#[pyo3(signature = (device, accel_rms_g, start_hz, stop_hz, max_step_hz = 0.5))]
fn interface_response<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    max_step_hz: f64,
) -> PyResult<Bound<'py, PyDict>> {
    for (n, v) in [
        ("accel_rms_g", accel_rms_g),
        ("start_hz", start_hz),
        ("stop_hz", stop_hz),
        ("max_step_hz", max_step_hz),
    ] {
        positive(n, v)?;
    }
    let dev = device.inner.clone();
    let branch = py
        .detach(move || {
            frequency_branch(&dev, accel_rms_g, start_hz, stop_hz, max_step_hz, &Silent)
        })
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    let col =
        |f: &dyn Fn(&Orbit) -> f64| array(py, branch.points.iter().map(|p| f(&p.orbit)).collect());
    d.set_item("freq_hz", col(&|o| o.forcing.freq_hz))?;
    d.set_item(
        "vdc_v",
        col(&|o| o.summary.outputs.first().map_or(f64::NAN, |s| s.mean)),
    )?;
    d.set_item("p_dc_w", col(&|o| o.summary.p_total_w))?;
    d.set_item("x_peak_m", col(&|o| o.summary.x_max_m))?;
    d.set_item("multiplier_max_abs", col(&|o| o.max_multiplier_abs()))?;
    d.set_item("method", vec!["newton"; branch.points.len()])?;
    d.set_item(
        "stable",
        branch
            .points
            .iter()
            .map(|p| p.orbit.is_stable())
            .collect::<Vec<bool>>(),
    )?;
    d.set_item(
        "folds_hz",
        branch
            .events_of(EventKind::Fold)
            .map(|e| e.param)
            .collect::<Vec<f64>>(),
    )?;
    // The branch ends at its first point past `stop_hz`, or at its first point back past
    // `start_hz` (a branch that turns at a fold and runs out below its start).
    let last_hz = branch
        .points
        .last()
        .map_or(start_hz, |p| p.orbit.forcing.freq_hz);
    let reached = (last_hz - stop_hz) * (stop_hz - start_hz) >= 0.0;
    d.set_item(
        "end",
        if reached {
            "reached".to_string()
        } else {
            format!("turned back past the start at {last_hz} Hz")
        },
    )?;
    Ok(d)
}

/// The periodic steady state of a device at each frequency of `freqs_hz` in order (an up- or
/// down-sweep as given), found by shooting on the period map from the previous one's state (the
/// first from rest): the library's `periodic::frequency_sweep`. Keys: per-point arrays
/// `freq_hz`, `vdc_v` (the mean of the model's first output: behind a circuit, the storage
/// voltage), `p_dc_w` (the mean power of the loads on the outputs: behind a circuit, the DC
/// load's), `ripple_v` (the first output's peak-to-peak), `x_peak_m`, `multiplier_max_abs`
/// (NaN where no period-one steady state was found), the lists `stable`, `method` ("newton",
/// "period map", or the error where none was found) and `found`.
#[pyfunction]
fn interface_sweep<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    freqs_hz: Vec<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    positive("accel_rms_g", accel_rms_g)?;
    if freqs_hz.is_empty() {
        return Err(arg_err("freqs_hz must hold at least one frequency"));
    }
    for &f in &freqs_hz {
        positive("every frequency of freqs_hz", f)?;
    }
    let dev = device.inner.clone();
    let fs = freqs_hz.clone();
    let results = py
        .detach(move || {
            frequency_sweep(&dev, &fs, accel_rms_g, &SteadySettings::default(), &Silent)
        })
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&PeriodicState) -> f64| {
        array(
            py,
            results
                .iter()
                .map(|r| r.as_ref().map_or(f64::NAN, f))
                .collect(),
        )
    };
    d.set_item("freq_hz", array(py, freqs_hz))?;
    d.set_item("vdc_v", col(&|s| s.vdc_v))?;
    d.set_item("p_dc_w", col(&|s| s.p_dc_w))?;
    d.set_item("ripple_v", col(&|s| s.ripple_v))?;
    d.set_item("x_peak_m", col(&|s| s.x_peak_m))?;
    d.set_item("multiplier_max_abs", col(&|s| s.max_multiplier))?;
    d.set_item(
        "stable",
        results
            .iter()
            .map(|r| r.as_ref().is_ok_and(PeriodicState::is_stable))
            .collect::<Vec<bool>>(),
    )?;
    d.set_item(
        "method",
        results
            .iter()
            .map(|r| match r {
                Ok(s) => s.method.label().to_string(),
                Err(e) => e.to_string(),
            })
            .collect::<Vec<String>>(),
    )?;
    d.set_item(
        "found",
        results.iter().map(Result::is_ok).collect::<Vec<bool>>(),
    )?;
    Ok(d)
}

/// Charges the storage of a device (a model with a storage output) from `start_v` to `target_v` under a
/// sine at `freq_hz`, `accel_rms_g`, from rest at phase zero, ramped up over `ramp_periods`
/// periods (0: at once): the library's `charging::charge`, with the `endstop charge` command's
/// settings (blocks of
/// 200 periods, samples every `max(t_max_s / 20000, period / 8)`). Keys: `time_to_target_s`,
/// `stored_j`, arrays `t_s` and `vs_v`. A target out of reach raises `SolverError`.
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

/// An ensemble of band-limited white-noise records (record i uses stream i of `seed`) of a model
/// with a storage output, summarised over the records: the library's `storage_ensemble` and
/// `StorageSummary`, as the `endstop random` command calls them on such a model (its noise, and
/// its pre-roll: the longer of five ring-up times and five storage time constants `R C_s`).
/// Keys: `p_dc_w`, `p_dc_ci95_w`, `p_drive_w`, `efficiency`, `efficiency_ci95`, `vdc_v`,
/// `preroll_s`, and per-record arrays `p_dc_w_each`, `p_drive_w_each`, `vdc_v_each`,
/// `ledger_relative_residual_each`. An open DC load (no steady mean) raises `SolverError`.
#[pyfunction]
#[pyo3(signature = (device, psd_g2_per_hz, records = 4, duration_s = 10.0, seed = 2012))]
fn interface_ensemble<'py>(
    py: Python<'py>,
    device: &PyDevice,
    psd_g2_per_hz: f64,
    records: u64,
    duration_s: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    positive("psd_g2_per_hz", psd_g2_per_hz)?;
    positive("duration_s", duration_s)?;
    if records == 0 {
        return Err(arg_err("records must be at least 1"));
    }
    let dev = device.inner.clone();
    check_steady_mean(&dev).map_err(solver_err)?;
    let mut spec = paper_record(&dev, psd_g2_per_hz);
    spec.noise.duration_s = duration_s;
    let ens = py
        .detach(move || storage_ensemble(&dev, &spec, seed, records))
        .map_err(solver_err)?;
    let each = |f: fn(&StorageRecord) -> f64| ens.iter().map(f).collect::<Vec<f64>>();
    let sum = StorageSummary::of(&ens);
    let d = PyDict::new(py);
    d.set_item("p_dc_w", sum.p_dc_w.mean)?;
    d.set_item("p_dc_ci95_w", sum.p_dc_w.ci95)?;
    d.set_item("p_drive_w", sum.p_drive_w.mean)?;
    d.set_item("efficiency", sum.efficiency.mean)?;
    d.set_item("efficiency_ci95", sum.efficiency.ci95)?;
    d.set_item("vdc_v", sum.vdc_v.mean)?;
    d.set_item("preroll_s", spec.transient_s)?;
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
    m.add_function(wrap_pyfunction!(interface_response, m)?)?;
    m.add_function(wrap_pyfunction!(interface_sweep, m)?)?;
    m.add_function(wrap_pyfunction!(charge_storage, m)?)?;
    m.add_function(wrap_pyfunction!(interface_ensemble, m)?)?;
    Ok(())
}

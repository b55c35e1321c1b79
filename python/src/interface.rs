//! `endstop.study` for a device with an interface circuit (a bridge, SSHI or SECE into a
//! storage capacitor): the steady state's DC voltage and power continued in frequency through
//! folds with its stability, and the charging of the storage. Each returns a dict of numbers
//! and numpy arrays with the GIL released while it runs.

use endstop::drive::Sine;
use endstop::paper::setups::paper_record;
use endstop::progress::Silent;
use endstop::study::interface::charging::{charge, ChargeSettings};
use endstop::study::interface::continuation::{
    continue_frequency, IfBranchEnd, IfContinuationSettings,
};
use endstop::study::interface::record::{check_steady_mean, noise_ensemble, DcRecord, DcSummary};
use endstop::study::interface::sweep::frequency_sweep;
use endstop::study::interface::{IfSteady, SteadySettings};
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

/// The steady state of a device with an interface continued in frequency from `start_hz` to
/// `stop_hz` through folds (the library's `continue_frequency`, steps of at most
/// `max_step_hz`). Keys: per-point arrays `freq_hz`, `vdc_v`, `p_dc_w`, `x_peak_m`,
/// `multiplier_max_abs`, the lists `stable` and `method` (how each steady state was found:
/// "newton" or "period map"); `folds_hz` and `end` ("reached", "stalled at <f> Hz" or "max
/// points").
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
    let mut set = IfContinuationSettings::new(start_hz, stop_hz, accel_rms_g);
    set.max_freq_step_hz = max_step_hz;
    set.ds_max = max_step_hz / set.freq_scale_hz;
    let dev = device.inner.clone();
    let branch = py
        .detach(move || continue_frequency(&dev, &set, &Silent))
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&endstop::study::interface::IfSteady) -> f64| {
        array(py, branch.points.iter().map(|p| f(&p.steady)).collect())
    };
    d.set_item("freq_hz", col(&|s| s.freq_hz))?;
    d.set_item("vdc_v", col(&|s| s.vdc_v))?;
    d.set_item("p_dc_w", col(&|s| s.p_dc_w))?;
    d.set_item("x_peak_m", col(&|s| s.x_peak_m))?;
    d.set_item("multiplier_max_abs", col(&|s| s.max_multiplier))?;
    d.set_item(
        "method",
        branch
            .points
            .iter()
            .map(|p| p.steady.method.label())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "stable",
        branch
            .points
            .iter()
            .map(|p| p.is_stable())
            .collect::<Vec<bool>>(),
    )?;
    d.set_item(
        "folds_hz",
        branch.folds.iter().map(|f| f.0).collect::<Vec<f64>>(),
    )?;
    d.set_item(
        "end",
        match branch.end {
            IfBranchEnd::Reached => "reached".to_string(),
            IfBranchEnd::Stalled(f) => format!("stalled at {f} Hz"),
            IfBranchEnd::MaxPoints => "max points".to_string(),
        },
    )?;
    Ok(d)
}

/// The steady state of a device with an interface at each frequency of `freqs_hz` in order
/// (an up- or down-sweep as given), each shot from the previous one's (the first from rest):
/// the `endstop sweep` command's study on such a device. Keys: per-point arrays `freq_hz`,
/// `vdc_v`, `p_dc_w`, `ripple_v`, `x_peak_m`, `multiplier_max_abs` (NaN where no period-one
/// steady state was found), the lists `stable`, `method` ("newton", "period map", or the
/// error where none was found) and `found`.
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
    let results = py.detach(move || {
        frequency_sweep(&dev, &fs, accel_rms_g, &SteadySettings::default(), &Silent)
    });
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&IfSteady) -> f64| {
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
            .map(|r| r.as_ref().is_ok_and(IfSteady::is_stable))
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

/// Charges the storage of a device with an interface from `start_v` to `target_v` under a
/// sine at `freq_hz`, `accel_rms_g`, from rest at phase zero, ramped up over `ramp_periods`
/// periods (0: at once): the `endstop charge` command's study with its settings (blocks of
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

/// An ensemble of band-limited white-noise records (record i uses stream i of `seed`) through
/// the interface: the `endstop random` command's study on such a device (its noise, and its
/// pre-roll: the longer of five ring-up times and five storage time constants `R C_s`).
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
        .detach(move || noise_ensemble(&dev, &spec, seed, records))
        .map_err(solver_err)?;
    let each = |f: fn(&DcRecord) -> f64| ens.iter().map(f).collect::<Vec<f64>>();
    let sum = DcSummary::of(&ens);
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

//! `endstop.fit`: the general fit of a device to measured sweeps ([`endstop::fit`]), the twin
//! of the `endstop fit` command. The data sets come as dicts (built by
//! `endstop.fit.sweep_data` in Python), the result as a dict with the GIL released while the
//! fit runs.

use endstop::device::ParamRange;
use endstop::fit::{
    self, Direction, Feature, FeatureKind, FitError, FitReport, FitSettings, Point, Quantity,
    SweepData,
};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{arg_err, array, param_err, solver_err, PyDevice};

fn fit_err(e: FitError) -> PyErr {
    match e {
        // The library's error names the field (`ParamError.field`).
        FitError::Param { error, .. } => param_err(error),
        FitError::Model(e) => solver_err(e),
        other => arg_err(other.to_string()),
    }
}

fn item<'py>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<Bound<'py, PyAny>> {
    d.get_item(key)?
        .ok_or_else(|| arg_err(format!("sweep dict: missing key `{key}`")))
}

fn optional<'py>(d: &Bound<'py, PyDict>, key: &str) -> PyResult<Option<Bound<'py, PyAny>>> {
    Ok(d.get_item(key)?.filter(|v| !v.is_none()))
}

/// A data set from its dict (the keys of `endstop.fit.sweep_data`).
fn sweep_from_dict(d: &Bound<'_, PyDict>) -> PyResult<SweepData> {
    let label: String = item(d, "label")?.extract()?;
    let direction = match item(d, "direction")?.extract::<String>()?.as_str() {
        "up" => Direction::Up,
        "down" => Direction::Down,
        other => return Err(arg_err(format!("{label}: direction `{other}`: up or down"))),
    };
    let quantity = match item(d, "quantity")?.extract::<String>()?.as_str() {
        "v1_rms_v" => Quantity::V1RmsV,
        "p_total_w" => Quantity::PTotalW,
        other => {
            return Err(arg_err(format!(
                "{label}: quantity `{other}`: v1_rms_v or p_total_w"
            )))
        }
    };
    let freqs: Vec<f64> = item(d, "freq_hz")?.extract()?;
    let values: Vec<f64> = item(d, "value")?.extract()?;
    let sigma: Option<Vec<f64>> = optional(d, "sigma")?.map(|s| s.extract()).transpose()?;
    if values.len() != freqs.len() || sigma.as_ref().is_some_and(|s| s.len() != freqs.len()) {
        return Err(arg_err(format!(
            "{label}: freq_hz, value and sigma must have the same length"
        )));
    }
    let points = freqs
        .iter()
        .zip(&values)
        .enumerate()
        .map(|(i, (&f, &v))| Point {
            freq_hz: f,
            value: v,
            sigma: sigma.as_ref().map(|s| s[i]),
        })
        .collect();
    let mut features = Vec::new();
    for (kind, key) in [
        (FeatureKind::Onset, "onset"),
        (FeatureKind::BranchEnd, "jump"),
    ] {
        if let Some(v) = optional(d, key)? {
            let (freq_hz, sigma_hz): (f64, f64) = v.extract()?;
            features.push(Feature {
                kind,
                freq_hz,
                sigma_hz,
            });
        }
    }
    Ok(SweepData {
        label,
        direction,
        accel_rms_g: item(d, "accel_rms_g")?.extract()?,
        quantity,
        points,
        grid_hz: optional(d, "grid_hz")?.map(|g| g.extract()).transpose()?,
        features,
    })
}

fn report_dict<'py>(py: Python<'py>, r: &FitReport) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let params = PyList::empty(py);
    for p in &r.params {
        let q = PyDict::new(py);
        q.set_item("path", &p.path)?;
        q.set_item("start", p.start)?;
        q.set_item("value", p.value)?;
        q.set_item("std_err", p.std_err)?;
        q.set_item("interval", p.interval)?;
        q.set_item("range", p.range)?;
        params.append(q)?;
    }
    d.set_item("params", params)?;
    d.set_item("correlation", r.correlation.clone())?;
    d.set_item(
        "warnings",
        r.warnings.iter().map(|w| w.to_string()).collect::<Vec<_>>(),
    )?;
    d.set_item("uncertainty", r.uncertainty.describe())?;
    d.set_item(
        "device",
        PyDevice {
            inner: r.device.clone(),
        },
    )?;
    d.set_item("accel_scale", r.accel_scale)?;
    d.set_item("ssr", r.ssr)?;
    d.set_item("dof", r.dof)?;
    d.set_item("reduced_chi2", r.reduced_chi2)?;
    d.set_item("chi2_p", r.chi2_p)?;
    d.set_item("model", &r.model)?;
    d.set_item("headline", r.headline())?;
    d.set_item("starts_tried", r.starts.len())?;
    d.set_item("starts_refined", r.starts_refined())?;
    let starts = PyList::empty(py);
    for (i, s) in r.starts.iter().enumerate() {
        let q = PyDict::new(py);
        q.set_item("origin", s.origin.to_string())?;
        q.set_item("values", s.values.clone())?;
        q.set_item("design_ssr", s.design_ssr)?;
        q.set_item("design_cut", s.design_cut)?;
        q.set_item("refined_ssr", s.refined.as_ref().map(|f| f.ssr))?;
        q.set_item(
            "refined_values",
            s.refined.as_ref().map(|f| f.values.clone()),
        )?;
        q.set_item("settled", s.refined.as_ref().map(|f| f.settled))?;
        q.set_item("reported", i == r.best_start)?;
        starts.append(q)?;
    }
    d.set_item("starts", starts)?;
    d.set_item("singular_ratio", r.singular_ratio)?;
    d.set_item("evaluations", r.evaluations)?;
    d.set_item("converged", r.stop.converged())?;
    let res = PyDict::new(py);
    let col = |f: &dyn Fn(&fit::Residual) -> f64| array(py, r.residuals.iter().map(f).collect());
    res.set_item(
        "dataset",
        r.residuals
            .iter()
            .map(|x| x.dataset.clone())
            .collect::<Vec<_>>(),
    )?;
    res.set_item(
        "what",
        r.residuals
            .iter()
            .map(|x| x.what.clone())
            .collect::<Vec<_>>(),
    )?;
    res.set_item("freq_hz", col(&|x| x.freq_hz))?;
    res.set_item("measured", col(&|x| x.measured))?;
    res.set_item("model", col(&|x| x.model))?;
    res.set_item("sigma", col(&|x| x.sigma))?;
    d.set_item("residuals", res)?;
    Ok(d)
}

/// Fits the free parameters (a list of `(path, lo, hi)`) of `device` to the data sets (a list
/// of dicts) by the library's fit; see `endstop.fit.fit`.
#[pyfunction]
#[pyo3(name = "fit")]
fn fit_py<'py>(
    py: Python<'py>,
    device: &PyDevice,
    sweeps: Vec<Bound<'py, PyDict>>,
    free: Vec<(String, f64, f64)>,
) -> PyResult<Bound<'py, PyDict>> {
    let data: Vec<SweepData> = sweeps
        .iter()
        .map(sweep_from_dict)
        .collect::<PyResult<_>>()?;
    let free: Vec<ParamRange> = free
        .into_iter()
        .map(|(path, lo, hi)| ParamRange::auto(&path, lo, hi))
        .collect();
    let dev = device.inner.clone();
    let report = py
        .detach(move || fit::fit(&dev, &data, &free, &FitSettings::default()))
        .map_err(fit_err)?;
    report_dict(py, &report)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit_py, m)?)
}

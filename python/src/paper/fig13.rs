//! `endstop.paper.fig13`: Figure 13, prototype 2's up-sweeps at 10 V.

use endstop::device::StiffnessModel;
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig13::Fig13;
use endstop::paper::Figure;
use endstop::study::steady::Measurement;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::paper::{claims_list, paper_device};
use crate::study::{steps_dict, sweep_dict};
use crate::{solver_err, PyDevice};

/// Figure 13 (`endstop::paper::figures::fig13`, its `run` and `claims`) on `device` (default: the published
/// prototype 2): every curve's sweep (the requested range) and refined transitions, the
/// repetition with halved numerics, the claim values, and the `numbers` of the figure's
/// `summary.json` (same keys).
#[pyfunction]
#[pyo3(signature = (device = None))]
fn paper_fig13_run<'py>(
    py: Python<'py>,
    device: Option<&PyDevice>,
) -> PyResult<Bound<'py, PyDict>> {
    let published = match device {
        Some(d) => paper_device(d)?,
        None => PyDevice::prototype(2)?.inner,
    };
    let run = py
        .detach(move || Fig13::run(&published, &|| {}))
        .map_err(solver_err)?;
    let claims = Claims::bundled().map_err(solver_err)?;
    let values = Fig13::claims(&run, &claims).map_err(solver_err)?;
    let out = PyDict::new(py);
    out.set_item(
        "device",
        PyDevice {
            inner: run.device.clone(),
        },
    )?;
    let numbers = PyDict::new(py);
    let curves = PyList::empty(py);
    for (c, h) in run.sweeps.curves.iter().zip(&run.sweeps.halved) {
        let k = c.spec.key();
        if let Some(t) = c.report.onset {
            numbers.set_item(format!("{k}_onset_hz"), t.value())?;
        }
        if let Some(t) = c.report.jump {
            numbers.set_item(format!("{k}_jump_hz"), t.value())?;
        }
        numbers.set_item(format!("{k}_max_v1_rms_v"), c.report.max_v1_rms_v())?;
        let d = PyDict::new(py);
        d.set_item("label", c.spec.label())?;
        d.set_item("key", &k)?;
        d.set_item("accel_rms_g", c.spec.accel_rms_g)?;
        d.set_item(
            "law",
            match c.spec.stiffness {
                StiffnessModel::Hertz => "hertz",
                StiffnessModel::Linear => "linear",
            },
        )?;
        d.set_item("bim_n_s_per_m", c.spec.bim_n_s_per_m)?;
        let in_range: Vec<&Measurement> = c.report.measurements_in_range().collect();
        d.set_item("in_range", steps_dict(py, &in_range)?)?;
        d.set_item("sweep", sweep_dict(py, &c.report)?)?;
        d.set_item("halved", sweep_dict(py, &h.report)?)?;
        curves.append(d)?;
    }
    if let Some(rel) = run.jump_difference_rel() {
        numbers.set_item("jump_hertz_minus_linear_rel", rel)?;
    }
    out.set_item("curves", curves)?;
    out.set_item("numbers", numbers)?;
    out.set_item("claims", claims_list(py, &values)?)?;
    Ok(out)
}

/// Adds the module's functions to `_native`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(paper_fig13_run, m)?)
}

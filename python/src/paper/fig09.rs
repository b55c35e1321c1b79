//! `endstop.paper.fig09`: Figure 9, prototype 1's amplitude continuations at 1220 Hz, and the
//! calibration of prototype 1 it uses.

use endstop::device::Device;
use endstop::paper::calibration::{calibrate_prototype1, Calibration};
use endstop::paper::claims::Claims;
use endstop::paper::figures::fig09::{self, Fig09};
use endstop::paper::setups::{ParamSet, Prototype1Sets};
use endstop::paper::Figure;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::paper::{claims_list, paper_device};
use crate::study::amplitude_dict;
use crate::{solver_err, PyDevice};

/// Calibrates prototype 1 (the end-stop gap fitted so that the 30 V, 5.5 g up-sweep first
/// touches a stop at the measured kink; `endstop::paper::calibration`), from `published`
/// (default: the published prototype 1).
fn calibration(published: Option<&PyDevice>) -> PyResult<(Device, Calibration)> {
    let published = match published {
        Some(d) => paper_device(d)?,
        None => PyDevice::prototype(1)?.inner,
    };
    let cal = calibrate_prototype1(&published).map_err(solver_err)?;
    Ok((published, cal))
}

/// The calibration of prototype 1 as a dict: the calibrated `device` and the fit's record
/// (`fitted_gap_m`, `published_gap_m`, `target_onset_hz`, `achieved_onset_hz`,
/// `evaluations`).
#[pyfunction]
#[pyo3(signature = (published = None))]
fn paper_calibrate_prototype1<'py>(
    py: Python<'py>,
    published: Option<&PyDevice>,
) -> PyResult<Bound<'py, PyDict>> {
    let published = published.cloned();
    let (_, cal) = py.detach(move || calibration(published.as_ref()))?;
    let d = PyDict::new(py);
    d.set_item("device", PyDevice { inner: cal.device })?;
    let r = &cal.record;
    d.set_item("fitted_gap_m", r.fitted_gap_m)?;
    d.set_item("published_gap_m", r.published_gap_m)?;
    d.set_item("target_onset_hz", r.target_onset_hz)?;
    d.set_item("achieved_onset_hz", r.achieved_onset_hz)?;
    d.set_item("evaluations", r.evaluations)?;
    Ok(d)
}

/// Figure 9 (`endstop::paper::figures::fig09`, its `run` and `claims`): prototype 1 at 1220 Hz, amplitude
/// continuations at 20, 30 and 40 V for the published and the calibrated set (default: the
/// published prototype 1 and its calibration, computed here), each repeated with halved
/// numerics; the claim values and the `numbers` of the figure's `summary.json` (same keys).
#[pyfunction]
#[pyo3(signature = (published = None, calibrated = None))]
fn paper_fig09_run<'py>(
    py: Python<'py>,
    published: Option<&PyDevice>,
    calibrated: Option<&PyDevice>,
) -> PyResult<Bound<'py, PyDict>> {
    let published = match published {
        Some(d) => paper_device(d)?,
        None => PyDevice::prototype(1)?.inner,
    };
    let calibrated = calibrated.map(paper_device).transpose()?;
    let run = py.detach(move || -> PyResult<fig09::Run> {
        let calibrated = match calibrated {
            Some(d) => d,
            None => calibrate_prototype1(&published).map_err(solver_err)?.device,
        };
        let sets = Prototype1Sets {
            published,
            calibrated,
        };
        Fig09::run(&sets, &|| {}).map_err(solver_err)
    })?;
    let claims = Claims::bundled().map_err(solver_err)?;
    let values = Fig09::claims(&run, &claims).map_err(solver_err)?;
    let out = PyDict::new(py);
    let numbers = PyDict::new(py);
    let sets = PyList::empty(py);
    for r in &run.sets {
        let set = PyDict::new(py);
        set.set_item("set", r.set.label())?;
        set.set_item(
            "device",
            PyDevice {
                inner: r.device.clone(),
            },
        )?;
        let curves = PyList::empty(py);
        for (c, h) in r.curves.iter().zip(&r.halved) {
            let k = format!("{}_{}v", r.set.label(), c.bias.volts());
            if let Some(t) = c.report.onset {
                numbers.set_item(format!("{k}_onset_g"), t.value())?;
            }
            let m = c.report.at_stop();
            numbers.set_item(format!("{k}_p1_at_5p5g_w"), m.p1_w)?;
            numbers.set_item(format!("{k}_p_both_at_5p5g_w"), m.p_total_w())?;
            let d = PyDict::new(py);
            d.set_item("bias_v", c.bias.volts())?;
            d.set_item("sweep", amplitude_dict(py, &c.report)?)?;
            d.set_item("halved", amplitude_dict(py, &h.report)?)?;
            curves.append(d)?;
        }
        set.set_item("curves", curves)?;
        sets.append(set)?;
    }
    if let Some(cal) = run.sets.iter().find(|r| r.set == ParamSet::Calibrated) {
        numbers.set_item(
            "calibrated_gap_m",
            endstop::paper::setups::endstop(&cal.device).gap_m,
        )?;
    }
    out.set_item("sets", sets)?;
    out.set_item("numbers", numbers)?;
    out.set_item("claims", claims_list(py, &values)?)?;
    Ok(out)
}

/// Adds the module's functions to `_native`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(paper_calibrate_prototype1, m)?)?;
    m.add_function(wrap_pyfunction!(paper_fig09_run, m)?)
}

//! `endstop.paper`: the paper's figure protocols as the book's chapters run them
//! ([`fig09`], [`fig13`]) and the study of why the paper deviates in pieces a cluster can
//! schedule ([`deviations`]).

use endstop::device::Device;
use endstop::paper::claims::Value;
use endstop::paper::setups::check_topology;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{arg_err, PyDevice};

mod deviations;
mod fig09;
mod fig13;

/// The claim values of a figure as a list of dicts (`claim`, `quantity`, `set`, `ours`,
/// `uncertainty`, `note`); `ours` is a number as the scorecard writes it (yes 1, no 0).
pub(crate) fn claims_list<'py>(py: Python<'py>, values: &[Value]) -> PyResult<Bound<'py, PyList>> {
    let l = PyList::empty(py);
    for v in values {
        let d = PyDict::new(py);
        d.set_item("claim", &v.claim)?;
        d.set_item("quantity", &v.quantity)?;
        d.set_item("set", v.set.label())?;
        d.set_item("ours", v.ours.to_f64())?;
        d.set_item("uncertainty", v.uncertainty)?;
        d.set_item("note", &v.note)?;
        l.append(d)?;
    }
    Ok(l)
}

/// A user's device for a figure of the paper: a copy of it, or a `ValueError` naming what
/// it lacks of the paper's topology (the figures read a comb pair and one Hertz line stop for
/// both sides, `endstop::paper::setups::check_topology`).
pub(crate) fn paper_device(device: &PyDevice) -> PyResult<Device> {
    check_topology(&device.inner).map_err(|e| arg_err(e.to_string()))?;
    Ok(device.inner.clone())
}

/// Adds the package's functions to `_native`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    fig09::register(m)?;
    fig13::register(m)?;
    deviations::register(m)
}

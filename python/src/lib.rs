//! `endstop._native`: the Python face of the `endstop` library (pyo3, numpy arrays).
//!
//! Results come back as plain dicts of floats, strings and 1-D numpy arrays; the Python
//! package (`python/pysrc/endstop/`) arranges these functions into modules (`endstop.linear`,
//! `endstop.study`, `endstop.paper.fig13`). Every simulation releases the GIL, so that Python
//! threads (a Dask worker's, say) run other work meanwhile. Parameter errors raise
//! `endstop.ParamError` (a `ValueError`) with the library's message, which names the field and
//! its valid range; solver failures raise `endstop.SolverError` (a `RuntimeError`).
//!
//! The Rust modules (private: the crate is the extension module, its API is Python's) mirror
//! the Python package's: `design` (`endstop.design`), `device` (`endstop.Device`), `fit`
//! (`endstop.fit`), `linear` (`endstop.linear`), `study` and `storage` (`endstop.study`: a
//! model with a storage output, behind an interface circuit, goes through the same functions,
//! `storage` holding its charging and its ensemble's report) and `paper` (`endstop.paper` and
//! its `fig09`, `fig13` and `deviations`); each registers its functions in `_native`.

use endstop::device::ParamError as LibParamError;
use numpy::PyArray1;
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;

mod design;
mod device;
mod fit;
mod fit_spectrum;
mod linear;
mod paper;
mod springs;
mod storage;
mod study;

pub(crate) use device::PyDevice;

create_exception!(
    _native,
    ParamError,
    PyValueError,
    "A device parameter is invalid: the message names the field, its value and its valid range."
);
create_exception!(
    _native,
    SolverError,
    PyRuntimeError,
    "A simulation failed (the integrator or the spectral analysis)."
);

pub(crate) fn param_err(e: LibParamError) -> PyErr {
    let field = e.field().map(str::to_string);
    let err = ParamError::new_err(e.to_string());
    Python::attach(|py| {
        let _ = err.value(py).setattr("field", field);
    });
    err
}

pub(crate) fn solver_err(e: impl std::fmt::Display) -> PyErr {
    SolverError::new_err(e.to_string())
}

pub(crate) fn arg_err(msg: impl Into<String>) -> PyErr {
    PyValueError::new_err(msg.into())
}

/// A vector as a 1-D numpy array.
pub(crate) fn array<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ParamError", py.get_type::<ParamError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyDevice>()?;
    design::register(m)?;
    fit::register(m)?;
    fit_spectrum::register(m)?;
    storage::register(m)?;
    linear::register(m)?;
    study::register(m)?;
    springs::register(m)?;
    paper::register(m)?;
    Ok(())
}

//! `endstop.spectrum`: fitting a device to a measured output spectrum under random vibration
//! ([`endstop::fit::spectrum`]), the twin of `endstop fit --spectrum`: emulators of the
//! spectrum's features over the free parameters from a design of ensembles, then the posterior
//! of the parameters with the emulators' uncertainty in it.

use endstop::device::ParamRange;
use endstop::fit::spectrum::{
    build_emulator, MeasuredSpectrum, SpectrumFitError, SpectrumSettings, FEATURES,
};
use endstop::fit::FitError;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{arg_err, param_err, solver_err, PyDevice};

fn err(e: SpectrumFitError) -> PyErr {
    match e {
        SpectrumFitError::Fit(FitError::Param { error, .. }) => param_err(error),
        SpectrumFitError::Fit(e) => arg_err(e.to_string()),
        SpectrumFitError::Data(_) => arg_err(e.to_string()),
        e => solver_err(e),
    }
}

/// Fits `free` (`(path, lo, hi)` triples) of `device` to the measured spectrum
/// (`freq_hz`, `psd_w_per_hz` at the stated `accel_psd_g2_per_hz`, averaging `records` 10 s
/// records); see `endstop.spectrum.fit`.
#[pyfunction]
#[pyo3(signature = (device, freq_hz, psd_w_per_hz, accel_psd_g2_per_hz, free, records = 1,
                    per_param = 10, design_records = 16, seed = 17))]
#[allow(clippy::too_many_arguments)]
fn fit_spectrum<'py>(
    py: Python<'py>,
    device: &PyDevice,
    freq_hz: Vec<f64>,
    psd_w_per_hz: Vec<f64>,
    accel_psd_g2_per_hz: f64,
    free: Vec<(String, f64, f64)>,
    records: usize,
    per_param: usize,
    design_records: usize,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    let measured = MeasuredSpectrum {
        freq_hz,
        psd_w_per_hz,
        accel_psd_g2_per_hz,
        records,
    };
    measured.validate().map_err(err)?;
    if per_param == 0 || design_records < 2 {
        return Err(arg_err(
            "per_param must be at least 1 and design_records at least 2",
        ));
    }
    let free: Vec<ParamRange> = free
        .into_iter()
        .map(|(path, lo, hi)| ParamRange::auto(&path, lo, hi))
        .collect();
    let dev = device.inner.clone();
    let settings = SpectrumSettings {
        per_param,
        records: design_records,
        seed,
        ..SpectrumSettings::default()
    };
    let est = py
        .detach(move || {
            let em = build_emulator(
                &dev,
                &free,
                accel_psd_g2_per_hz,
                measured.band(),
                settings,
                &|| {},
            )?;
            em.fit(&measured)
        })
        .map_err(err)?;
    let d = PyDict::new(py);
    let params = PyList::empty(py);
    for p in &est.params {
        let r = PyDict::new(py);
        r.set_item("path", &p.path)?;
        r.set_item("mean", p.mean)?;
        r.set_item("best", p.best)?;
        r.set_item("interval", p.interval)?;
        params.append(r)?;
    }
    d.set_item("params", params)?;
    d.set_item("features", FEATURES.to_vec())?;
    d.set_item("measured", est.measured.to_vec())?;
    d.set_item("predicted", est.predicted.to_vec())?;
    d.set_item("implausibility", est.implausibility.to_vec())?;
    d.set_item("effective_samples", est.effective_samples)?;
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(fit_spectrum, m)?)
}

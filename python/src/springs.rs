//! Nonlinear suspensions from Python: a device's static equilibria, and the displacement of a
//! random ensemble (histogram with its interval across records, well shares, well-to-well
//! transitions, and the exact stationary density where it applies).

use endstop::physics::suspension::Place;
use endstop::study::displacement::{displacement_ensemble, DisplacementBins};
use endstop::validation::stationary_law::StationaryLaw;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{arg_err, array, solver_err, PyDevice};

/// The static equilibria of a device's suspension with its stops' springs: a list of dicts
/// with ``x_m``, ``stiffness_n_per_m``, ``stable``, ``energy_j`` and ``place`` (``free``,
/// ``upper_stop`` or ``lower_stop``), sorted by position.
#[pyfunction]
fn equilibria<'py>(py: Python<'py>, device: &PyDevice) -> PyResult<Bound<'py, PyList>> {
    let out = PyList::empty(py);
    for e in device.inner.equilibria() {
        let d = PyDict::new(py);
        d.set_item("x_m", e.x_m)?;
        d.set_item("stiffness_n_per_m", e.stiffness_n_per_m)?;
        d.set_item("stable", e.stable)?;
        d.set_item("energy_j", e.energy_j)?;
        d.set_item(
            "place",
            match e.place {
                Place::Free => "free",
                Place::UpperStop => "upper_stop",
                Place::LowerStop => "lower_stop",
            },
        )?;
        out.append(d)?;
    }
    Ok(out)
}

/// The displacement of ``records`` band-limited white-noise records (streams ``0..records`` of
/// ``seed``), read into ``bins`` equal bins over ``[-reach_m, reach_m]``.
#[pyfunction]
#[pyo3(signature = (device, psd_g2_per_hz, reach_m, bins = 80, records = 8, duration_s = 10.0, seed = 2012))]
#[allow(clippy::too_many_arguments)]
fn displacement<'py>(
    py: Python<'py>,
    device: &PyDevice,
    psd_g2_per_hz: f64,
    reach_m: f64,
    bins: usize,
    records: u64,
    duration_s: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    if !(psd_g2_per_hz.is_finite() && psd_g2_per_hz > 0.0) {
        return Err(arg_err(
            "psd_g2_per_hz must be a positive two-sided PSD in g^2/Hz",
        ));
    }
    if !(duration_s.is_finite() && duration_s > 0.0 && reach_m.is_finite() && reach_m > 0.0) {
        return Err(arg_err("duration_s and reach_m must be positive"));
    }
    if records < 2 || bins == 0 {
        return Err(arg_err("records must be at least 2 and bins at least 1"));
    }
    let dev = device.inner.clone();
    let mut spec = endstop::paper::setups::paper_record(&dev, psd_g2_per_hz);
    spec.noise.duration_s = duration_s;
    let b = DisplacementBins::uniform(&dev, -reach_m, reach_m, bins);
    let wells = b.wells;
    let (ens, law) = py
        .detach(move || {
            displacement_ensemble(&dev, &spec, &b, seed, records)
                .map(|e| (e, StationaryLaw::of(&dev, &spec).ok()))
        })
        .map_err(solver_err)?;
    let dens = ens.density();
    let d = PyDict::new(py);
    d.set_item("x_m", array(py, dens.iter().map(|v| v.0).collect()))?;
    d.set_item(
        "density_per_m",
        array(py, dens.iter().map(|v| v.1).collect()),
    )?;
    d.set_item(
        "density_ci95_per_m",
        array(py, dens.iter().map(|v| v.2).collect()),
    )?;
    d.set_item(
        "exact_density_per_m",
        law.map(|l| array(py, dens.iter().map(|v| l.density(v.0)).collect())),
    )?;
    d.set_item("x2_mean_m2", ens.stat(|r| r.x2_mean_m2).mean)?;
    d.set_item("transitions", ens.transitions())?;
    let rate = ens.transition_rate();
    d.set_item("transition_rate_per_s", wells.map(|_| rate.mean))?;
    d.set_item("transition_rate_ci95_per_s", wells.map(|_| rate.ci95))?;
    d.set_item("wells_m", wells.map(|(w, _)| w.to_vec()))?;
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(equilibria, m)?)?;
    m.add_function(wrap_pyfunction!(displacement, m)?)?;
    Ok(())
}

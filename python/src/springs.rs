//! Nonlinear suspensions from Python: a device's static equilibria, and the displacement of a
//! random ensemble (histogram with its interval across records, well shares, passages from one
//! well's bottom to the other's, and the exact stationary density where it applies), and the
//! basins of the stable orbits under a sine, each orbit placed by well.

use endstop::model::Model;
use endstop::physics::suspension::Place;
use endstop::progress::Silent;
use endstop::study::attractors::{find_attractors, seeds, AttractorSearch, Attractors};
use endstop::study::basins::{basins as basin_map, BasinGrid, BasinSettings, Basins, UNSETTLED};
use endstop::study::displacement::{displacement_ensemble, DisplacementBins};
use endstop::study::orbit::{Forcing, OrbitError, ShootingOptions};
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
    for e in endstop::physics::statics::equilibria(&device.inner) {
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

/// The basins under a sine of ``freq_hz`` at ``accel_rms_g`` (g rms) on a grid of ``cells``
/// by ``cells`` initial states over ``x_range_m`` and ``v_range_m_per_s``, the attractors found
/// from the wells at rest and ``seeds_per_side`` squared states over the grid (as ``endstop
/// basins``).
#[pyfunction]
#[pyo3(signature = (device, freq_hz, accel_rms_g, x_range_m, v_range_m_per_s, cells = 21, max_periods = 1000, settle_tol = 1e-3, seeds_per_side = 5))]
#[allow(clippy::too_many_arguments)]
fn basins<'py>(
    py: Python<'py>,
    device: &PyDevice,
    freq_hz: f64,
    accel_rms_g: f64,
    x_range_m: (f64, f64),
    v_range_m_per_s: (f64, f64),
    cells: usize,
    max_periods: usize,
    settle_tol: f64,
    seeds_per_side: usize,
) -> PyResult<Bound<'py, PyDict>> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !(positive(freq_hz) && positive(accel_rms_g)) {
        return Err(arg_err(
            "freq_hz and accel_rms_g must be finite and positive",
        ));
    }
    let range = |r: (f64, f64)| r.0.is_finite() && r.1.is_finite() && r.0 < r.1;
    if !(range(x_range_m) && range(v_range_m_per_s)) {
        return Err(arg_err(
            "x_range_m and v_range_m_per_s must be (lo, hi) with lo < hi",
        ));
    }
    if cells < 2
        || max_periods == 0
        || seeds_per_side > cells
        || !(positive(settle_tol) && settle_tol < 1.0)
    {
        return Err(arg_err(
            "cells must be at least 2, max_periods at least 1, seeds_per_side at most cells, \
             and settle_tol in (0, 1)",
        ));
    }
    let dev = device.inner.clone();
    let grid = BasinGrid {
        x_m: x_range_m,
        v_m_per_s: v_range_m_per_s,
        nx: cells,
        nv: cells,
    };
    let forcing = Forcing {
        freq_hz,
        accel_rms_g,
    };
    let (found, b) = py
        .detach(move || {
            endstop::with_harvester!(&dev, |h| attractors_and_basins(
                &h,
                &dev,
                &forcing,
                grid,
                seeds_per_side,
                max_periods,
                settle_tol
            ))
        })
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    d.set_item("x0_m", array(py, b.cells.iter().map(|c| c.0).collect()))?;
    d.set_item(
        "v0_m_per_s",
        array(py, b.cells.iter().map(|c| c.1).collect()),
    )?;
    let labels: Vec<&str> = (0..b.cells.len()).map(|i| b.label(i)).collect();
    d.set_item("attractor", labels)?;
    let places: Vec<&str> = b
        .attractor
        .iter()
        .map(|a| a.map_or(UNSETTLED, |k| found.found[k].place.label()))
        .collect();
    d.set_item("place", places)?;
    d.set_item("periods", b.periods.clone())?;
    let shares = b.shares();
    let table = PyList::empty(py);
    for (f, (_, share)) in found.found.iter().zip(&shares) {
        let a = PyDict::new(py);
        a.set_item("label", f.label.as_str())?;
        a.set_item("place", f.place.label())?;
        a.set_item("x_lower_m", f.orbit.summary.x_lower_m)?;
        a.set_item("x_upper_m", f.orbit.summary.x_upper_m)?;
        a.set_item("p_w", f.orbit.summary.p_total_w)?;
        a.set_item("share", *share)?;
        table.append(a)?;
    }
    d.set_item("attractors", table)?;
    Ok(d)
}

/// The stable orbits of one drive period of `model` (assembled from `device`) reached from the
/// wells at rest and `seeds_per_side` squared states over `grid`, and the basins of the grid
/// among them: the study of ``endstop basins``, with its default shooting and search.
fn attractors_and_basins<M: Model<N>, const N: usize>(
    model: &M,
    device: &endstop::device::Device,
    forcing: &Forcing,
    grid: BasinGrid,
    seeds_per_side: usize,
    max_periods: usize,
    settle_tol: f64,
) -> Result<(Attractors, Basins), OrbitError> {
    let shooting = ShootingOptions::default();
    let found = find_attractors(
        model,
        device,
        forcing,
        shooting,
        &seeds(device, &grid, seeds_per_side),
        &AttractorSearch::default(),
    )?;
    if found.found.is_empty() {
        return Err(OrbitError::Invalid(
            "no stable orbit of one drive period found: the basins need an attractor".into(),
        ));
    }
    let settings = BasinSettings {
        grid,
        max_periods,
        settle_tol,
        rtol: shooting.rtol,
    };
    let b = basin_map(model, forcing, &found.catalogue(), &settings, &Silent)?;
    Ok((found, b))
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(equilibria, m)?)?;
    m.add_function(wrap_pyfunction!(displacement, m)?)?;
    m.add_function(wrap_pyfunction!(basins, m)?)?;
    Ok(())
}

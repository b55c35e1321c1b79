//! `endstop.linear`: the linear theory of the differential mode (eqs 11-22).

use endstop::paper::qm::{QmReading, EQ21_QM};
use endstop::physics::linear::{white_noise_power_w, LinearResponse};
use endstop::physics::two_port::{self, TwoPort};
use endstop::G;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::PyDict;

use crate::{arg_err, PyDevice};

fn qm_reading(name: &str) -> PyResult<QmReading> {
    match name {
        "open_circuit" => Ok(QmReading::OpenCircuit),
        "suspension" => Ok(QmReading::Suspension),
        "measured_resonance" => Ok(QmReading::MeasuredResonance),
        _ => Err(arg_err(format!(
            "Qm reading `{name}`: must be \"open_circuit\" (sqrt(K m)/b, eq 21's), \"suspension\" \
             (sqrt(km m)/b) or \"measured_resonance\" (m w0/b)"
        ))),
    }
}

/// The two-port of eqs 15-18 for a capacitor-pair device; any other transducer is a
/// `ValueError` naming the device (the two-port and eq 21 are a pair's theory).
fn pair(device: &PyDevice) -> PyResult<TwoPort> {
    TwoPort::try_of(&device.inner).ok_or_else(|| {
        arg_err(format!(
            "device `{}`: the two-port of eqs 15-18 and eq 21 need a capacitor-pair transducer; \
             use linear.white_noise_power_w and linear.linear_output_psd for any device",
            device.inner.name
        ))
    })
}

/// The differential-mode two-port (eqs 15-18, 22) and its Qm readings, as a dict.
#[pyfunction]
#[pyo3(name = "two_port")]
fn two_port_dict<'py>(py: Python<'py>, device: &PyDevice) -> PyResult<Bound<'py, PyDict>> {
    let tp = pair(device)?;
    let d = PyDict::new(py);
    d.set_item("capacitance_f", tp.capacitance_f)?;
    d.set_item("gamma_n_per_v", tp.gamma_n_per_v)?;
    d.set_item("stiffness_n_per_m", tp.stiffness_n_per_m)?;
    d.set_item("k2", tp.k2)?;
    d.set_item("resonance_hz", tp.resonance_hz())?;
    d.set_item("r_load", tp.r_load())?;
    let qm = PyDict::new(py);
    qm.set_item("open_circuit", tp.qm_open_circuit())?;
    qm.set_item("suspension", tp.qm_suspension())?;
    qm.set_item("measured_resonance", tp.qm_measured_resonance())?;
    d.set_item("qm", qm)?;
    d.set_item("eq21_efficiency", tp.broadband_efficiency(EQ21_QM.of(&tp)))?;
    Ok(d)
}

/// Coupling k^2 of eq 18 (a fraction).
#[pyfunction]
fn k2(device: &PyDevice) -> PyResult<f64> {
    Ok(pair(device)?.k2)
}

/// Mechanical quality factor under a reading (`open_circuit`, `suspension`,
/// `measured_resonance`).
#[pyfunction]
#[pyo3(signature = (device, reading = "open_circuit"))]
fn qm(device: &PyDevice, reading: &str) -> PyResult<f64> {
    Ok(qm_reading(reading)?.of(&pair(device)?))
}

/// Broadband efficiency 2P/(m Sa) of eq 21 (fraction), with Qm = sqrt(K m)/b, or with the
/// given reading.
#[pyfunction]
#[pyo3(signature = (device, reading = "open_circuit"))]
fn eq21_efficiency(device: &PyDevice, reading: &str) -> PyResult<f64> {
    let tp = pair(device)?;
    Ok(tp.broadband_efficiency(qm_reading(reading)?.of(&tp)))
}

/// Mean power of both loads (W) by eq 21 at a two-sided acceleration PSD (g^2/Hz).
#[pyfunction]
fn eq21_power_w(device: &PyDevice, psd_g2_per_hz: f64) -> PyResult<f64> {
    pair(device)?;
    Ok(two_port::eq21_power_w(&device.inner, psd_g2_per_hz))
}

/// Mean power of the loads (W) of the linearised model of any device under white base
/// acceleration of two-sided density `psd_g2_per_hz` (g^2/Hz) limited to `[lo_hz, hi_hz]`.
#[pyfunction]
#[pyo3(name = "white_noise_power_w")]
fn white_noise_power_w_py(
    device: &PyDevice,
    psd_g2_per_hz: f64,
    lo_hz: f64,
    hi_hz: f64,
) -> PyResult<f64> {
    if !(psd_g2_per_hz.is_finite() && psd_g2_per_hz > 0.0) {
        return Err(arg_err(format!(
            "psd_g2_per_hz = {psd_g2_per_hz}: must be positive"
        )));
    }
    if !(lo_hz.is_finite() && hi_hz.is_finite() && 0.0 < lo_hz && lo_hz < hi_hz) {
        return Err(arg_err(format!(
            "band [{lo_hz}, {hi_hz}] Hz: must satisfy 0 < lo_hz < hi_hz"
        )));
    }
    Ok(white_noise_power_w(
        &device.inner,
        psd_g2_per_hz * G * G,
        lo_hz,
        hi_hz,
    ))
}

/// The linearised model's one-sided output power PSD of both loads (W/Hz) at the given
/// frequencies, for a two-sided acceleration PSD (g^2/Hz).
#[pyfunction]
fn linear_output_psd<'py>(
    py: Python<'py>,
    device: &PyDevice,
    psd_g2_per_hz: f64,
    freq_hz: PyReadonlyArray1<'py, f64>,
) -> PyResult<Bound<'py, PyArray1<f64>>> {
    let f = freq_hz.as_slice()?;
    let density = LinearResponse::of(&device.inner)
        .output_psd(psd_g2_per_hz * G * G, f)
        .density;
    Ok(PyArray1::from_vec(py, density))
}

/// The bias voltage (V) at which eq 18 gives the coupling `k2`.
#[pyfunction]
fn bias_for_coupling(device: &PyDevice, k2: f64) -> PyResult<f64> {
    if !(0.0..1.0).contains(&k2) {
        return Err(arg_err(format!("k2 = {k2}: must be in [0, 1)")));
    }
    pair(device)?;
    Ok(two_port::bias_for_coupling(&device.inner, k2))
}

/// Adds the module's functions to `_native`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for f in [
        wrap_pyfunction!(two_port_dict, m)?,
        wrap_pyfunction!(k2, m)?,
        wrap_pyfunction!(qm, m)?,
        wrap_pyfunction!(eq21_efficiency, m)?,
        wrap_pyfunction!(eq21_power_w, m)?,
        wrap_pyfunction!(white_noise_power_w_py, m)?,
        wrap_pyfunction!(linear_output_psd, m)?,
        wrap_pyfunction!(bias_for_coupling, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}

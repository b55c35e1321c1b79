//! `endstop._native`: the Python face of the `endstop` library (pyo3, numpy arrays).
//!
//! Results come back as plain dicts of floats, strings and 1-D numpy arrays; the Python
//! package (`python/pysrc/endstop/`) arranges these functions into modules (`endstop.linear`,
//! `endstop.study`, `endstop.paper.fig13`). Every simulation releases the GIL, so that Python
//! threads (a Dask worker's, say) run other work meanwhile. Parameter errors raise
//! `endstop.ParamError` (a `ValueError`) with the library's message, which names the field and
//! its valid range; solver failures raise `endstop.SolverError` (a `RuntimeError`).

use endstop::device::{Device, ParamError as LibParamError, StiffnessModel};
use endstop::paper::calibration::{calibrate_prototype1, Calibration};
use endstop::paper::claims::{Claims, Value};
use endstop::paper::figures::fig09::{self, Fig09};
use endstop::paper::figures::fig13::Fig13;
use endstop::paper::setups::{ParamSet, Prototype1Sets};
use endstop::paper::Figure;
use endstop::physics::two_port::{self, QmReading, TwoPort, EQ21_QM};
use endstop::study::amplitude::{amplitude_sweep_report, AmplitudeReport};
use endstop::study::ensemble::{run_ensemble, EnsembleSpec};
use endstop::study::record::{simulate_record, RecordSpec, RecordSummary};
use endstop::study::steady::{steady_config, Measurement};
use endstop::study::stepped::{linspace_step, Transition};
use endstop::study::sweep::{self, SweepReport, SweepSettings};
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::create_exception;
use pyo3::exceptions::{PyRuntimeError, PyValueError};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString};

mod study;

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

/// The published parameter files the package carries (the repository's `data/`).
const PROTOTYPE1_TOML: &str = include_str!("../../data/prototype1.toml");
const PROTOTYPE2_TOML: &str = include_str!("../../data/prototype2.toml");

fn param_err(e: LibParamError) -> PyErr {
    let field = match &e {
        LibParamError::OutOfRange { field, .. } => Some(field.clone()),
        LibParamError::Parse { .. } => None,
    };
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

// ---------------------------------------------------------------------------------------------
// Device

/// A harvester: the parameters of a device file, validated.
#[pyclass(frozen, name = "Device", module = "endstop")]
#[derive(Clone)]
pub struct PyDevice {
    pub(crate) inner: Device,
}

fn toml_to_py<'py>(py: Python<'py>, v: &toml::Value) -> PyResult<Bound<'py, PyAny>> {
    Ok(match v {
        toml::Value::String(s) => PyString::new(py, s).into_any(),
        toml::Value::Integer(i) => i.into_pyobject(py)?.into_any(),
        toml::Value::Float(f) => PyFloat::new(py, *f).into_any(),
        toml::Value::Boolean(b) => PyBool::new(py, *b).to_owned().into_any(),
        toml::Value::Datetime(d) => PyString::new(py, &d.to_string()).into_any(),
        toml::Value::Array(a) => {
            let l = PyList::empty(py);
            for x in a {
                l.append(toml_to_py(py, x)?)?;
            }
            l.into_any()
        }
        toml::Value::Table(t) => {
            let d = PyDict::new(py);
            for (k, x) in t {
                d.set_item(k, toml_to_py(py, x)?)?;
            }
            d.into_any()
        }
    })
}

fn py_to_toml(v: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
    if let Ok(d) = v.cast::<PyDict>() {
        let mut t = toml::map::Map::new();
        for (k, x) in d.iter() {
            let k: String = k
                .extract()
                .map_err(|_| arg_err(format!("{path}: keys must be strings")))?;
            let p = if path.is_empty() {
                k.clone()
            } else {
                format!("{path}.{k}")
            };
            t.insert(k, py_to_toml(&x, &p)?);
        }
        Ok(toml::Value::Table(t))
    } else if v.is_instance_of::<PyBool>() {
        Ok(toml::Value::Boolean(v.extract()?))
    } else if v.is_instance_of::<PyInt>() {
        Ok(toml::Value::Integer(v.extract()?))
    } else if let Ok(f) = v.extract::<f64>() {
        Ok(toml::Value::Float(f))
    } else if let Ok(s) = v.extract::<String>() {
        Ok(toml::Value::String(s))
    } else {
        Err(arg_err(format!(
            "`{path}`: expected a number, a string, a bool or a dict, got {}",
            v.get_type().name()?
        )))
    }
}

#[pymethods]
impl PyDevice {
    /// Loads and validates a device file (TOML, as `data/prototype2.toml`).
    #[staticmethod]
    fn from_toml(path: std::path::PathBuf) -> PyResult<Self> {
        let text = std::fs::read_to_string(&path).map_err(|e| {
            pyo3::exceptions::PyOSError::new_err(format!(
                "cannot read device file {}: {e}",
                path.display()
            ))
        })?;
        Self::from_toml_str(&text, &path.display().to_string())
    }

    /// Parses and validates a device from TOML text; `source` names it in error messages.
    #[staticmethod]
    #[pyo3(signature = (text, source = "<string>"))]
    fn from_toml_str(text: &str, source: &str) -> PyResult<Self> {
        Device::from_toml_str(text, source)
            .map(|inner| Self { inner })
            .map_err(param_err)
    }

    /// Builds and validates a device from a dict with the layout of a device file
    /// (`{"name": ..., "geometry": {...}, "mechanics": {...}, ...}`, SI units).
    #[staticmethod]
    #[pyo3(signature = (d, source = "<dict>"))]
    fn from_dict(d: &Bound<'_, PyDict>, source: &str) -> PyResult<Self> {
        let value = py_to_toml(d.as_any(), "")?;
        // Through the TOML text, so that the checks (unknown or missing keys, ranges) are the
        // ones a device file gets.
        let text = toml::to_string(&value).map_err(|e| arg_err(e.to_string()))?;
        Self::from_toml_str(&text, source)
    }

    /// The published parameters of prototype 1 or 2 (the repository's `data/prototypeN.toml`).
    #[staticmethod]
    pub(crate) fn prototype(n: u32) -> PyResult<Self> {
        let (text, name) = match n {
            1 => (PROTOTYPE1_TOML, "data/prototype1.toml"),
            2 => (PROTOTYPE2_TOML, "data/prototype2.toml"),
            _ => return Err(arg_err(format!("prototype {n}: must be 1 or 2"))),
        };
        Self::from_toml_str(text, name)
    }

    /// The parameters as a dict (the layout of a device file).
    fn to_dict<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyAny>> {
        let v = toml::Value::try_from(&self.inner).map_err(|e| arg_err(e.to_string()))?;
        toml_to_py(py, &v)
    }

    /// The parameters as TOML text.
    fn to_toml(&self) -> String {
        self.inner.to_toml_string()
    }

    /// A copy at another bias voltage (V), validated.
    fn with_bias(&self, bias_v: f64) -> PyResult<Self> {
        let d = self.inner.with_bias(bias_v);
        d.validate("with_bias").map_err(param_err)?;
        Ok(Self { inner: d })
    }

    /// A copy with another end-stop law (`"linear"` or `"hertz"`) and damping b_im (N s/m).
    #[pyo3(signature = (law, damping_n_s_per_m, tension_free = false))]
    fn with_endstop(
        &self,
        law: &str,
        damping_n_s_per_m: f64,
        tension_free: bool,
    ) -> PyResult<Self> {
        let law = match law {
            "linear" => StiffnessModel::Linear,
            "hertz" => StiffnessModel::Hertz,
            _ => {
                return Err(arg_err(format!(
                    "law `{law}`: must be \"linear\" or \"hertz\""
                )))
            }
        };
        let mut d = self.inner.with_endstop(law, damping_n_s_per_m);
        d.endstop.tension_free = tension_free;
        d.validate("with_endstop").map_err(param_err)?;
        Ok(Self { inner: d })
    }

    /// A copy with the end-stop gap x_max (m) changed, validated.
    fn with_endstop_gap(&self, endstop_gap_m: f64) -> PyResult<Self> {
        let mut d = self.inner.clone();
        d.geometry.endstop_gap_m = endstop_gap_m;
        d.validate("with_endstop_gap").map_err(param_err)?;
        Ok(Self { inner: d })
    }

    /// Device name.
    #[getter]
    fn name(&self) -> String {
        self.inner.name.clone()
    }

    /// Parameter set label (`published`, `calibrated`, ...).
    #[getter]
    fn params(&self) -> String {
        self.inner.params.clone()
    }

    /// Bias voltage (V).
    #[getter]
    fn bias_v(&self) -> f64 {
        self.inner.electrical.bias_v
    }

    fn __repr__(&self) -> String {
        format!(
            "Device(name={:?}, params={:?}, bias_v={})",
            self.inner.name, self.inner.params, self.inner.electrical.bias_v
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }
}

// ---------------------------------------------------------------------------------------------
// Linear theory (eqs 11-22)

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

/// The differential-mode two-port (eqs 15-18, 22) and its Qm readings, as a dict.
#[pyfunction]
#[pyo3(name = "two_port")]
fn two_port_dict<'py>(py: Python<'py>, device: &PyDevice) -> PyResult<Bound<'py, PyDict>> {
    let tp = TwoPort::of(&device.inner);
    let d = PyDict::new(py);
    d.set_item("capacitance_f", tp.capacitance_f)?;
    d.set_item("gamma_n_per_v", tp.gamma_n_per_v)?;
    d.set_item("stiffness_n_per_m", tp.stiffness_n_per_m)?;
    d.set_item("k2", tp.k2)?;
    d.set_item("resonance_hz", tp.resonance_hz())?;
    d.set_item("r_load", tp.r_load())?;
    let qm = PyDict::new(py);
    qm.set_item("open_circuit", tp.qm(QmReading::OpenCircuit))?;
    qm.set_item("suspension", tp.qm(QmReading::Suspension))?;
    qm.set_item("measured_resonance", tp.qm(QmReading::MeasuredResonance))?;
    d.set_item("qm", qm)?;
    d.set_item("eq21_efficiency", tp.broadband_efficiency(tp.qm(EQ21_QM)))?;
    Ok(d)
}

/// Coupling k^2 of eq 18 (a fraction).
#[pyfunction]
fn k2(device: &PyDevice) -> f64 {
    TwoPort::of(&device.inner).k2
}

/// Mechanical quality factor under a reading (`open_circuit`, `suspension`,
/// `measured_resonance`).
#[pyfunction]
#[pyo3(signature = (device, reading = "open_circuit"))]
fn qm(device: &PyDevice, reading: &str) -> PyResult<f64> {
    Ok(TwoPort::of(&device.inner).qm(qm_reading(reading)?))
}

/// Broadband efficiency 2P/(m Sa) of eq 21 (fraction), with Qm = sqrt(K m)/b, or with the
/// given reading.
#[pyfunction]
#[pyo3(signature = (device, reading = "open_circuit"))]
fn eq21_efficiency(device: &PyDevice, reading: &str) -> PyResult<f64> {
    let tp = TwoPort::of(&device.inner);
    Ok(tp.broadband_efficiency(tp.qm(qm_reading(reading)?)))
}

/// Mean power of both loads (W) by eq 21 at a two-sided acceleration PSD (g^2/Hz).
#[pyfunction]
fn eq21_power_w(device: &PyDevice, psd_g2_per_hz: f64) -> f64 {
    two_port::eq21_power_w(&device.inner, psd_g2_per_hz)
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
    let p = two_port::linear_output_psd(&device.inner, psd_g2_per_hz, f);
    Ok(PyArray1::from_vec(py, p.density))
}

/// The bias voltage (V) at which eq 18 gives the coupling `k2`.
#[pyfunction]
fn bias_for_coupling(device: &PyDevice, k2: f64) -> PyResult<f64> {
    if !(0.0..1.0).contains(&k2) {
        return Err(arg_err(format!("k2 = {k2}: must be in [0, 1)")));
    }
    Ok(two_port::bias_for_coupling(&device.inner, k2))
}

// ---------------------------------------------------------------------------------------------
// Sweeps

fn array<'py>(py: Python<'py>, v: Vec<f64>) -> Bound<'py, PyArray1<f64>> {
    PyArray1::from_vec(py, v)
}

/// Per-step columns of a continuation, as numpy arrays.
fn steps_dict<'py>(py: Python<'py>, steps: &[&Measurement]) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let col = |f: fn(&Measurement) -> f64| array(py, steps.iter().map(|m| f(m)).collect());
    d.set_item("freq_hz", col(|m| m.freq_hz))?;
    d.set_item("accel_rms_g", col(|m| m.accel_rms_g))?;
    d.set_item("v1_rms_v", col(|m| m.v1_rms_v))?;
    d.set_item("v2_rms_v", col(|m| m.v2_rms_v))?;
    d.set_item("vdiff_rms_v", col(|m| m.vdiff_rms_v))?;
    d.set_item("p1_w", col(|m| m.p1_w))?;
    d.set_item("p2_w", col(|m| m.p2_w))?;
    d.set_item("p_total_w", col(|m| m.p_total_w()))?;
    d.set_item("x_peak_m", col(|m| m.x_peak_m))?;
    d.set_item("contact_fraction", col(|m| m.contact_fraction))?;
    d.set_item("impacts_per_period", col(|m| m.impacts_per_period))?;
    d.set_item("blocks", col(|m| m.blocks as f64))?;
    d.set_item(
        "converged",
        steps.iter().map(|m| m.converged).collect::<Vec<bool>>(),
    )?;
    Ok(d)
}

fn transition_items(
    d: &Bound<'_, PyDict>,
    name: &str,
    unit: &str,
    t: Option<Transition>,
) -> PyResult<()> {
    d.set_item(format!("{name}_{unit}"), t.map(|t| t.value()))?;
    d.set_item(
        format!("{name}_bracket_{unit}"),
        t.map(|t| (t.before, t.after)),
    )?;
    Ok(())
}

/// An up-sweep report as a dict: the steps (arrays) and the refined transitions.
fn sweep_dict<'py>(py: Python<'py>, r: &SweepReport) -> PyResult<Bound<'py, PyDict>> {
    let all: Vec<&Measurement> = r.measurements().collect();
    let d = steps_dict(py, &all)?;
    d.set_item("extended_from", r.extended_from)?;
    d.set_item("contact_at_start", r.contact_at_start)?;
    transition_items(&d, "onset", "hz", r.onset)?;
    transition_items(&d, "jump", "hz", r.jump)?;
    d.set_item("jump_power_ratio", r.jump_power_ratio)?;
    transition_items(&d, "contact_lost", "hz", r.contact_lost)?;
    match r.branch_end() {
        Some(end) => {
            d.set_item("branch_end_hz", end.transition.value())?;
            d.set_item("branch_end_kind", end.kind.label())?;
        }
        None => {
            d.set_item("branch_end_hz", py.None())?;
            d.set_item("branch_end_kind", py.None())?;
        }
    }
    d.set_item("max_v1_rms_v", r.max_v1_rms_v())?;
    d.set_item("all_converged", r.all_converged())?;
    let s = r.total_stats();
    d.set_item("integrator_steps", s.accepted)?;
    d.set_item("contact_events", s.events)?;
    Ok(d)
}

/// Stepped-sine up-sweep with continuation (each frequency starts from the previous steady
/// state), the impact onset, jump and loss of contact refined by bisection to brackets
/// narrower than `refine_tol_hz`: the `endstop sweep` command's study (the same grid
/// `start_hz..stop_hz` by `step_hz`, steady-state settings for the middle of the range).
#[pyfunction]
#[pyo3(signature = (device, accel_rms_g, start_hz, stop_hz, step_hz = 2.0, refine_tol_hz = 0.1))]
fn up_sweep<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
    refine_tol_hz: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = sweep_settings(
        &device.inner,
        accel_rms_g,
        start_hz,
        stop_hz,
        step_hz,
        refine_tol_hz,
    )?;
    let dev = device.inner.clone();
    let report = py
        .detach(move || settings.run(&dev, accel_rms_g, |_| {}))
        .map_err(solver_err)?;
    sweep_dict(py, &report)
}

/// Checks the arguments shared by the frequency studies ([`sweep::check_range`]), naming
/// them as this module does.
fn check_range(accel_rms_g: f64, start_hz: f64, stop_hz: f64, step_hz: f64) -> PyResult<()> {
    sweep::check_range(accel_rms_g, start_hz, stop_hz, step_hz).map_err(|e| {
        arg_err(match e {
            sweep::RangeError::Ends => {
                "start_hz and stop_hz must be positive with stop_hz > start_hz"
            }
            sweep::RangeError::Step => "step_hz must be positive and not larger than the range",
            sweep::RangeError::Accel => "accel_rms_g must be a finite positive number",
        })
    })
}

/// The sweep settings of a range after its arguments are checked: the library's
/// [`SweepSettings::for_device`], the settings of the `endstop` command's sweeps.
fn sweep_settings(
    device: &Device,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
    refine_tol_hz: f64,
) -> PyResult<SweepSettings> {
    check_range(accel_rms_g, start_hz, stop_hz, step_hz)?;
    if !(refine_tol_hz.is_finite() && refine_tol_hz > 0.0) {
        return Err(arg_err("refine_tol_hz must be positive"));
    }
    let freqs = linspace_step(start_hz, stop_hz, step_hz);
    Ok(SweepSettings::for_device(device, freqs, refine_tol_hz))
}

/// Stepped-sine down-sweep from `stop_hz` to `start_hz` (each step from the previous steady
/// state) with the jump up and the first contact refined to brackets narrower than
/// `refine_tol_hz`: the down-sweep of the `endstop response` command. Keys: the per-step
/// arrays (frequencies decreasing) as in `up_sweep`, `jump_hz`, `contact_hz` (midpoints of
/// `*_bracket_hz`, or None), `jump_power_ratio`, `branch_end_hz` and `branch_end_kind`.
#[pyfunction]
#[pyo3(signature = (device, accel_rms_g, start_hz, stop_hz, step_hz = 2.0, refine_tol_hz = 0.1))]
fn down_sweep<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
    refine_tol_hz: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = sweep_settings(
        &device.inner,
        accel_rms_g,
        start_hz,
        stop_hz,
        step_hz,
        refine_tol_hz,
    )?;
    let dev = device.inner.clone();
    let report = py
        .detach(move || settings.run_down(&dev, accel_rms_g, |_| {}))
        .map_err(solver_err)?;
    let all: Vec<&Measurement> = report.measurements().collect();
    let d = steps_dict(py, &all)?;
    transition_items(&d, "jump", "hz", report.jump)?;
    d.set_item("jump_power_ratio", report.jump_power_ratio)?;
    transition_items(&d, "contact", "hz", report.contact)?;
    match report.branch_end() {
        Some((kind, t)) => {
            d.set_item("branch_end_hz", t.value())?;
            d.set_item("branch_end_kind", kind.label())?;
        }
        None => {
            d.set_item("branch_end_hz", py.None())?;
            d.set_item("branch_end_kind", py.None())?;
        }
    }
    Ok(d)
}

/// The periodic orbits continued in frequency (shooting, Floquet multipliers,
/// pseudo-arclength continuation through folds) from `start_hz` to `stop_hz` with steps of at
/// most `step_hz`: the continuation of the `endstop response` command. Keys: per-orbit arrays
/// `freq_hz`, `v1_rms_v`, `p_total_w`, `x_max_m`, `multiplier_max_abs`, `stable` (bool);
/// `events`, a list of dicts (`kind`: fold, branch point, period doubling, torus or grazing;
/// `freq_hz`, `at_grazing`, `stable_before`, `stable_after`); `folds_hz` and `grazing_hz`
/// (lists); `max_residual`.
#[pyfunction]
#[pyo3(signature = (device, accel_rms_g, start_hz, stop_hz, step_hz = 2.0))]
fn orbits<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
) -> PyResult<Bound<'py, PyDict>> {
    use endstop::study::continuation::{frequency_branch, EventKind};
    check_range(accel_rms_g, start_hz, stop_hz, step_hz)?;
    let dev = device.inner.clone();
    let branch = py
        .detach(move || frequency_branch(&dev, accel_rms_g, start_hz, stop_hz, step_hz, |_| {}))
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&endstop::study::orbit::Orbit) -> f64| {
        array(py, branch.points.iter().map(|p| f(&p.orbit)).collect())
    };
    d.set_item("freq_hz", col(&|o| o.forcing.freq_hz))?;
    d.set_item("v1_rms_v", col(&|o| o.summary.v1_rms_v))?;
    d.set_item("p_total_w", col(&|o| o.summary.p_total_w))?;
    d.set_item("x_max_m", col(&|o| o.summary.x_max_m))?;
    d.set_item("multiplier_max_abs", col(&|o| o.max_multiplier_abs()))?;
    d.set_item(
        "stable",
        branch
            .points
            .iter()
            .map(|p| p.orbit.is_stable())
            .collect::<Vec<bool>>(),
    )?;
    let events = PyList::empty(py);
    for e in &branch.events {
        let ed = PyDict::new(py);
        ed.set_item("kind", e.kind.label())?;
        ed.set_item("freq_hz", e.param)?;
        ed.set_item("at_grazing", e.at_grazing)?;
        ed.set_item("stable_before", e.stable_before)?;
        ed.set_item("stable_after", e.stable_after)?;
        events.append(ed)?;
    }
    d.set_item("events", events)?;
    let of = |k: EventKind| branch.events_of(k).map(|e| e.param).collect::<Vec<f64>>();
    d.set_item("folds_hz", of(EventKind::Fold))?;
    d.set_item("grazing_hz", of(EventKind::Grazing))?;
    d.set_item("max_residual", branch.max_residual())?;
    Ok(d)
}

fn amplitude_dict<'py>(py: Python<'py>, r: &AmplitudeReport) -> PyResult<Bound<'py, PyDict>> {
    let all: Vec<&Measurement> = r.sweep.steps.iter().map(|s| &s.measurement).collect();
    let d = steps_dict(py, &all)?;
    d.set_item("extended_from", r.extended_from)?;
    d.set_item("contact_at_start", r.contact_at_start)?;
    transition_items(&d, "onset", "g", r.onset)?;
    Ok(d)
}

/// Amplitude continuation at a fixed frequency over increasing RMS accelerations (g), each
/// step starting from the previous final state, the impact onset refined by bisection to a
/// bracket narrower than `refine_tol_g` (the study of Figure 9).
#[pyfunction]
#[pyo3(signature = (device, freq_hz, accels_rms_g, refine_tol_g = 0.005))]
fn amplitude_sweep<'py>(
    py: Python<'py>,
    device: &PyDevice,
    freq_hz: f64,
    accels_rms_g: PyReadonlyArray1<'py, f64>,
    refine_tol_g: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let acc = accels_rms_g.as_slice()?.to_vec();
    if acc.len() < 2
        || acc
            .windows(2)
            .any(|w| w[1].partial_cmp(&w[0]) != Some(std::cmp::Ordering::Greater))
        || acc[0] < 0.0
    {
        return Err(arg_err(
            "accels_rms_g must hold at least two increasing non-negative values",
        ));
    }
    if !(freq_hz.is_finite() && freq_hz > 0.0) {
        return Err(arg_err("freq_hz must be positive"));
    }
    let dev = device.inner.clone();
    let report = py
        .detach(move || {
            let cfg = steady_config(&dev, freq_hz);
            amplitude_sweep_report(&dev, freq_hz, &acc, &cfg, refine_tol_g, |_| {})
        })
        .map_err(solver_err)?;
    amplitude_dict(py, &report)
}

// ---------------------------------------------------------------------------------------------
// Random vibration

fn summary_items(d: &Bound<'_, PyDict>, s: &RecordSummary) -> PyResult<()> {
    d.set_item("p1_w", s.p1_w)?;
    d.set_item("p2_w", s.p2_w)?;
    d.set_item("p_total_w", s.p_total_w())?;
    d.set_item("x_rms_m", s.x_rms_m)?;
    d.set_item("x_peak_m", s.x_peak_m)?;
    d.set_item("contact_fraction", s.contact_fraction)?;
    d.set_item("impacts", s.impacts)?;
    d.set_item("accel_mean_square_si", s.accel_mean_square_si)?;
    Ok(())
}

fn record_spec(device: &Device, psd_g2_per_hz: f64, duration_s: f64) -> PyResult<RecordSpec> {
    if !(psd_g2_per_hz.is_finite() && psd_g2_per_hz > 0.0) {
        return Err(arg_err(
            "psd_g2_per_hz must be a positive two-sided PSD in g^2/Hz",
        ));
    }
    if !(duration_s.is_finite() && duration_s > 0.0) {
        return Err(arg_err("duration_s must be positive"));
    }
    let mut spec = RecordSpec::paper(device, psd_g2_per_hz);
    spec.noise.duration_s = duration_s;
    Ok(spec)
}

/// One random-vibration record: band-limited white noise (10 kHz band, 100 kHz sampling) of
/// two-sided level `psd_g2_per_hz` (g^2/Hz), realisation `stream` of `seed`, from rest with the
/// device's pre-roll discarded. Returns the load voltages (arrays) and the record's summary.
#[pyfunction]
#[pyo3(signature = (device, psd_g2_per_hz, seed = 2012, stream = 0, duration_s = 10.0))]
fn record<'py>(
    py: Python<'py>,
    device: &PyDevice,
    psd_g2_per_hz: f64,
    seed: u64,
    stream: u64,
    duration_s: f64,
) -> PyResult<Bound<'py, PyDict>> {
    let spec = record_spec(&device.inner, psd_g2_per_hz, duration_s)?;
    let dev = device.inner.clone();
    let rec = py
        .detach(move || simulate_record(&dev, &spec, seed, stream))
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    d.set_item("sample_rate_hz", rec.sample_rate_hz)?;
    d.set_item("v1_v", array(py, rec.v1_v))?;
    d.set_item("v2_v", array(py, rec.v2_v))?;
    summary_items(&d, &rec.summary)?;
    Ok(d)
}

/// An ensemble of independent random-vibration records (record i uses stream i of `seed`),
/// with the ensemble-mean output PSD, power, efficiency and bandwidth: the `endstop random`
/// command's study (same segmenting and analysis band).
#[pyfunction]
#[pyo3(signature = (device, psd_g2_per_hz, records = 4, duration_s = 10.0, seed = 2012))]
fn ensemble<'py>(
    py: Python<'py>,
    device: &PyDevice,
    psd_g2_per_hz: f64,
    records: usize,
    duration_s: f64,
    seed: u64,
) -> PyResult<Bound<'py, PyDict>> {
    if records == 0 {
        return Err(arg_err("records must be at least 1"));
    }
    let record = record_spec(&device.inner, psd_g2_per_hz, duration_s)?;
    let dev = device.inner.clone();
    let spec = EnsembleSpec::for_device(&dev, record, seed, records);
    let nperseg = spec.welch.nperseg;
    let ens = py
        .detach(move || run_ensemble(&dev, &spec, || {}))
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    d.set_item("nperseg", nperseg)?;
    d.set_item("power_w", ens.power_w.mean)?;
    d.set_item("power_ci95_w", ens.power_w.ci95)?;
    d.set_item("efficiency", ens.efficiency.mean)?;
    d.set_item("efficiency_ci95", ens.efficiency.ci95)?;
    d.set_item("bw3db_hz", ens.mean_widths.bw3db_hz())?;
    d.set_item("bw6db_hz", ens.mean_widths.bw6db_hz())?;
    d.set_item("x_rms_m", ens.x_rms_m.mean)?;
    d.set_item("x_peak_m", ens.x_peak_m)?;
    d.set_item("contact_fraction", ens.contact_fraction.mean)?;
    d.set_item("impacts", ens.impacts)?;
    d.set_item(
        "eq21_power_w",
        two_port::eq21_power_w(&device.inner, psd_g2_per_hz),
    )?;
    let psd = &ens.mean_spectrum.total;
    d.set_item("freq_hz", array(py, psd.freq_hz.clone()))?;
    d.set_item("out_psd_w_per_hz", array(py, psd.density.clone()))?;
    let per = PyDict::new(py);
    let recs = &ens.records;
    per.set_item(
        "stream",
        recs.iter().map(|r| r.stream).collect::<Vec<u64>>(),
    )?;
    per.set_item(
        "p_total_w",
        array(py, recs.iter().map(|r| r.summary.p_total_w()).collect()),
    )?;
    per.set_item(
        "x_rms_m",
        array(py, recs.iter().map(|r| r.summary.x_rms_m).collect()),
    )?;
    per.set_item(
        "contact_fraction",
        array(
            py,
            recs.iter().map(|r| r.summary.contact_fraction).collect(),
        ),
    )?;
    per.set_item(
        "bw3db_hz",
        array(py, recs.iter().map(|r| r.widths.bw3db_hz()).collect()),
    )?;
    d.set_item("records", per)?;
    Ok(d)
}

// ---------------------------------------------------------------------------------------------
// The paper's figures

fn claims_list<'py>(py: Python<'py>, values: &[Value]) -> PyResult<Bound<'py, PyList>> {
    let l = PyList::empty(py);
    for v in values {
        let d = PyDict::new(py);
        d.set_item("claim", &v.claim)?;
        d.set_item("quantity", &v.quantity)?;
        d.set_item("set", v.set.label())?;
        d.set_item("ours", v.ours)?;
        d.set_item("uncertainty", v.uncertainty)?;
        d.set_item("note", &v.note)?;
        l.append(d)?;
    }
    Ok(l)
}

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
        Some(d) => d.inner.clone(),
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

/// Calibrates prototype 1 (the end-stop gap fitted so that the 30 V, 5.5 g up-sweep first
/// touches a stop at the measured kink; `endstop::paper::calibration`), from `published`
/// (default: the published prototype 1).
fn calibration(published: Option<&PyDevice>) -> PyResult<(Device, Calibration)> {
    let published = match published {
        Some(d) => d.inner.clone(),
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
        Some(d) => d.inner.clone(),
        None => PyDevice::prototype(1)?.inner,
    };
    let calibrated = calibrated.map(|d| d.inner.clone());
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
        numbers.set_item("calibrated_gap_m", cal.device.geometry.endstop_gap_m)?;
    }
    out.set_item("sets", sets)?;
    out.set_item("numbers", numbers)?;
    out.set_item("claims", claims_list(py, &values)?)?;
    Ok(out)
}

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("ParamError", py.get_type::<ParamError>())?;
    m.add("SolverError", py.get_type::<SolverError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<PyDevice>()?;
    for f in [
        wrap_pyfunction!(two_port_dict, m)?,
        wrap_pyfunction!(k2, m)?,
        wrap_pyfunction!(qm, m)?,
        wrap_pyfunction!(eq21_efficiency, m)?,
        wrap_pyfunction!(eq21_power_w, m)?,
        wrap_pyfunction!(linear_output_psd, m)?,
        wrap_pyfunction!(bias_for_coupling, m)?,
        wrap_pyfunction!(up_sweep, m)?,
        wrap_pyfunction!(amplitude_sweep, m)?,
        wrap_pyfunction!(down_sweep, m)?,
        wrap_pyfunction!(orbits, m)?,
        wrap_pyfunction!(record, m)?,
        wrap_pyfunction!(ensemble, m)?,
        wrap_pyfunction!(paper_calibrate_prototype1, m)?,
        wrap_pyfunction!(paper_fig09_run, m)?,
        wrap_pyfunction!(paper_fig13_run, m)?,
    ] {
        m.add_function(f)?;
    }
    study::register(m)?;
    Ok(())
}

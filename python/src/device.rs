//! `endstop.Device`: the parameters of a device file, validated, with the published
//! prototypes the package carries.

use endstop::device::{Device, StiffnessModel};
use pyo3::prelude::*;
use pyo3::types::{PyBool, PyDict, PyFloat, PyInt, PyList, PyString};

use crate::{arg_err, param_err};

/// The published parameter files the package carries (the repository's `data/`).
const PROTOTYPE1_TOML: &str = include_str!("../../data/prototype1.toml");
const PROTOTYPE2_TOML: &str = include_str!("../../data/prototype2.toml");

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

pub(crate) fn py_to_toml(v: &Bound<'_, PyAny>, path: &str) -> PyResult<toml::Value> {
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
        let v: toml::Value =
            toml::from_str(&self.inner.to_toml_string()).map_err(|e| arg_err(e.to_string()))?;
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
        let d = endstop::paper::setups::with_endstop(&self.inner, law, damping_n_s_per_m)
            .with_tension_free(tension_free);
        d.validate("with_endstop").map_err(param_err)?;
        Ok(Self { inner: d })
    }

    /// A copy with the end-stop gap x_max (m) changed, validated.
    fn with_endstop_gap(&self, endstop_gap_m: f64) -> PyResult<Self> {
        let d = self.inner.with_stop_gap(endstop_gap_m);
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

    /// Bias voltage (V) of an electrostatic transducer; None for the others.
    #[getter]
    fn bias_v(&self) -> Option<f64> {
        self.inner.bias_v()
    }

    fn __repr__(&self) -> String {
        format!(
            "Device(name={:?}, params={:?}, transducer={:?})",
            self.inner.name,
            self.inner.params,
            self.inner.transducer.key()
        )
    }

    fn __eq__(&self, other: &Self) -> bool {
        self.inner == other.inner
    }
}

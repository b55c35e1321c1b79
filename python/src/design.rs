//! `endstop.design`: the designer's inverse question ([`endstop::design`]), the twin of the
//! `endstop design` command: the same problem built by [`Problem::new`] from the same inputs
//! (ranges of device keys, interfaces by name or as tables, frequencies, acceleration,
//! limits, or a noise objective in place of the sines) and solved by [`Problem::solve`] with
//! the GIL released, the answer under noise confirmed on fresh records by [`Problem::confirm`];
//! the answer as a dict with every evaluated design as numpy arrays. A measured record in
//! place of the sines is checked and resampled by the library's [`MeasuredRecord`], as the
//! command's `--accel-file` is, and designed over by [`Problem::under_record`].

use endstop::design::{
    interfaces, Answer, DesignError, Evaluated, Limits, NoiseObjective, Problem, RecordObjective,
    SearchSettings, Study, Verdict, Vibration, LIMIT_NAMES,
};
use endstop::device::{Interface, ParamRange, Spacing};
use endstop::drive::measured::MeasuredRecord;
use endstop::progress::Silent;
use numpy::{PyArray1, PyReadonlyArray1};
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList, PyString};

use crate::device::py_to_toml;
use crate::{arg_err, array, param_err, solver_err, ParamError, PyDevice};

/// The library's errors as the package's: a parameter, range or interface table that does
/// not fit the device raises `ParamError` (naming the field), a design that no evaluation
/// reached `SolverError`, a malformed problem or search setting `ValueError`.
fn design_err(e: DesignError) -> PyErr {
    match e {
        DesignError::Range { interface, error } => {
            let field = error.field().map(str::to_string);
            let err = ParamError::new_err(format!("interface `{interface}`: {error}"));
            Python::attach(|py| {
                let _ = err.value(py).setattr("field", field);
            });
            err
        }
        DesignError::Interface(error) => param_err(error),
        e @ DesignError::NoEvaluation(_) => solver_err(e),
        e => arg_err(e.to_string()),
    }
}

/// A range from `(path, lo, hi)` or `(path, lo, hi, spacing)`, spacing `"log"` or `"linear"`
/// (without it, as the command's `PATH=LO..HI`: [`Spacing::auto`]).
fn range_of(r: &Bound<'_, PyAny>) -> PyResult<ParamRange> {
    let (path, lo, hi, spacing): (String, f64, f64, Option<String>) =
        if let Ok((p, lo, hi)) = r.extract::<(String, f64, f64)>() {
            (p, lo, hi, None)
        } else {
            r.extract::<(String, f64, f64, String)>()
                .map(|(p, lo, hi, s)| (p, lo, hi, Some(s)))
                .map_err(|_| {
                    arg_err("a range is (path, lo, hi) or (path, lo, hi, \"log\" | \"linear\")")
                })?
        };
    let spacing = match spacing.as_deref() {
        None => Spacing::auto(lo, hi),
        Some("log") => Spacing::Log,
        Some("linear") => Spacing::Linear,
        Some(other) => {
            return Err(arg_err(format!(
                "range `{path}`: spacing `{other}` must be \"log\" or \"linear\""
            )))
        }
    };
    ParamRange::new(&path, lo, hi, spacing).map_err(param_err)
}

/// The interfaces: each a name (`"resistive"` or the device's own interface's key) or a dict
/// in a device file's `[interface]` form; none: the device's own interface.
fn interfaces_of(device: &PyDevice, list: Option<&Bound<'_, PyList>>) -> PyResult<Vec<Interface>> {
    let Some(list) = list else {
        return Ok(vec![device.inner.interface.clone()]);
    };
    let mut out = Vec::new();
    for (i, item) in list.iter().enumerate() {
        if item.is_instance_of::<PyString>() {
            let name: String = item.extract()?;
            out.push(interfaces::by_name(&device.inner, &name).map_err(design_err)?);
        } else if let Ok(d) = item.cast::<PyDict>() {
            let toml::Value::Table(t) = py_to_toml(d.as_any(), "interface")? else {
                return Err(arg_err("an interface dict must be a table"));
            };
            let source = format!("interfaces[{i}]");
            out.extend(interfaces::from_tables(&device.inner, &[t], &source).map_err(design_err)?);
        } else {
            return Err(arg_err(format!(
                "interfaces[{i}]: a name (str) or a device file's [interface] (dict), not {}",
                item.get_type().name()?
            )));
        }
    }
    Ok(out)
}

fn bool_array<'py>(py: Python<'py>, v: Vec<bool>) -> Bound<'py, PyArray1<bool>> {
    PyArray1::from_vec(py, v)
}

/// One design as a dict: its interface, parameter values, power and limits reached, the
/// violation and the margins on the limits.
fn design_dict<'py>(
    py: Python<'py>,
    p: &Problem,
    e: &Evaluated,
    verdict: Option<Verdict>,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    if let Some(v) = verdict {
        d.set_item(
            "verdict",
            match v {
                Verdict::Optimum => "optimum",
                Verdict::Infeasible => "infeasible",
            },
        )?;
    }
    d.set_item("interface", p.interfaces[e.interface].key())?;
    d.set_item("interface_index", e.interface)?;
    let params = PyDict::new(py);
    for (r, v) in p.ranges.iter().zip(&e.values) {
        params.set_item(&r.path, v)?;
    }
    d.set_item("params", params)?;
    d.set_item("unit", e.unit.clone())?;
    d.set_item("feasible", e.feasible())?;
    d.set_item("violation", e.violation)?;
    let margins = PyDict::new(py);
    match &e.result {
        Ok(q) => {
            d.set_item("power_w", q.power_w)?;
            d.set_item("worst_freq_hz", q.worst_freq_hz)?;
            d.set_item("best_power_w", q.best_power_w)?;
            d.set_item("impact_speed_m_s", q.impact_speed_m_s)?;
            d.set_item("contact_force_n", q.contact_force_n)?;
            d.set_item("displacement_m", q.displacement_m)?;
            d.set_item("impacts_per_s", q.impacts_per_s)?;
            for (name, m) in LIMIT_NAMES.iter().zip(p.limits.margins(q)) {
                if let Some(m) = m {
                    margins.set_item(name, m)?;
                }
            }
            d.set_item("error", py.None())?;
        }
        Err(why) => d.set_item("error", why)?,
    }
    d.set_item("margins", margins)?;
    Ok(d)
}

/// Every evaluated design as columns: numpy arrays of numbers and flags, lists of strings.
fn designs_dict<'py>(
    py: Python<'py>,
    p: &Problem,
    evals: &[Evaluated],
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    let perf = |f: fn(&endstop::design::Performance) -> f64| {
        array(
            py,
            evals
                .iter()
                .map(|e| e.result.as_ref().map_or(f64::NAN, f))
                .collect(),
        )
    };
    d.set_item(
        "interface",
        evals
            .iter()
            .map(|e| p.interfaces[e.interface].key())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "interface_index",
        PyArray1::from_vec(py, evals.iter().map(|e| e.interface as i64).collect()),
    )?;
    for (k, r) in p.ranges.iter().enumerate() {
        d.set_item(
            &r.path,
            array(py, evals.iter().map(|e| e.values[k]).collect()),
        )?;
    }
    d.set_item(
        "evaluated",
        bool_array(py, evals.iter().map(|e| e.result.is_ok()).collect()),
    )?;
    d.set_item(
        "feasible",
        bool_array(py, evals.iter().map(Evaluated::feasible).collect()),
    )?;
    d.set_item(
        "violation",
        array(py, evals.iter().map(|e| e.violation).collect()),
    )?;
    d.set_item("power_w", perf(|q| q.power_w))?;
    d.set_item("worst_freq_hz", perf(|q| q.worst_freq_hz))?;
    d.set_item("impact_speed_m_s", perf(|q| q.impact_speed_m_s))?;
    d.set_item("contact_force_n", perf(|q| q.contact_force_n))?;
    d.set_item("displacement_m", perf(|q| q.displacement_m))?;
    d.set_item("impacts_per_s", perf(|q| q.impacts_per_s))?;
    d.set_item(
        "error",
        evals
            .iter()
            .map(|e| e.result.as_ref().err().cloned().unwrap_or_default())
            .collect::<Vec<_>>(),
    )?;
    Ok(d)
}

fn answer_dict<'py>(py: Python<'py>, p: &Problem, a: &Answer) -> PyResult<Bound<'py, PyDict>> {
    design_dict(py, p, &a.design, Some(a.verdict))
}

/// The most samples a resampled record may have (as the command's).
const MAX_RESAMPLED: usize = 1 << 27;

/// The measured record of `accel_m_s2` (m/s^2) sampled at `sample_rate_hz`, checked and
/// resampled to `integrator_rate_hz` (default: its own rate) by [`MeasuredRecord`], as the
/// command reads and resamples `--accel-file` to `--sample-rate-hz`; none without a record.
fn record_of(
    accel_m_s2: Option<PyReadonlyArray1<'_, f64>>,
    sample_rate_hz: Option<f64>,
    integrator_rate_hz: Option<f64>,
) -> PyResult<Option<RecordObjective>> {
    let (accel, fs) = match (accel_m_s2, sample_rate_hz) {
        (None, None) if integrator_rate_hz.is_none() => return Ok(None),
        (None, _) => {
            return Err(arg_err(
                "sample_rate_hz and integrator_rate_hz describe a measured record: give \
                 accel_m_s2 with them",
            ))
        }
        (Some(_), None) => {
            return Err(arg_err(
                "accel_m_s2 needs its sample_rate_hz (Hz): the record's samples are at \
                 t = k / sample_rate_hz",
            ))
        }
        (Some(a), Some(fs)) => (a.as_array().to_vec(), fs),
    };
    // The library names the source (`accel_m_s2`), the field, the sample and the value.
    let rec = MeasuredRecord::from_uniform("accel_m_s2", fs, accel)
        .map_err(|e| arg_err(e.to_string()))?;
    let rate = integrator_rate_hz.unwrap_or(fs);
    if !(rate.is_finite() && rate > 0.0) {
        return Err(arg_err(format!(
            "integrator_rate_hz = {rate}: must be finite and > 0"
        )));
    }
    let samples = rec.duration_s() * rate;
    if samples > MAX_RESAMPLED as f64 {
        return Err(arg_err(format!(
            "integrator_rate_hz = {rate} gives {samples:.0} samples over the record's {} s: \
             must give at most {MAX_RESAMPLED}",
            rec.duration_s()
        )));
    }
    Ok(Some(RecordObjective::new(rec.resampled(rate), rate)))
}

/// The sines of a problem, its noise objective (`psd_g2_per_hz` given, in place of the
/// frequencies and the acceleration, as the command's `--psd`: what the command's
/// `NoiseArgs::objective` builds, with the pre-roll left to [`Problem::under_noise`]), or its
/// measured record (`accel_m_s2` given, as the command's `--accel-file`, the pre-roll left to
/// [`Problem::under_record`]).
struct Excitation {
    freqs_hz: Option<Vec<f64>>,
    accel_rms_g: Option<f64>,
    noise: Option<NoiseObjective>,
    record: Option<RecordObjective>,
}

impl Excitation {
    fn problem(
        self,
        device: &PyDevice,
        interfaces: Vec<Interface>,
        ranges: Vec<ParamRange>,
        limits: Limits,
    ) -> PyResult<Problem> {
        let dev = device.inner.clone();
        if let Some(r) = self.record {
            if self.noise.is_some() {
                return Err(arg_err(
                    "give a noise (psd_g2_per_hz) or a measured record (accel_m_s2), not both",
                ));
            }
            if self.freqs_hz.is_some() || self.accel_rms_g.is_some() {
                return Err(arg_err(
                    "accel_m_s2 replaces freqs_hz and accel_rms_g: give the record or the sines",
                ));
            }
            return Problem::under_record(dev, interfaces, ranges, r, limits).map_err(design_err);
        }
        match (self.noise, self.freqs_hz, self.accel_rms_g) {
            (Some(n), None, None) => {
                n.check().map_err(|e| {
                    arg_err(format!(
                        "psd_g2_per_hz, records, duration_s, noise_band_hz, noise_seed: {e}"
                    ))
                })?;
                Problem::under_noise(dev, interfaces, ranges, n, limits)
            }
            (Some(_), _, _) => {
                return Err(arg_err(
                    "psd_g2_per_hz replaces freqs_hz and accel_rms_g: give the noise or the sines",
                ))
            }
            (None, Some(freqs_hz), Some(accel_rms_g)) => Problem::new(
                dev,
                interfaces,
                ranges,
                Vibration {
                    freqs_hz,
                    accel_rms_g,
                },
                limits,
            ),
            (None, _, _) => {
                return Err(arg_err(
                    "give freqs_hz and accel_rms_g (sines), psd_g2_per_hz (noise) or accel_m_s2 \
                     (a measured record)",
                ))
            }
        }
        .map_err(design_err)
    }
}

/// Solves a design problem by the library's search; see `endstop.design.design`.
#[pyfunction]
#[pyo3(name = "design")]
#[pyo3(signature = (device, ranges, freqs_hz = None, accel_rms_g = None, interfaces = None,
    max_impact_speed_m_s = None, max_contact_force_n = None, max_displacement_m = None,
    max_impacts_per_s = None, samples = 32, seed = 0, psd_g2_per_hz = None, records = 8,
    duration_s = 2.0, noise_band_hz = 10e3, noise_seed = 2012, accel_m_s2 = None,
    sample_rate_hz = None, integrator_rate_hz = None))]
#[allow(clippy::too_many_arguments)]
fn design_py<'py>(
    py: Python<'py>,
    device: &PyDevice,
    ranges: Vec<Bound<'py, PyAny>>,
    freqs_hz: Option<Vec<f64>>,
    accel_rms_g: Option<f64>,
    interfaces: Option<Bound<'py, PyList>>,
    max_impact_speed_m_s: Option<f64>,
    max_contact_force_n: Option<f64>,
    max_displacement_m: Option<f64>,
    max_impacts_per_s: Option<f64>,
    samples: usize,
    seed: u32,
    psd_g2_per_hz: Option<f64>,
    records: u64,
    duration_s: f64,
    noise_band_hz: f64,
    noise_seed: u64,
    accel_m_s2: Option<PyReadonlyArray1<'py, f64>>,
    sample_rate_hz: Option<f64>,
    integrator_rate_hz: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let record = record_of(accel_m_s2, sample_rate_hz, integrator_rate_hz)?;
    let ranges = ranges.iter().map(range_of).collect::<PyResult<Vec<_>>>()?;
    let interfaces = interfaces_of(device, interfaces.as_ref())?;
    let excitation = Excitation {
        freqs_hz,
        accel_rms_g,
        noise: psd_g2_per_hz.map(|psd| NoiseObjective {
            psd_g2_per_hz: psd,
            bandwidth_hz: noise_band_hz,
            records,
            duration_s,
            seed: noise_seed,
            transient_s: 0.0,
        }),
        record,
    };
    let limits = Limits {
        impact_speed_m_s: max_impact_speed_m_s,
        contact_force_n: max_contact_force_n,
        displacement_m: max_displacement_m,
        impacts_per_s: max_impacts_per_s,
    };
    let p = excitation.problem(device, interfaces, ranges, limits)?;
    let settings = SearchSettings {
        samples,
        seed,
        ..SearchSettings::default()
    };
    let (study, confirmed) = py
        .detach(|| -> Result<_, DesignError> {
            let study: Study = p.solve(&settings, &Silent)?;
            let fresh = p.noise.as_ref().and_then(NoiseObjective::fresh_seed);
            let confirmed = fresh
                .and_then(|f| p.confirm(&study.answer.design, f))
                .transpose()?;
            Ok((study, fresh.zip(confirmed)))
        })
        .map_err(design_err)?;
    let d = PyDict::new(py);
    d.set_item("best", answer_dict(py, &p, &study.answer)?)?;
    let per = PyList::empty(py);
    for a in &study.per_interface {
        match a {
            Some(a) => per.append(answer_dict(py, &p, a)?)?,
            None => per.append(py.None())?,
        }
    }
    d.set_item("per_interface", per)?;
    d.set_item("designs", designs_dict(py, &p, &study.evaluations)?)?;
    d.set_item(
        "interfaces",
        p.interfaces.iter().map(Interface::key).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "ranges",
        p.ranges.iter().map(|r| r.path.clone()).collect::<Vec<_>>(),
    )?;
    d.set_item("samples", settings.samples)?;
    d.set_item("seed", settings.seed)?;
    d.set_item("polish_starts", settings.polish_starts)?;
    d.set_item("max_iters", settings.max_iters)?;
    d.set_item(
        "budget",
        settings.budget(p.interfaces.len(), p.ranges.len()),
    )?;
    d.set_item("evaluations", study.evaluations.len())?;
    // Under noise, the answer measured again on fresh records (the command's
    // `power_confirmed_w` and `power_confirmed_ci95_w`); None under sines.
    d.set_item("power_confirmed_w", confirmed.map(|(_, c)| c.mean))?;
    d.set_item("power_confirmed_ci95_w", confirmed.map(|(_, c)| c.ci95))?;
    d.set_item("confirm_seed", confirmed.map(|(s, _)| s))?;
    d.set_item("settings", settings_dict(py, &p, &settings)?)?;
    Ok(d)
}

/// What repeats the run besides the device, as the `settings` of the command's
/// `summary.json`: the vibration, the limits, the search's settings (its seed among them) and
/// the steady state's.
fn settings_dict<'py>(
    py: Python<'py>,
    p: &Problem,
    search: &SearchSettings,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("freqs_hz", p.vibration.freqs_hz.clone())?;
    // Under noise or a record there is no sine: None, as the command records an acceleration
    // not given.
    d.set_item(
        "accel_rms_g",
        Some(p.vibration.accel_rms_g).filter(|_| p.noise.is_none() && p.record.is_none()),
    )?;
    d.set_item("noise", p.noise.map(|n| noise_dict(py, &n)).transpose()?)?;
    d.set_item(
        "record",
        p.record.as_ref().map(|r| record_dict(py, r)).transpose()?,
    )?;
    let limits = PyDict::new(py);
    let l = &p.limits;
    for (name, v) in LIMIT_NAMES.iter().zip([
        l.impact_speed_m_s,
        l.contact_force_n,
        l.displacement_m,
        l.impacts_per_s,
    ]) {
        limits.set_item(name, v)?;
    }
    d.set_item("limits", limits)?;
    let s = PyDict::new(py);
    s.set_item("samples", search.samples)?;
    s.set_item("polish_starts", search.polish_starts)?;
    s.set_item("max_iters", search.max_iters)?;
    s.set_item("simplex_size", search.simplex_size)?;
    s.set_item("sd_tolerance", search.sd_tolerance)?;
    s.set_item("seed", search.seed)?;
    d.set_item("search", s)?;
    let st = &p.steady;
    let s = PyDict::new(py);
    s.set_item("rtol", st.rtol)?;
    s.set_item("transient_periods", st.transient_periods)?;
    s.set_item("max_newton", st.max_newton)?;
    s.set_item("tol", st.tol)?;
    s.set_item("jacobian", format!("{:?}", st.jacobian))?;
    s.set_item("max_map_periods", st.max_map_periods)?;
    d.set_item("steady", s)?;
    Ok(d)
}

/// The noise objective as the command's `summary.json` records it (its `settings.noise`), the
/// pre-roll as the problem set it.
fn noise_dict<'py>(py: Python<'py>, n: &NoiseObjective) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("psd_g2_per_hz", n.psd_g2_per_hz)?;
    d.set_item("bandwidth_hz", n.bandwidth_hz)?;
    d.set_item("records", n.records)?;
    d.set_item("duration_s", n.duration_s)?;
    d.set_item("seed", n.seed)?;
    d.set_item("transient_s", n.transient_s)?;
    Ok(d)
}

/// The measured record as the problem holds it: the integrator's rate, its samples at that
/// rate, the pre-roll the problem set and the analysed stretch after it (the command's
/// `record_sample_rate_hz` and `record_transient_s`).
fn record_dict<'py>(py: Python<'py>, r: &RecordObjective) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("sample_rate_hz", r.sample_rate_hz)?;
    d.set_item("samples", r.accel_m_s2.len())?;
    d.set_item("transient_s", r.transient_s)?;
    d.set_item("analysed_s", r.analysed_s())?;
    Ok(d)
}

pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_function(wrap_pyfunction!(design_py, m)?)
}

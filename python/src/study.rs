//! `endstop.study`: simulations of the nonlinear model (eqs 1-10): frequency sweeps up and
//! down, the continuation of periodic orbits, amplitude sweeps, one random record and an
//! ensemble, each returning a dict of numbers and numpy arrays with the GIL released while it
//! runs.

use endstop::device::Device;
use endstop::drive::swept_sine_samples;
use endstop::paper::setups::paper_record;
use endstop::physics::linear::white_noise_power_w;
use endstop::physics::two_port::{self, TwoPort};
use endstop::progress::Silent;
use endstop::study::amplitude::{amplitude_sweep_report, AmplitudeReport};
use endstop::study::random::{random_ensemble, RandomEnsemble};
use endstop::study::record::{
    simulate_drive, simulate_record, transient_s, RecordSpec, RecordSummary, SampledDrive, Scheme,
    DEFAULT_RTOL,
};
use endstop::study::steady::{settle_settings, Measurement};
use endstop::study::stepped::{linspace_step, Approach, Transition};
use endstop::study::sweep::{self, SweepReport, SweepSettings};
use endstop::G;
use numpy::PyReadonlyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::storage::storage_ensemble_dict;
use crate::{arg_err, array, solver_err, PyDevice};

// ---------------------------------------------------------------------------------------------
// Sweeps

/// Per-step columns of a continuation, as numpy arrays.
pub(crate) fn steps_dict<'py>(
    py: Python<'py>,
    steps: &[&Measurement],
) -> PyResult<Bound<'py, PyDict>> {
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
pub(crate) fn sweep_dict<'py>(py: Python<'py>, r: &SweepReport) -> PyResult<Bound<'py, PyDict>> {
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
#[pyo3(signature = (device, accel_rms_g, start_hz, stop_hz, step_hz = 2.0, refine_tol_hz = 0.1, ramp_rate_hz_per_s = None))]
#[allow(clippy::too_many_arguments)]
fn up_sweep<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
    refine_tol_hz: f64,
    ramp_rate_hz_per_s: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = sweep_settings(
        &device.inner,
        accel_rms_g,
        start_hz,
        stop_hz,
        step_hz,
        refine_tol_hz,
    )?;
    let approach = approach(ramp_rate_hz_per_s)?;
    let dev = device.inner.clone();
    let report = py
        .detach(move || settings.run_with(&dev, accel_rms_g, approach, &Silent))
        .map_err(solver_err)?;
    sweep_dict(py, &report)
}

/// How a sweep's steps are reached: at once (`None`, as the paper's figures and the
/// `endstop` command's `--steps-at-once`), or by a phase-continuous ramp at this rate (Hz/s,
/// as its `--ramp-rate`).
fn approach(ramp_rate_hz_per_s: Option<f64>) -> PyResult<Approach> {
    match ramp_rate_hz_per_s {
        None => Ok(Approach::Jump),
        Some(r) if r.is_finite() && r > 0.0 => Ok(Approach::Ramp { rate_per_s: r }),
        Some(r) => Err(arg_err(format!(
            "ramp_rate_hz_per_s must be a finite positive rate in Hz/s, not {r}"
        ))),
    }
}

/// Checks the arguments shared by the frequency studies ([`sweep::check_range`]), naming
/// them as this module does.
fn check_range(accel_rms_g: f64, start_hz: f64, stop_hz: f64, step_hz: f64) -> PyResult<()> {
    sweep::check_range(accel_rms_g, start_hz, stop_hz, step_hz).map_err(|e| {
        arg_err(match e {
            sweep::RangeError::Ends => {
                "start_hz and stop_hz must be positive with stop_hz > start_hz"
            }
            sweep::RangeError::Step => {
                "step_hz must be positive, not larger than the range, and give at most 100000 steps"
            }
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
#[pyo3(signature = (device, accel_rms_g, start_hz, stop_hz, step_hz = 2.0, refine_tol_hz = 0.1, ramp_rate_hz_per_s = None))]
#[allow(clippy::too_many_arguments)]
fn down_sweep<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_rms_g: f64,
    start_hz: f64,
    stop_hz: f64,
    step_hz: f64,
    refine_tol_hz: f64,
    ramp_rate_hz_per_s: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    let settings = sweep_settings(
        &device.inner,
        accel_rms_g,
        start_hz,
        stop_hz,
        step_hz,
        refine_tol_hz,
    )?;
    let approach = approach(ramp_rate_hz_per_s)?;
    let dev = device.inner.clone();
    let report = py
        .detach(move || settings.run_down_with(&dev, accel_rms_g, approach, &Silent))
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
/// most `step_hz`, for any device (a circuit's switchings are events of the orbit like its
/// impacts): the continuation of the `endstop response` command. Keys: per-orbit arrays
/// `freq_hz`, `v1_rms_v` and `v1_mean_v` (the RMS and the mean of the model's first output:
/// load 1's voltage, or behind a circuit the storage voltage), `p_total_w` (the mean power of
/// the loads on the outputs: behind a circuit, the DC load's), `x_max_m`,
/// `multiplier_max_abs`, `stable` (bool);
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
        .detach(move || frequency_branch(&dev, accel_rms_g, start_hz, stop_hz, step_hz, &Silent))
        .map_err(solver_err)?;
    let d = PyDict::new(py);
    let col = |f: &dyn Fn(&endstop::study::orbit::Orbit) -> f64| {
        array(py, branch.points.iter().map(|p| f(&p.orbit)).collect())
    };
    d.set_item("freq_hz", col(&|o| o.forcing.freq_hz))?;
    d.set_item("v1_rms_v", col(&|o| o.summary.v1_rms_v))?;
    d.set_item(
        "v1_mean_v",
        col(&|o| o.summary.outputs.first().map_or(0.0, |s| s.mean)),
    )?;
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

pub(crate) fn amplitude_dict<'py>(
    py: Python<'py>,
    r: &AmplitudeReport,
) -> PyResult<Bound<'py, PyDict>> {
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
            let cfg = settle_settings(&dev, freq_hz);
            amplitude_sweep_report(&dev, freq_hz, &acc, &cfg, refine_tol_g, &Silent)
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
    let mut spec = paper_record(device, psd_g2_per_hz);
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
    let mut rec = py
        .detach(move || simulate_record(&dev, &spec, seed, stream))
        .map_err(solver_err)?;
    let [v1, v2] = rec.take_pair();
    let d = PyDict::new(py);
    d.set_item("sample_rate_hz", rec.sample_rate_hz)?;
    d.set_item("v1_v", array(py, v1))?;
    d.set_item("v2_v", array(py, v2))?;
    summary_items(&d, &rec.summary)?;
    Ok(d)
}

/// One record under a sine, `a(t) = accel_g g sin(2 pi freq_hz t)` from rest, sampled at
/// `sample_rate_hz`: the device's pre-roll, discarded, then `duration_s` analysed, as
/// `endstop random --sine-g`; with `chirp_to_hz`, swept linearly from `freq_hz` to it over the
/// analysed time at a continuous phase (`--chirp-to-hz`). Returns what [`record`] returns.
#[pyfunction]
#[pyo3(signature = (device, accel_g, freq_hz, duration_s = 10.0, sample_rate_hz = 100e3, chirp_to_hz = None))]
fn sine_record<'py>(
    py: Python<'py>,
    device: &PyDevice,
    accel_g: f64,
    freq_hz: f64,
    duration_s: f64,
    sample_rate_hz: f64,
    chirp_to_hz: Option<f64>,
) -> PyResult<Bound<'py, PyDict>> {
    if !(accel_g.is_finite() && freq_hz.is_finite() && freq_hz > 0.0) {
        return Err(arg_err("accel_g must be finite and freq_hz positive"));
    }
    let to_hz = chirp_to_hz.unwrap_or(freq_hz);
    if !(to_hz.is_finite() && to_hz > 0.0) {
        return Err(arg_err("chirp_to_hz must be positive"));
    }
    if !(duration_s.is_finite() && duration_s > 0.0) {
        return Err(arg_err("duration_s must be positive"));
    }
    if !(sample_rate_hz.is_finite() && sample_rate_hz > 0.0) {
        return Err(arg_err("sample_rate_hz must be positive"));
    }
    let dev = device.inner.clone();
    let n_tr = (transient_s(&dev) * sample_rate_hz).round() as usize;
    let n = n_tr + (duration_s * sample_rate_hz).round() as usize;
    let drive = SampledDrive {
        accel: swept_sine_samples(accel_g * G, freq_hz, to_hz, sample_rate_hz, n_tr, n).into(),
        sample_rate_hz,
        transient_samples: n_tr,
    };
    let mut rec = py
        .detach(move || simulate_drive(&dev, &drive, DEFAULT_RTOL, Scheme::Exponential))
        .map_err(solver_err)?;
    let [v1, v2] = rec.take_pair();
    let d = PyDict::new(py);
    d.set_item("sample_rate_hz", rec.sample_rate_hz)?;
    d.set_item("v1_v", array(py, v1))?;
    d.set_item("v2_v", array(py, v2))?;
    summary_items(&d, &rec.summary)?;
    Ok(d)
}

/// An ensemble of independent random-vibration records (record i uses stream i of `seed`) of
/// any device, reported as the `endstop random` command reports it: for a transducer with its
/// own loads, the ensemble-mean output PSD, power, efficiency and bandwidth (same segmenting
/// and analysis band); for a model with a storage (behind an interface circuit), its DC power,
/// the drive's power, their ratio, the storage voltage and the energy ledger of each record
/// ([`crate::storage::storage_ensemble_dict`]). The records and what they report are the
/// library's one random path (`endstop::study::random`), the command's too.
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
    let band_hz = record.noise.bandwidth_hz;
    let preroll_s = record.transient_s;
    let ens = match py
        .detach(move || random_ensemble(&dev, &record, seed, records, &Silent))
        .map_err(solver_err)?
    {
        RandomEnsemble::Output(ens) => ens,
        RandomEnsemble::Storage(ens) => return storage_ensemble_dict(py, &ens, preroll_s),
    };
    let nperseg = ens.spec.welch.nperseg;
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
    // Eq 21 is a capacitor pair's theory (None for another transducer); the linearised
    // model's power over the record's band is every device's.
    d.set_item(
        "eq21_power_w",
        TwoPort::try_of(&device.inner)
            .map(|_| two_port::eq21_power_w(&device.inner, psd_g2_per_hz)),
    )?;
    d.set_item(
        "linear_power_w",
        white_noise_power_w(&device.inner, psd_g2_per_hz * G * G, 1e-3, band_hz),
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

/// Adds the module's functions to `_native`.
pub(crate) fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for f in [
        wrap_pyfunction!(up_sweep, m)?,
        wrap_pyfunction!(amplitude_sweep, m)?,
        wrap_pyfunction!(down_sweep, m)?,
        wrap_pyfunction!(orbits, m)?,
        wrap_pyfunction!(record, m)?,
        wrap_pyfunction!(sine_record, m)?,
        wrap_pyfunction!(ensemble, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}

//! "Why the paper deviates" (`endstop::paper::deviations`) in pieces a cluster can schedule: the
//! Saltelli design, one point's evaluation, the indices from the evaluations, the calibration's
//! starts, one start's search, and the calibration from the starts' fits. Each piece is the
//! library's own function (`sobol` and `calibrate` are the same pieces run in one process), so
//! a study spread over Dask workers gives the numbers `just deviations` gives.
//!
//! Evaluations travel as plain dicts (`claim`, `quantity`, `paper`, `tolerance`, `unit`,
//! `outcome`, `value`, `deviation`, `meets`, `kind`), which pickle; on the way back only `claim`, `quantity`, `outcome` and
//! `value` are read and the rest is recomputed from the claims file.

use endstop::device::Device;
use endstop::num::minimax::{Fit, MinimaxSettings};
use endstop::paper::claims::{Claims, Kind};
use endstop::paper::deviations::{
    self, DeviationsError, Evaluation, Outcome, Prototype, Scope, SobolDesign, STUDY_BOOTSTRAP,
    STUDY_SEED,
};
use endstop::paper::deviations::{Ranges, RangesFile};
use numpy::PyArray2;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};

use crate::{arg_err, solver_err, PyDevice};

fn prototype(key: &str) -> PyResult<Prototype> {
    Prototype::BOTH
        .into_iter()
        .find(|p| p.key() == key)
        .ok_or_else(|| arg_err(format!("prototype = {key:?}: must be \"p1\" or \"p2\"")))
}

/// The published device of a prototype, its ranges and the claims file.
fn inputs(p: Prototype) -> PyResult<(Device, Ranges, Claims)> {
    let ranges = RangesFile::bundled().map_err(solver_err)?;
    let (n, r) = match p {
        Prototype::P1 => (1, ranges.prototype1),
        Prototype::P2 => (2, ranges.prototype2),
    };
    Ok((
        PyDevice::prototype(n)?.inner,
        r,
        Claims::bundled().map_err(solver_err)?,
    ))
}

fn scope(ensemble_records: Option<usize>) -> PyResult<Scope> {
    if ensemble_records == Some(0) {
        return Err(arg_err(
            "ensemble_records = 0: must be at least 1 (or None)",
        ));
    }
    Ok(Scope { ensemble_records })
}

/// The factors' names (both prototypes have the same, in the same order).
fn factor_names() -> PyResult<Vec<String>> {
    let ranges = RangesFile::bundled().map_err(solver_err)?;
    Ok(ranges
        .prototype1
        .names()
        .iter()
        .map(|n| n.to_string())
        .collect())
}

fn design(base_rows: usize, seed: u32, scope: Scope) -> PyResult<SobolDesign> {
    Ok(SobolDesign {
        factors: factor_names()?.len(),
        base_rows,
        seed,
        bootstrap: STUDY_BOOTSTRAP,
        scope,
    })
}

fn err(e: DeviationsError) -> PyErr {
    match e {
        DeviationsError::Ranges(_)
        | DeviationsError::Evaluations(_)
        | DeviationsError::Sensitivity(_) => arg_err(e.to_string()),
        e => solver_err(e),
    }
}

fn kind_label(k: Kind) -> &'static str {
    match k {
        Kind::Quantitative => "quantitative",
        Kind::Qualitative => "yes/no",
    }
}

fn evaluation_dict<'py>(
    py: Python<'py>,
    e: &Evaluation,
    claims: &Claims,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("claim", e.quantity.claim)?;
    d.set_item("quantity", e.quantity.quantity)?;
    let c = claims
        .get(e.quantity.claim, e.quantity.quantity)
        .ok_or_else(|| {
            solver_err(DeviationsError::UnknownClaim(
                e.quantity.claim,
                e.quantity.quantity,
            ))
        })?;
    d.set_item("paper", c.paper.to_f64())?;
    d.set_item("tolerance", c.tolerance())?;
    d.set_item("unit", &c.unit)?;
    d.set_item("outcome", e.outcome.label())?;
    d.set_item("value", e.value)?;
    d.set_item("deviation", e.deviation)?;
    d.set_item("meets", e.meets)?;
    d.set_item("kind", kind_label(e.kind))?;
    d.set_item("ci95", e.ci95)?;
    Ok(d)
}

fn evaluations_list<'py>(
    py: Python<'py>,
    es: &[Evaluation],
    claims: &Claims,
) -> PyResult<Bound<'py, PyList>> {
    let l = PyList::empty(py);
    for e in es {
        l.append(evaluation_dict(py, e, claims)?)?;
    }
    Ok(l)
}

/// The value of `key` in a dict of kind `what`, extracted; a named error if it is missing.
fn field<'py, T: FromPyObjectOwned<'py>>(
    d: &Bound<'py, PyDict>,
    what: &str,
    key: &str,
) -> PyResult<T> {
    d.get_item(key)?
        .ok_or_else(|| arg_err(format!("{what} dict lacks the key {key:?}")))?
        .extract()
        .map_err(Into::into)
}

/// An evaluation dict back into the library's evaluation, renormalised by the claims file.
fn evaluation_of(p: Prototype, d: &Bound<'_, PyDict>, claims: &Claims) -> PyResult<Evaluation> {
    let get = |k: &str| field::<String>(d, "an evaluation", k);
    let (claim, quantity, label) = (get("claim")?, get("quantity")?, get("outcome")?);
    let value: f64 = field(d, "an evaluation", "value")?;
    let qty = p.quantity(&claim, &quantity).ok_or_else(|| {
        arg_err(format!(
            "({claim}, {quantity}) is not a quantity of the study of {}",
            p.key()
        ))
    })?;
    let outcome = Outcome::from_label(&label, value)
        .ok_or_else(|| arg_err(format!("outcome = {label:?} is not an outcome label")))?;
    // A dict without "ci95" (or with None or NaN there, as a data frame stores it) has no
    // interval.
    let ci95: Option<f64> = match d.get_item("ci95")? {
        Some(v) => v.extract()?,
        None => None,
    };
    Ok(deviations::normalise(&qty, outcome, claims)
        .map_err(err)?
        .with_ci95(ci95.filter(|c| c.is_finite())))
}

/// The keys of the uncertain factors, in the order of a point's coordinates.
#[pyfunction]
fn paper_deviations_factors() -> PyResult<Vec<String>> {
    factor_names()
}

/// The points of the Saltelli design of `base_rows` base rows (a power of two), one row per
/// point in unit-cube coordinates (`base_rows * (factors + 2)` rows).
#[pyfunction]
#[pyo3(signature = (base_rows, seed = STUDY_SEED))]
fn paper_deviations_design<'py>(
    py: Python<'py>,
    base_rows: usize,
    seed: u32,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let d = design(base_rows, seed, Scope::default())?
        .design()
        .map_err(err)?;
    PyArray2::from_vec2(py, &d.points()).map_err(|e| arg_err(e.to_string()))
}

/// The study's quantities of prototype `prototype` (`"p1"` or `"p2"`) at a unit-cube point,
/// each a dict; the ensemble claims too when `ensemble_records` is given (records per level).
#[pyfunction]
#[pyo3(signature = (prototype, point, ensemble_records = None))]
fn paper_deviations_evaluate<'py>(
    py: Python<'py>,
    prototype: &str,
    point: Vec<f64>,
    ensemble_records: Option<usize>,
) -> PyResult<Bound<'py, PyList>> {
    let p = self::prototype(prototype)?;
    let scope = scope(ensemble_records)?;
    let (base, ranges, claims) = inputs(p)?;
    let es = py
        .detach(|| deviations::evaluate_at(p, &ranges, &base, &point, &claims, scope))
        .map_err(err)?;
    evaluations_list(py, &es, &claims)
}

/// The Sobol indices of every quantity from `evaluations` (one list of dicts per design point,
/// in design order): one dict per quantity and factor, with the columns of the study's
/// `sobol.parquet`.
#[pyfunction]
#[pyo3(signature = (prototype, base_rows, evaluations, ensemble_records = None, seed = STUDY_SEED))]
fn paper_deviations_indices<'py>(
    py: Python<'py>,
    prototype: &str,
    base_rows: usize,
    evaluations: Vec<Vec<Bound<'py, PyDict>>>,
    ensemble_records: Option<usize>,
    seed: u32,
) -> PyResult<Bound<'py, PyList>> {
    let p = self::prototype(prototype)?;
    let d = design(base_rows, seed, scope(ensemble_records)?)?;
    let factors = factor_names()?;
    let claims = Claims::bundled().map_err(solver_err)?;
    let evals = evaluations
        .iter()
        .map(|point| point.iter().map(|e| evaluation_of(p, e, &claims)).collect())
        .collect::<PyResult<Vec<Vec<Evaluation>>>>()?;
    let run = py
        .detach(move || deviations::sobol_indices(p, d, evals))
        .map_err(err)?;
    let rows = PyList::empty(py);
    for q in &run.quantities {
        let Some(ix) = &q.indices else { continue };
        for (i, f) in factors.iter().enumerate() {
            let r = PyDict::new(py);
            r.set_item("prototype", p.key())?;
            r.set_item("claim", q.quantity.claim)?;
            r.set_item("quantity", q.quantity.quantity)?;
            r.set_item("factor", f)?;
            for (k, x) in [("first", ix.first[i]), ("total", ix.total[i])] {
                r.set_item(k, x.value)?;
                r.set_item(format!("{k}_lo"), x.lo)?;
                r.set_item(format!("{k}_hi"), x.hi)?;
            }
            r.set_item("absent_share", q.absent_share)?;
            r.set_item("no_fold_share", q.no_fold_share)?;
            r.set_item("no_grazing_share", q.no_grazing_share)?;
            r.set_item("failed_share", q.failed_share)?;
            rows.append(r)?;
        }
    }
    Ok(rows)
}

fn minimax(starts: usize, iterations: u64, seed: u32) -> MinimaxSettings {
    MinimaxSettings {
        starts,
        max_iters: iterations,
        seed,
        ..MinimaxSettings::default()
    }
}

fn fit_dict<'py>(py: Python<'py>, f: &Fit) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("start", f.start)?;
    d.set_item("point", f.point.clone())?;
    d.set_item("deviations", f.deviations.clone())?;
    d.set_item("worst", f.worst)?;
    d.set_item("iterations", f.iterations)?;
    d.set_item("failures", f.failures)?;
    Ok(d)
}

/// The calibration's starts of a prototype: the published point, then `starts` points of the
/// scrambled Sobol sequence (one row each, unit-cube coordinates).
#[pyfunction]
#[pyo3(signature = (prototype, starts, seed = STUDY_SEED))]
fn paper_deviations_calibration_starts<'py>(
    py: Python<'py>,
    prototype: &str,
    starts: usize,
    seed: u32,
) -> PyResult<Bound<'py, PyArray2<f64>>> {
    let (base, ranges, _) = inputs(self::prototype(prototype)?)?;
    let s =
        deviations::calibration_starts(&ranges, &base, minimax(starts, 1, seed)).map_err(err)?;
    PyArray2::from_vec2(py, &s).map_err(|e| arg_err(e.to_string()))
}

/// One start of the calibration (start `start` of `paper_deviations_calibration_starts` with
/// `starts` Sobol starts), at most `iterations` Nelder-Mead iterations: a dict with `start`,
/// `point`, `deviations`, `worst`, `iterations`, `failures`.
#[pyfunction]
#[pyo3(signature = (prototype, start, starts, iterations, ensemble_records = None, seed = STUDY_SEED))]
fn paper_deviations_calibrate_start<'py>(
    py: Python<'py>,
    prototype: &str,
    start: usize,
    starts: usize,
    iterations: u64,
    ensemble_records: Option<usize>,
    seed: u32,
) -> PyResult<Bound<'py, PyDict>> {
    let p = self::prototype(prototype)?;
    let scope = scope(ensemble_records)?;
    let (base, ranges, claims) = inputs(p)?;
    let settings = minimax(starts, iterations, seed);
    let fit = py
        .detach(move || {
            deviations::calibrate_start(p, &ranges, &base, settings, &claims, scope, start)
        })
        .map_err(err)?;
    fit_dict(py, &fit)
}

/// The calibration from its starts' fits (the dicts of `paper_deviations_calibrate_start`, in any
/// order): `fits` best first, `worst`, `published_worst`, `meets_all`, and the evaluations
/// `best` and `published`.
#[pyfunction]
#[pyo3(signature = (prototype, fits, ensemble_records = None))]
fn paper_deviations_calibration<'py>(
    py: Python<'py>,
    prototype: &str,
    fits: Vec<Bound<'py, PyDict>>,
    ensemble_records: Option<usize>,
) -> PyResult<Bound<'py, PyDict>> {
    let p = self::prototype(prototype)?;
    let scope = scope(ensemble_records)?;
    let (base, ranges, claims) = inputs(p)?;
    let fits = fits
        .iter()
        .map(|d| {
            Ok(Fit {
                start: field(d, "a fit", "start")?,
                point: field(d, "a fit", "point")?,
                deviations: field(d, "a fit", "deviations")?,
                worst: field(d, "a fit", "worst")?,
                iterations: field(d, "a fit", "iterations")?,
                failures: field(d, "a fit", "failures")?,
            })
        })
        .collect::<PyResult<Vec<Fit>>>()?;
    let cal = py
        .detach(|| deviations::calibration_of_fits(p, &ranges, &base, &claims, scope, fits))
        .map_err(err)?;
    let d = PyDict::new(py);
    let fl = PyList::empty(py);
    for f in &cal.fits {
        fl.append(fit_dict(py, f)?)?;
    }
    d.set_item("fits", fl)?;
    d.set_item("worst", cal.worst())?;
    d.set_item("published_worst", cal.published_worst())?;
    d.set_item("meets_all", cal.meets_all())?;
    d.set_item("best", evaluations_list(py, &cal.best, &claims)?)?;
    d.set_item("published", evaluations_list(py, &cal.published, &claims)?)?;
    Ok(d)
}

/// One wave as Python passes it: its points and the evaluation dicts at each.
type WaveDicts<'py> = (Vec<Vec<f64>>, Vec<Vec<Bound<'py, PyDict>>>);

fn history_settings(
    per_input: usize,
    max_waves: usize,
    pool: usize,
    seed: u32,
) -> endstop::num::history::HistorySettings {
    endstop::num::history::HistorySettings {
        per_input,
        max_waves,
        pool,
        seed,
        ..Default::default()
    }
}

/// The history match of `prototype` replayed from its waves so far: `waves` is a list of
/// `(points, evaluations)` (each wave's design as `paper_deviations_history` gave it and the
/// `paper_deviations_evaluate` dicts at its points, in order). Returns a dict: `next_design` (the
/// points to evaluate next, or None once the match has ended), `outputs` (the emulated
/// claims), `waves` (one summary dict per wave), `answer`, `projections` (one dict per cell of
/// the last wave), and with `sobol=True` the emulators' Sobol indices (`indices`).
#[pyfunction]
#[pyo3(signature = (prototype, waves, per_input = 10, max_waves = 4, pool = 1 << 14,
                    ensemble_records = None, seed = STUDY_SEED, sobol = false))]
#[allow(clippy::too_many_arguments)]
fn paper_deviations_history<'py>(
    py: Python<'py>,
    prototype: &str,
    waves: Vec<WaveDicts<'py>>,
    per_input: usize,
    max_waves: usize,
    pool: usize,
    ensemble_records: Option<usize>,
    seed: u32,
    sobol: bool,
) -> PyResult<Bound<'py, PyDict>> {
    let p = self::prototype(prototype)?;
    let scope = scope(ensemble_records)?;
    let (_, ranges, claims) = inputs(p)?;
    let waves = waves
        .iter()
        .map(|(pts, evals)| {
            let e = evals
                .iter()
                .map(|point| point.iter().map(|e| evaluation_of(p, e, &claims)).collect())
                .collect::<PyResult<Vec<Vec<Evaluation>>>>()?;
            Ok((pts.clone(), e))
        })
        .collect::<PyResult<Vec<_>>>()?;
    let settings = history_settings(per_input, max_waves, pool, seed);
    let (run, indices) = py
        .detach(move || -> Result<_, DeviationsError> {
            let mut run = deviations::HistoryRun::new(p, &ranges, scope, &claims, settings)?;
            for (pts, e) in waves {
                run.add_wave(&pts, e)?;
            }
            let indices = if sobol {
                run.sobol(endstop::num::gp_sensitivity::EmulatedSobol {
                    seed,
                    ..Default::default()
                })?
            } else {
                Vec::new()
            };
            Ok((run, indices))
        })
        .map_err(err)?;
    let d = PyDict::new(py);
    match run.next_design() {
        Some(x) => d.set_item(
            "next_design",
            PyArray2::from_vec2(py, &x).map_err(|e| arg_err(e.to_string()))?,
        )?,
        None => d.set_item("next_design", py.None())?,
    }
    let names: Vec<(String, String)> = run
        .outputs()
        .iter()
        .map(|q| (q.claim.to_string(), q.quantity.to_string()))
        .collect();
    d.set_item("outputs", names.clone())?;
    let ws = PyList::empty(py);
    for s in &run.matcher.summaries {
        let w = PyDict::new(py);
        w.set_item("wave", s.wave)?;
        w.set_item("new_runs", s.new_runs)?;
        w.set_item("training_runs", s.training_runs)?;
        w.set_item("pool", s.pool)?;
        w.set_item("non_implausible_fraction", s.fraction())?;
        w.set_item("all_within_cut_fraction", s.fraction_all())?;
        w.set_item("stop", s.stop.map(|s| s.label()))?;
        let claims_rows = PyList::empty(py);
        for (j, (c, q)) in names.iter().enumerate() {
            let r = PyDict::new(py);
            r.set_item("claim", c)?;
            r.set_item("quantity", q)?;
            r.set_item("ruled_out", s.ruled_out[j])?;
            r.set_item("loo", s.loo[j].clone())?;
            claims_rows.append(r)?;
        }
        w.set_item("claims", claims_rows)?;
        let met = run.met_in_wave(s.wave);
        let yes_no = PyList::empty(py);
        for (k, q) in run.quantities.iter().enumerate() {
            if !run.emulated.contains(&k) {
                yes_no.append((q.claim, q.quantity, met[k]))?;
            }
        }
        w.set_item("yes_no_met", yes_no)?;
        ws.append(w)?;
    }
    d.set_item("waves", ws)?;
    if let Some(a) = run.answer() {
        let ad = PyDict::new(py);
        ad.set_item("stop", a.stop.map(|s| s.label()))?;
        ad.set_item("waves", a.waves)?;
        ad.set_item("runs", a.runs)?;
        ad.set_item("fraction", a.fraction)?;
        ad.set_item("fraction_all", a.fraction_all)?;
        ad.set_item("pool", a.pool)?;
        ad.set_item("runs_meeting_all", a.runs_meeting_all)?;
        ad.set_item("kept_all", a.kept_all)?;
        ad.set_item("none_reproduces", a.none_reproduces())?;
        d.set_item("answer", ad)?;
    }
    let cells = PyList::empty(py);
    if let Some(s) = run.matcher.summaries.last() {
        let n = run.matcher.settings.cells;
        for pr in &s.projections {
            for (c, (m, o)) in pr
                .min_implausibility
                .iter()
                .zip(&pr.optical_depth)
                .enumerate()
            {
                let r = PyDict::new(py);
                r.set_item("wave", s.wave)?;
                r.set_item("factor_x", &run.factors[pr.i])?;
                r.set_item("factor_y", &run.factors[pr.j])?;
                r.set_item("cell_x", c / n)?;
                r.set_item("cell_y", c % n)?;
                r.set_item("min_implausibility", *m)?;
                r.set_item("optical_depth", *o)?;
                cells.append(r)?;
            }
        }
    }
    d.set_item("projections", cells)?;
    let rows = PyList::empty(py);
    for (q, ix) in &indices {
        let Some(ix) = ix else { continue };
        for (i, f) in run.factors.iter().enumerate() {
            let r = PyDict::new(py);
            r.set_item("prototype", p.key())?;
            r.set_item("claim", q.claim)?;
            r.set_item("quantity", q.quantity)?;
            r.set_item("factor", f)?;
            for (k, x) in [("first", ix.first[i]), ("total", ix.total[i])] {
                r.set_item(k, x.value)?;
                r.set_item(format!("{k}_lo"), x.lo)?;
                r.set_item(format!("{k}_hi"), x.hi)?;
            }
            rows.append(r)?;
        }
    }
    d.set_item("indices", rows)?;
    Ok(d)
}

/// Adds the study's functions to the module.
pub fn register(m: &Bound<'_, PyModule>) -> PyResult<()> {
    for f in [
        wrap_pyfunction!(paper_deviations_factors, m)?,
        wrap_pyfunction!(paper_deviations_design, m)?,
        wrap_pyfunction!(paper_deviations_evaluate, m)?,
        wrap_pyfunction!(paper_deviations_indices, m)?,
        wrap_pyfunction!(paper_deviations_calibration_starts, m)?,
        wrap_pyfunction!(paper_deviations_calibrate_start, m)?,
        wrap_pyfunction!(paper_deviations_calibration, m)?,
        wrap_pyfunction!(paper_deviations_history, m)?,
    ] {
        m.add_function(f)?;
    }
    Ok(())
}

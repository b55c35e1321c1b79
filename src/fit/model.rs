//! The stepped-sweep model of a measured data set: the stepped sweep over its grid at its
//! stated acceleration, with the fit's tighter steady-state criterion and refinement, and the
//! values it gives at the measured points and features. The fit's model where the branches
//! cannot be identified, the generator of synthetic data in the tests, and (with a plain
//! sweep's settings, [`model_curve`]) the curve of the plots.

use serde::Serialize;

use super::{
    Direction, FeatureKind, FitError, Quantity, SweepData, FIT_REFINE_TOL_HZ, FIT_REL_CHANGE_TOL,
};
use crate::device::Device;
use crate::ode::SolverError;
use crate::study::record::ring_up_time_s;
use crate::study::steady::{Measurement, SettleSettings, FOLD_BLOCK_PERIODS};
use crate::study::sweep::{DownSweepReport, Refine, SweepReport, SweepSettings, REFINE_TOL_HZ};

/// The value of a measured quantity in a model measurement.
fn quantity_of(q: Quantity, m: &Measurement) -> f64 {
    match q {
        Quantity::V1RmsV => m.v1_rms_v,
        Quantity::PTotalW => m.p_total_w(),
    }
}

/// The model of a data set: the stepped sweep over its grid, and its features.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ModelSweep {
    /// (frequency in Hz, value in the data set's quantity), frequency increasing.
    pub curve: Vec<(f64, f64)>,
    /// Refined impact onset (Hz; up-sweeps), or the grid end it lies beyond.
    pub onset_hz: Option<f64>,
    /// Refined end of the branch (Hz), or the grid end it lies beyond.
    pub branch_end_hz: Option<f64>,
}

/// The model of a data set on `device` with the acceleration factor `scale` (the fit's sweep
/// settings, see the module docs).
pub fn model_sweep(device: &Device, scale: f64, data: &SweepData) -> Result<ModelSweep, FitError> {
    sweep_with(&fit_settings(device, data), device, scale, data)
}

/// The fit's sweep settings over the grid of `data` (see the module docs). A step whose
/// response is not periodic (a rigid stop's irregular impacts near grazing) never meets the
/// criterion and runs to the block limit, most of such a sweep's cost; its value is one
/// block's RMS of that response, a sample that moves with any change of the run. Ending
/// those steps once their change between blocks stops falling moves the fit's optimum with
/// the samples: tried on the recovery family's case 21, its damping's interval no longer held
/// the truth (6.90e-2, interval 6.59e-2 .. 7.22e-2, truth 7.54e-2), so they run on.
fn fit_settings(device: &Device, data: &SweepData) -> SweepSettings {
    let mut settings = SweepSettings::for_device(device, data.grid(), FIT_REFINE_TOL_HZ);
    settings.cfg.rel_change_tol = FIT_REL_CHANGE_TOL;
    settings
}

/// The transitions the values of `data` read ([`values_of`]): the onset where it measures
/// one, the end of the branch where it measures one or its points show a jump. The others
/// are left unrefined: each refinement is a bisection of steady states, and the coarse steps
/// the points read do not depend on it.
fn refine_for(data: &SweepData) -> Refine {
    refine_reading(data, data.measured_jump().is_some())
}

/// The onset refined where `data` measures one, the end of the branch where it measures one
/// or where `end_read` (a reader of the sweep other than the features needs it).
fn refine_reading(data: &SweepData, end_read: bool) -> Refine {
    let has = |kind| data.features.iter().any(|f| f.kind == kind);
    Refine {
        onset: has(FeatureKind::Onset),
        branch_end: has(FeatureKind::BranchEnd) || end_read,
        contact_beside_jump: false,
    }
}

/// The stepped sweep of a data set with the settings of a plain sweep
/// ([`SweepSettings::for_device`], transitions refined to [`REFINE_TOL_HZ`]): what the
/// `endstop sweep` command shows, for plots.
pub fn model_curve(device: &Device, scale: f64, data: &SweepData) -> Result<ModelSweep, FitError> {
    let settings = SweepSettings::for_device(device, data.grid(), REFINE_TOL_HZ);
    sweep_with(&settings, device, scale, data)
}

fn sweep_with(
    settings: &SweepSettings,
    device: &Device,
    scale: f64,
    data: &SweepData,
) -> Result<ModelSweep, FitError> {
    Ok(model_of(
        &SweepRun::run(settings, device, scale, data, Refine::ALL)?,
        data,
    ))
}

/// A stepped sweep of a data set in its direction, as the sweep reports it.
#[derive(Debug, Clone)]
pub(super) enum SweepRun {
    /// An up-sweep.
    Up(SweepReport),
    /// A down-sweep.
    Down(DownSweepReport),
}

impl SweepRun {
    /// The sweep of `data`'s grid in its direction at its acceleration times `scale`, with
    /// the transitions `refine` names refined.
    pub(super) fn run(
        settings: &SweepSettings,
        device: &Device,
        scale: f64,
        data: &SweepData,
        refine: Refine,
    ) -> Result<Self, SolverError> {
        let accel = data.accel_rms_g * scale;
        let never = &mut |_: &Measurement| false;
        let run = match data.direction {
            Direction::Up => settings
                .run_until_refining(device, accel, refine, never)?
                .map(SweepRun::Up),
            Direction::Down => settings
                .run_down_until_refining(device, accel, refine, never)?
                .map(SweepRun::Down),
        };
        Ok(run.expect("a sweep that is never stopped completes"))
    }

    /// The plain sweep of `data` ([`model_curve`]'s settings): the sweep the branches are
    /// identified from, with the transitions the identification reads refined (the onset
    /// where the data measure it; the end of the branch where they measure it or have points).
    pub(super) fn plain(
        device: &Device,
        scale: f64,
        data: &SweepData,
    ) -> Result<Self, SolverError> {
        let settings = SweepSettings::for_device(device, data.grid(), REFINE_TOL_HZ);
        let refine = refine_reading(data, !data.points.is_empty());
        Self::run(&settings, device, scale, data, refine)
    }

    /// The sweep of `data` with `settings`, telling `on_point(j, value)` the model's value at
    /// point `j` of `data` as soon as the coarse steps fix it (the value the whole sweep gives
    /// it, bit for bit: the steps on either side of the point are measured, and those that
    /// follow lie beyond it), the points in their order. `None` as soon as `on_point` returns
    /// true: the rest of the sweep is not run.
    fn watched(
        settings: &SweepSettings,
        device: &Device,
        scale: f64,
        data: &SweepData,
        on_point: &mut dyn FnMut(usize, f64) -> bool,
    ) -> Result<Option<Self>, SolverError> {
        let accel = data.accel_rms_g * scale;
        // The steps so far, by frequency increasing, and the next point not yet told.
        let mut curve: Vec<(f64, f64)> = Vec::new();
        let mut next = 0;
        let mut stop = |m: &Measurement| {
            let at = curve.partition_point(|c| c.0 < m.freq_hz);
            curve.insert(at, (m.freq_hz, quantity_of(data.quantity, m)));
            while let Some(p) = data.points.get(next) {
                let fixed = match data.direction {
                    Direction::Up => p.freq_hz <= m.freq_hz,
                    Direction::Down => p.freq_hz >= m.freq_hz,
                };
                if !fixed {
                    break;
                }
                next += 1;
                if on_point(next - 1, interpolate(&curve, p.freq_hz)) {
                    return true;
                }
            }
            false
        };
        let refine = refine_for(data);
        Ok(match data.direction {
            Direction::Up => settings
                .run_until_refining(device, accel, refine, &mut stop)?
                .map(SweepRun::Up),
            Direction::Down => settings
                .run_down_until_refining(device, accel, refine, &mut stop)?
                .map(SweepRun::Down),
        })
    }
}

/// The model of `data` in the sweep `run` over its grid.
fn model_of(run: &SweepRun, data: &SweepData) -> ModelSweep {
    let grid = data.grid();
    let (lo, hi) = (
        grid.iter().copied().fold(f64::INFINITY, f64::min),
        grid.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    );
    let (mut curve, onset_hz, branch_end_hz): (Vec<(f64, f64)>, Option<f64>, Option<f64>) =
        match run {
            SweepRun::Up(r) => {
                let curve = r
                    .measurements()
                    .map(|m| (m.freq_hz, quantity_of(data.quantity, m)))
                    .collect();
                let onset = match r.onset {
                    Some(t) => t.value(),
                    None if r.contact_at_start => lo,
                    None => hi,
                };
                let end = match r.branch_end() {
                    Some(e) => e.transition.value(),
                    None if r.any_contact() => hi,
                    None => lo,
                };
                (curve, Some(onset), Some(end))
            }
            SweepRun::Down(r) => {
                let curve = r
                    .measurements()
                    .map(|m| (m.freq_hz, quantity_of(data.quantity, m)))
                    .collect();
                let end = r.branch_end().map_or(lo, |(_, t)| t.value());
                (curve, None, Some(end))
            }
        };
    curve.sort_by(|a, b| a.0.total_cmp(&b.0));
    ModelSweep {
        curve,
        onset_hz,
        branch_end_hz,
    }
}

/// The model's values for a data set (its points, its features, then the end of its branch
/// where the points show a jump, [`SweepData::measured_jump`]) on `device` with the
/// acceleration factor `scale`.
///
/// ```
/// use endstop::device::Device;
/// use endstop::fit::{model_values, Direction, Point, Quantity, SweepData};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// // Two points of an up-sweep at 0.01 g rms, far below the stopper.
/// let point = |freq_hz| Point { freq_hz, value: 1.0, sigma: None };
/// let data = SweepData {
///     label: "example".into(),
///     direction: Direction::Up,
///     accel_rms_g: 0.01,
///     quantity: Quantity::V1RmsV,
///     points: vec![point(110.0), point(115.0)],
///     grid_hz: None,
///     features: vec![],
/// };
/// // Off the stopper the model is linear: twice the acceleration factor, twice the voltage.
/// // Each value is a steady state to the fit's criterion (1e-6 between blocks), so 1e-5.
/// let v1 = model_values(&device, 1.0, &data)?;
/// let v2 = model_values(&device, 2.0, &data)?;
/// assert_eq!(v1.len(), 2);
/// assert!(v1.iter().zip(&v2).all(|(a, b)| (b / a - 2.0).abs() < 1e-5));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn model_values(device: &Device, scale: f64, data: &SweepData) -> Result<Vec<f64>, FitError> {
    let settings = fit_settings(device, data);
    let run = SweepRun::run(&settings, device, scale, data, refine_for(data))?;
    Ok(values_of(&model_of(&run, data), data))
}

/// Most intervals of the grid of the cheap model's sweep of a data set without points (see
/// `design_values`).
pub const DESIGN_GRID_INTERVALS: usize = 16;

/// Shortest steady-state block of the cheap model's sweeps (periods): a quarter of a plain
/// sweep's ([`FOLD_BLOCK_PERIODS`]). Past a fold the state leaves the branch after a passage
/// time that falls like the inverse square root of the distance from the fold (see
/// [`crate::study::steady`]), so a horizon a quarter as long leaves the branch within 16 times
/// the distance a plain sweep's does: 1.6 Hz past prototype 1's folds instead of 0.1 Hz,
/// about a grid step of a measured sweep (1 to 5 Hz), which is all a ranking of starts needs.
/// Where the ring-up time sets a plain sweep's block instead, the cheap model's is a quarter
/// of it too ([`DESIGN_RING_FRACTION`]).
pub const DESIGN_BLOCK_PERIODS: usize = FOLD_BLOCK_PERIODS / 4;

/// The cheap model's blocks where the ring-up time `2m/b` sets them: this fraction of it. A
/// transient of relative size `a` decays like `a exp(-t b / 2m)`, so it changes by
/// `a (1 - exp(-B b / 2m))` over a block of `B`: the steady-state criterion (a relative change
/// `tol` of the RMS voltages between blocks) leaves a transient of `tol / (1 - e^-1/4)`, 4.5
/// `tol` (4.5e-3 with a plain sweep's criterion), against 1.6 `tol` with blocks of the whole
/// ring-up time. The cheap model only ranks the starts, and the refinement's own models are
/// converged to their criteria: the recovery family's fits refine the same starts and end at
/// the same values with either block.
pub const DESIGN_RING_FRACTION: f64 = 0.25;

/// The cheap model's sweep settings over `grid`: a plain sweep's ([`model_curve`]) with
/// blocks of [`DESIGN_RING_FRACTION`] of the ring-up time, at least [`DESIGN_BLOCK_PERIODS`]
/// periods.
fn design_settings(device: &Device, grid: Vec<f64>) -> SweepSettings {
    let (lo, hi) = grid
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &f| {
            (lo.min(f), hi.max(f))
        });
    let mut settings = SweepSettings::for_device(device, grid, REFINE_TOL_HZ);
    settings.cfg = SettleSettings::for_ring_time(
        DESIGN_RING_FRACTION * ring_up_time_s(device),
        0.5 * (lo + hi),
        DESIGN_BLOCK_PERIODS,
    );
    settings
}

/// The values of [`model_values`] from the stepped sweep with the cheap settings
/// (`design_settings`): the model that ranks the fit's starts. A data set without points
/// (features only) is swept on its grid thinned to at most [`DESIGN_GRID_INTERVALS`]
/// intervals, its ends kept: its features are refined by bisection whatever the grid.
///
/// The sweep of the data set's own grid tells `on_point` each point's value as soon as it is
/// fixed (the value the whole sweep gives it); `None` when `on_point` stopped it.
pub(super) fn design_values(
    device: &Device,
    scale: f64,
    data: &SweepData,
    on_point: &mut dyn FnMut(usize, f64) -> bool,
) -> Result<Option<Vec<f64>>, FitError> {
    let grid = data.grid();
    if !data.points.is_empty() || grid.len() <= DESIGN_GRID_INTERVALS + 1 {
        let settings = design_settings(device, grid);
        let Some(run) = SweepRun::watched(&settings, device, scale, data, on_point)? else {
            return Ok(None);
        };
        return Ok(Some(values_of(&model_of(&run, data), data)));
    }
    let every = (grid.len() - 1).div_ceil(DESIGN_GRID_INTERVALS);
    let mut thin: Vec<f64> = grid.iter().copied().step_by(every).collect();
    if thin.last() != grid.last() {
        thin.push(grid[grid.len() - 1]);
    }
    let coarse = SweepData {
        grid_hz: Some(thin),
        ..data.clone()
    };
    let settings = design_settings(device, coarse.grid());
    Ok(Some(values_of(
        &model_of(
            &SweepRun::run(&settings, device, scale, &coarse, refine_for(&coarse))?,
            &coarse,
        ),
        &coarse,
    )))
}

/// The values of a data set's points, features and jump in the model sweep `m`.
fn values_of(m: &ModelSweep, data: &SweepData) -> Vec<f64> {
    let grid = data.grid();
    let lo = grid.iter().copied().fold(f64::INFINITY, f64::min);
    let hi = grid.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let mut out: Vec<f64> = data
        .points
        .iter()
        .map(|p| interpolate(&m.curve, p.freq_hz))
        .collect();
    for f in &data.features {
        out.push(match f.kind {
            FeatureKind::Onset => m.onset_hz.unwrap_or(hi),
            FeatureKind::BranchEnd => m.branch_end_hz.unwrap_or(lo),
        });
    }
    if data.measured_jump().is_some() {
        out.push(m.branch_end_hz.unwrap_or(lo));
    }
    out
}

/// Linear interpolation in a curve sorted by frequency (exact at its frequencies).
fn interpolate(curve: &[(f64, f64)], f: f64) -> f64 {
    let k = curve.partition_point(|c| c.0 < f);
    if k < curve.len() && curve[k].0 == f {
        return curve[k].1;
    }
    if k == 0 {
        return curve[0].1;
    }
    if k == curve.len() {
        return curve[k - 1].1;
    }
    let (a, b) = (curve[k - 1], curve[k]);
    a.1 + (b.1 - a.1) * (f - a.0) / (b.0 - a.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::fit::{Feature, Point};

    /// The values with only the transitions they read refined equal, bit for bit, those of the
    /// sweep with every transition refined: up and down, with points of no value, with the
    /// points the sweep gives (a jump between them where it shows one), and with the onset
    /// (up) and the branch end measured.
    #[test]
    fn refining_only_the_transitions_read_leaves_every_value_the_same() {
        let text = include_str!(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/data/examples/piezo_cantilever.toml"
        ));
        let device = Device::from_toml_str(text, "piezo_cantilever.toml").unwrap();
        let same = |data: &SweepData| {
            let partly = model_values(&device, 1.0, data).unwrap();
            let wholly = values_of(&model_sweep(&device, 1.0, data).unwrap(), data);
            let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
            assert_eq!(bits(&partly), bits(&wholly), "{:?}", data.direction);
            partly
        };
        for direction in [Direction::Up, Direction::Down] {
            let mut data = SweepData {
                label: "refine".into(),
                direction,
                accel_rms_g: 0.5,
                quantity: Quantity::V1RmsV,
                points: (0..=15)
                    .map(|i| Point {
                        freq_hz: 100.0 + 4.0 * i as f64,
                        value: 0.0,
                        sigma: None,
                    })
                    .collect(),
                grid_hz: None,
                features: vec![],
            };
            let values = same(&data);
            for (p, v) in data.points.iter_mut().zip(values) {
                p.value = v;
            }
            same(&data);
            let feature = |kind| Feature {
                kind,
                freq_hz: 130.0,
                sigma_hz: 1.0,
            };
            data.features = match direction {
                Direction::Up => vec![feature(FeatureKind::Onset), feature(FeatureKind::BranchEnd)],
                Direction::Down => vec![feature(FeatureKind::BranchEnd)],
            };
            same(&data);
        }
    }
}

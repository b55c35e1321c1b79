//! Basins of attraction at a fixed sinusoidal drive: which initial states end on which of
//! the coexisting stable periodic orbits.
//!
//! Every cell of a grid of initial positions and velocities starts at drive phase zero with
//! the charges at their static equilibrium (both node voltages zero at that position) and is
//! integrated period by period; after each period its stroboscopic state is compared (in the
//! scaled norm of [`crate::study::orbit`]) with the state at drive phase zero of every
//! attractor of a catalogue of converged stable orbits. A cell belongs to an attractor once it
//! stays within [`BasinSettings::settle_tol`] of it for two successive periods; a cell that
//! does not settle within [`BasinSettings::max_periods`] is reported as unsettled (never
//! dropped). Cells run in parallel (rayon) and are collected in grid order, so the result does
//! not depend on the number of threads.

use nalgebra::{DVector, SVector};
use rayon::prelude::*;

use crate::model::{Driven, Model};
use crate::ode::{Dopri5, Stats};
use crate::progress::Progress;
use crate::study::orbit::{Forcing, Orbit, OrbitError, Shooter};

/// A grid of initial states.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BasinGrid {
    /// Initial positions from .. to (m), `nx` values, ends included.
    pub x_m: (f64, f64),
    /// Initial velocities from .. to (m/s), `nv` values, ends included.
    pub v_m_per_s: (f64, f64),
    /// Number of positions.
    pub nx: usize,
    /// Number of velocities.
    pub nv: usize,
}

impl BasinGrid {
    /// The same ranges with twice as many intervals in each direction (every cell kept; an
    /// empty direction stays empty).
    pub fn refined(&self) -> Self {
        Self {
            nx: (2 * self.nx).saturating_sub(1),
            nv: (2 * self.nv).saturating_sub(1),
            ..*self
        }
    }

    fn value(range: (f64, f64), n: usize, i: usize) -> f64 {
        if n == 1 {
            return range.0;
        }
        range.0 + (range.1 - range.0) * i as f64 / (n - 1) as f64
    }

    /// The initial (x, v) of every cell, velocity-major (row by row of velocity).
    pub fn cells(&self) -> Vec<(f64, f64)> {
        (0..self.nv)
            .flat_map(|j| {
                (0..self.nx).map(move |i| {
                    (
                        Self::value(self.x_m, self.nx, i),
                        Self::value(self.v_m_per_s, self.nv, j),
                    )
                })
            })
            .collect()
    }
}

/// The two state components a grid of initial states spans: a position and a velocity (of
/// one mass or of two), every other component starting at rest, with the transducer's parts at
/// their static equilibrium at the transducer's mass's position ([`Model::static_state`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Slice {
    /// The state component of the grid's positions.
    pub x: usize,
    /// The state component of the grid's velocities.
    pub v: usize,
}

impl Slice {
    /// The first mass's position and velocity (the transducer's: components 0 and 1).
    pub const FIRST: Slice = Slice { x: 0, v: 1 };

    /// The initial state of the cell `(x, v)` on this slice (see [`Slice`]).
    pub fn state<M: Model<N>, const N: usize>(&self, base: &M, x: f64, v: f64) -> SVector<f64, N> {
        let x_first = if self.x == 0 { x } else { 0.0 };
        let v_first = if self.v == 1 { v } else { 0.0 };
        let mut y = base.static_state(x_first, v_first);
        y[self.x] = x;
        y[self.v] = v;
        y
    }

    /// Refuses a slice whose components are not a position and a velocity of `base`'s masses.
    fn check<M: Model<N>, const N: usize>(&self, base: &M) -> Result<(), OrbitError> {
        let masses = &base.layout().masses;
        let is_x = masses.iter().any(|&(x, _)| x == self.x);
        let is_v = masses.iter().any(|&(_, v)| v == self.v);
        // A model whose layout lists no masses has the first mass at 0 and 1.
        let first = masses.is_empty() && *self == Self::FIRST;
        if (is_x && is_v) || first {
            Ok(())
        } else {
            Err(OrbitError::Invalid(format!(
                "basins: the slice (components {} and {}) is not a mass's position and a \
                 mass's velocity (the masses' components are {masses:?})",
                self.x, self.v
            )))
        }
    }
}

/// Settings of a basin computation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BasinSettings {
    /// The grid.
    pub grid: BasinGrid,
    /// Largest number of drive periods per cell.
    pub max_periods: usize,
    /// Scaled distance to an attractor's stroboscopic state below which a cell has settled.
    pub settle_tol: f64,
    /// Integrator relative tolerance.
    pub rtol: f64,
}

/// One attractor of the catalogue: a label and its state at drive phase zero.
#[derive(Debug, Clone, PartialEq)]
pub struct Attractor {
    /// Label (used in column values and summary keys).
    pub label: String,
    /// State at drive phase zero (the model's components).
    pub state: DVector<f64>,
}

impl Attractor {
    /// The attractor of a stable orbit, labelled `label`.
    pub fn of_orbit<M: Model<N>, const N: usize>(
        shooter: &Shooter<'_, M, N>,
        orbit: &Orbit,
        label: &str,
    ) -> Result<Self, OrbitError> {
        if !orbit.is_stable() {
            return Err(OrbitError::Invalid(format!(
                "the orbit labelled {label} is unstable (largest multiplier {})",
                orbit.max_multiplier_abs()
            )));
        }
        let state = shooter
            .state_at_phase(orbit, 0.0)
            .map_err(|e| OrbitError::Solver {
                what: "frequency (Hz)",
                param: orbit.forcing.freq_hz,
                source: e,
            })?;
        Ok(Self {
            label: label.to_string(),
            state: DVector::from_column_slice(state.as_slice()),
        })
    }
}

/// One cell's attractor (if it settled), the periods it ran and its integrator counters.
type CellOutcome = (Option<usize>, usize, Stats);

/// The label of cells that did not settle.
pub const UNSETTLED: &str = "unsettled";

/// The basins on a grid.
#[derive(Debug, Clone, PartialEq)]
pub struct Basins {
    /// Initial (x, v) of every cell, in grid order ([`BasinGrid::cells`]).
    pub cells: Vec<(f64, f64)>,
    /// Index into `labels` of each cell's attractor (`None`: unsettled).
    pub attractor: Vec<Option<usize>>,
    /// The catalogue's labels.
    pub labels: Vec<String>,
    /// Periods each cell ran.
    pub periods: Vec<usize>,
    /// Integrator counters of every cell integrated (a cell [`refine`] takes from the coarse
    /// grid is not counted again).
    pub stats: Stats,
}

impl Basins {
    /// Label of a cell's attractor ([`UNSETTLED`] when it did not settle).
    pub fn label(&self, cell: usize) -> &str {
        self.attractor[cell].map_or(UNSETTLED, |k| self.labels[k].as_str())
    }

    /// Share of the cells of each attractor, in catalogue order, then the unsettled share
    /// (labelled [`UNSETTLED`]); the shares sum to 1.
    pub fn shares(&self) -> Vec<(String, f64)> {
        let n = self.cells.len() as f64;
        let mut out: Vec<(String, f64)> = self
            .labels
            .iter()
            .enumerate()
            .map(|(k, l)| {
                let c = self.attractor.iter().filter(|a| **a == Some(k)).count();
                (l.clone(), c as f64 / n)
            })
            .collect();
        let u = self.attractor.iter().filter(|a| a.is_none()).count();
        out.push((UNSETTLED.to_string(), u as f64 / n));
        out
    }
}

/// The basins of `attractors` under `forcing` on the grid of `settings` (see the module
///
/// ```
/// use endstop::device::Device;
/// use endstop::progress::Silent;
/// use endstop::study::attractors::{find_attractors, seeds, AttractorSearch, Place};
/// use endstop::study::basins::{basins, BasinGrid, BasinSettings};
/// use endstop::study::displacement::two_wells;
/// use endstop::study::orbit::{Forcing, ShootingOptions};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/bistable_stops_em.toml"));
/// let device = Device::from_toml_str(text, "bistable_stops_em.toml")?;
/// // A weak drive far above the wells' 40 Hz: each well keeps its own small orbit. Two cells,
/// // one at rest at the bottom of each well, each settle on their own well's orbit.
/// let forcing = Forcing { freq_hz: 70.0, accel_rms_g: 0.05 };
/// let ([left, right], _) = two_wells(&device).unwrap();
/// let grid = BasinGrid { x_m: (left, right), v_m_per_s: (0.0, 0.0), nx: 2, nv: 1 };
/// let settings = BasinSettings { grid, max_periods: 2000, settle_tol: 1e-4, rtol: 1e-9 };
/// let b = endstop::with_harvester!(&device, |h| {
///     let found = find_attractors(
///         &h, &device, &forcing, ShootingOptions::default(), &seeds(&device, &grid, 0),
///         &AttractorSearch::default(),
///     )?;
///     assert_eq!(found.found[0].place, Place::LeftWell);
///     assert_eq!(found.found[1].place, Place::RightWell);
///     basins(&h, &forcing, &found.catalogue(), &settings, &Silent)
/// })?;
/// assert_eq!(b.label(0), Place::LeftWell.label());
/// assert_eq!(b.label(1), Place::RightWell.label());
/// let total: f64 = b.shares().iter().map(|(_, s)| s).sum();
/// assert!((total - 1.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
/// docs); `on_cell.tick()` is called after each cell.
pub fn basins<M: Model<N>, const N: usize>(
    base: &M,
    forcing: &Forcing,
    attractors: &[Attractor],
    settings: &BasinSettings,
    on_cell: &dyn Progress,
) -> Result<Basins, OrbitError> {
    basins_on(base, forcing, attractors, settings, Slice::FIRST, on_cell)
}

/// The basins as [`basins`] gives them, with the grid on `slice` (a position and a velocity of
/// any masses; every other component at rest) instead of the first mass's.
pub fn basins_on<M: Model<N>, const N: usize>(
    base: &M,
    forcing: &Forcing,
    attractors: &[Attractor],
    settings: &BasinSettings,
    slice: Slice,
    on_cell: &dyn Progress,
) -> Result<Basins, OrbitError> {
    slice.check(base)?;
    let cells = settings.grid.cells();
    let known = vec![None; cells.len()];
    settle_cells(
        base, forcing, attractors, settings, slice, cells, known, on_cell,
    )
}

/// The basins on `coarse_settings.grid.refined()`, with the other settings of
/// `coarse_settings`, taking every cell that the refined grid shares with `coarse` (computed
/// by [`basins`] with `coarse_settings` and the same `attractors`) from it instead of
/// integrating it again; `on_cell.tick()` is called after each new cell.
///
/// A shared cell is taken only when its initial state is the coarse cell's to the bit (it is
/// for [`BasinGrid::cells`], whose even-indexed refined values repeat the coarse ones exactly),
/// so the result is the one [`basins`] gives on the refined grid, except that `stats` counts
/// only the cells integrated here.
pub fn refine<M: Model<N>, const N: usize>(
    base: &M,
    forcing: &Forcing,
    attractors: &[Attractor],
    coarse_settings: &BasinSettings,
    coarse: &Basins,
    on_cell: &dyn Progress,
) -> Result<Basins, OrbitError> {
    let g = coarse_settings.grid;
    if g.nx == 0 || g.nv == 0 {
        return Err(OrbitError::Invalid(
            "refine: the coarse grid is empty (basins need a non-empty grid)".into(),
        ));
    }
    let labels: Vec<&str> = attractors.iter().map(|a| a.label.as_str()).collect();
    if coarse.cells.len() != g.nx * g.nv || coarse.labels != labels {
        return Err(OrbitError::Invalid(format!(
            "refine: the coarse basins ({} cells, attractors {:?}) are not those of a {}x{} grid \
             with attractors {labels:?}",
            coarse.cells.len(),
            coarse.labels,
            g.nx,
            g.nv
        )));
    }
    let fine = g.refined();
    let cells = fine.cells();
    let known = cells
        .iter()
        .enumerate()
        .map(|(k, &cell)| {
            let (i, j) = (k % fine.nx, k / fine.nx);
            let c = (j / 2) * g.nx + i / 2;
            let same = |a: (f64, f64), b: (f64, f64)| {
                a.0.to_bits() == b.0.to_bits() && a.1.to_bits() == b.1.to_bits()
            };
            (i % 2 == 0 && j % 2 == 0 && same(coarse.cells[c], cell))
                .then(|| (coarse.attractor[c], coarse.periods[c]))
        })
        .collect();
    let settings = BasinSettings {
        grid: fine,
        ..*coarse_settings
    };
    settle_cells(
        base,
        forcing,
        attractors,
        &settings,
        Slice::FIRST,
        cells,
        known,
        on_cell,
    )
}

/// Integrates every cell of `cells` without a `known` outcome until it settles (see the
/// module docs), each started on `slice`, and collects the outcomes in grid order.
#[allow(clippy::too_many_arguments)]
fn settle_cells<M: Model<N>, const N: usize>(
    base: &M,
    forcing: &Forcing,
    attractors: &[Attractor],
    settings: &BasinSettings,
    slice: Slice,
    cells: Vec<(f64, f64)>,
    known: Vec<Option<(Option<usize>, usize)>>,
    on_cell: &dyn Progress,
) -> Result<Basins, OrbitError> {
    if attractors.is_empty() || settings.grid.nx == 0 || settings.grid.nv == 0 {
        return Err(OrbitError::Invalid(
            "basins need at least one attractor and a non-empty grid".into(),
        ));
    }
    let model = Driven::new(base, forcing.sine(0.0));
    let scales = base.scales();
    let period = forcing.period_s();
    let opts = base.solver_options(settings.rtol);
    let states: Vec<SVector<f64, N>> = attractors
        .iter()
        .map(|a| SVector::<f64, N>::from_column_slice(a.state.as_slice()))
        .collect();
    let results: Vec<Result<CellOutcome, OrbitError>> = cells
        .par_iter()
        .zip(&known)
        .map(|(&(x, v), known)| {
            if let Some((found, k)) = *known {
                return Ok((found, k, Stats::default()));
            }
            let y0 = slice.state(base, x, v);
            let mut ode = Dopri5::new(0.0, y0, base.mode_of(&y0), opts.clone());
            let mut previous: Option<usize> = None;
            let mut found = None;
            let mut k = 0;
            while k < settings.max_periods {
                k += 1;
                ode.integrate(&model, k as f64 * period, |_, _| {})
                    .map_err(|e| OrbitError::Solver {
                        what: "frequency (Hz)",
                        param: forcing.freq_hz,
                        source: e,
                    })?;
                let y = ode.y();
                let near = states
                    .iter()
                    .position(|a| (y - a).component_div(&scales).norm() < settings.settle_tol);
                if near.is_some() && near == previous {
                    found = near;
                    break;
                }
                previous = near;
            }
            on_cell.tick();
            Ok((found, k, ode.stats()))
        })
        .collect();
    let mut out = Basins {
        cells,
        attractor: Vec::with_capacity(results.len()),
        labels: attractors.iter().map(|a| a.label.clone()).collect(),
        periods: Vec::with_capacity(results.len()),
        stats: Stats::default(),
    };
    for r in results {
        let (a, k, st) = r?;
        out.attractor.push(a);
        out.periods.push(k);
        out.stats += st;
    }
    Ok(out)
}

//! The stable periodic orbits of a device at a fixed sine drive, found by settling seeds, and
//! where each one lives: in which well of a device with two wells, or across the barrier.
//!
//! Each seed (an initial position and velocity at drive phase zero, the transducer at its
//! static equilibrium, as [`crate::study::basins`] starts its cells) is integrated for
//! [`AttractorSearch::transient_periods`] drive periods; Newton's method on the period map
//! ([`Shooter::solve`]) then starts from its state at drive phase zero. A converged stable orbit
//! is kept unless one kept before lies within [`AttractorSearch::same_tol`] of it (the scaled
//! norm of the states at drive phase zero). Seeds whose orbit does not converge, is unstable,
//! or repeats one kept are counted in [`Attractors`], never hidden. Only orbits of one drive
//! period are found: a cell of the basins that settles on a subharmonic or chaotic motion stays
//! unsettled there.
//!
//! **Where an orbit lives.** For a device with two wells ([`two_wells`]), an orbit whose
//! displacement stays below the barrier all period is in the left (lower) well, one that stays
//! above it in the right (upper) well, and one that crosses it is inter-well; a device with one
//! well has one place. Attractors are labelled by their place, and where several share a place,
//! by their amplitude as well (`small`, `large`; or their rank).
//!
//! ```
//! use endstop::device::Device;
//! use endstop::study::attractors::{find_attractors, seeds, AttractorSearch, Place};
//! use endstop::study::basins::BasinGrid;
//! use endstop::study::orbit::{Forcing, ShootingOptions};
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/bistable_stops_em.toml"));
//! let device = Device::from_toml_str(text, "bistable_stops_em.toml")?;
//! // A weak drive far above the wells' resonance: each well keeps its own small orbit.
//! let forcing = Forcing { freq_hz: 70.0, accel_rms_g: 0.05 };
//! let grid = BasinGrid { x_m: (-7e-4, 7e-4), v_m_per_s: (-0.1, 0.1), nx: 3, nv: 1 };
//! let found = endstop::with_harvester!(&device, |h| find_attractors(
//!     &h, &device, &forcing, ShootingOptions::default(), &seeds(&device, &grid, 0),
//!     &AttractorSearch::default(),
//! ))?;
//! let places: Vec<Place> = found.found.iter().map(|a| a.place).collect();
//! assert_eq!(places, [Place::LeftWell, Place::RightWell]);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

use nalgebra::SVector;
use rayon::prelude::*;

use crate::device::Device;
use crate::laws::suspension::Place as EquilibriumPlace;
use crate::model::Model;
use crate::ode::Stats;
use crate::study::basins::{Attractor, BasinGrid};
use crate::study::displacement::two_wells;
use crate::study::orbit::{Forcing, Orbit, OrbitError, Parameter, Shooter, ShootingOptions};

/// Where an orbit lives.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Place {
    /// The device has one well (or none between its stops): no place to tell.
    Single,
    /// Below the barrier all period (the left, lower, well).
    LeftWell,
    /// Above the barrier all period (the right, upper, well).
    RightWell,
    /// Crosses the barrier.
    InterWell,
}

impl Place {
    /// Label for tables, plots and column values.
    pub fn label(self) -> &'static str {
        match self {
            Place::Single => "orbit",
            Place::LeftWell => "left well",
            Place::RightWell => "right well",
            Place::InterWell => "inter-well",
        }
    }

    /// The place of an orbit of `device` (see the module docs).
    pub fn of(device: &Device, orbit: &Orbit) -> Self {
        match two_wells(device) {
            None => Place::Single,
            Some((_, barrier)) if orbit.summary.x_upper_m < barrier => Place::LeftWell,
            Some((_, barrier)) if orbit.summary.x_lower_m > barrier => Place::RightWell,
            Some(_) => Place::InterWell,
        }
    }
}

/// Settings of the search.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AttractorSearch {
    /// Drive periods each seed is integrated before Newton starts.
    pub transient_periods: usize,
    /// Scaled distance between the states at drive phase zero below which two orbits are one.
    pub same_tol: f64,
}

impl Default for AttractorSearch {
    /// 200 periods of transient (a device whose free decay loses 1 % per period settles by a
    /// factor e^2 in them, close enough for Newton, which converges from much further), and
    /// orbits the same within 1e-4 (converged orbits are accurate to about 1e-9).
    fn default() -> Self {
        Self {
            transient_periods: 200,
            same_tol: 1e-4,
        }
    }
}

/// One attractor found.
#[derive(Debug, Clone, PartialEq)]
pub struct Found {
    /// The stable orbit, with its section at drive phase zero.
    pub orbit: Orbit,
    /// Where it lives.
    pub place: Place,
    /// Its label ([`Place::label`], with its amplitude where several share the place).
    pub label: String,
    /// The first seed (index into the seeds) that found it.
    pub seed: usize,
}

/// The result of a search: the attractors and what became of every seed.
#[derive(Debug, Clone, PartialEq)]
pub struct Attractors {
    /// The attractors, by place and then amplitude.
    pub found: Vec<Found>,
    /// Seeds tried.
    pub seeds: usize,
    /// Seeds from which Newton did not converge (or the integration failed).
    pub not_converged: usize,
    /// Seeds that converged on an unstable orbit.
    pub unstable: usize,
    /// Seeds that converged on an attractor found before.
    pub repeats: usize,
    /// Integrator counters.
    pub stats: Stats,
}

impl Attractors {
    /// The catalogue of the basins ([`crate::study::basins::basins`]): each attractor's label
    /// and state at drive phase zero.
    pub fn catalogue(&self) -> Vec<Attractor> {
        self.found
            .iter()
            .map(|f| Attractor {
                label: f.label.clone(),
                state: f.orbit.state.clone(),
            })
            .collect()
    }
}

/// The seeds of a search over `grid`: the device's stable equilibria between its stops at
/// rest, then the cells of the grid's ranges taken `per_side` by `per_side` (none for 0).
pub fn seeds(device: &Device, grid: &BasinGrid, per_side: usize) -> Vec<(f64, f64)> {
    let mut out: Vec<(f64, f64)> = crate::physics::statics::equilibria(device)
        .iter()
        .filter(|e| e.stable && e.place == EquilibriumPlace::Free)
        .map(|e| (e.x_m, 0.0))
        .collect();
    out.extend(grid_seeds(grid, per_side));
    out
}

/// The cells of `grid`'s ranges taken `per_side` by `per_side` (none for 0): the seeds a
/// search spreads over the grid's plane.
pub fn grid_seeds(grid: &BasinGrid, per_side: usize) -> Vec<(f64, f64)> {
    BasinGrid {
        nx: per_side,
        nv: per_side,
        ..*grid
    }
    .cells()
}

/// What one seed gave: an orbit (stable or not), or nothing.
type SeedOutcome = (Option<Orbit>, Stats);

/// The stable period-one orbits of `device` (whose model is `base`) under `forcing` reached
/// from `seeds` (see the module docs). Seeds run in parallel and are read in order, so the
/// result does not depend on the number of threads.
pub fn find_attractors<M: Model<N>, const N: usize>(
    base: &M,
    device: &Device,
    forcing: &Forcing,
    shooting: ShootingOptions,
    seeds: &[(f64, f64)],
    search: &AttractorSearch,
) -> Result<Attractors, OrbitError> {
    let starts: Vec<SVector<f64, N>> = seeds
        .iter()
        .map(|&(x, v)| base.static_state(x, v))
        .collect();
    find_attractors_from(base, device, forcing, shooting, &starts, search)
}

/// The stable period-one orbits reached from the initial states `starts` (each a whole
/// state, as [`find_attractors`] makes from its seeds on the first mass).
pub fn find_attractors_from<M: Model<N>, const N: usize>(
    base: &M,
    device: &Device,
    forcing: &Forcing,
    shooting: ShootingOptions,
    starts: &[SVector<f64, N>],
    search: &AttractorSearch,
) -> Result<Attractors, OrbitError> {
    if !(search.same_tol.is_finite() && search.same_tol > 0.0) {
        return Err(OrbitError::Invalid(format!(
            "the tolerance for one orbit must be finite and positive, not {}",
            search.same_tol
        )));
    }
    let shooter = Shooter::new(base, shooting);
    let period = forcing.period_s();
    let outcomes: Vec<SeedOutcome> = starts
        .par_iter()
        .map(|&y0| {
            let mut stats = Stats::default();
            let transient = search.transient_periods as f64 * period;
            let Ok((y, _, st)) = shooter.advance(forcing, 0.0, y0, transient) else {
                return (None, stats);
            };
            stats += st;
            let orbit = shooter
                .solve(forcing, Parameter::Frequency, 0.0, y, &mut stats)
                .ok();
            (orbit, stats)
        })
        .collect();
    let mut out = Attractors {
        found: Vec::new(),
        seeds: starts.len(),
        not_converged: 0,
        unstable: 0,
        repeats: 0,
        stats: Stats::default(),
    };
    for (seed, (orbit, stats)) in outcomes.into_iter().enumerate() {
        out.stats += stats;
        let Some(orbit) = orbit else {
            out.not_converged += 1;
            continue;
        };
        if !orbit.is_stable() {
            out.unstable += 1;
            continue;
        }
        let known = out.found.iter().any(|f| {
            shooter.norm(&(f.orbit.state_n::<N>() - orbit.state_n::<N>())) < search.same_tol
        });
        if known {
            out.repeats += 1;
            continue;
        }
        out.found.push(Found {
            place: Place::of(device, &orbit),
            orbit,
            label: String::new(),
            seed,
        });
    }
    label(&mut out.found);
    Ok(out)
}

/// Sorts attractors by place and amplitude and labels them (see the module docs).
fn label(found: &mut [Found]) {
    found.sort_by(|a, b| {
        a.place
            .cmp(&b.place)
            .then(a.orbit.summary.x_max_m.total_cmp(&b.orbit.summary.x_max_m))
    });
    let places: Vec<Place> = found.iter().map(|f| f.place).collect();
    for (i, f) in found.iter_mut().enumerate() {
        let same = places.iter().filter(|p| **p == f.place).count();
        let rank = places[..i].iter().filter(|p| **p == f.place).count();
        let place = f.place.label();
        f.label = match (same, rank) {
            (1, _) => place.to_string(),
            (2, 0) => format!("{place}, small"),
            (2, _) => format!("{place}, large"),
            _ => format!("{place}, amplitude rank {}", rank + 1),
        };
    }
}

//! The basins of attraction of a case at its basin frequency (inside the hysteresis band): the
//! grid, the attractors (the stable orbits of the branch there), and the convergence of the
//! basins' shares on a grid twice as fine.

use crate::ode::Stats;
use crate::physics::harvester::Harvester;
use crate::progress::Progress;
use crate::study::basins::{basins, refine, Attractor, BasinGrid, BasinSettings, Basins};
use crate::study::continuation::Branch;
use crate::study::orbit::{Forcing, Orbit, OrbitError, Shooter};

use super::{CaseRun, Setup};

/// Grid of the basin plots: 41 x 41 initial states over +-1.5 x_max and +-1.5 w x_max.
pub const BASIN_CELLS: usize = 41;

/// Largest number of drive periods per basin cell (prototype 2's lower orbit has its largest
/// multiplier at 0.97: some 250 periods to settle to 1e-3 from a distance of order one).
pub const BASIN_MAX_PERIODS: usize = 4000;

/// Scaled distance at which a basin cell has settled on an attractor.
pub const BASIN_SETTLE_TOL: f64 = 1e-3;

/// Integrator tolerance of the basin cells. A cell is classified at a scaled distance of
/// [`BASIN_SETTLE_TOL`] from an attractor, five orders of magnitude above the integration's
/// global error at this tolerance (some 15 rtol, [`crate::study::orbit::ShootingOptions`]);
/// the attractors' states themselves come from the shooting at its own 1e-10. At 1e-8, where
/// the step limit of a fiftieth of the natural period binds, a cell takes about half the steps
/// it takes at 1e-10, and every cell of both cases' grids ends on the same attractor as at
/// 1e-10 (the test `basins_do_not_depend_on_the_tolerance` checks a grid of each case; on the
/// book's grids and their refinements one cell in 6561 settles one period apart).
pub const BASIN_RTOL: f64 = 1e-8;

impl Setup {
    /// The basin settings of the case at its basin frequency (the grid spans 1.5 times the
    /// gap and 1.5 times the gap times the angular drive frequency).
    pub fn basin_settings(&self, cells: usize) -> Option<BasinSettings> {
        let f = self.case.basin_freq_hz()?;
        let xmax = crate::paper::setups::endstop(&self.device).gap_m;
        let vmax = 2.0 * std::f64::consts::PI * f * xmax;
        Some(BasinSettings {
            grid: BasinGrid {
                x_m: (-1.5 * xmax, 1.5 * xmax),
                v_m_per_s: (-1.5 * vmax, 1.5 * vmax),
                nx: cells,
                nv: cells,
            },
            max_periods: BASIN_MAX_PERIODS,
            settle_tol: BASIN_SETTLE_TOL,
            rtol: BASIN_RTOL,
        })
    }
}

/// Labels of the attractors at a basin frequency: the stable orbits there, the impacting one
/// `upper` and the other `lower`.
fn attractor_label(o: &Orbit) -> &'static str {
    if o.is_impacting() {
        "upper"
    } else {
        "lower"
    }
}

/// The attractors at a basin frequency: (label, orbit).
pub(super) type Attractors = Vec<(String, Orbit)>;

/// The basins of `setup` at its basin frequency on a grid of `cells` squared cells, with the
/// attractors; `None` if the case has no basin frequency.
pub(super) fn case_basins(
    setup: &Setup,
    branch: &Branch,
    cells: usize,
    stats: &mut Stats,
    on_step: &dyn Progress,
) -> Result<Option<(Basins, Attractors)>, OrbitError> {
    let Some(bs) = setup.basin_settings(cells) else {
        return Ok(None);
    };
    let f = setup
        .case
        .basin_freq_hz()
        .expect("a case with basin settings has a frequency");
    let h = Harvester::<4>::new(&setup.device)?;
    let shooter = Shooter::new(&h, setup.continuation.shooting);
    let orbits = branch.orbits_at(&shooter, f, stats)?;
    let mut attractors = Vec::new();
    let mut catalogue = Vec::new();
    for o in orbits.into_iter().filter(|o| o.is_stable()) {
        let label = attractor_label(&o);
        catalogue.push(Attractor::of_orbit(&shooter, &o, label)?);
        attractors.push((label.to_string(), o));
    }
    let forcing = Forcing {
        freq_hz: f,
        accel_rms_g: setup.accel_rms_g,
    };
    let b = basins(&h, &forcing, &catalogue, &bs, on_step)?;
    Ok(Some((b, attractors)))
}

/// The basins of a case on a grid twice as fine as its own, and how far the attractors'
/// shares moved.
#[derive(Debug, Clone)]
pub struct BasinConvergence {
    /// The basins on the finer grid.
    pub fine: Basins,
    /// The largest change of an attractor's share from the case's grid to the finer one.
    pub largest_share_change: f64,
}

/// The convergence of a case's basins (computed on a grid of `cells` squared cells): the
/// basins again on a grid twice as fine, the cells it shares with the coarse grid taken from
/// it; `None` if the case has no basins.
pub fn basin_convergence(
    run: &CaseRun,
    cells: usize,
) -> Result<Option<BasinConvergence>, OrbitError> {
    let setup = &run.setup;
    let (Some(bs), Some(coarse), Some(f)) = (
        setup.basin_settings(cells),
        run.basins.as_ref(),
        setup.case.basin_freq_hz(),
    ) else {
        return Ok(None);
    };
    let h = Harvester::<4>::new(&setup.device)?;
    let shooter = Shooter::new(&h, setup.continuation.shooting);
    let catalogue = run
        .attractors
        .iter()
        .map(|(l, o)| Attractor::of_orbit(&shooter, o, l))
        .collect::<Result<Vec<_>, _>>()?;
    let forcing = Forcing {
        freq_hz: f,
        accel_rms_g: setup.accel_rms_g,
    };
    let fine = refine(&h, &forcing, &catalogue, &bs, coarse, &|| {})?;
    let largest_share_change = coarse
        .shares()
        .iter()
        .zip(fine.shares())
        .map(|(a, b)| (a.1 - b.1).abs())
        .fold(0.0, f64::max);
    Ok(Some(BasinConvergence {
        fine,
        largest_share_change,
    }))
}

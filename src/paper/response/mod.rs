//! The whole response curve of Figures 8 and 13: both stable branches, the unstable branch
//! between them, their folds and grazing points (by shooting and pseudo-arclength
//! continuation, [`crate::study::continuation`]), the up- and down-sweeps on top
//! ([`crate::study::sweep`]), the Floquet multipliers of the coexisting orbits inside the
//! hysteresis band, and the basins of attraction there ([`crate::study::basins`]). The phase of
//! each orbit's displacement against the drive ([`phase_lag_deg`]) tells the upper and the
//! unstable branch apart where the stops hold their RMS voltages together.
//!
//! The study is split by job: the cases and their runs here, the folds beside the
//! scorecard's jump claims (`folds.rs`, [`claim_folds`]), the steady-state criterion on the
//! ghost past the upper fold (`ghost.rs`, [`ghost_study`]), and the basins with their
//! convergence (`basins.rs`, [`basin_convergence`]).

mod basins;
mod folds;
mod ghost;

use rayon::prelude::*;
use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::ode::{SolverError, Stats};
use crate::paper::figures::fig13;
use crate::paper::setups::{prototype1_setup, with_endstop, ParamSet, FIG13_BIAS_V};
use crate::paper::sweeps::{self, P1_HIGH_ACCEL_RMS_G, P1_SWEEP_STEP_HZ};
use crate::physics::harvester::Harvester;
use crate::progress::{Progress, Silent};
use crate::study::basins::Basins;
use crate::study::continuation::{
    branch_from_rest, Branch, ContinuationSettings, Diagram, DiagramEvent,
};
use crate::study::orbit::{Forcing, Orbit, OrbitError, Shooter};
use crate::study::steady::{settle_settings, SettleSettings, FOLD_BLOCK_PERIODS};
use crate::study::sweep::{DownSweepReport, SweepReport, SweepSettings};

pub use basins::{
    basin_convergence, BasinConvergence, BASIN_CELLS, BASIN_MAX_PERIODS, BASIN_RTOL,
    BASIN_SETTLE_TOL,
};
pub use folds::{claim_folds, fold_key, FIG13_JUMP_CLAIM, FOLD_CLAIMS};
pub use ghost::{ghost_study, GhostRow, GHOST_MAX_PERIODS, GHOST_OFFSETS_HZ};

use basins::case_basins;

/// The cases, each a device, a drive level and the sweep protocol of its figure.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Case {
    /// Figure 13: prototype 2, 10 V, 0.31 g rms, linear k_im (eq 19), b_im = 0.4 N s/m.
    Fig13P2,
    /// Figure 8: prototype 1 as published, 30 V, 5.5 g rms, Hertz (eq 6), b_im = 1.5 N s/m.
    Fig08P1Published,
    /// The same with the calibrated end-stop gap.
    Fig08P1Calibrated,
}

impl Case {
    /// Every case, in the order of the tables.
    pub const ALL: [Case; 3] = [
        Case::Fig13P2,
        Case::Fig08P1Published,
        Case::Fig08P1Calibrated,
    ];

    /// Key in column values and summary numbers.
    pub fn key(self) -> &'static str {
        match self {
            Case::Fig13P2 => "fig13_p2",
            Case::Fig08P1Published => "fig08_p1_published",
            Case::Fig08P1Calibrated => "fig08_p1_calibrated",
        }
    }

    /// Label for tables and plots.
    pub fn label(self) -> &'static str {
        match self {
            Case::Fig13P2 => "Figure 13, prototype 2, 0.31 g",
            Case::Fig08P1Published => "Figure 8, prototype 1 (published), 5.5 g",
            Case::Fig08P1Calibrated => "Figure 8, prototype 1 (calibrated), 5.5 g",
        }
    }

    /// The parameter set under which the case's jump is scored.
    pub fn set(self) -> ParamSet {
        match self {
            Case::Fig08P1Calibrated => ParamSet::Calibrated,
            _ => ParamSet::Published,
        }
    }

    /// The frequency of the basin plot (Hz), where the case has one: prototype 2 at 720 Hz,
    /// the calibrated prototype 1 at the middle of its hysteresis band (between the end of
    /// the lower branch at 1300.9 Hz and the upper fold at 1390.6 Hz, from the continuation).
    pub fn basin_freq_hz(self) -> Option<f64> {
        match self {
            Case::Fig13P2 => Some(720.0),
            Case::Fig08P1Published => None,
            Case::Fig08P1Calibrated => Some(1345.0),
        }
    }
}

/// Everything one case computes from.
#[derive(Debug, Clone)]
pub struct Setup {
    /// The case.
    pub case: Case,
    /// The device with its bias and end-stop model.
    pub device: Device,
    /// RMS acceleration (g).
    pub accel_rms_g: f64,
    /// The sweeps (the figure's protocol; the down-sweep takes the same grid downwards).
    pub sweep: SweepSettings,
    /// The continuation over the sweep's range.
    pub continuation: ContinuationSettings,
    /// Transient periods before Newton if it fails from rest at the first frequency.
    pub transient_periods: usize,
}

/// The cases' setups: `p2` and `p1` as published (loaded), `p1_calibrated` the calibration's
/// device.
pub fn setups(p2: &Device, p1: &Device, p1_calibrated: &Device) -> Vec<Setup> {
    Case::ALL
        .iter()
        .map(|&case| {
            let (device, accel, sweep, step) = match case {
                Case::Fig13P2 => {
                    let d = with_endstop(&p2.with_bias(FIG13_BIAS_V), StiffnessModel::Linear, 0.4);
                    let s = fig13::sweep_settings(&d);
                    (d, 0.31, s, 2.0)
                }
                Case::Fig08P1Published | Case::Fig08P1Calibrated => {
                    let base = if case == Case::Fig08P1Published {
                        p1
                    } else {
                        p1_calibrated
                    };
                    let d = prototype1_setup(base);
                    let s = sweeps::sweep_settings(&d);
                    (d, P1_HIGH_ACCEL_RMS_G, s, P1_SWEEP_STEP_HZ)
                }
            };
            let f = &sweep.freqs_hz;
            let continuation = ContinuationSettings::frequency(f[0], f[f.len() - 1], step);
            Setup {
                case,
                device,
                accel_rms_g: accel,
                sweep,
                continuation,
                transient_periods: 200,
            }
        })
        .collect()
}

/// Failures of the response study.
#[derive(Debug, Error)]
pub enum ResponseError {
    /// A sweep's integration failed.
    #[error("{case}: sweep: {source}")]
    Sweep {
        /// Case key.
        case: &'static str,
        /// The error.
        source: SolverError,
    },
    /// Shooting, continuation or basins failed.
    #[error("{case}: {source}")]
    Orbit {
        /// Case key.
        case: &'static str,
        /// The error.
        source: OrbitError,
    },
}

/// The coexisting orbits at one frequency inside the hysteresis band.
#[derive(Debug, Clone)]
pub struct Probe {
    /// Frequency (Hz).
    pub freq_hz: f64,
    /// Every orbit of the branch there, in branch order.
    pub orbits: Vec<Orbit>,
}

impl Probe {
    /// Which of the coexisting orbits `o` is, for tables: the upper (impacting, stable), the
    /// middle (impacting, unstable) or the lower (free flight) branch's.
    pub fn orbit_label(o: &Orbit) -> &'static str {
        match (o.is_impacting(), o.is_stable()) {
            (true, true) => "upper (impacting)",
            (true, false) => "middle (impacting, unstable)",
            (false, _) => "lower (free flight)",
        }
    }
}

/// One case's results.
#[derive(Debug, Clone)]
pub struct CaseRun {
    /// The setup.
    pub setup: Setup,
    /// The up-sweep.
    pub up: SweepReport,
    /// The down-sweep.
    pub down: DownSweepReport,
    /// The continued branch.
    pub branch: Branch,
    /// The orbits at the middle of the hysteresis band (if there is a band).
    pub probe: Option<Probe>,
    /// The basins at the case's basin frequency (if it has one).
    pub basins: Option<Basins>,
    /// The attractors of the basins (label, orbit).
    pub attractors: Vec<(String, Orbit)>,
    /// Wall-clock time of the continuation alone (s).
    pub continuation_s: f64,
    /// The sweep's steady-state criterion on the ghost past the upper fold ([`ghost_study`]).
    pub ghost: Vec<GhostRow>,
    /// The same study with blocks of the ring-up time alone ([`settle_settings`]), where the
    /// sweep's blocks are longer (the criterion without the fold rule).
    pub ghost_ring_up: Vec<GhostRow>,
    /// The up-sweep again with half the sweep's blocks, where the fold rule
    /// ([`FOLD_BLOCK_PERIODS`]) sets them: the convergence of the rule.
    pub up_half_blocks: Option<SweepReport>,
    /// The branch's events as the bifurcation diagram names them ([`Diagram::from_branch`]:
    /// a corner at grazing is a grazing that turns; a branch point of a symmetric orbit whose
    /// half-period map has a multiplier at -1 is a symmetry-breaking pitchfork). Filled in by
    /// [`run_case`].
    pub named_events: Vec<DiagramEvent>,
}

impl CaseRun {
    /// The upper branch's fold: the fold (away from grazing) at the highest frequency at
    /// which the branch loses stability.
    pub fn fold_hz(&self) -> Option<f64> {
        upper_fold_hz(&self.branch)
    }

    /// Lowest and highest grazing frequencies (Hz).
    pub fn grazing_hz(&self) -> Option<(f64, f64)> {
        // A corner of the branch at grazing counts as a grazing point (its fold event is
        // located at the grazing orbit).
        let g: Vec<f64> = self.branch.grazing_events().map(|e| e.param).collect();
        if g.is_empty() {
            return None;
        }
        let lo = g.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = g.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        Some((lo, hi))
    }

    /// Where the lower (non-impacting) branch ends going down: the corner at which the
    /// unstable impacting branch meets it (a fold at grazing), else the highest grazing.
    pub fn lower_end_hz(&self) -> Option<f64> {
        let corner = self
            .branch
            .grazing_events()
            .filter(|e| !e.stable_before && e.stable_after)
            .map(|e| e.param)
            .fold(None, |m: Option<f64>, p| Some(m.map_or(p, |m| m.max(p))));
        corner.or(self.grazing_hz().map(|g| g.1))
    }

    /// The hysteresis band (lower end, upper fold), when the branch has one.
    pub fn band_hz(&self) -> Option<(f64, f64)> {
        match (self.lower_end_hz(), self.fold_hz()) {
            (Some(a), Some(b)) if a < b => Some((a, b)),
            _ => None,
        }
    }

    /// The up-sweep's jump (Hz).
    pub fn up_jump_hz(&self) -> Option<f64> {
        self.up.jump.map(|t| t.value())
    }

    /// The down-sweep's confirmed jump (Hz).
    pub fn down_jump_hz(&self) -> Option<f64> {
        self.down.jump.map(|t| t.value())
    }

    /// Where the up-sweep leaves the impacting branch: its jump, else its loss of contact (Hz).
    pub fn up_end_hz(&self) -> Option<f64> {
        self.up.branch_end().map(|e| e.transition.value())
    }

    /// Where the down-sweep leaves the lower branch: its jump, else its first contact (Hz).
    pub fn down_end_hz(&self) -> Option<f64> {
        self.down.branch_end().map(|e| e.1.value())
    }

    /// The summary numbers of the case, named `<case>_<quantity>`; a quantity that does not
    /// exist for the case is absent. No wall-clock time is among them (the summary is the same
    /// bytes on every run; the continuation's time is in the chapter's cost table).
    pub fn numbers(&self) -> Vec<(String, f64)> {
        let k = self.setup.case.key();
        let mut out = Vec::new();
        let mut put = |name: &str, v: Option<f64>| {
            if let Some(v) = v {
                out.push((format!("{k}_{name}"), v));
            }
        };
        put("up_jump_hz", self.up_jump_hz());
        put("down_jump_hz", self.down_jump_hz());
        put("fold_hz", self.fold_hz());
        put("grazing_lo_hz", self.grazing_hz().map(|g| g.0));
        put("grazing_hi_hz", self.grazing_hz().map(|g| g.1));
        put("lower_end_hz", self.lower_end_hz());
        put("up_end_hz", self.up_end_hz());
        put("down_end_hz", self.down_end_hz());
        put(
            "up_end_minus_fold_hz",
            self.up_end_hz().zip(self.fold_hz()).map(|(a, b)| a - b),
        );
        put(
            "down_end_minus_lower_end_hz",
            self.down_end_hz()
                .zip(self.lower_end_hz())
                .map(|(a, b)| a - b),
        );
        put("down_contact_power_ratio", self.down.contact_power_ratio);
        let half_end = self
            .up_half_blocks
            .as_ref()
            .and_then(|r| r.branch_end())
            .map(|e| e.transition.value());
        put("up_end_half_blocks_hz", half_end);
        put(
            "up_end_half_blocks_minus_fold_hz",
            half_end.zip(self.fold_hz()).map(|(a, b)| a - b),
        );
        put("up_jump_power_ratio", self.up.jump_power_ratio);
        put("max_residual", Some(self.branch.max_residual()));
        if let Some(b) = &self.basins {
            for (label, share) in b.shares() {
                out.push((format!("{k}_basin_share_{label}"), share));
            }
        }
        out
    }
}

/// Everything the response study computes.
#[derive(Debug, Clone)]
pub struct Run {
    /// One per case, in [`Case::ALL`] order.
    pub cases: Vec<CaseRun>,
}

impl Run {
    /// The run of a case.
    pub fn case(&self, case: Case) -> &CaseRun {
        self.cases
            .iter()
            .find(|c| c.setup.case == case)
            .expect("every case is run")
    }
}

/// The continuation of a setup from its first frequency.
pub fn continuation(setup: &Setup) -> Result<Branch, OrbitError> {
    let s = &setup.continuation;
    let start = Forcing {
        freq_hz: s.start,
        accel_rms_g: setup.accel_rms_g,
    };
    branch_from_rest(&setup.device, start, s, setup.transient_periods, &Silent)
}

/// The upper fold of a branch ([`Branch::upper_fold`]): its frequency (Hz).
pub fn upper_fold_hz(branch: &Branch) -> Option<f64> {
    branch.upper_fold().map(|e| e.param)
}

/// The phase by which an orbit's displacement lags the drive (degrees): the drive's phase at
/// the displacement's upward zero crossing, in (-90, 270]. The base acceleration drives the
/// mass in phase well below resonance (0), in quadrature at resonance (90) and in antiphase
/// well above (180): where the stops hold the RMS voltages of the upper and the unstable
/// branch to nearly the same value, their phases differ. `None` if the orbit's displacement
/// does not cross zero.
pub fn phase_lag_deg(orbit: &Orbit) -> Option<f64> {
    let t = orbit.summary.upcrossing_s?;
    let w = 2.0 * std::f64::consts::PI * orbit.forcing.freq_hz;
    let lag = (orbit.phase_rad + w * t)
        .rem_euclid(2.0 * std::f64::consts::PI)
        .to_degrees();
    Some(if lag > 270.0 { lag - 360.0 } else { lag })
}

/// The core of a case: both sweeps (in parallel) and the continuation, with nothing else
/// filled in (no probe, basins or ghost study).
pub fn sweeps_and_branch(setup: &Setup, on_step: &dyn Progress) -> Result<CaseRun, ResponseError> {
    let key = setup.case.key();
    let serr = |source| ResponseError::Sweep { case: key, source };
    let (up, down) = rayon::join(
        || setup.sweep.run(&setup.device, setup.accel_rms_g, on_step),
        || {
            setup
                .sweep
                .run_down(&setup.device, setup.accel_rms_g, on_step)
        },
    );
    let (up, down) = (up.map_err(serr)?, down.map_err(serr)?);
    let t0 = std::time::Instant::now();
    let branch =
        continuation(setup).map_err(|source| ResponseError::Orbit { case: key, source })?;
    Ok(CaseRun {
        setup: setup.clone(),
        up,
        down,
        branch,
        probe: None,
        basins: None,
        attractors: Vec::new(),
        continuation_s: t0.elapsed().as_secs_f64(),
        ghost: Vec::new(),
        ghost_ring_up: Vec::new(),
        up_half_blocks: None,
        named_events: Vec::new(),
    })
}

/// Runs one case: both sweeps, the continuation, the probe and the basins.
pub fn run_case(
    setup: &Setup,
    basin_cells: usize,
    on_step: &dyn Progress,
) -> Result<CaseRun, ResponseError> {
    let key = setup.case.key();
    let serr = |source| ResponseError::Sweep { case: key, source };
    let oerr = |source| ResponseError::Orbit { case: key, source };
    let mut run = sweeps_and_branch(setup, on_step)?;
    let h = Harvester::<4>::new(&setup.device).map_err(|e| oerr(e.into()))?;
    let shooter = Shooter::new(&h, setup.continuation.shooting);
    let mut stats = Stats::default();
    run.named_events = Diagram::from_branch(&shooter, &run.branch)
        .map_err(oerr)?
        .events;
    let cfg = &setup.sweep.cfg;
    run.ghost = ghost_study(setup, &run.branch, cfg, &GHOST_OFFSETS_HZ).map_err(oerr)?;
    if let Some(fold) = run.fold_hz() {
        let ring_up = SettleSettings {
            block_periods: settle_settings(&setup.device, fold).block_periods,
            ..cfg.clone()
        };
        if ring_up.block_periods < cfg.block_periods {
            run.ghost_ring_up =
                ghost_study(setup, &run.branch, &ring_up, &GHOST_OFFSETS_HZ).map_err(oerr)?;
        }
    }
    if cfg.block_periods == FOLD_BLOCK_PERIODS {
        let mut half = setup.sweep.clone();
        half.cfg.block_periods = FOLD_BLOCK_PERIODS / 2;
        run.up_half_blocks = Some(
            half.run(&setup.device, setup.accel_rms_g, &Silent)
                .map_err(serr)?,
        );
    }
    if let Some((a, b)) = run.band_hz() {
        let f = 0.5 * (a + b);
        let orbits = run
            .branch
            .orbits_at(&shooter, f, &mut stats)
            .map_err(oerr)?;
        run.probe = Some(Probe { freq_hz: f, orbits });
    }
    if let Some((b, attractors)) =
        case_basins(setup, &run.branch, basin_cells, &mut stats, on_step).map_err(oerr)?
    {
        run.basins = Some(b);
        run.attractors = attractors;
    }
    Ok(run)
}

/// Coarse steps of both sweeps of every setup plus the basin cells (for a progress bar).
pub fn work_units(setups: &[Setup], basin_cells: usize) -> usize {
    setups
        .iter()
        .map(|s| {
            2 * s.sweep.freqs_hz.len()
                + s.case
                    .basin_freq_hz()
                    .map_or(0, |_| basin_cells * basin_cells)
        })
        .sum()
}

/// Runs every case (in parallel) with basin grids of `basin_cells` squared cells.
pub fn run(
    setups: &[Setup],
    basin_cells: usize,
    on_step: &dyn Progress,
) -> Result<Run, ResponseError> {
    let cases = setups
        .par_iter()
        .map(|s| run_case(s, basin_cells, on_step))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Run { cases })
}

//! The whole response curve of Figures 8 and 13: both stable branches, the unstable branch
//! between them, their folds and grazing points (by shooting and pseudo-arclength
//! continuation, [`crate::study::continuation`]), the up- and down-sweeps on top
//! ([`crate::study::sweep`]), the Floquet multipliers of the coexisting orbits inside the
//! hysteresis band, and the basins of attraction there ([`crate::study::basins`]).

use rayon::prelude::*;
use thiserror::Error;

use crate::device::{Device, StiffnessModel};
use crate::drive::Sine;
use crate::ode::{SolverError, Stats};
use crate::paper::setups::{endstop, prototype1_setup, ParamSet, FIG13_BIAS_V};
use crate::paper::{fig08, fig13};
use crate::physics::harvester::Harvester;
use crate::study::basins::{basins, Attractor, BasinGrid, BasinSettings, Basins};
use crate::study::continuation::{branch_from_rest, Branch, ContinuationSettings};
use crate::study::orbit::{Forcing, Orbit, OrbitError, Shooter};
use crate::study::steady::{steady_config, SteadyConfig, FOLD_BLOCK_PERIODS};
use crate::study::sweep::{DownSweepReport, SweepReport, SweepSettings};

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

/// The continuation-only cases behind the scorecard's jump claims of Figure 8 that the
/// sweep cases above do not cover: prototype 1 at 5.5 g with another end-stop model, under
/// both parameter sets. Each is `(claim id, quantity, stiffness, b_im)`.
pub const FOLD_CLAIMS: [(&str, &str, StiffnessModel, f64); 4] = [
    ("F8-c", "jump_hertz_bim1p5_hz", StiffnessModel::Hertz, 1.5),
    ("F8-d", "jump_hertz_bim0_hz", StiffnessModel::Hertz, 0.0),
    ("F8-e", "jump_hertz_bim10_hz", StiffnessModel::Hertz, 10.0),
    ("F8-f", "jump_linear_bim2_hz", StiffnessModel::Linear, 2.0),
];

/// The claim of Figure 13's jump (prototype 2, published set), whose fold is
/// [`Case::Fig13P2`]'s.
pub const FIG13_JUMP_CLAIM: (&str, &str) = ("F13", "jump_0p31g");

/// Summary key of the fold beside a jump claim under a parameter set (`None`: the row is not a
/// jump claim).
pub fn fold_key(claim: &str, quantity: &str, set: &str) -> Option<String> {
    if (claim, quantity) == FIG13_JUMP_CLAIM && set == ParamSet::Published.label() {
        return Some(format!("{}_fold_hz", Case::Fig13P2.key()));
    }
    FOLD_CLAIMS
        .iter()
        .find(|c| c.0 == claim && c.1 == quantity)
        .map(|c| format!("{}_{set}_fold_hz", fold_case_key(c.0)))
}

fn fold_case_key(claim: &str) -> String {
    format!("claim_{}", claim.to_lowercase().replace('-', ""))
}

/// The upper fold of prototype 1 at 5.5 g for every jump claim of [`FOLD_CLAIMS`] under both
/// parameter sets, by continuation alone over Figure 8's range (extended to 2000 Hz: without
/// end-stop damping the branch reaches 1600 Hz). Returns `(summary key, fold)`; a case
/// without a fold gives no entry.
pub fn claim_folds(
    p1: &Device,
    p1_calibrated: &Device,
) -> Result<Vec<(String, f64)>, ResponseError> {
    let jobs: Vec<(String, Device)> = FOLD_CLAIMS
        .iter()
        .flat_map(|&(id, _, law, bim)| {
            [
                (ParamSet::Published, p1),
                (ParamSet::Calibrated, p1_calibrated),
            ]
            .into_iter()
            .map(move |(set, d)| {
                (
                    format!("{}_{}_fold_hz", fold_case_key(id), set.label()),
                    prototype1_setup(d).with_endstop(law, bim),
                )
            })
        })
        .collect();
    jobs.par_iter()
        .map(|(key, device)| {
            let setup = Setup {
                case: Case::Fig08P1Published,
                device: device.clone(),
                accel_rms_g: fig08::P1_HIGH_ACCEL_RMS_G,
                sweep: fig08::sweep_settings(device),
                continuation: ContinuationSettings::frequency(
                    fig08::P1_SWEEP_START_HZ,
                    2000.0,
                    fig08::P1_SWEEP_STEP_HZ,
                ),
                transient_periods: 200,
            };
            let branch = continuation(&setup).map_err(|source| ResponseError::Orbit {
                case: "claim folds",
                source,
            })?;
            Ok(upper_fold_hz(&branch).map(|f| (key.clone(), f)))
        })
        .collect::<Result<Vec<_>, _>>()
        .map(|v| v.into_iter().flatten().collect())
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

/// Grid of the basin plots: 41 x 41 initial states over +-1.5 x_max and +-1.5 w x_max.
pub const BASIN_CELLS: usize = 41;

/// Largest number of drive periods per basin cell (prototype 2's lower orbit has its largest
/// multiplier at 0.97: some 250 periods to settle to 1e-3 from a distance of order one).
pub const BASIN_MAX_PERIODS: usize = 4000;

/// Scaled distance at which a basin cell has settled on an attractor.
pub const BASIN_SETTLE_TOL: f64 = 1e-3;

impl Setup {
    /// The basin settings of the case at its basin frequency (the grid spans 1.5 times the
    /// gap and 1.5 times the gap times the angular drive frequency).
    pub fn basin_settings(&self, cells: usize) -> Option<BasinSettings> {
        let f = self.case.basin_freq_hz()?;
        let xmax = endstop(&self.device).gap_m;
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
            rtol: self.continuation.shooting.rtol,
        })
    }
}

/// The cases' setups: `p2` and `p1` as published (loaded), `p1_calibrated` the calibration's
/// device.
pub fn setups(p2: &Device, p1: &Device, p1_calibrated: &Device) -> Vec<Setup> {
    Case::ALL
        .iter()
        .map(|&case| {
            let (device, accel, sweep, step) = match case {
                Case::Fig13P2 => {
                    let d = p2
                        .with_bias(FIG13_BIAS_V)
                        .with_endstop(StiffnessModel::Linear, 0.4);
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
                    let s = fig08::sweep_settings(&d);
                    (d, fig08::P1_HIGH_ACCEL_RMS_G, s, fig08::P1_SWEEP_STEP_HZ)
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
    /// The same study with blocks of the ring-up time alone ([`steady_config`]), where the
    /// sweep's blocks are longer (the criterion without the fold rule).
    pub ghost_ring_up: Vec<GhostRow>,
    /// The up-sweep again with half the sweep's blocks, where the fold rule
    /// ([`FOLD_BLOCK_PERIODS`]) sets them: the convergence of the rule.
    pub up_half_blocks: Option<SweepReport>,
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
    branch_from_rest(&setup.device, start, s, setup.transient_periods, |_| {})
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

/// The upper fold of a branch ([`Branch::upper_fold`]): its frequency (Hz).
pub fn upper_fold_hz(branch: &Branch) -> Option<f64> {
    branch.upper_fold().map(|e| e.param)
}

/// Offsets above the upper fold at which the stepped sweep's steady-state criterion is
/// tested on the saddle-node's ghost (Hz).
pub const GHOST_OFFSETS_HZ: [f64; 7] = [0.1, 0.25, 0.5, 1.0, 1.5, 2.0, 3.0];

/// Largest number of periods followed when counting how long the ghost keeps impacting.
pub const GHOST_MAX_PERIODS: usize = 4000;

/// The stepped sweep's steady-state criterion just past the upper fold, where no impacting
/// orbit exists: one step from the upper orbit 1 Hz below the fold.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GhostRow {
    /// Frequency above the fold (Hz).
    pub offset_hz: f64,
    /// The criterion's block length (periods).
    pub block_periods: usize,
    /// The criterion's measurement is in contact (it accepts the dying orbit as steady).
    pub accepted_in_contact: bool,
    /// Measured blocks the criterion used.
    pub blocks: usize,
    /// Periods the criterion simulated (settling and measured blocks).
    pub periods_simulated: usize,
    /// The last period with contact when the same start is followed for
    /// [`GHOST_MAX_PERIODS`] periods (the life of the ghost).
    pub last_contact_period: usize,
}

/// The ghost study of a case under the steady-state criterion `cfg`, at `offsets_hz` above
/// the upper fold of `branch` (empty without an upper fold).
pub fn ghost_study(
    setup: &Setup,
    branch: &Branch,
    cfg: &SteadyConfig,
    offsets_hz: &[f64],
) -> Result<Vec<GhostRow>, OrbitError> {
    let Some(fold) = upper_fold_hz(branch) else {
        return Ok(Vec::new());
    };
    let h = Harvester::new(
        &setup.device,
        Sine::from_rms_g(setup.accel_rms_g, setup.continuation.start),
    );
    let shooter = Shooter::new(&h, setup.continuation.shooting);
    let mut stats = Stats::default();
    let below = fold - 1.0;
    let upper = branch
        .orbits_at(&shooter, below, &mut stats)?
        .into_iter()
        .find(|o| o.is_stable() && o.is_impacting())
        .ok_or(OrbitError::Invalid(format!(
            "no stable impacting orbit 1 Hz below the fold at {fold} Hz"
        )))?;
    let y0 = shooter
        .state_at_phase(&upper, 0.0)
        .map_err(|e| OrbitError::Solver {
            what: "frequency (Hz)",
            param: below,
            source: e,
        })?;
    offsets_hz
        .iter()
        .map(|&df| {
            let f = fold + df;
            let serr = |e| OrbitError::Solver {
                what: "frequency (Hz)",
                param: f,
                source: e,
            };
            let model = h.with_excitation(Sine::from_rms_g(setup.accel_rms_g, f));
            let (m, _, _, _) = crate::study::steady::steady_state(
                &model,
                y0,
                crate::study::orbit::mode_of(&h, &y0),
                setup.accel_rms_g,
                cfg,
            )
            .map_err(serr)?;
            let forcing = Forcing {
                freq_hz: f,
                accel_rms_g: setup.accel_rms_g,
            };
            let mut y = y0;
            let mut last_contact = 0;
            for k in 1..=GHOST_MAX_PERIODS {
                let mut contact = false;
                let (y1, _, _) = shooter
                    .flow(&forcing, 0.0, y, forcing.period_s(), |_, mode| {
                        contact |= mode.in_contact()
                    })
                    .map_err(serr)?;
                y = y1;
                if contact {
                    last_contact = k;
                } else if k > last_contact + 50 {
                    break;
                }
            }
            Ok(GhostRow {
                offset_hz: df,
                block_periods: cfg.block_periods,
                accepted_in_contact: m.contact_fraction > 0.0,
                blocks: m.blocks,
                periods_simulated: (cfg.settle_blocks + m.blocks) * cfg.block_periods,
                last_contact_period: last_contact,
            })
        })
        .collect()
}

/// The core of a case: both sweeps (in parallel) and the continuation, with nothing else
/// filled in (no probe, basins or ghost study).
pub fn sweeps_and_branch(
    setup: &Setup,
    on_step: &(dyn Fn() + Sync),
) -> Result<CaseRun, ResponseError> {
    let key = setup.case.key();
    let serr = |source| ResponseError::Sweep { case: key, source };
    let (up, down) = rayon::join(
        || {
            setup
                .sweep
                .run(&setup.device, setup.accel_rms_g, |_| on_step())
        },
        || {
            setup
                .sweep
                .run_down(&setup.device, setup.accel_rms_g, |_| on_step())
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
    })
}

/// Runs one case: both sweeps, the continuation, the probe and the basins.
pub fn run_case(
    setup: &Setup,
    basin_cells: usize,
    on_step: &(dyn Fn() + Sync),
) -> Result<CaseRun, ResponseError> {
    let key = setup.case.key();
    let serr = |source| ResponseError::Sweep { case: key, source };
    let oerr = |source| ResponseError::Orbit { case: key, source };
    let mut run = sweeps_and_branch(setup, on_step)?;
    let h = Harvester::new(
        &setup.device,
        Sine::from_rms_g(setup.accel_rms_g, setup.continuation.start),
    );
    let shooter = Shooter::new(&h, setup.continuation.shooting);
    let mut stats = Stats::default();
    let cfg = &setup.sweep.cfg;
    run.ghost = ghost_study(setup, &run.branch, cfg, &GHOST_OFFSETS_HZ).map_err(oerr)?;
    if let Some(fold) = run.fold_hz() {
        let ring_up = SteadyConfig {
            block_periods: steady_config(&setup.device, fold).block_periods,
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
            half.run(&setup.device, setup.accel_rms_g, |_| {})
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
    if let Some(bs) = setup.basin_settings(basin_cells) {
        let f = setup.case.basin_freq_hz().expect("a basin frequency");
        let orbits = run
            .branch
            .orbits_at(&shooter, f, &mut stats)
            .map_err(oerr)?;
        let mut attractors = Vec::new();
        let mut catalogue = Vec::new();
        for o in orbits.into_iter().filter(|o| o.is_stable()) {
            let label = attractor_label(&o);
            catalogue.push(Attractor::of_orbit(&shooter, &o, label).map_err(oerr)?);
            attractors.push((label.to_string(), o));
        }
        let forcing = Forcing {
            freq_hz: f,
            accel_rms_g: setup.accel_rms_g,
        };
        run.basins = Some(basins(&h, &forcing, &catalogue, &bs, on_step).map_err(oerr)?);
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
    on_step: &(dyn Fn() + Sync),
) -> Result<Run, ResponseError> {
    let cases = setups
        .par_iter()
        .map(|s| run_case(s, basin_cells, on_step))
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Run { cases })
}

//! The stepped sweep's steady-state criterion on the ghost of the upper fold: just past the
//! fold no impacting orbit exists, but a start from the upper orbit keeps touching the stops
//! for many periods, and a criterion with short blocks can accept that dying state as steady.

use crate::drive::Sine;
use crate::model::Model;
use crate::ode::Stats;
use crate::physics::harvester::Harvester;
use crate::study::continuation::Branch;
use crate::study::orbit::{Forcing, OrbitError, Shooter};
use crate::study::steady::SettleSettings;

use super::{upper_fold_hz, Setup};

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
    cfg: &SettleSettings,
    offsets_hz: &[f64],
) -> Result<Vec<GhostRow>, OrbitError> {
    let Some(fold) = upper_fold_hz(branch) else {
        return Ok(Vec::new());
    };
    let h = Harvester::<4>::new(&setup.device)?;
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
            let (m, _, _, _) = crate::study::steady::steady_state(
                &h,
                Sine::from_rms_g(setup.accel_rms_g, f),
                y0,
                h.mode_of(&y0),
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

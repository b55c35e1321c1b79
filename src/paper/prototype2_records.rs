//! Prototype 2 under random vibration (Figures 14 and 15): one list of levels and one protocol
//! whose ensembles both figures read. Figure 14 takes every level ([`LEVELS`]); Figure 15 takes
//! the three the list marks as its own ([`Fig15Level`]), which carry MATLAB's default Welch
//! segmenting beside the figures' own. A run of the protocol is therefore both figures'
//! records at once ([`Run`]), and a run of Figure 15's levels alone is the same records, since
//! every ensemble's streams are keyed by its level
//! ([`first_stream_for_level`](crate::study::ensemble::first_stream_for_level)).
//!
//! Beside the levels the protocol can run what only Figure 14's chapter shows
//! ([`Extras`]): the end-stop readings one switch away at claim F14-b's level, and the
//! convergence check of the records at a tight tolerance.

use rayon::prelude::*;

use crate::device::{Device, StiffnessModel};
use crate::paper::ensembles::{
    protocol_spec, run_levels, Level, LevelCase, P2_BAND_HZ, P2_NPERSEG,
};
use crate::paper::setups::{prototype2_setup, with_endstop, ParamSet};
use crate::progress::Progress;
use crate::study::record::{simulate_record, RecordError, Scheme};

/// One of Figure 15's three levels.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Fig15Level {
    /// 0.34e-3 g²/Hz (claim F15-a, and the base of every ratio).
    L034,
    /// 0.55e-3 g²/Hz (claim F15-b).
    L055,
    /// 1.69e-3 g²/Hz (claim F15-c, and claim F14-b's level).
    L169,
}

impl Fig15Level {
    /// Figure 15's levels, in increasing PSD.
    pub const ALL: [Fig15Level; 3] = [Fig15Level::L034, Fig15Level::L055, Fig15Level::L169];

    /// The position of the level in [`Fig15Level::ALL`] (and in Figure 15's runs).
    pub const fn index(self) -> usize {
        match self {
            Fig15Level::L034 => 0,
            Fig15Level::L055 => 1,
            Fig15Level::L169 => 2,
        }
    }

    /// The level's index in [`LEVELS`].
    pub const fn in_levels(self) -> usize {
        let mut i = 0;
        while i < LEVELS.len() {
            if let Some(l) = LEVELS[i].fig15 {
                if l.index() == self.index() {
                    return i;
                }
            }
            i += 1;
        }
        panic!("every level of Figure 15 is in LEVELS")
    }

    /// Two-sided acceleration PSD (g²/Hz).
    pub const fn psd_g2_per_hz(self) -> f64 {
        LEVELS[self.in_levels()].psd_g2_per_hz
    }
}

/// One level of the protocol.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct P2Level {
    /// Two-sided acceleration PSD (g²/Hz).
    pub psd_g2_per_hz: f64,
    /// Which of Figure 15's levels it is, if it is one.
    pub fig15: Option<Fig15Level>,
}

const fn grid(psd_g2_per_hz: f64) -> P2Level {
    P2Level {
        psd_g2_per_hz,
        fig15: None,
    }
}

const fn fig15(psd_g2_per_hz: f64, level: Fig15Level) -> P2Level {
    P2Level {
        psd_g2_per_hz,
        fig15: Some(level),
    }
}

/// The levels (g²/Hz), in increasing PSD: Figure 14's logarithmic grid from 1e-5 to 2e-3, which
/// includes the paper's 0.34e-3, 0.55e-3 and 1.69e-3 of Figure 15.
pub const LEVELS: [P2Level; 10] = [
    grid(1e-5),
    grid(2e-5),
    grid(5e-5),
    grid(1e-4),
    grid(2e-4),
    fig15(0.34e-3, Fig15Level::L034),
    fig15(0.55e-3, Fig15Level::L055),
    grid(1e-3),
    fig15(1.69e-3, Fig15Level::L169),
    grid(2e-3),
];

/// Records per level. A record's efficiency scatters by about 6 % (relative) in the linear
/// regime (10 s span only some 150 correlation times of a 12 Hz wide response), so 32 give a
/// 95 % CI of about 2 % per level, and the linear levels pooled about 1 %; they are enough
/// for 5-95 % quantiles of single-record widths and 1024 record pairs per ratio (Figure 15).
pub const REALISATIONS: usize = 32;

/// Relative tolerance of the convergence check, a hundred times tighter than the default.
pub const TIGHT_RTOL: f64 = 1e-9;

/// Records per checked level run again at [`TIGHT_RTOL`].
pub const CONVERGENCE_RECORDS: usize = 2;

/// Which levels a run simulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Levels {
    /// Every level of [`LEVELS`] (Figure 14, and Figure 15 from the same records).
    All,
    /// Figure 15's three alone.
    Fig15,
}

/// What a run simulates beside its levels (the claims need neither).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Extras {
    /// The end-stop readings one switch away at claim F14-b's level, on the same records:
    /// Hertz contact with the paper's equally good b_im = 0.34 N s/m, and a tension-free
    /// contact (eq 1 clipped at zero).
    pub other_readings: bool,
    /// The first [`CONVERGENCE_RECORDS`] records of the lowest level and of F14-b's level
    /// again at [`TIGHT_RTOL`].
    pub convergence: bool,
}

impl Extras {
    /// Everything Figure 14's chapter shows.
    pub const FULL: Extras = Extras {
        other_readings: true,
        convergence: true,
    };

    /// The levels only, which is all the claims need.
    pub const NONE: Extras = Extras {
        other_readings: false,
        convergence: false,
    };
}

/// What a run simulates.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Scope {
    /// The levels.
    pub levels: Levels,
    /// Records per level (the first of every level's streams).
    pub records: usize,
    /// What else.
    pub extras: Extras,
}

impl Scope {
    /// Records a run of this scope simulates (the unit of its progress).
    pub fn records_simulated(&self) -> usize {
        let levels = match self.levels {
            Levels::All => LEVELS.len(),
            Levels::Fig15 => Fig15Level::ALL.len(),
        };
        let readings = if self.extras.other_readings { 2 } else { 0 };
        (levels + readings) * self.records
    }
}

/// One record run at the default and at the tight tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Convergence {
    /// Index of the level in [`LEVELS`].
    pub level: usize,
    /// Index of the record in its ensemble.
    pub record: usize,
    /// Power of both loads at the default tolerance (W).
    pub p_w: f64,
    /// The same at [`TIGHT_RTOL`] (W).
    pub p_tight_w: f64,
}

/// The simulations of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Prototype 2 as simulated ([`prototype2_setup`]).
    pub device: Device,
    /// One ensemble per level simulated, in the order of [`LEVELS`]; each level's `index` is
    /// its index there.
    pub levels: Vec<Level>,
    /// The other end-stop readings at F14-b's level (empty unless asked for).
    pub other_readings: Vec<Level>,
    /// The convergence check (empty unless asked for).
    pub convergence: Vec<Convergence>,
}

impl Run {
    /// The ensemble of one of Figure 15's levels (`None` if the run did not simulate it).
    pub fn fig15_level(&self, which: Fig15Level) -> Option<&Level> {
        self.levels.iter().find(|l| l.index == which.in_levels())
    }
}

/// The level of index `index` in [`LEVELS`] as an ensemble to run, for `device` under a
/// reading of the end-stop (`None`: the figure's own).
fn case(device: &Device, index: usize, records: usize, variant: Option<&str>) -> LevelCase {
    let level = LEVELS[index];
    LevelCase {
        set: ParamSet::Published,
        variant: variant.map(str::to_string),
        index,
        device: device.clone(),
        spec: protocol_spec(
            device,
            level.psd_g2_per_hz,
            P2_NPERSEG,
            P2_BAND_HZ,
            records,
            // Figure 15's levels carry its second segmenting.
            variant.is_none() && level.fig15.is_some(),
        ),
    }
}

/// Runs the protocol for prototype 2 (the parameter file's device; [`prototype2_setup`] is
/// applied here), calling `progress` after each record of the ensembles.
pub fn run(prototype2: &Device, scope: Scope, progress: &dyn Progress) -> Result<Run, RecordError> {
    let dev = prototype2_setup(prototype2);
    let indices: Vec<usize> = match scope.levels {
        Levels::All => (0..LEVELS.len()).collect(),
        Levels::Fig15 => Fig15Level::ALL.iter().map(|l| l.in_levels()).collect(),
    };
    let mut cases: Vec<LevelCase> = indices
        .iter()
        .map(|&i| case(&dev, i, scope.records, None))
        .collect();
    let f14b = Fig15Level::L169.in_levels();
    if scope.extras.other_readings {
        let tension_free = dev.with_tension_free(true);
        let hertz = with_endstop(&dev, StiffnessModel::Hertz, 0.34);
        cases.push(case(
            &hertz,
            f14b,
            scope.records,
            Some("Hertz contact (eq 6), b_im = 0.34 N s/m"),
        ));
        cases.push(case(
            &tension_free,
            f14b,
            scope.records,
            Some("linear k_im, b_im = 0.4 N s/m, tension-free"),
        ));
    }
    let mut levels = run_levels(cases, progress)?;
    let other_readings = levels.split_off(indices.len());
    let convergence = if scope.extras.convergence {
        convergence_check(&dev, &levels, &[indices[0], f14b])?
    } else {
        Vec::new()
    };
    Ok(Run {
        device: dev,
        levels,
        other_readings,
        convergence,
    })
}

/// Runs the first records of the levels `checked` (indices into [`LEVELS`]) again with
/// Dormand-Prince everywhere ([`Scheme::Dopri5`], no exponential free-flight step) at
/// [`TIGHT_RTOL`]. Without impacts the trajectory itself converges; with impacts it does not
/// (nearby trajectories part after a few impacts), and only the statistics can: the change
/// must then be small against the record-to-record scatter.
fn convergence_check(
    dev: &Device,
    levels: &[Level],
    checked: &[usize],
) -> Result<Vec<Convergence>, RecordError> {
    let jobs: Vec<(&Level, usize)> = checked
        .iter()
        .filter_map(|&i| levels.iter().find(|l| l.index == i))
        .flat_map(|l| (0..CONVERGENCE_RECORDS).map(move |r| (l, r)))
        .collect();
    jobs.into_par_iter()
        .map(|(level, record)| {
            let e = &level.ens;
            let mut spec = e.spec.record;
            spec.rtol = TIGHT_RTOL;
            spec.scheme = Scheme::Dopri5;
            let r = simulate_record(dev, &spec, e.spec.seed, e.spec.first_stream + record as u64)?;
            Ok(Convergence {
                level: level.index,
                record,
                p_w: e.records[record].summary.p_total_w(),
                p_tight_w: r.summary.p_total_w(),
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_levels_rise_and_figure_15_has_three_in_order() {
        assert!(LEVELS
            .windows(2)
            .all(|w| w[0].psd_g2_per_hz < w[1].psd_g2_per_hz));
        let marked: Vec<Fig15Level> = LEVELS.iter().filter_map(|l| l.fig15).collect();
        assert_eq!(marked, Fig15Level::ALL);
        for l in Fig15Level::ALL {
            assert_eq!(LEVELS[l.in_levels()].fig15, Some(l));
        }
    }
}

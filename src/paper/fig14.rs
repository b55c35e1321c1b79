//! Figure 14: prototype 2 at 15 V (linear k_im of eq 19, b_im = 0.4 N s/m), harvested power
//! and efficiency against the input level, with the linear theory of eq 21 (claims F14-a and
//! F14-b).

use rayon::prelude::*;

use crate::device::{Device, StiffnessModel};
use crate::num::stats::MeanCi;
use crate::paper::claims::{Claims, Value};
use crate::paper::ensembles::{
    level_label, protocol_spec, run_levels, Level, LevelCase, P2_BAND_HZ, P2_NPERSEG,
};
use crate::paper::setups::prototype2_setup;
use crate::physics::two_port::{efficiency, eq21_efficiency};
use crate::study::ensemble::Ensemble;
use crate::study::record::{simulate_record, BroadbandError, Scheme};

/// Figure 14's levels (g²/Hz): a logarithmic grid from 1e-5 to 2e-3 that includes the paper's
/// 0.34e-3, 0.55e-3 and 1.69e-3.
pub const FIG14_LEVELS: [f64; 10] = [
    1e-5, 2e-5, 5e-5, 1e-4, 2e-4, 0.34e-3, 0.55e-3, 1e-3, 1.69e-3, 2e-3,
];

/// Index in [`FIG14_LEVELS`] of claim F14-b's level, 1.69e-3 g²/Hz.
pub const F14B_LEVEL: usize = 8;

/// Records per level in Figure 14. A record's efficiency scatters by about 6 % (relative) in
/// the linear regime (10 s span only some 150 correlation times of a 12 Hz wide response), so
/// 32 give a 95 % CI of about 2 % per level, and the linear levels pooled about 1 %.
pub const FIG14_REALISATIONS: usize = 32;

/// "Impacts are frequent" (the paper's wording for the sublinear regime of Figure 14): the
/// mass spends at least this fraction of the time in contact.
pub const FREQUENT_CONTACT: f64 = 1e-5;

/// Relative tolerance of the convergence check, a hundred times tighter than the default.
pub const TIGHT_RTOL: f64 = 1e-9;

/// Records per checked level run again at [`TIGHT_RTOL`].
pub const CONVERGENCE_RECORDS: usize = 2;

/// What Figure 14 runs beside its levels (the claims need neither).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Protocol {
    /// The end-stop readings one switch away at claim F14-b's level, on the same records:
    /// Hertz contact with the paper's equally good b_im = 0.34 N s/m, and a tension-free
    /// contact (eq 1 clipped at zero).
    pub other_readings: bool,
    /// The first [`CONVERGENCE_RECORDS`] records of the lowest level and of F14-b's level
    /// again at [`TIGHT_RTOL`].
    pub convergence: bool,
}

impl Protocol {
    /// Everything the figure's chapter shows.
    pub const FULL: Protocol = Protocol {
        other_readings: true,
        convergence: true,
    };

    /// The levels only, which is all the claims need.
    pub const CLAIMS: Protocol = Protocol {
        other_readings: false,
        convergence: false,
    };
}

/// One record run at the default and at the tight tolerance.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Convergence {
    /// Index of the level in [`FIG14_LEVELS`].
    pub level: usize,
    /// Index of the record in its ensemble.
    pub record: usize,
    /// Power of both loads at the default tolerance (W).
    pub p_w: f64,
    /// The same at [`TIGHT_RTOL`] (W).
    pub p_tight_w: f64,
}

/// The simulations of Figure 14.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// Prototype 2 as simulated ([`prototype2_setup`]).
    pub device: Device,
    /// One ensemble per level of [`FIG14_LEVELS`], in order.
    pub levels: Vec<Level>,
    /// The other end-stop readings at F14-b's level (empty unless asked for).
    pub other_readings: Vec<Level>,
    /// The convergence check (empty unless asked for).
    pub convergence: Vec<Convergence>,
}

/// Runs Figure 14 for prototype 2 (the parameter file's device), calling `progress` after each
/// record of the ensembles.
pub fn run(
    prototype2: &Device,
    protocol: Protocol,
    progress: &(dyn Fn() + Sync),
) -> Result<Run, BroadbandError> {
    let dev = prototype2_setup(prototype2);
    let case = |set: &str, index: usize, d: &Device| LevelCase {
        set: set.to_string(),
        index,
        device: d.clone(),
        spec: protocol_spec(
            d,
            FIG14_LEVELS[index],
            P2_NPERSEG,
            P2_BAND_HZ,
            FIG14_REALISATIONS,
            // Figure 15's levels carry its second segmenting, so that Figure 15 can take
            // these ensembles ([`crate::paper::fig15::from_fig14`]).
            set == "published" && crate::paper::fig15::IN_FIG14.contains(&index),
        ),
    };
    let mut cases: Vec<LevelCase> = (0..FIG14_LEVELS.len())
        .map(|i| case("published", i, &dev))
        .collect();
    if protocol.other_readings {
        let tension_free = dev.with_tension_free(true);
        let hertz = dev.with_endstop(StiffnessModel::Hertz, 0.34);
        cases.push(case(
            "Hertz contact (eq 6), b_im = 0.34 N s/m",
            F14B_LEVEL,
            &hertz,
        ));
        cases.push(case(
            "linear k_im, b_im = 0.4 N s/m, tension-free",
            F14B_LEVEL,
            &tension_free,
        ));
    }
    let mut levels = run_levels(cases, progress)?;
    let other_readings = levels.split_off(FIG14_LEVELS.len());
    let convergence = if protocol.convergence {
        convergence_check(&dev, &levels)?
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

/// Runs the first records of the lowest level and of F14-b's level again with Dormand-Prince
/// everywhere ([`Scheme::Dopri5`], no exponential free-flight step) at [`TIGHT_RTOL`].
/// Without impacts the trajectory itself converges; with impacts it does not (nearby
/// trajectories part after a few impacts), and only the statistics can: the change must then
/// be small against the record-to-record scatter.
fn convergence_check(dev: &Device, levels: &[Level]) -> Result<Vec<Convergence>, BroadbandError> {
    let jobs: Vec<(usize, usize)> = [0, F14B_LEVEL]
        .iter()
        .flat_map(|&l| (0..CONVERGENCE_RECORDS).map(move |i| (l, i)))
        .collect();
    jobs.into_par_iter()
        .map(|(level, record)| {
            let e = &levels[level].ens;
            let mut spec = e.spec.record;
            spec.rtol = TIGHT_RTOL;
            spec.scheme = Scheme::Dopri5;
            let r = simulate_record(dev, &spec, e.spec.seed, e.spec.first_stream + record as u64)?;
            Ok(Convergence {
                level,
                record,
                p_w: e.records[record].summary.p_total_w(),
                p_tight_w: r.summary.p_total_w(),
            })
        })
        .collect()
}

/// Efficiency `2P/(m Sa)` of every record of the ensembles pooled (in the linear regime the
/// efficiency does not depend on the level): mean and 95 % CI over the records (claim F14-a).
pub fn pooled_efficiency(device: &Device, ensembles: &[&Ensemble]) -> MeanCi {
    let effs: Vec<f64> = ensembles
        .iter()
        .flat_map(|e| {
            let sa = e.psd_g2_per_hz();
            e.records
                .iter()
                .map(move |r| efficiency(device, r.summary.p_total_w(), sa))
        })
        .collect();
    MeanCi::of(&effs)
}

/// Sublinear growth of the power with `Sa` (claim F14-b): starting from the linear-regime
/// efficiency `linear`, the efficiency of every ensemble (in increasing `Sa`) whose mean time
/// in contact is at least [`FREQUENT_CONTACT`] is below that of the one before (`P/Sa`
/// falls), and the last is below the linear value by more than both 95 % CIs. False when no
/// ensemble has frequent impacts.
pub fn sublinear_growth(linear: &MeanCi, ensembles: &[&Ensemble]) -> bool {
    let frequent: Vec<&&Ensemble> = ensembles
        .iter()
        .filter(|e| e.contact_fraction.mean >= FREQUENT_CONTACT)
        .collect();
    let mut prev = linear.mean;
    let mut falling = !frequent.is_empty();
    for e in &frequent {
        falling &= e.efficiency.mean < prev;
        prev = e.efficiency.mean;
    }
    let last_drop = frequent
        .last()
        .is_some_and(|e| linear.mean - e.efficiency.mean > linear.ci95 + e.efficiency.ci95);
    falling && last_drop
}

/// What Figure 14 shows.
#[derive(Debug, Clone, PartialEq)]
pub struct Findings {
    /// Efficiency of eq 21 (fraction).
    pub eq21: f64,
    /// Indices of the levels where no record touched a stop.
    pub linear_levels: Vec<usize>,
    /// Efficiency of the records of those levels pooled ([`pooled_efficiency`]).
    pub pooled: MeanCi,
    /// `(pooled - eq 21)` in standard errors of the pooled mean.
    pub pooled_minus_eq21_se: f64,
    /// Indices of the levels with frequent impacts ([`FREQUENT_CONTACT`]).
    pub frequent_levels: Vec<usize>,
    /// Sublinear growth ([`sublinear_growth`] from the pooled efficiency).
    pub sublinear: bool,
    /// Local log-log slope of the mean power between neighbouring levels: (from, to, slope).
    pub slopes: Vec<(usize, usize, f64)>,
}

/// Figure 14's findings.
pub fn findings(run: &Run) -> Findings {
    let linear_levels: Vec<usize> = run
        .levels
        .iter()
        .filter(|l| l.ens.no_impact())
        .map(|l| l.index)
        .collect();
    let linear: Vec<&Ensemble> = linear_levels.iter().map(|&i| &run.levels[i].ens).collect();
    let pooled = pooled_efficiency(&run.device, &linear);
    let all: Vec<&Ensemble> = run.levels.iter().map(|l| &l.ens).collect();
    let eq21 = eq21_efficiency(&run.device);
    Findings {
        eq21,
        pooled_minus_eq21_se: (pooled.mean - eq21) / (pooled.std / (pooled.n as f64).sqrt()),
        frequent_levels: run
            .levels
            .iter()
            .filter(|l| l.ens.contact_fraction.mean >= FREQUENT_CONTACT)
            .map(|l| l.index)
            .collect(),
        sublinear: sublinear_growth(&pooled, &all),
        slopes: run
            .levels
            .windows(2)
            .map(|w| {
                let p = w[1].ens.power_w.mean / w[0].ens.power_w.mean;
                (
                    w[0].index,
                    w[1].index,
                    p.ln() / (w[1].sa() / w[0].sa()).ln(),
                )
            })
            .collect(),
        linear_levels,
        pooled,
    }
}

/// Claims F14-a (simulated efficiency in the linear regime) and F14-b (efficiency at 1.69e-3
/// g²/Hz and sublinear growth), published set. Eq 21's efficiency (F14-a) is Table 3's.
pub fn claims(run: &Run, _claims: &Claims) -> Vec<Value> {
    let f = findings(run);
    let labels = |idx: &[usize]| -> String {
        idx.iter()
            .map(|&i| level_label(FIG14_LEVELS[i]))
            .collect::<Vec<_>>()
            .join(", ")
    };
    let b = &run.levels[F14B_LEVEL].ens.efficiency;
    vec![
        Value::new(
            "F14-a",
            "eff_sim_linear_pct",
            "published",
            f.pooled.mean * 100.0,
            Some(f.pooled.ci95 * 100.0),
            format!(
                "{} records of the levels without impact ({}) pooled; CI: Student t",
                f.pooled.n,
                labels(&f.linear_levels)
            ),
        ),
        Value::new(
            "F14-b",
            "eff_1p69e-3_pct",
            "published",
            b.mean * 100.0,
            Some(b.ci95 * 100.0),
            format!("mean of {} records; CI: Student t", b.n),
        ),
        Value::yes_no(
            "F14-b",
            "sublinear_power_growth",
            "published",
            f.sublinear,
            format!(
                "efficiency falls level by level where in contact at least {FREQUENT_CONTACT} \
                 of the time ({})",
                labels(&f.frequent_levels)
            ),
        ),
    ]
}

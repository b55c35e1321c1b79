//! Figure 14: prototype 2 at 15 V (linear k_im of eq 19, b_im = 0.4 N s/m), harvested power
//! and efficiency against the input level, with the linear theory of eq 21 (claims F14-a and
//! F14-b).

use crate::device::Device;
use crate::num::stats::MeanCi;
use crate::paper::claims::{keys, Claims, ClaimsError, Value};
use crate::paper::ensembles::level_label;
use crate::paper::prototype2_records::{self, Extras, Fig15Level, Levels, Scope, LEVELS};
use crate::paper::setups::ParamSet;
use crate::paper::Figure;
use crate::physics::two_port::{efficiency, eq21_efficiency};
use crate::progress::Progress;
use crate::study::ensemble::Ensemble;
use crate::study::record::RecordError;

pub use crate::paper::prototype2_records::{Convergence, TIGHT_RTOL};

/// Figure 14's levels (g²/Hz): the protocol's ([`LEVELS`]), a logarithmic grid from 1e-5 to
/// 2e-3 that includes the paper's 0.34e-3, 0.55e-3 and 1.69e-3.
pub const FIG14_LEVELS: [f64; LEVELS.len()] = {
    let mut out = [0.0; LEVELS.len()];
    let mut i = 0;
    while i < LEVELS.len() {
        out[i] = LEVELS[i].psd_g2_per_hz;
        i += 1;
    }
    out
};

/// Index in [`FIG14_LEVELS`] of claim F14-b's level, 1.69e-3 g²/Hz (Figure 15's highest).
pub const F14B_LEVEL: usize = Fig15Level::L169.in_levels();

/// Records per level in Figure 14 ([`prototype2_records::REALISATIONS`]).
pub const FIG14_REALISATIONS: usize = prototype2_records::REALISATIONS;

/// "Impacts are frequent" (the paper's wording for the sublinear regime of Figure 14): the
/// mass spends at least this fraction of the time in contact.
pub const FREQUENT_CONTACT: f64 = 1e-5;

/// The simulations of Figure 14: the protocol run at every level ([`Levels::All`]).
pub type Run = prototype2_records::Run;

/// What Figure 14 runs on.
#[derive(Debug, Clone, PartialEq)]
pub struct Setup {
    /// Prototype 2 as published ([`crate::paper::setups::prototype2_setup`] is applied in the
    /// run).
    pub prototype2: Device,
    /// What the run simulates beside the levels: [`Extras::FULL`] for the chapter,
    /// [`Extras::NONE`] for the claims alone.
    pub extras: Extras,
}

impl Setup {
    /// The protocol's scope of this setup.
    pub fn scope(&self) -> Scope {
        Scope {
            levels: Levels::All,
            records: FIG14_REALISATIONS,
            extras: self.extras,
        }
    }
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

/// Figure 14: prototype 2's power and efficiency against the level, with eq 21.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig14;

impl Figure for Fig14 {
    const NAME: &'static str = "fig14";
    type Setup = Setup;
    type Run = Run;
    type Error = RecordError;

    fn work(setup: &Setup) -> usize {
        setup.scope().records_simulated()
    }

    /// Runs the protocol at every level for prototype 2, calling `progress` after each record
    /// of the ensembles.
    fn run(setup: &Setup, progress: &dyn Progress) -> Result<Run, RecordError> {
        prototype2_records::run(&setup.prototype2, setup.scope(), progress)
    }

    /// Claims F14-a (simulated efficiency in the linear regime) and F14-b (efficiency at
    /// 1.69e-3 g²/Hz and sublinear growth), published set. Eq 21's efficiency (F14-a) is
    /// Table 3's.
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let f = findings(run);
        let labels = |idx: &[usize]| -> String {
            idx.iter()
                .map(|&i| level_label(FIG14_LEVELS[i]))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let b = &run.levels[F14B_LEVEL].ens.efficiency;
        let set = ParamSet::Published;
        claims.known(vec![
            Value::new(
                keys::F14A_EFF_SIM_LINEAR,
                set,
                f.pooled.mean * 100.0,
                Some(f.pooled.ci95 * 100.0),
                format!(
                    "{} records of the levels without impact ({}) pooled; CI: Student t",
                    f.pooled.n,
                    labels(&f.linear_levels)
                ),
            ),
            Value::new(
                keys::F14B_EFF,
                set,
                b.mean * 100.0,
                Some(b.ci95 * 100.0),
                format!("mean of {} records; CI: Student t", b.n),
            ),
            Value::yes_no(
                keys::F14B_SUBLINEAR,
                set,
                f.sublinear,
                format!(
                    "efficiency falls level by level where in contact at least \
                     {FREQUENT_CONTACT} of the time ({})",
                    labels(&f.frequent_levels)
                ),
            ),
        ])
    }
}

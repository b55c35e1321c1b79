//! Validation against references nobody here wrote: every check compares one of our numbers
//! with a reference value (a closed form, an exact law, a peer tool's output) and carries its
//! tolerance with the reason for it. The book's "Validation against references" chapter prints
//! the checks as tables, and `tests/validation.rs` asserts each of them.
//!
//! | module | reference |
//! |---|---|
//! | [`linear_harvesters`] | the linear piezoelectric and electromagnetic harvesters' closed forms ([`crate::physics::closed_forms`]) against the time-domain steady state and against [`crate::physics::linear`]; their optimal loads against the time-domain power maximised over the load |
//! | [`random_law`] | the power that white base acceleration delivers to a mass, `m Sa / 2`, against random ensembles' drive power, with their energy ledgers' closure |
//! | [`band_limit`] | the band-limited noise's shortfall from that law at several bandwidths, against its first-order estimate (a recorded study), and the rigid stops' cells against an independent simulation of the same equations |
//! | [`grazing`] | where a linear oscillator's amplitude equals the gap of a rigid stop, against the continuation's grazing points |
//! | [`interfaces`] | the standard bridge, parallel and series SSHI and SECE closed forms against the steady state behind each interface; the standard bridge with strong coupling against the first-harmonic balance |
//! | [`nlvib`] | NLvib-py's harmonic balance and an exact shooting of a one-sided spring oscillator, against our shooting and continuation |
//! | [`nlvib_duffing`] | NLvib-py's harmonic balance of NLvib's Duffing example, against our continuation's folds, amplitudes and stability |
//! | [`impact_damper`] | the impact damper of Masri & Caughey (1966): its symmetric two-impacts-per-cycle motion and its stability in closed form (derived from their conditions), against our shooting's orbits, Floquet multipliers and stability boundary |
//! | [`stationary_law`] | the exact stationary density `exp(-U/theta)` of white-noise driven devices with viscous damping and any conservative suspension and stops, against random ensembles' histograms, moments, contact and well shares and load power |
//! | [`escapes`], [`kramers`] | the escape over a double well's barrier: random ensembles' barrier passages against Rice's count on the exact law, and their escapes that settle in the other well against Kramers' rate (moderate damping) or the energy-diffusion limit (light damping) |
//!
//! This module computes and judges; reading the reference files and writing the tables is the
//! callers' job (the `validation` experiment and the tests).

pub mod band_limit;
pub mod cases;
pub mod escapes;
pub mod grazing;
pub mod harmonics;
pub mod impact_damper;
pub mod interfaces;
pub mod kramers;
pub mod linear_harvesters;
pub mod nlvib;
pub mod nlvib_duffing;
pub mod random_law;
pub mod spring_cases;
pub mod stationary_law;

use serde::{Deserialize, Serialize};

use crate::num::compare::Comparison;
pub use crate::num::compare::{Measure, Verdict};

/// One comparison of our value with a reference value, with where the reference comes from and
/// why the tolerance is what it is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Check {
    /// Which group of the chapter the check belongs to (its table).
    pub group: String,
    /// Where the reference value comes from (a closed form and its source, a peer tool).
    pub source: String,
    /// What is compared, with its unit.
    pub quantity: String,
    /// Our value against the reference value, with the measure and the tolerance.
    pub compared: Comparison,
    /// Why the tolerance is what it is.
    pub reason: String,
    /// `Some(why)` for a row reported as an open question: its reference is a hypothesis that
    /// a study did not confirm, so the row shows our value and its difference but is neither
    /// within nor outside a tolerance ([`Check::verdict`] is [`Verdict::Open`]).
    #[serde(default)]
    pub open: Option<String>,
}

impl Check {
    /// The difference, as the comparison's measure says.
    pub fn difference(&self) -> f64 {
        self.compared.difference()
    }

    /// [`Verdict::Open`] for an open question, else the comparison's verdict (a NaN on either
    /// side deviates).
    pub fn verdict(&self) -> Verdict {
        if self.open.is_some() {
            Verdict::Open
        } else {
            self.compared.verdict()
        }
    }

    /// True when the check is judged and within its tolerance.
    pub fn passes(&self) -> bool {
        self.verdict() == Verdict::Reproduced
    }

    /// True for a row reported as an open question (see [`Check::open`]).
    pub fn is_open(&self) -> bool {
        self.verdict() == Verdict::Open
    }
}

/// Builds the checks of one group, with one reference source and reason by default.
#[derive(Debug, Clone)]
pub(crate) struct Group {
    name: String,
    checks: Vec<Check>,
}

impl Group {
    pub(crate) fn new(name: &str) -> Self {
        Self {
            name: name.to_string(),
            checks: Vec::new(),
        }
    }

    /// Adds a check.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn add(
        &mut self,
        reference: &str,
        quantity: &str,
        theirs: f64,
        ours: f64,
        measure: Measure,
        tolerance: f64,
        reason: &str,
    ) {
        self.checks.push(Check {
            group: self.name.clone(),
            source: reference.to_string(),
            quantity: quantity.to_string(),
            compared: Comparison {
                ours,
                reference: theirs,
                measure,
                tolerance,
            },
            reason: reason.to_string(),
            open: None,
        });
    }

    /// Marks the last check added as an open question (see [`Check::open`]).
    pub(crate) fn open_last(&mut self, why: &str) {
        if let Some(c) = self.checks.last_mut() {
            c.open = Some(why.to_string());
        }
    }

    pub(crate) fn into_checks(self) -> Vec<Check> {
        self.checks
    }
}

/// Why a validation could not be computed.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum ValidationError {
    /// The device does not fit the reference (e.g. stops on a closed form's device).
    #[error("device: {0}")]
    Device(String),
    /// Shooting or continuation failed.
    #[error("orbit: {0}")]
    Orbit(#[from] crate::study::orbit::OrbitError),
    /// A random record failed.
    #[error("record: {0}")]
    Record(#[from] crate::study::record::RecordError),
    /// A reference file could not be read.
    #[error("reference {file}: {message}")]
    Reference {
        /// The file's name.
        file: String,
        /// What is wrong.
        message: String,
    },
}

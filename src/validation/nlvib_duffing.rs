//! A peer tool on NLvib's Duffing example: `m q'' + d q' + k q + k3 q^3 = F cos(Omega t)` with
//! m = 1 kg, d = 0.05 N s/m, k = 1 N/m, k3 = 0.1 N/m^3, F = 0.18 N, Omega from 0.5 to 1.6
//! rad/s (NLvib's `EXAMPLES/01_Duffing/Duffing.m`), computed by NLvib-py's harmonic balance for
//! H = 1 to 15 harmonics and stored with its provenance under `data/references/nlvib_duffing/`
//! (`PROVENANCE.md` there: commits, commands, columns).
//!
//! In our model it is `data/validation/nlvib_duffing.toml` (a `polynomial` suspension, no
//! stops, no transducer) driven by `m a(t)` with `sqrt(2) a_rms = F / m`; the cosine is our sine
//! at drive phase pi/2, which changes no amplitude, fold or multiplier.
//!
//! Compared ([`hb_convergence`], [`checks`]):
//! * **The folds.** The branch from 0.5 rad/s climbs the resonant (hardening) part to its upper
//!   fold, returns along the unstable middle part to the lower fold and continues on the low
//!   part. NLvib's turning points (a parabola through the extremal point and its neighbours,
//!   as the driver script takes them) against ours (located on the branch): the difference
//!   must not grow from one H to the next beyond the turning point's own accuracy, and at the
//!   largest H must be within it. That accuracy is estimated from NLvib's own points: the
//!   difference between the vertices of the parabolas through the extremal point's two
//!   neighbouring triples.
//! * **The amplitudes**, at NLvib's own points nearest [`OMEGAS_RAD_S`] on each part (no
//!   interpolation of its branch): its first-harmonic amplitude against ours at the same
//!   frequency on the same part; the largest difference must shrink as H grows (to rounding,
//!   [`AMPLITUDE_FLOOR_M`]).
//! * **Stability.** NLvib-py's harmonic balance has no stability analysis; its flag marks the
//!   points between two folds, which on this branch is the unstable middle part. Our Floquet
//!   verdict at the compared points must agree with it.

use serde::Deserialize;

use crate::device::Device;
use crate::model::Model;
use crate::ode::Stats;
use crate::physics::harvester::Harvester;
use crate::progress::Silent;
use crate::study::continuation::{continue_branch, first_orbit, Branch, ContinuationSettings};
use crate::study::orbit::{Forcing, Orbit, Parameter, Shooter, ShootingOptions};
use crate::validation::harmonics::first_harmonic;
use crate::validation::{Check, Group, Measure, ValidationError};

const TWO_PI: f64 = 2.0 * std::f64::consts::PI;

/// The harmonic truncations NLvib-py was run with (`nlvib_hb_HNN.csv`).
pub const HARMONICS: [usize; 6] = [1, 3, 5, 7, 10, 15];
/// The forcing amplitude F (N).
pub const FORCE_N: f64 = 0.18;
/// The frequencies (rad/s) near which amplitudes are compared.
pub const OMEGAS_RAD_S: [f64; 5] = [0.8, 1.0, 1.2, 1.3, 1.4];
/// The amplitude difference accepted at the largest H and as growth from one H to the next
/// (m): our shooting integrates to rtol 1e-10 (amplitudes of order 1 m, so about 1e-9), NLvib's
/// Newton stops at a residual of 1e-10, and a cubic's AFT with 128 samples is exact for H
/// below 32.
pub const AMPLITUDE_FLOOR_M: f64 = 1e-7;

/// One point of NLvib-py's harmonic-balance branch.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub struct DuffingHbPoint {
    /// Index along the branch.
    pub point: usize,
    /// Arclength along the branch.
    pub arclength: f64,
    /// Omega (rad/s).
    pub omega_rad_s: f64,
    /// First-harmonic amplitude (m).
    pub a1_amplitude_m: f64,
    /// NLvib-py's flag: between two folds.
    pub nlvib_unstable_between_folds: bool,
}

/// The stored branches, one per H in [`HARMONICS`] order.
#[derive(Debug, Clone, PartialEq)]
pub struct DuffingReference {
    /// `(H, points)`.
    pub hb: Vec<(usize, Vec<DuffingHbPoint>)>,
}

/// A turning point of a stored branch.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Turn {
    /// Index of the extremal point.
    pub point: usize,
    /// Omega at the vertex of the parabola through the point and its neighbours (rad/s).
    pub omega_rad_s: f64,
    /// The vertex's accuracy: its difference from the vertices of the neighbouring triples'
    /// parabolas (rad/s).
    pub accuracy_rad_s: f64,
    /// True for a maximum of Omega (the upper fold).
    pub upper: bool,
}

fn vertex(p: &[DuffingHbPoint]) -> f64 {
    // Parabola omega(s) through three points (Newton's divided differences), at its vertex.
    let (s0, s1, s2) = (p[0].arclength, p[1].arclength, p[2].arclength);
    let (w0, w1, w2) = (p[0].omega_rad_s, p[1].omega_rad_s, p[2].omega_rad_s);
    let d01 = (w1 - w0) / (s1 - s0);
    let d12 = (w2 - w1) / (s2 - s1);
    let c = (d12 - d01) / (s2 - s0);
    // w(s) = w0 + d01 (s - s0) + c (s - s0)(s - s1); w'(s*) = 0.
    let s_star = (c * (s0 + s1) - d01) / (2.0 * c);
    w0 + d01 * (s_star - s0) + c * (s_star - s0) * (s_star - s1)
}

impl DuffingReference {
    /// File names relative to the reference's directory.
    pub fn files() -> Vec<String> {
        HARMONICS
            .iter()
            .map(|h| format!("nlvib_hb_H{h:02}.csv"))
            .collect()
    }

    /// Parses the files, which `read(name)` returns for each of [`DuffingReference::files`].
    pub fn parse(
        mut read: impl FnMut(&str) -> Result<String, ValidationError>,
    ) -> Result<Self, ValidationError> {
        let mut hb = Vec::new();
        for h in HARMONICS {
            let name = format!("nlvib_hb_H{h:02}.csv");
            let text = read(&name)?;
            let pts = csv::Reader::from_reader(text.as_bytes())
                .deserialize()
                .collect::<Result<Vec<DuffingHbPoint>, _>>()
                .map_err(|e| ValidationError::Reference {
                    file: name.clone(),
                    message: e.to_string(),
                })?;
            hb.push((h, pts));
        }
        Ok(Self { hb })
    }

    /// The turning points of a branch (interior extrema of Omega along it).
    pub fn turns(points: &[DuffingHbPoint]) -> Vec<Turn> {
        let mut out = Vec::new();
        for i in 2..points.len().saturating_sub(2) {
            let up = points[i].omega_rad_s - points[i - 1].omega_rad_s;
            let down = points[i + 1].omega_rad_s - points[i].omega_rad_s;
            if up * down >= 0.0 {
                continue;
            }
            let w = vertex(&points[i - 1..=i + 1]);
            let others = [vertex(&points[i - 2..=i]), vertex(&points[i..=i + 2])];
            let acc = others.iter().map(|o| (o - w).abs()).fold(0.0, f64::max);
            out.push(Turn {
                point: i,
                omega_rad_s: w,
                accuracy_rad_s: acc,
                upper: up > 0.0,
            });
        }
        out
    }
}

/// Our model of the example.
pub struct Ours {
    model: Harvester<4>,
    accel_rms_g: f64,
}

impl Ours {
    /// The model of `data/validation/nlvib_duffing.toml` under F cos(Omega t).
    pub fn new(device: &Device) -> Result<Self, ValidationError> {
        let a = FORCE_N / device.mechanics.mass_kg / std::f64::consts::SQRT_2 / crate::G;
        Ok(Self {
            model: Harvester::<4>::new(device)
                .map_err(|e| ValidationError::Device(e.to_string()))?,
            accel_rms_g: a,
        })
    }

    fn shooter(&self) -> Shooter<'_, Harvester<4>, 4> {
        Shooter::new(&self.model, ShootingOptions::default())
    }

    /// Our branch from Omega = `from` to `to` (rad/s), started from rest.
    pub fn branch(
        &self,
        from: f64,
        to: f64,
        max_step_rad_s: f64,
    ) -> Result<Branch, ValidationError> {
        let mut settings =
            ContinuationSettings::frequency(from / TWO_PI, to / TWO_PI, max_step_rad_s / TWO_PI);
        settings.locate_tol = 1e-9;
        let s = self.shooter();
        let mut stats = Stats::default();
        let first = first_orbit(
            &s,
            &Forcing {
                freq_hz: from / TWO_PI,
                accel_rms_g: self.accel_rms_g,
            },
            Parameter::Frequency,
            self.model.rest_state(),
            200,
            &mut stats,
        )?;
        Ok(continue_branch(&self.model, first, &settings, &Silent)?)
    }

    /// The first-harmonic amplitude of x over an orbit (m).
    pub fn a1(&self, orbit: &Orbit) -> Result<f64, ValidationError> {
        first_harmonic(&self.shooter(), orbit, |y| y[0])
            .map(|c| c.norm())
            .map_err(|e| {
                ValidationError::Orbit(crate::study::orbit::OrbitError::Solver {
                    what: Parameter::Frequency.label(),
                    param: orbit.forcing.freq_hz,
                    source: e,
                })
            })
    }

    /// Our orbits at Omega, in branch order.
    pub fn orbits_at(
        &self,
        branch: &Branch,
        omega_rad_s: f64,
    ) -> Result<Vec<Orbit>, ValidationError> {
        let mut stats = Stats::default();
        Ok(branch.orbits_at(&self.shooter(), omega_rad_s / TWO_PI, &mut stats)?)
    }
}

/// One H against ours.
#[derive(Debug, Clone, PartialEq)]
pub struct DuffingComparison {
    /// H.
    pub harmonics: usize,
    /// NLvib's upper and lower folds (rad/s) and their accuracies.
    pub folds: [(f64, f64); 2],
    /// Ours (rad/s).
    pub our_folds: [f64; 2],
    /// Compared points: (part 0 resonant, 1 middle, 2 low; Omega; NLvib's a1; ours; NLvib's
    /// flag says unstable; ours is stable).
    pub points: Vec<(usize, f64, f64, f64, bool, bool)>,
}

impl DuffingComparison {
    /// The largest `|NLvib - ours|` of the two folds (rad/s).
    pub fn fold_difference(&self) -> f64 {
        (0..2)
            .map(|i| (self.folds[i].0 - self.our_folds[i]).abs())
            .fold(0.0, f64::max)
    }

    /// The larger accuracy of NLvib's two turning points (rad/s).
    pub fn fold_accuracy(&self) -> f64 {
        self.folds[0].1.max(self.folds[1].1)
    }

    /// The largest `|NLvib - ours|` of the amplitudes (m).
    pub fn worst_amplitude_difference(&self) -> f64 {
        self.points
            .iter()
            .map(|p| (p.2 - p.3).abs())
            .fold(0.0, f64::max)
    }

    /// Stability verdicts that differ (NLvib's flag against our Floquet verdict).
    pub fn disagreements(&self) -> usize {
        self.points.iter().filter(|p| p.4 == p.5).count()
    }
}

/// Our folds: the upper (largest frequency) and the lower (smallest) of the branch (rad/s).
pub fn our_folds(branch: &Branch) -> Result<[f64; 2], ValidationError> {
    let folds: Vec<f64> = branch
        .events_of(crate::study::continuation::EventKind::Fold)
        .map(|e| e.param * TWO_PI)
        .collect();
    if folds.len() < 2 {
        return Err(ValidationError::Device(format!(
            "our branch has {} folds, not two",
            folds.len()
        )));
    }
    let hi = folds.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let lo = folds.iter().copied().fold(f64::INFINITY, f64::min);
    Ok([hi, lo])
}

/// Every H against our branch (see the module docs).
pub fn hb_convergence(
    ours: &Ours,
    branch: &Branch,
    reference: &DuffingReference,
) -> Result<Vec<DuffingComparison>, ValidationError> {
    let our = our_folds(branch)?;
    let mut out = Vec::new();
    for (h, points) in &reference.hb {
        let turns = DuffingReference::turns(points);
        let up = turns.iter().find(|t| t.upper).copied();
        let lo = turns.iter().find(|t| !t.upper).copied();
        let (Some(up), Some(lo)) = (up, lo) else {
            return Err(ValidationError::Reference {
                file: format!("nlvib_hb_H{h:02}.csv"),
                message: "the branch has not two turning points".into(),
            });
        };
        let mut compared = Vec::new();
        for part in 0..3usize {
            let on_part = |p: &&DuffingHbPoint| match part {
                0 => p.point < up.point,
                1 => p.point > up.point && p.point < lo.point,
                _ => p.point > lo.point,
            };
            for target in OMEGAS_RAD_S {
                let Some(p) = points
                    .iter()
                    .filter(on_part)
                    .min_by(|a, b| {
                        (a.omega_rad_s - target)
                            .abs()
                            .total_cmp(&(b.omega_rad_s - target).abs())
                    })
                    .filter(|p| (p.omega_rad_s - target).abs() < 0.02)
                else {
                    continue;
                };
                let orbits = ours.orbits_at(branch, p.omega_rad_s)?;
                // Between our folds the branch crosses a frequency three times; outside once,
                // on the resonant part below the lower fold and on the low part above the
                // upper fold.
                let o = match (orbits.len(), part) {
                    (3, k) => orbits.get(k),
                    (1, 0) if p.omega_rad_s < our[1] => orbits.first(),
                    (1, 2) if p.omega_rad_s > our[0] => orbits.first(),
                    _ => None,
                };
                let Some(o) = o else { continue };
                compared.push((
                    part,
                    p.omega_rad_s,
                    p.a1_amplitude_m,
                    ours.a1(o)?,
                    p.nlvib_unstable_between_folds,
                    o.is_stable(),
                ));
            }
        }
        out.push(DuffingComparison {
            harmonics: *h,
            folds: [
                (up.omega_rad_s, up.accuracy_rad_s),
                (lo.omega_rad_s, lo.accuracy_rad_s),
            ],
            our_folds: our,
            points: compared,
        });
    }
    Ok(out)
}

/// The checks (see the module docs).
pub fn checks(hb: &[DuffingComparison]) -> Vec<Check> {
    let mut g = Group::new("peer: NLvib's Duffing example");
    let src = "NLvib-py harmonic balance (Duffing example)";
    for w in hb.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        g.add(
            src,
            &format!(
                "largest |fold - ours| (rad/s), H = {} (reference: H = {})",
                b.harmonics, a.harmonics
            ),
            a.fold_difference(),
            b.fold_difference(),
            Measure::NotAbove,
            b.fold_accuracy(),
            "shrinks with H, down to the accuracy of NLvib's turning point",
        );
        g.add(
            src,
            &format!(
                "largest |a1 - ours| (m), H = {} (reference: H = {})",
                b.harmonics, a.harmonics
            ),
            a.worst_amplitude_difference(),
            b.worst_amplitude_difference(),
            Measure::NotAbove,
            AMPLITUDE_FLOOR_M,
            "shrinks with H, down to the solvers' tolerances",
        );
    }
    if let Some(last) = hb.last() {
        g.add(
            src,
            &format!("largest |fold - ours| (rad/s), H = {}", last.harmonics),
            0.0,
            last.fold_difference(),
            Measure::Absolute,
            last.fold_accuracy(),
            "the accuracy of NLvib's turning point (parabolas through neighbouring triples)",
        );
        g.add(
            src,
            &format!(
                "largest |a1 - ours| (m) over {} points, H = {}",
                last.points.len(),
                last.harmonics
            ),
            0.0,
            last.worst_amplitude_difference(),
            Measure::Absolute,
            AMPLITUDE_FLOOR_M,
            "the solvers' tolerances",
        );
        g.add(
            src,
            &format!(
                "stability verdicts that differ (NLvib's between-folds flag against our \
                 Floquet multipliers), of {} points, H = {}",
                last.points.len(),
                last.harmonics
            ),
            0.0,
            last.disagreements() as f64,
            Measure::Absolute,
            0.0,
            "on this branch the part between the folds is the unstable one",
        );
    }
    g.into_checks()
}

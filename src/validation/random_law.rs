//! The exact law of random vibration: white base acceleration of two-sided density `Sa`
//! delivers the mean power `m Sa / 2` to a mass (`m G_a / 4` with the one-sided `G_a`), whatever
//! the stops and the transducer ([`white_noise_input_power_w`], derived there). In a
//! stationary state the dissipation takes the same mean power: both dampers, the contact
//! damping, the energy lost at impacts on rigid stops, the coil's resistance and the loads.
//!
//! An ensemble of records of band-limited noise (the project's records: flat two-sided density
//! `Sa` up to `B`, sampled at `fs`, read between samples linearly) measures both over each
//! record's analysed window ([`record_ledgers`]). The checks ([`checks`]) are that the law,
//! less the band's deficit below, lies inside the 95 % interval (Student's t, [`MeanCi`]) of the
//! mean drive power, and that every record's ledger closes, so that the dissipation takes the
//! same power.
//!
//! Band-limited noise falls short of white noise by the part of the velocity's response beyond
//! the band. The drive's power is `E[a v] = int_0^inf R(s) g(s) ds` (Novikov's formula for a
//! Gaussian drive), with `R` the acceleration's autocorrelation and `g(s)` the mean response of
//! the velocity at `t` to an impulse of acceleration at `t - s`. White noise sees only
//! `g(0+) = 1`; band-limited noise, correlated over lags of about `1/B`, sees the response's
//! first fall, `g(s) = 1 - (gamma + (1 + e) nu) s + ...`: the damping rate `gamma = c/m`, and
//! the impacts on rigid stops, each of which reverses a perturbation of the velocity (`v -> -e
//! v`, a fall of `1 + e`) with the probability `nu s` that one of `nu` impacts per second falls
//! within the lag. The part of `int_0^inf s R(s) ds` that the band leaves out, `-int_{|f|>B} Sa
//! / (2 pi f)^2 df`, makes the deficit about `(gamma + (1 + e) nu) / (pi^2 B)` of the law (`B`
//! in Hz, the rates in 1/s; [`band_deficit`]). A compliant stop turns the velocity over its
//! contact time, for the chapter's Hertz stops far longer than `1/B`, and adds only its contact
//! damping, as a transducer adds its electrical damping; both are left out of the estimate.
//!
//! The estimate is a hypothesis made after a miss: the rigid-stop ensemble first fell short of
//! the bare law by more than its interval, and the deficit was derived to explain it.
//! [`super::band_limit`] tests it on cases it was not derived from: the damper's term on the
//! linear device, the impact term `(1 + e) nu` at other bandwidths, restitutions and gaps.
//!
//! Cost: one record of `T` seconds is `T fs` samples, mostly exponential steps (about a
//! microsecond each with the ledger) and Dormand-Prince steps around every impact.

use rayon::prelude::*;

use crate::device::{Device, StopLaw};
use crate::model::Ledger;
use crate::num::stats::MeanCi;
use crate::physics::closed_forms::white_noise_input_power_w;
use crate::study::record::{FreeFlightPath, RecordSpec};
use crate::study::record_ledger::record_ledgers;
use crate::validation::{Check, Group, Measure, ValidationError};

/// The ledger's balance must close to this relative residual on every record (the tolerance of
/// the record's Dormand-Prince integration in and near contact, rtol 1e-7, makes the balance's
/// error first order in it; the record ledger's tests tighten it).
pub const LEDGER_RESIDUAL_TOL: f64 = 1e-5;

/// One record's powers over its analysed window (W).
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct RecordPowers {
    /// Realisation (noise stream).
    pub stream: u64,
    /// Mean power of the drive, `m a v`.
    pub drive_w: f64,
    /// Mean total dissipation ([`dissipation_j`] over the window's length).
    pub dissipation_w: f64,
    /// Mechanical damper.
    pub mech_damping_w: f64,
    /// Contact damping, clip losses less re-engagement gains (the stop's net absorption).
    pub stop_w: f64,
    /// Kinetic energy lost at impacts on rigid stops.
    pub impact_losses_w: f64,
    /// Loads.
    pub loads_w: f64,
    /// Coil resistance.
    pub internal_w: f64,
    /// Impacts per second.
    pub impacts_per_s: f64,
    /// Fraction of the window in contact (on a rigid stop: resting on it).
    pub contact_fraction: f64,
    /// The window's energy-balance residual over the sum of its terms' magnitudes.
    pub relative_residual: f64,
    /// True when the free flight went by the exponential step.
    pub exponential: bool,
}

/// Every dissipation of a ledger (J): both dampers, the stop's net absorption, the impact
/// losses, the loads and the coil.
pub fn dissipation_j(l: &Ledger) -> f64 {
    l.mech_damping() + l.stop_absorbed() + l.impact_losses() + l.loads() + l.internal()
}

/// An ensemble's drive power and dissipation against the law.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct LawEnsemble {
    /// The device's name.
    pub device: String,
    /// Two-sided acceleration density Sa (g^2/Hz).
    pub psd_g2_per_hz: f64,
    /// The law, `m Sa / 2` (W).
    pub law_w: f64,
    /// The white-noise deficit of the band ([`band_deficit`]): the damper's and, with the
    /// ensemble's mean impact rate, the rigid stops' (relative to the law).
    pub band_deficit: f64,
    /// Each record's powers.
    pub records: Vec<RecordPowers>,
    /// The number of records the ensemble was asked for: a check over fewer fails.
    pub stated_records: u64,
    /// The device has a rigid (restitution) stop: its deficit carries the impact term.
    pub rigid_stops: bool,
}

impl LawEnsemble {
    /// True when the ensemble holds every record it was asked for (and at least two).
    pub fn complete(&self) -> bool {
        self.records.len() as u64 == self.stated_records && self.records.len() >= 2
    }

    /// Mean drive power with its 95 % interval.
    pub fn drive(&self) -> MeanCi {
        MeanCi::of(&self.records.iter().map(|r| r.drive_w).collect::<Vec<_>>())
    }

    /// Mean total dissipation with its 95 % interval.
    pub fn dissipation(&self) -> MeanCi {
        MeanCi::of(
            &self
                .records
                .iter()
                .map(|r| r.dissipation_w)
                .collect::<Vec<_>>(),
        )
    }

    /// The mean of one record quantity.
    pub fn mean(&self, f: impl Fn(&RecordPowers) -> f64) -> f64 {
        self.records.iter().map(f).sum::<f64>() / self.records.len() as f64
    }

    /// The law less the band's deficit (W): what band-limited noise delivers.
    pub fn band_law_w(&self) -> f64 {
        self.law_w * (1.0 - self.band_deficit)
    }

    /// The largest relative residual of the records' balances; NaN for an ensemble short of
    /// its records ([`LawEnsemble::complete`]), so that a check on it fails.
    pub fn worst_residual(&self) -> f64 {
        if !self.complete() {
            return f64::NAN;
        }
        self.records
            .iter()
            .map(|r| r.relative_residual.abs())
            .fold(0.0, f64::max)
    }
}

/// The part of white noise's input power that a band limited to `bandwidth_hz` misses (see
/// the module docs), relative to the law: `(gamma + (1 + e) nu) / (pi^2 B)` with `gamma =
/// c/m` for a mass `mass_kg` and damping `damping_n_s_per_m`, and `nu` impacts per second on
/// rigid stops of restitution `e` (`rigid_one_plus_e = 1 + e`; zero rate without them).
pub fn band_deficit(
    mass_kg: f64,
    damping_n_s_per_m: f64,
    rigid_impacts_per_s: f64,
    rigid_one_plus_e: f64,
    bandwidth_hz: f64,
) -> f64 {
    (damping_n_s_per_m / mass_kg + rigid_one_plus_e * rigid_impacts_per_s)
        / (std::f64::consts::PI.powi(2) * bandwidth_hz)
}

/// `1 + e` of a device's rigid (restitution) stops, the mean over both sides when their
/// coefficients differ; `None` without a rigid stop. A device that mixes a rigid and a compliant
/// stop counts every impact as rigid in [`band_deficit`] (an overestimate of its deficit).
pub fn rigid_one_plus_e(device: &Device) -> Option<f64> {
    let es: Vec<f64> = device
        .stops
        .present()
        .filter_map(|(_, s)| match s.law {
            StopLaw::Restitution { coefficient } => Some(1.0 + coefficient),
            _ => None,
        })
        .collect();
    (!es.is_empty()).then(|| es.iter().sum::<f64>() / es.len() as f64)
}

/// Runs `records` records of `spec` (streams `0..records` of `seed`, in parallel) on `device`
/// and books each one's powers over its analysed window.
pub fn law_ensemble(
    device: &Device,
    spec: &RecordSpec,
    seed: u64,
    records: u64,
) -> Result<LawEnsemble, ValidationError> {
    let sa_si = spec.noise.psd_si();
    let powers = (0..records)
        .into_par_iter()
        .map(|stream| {
            let (rec, books) = record_ledgers(device, spec, seed, stream)?;
            let l = books.analysed;
            let t = books.analysed_s;
            Ok(RecordPowers {
                stream,
                drive_w: l.excitation() / t,
                dissipation_w: dissipation_j(&l) / t,
                mech_damping_w: l.mech_damping() / t,
                stop_w: l.stop_absorbed() / t,
                impact_losses_w: l.impact_losses() / t,
                loads_w: l.loads() / t,
                internal_w: l.internal() / t,
                impacts_per_s: rec.summary.impacts as f64 / t,
                contact_fraction: rec.summary.contact_fraction,
                relative_residual: l.relative_residual(),
                exponential: rec.summary.free_flight == FreeFlightPath::Exponential,
            })
        })
        .collect::<Result<Vec<_>, ValidationError>>()?;
    let m = &device.mechanics;
    let (rate, one_plus_e) = match rigid_one_plus_e(device) {
        Some(f) => (
            powers.iter().map(|r| r.impacts_per_s).sum::<f64>() / powers.len().max(1) as f64,
            f,
        ),
        None => (0.0, 0.0),
    };
    Ok(LawEnsemble {
        device: device.name.clone(),
        psd_g2_per_hz: spec.noise.psd_g2_per_hz,
        law_w: white_noise_input_power_w(m.mass_kg, sa_si),
        band_deficit: band_deficit(
            m.mass_kg,
            m.damping_n_s_per_m,
            rate,
            one_plus_e,
            spec.noise.bandwidth_hz,
        ),
        records: powers,
        stated_records: records,
        rigid_stops: rigid_one_plus_e(device).is_some(),
    })
}

/// The checks of an ensemble: its mean drive power against the law less the band's deficit
/// (within the ensemble's 95 % interval), and the energy ledger's closure over its records.
///
/// The dissipation is not held to the law beside the drive: the ledger closes (the second
/// check), so their means are the same number to its residual, and a second row would count
/// one check twice. An ensemble short of the records it was asked for fails both checks.
///
/// The band's deficit, derived after this check first missed on a device with rigid stops,
/// carries for such a device the impact term `(1 + e) nu`; [`super::band_limit`] tests it on
/// cases it was not derived from. Unless that study confirmed it (`impact_limit` is `None`,
/// see [`super::band_limit::ImpactTerm::limit`]), the drive row of such a device shows its
/// shortfall without a verdict ([`Check::open`]), with the study's statement of the limit and
/// its evidence.
pub fn checks(e: &LawEnsemble, impact_limit: Option<&str>) -> Vec<Check> {
    let mut g = Group::new(&format!("random vibration: {}", e.device));
    let theirs = e.band_law_w();
    let d = e.drive();
    let n = format!("{} of {} records", e.records.len(), e.stated_records);
    g.add(
        "m Sa / 2 (white base acceleration), less the band's deficit",
        &format!("{}: mean drive power m<a v> (W), {n}", e.device),
        theirs,
        if e.complete() { d.mean } else { f64::NAN },
        Measure::Relative,
        d.ci95 / theirs,
        "the ensemble's 95 % interval (Student's t)",
    );
    if let (true, Some(why)) = (e.rigid_stops, impact_limit) {
        g.open_last(why);
    }
    g.add(
        "energy balance of each record",
        &format!(
            "{}: largest relative residual of the window's ledger, {n}",
            e.device
        ),
        0.0,
        e.worst_residual(),
        Measure::Absolute,
        LEDGER_RESIDUAL_TOL,
        "Dormand-Prince at rtol 1e-7 in contact; the balance's error is first order in it",
    );
    g.into_checks()
}

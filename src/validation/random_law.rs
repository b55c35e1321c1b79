//! The exact law of random vibration: white base acceleration of two-sided density `Sa`
//! delivers the mean power `m Sa / 2` to a mass (`m G_a / 4` with the one-sided `G_a`), whatever
//! the stops and the transducer ([`white_noise_input_power_w`], derived there). In a
//! stationary state the dissipation takes the same mean power: both dampers, the contact
//! damping, the energy lost at impacts on rigid stops, the coil's resistance and the loads.
//!
//! An ensemble of records of band-limited noise (the project's records: flat two-sided density
//! `Sa` up to `B`, sampled at `fs`, read between samples linearly) measures both over each
//! record's analysed window ([`record_ledgers`]); each mean carries the ensemble's 95 % interval
//! (Student's t, [`MeanCi`]), and the check is that the law lies inside it.
//!
//! Band-limited noise falls short of white noise by the part of the velocity's response beyond
//! the band: for a linear oscillator of damping rate `gamma = c/m` the real part of the
//! velocity's response per acceleration falls as `gamma / w^2` above resonance, so the
//! deficit is about `gamma / (pi^2 B)` of the law (`B` in Hz, `gamma` in 1/s), a few 1e-3 for
//! the devices of the book's chapter ([`band_deficit`]), well inside their intervals.
//!
//! Cost: one record of `T` seconds is `T fs` samples, mostly exponential steps (about a
//! microsecond each with the ledger) and Dormand-Prince steps around every impact.

use rayon::prelude::*;

use crate::device::Device;
use crate::num::stats::MeanCi;
use crate::physics::closed_forms::white_noise_input_power_w;
use crate::physics::energy::EnergyLedger;
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
    /// The window's energy-balance residual over the sum of its terms' magnitudes.
    pub relative_residual: f64,
    /// True when the free flight went by the exponential step.
    pub exponential: bool,
}

/// Every dissipation of a ledger (J): both dampers, the stop's net absorption, the impact
/// losses, the loads and the coil.
pub fn dissipation_j(l: &EnergyLedger) -> f64 {
    l.mech_damping + l.stop_absorbed() + l.impact_losses + l.loads + l.internal
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
    /// The white-noise deficit of the band for the device without stops ([`band_deficit`]).
    pub band_deficit: f64,
    /// Each record's powers.
    pub records: Vec<RecordPowers>,
}

impl LawEnsemble {
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

    /// The largest relative residual of the records' balances.
    pub fn worst_residual(&self) -> f64 {
        self.records
            .iter()
            .map(|r| r.relative_residual.abs())
            .fold(0.0, f64::max)
    }
}

/// The part of white noise's input power that a band limited to `bandwidth_hz` misses for a
/// linear oscillator of mass `mass_kg` and damping `damping_n_s_per_m`: about
/// `gamma / (pi^2 B)` with `gamma = c/m` (see the module docs), relative to the law.
pub fn band_deficit(mass_kg: f64, damping_n_s_per_m: f64, bandwidth_hz: f64) -> f64 {
    damping_n_s_per_m / mass_kg / (std::f64::consts::PI.powi(2) * bandwidth_hz)
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
                drive_w: l.excitation / t,
                dissipation_w: dissipation_j(&l) / t,
                mech_damping_w: l.mech_damping / t,
                stop_w: l.stop_absorbed() / t,
                impact_losses_w: l.impact_losses / t,
                loads_w: l.loads / t,
                internal_w: l.internal / t,
                impacts_per_s: rec.summary.impacts as f64 / t,
                relative_residual: l.relative_residual(),
                exponential: rec.summary.free_flight == FreeFlightPath::Exponential,
            })
        })
        .collect::<Result<Vec<_>, ValidationError>>()?;
    let m = &device.mechanics;
    Ok(LawEnsemble {
        device: device.name.clone(),
        psd_g2_per_hz: spec.noise.psd_g2_per_hz,
        law_w: white_noise_input_power_w(m.mass_kg, sa_si),
        band_deficit: band_deficit(m.mass_kg, m.damping_n_s_per_m, spec.noise.bandwidth_hz),
        records: powers,
    })
}

/// The checks of an ensemble: its mean drive power and mean dissipation against the law
/// (within the ensemble's 95 % interval), and every record's energy balance.
pub fn checks(e: &LawEnsemble) -> Vec<Check> {
    let mut g = Group::new(&format!("random vibration: {}", e.device));
    let src = "m Sa / 2 (white base acceleration)";
    let why = "the ensemble's 95 % interval (Student's t)";
    for (what, ci) in [
        ("mean drive power m<a v> (W)", e.drive()),
        ("mean total dissipation (W)", e.dissipation()),
    ] {
        g.add(
            src,
            what,
            e.law_w,
            ci.mean,
            Measure::Relative,
            ci.ci95 / e.law_w,
            why,
        );
    }
    g.add(
        "energy balance of each record",
        "largest relative residual of the window's ledger",
        0.0,
        e.worst_residual(),
        Measure::Absolute,
        LEDGER_RESIDUAL_TOL,
        "Dormand-Prince at rtol 1e-7 in contact; the balance's error is first order in it",
    );
    g.into_checks()
}

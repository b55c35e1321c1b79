//! Escape over the barrier of a double well: the well-to-well rate of random ensembles against
//! Kramers' law.
//!
//! For a mass in a symmetric double well with viscous damping `gamma = c / m`, driven by white
//! noise of temperature `theta` ([`crate::validation::stationary_law`]) well below the
//! barrier `dU`, the rate of escape from one well is Kramers' rate for moderate to strong
//! friction (Kramers, Physica 7, 284, 1940; reviewed by Haenggi, Talkner and Borkovec, Rev.
//! Mod. Phys. 62, 251, 1990)
//!
//! `r = (w_0 / (2 pi w_b)) (sqrt(gamma^2 / 4 + w_b^2) - gamma / 2) exp(-dU / theta)`,
//!
//! `w_0` the small-oscillation frequency in the well, `w_b = sqrt(|U''| / m)` at the barrier
//! top. It is the first term of an expansion in `theta / dU`, so at finite barriers its
//! prefactor holds to about `theta / dU` (relative); it needs the energy lost over one passage
//! near the barrier to exceed `theta` (Kramers' turnover: `gamma I_b / theta >> 1` with `I_b`
//! the action of the barrier orbit, [`turnover`]), which the devices here meet by a wide
//! margin.
//!
//! In a symmetric double well the transitions of
//! [`crate::study::displacement`] (from one well's bottom to the other's) occur at the rate
//! `r` whichever well the mass is in. The checks ([`checks`]): at each level the measured rate
//! against the law (relative, within `theta / dU` plus the ensemble's 95 % interval); and over
//! the levels the slope of `ln r` against `dU / theta` (a weighted least-squares fit) against
//! -1, within its 95 % interval plus the change of `ln(1 + theta / dU)` per unit of `dU / theta`
//! across the levels (the first neglected order's effect on the slope).

use crate::device::{Device, Suspension};
use crate::study::displacement::DisplacementEnsemble;
use crate::study::record::RecordSpec;
use crate::validation::stationary_law::StationaryLaw;
use crate::validation::{Check, Group, Measure, ValidationError};

/// Kramers' rate and its parts for one device and level.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KramersRate {
    /// The barrier over the temperature, `dU / theta`.
    pub barrier_over_theta: f64,
    /// The prefactor (1/s).
    pub prefactor_per_s: f64,
    /// The rate (1/s).
    pub rate_per_s: f64,
    /// Kramers' turnover parameter `gamma I_b / theta` (must be >> 1).
    pub turnover: f64,
}

/// The action `I_b = m \oint v dx` of the orbit at the barrier's energy in one well of the
/// double well `U = dU ((x/x_w)^2 - 1)^2` (J s): from the barrier top to the outer turning
/// point `sqrt(2) x_w` and back, `2 int sqrt(2 m (dU - U)) dx`.
pub fn turnover(mass_kg: f64, well_m: f64, barrier_j: f64) -> f64 {
    let n = 2000;
    let b = std::f64::consts::SQRT_2 * well_m;
    let h = b / n as f64;
    let mut s = 0.0;
    for i in 0..n {
        let x = (i as f64 + 0.5) * h;
        let q = (x / well_m).powi(2) - 1.0;
        let u = barrier_j * q * q;
        s += (2.0 * mass_kg * (barrier_j - u).max(0.0)).sqrt() * h;
    }
    2.0 * s
}

/// Kramers' rate for a `bistable` device under the records of `spec`.
pub fn kramers_rate(device: &Device, spec: &RecordSpec) -> Result<KramersRate, ValidationError> {
    let Suspension::Bistable { well_m, barrier_j } = device.mechanics.suspension else {
        return Err(ValidationError::Device(
            "Kramers' law here needs a `bistable` suspension".into(),
        ));
    };
    let law = StationaryLaw::of(device, spec)?;
    let m = device.mechanics.mass_kg;
    let k = 4.0 * barrier_j / (well_m * well_m);
    let w0 = (2.0 * k / m).sqrt();
    let wb = (k / m).sqrt();
    let gamma = law.damping_n_s_per_m / m;
    let pre = w0 / (2.0 * std::f64::consts::PI * wb)
        * ((gamma * gamma / 4.0 + wb * wb).sqrt() - gamma / 2.0);
    let ratio = barrier_j / law.theta_j;
    Ok(KramersRate {
        barrier_over_theta: ratio,
        prefactor_per_s: pre,
        rate_per_s: pre * (-ratio).exp(),
        turnover: gamma * turnover(m, well_m, barrier_j) / law.theta_j,
    })
}

/// One level's ensemble beside its Kramers rate.
#[derive(Debug, Clone)]
pub struct KramersLevel {
    /// The law.
    pub law: KramersRate,
    /// The ensemble.
    pub ensemble: DisplacementEnsemble,
}

/// The checks over levels (see the module docs).
pub fn checks(device: &Device, levels: &[KramersLevel]) -> Vec<Check> {
    let mut g = Group::new(&format!("escape over the barrier: {}", device.name));
    let src = "Kramers' rate, moderate-to-strong friction (Kramers 1940; Haenggi et al. 1990)";
    let mut pts = Vec::new();
    for l in levels {
        let ci = l.ensemble.transition_rate();
        let acc = 1.0 / l.law.barrier_over_theta;
        g.add(
            src,
            &format!(
                "{}: well-to-well rate at dU/theta = {:.2} (1/s; {} transitions)",
                device.name,
                l.law.barrier_over_theta,
                l.ensemble.transitions()
            ),
            l.law.rate_per_s,
            ci.mean,
            Measure::Relative,
            acc + ci.ci95 / l.law.rate_per_s,
            "the asymptotic law's accuracy theta/dU plus the ensemble's 95 % interval",
        );
        // ln r with its standard error (delta method; the records' spread is the known
        // error of each level's mean, so the fit's interval is normal).
        pts.push((
            l.law.barrier_over_theta,
            ci.mean.ln(),
            ci.std / (ci.n as f64).sqrt() / ci.mean,
        ));
    }
    if pts.len() >= 3 {
        // Weighted least squares of ln r on dU/theta.
        let w: Vec<f64> = pts.iter().map(|p| 1.0 / (p.2 * p.2)).collect();
        let sw: f64 = w.iter().sum();
        let xm = pts.iter().zip(&w).map(|(p, w)| w * p.0).sum::<f64>() / sw;
        let ym = pts.iter().zip(&w).map(|(p, w)| w * p.1).sum::<f64>() / sw;
        let sxx: f64 = pts
            .iter()
            .zip(&w)
            .map(|(p, w)| w * (p.0 - xm).powi(2))
            .sum();
        let sxy: f64 = pts
            .iter()
            .zip(&w)
            .map(|(p, w)| w * (p.0 - xm) * (p.1 - ym))
            .sum();
        let slope = sxy / sxx;
        let se = (1.0 / sxx).sqrt();
        let (a, b) = (pts[0].0, pts[pts.len() - 1].0);
        let bias = ((1.0 + 1.0 / a).ln() - (1.0 + 1.0 / b).ln()).abs() / (b - a).abs();
        g.add(
            "Kramers: d ln r / d(dU/theta) = -1",
            &format!("{}: slope of ln(rate) against dU/theta", device.name),
            -1.0,
            slope,
            Measure::Absolute,
            1.96 * se + bias,
            "the fit's 95 % interval plus the first neglected order's effect over the levels",
        );
    }
    g.into_checks()
}

//! Linear electromechanical two-port of the differential mode (eqs 11-18) and the broadband
//! efficiency of a linear harvester driven by white-noise acceleration (eqs 21-22).
//!
//! Two anti-phase transducers decouple, once linearised, into a common and a differential
//! mode. The differential two-port has (eqs 15-17)
//! C = (C0 + Cp + CL)/2, Gamma = C0 Vb / x0, K = km + 2 C0^2 Vb^2 / (x0^2 (C0 + Cp + CL)),
//! and coupling k^2 = Gamma^2 / (K C) (eq 18).
//!
//! The output PSD of this linear theory is the general one of [`crate::physics::linear`] (any
//! transducer), which a test holds to the pair's closed form of eqs 11-17.

use crate::device::{Device, Transducer};
use crate::G;

/// The differential-mode two-port and its figures of merit at one bias voltage.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TwoPort {
    /// C = (C0 + Cp + CL)/2 (F), eq 15.
    pub capacitance_f: f64,
    /// Gamma = C0 Vb / x0 (N/V), eq 16.
    pub gamma_n_per_v: f64,
    /// K, open-circuit stiffness (N/m), eq 17.
    pub stiffness_n_per_m: f64,
    /// k^2 = Gamma^2/(K C), eq 18 (a fraction, not %).
    pub k2: f64,
    /// Proof mass (kg).
    pub mass_kg: f64,
    /// Mechanical damping b (N s/m).
    pub damping_n_s_per_m: f64,
    /// Suspension stiffness km (N/m).
    pub km_n_per_m: f64,
    /// Measured resonance used by [`TwoPort::qm_measured_resonance`] (Hz; NaN when the device
    /// quotes none).
    pub measured_resonance_hz: f64,
    /// Load resistance RL (ohm).
    pub load_resistance_ohm: f64,
}

impl TwoPort {
    /// The two-port of a device with a capacitor pair at its bias voltage (eqs 15-18); `None`
    /// for other transducers. For a gap-closing pair, `x0` reads `d0` and K includes the
    /// electrostatic spring at rest, `-2 C0 Vb^2 / d0^2`.
    pub fn try_of(device: &Device) -> Option<Self> {
        let (c0, cp, cl, rl, vb, x0, k_es) = match &device.transducer {
            Transducer::AreaOverlapPair(p) => (
                p.c0_f,
                p.cp_f,
                p.load_capacitance_f,
                p.load_resistance_ohm,
                p.bias_v,
                p.finger_overlap_m,
                0.0,
            ),
            Transducer::GapClosingPair(p) => (
                p.c0_f,
                p.cp_f,
                p.load_capacitance_f,
                p.load_resistance_ohm,
                p.bias_v,
                p.electrode_gap_m,
                p.electrostatic_stiffness_n_per_m(),
            ),
            _ => return None,
        };
        let m = &device.mechanics;
        let ctot = c0 + cp + cl;
        let capacitance_f = ctot / 2.0;
        let gamma = c0 * vb / x0;
        let k = m.stiffness_n_per_m + 2.0 * c0 * c0 * vb * vb / (x0 * x0 * ctot) + k_es;
        Some(Self {
            capacitance_f,
            gamma_n_per_v: gamma,
            stiffness_n_per_m: k,
            k2: gamma * gamma / (k * capacitance_f),
            mass_kg: m.mass_kg,
            damping_n_s_per_m: m.damping_n_s_per_m,
            km_n_per_m: m.stiffness_n_per_m,
            measured_resonance_hz: m.measured_resonance_hz.unwrap_or(f64::NAN),
            load_resistance_ohm: rl,
        })
    }

    /// [`TwoPort::try_of`] for the paper's devices.
    ///
    /// # Panics
    /// When the device's transducer is not a capacitor pair (use [`TwoPort::try_of`] for
    /// devices from users).
    pub fn of(device: &Device) -> Self {
        Self::try_of(device).expect("the two-port of eqs 15-18 needs a capacitor-pair transducer")
    }

    /// Mechanical quality factor with the suspension stiffness alone, `sqrt(km m) / b`.
    pub fn qm_suspension(&self) -> f64 {
        (self.km_n_per_m * self.mass_kg).sqrt() / self.damping_n_s_per_m
    }

    /// Mechanical quality factor with the open-circuit stiffness K of eq 17, `sqrt(K m) / b`
    /// (the one eq 21 is derived with).
    pub fn qm_open_circuit(&self) -> f64 {
        (self.stiffness_n_per_m * self.mass_kg).sqrt() / self.damping_n_s_per_m
    }

    /// Mechanical quality factor with the device's measured resonance f0, `m 2 pi f0 / b` (NaN
    /// when the device quotes none).
    pub fn qm_measured_resonance(&self) -> f64 {
        self.mass_kg * 2.0 * std::f64::consts::PI * self.measured_resonance_hz
            / self.damping_n_s_per_m
    }

    /// Open-circuit resonance sqrt(K/m)/(2 pi) (Hz).
    pub fn resonance_hz(&self) -> f64 {
        (self.stiffness_n_per_m / self.mass_kg).sqrt() / (2.0 * std::f64::consts::PI)
    }

    /// Normalised load rL = 2 RL C sqrt(K/m), eq 22.
    pub fn r_load(&self) -> f64 {
        2.0 * self.load_resistance_ohm
            * self.capacitance_f
            * (self.stiffness_n_per_m / self.mass_kg).sqrt()
    }

    /// Broadband efficiency 2P/(m Sa) of eq 21 for a given Qm (fraction, not %).
    ///
    /// Eq 21 is derived with Qm = sqrt(K m)/b and rL of eq 22; other readings are offered
    /// for sensitivity only.
    pub fn broadband_efficiency(&self, qm: f64) -> f64 {
        let rl = self.r_load();
        let k2 = self.k2;
        rl * k2 * qm / (1.0 + (1.0 / qm + k2 * qm) * rl + rl * rl)
    }

    /// Harvested power of both loads (W) for a two-sided acceleration PSD (m^2/s^4/Hz), eq 21.
    pub fn broadband_power_w(&self, psd_si: f64, qm: f64) -> f64 {
        self.mass_kg * psd_si / 2.0 * self.broadband_efficiency(qm)
    }
}

/// The bias voltage (V) at which eq 18 gives the coupling `k2` (a fraction in `[0, 1)`), the
/// inverse of [`TwoPort::of`]'s `k2` in closed form: with `a = C0²/x0²` and
/// `Ct = C0 + Cp + CL`, eq 18 reads `k² = 2 a Vb² / (km Ct + 2 a Vb²)`, so
/// `Vb² = k² km Ct / (2 a (1 - k²))`. NaN outside `[0, 1)`.
pub fn bias_for_coupling(device: &Device, k2: f64) -> f64 {
    let Transducer::AreaOverlapPair(e) = &device.transducer else {
        return f64::NAN;
    };
    if !(0.0..1.0).contains(&k2) {
        return f64::NAN;
    }
    let ct = e.c0_f + e.cp_f + e.load_capacitance_f;
    let a = (e.c0_f / e.finger_overlap_m).powi(2);
    (k2 * device.mechanics.stiffness_n_per_m * ct / (2.0 * a * (1.0 - k2))).sqrt()
}

/// Linear theory of eq 21: mean power of both loads (W) at a two-sided acceleration PSD
/// `psd_g2_per_hz` (g²/Hz), with `Qm = sqrt(K m)/b` (the reading eq 21 is derived with).
pub fn eq21_power_w(device: &Device, psd_g2_per_hz: f64) -> f64 {
    let tp = TwoPort::of(device);
    tp.broadband_power_w(psd_g2_per_hz * G * G, tp.qm_open_circuit())
}

/// Linear theory of eq 21: efficiency `2P/(m Sa)` (fraction), `Qm = sqrt(K m)/b`.
pub fn eq21_efficiency(device: &Device) -> f64 {
    let tp = TwoPort::of(device);
    tp.broadband_efficiency(tp.qm_open_circuit())
}

/// Efficiency `2P/(m Sa)` (fraction) of a mean power `p_w` (both loads) at two-sided level
/// `psd_g2_per_hz` (g²/Hz) for `device`'s proof mass.
pub fn efficiency(device: &Device, p_w: f64, psd_g2_per_hz: f64) -> f64 {
    2.0 * p_w / (device.mechanics.mass_kg * psd_g2_per_hz * G * G)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bias_for_coupling_inverts_eq18() {
        let text = include_str!("../../data/prototype1.toml");
        let d = Device::from_toml_str(text, "prototype1.toml").unwrap();
        for k2 in [1e-4, 0.0144, 0.3] {
            let vb = bias_for_coupling(&d, k2);
            let back = TwoPort::of(&d.with_bias(vb)).k2;
            assert!((back / k2 - 1.0).abs() < 1e-12, "{k2}: {back}");
        }
        assert_eq!(bias_for_coupling(&d, 0.0), 0.0);
        assert!(bias_for_coupling(&d, 1.0).is_nan());
    }

    /// The pair's output PSD in closed form (eqs 11-17 in the frequency domain), one-sided,
    /// W/Hz, both loads. In the differential mode (V1 = -V2 = V, which the symmetric start
    /// from rest preserves to first order) the linearised model of eqs 7-10 reads, with
    /// `Ct = C0 + Cp + CL` and `Gamma = C0 Vb / x0`: `V = Gamma x jw RL / (1 + jw RL Ct)`, and
    /// `(km - w² m + jw b + 2 Gamma² jw RL / (1 + jw RL Ct)) x = m a`. The power of both loads
    /// is `2|V|²/RL`, and the one-sided acceleration PSD is `2 Sa`, so
    /// `S_P(f) = 4 Sa |V/a|² / RL`.
    fn closed_form_psd_w_per_hz(device: &Device, psd_g2_per_hz: f64, freq_hz: f64) -> f64 {
        let tp = TwoPort::of(device);
        let m = device.mechanics.mass_kg;
        let b = device.mechanics.damping_n_s_per_m;
        // The suspension, with a gap-closing pair's electrostatic spring at rest.
        let k_es = match &device.transducer {
            Transducer::GapClosingPair(p) => p.electrostatic_stiffness_n_per_m(),
            _ => 0.0,
        };
        let km = device.mechanics.stiffness_n_per_m + k_es;
        let ct = 2.0 * tp.capacitance_f;
        let gamma = tp.gamma_n_per_v;
        let rl = tp.load_resistance_ohm;
        let w = 2.0 * std::f64::consts::PI * freq_hz;
        // z = jw RL / (1 + jw RL Ct) = (jw RL)(1 - jw RL Ct) / (1 + (w RL Ct)^2).
        let wrc = w * rl * ct;
        let den = 1.0 + wrc * wrc;
        let (z_re, z_im) = (w * rl * wrc / den, w * rl / den);
        // Mechanical impedance plus 2 Gamma^2 z.
        let d_re = km - w * w * m + 2.0 * gamma * gamma * z_re;
        let d_im = w * b + 2.0 * gamma * gamma * z_im;
        let x_over_a_sq = m * m / (d_re * d_re + d_im * d_im);
        let v_over_a_sq = gamma * gamma * (z_re * z_re + z_im * z_im) * x_over_a_sq;
        4.0 * psd_g2_per_hz * G * G * v_over_a_sq / rl
    }

    /// The crate's one linear output PSD ([`crate::physics::linear::LinearResponse`], the
    /// model linearised about rest and solved as a linear system) is, for the paper's pair,
    /// the closed form of eqs 11-17: two solutions of the same equations, equal to rounding.
    #[test]
    fn the_linear_response_of_a_pair_is_the_closed_form_of_eqs_11_to_17() {
        for name in ["prototype1", "prototype2"] {
            let text = match name {
                "prototype1" => include_str!("../../data/prototype1.toml"),
                _ => include_str!("../../data/prototype2.toml"),
            };
            let d = Device::from_toml_str(text, name).unwrap();
            let lin = crate::physics::linear::LinearResponse::of(&d);
            let f0 = TwoPort::of(&d).resonance_hz();
            for f in [0.1 * f0, 0.9 * f0, f0, 1.1 * f0, 10.0 * f0] {
                let closed = closed_form_psd_w_per_hz(&d, 1e-3, f);
                let ours = lin.output_psd_w_per_hz(1e-3 * G * G, f);
                assert!(
                    ((ours - closed) / closed).abs() < 1e-10,
                    "{name} at {f} Hz: {ours:e} vs {closed:e}"
                );
            }
        }
    }
}

//! Linear theory of any device: the model linearised about rest, away from the stops, as a
//! frequency response.
//!
//! Free of the stops, the model is `y' = L y + c a(t) + N(y)` (the free flight split of the
//! harvester with its transducer's own loads,
//! [`crate::physics::harvester::Harvester::flight_matrix`], its interface circuit left out);
//! for small motion `N` is negligible (for the piezoelectric and electromagnetic transducers
//! and without one it is zero) and the response to `a(t) = Re(A e^{jwt})` is
//! `Y = (jw I - L)^{-1} c A`. The load voltages are linear in the state, so each has a
//! transfer function `V_i / A`, and the mean power of the loads under a sine of amplitude `A`
//! is `sum_i |V_i/A|^2 |A|^2 / (2 R)`.
//!
//! Under white base acceleration of two-sided density `Sa` (m^2 s^-4 / Hz) the one-sided
//! output power density is `2 Sa sum_i |V_i/A|^2 / R` ([`LinearResponse::output_psd_w_per_hz`],
//! on a grid [`LinearResponse::output_psd`], its widths [`linear_widths`]): the one linear
//! output PSD of the crate, for every transducer.
//!
//! For the paper's comb pair these are eqs 11-17 and their frequency-domain form
//! ([`crate::physics::two_port`]); for the other transducers they are the textbook closed forms
//! (the book's "Validation against references" chapter compares the two).

use nalgebra::{Complex, Matrix4, Vector4};

use crate::device::Device;
use crate::physics::harvester::Harvester;
use crate::physics::transducer::TransducerModel;
use crate::signal::{Psd, Widths};

/// The linearised model of a device.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LinearResponse {
    l: Matrix4<f64>,
    transducer: TransducerModel,
    active: usize,
}

impl LinearResponse {
    /// The linearised model of `device` about rest.
    pub fn of(device: &Device) -> Self {
        let h = Harvester::<4>::with_own_loads(device);
        let transducer = TransducerModel::of(&device.transducer);
        Self {
            // A loaded transducer's port always has its split.
            l: h.flight_matrix()
                .unwrap_or_else(|| Matrix4::from_element(f64::NAN)),
            transducer,
            active: transducer.active_states(),
        }
    }

    /// The state's response per unit base acceleration at `freq_hz`: `(jw I - L)^{-1} c`
    /// (x in m per m/s^2, ...); components the transducer leaves unused are zero.
    pub fn state_per_accel(&self, freq_hz: f64) -> Vector4<Complex<f64>> {
        let w = 2.0 * std::f64::consts::PI * freq_hz;
        let n = self.active;
        let mut a = nalgebra::DMatrix::<Complex<f64>>::zeros(n, n);
        for i in 0..n {
            for j in 0..n {
                a[(i, j)] = Complex::new(-self.l[(i, j)], if i == j { w } else { 0.0 });
            }
        }
        let mut rhs = nalgebra::DVector::<Complex<f64>>::zeros(n);
        rhs[1] = Complex::new(1.0, 0.0);
        let x = a
            .lu()
            .solve(&rhs)
            .unwrap_or_else(|| nalgebra::DVector::from_element(n, Complex::new(f64::NAN, 0.0)));
        let mut out = Vector4::from_element(Complex::new(0.0, 0.0));
        for i in 0..n {
            out[i] = x[i];
        }
        out
    }

    /// The load voltages per unit base acceleration at `freq_hz` (V per m/s^2): both nodes of
    /// a pair, `[V, 0]` for one load, zero without a transducer.
    pub fn voltages_per_accel(&self, freq_hz: f64) -> [Complex<f64>; 2] {
        let zero = Complex::new(0.0, 0.0);
        // Without a transducer there is no voltage, whatever the mechanical state: the
        // state's complex solve is skipped.
        if let TransducerModel::None = self.transducer {
            return [zero, zero];
        }
        let y = self.state_per_accel(freq_hz);
        match self.transducer {
            TransducerModel::None => [zero, zero],
            TransducerModel::Pair(p) => {
                // V_i = (s_i + (C_i - C0) Vb) / (C0 + Cp + CL) to first order, with
                // C_1,2 - C0 = +-(C0 / x0) x (and C0 / d0 for a gap-closing pair).
                let ct = p.c0 + p.cp + p.cl;
                let a = p.c0 / p.length_scale();
                [
                    (y[2] + y[0] * (a * p.vb)) / ct,
                    (y[3] - y[0] * (a * p.vb)) / ct,
                ]
            }
            TransducerModel::Piezo { .. } => [y[2], zero],
            TransducerModel::Electromagnetic { phi, rc, l, r } => {
                let i = if l > 0.0 {
                    y[2]
                } else {
                    y[1] * (phi / (rc + r))
                };
                [i * r, zero]
            }
        }
    }

    /// Mean power of the loads under a sine of RMS acceleration `accel_rms_si` (m/s^2) at
    /// `freq_hz` (W).
    pub fn sine_power_w(&self, accel_rms_si: f64, freq_hz: f64) -> f64 {
        let r = self.transducer.load_resistance();
        let [v1, v2] = self.voltages_per_accel(freq_hz);
        (v1.norm_sqr() + v2.norm_sqr()) * accel_rms_si * accel_rms_si / r
    }

    /// One-sided output power density of the loads under white base acceleration of two-sided
    /// density `sa_si` ((m/s^2)^2/Hz) at `freq_hz` (W/Hz).
    pub fn output_psd_w_per_hz(&self, sa_si: f64, freq_hz: f64) -> f64 {
        let r = self.transducer.load_resistance();
        let [v1, v2] = self.voltages_per_accel(freq_hz);
        2.0 * sa_si * (v1.norm_sqr() + v2.norm_sqr()) / r
    }

    /// [`LinearResponse::output_psd_w_per_hz`] on a grid of frequencies, as a [`Psd`] (W/Hz,
    /// one-sided; `segments` is zero: nothing is averaged).
    pub fn output_psd(&self, sa_si: f64, freq_hz: &[f64]) -> Psd {
        Psd {
            freq_hz: freq_hz.to_vec(),
            density: freq_hz
                .iter()
                .map(|&f| self.output_psd_w_per_hz(sa_si, f))
                .collect(),
            segments: 0,
        }
    }

    /// The displacement amplitude per unit acceleration amplitude at `freq_hz` (s^2).
    pub fn displacement_per_accel(&self, freq_hz: f64) -> f64 {
        self.state_per_accel(freq_hz)[0].norm()
    }
}

/// The open-circuit stiffness of a device (N/m): the suspension, stiffened by the
/// transducer with its loads open (eq 17's K for a pair, `km + theta^2 / Cp` for a
/// piezoelectric transducer, `km` for the others).
pub fn open_circuit_stiffness_n_per_m(device: &Device) -> f64 {
    let km = device.mechanics.stiffness_n_per_m;
    match TransducerModel::of(&device.transducer) {
        TransducerModel::Pair(_) => crate::physics::two_port::TwoPort::of(device).stiffness_n_per_m,
        TransducerModel::Piezo { theta, cp, .. } => km + theta * theta / cp,
        _ => km,
    }
}

/// The open-circuit resonance `sqrt(K/m)/(2 pi)` of a device (Hz), with K of
/// [`open_circuit_stiffness_n_per_m`].
pub fn open_circuit_resonance_hz(device: &Device) -> f64 {
    (open_circuit_stiffness_n_per_m(device) / device.mechanics.mass_kg).sqrt()
        / (2.0 * std::f64::consts::PI)
}

/// The mechanical quality factor `sqrt(K m)/b` with the open-circuit stiffness (eq 21's
/// reading for a pair).
pub fn open_circuit_qm(device: &Device) -> f64 {
    (open_circuit_stiffness_n_per_m(device) * device.mechanics.mass_kg).sqrt()
        / device.mechanics.damping_n_s_per_m
}

/// Widths of a device's linear output PSD ([`LinearResponse::output_psd_w_per_hz`]),
/// evaluated on a grid of 0.01 Hz over `f_lo..f_hi` (the true widths, free of any estimator).
pub fn linear_widths(device: &Device, f_lo: f64, f_hi: f64) -> Widths {
    let n = ((f_hi - f_lo) / 0.01).ceil() as usize + 1;
    let f: Vec<f64> = (0..n).map(|i| f_lo + 0.01 * i as f64).collect();
    Widths::of(&LinearResponse::of(device).output_psd(1.0, &f))
}

/// Mean power of the loads under white base acceleration of two-sided density `sa_si`
/// ((m/s^2)^2/Hz) limited to the band `[lo_hz, hi_hz]` (W): the integral of
/// [`LinearResponse::output_psd_w_per_hz`] over the band, by the trapezoidal rule on a grid
/// of 1/50 of the open-circuit half-power width within 100 widths of the open-circuit
/// resonance and of 1 % steps in frequency elsewhere, which resolves the resonance peak (of
/// relative width 1/Qm) of every transducer. For a capacitor pair and a band much wider than
/// the resonance it is eq 21's power (tested).
pub fn white_noise_power_w(device: &Device, sa_si: f64, lo_hz: f64, hi_hz: f64) -> f64 {
    let lin = LinearResponse::of(device);
    let f0 = open_circuit_resonance_hz(device);
    let width = f0 / open_circuit_qm(device).max(0.5);
    let (near_lo, near_hi) = (
        (f0 - 100.0 * width).max(lo_hz),
        (f0 + 100.0 * width).min(hi_hz),
    );
    let mut grid = Vec::new();
    let mut f = lo_hz.max(1e-6 * f0);
    while f < near_lo {
        grid.push(f);
        f *= 1.01;
    }
    let fine = width / 50.0;
    let mut f = near_lo.max(grid.last().copied().unwrap_or(near_lo));
    while f < near_hi {
        grid.push(f);
        f += fine;
    }
    let mut f = near_hi.max(grid.last().copied().unwrap_or(near_hi));
    while f < hi_hz {
        grid.push(f);
        f *= 1.01;
    }
    grid.push(hi_hz);
    grid.dedup();
    let p: Vec<f64> = grid
        .iter()
        .map(|&f| lin.output_psd_w_per_hz(sa_si, f))
        .collect();
    grid.windows(2)
        .zip(p.windows(2))
        .map(|(f, p)| 0.5 * (p[0] + p[1]) * (f[1] - f[0]))
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;

    /// For the paper's pair the band power over a band far wider than the resonance is eq 21's
    /// closed form (two-port theory, integrated analytically).
    #[test]
    fn band_power_of_a_pair_is_eq21() {
        let d = Device::from_toml_str(
            include_str!("../../data/prototype2.toml"),
            "prototype2.toml",
        )
        .unwrap();
        let psd_g2 = 1e-4;
        let eq21 = crate::physics::two_port::eq21_power_w(&d, psd_g2);
        let f0 = open_circuit_resonance_hz(&d);
        let ours = white_noise_power_w(&d, psd_g2 * crate::G * crate::G, 1e-3 * f0, 1e3 * f0);
        assert!(
            ((ours - eq21) / eq21).abs() < 1e-3,
            "band power {ours:e} W, eq 21 {eq21:e} W"
        );
    }
}

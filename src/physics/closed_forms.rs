//! Closed forms of linear harvesters and of a linear oscillator, written from the textbook
//! equations as references: the book's "Validation against references" chapter checks the
//! time-domain model (and the general linear response of [`crate::physics::linear`]) against
//! them. Nothing here calls the model; each form is solved by hand from its source's equations,
//! as the docs of each item show.
//!
//! Conventions: a sinusoidal base acceleration `a(t) = Re(A e^{jwt})` (m/s^2), the mechanical
//! impedance `Z_m(w) = k - w^2 m + j w c`, and the project's sign of the drive (eq 7:
//! `m x'' + c x' + k x + F_e = + m a`). The textbooks write `- m a` for a base acceleration; that
//! flips the sign of every response phasor and changes no magnitude, no power and no optimal
//! load.
//!
//! | item | source |
//! |---|---|
//! | [`Oscillator`] | the linear base-excited oscillator, `X / A = m / Z_m` |
//! | [`Oscillator::grazing_rad_s`] | where `|X| = gap`: the start and end of contact with a stop |
//! | [`Piezoelectric`] | the lumped single-mode piezoelectric harvester with a resistive load (A. Erturk and D. J. Inman, *Piezoelectric Energy Harvesting*, Wiley 2011, its lumped-parameter electromechanical equations) |
//! | [`Electromagnetic`] | the velocity-damped generator of C. B. Williams and R. B. Yates, Sens. Actuators A 52 (1996) 8, with the coil of N. G. Stephen, J. Sound Vib. 293 (2006) 409 (resistance and inductance, resistive load) |
//! | [`white_noise_input_power_w`] | the power a white base acceleration delivers to a mass, derived in its docs |

use nalgebra::Complex;

use crate::num::polynomial::quadratic_roots;

type C64 = Complex<f64>;

/// A linear single-degree-of-freedom oscillator on a moving base.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Oscillator {
    /// Mass m (kg).
    pub mass_kg: f64,
    /// Stiffness k (N/m).
    pub stiffness_n_per_m: f64,
    /// Viscous damping c (N s/m).
    pub damping_n_s_per_m: f64,
}

impl Oscillator {
    /// The mechanical impedance `Z_m(w) = k - w^2 m + j w c` (N/m) at `w` (rad/s).
    pub fn impedance(&self, w_rad_s: f64) -> C64 {
        C64::new(
            self.stiffness_n_per_m - w_rad_s * w_rad_s * self.mass_kg,
            w_rad_s * self.damping_n_s_per_m,
        )
    }

    /// The displacement per base acceleration, `X / A = m / Z_m` (s^2).
    pub fn displacement_per_accel(&self, w_rad_s: f64) -> C64 {
        C64::new(self.mass_kg, 0.0) / self.impedance(w_rad_s)
    }

    /// The frequencies (rad/s) where the amplitude of the motion under a base acceleration of
    /// amplitude `accel_amplitude_m_s2` equals `gap_m`, in increasing order: the roots of
    /// `|Z_m(w)| = m A / gap`, i.e. with `u = w^2`,
    ///
    /// `m^2 u^2 + (c^2 - 2 k m) u + k^2 - (m A / gap)^2 = 0`.
    ///
    /// Two roots bracket the resonance when the static deflection `m A / k` is below the gap
    /// and the resonant amplitude above it; one (the upper) when the static deflection already
    /// exceeds the gap; none when the motion never reaches the gap.
    pub fn grazing_rad_s(&self, accel_amplitude_m_s2: f64, gap_m: f64) -> Vec<f64> {
        let (m, k, c) = (self.mass_kg, self.stiffness_n_per_m, self.damping_n_s_per_m);
        let f = m * accel_amplitude_m_s2 / gap_m;
        let (qa, qb, qc) = (m * m, c * c - 2.0 * k * m, k * k - f * f);
        let mut u: Vec<f64> = quadratic_roots(qa, qb, qc)
            .into_iter()
            .flatten()
            .filter(|u| *u > 0.0 && u.is_finite())
            .collect();
        u.sort_by(f64::total_cmp);
        u.into_iter().map(f64::sqrt).collect()
    }
}

/// The lumped single-mode piezoelectric harvester with a resistive load (Erturk and Inman
/// 2011):
///
/// `m x'' + c x' + k x - theta V = m a`,  `Cp V' + V / R + theta x' = 0`.
///
/// With `x = X e^{jwt}`, `V = V e^{jwt}`, the electrical equation gives
/// `V = -j w theta R X / (1 + j w R Cp)`; put into the mechanical one,
///
/// `V / A = -j w theta R m / (Z_m (1 + j w R Cp) + j w theta^2 R)`,
///
/// `X / A = m (1 + j w R Cp) / (Z_m (1 + j w R Cp) + j w theta^2 R)`.
///
/// The mean power of the load is `|V|^2 / (2 R)`. As a function of `R` it is
/// `P ~ R / |Z_m + R W|^2` with `W = j w (Cp Z_m + theta^2)`, whose derivative vanishes at
/// `|Z_m|^2 = R^2 |W|^2`: the optimal load at `w` is
///
/// `R_opt = |Z_m| / (w |Cp Z_m + theta^2|)`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Piezoelectric {
    /// The mechanical oscillator.
    pub oscillator: Oscillator,
    /// Coupling theta (N/V).
    pub coupling_n_per_v: f64,
    /// Clamped capacitance Cp (F).
    pub capacitance_f: f64,
    /// Load resistance R (ohm).
    pub load_resistance_ohm: f64,
}

impl Piezoelectric {
    /// `Z_m (1 + j w R Cp) + j w theta^2 R` (N/m): the denominator of the responses.
    fn denominator(&self, w: f64) -> C64 {
        let r = self.load_resistance_ohm;
        let t = self.coupling_n_per_v;
        self.oscillator.impedance(w) * C64::new(1.0, w * r * self.capacitance_f)
            + C64::new(0.0, w * t * t * r)
    }

    /// The load voltage per base acceleration `V / A` (V s^2 / m) at `w` (rad/s).
    pub fn voltage_per_accel(&self, w_rad_s: f64) -> C64 {
        let w = w_rad_s;
        C64::new(
            0.0,
            -w * self.coupling_n_per_v * self.load_resistance_ohm * self.oscillator.mass_kg,
        ) / self.denominator(w)
    }

    /// The displacement per base acceleration `X / A` (s^2) at `w` (rad/s).
    pub fn displacement_per_accel(&self, w_rad_s: f64) -> C64 {
        let w = w_rad_s;
        C64::new(
            self.oscillator.mass_kg,
            self.oscillator.mass_kg * w * self.load_resistance_ohm * self.capacitance_f,
        ) / self.denominator(w)
    }

    /// Mean power of the load (W) under a sine of RMS acceleration `accel_rms_m_s2` (m/s^2)
    /// at `w` (rad/s): `|V/A|^2 |A|^2 / (2 R)` with `|A| = sqrt(2) a_rms`.
    pub fn mean_power_w(&self, accel_rms_m_s2: f64, w_rad_s: f64) -> f64 {
        self.voltage_per_accel(w_rad_s).norm_sqr() * accel_rms_m_s2 * accel_rms_m_s2
            / self.load_resistance_ohm
    }

    /// The load that maximises the power at `w` (rad/s), `|Z_m| / (w |Cp Z_m + theta^2|)`
    /// (ohm).
    pub fn optimal_load_ohm(&self, w_rad_s: f64) -> f64 {
        let z = self.oscillator.impedance(w_rad_s);
        let t = self.coupling_n_per_v;
        z.norm() / (w_rad_s * (z * self.capacitance_f + t * t).norm())
    }

    /// The short-circuit resonance `sqrt(k/m)` (rad/s).
    pub fn short_circuit_rad_s(&self) -> f64 {
        (self.oscillator.stiffness_n_per_m / self.oscillator.mass_kg).sqrt()
    }

    /// The open-circuit resonance `sqrt((k + theta^2/Cp)/m)` (rad/s).
    pub fn open_circuit_rad_s(&self) -> f64 {
        let t = self.coupling_n_per_v;
        ((self.oscillator.stiffness_n_per_m + t * t / self.capacitance_f) / self.oscillator.mass_kg)
            .sqrt()
    }
}

/// The electromagnetic (velocity-damped) harvester with a coil of resistance `Rc` and
/// inductance `L` and a resistive load `R` (Williams and Yates 1996; Stephen 2006):
///
/// `m x'' + c x' + k x + Phi I = m a`,  `L I' + (Rc + R) I = Phi x'`.
///
/// With phasors, `I = j w Phi X / (Rc + R + j w L)`, and
///
/// `I / A = j w Phi m / (Z_m (Rc + R + j w L) + j w Phi^2)`,
///
/// `X / A = m (Rc + R + j w L) / (Z_m (Rc + R + j w L) + j w Phi^2)`.
///
/// The load's voltage is `R I` and its mean power `R |I|^2 / 2`. As a function of `R` this is
/// `P ~ R / |U + R Z_m|^2` with `U = Z_m (Rc + j w L) + j w Phi^2`, maximal at
///
/// `R_opt = |Z_m (Rc + j w L) + j w Phi^2| / |Z_m|`;
///
/// at the mechanical resonance `w = sqrt(k/m)` with `L = 0`, `Z_m = j w c` and this is Stephen's
/// `R_opt = Rc + Phi^2 / c` ([`Electromagnetic::stephen_optimal_load_ohm`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Electromagnetic {
    /// The mechanical oscillator.
    pub oscillator: Oscillator,
    /// Transduction factor Phi (N/A).
    pub transduction_n_per_a: f64,
    /// Coil resistance Rc (ohm).
    pub coil_resistance_ohm: f64,
    /// Coil inductance L (H).
    pub coil_inductance_h: f64,
    /// Load resistance R (ohm).
    pub load_resistance_ohm: f64,
}

impl Electromagnetic {
    /// The coil current per base acceleration `I / A` (A s^2 / m) at `w` (rad/s).
    pub fn current_per_accel(&self, w_rad_s: f64) -> C64 {
        let w = w_rad_s;
        let phi = self.transduction_n_per_a;
        let zc = C64::new(
            self.coil_resistance_ohm + self.load_resistance_ohm,
            w * self.coil_inductance_h,
        );
        C64::new(0.0, w * phi * self.oscillator.mass_kg)
            / (self.oscillator.impedance(w) * zc + C64::new(0.0, w * phi * phi))
    }

    /// The load voltage per base acceleration `R I / A` (V s^2 / m) at `w` (rad/s).
    pub fn voltage_per_accel(&self, w_rad_s: f64) -> C64 {
        self.current_per_accel(w_rad_s) * self.load_resistance_ohm
    }

    /// The displacement per base acceleration `X / A` (s^2) at `w` (rad/s).
    pub fn displacement_per_accel(&self, w_rad_s: f64) -> C64 {
        let w = w_rad_s;
        let phi = self.transduction_n_per_a;
        let zc = C64::new(
            self.coil_resistance_ohm + self.load_resistance_ohm,
            w * self.coil_inductance_h,
        );
        zc * self.oscillator.mass_kg
            / (self.oscillator.impedance(w) * zc + C64::new(0.0, w * phi * phi))
    }

    /// Mean power of the load (W) under a sine of RMS acceleration `accel_rms_m_s2` (m/s^2)
    /// at `w` (rad/s): `R |I/A|^2 |A|^2 / 2`.
    pub fn mean_power_w(&self, accel_rms_m_s2: f64, w_rad_s: f64) -> f64 {
        self.load_resistance_ohm
            * self.current_per_accel(w_rad_s).norm_sqr()
            * accel_rms_m_s2
            * accel_rms_m_s2
    }

    /// Mean power lost in the coil's resistance (W), `Rc |I|^2 / 2`.
    pub fn coil_loss_w(&self, accel_rms_m_s2: f64, w_rad_s: f64) -> f64 {
        self.coil_resistance_ohm
            * self.current_per_accel(w_rad_s).norm_sqr()
            * accel_rms_m_s2
            * accel_rms_m_s2
    }

    /// The load that maximises the power at `w` (rad/s),
    /// `|Z_m (Rc + j w L) + j w Phi^2| / |Z_m|` (ohm).
    pub fn optimal_load_ohm(&self, w_rad_s: f64) -> f64 {
        let w = w_rad_s;
        let z = self.oscillator.impedance(w);
        let phi = self.transduction_n_per_a;
        let u = z * C64::new(self.coil_resistance_ohm, w * self.coil_inductance_h)
            + C64::new(0.0, w * phi * phi);
        u.norm() / z.norm()
    }

    /// Stephen's optimal load at the mechanical resonance of a coil without inductance,
    /// `Rc + Phi^2 / c` (ohm).
    pub fn stephen_optimal_load_ohm(&self) -> f64 {
        self.coil_resistance_ohm
            + self.transduction_n_per_a * self.transduction_n_per_a
                / self.oscillator.damping_n_s_per_m
    }

    /// The mechanical resonance `sqrt(k/m)` (rad/s).
    pub fn resonance_rad_s(&self) -> f64 {
        (self.oscillator.stiffness_n_per_m / self.oscillator.mass_kg).sqrt()
    }
}

/// The mean power (W) that a white base acceleration of **two-sided** density `sa_si`
/// ((m/s^2)^2/Hz) delivers to a mass `mass_kg`: `m Sa / 2`, i.e. `m G_a / 4` with the one-sided
/// density `G_a = 2 Sa`.
///
/// The drive is the force `m a(t)` on the mass, and its power `m a v`. With `R_a(s) = Sa
/// delta(s)`, the velocity's part correlated with the drive is its response to the drive's
/// past, `v(t) = int_0^inf h(s) a(t - s) ds + ...`, whose kernel starts at `h(0+) = 1`
/// whatever else acts on the mass (stops, dampers and transducers act through the position and
/// velocity, which an impulse of acceleration does not move at once): `E[a v] = Sa h(0+) / 2`
/// (half the delta function falls at `s >= 0`). The law needs no linearity and holds for any
/// stops and transducer, as long as the drive is the only force that depends on `a`.
pub fn white_noise_input_power_w(mass_kg: f64, sa_si: f64) -> f64 {
    0.5 * mass_kg * sa_si
}

#[cfg(test)]
mod tests {
    use super::*;

    fn osc() -> Oscillator {
        Oscillator {
            mass_kg: 1.0,
            stiffness_n_per_m: 1.0,
            damping_n_s_per_m: 0.03,
        }
    }

    #[test]
    fn the_grazing_frequencies_are_where_the_amplitude_equals_the_gap() {
        let o = osc();
        let w = o.grazing_rad_s(0.1, 1.0);
        assert_eq!(w.len(), 2);
        for w in w {
            let amp = 0.1 * o.displacement_per_accel(w).norm();
            assert!((amp - 1.0).abs() < 1e-13, "{amp}");
        }
        // The static deflection beyond the gap: only the upper root.
        assert_eq!(o.grazing_rad_s(2.0, 1.0).len(), 1);
        // Never reaching the gap: none.
        assert!(o.grazing_rad_s(0.001, 1.0).is_empty());
    }

    /// The optimal loads make the power's derivative in R vanish and are maxima (powers at
    /// 1 +- 1e-3 times the load are both lower).
    #[test]
    fn the_optimal_loads_are_maxima_of_the_power() {
        let o = Oscillator {
            mass_kg: 0.01,
            stiffness_n_per_m: 4000.0,
            damping_n_s_per_m: 0.1,
        };
        let p = Piezoelectric {
            oscillator: o,
            coupling_n_per_v: 2e-3,
            capacitance_f: 20e-9,
            load_resistance_ohm: 1.0,
        };
        let e = Electromagnetic {
            oscillator: o,
            transduction_n_per_a: 5.0,
            coil_resistance_ohm: 100.0,
            coil_inductance_h: 0.01,
            load_resistance_ohm: 1.0,
        };
        for w in [500.0, 632.0, 700.0] {
            let r = p.optimal_load_ohm(w);
            let at = |r: f64| {
                Piezoelectric {
                    load_resistance_ohm: r,
                    ..p
                }
                .mean_power_w(1.0, w)
            };
            assert!(at(r) > at(r * 1.001) && at(r) > at(r / 1.001));
            let r = e.optimal_load_ohm(w);
            let at = |r: f64| {
                Electromagnetic {
                    load_resistance_ohm: r,
                    ..e
                }
                .mean_power_w(1.0, w)
            };
            assert!(at(r) > at(r * 1.001) && at(r) > at(r / 1.001));
        }
        // Stephen's form is the general one at resonance without inductance.
        let e0 = Electromagnetic {
            coil_inductance_h: 0.0,
            ..e
        };
        let rel = e0.optimal_load_ohm(e0.resonance_rad_s()) / e0.stephen_optimal_load_ohm() - 1.0;
        assert!(rel.abs() < 1e-13, "{rel}");
    }
}

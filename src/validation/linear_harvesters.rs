//! The linear piezoelectric and electromagnetic harvesters against their closed forms
//! ([`crate::physics::closed_forms`]).
//!
//! * **Frequency response.** At each frequency, the periodic orbit of the time-domain model
//!   (shooting, [`crate::study::orbit`], on a device without stops) gives the load voltage's
//!   fundamental ([`first_harmonic`]) and the mean load power over the period; the closed form
//!   gives the voltage phasor and the power. Compared: `|V/A|`, `arg V/A` and the mean power,
//!   and the general linear response of [`crate::physics::linear`] against the same closed form.
//! * **Optimal load.** The time-domain mean power as a function of the load, maximised by
//!   Brent's method on `ln R` (argmin's `BrentOpt`) inside the bracket of a coarse logarithmic
//!   scan, against the closed form's optimal load and the power there.
//!
//! Tolerances: the orbits are solved with the shooting defaults (integrator rtol 1e-10, the
//! period map's residual below 5e-10), so their fundamentals and powers are good to about
//! 1e-9; they are held to 1e-6 relative (1e-6 rad for the phase). The general linear response
//! and the closed form solve the same linear equations in two ways and are held to 1e-12. The
//! maximiser of a smooth function is located only to about the square root of the precision
//! of its values relative to its curvature: the optimal load to 1e-4, the power at it to 1e-6.

use argmin::core::{CostFunction, Error as ArgminError, Executor};
use argmin::solver::brent::BrentOpt;
use nalgebra::Complex;

use crate::device::{Device, Transducer};
use crate::drive::Sine;
use crate::model::Model;
use crate::ode::Stats;
use crate::physics::closed_forms::{Electromagnetic, Oscillator, Piezoelectric};
use crate::physics::harvester::Harvester;
use crate::physics::linear::LinearResponse;
use crate::study::orbit::{Forcing, Orbit, OrbitError, Parameter, Shooter, ShootingOptions};
use crate::validation::harmonics::first_harmonic;
use crate::validation::{Check, Group, Measure, ValidationError};

/// Tolerance of a time-domain quantity against its closed form (relative, or rad).
pub const TIME_DOMAIN_TOL: f64 = 1e-6;
/// Tolerance of [`crate::physics::linear`] against the closed form (relative).
pub const LINEAR_RESPONSE_TOL: f64 = 1e-12;
/// Tolerance of the time-domain optimal load against the closed form's (relative).
pub const OPTIMAL_LOAD_TOL: f64 = 1e-4;

const WHY_TIME_DOMAIN: &str =
    "shooting to rtol 1e-10 (orbit good to ~1e-9); the comparison is held to 1e-6";
const WHY_LINEAR: &str = "the same linear equations solved two ways: rounding only";
const WHY_LOAD: &str = "a maximiser is located to ~sqrt of its values' precision";

/// A linear harvester's closed form: the piezoelectric or the electromagnetic one.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum ClosedForm {
    /// Erturk and Inman's lumped piezoelectric harvester.
    Piezoelectric(Piezoelectric),
    /// Williams and Yates's electromagnetic harvester with Stephen's coil.
    Electromagnetic(Electromagnetic),
}

impl ClosedForm {
    /// The closed form of a device without stops and with a piezoelectric or electromagnetic
    /// transducer.
    pub fn of(device: &Device) -> Result<Self, ValidationError> {
        if device.stops.present().next().is_some() {
            return Err(ValidationError::Device(format!(
                "{}: the closed forms are linear; the device must have no stops",
                device.name
            )));
        }
        let m = &device.mechanics;
        let oscillator = Oscillator {
            mass_kg: m.mass_kg,
            stiffness_n_per_m: m.stiffness_n_per_m,
            damping_n_s_per_m: m.damping_n_s_per_m,
        };
        match &device.transducer {
            Transducer::Piezoelectric(p) => Ok(ClosedForm::Piezoelectric(Piezoelectric {
                oscillator,
                coupling_n_per_v: p.coupling_n_per_v,
                capacitance_f: p.capacitance_f,
                load_resistance_ohm: p.load_resistance_ohm,
            })),
            Transducer::Electromagnetic(e) => Ok(ClosedForm::Electromagnetic(Electromagnetic {
                oscillator,
                transduction_n_per_a: e.transduction_n_per_a,
                coil_resistance_ohm: e.coil_resistance_ohm,
                coil_inductance_h: e.coil_inductance_h,
                load_resistance_ohm: e.load_resistance_ohm,
            })),
            other => Err(ValidationError::Device(format!(
                "{}: no closed form for a `{}` transducer",
                device.name,
                other.key()
            ))),
        }
    }

    /// The source, for the tables.
    pub fn source(&self) -> &'static str {
        match self {
            ClosedForm::Piezoelectric(_) => "Erturk & Inman 2011, lumped model (closed form)",
            ClosedForm::Electromagnetic(_) => "Williams & Yates 1996 / Stephen 2006 (closed form)",
        }
    }

    /// The load voltage per base acceleration (V s^2/m) at `w` (rad/s).
    pub fn voltage_per_accel(&self, w_rad_s: f64) -> Complex<f64> {
        match self {
            ClosedForm::Piezoelectric(p) => p.voltage_per_accel(w_rad_s),
            ClosedForm::Electromagnetic(e) => e.voltage_per_accel(w_rad_s),
        }
    }

    /// Mean load power (W) under RMS acceleration `accel_rms_m_s2` at `w` (rad/s).
    pub fn mean_power_w(&self, accel_rms_m_s2: f64, w_rad_s: f64) -> f64 {
        match self {
            ClosedForm::Piezoelectric(p) => p.mean_power_w(accel_rms_m_s2, w_rad_s),
            ClosedForm::Electromagnetic(e) => e.mean_power_w(accel_rms_m_s2, w_rad_s),
        }
    }

    /// The optimal load (ohm) at `w` (rad/s).
    pub fn optimal_load_ohm(&self, w_rad_s: f64) -> f64 {
        match self {
            ClosedForm::Piezoelectric(p) => p.optimal_load_ohm(w_rad_s),
            ClosedForm::Electromagnetic(e) => e.optimal_load_ohm(w_rad_s),
        }
    }

    /// The same closed form with another load.
    pub fn with_load(&self, r_ohm: f64) -> Self {
        match *self {
            ClosedForm::Piezoelectric(p) => ClosedForm::Piezoelectric(Piezoelectric {
                load_resistance_ohm: r_ohm,
                ..p
            }),
            ClosedForm::Electromagnetic(e) => ClosedForm::Electromagnetic(Electromagnetic {
                load_resistance_ohm: r_ohm,
                ..e
            }),
        }
    }
}

/// The time-domain steady state of a device under a sine: its orbit, the load voltage's
/// fundamental per unit acceleration and the mean load power.
#[derive(Debug, Clone)]
pub struct SteadyResponse {
    /// The periodic orbit.
    pub orbit: Orbit,
    /// `V / A` from the fundamental of the load voltage (V s^2/m).
    pub voltage_per_accel: Complex<f64>,
    /// Mean power of the load over the period (W).
    pub mean_power_w: f64,
}

/// The periodic orbit of `device` under `accel_rms_g` (g rms) at `freq_hz`, by shooting from
/// rest with the default settings, with its load voltage's fundamental and mean power.
pub fn steady_response(
    device: &Device,
    accel_rms_g: f64,
    freq_hz: f64,
) -> Result<SteadyResponse, ValidationError> {
    let h = Harvester::<4>::new(device)
        .map_err(|e| ValidationError::Device(format!("{}: {e}", device.name)))?;
    let shooter = Shooter::new(&h, ShootingOptions::default());
    let forcing = Forcing {
        freq_hz,
        accel_rms_g,
    };
    let mut stats = Stats::default();
    let orbit = shooter.solve(
        &forcing,
        Parameter::Frequency,
        0.0,
        h.rest_state(),
        &mut stats,
    )?;
    let c = first_harmonic(&shooter, &orbit, |y| {
        let mut out = [0.0; 2];
        h.outputs(crate::model::Mode::FREE, y, &mut out);
        out[0]
    })
    .map_err(|e| ValidationError::Orbit(solver(freq_hz, e)))?;
    let amplitude = Sine::from_rms_g(accel_rms_g, freq_hz).amplitude_m_s2;
    Ok(SteadyResponse {
        voltage_per_accel: Complex::new(0.0, 1.0) * c / amplitude,
        mean_power_w: orbit.summary.p_total_w,
        orbit,
    })
}

fn solver(freq_hz: f64, e: crate::ode::SolverError) -> OrbitError {
    OrbitError::Solver {
        what: Parameter::Frequency.label(),
        param: freq_hz,
        source: e,
    }
}

/// The frequency-response checks of `device` (no stops; piezoelectric or electromagnetic)
/// under `accel_rms_g` at each of `freqs_hz`; an error for no frequency (nothing would be
/// checked).
pub fn frequency_response_checks(
    device: &Device,
    accel_rms_g: f64,
    freqs_hz: &[f64],
) -> Result<Vec<Check>, ValidationError> {
    if freqs_hz.is_empty() {
        return Err(ValidationError::Device(format!(
            "{}: no frequency to compare the response at",
            device.name
        )));
    }
    let cf = ClosedForm::of(device)?;
    let src = cf.source();
    let lin = LinearResponse::of(device);
    let a_rms = accel_rms_g * crate::G;
    let mut g = Group::new(&format!("frequency response: {}", device.name));
    for &f in freqs_hz {
        let w = 2.0 * std::f64::consts::PI * f;
        let reference = cf.voltage_per_accel(w);
        let ours = steady_response(device, accel_rms_g, f)?;
        let v = ours.voltage_per_accel;
        g.add(
            src,
            &format!("|V/A| at {f:.6} Hz (V s^2/m), time domain"),
            reference.norm(),
            v.norm(),
            Measure::Relative,
            TIME_DOMAIN_TOL,
            WHY_TIME_DOMAIN,
        );
        g.add(
            src,
            &format!("arg V/A at {f:.6} Hz (rad), time domain"),
            reference.arg(),
            reference.arg() + (v / reference).arg(),
            Measure::Absolute,
            TIME_DOMAIN_TOL,
            WHY_TIME_DOMAIN,
        );
        g.add(
            src,
            &format!("mean load power at {f:.6} Hz (W), time domain"),
            cf.mean_power_w(a_rms, w),
            ours.mean_power_w,
            Measure::Relative,
            TIME_DOMAIN_TOL,
            WHY_TIME_DOMAIN,
        );
        let l = lin.voltages_per_accel(f)[0];
        g.add(
            src,
            &format!("|V/A - linear response| / |V/A| at {f:.6} Hz"),
            0.0,
            (l - reference).norm() / reference.norm(),
            Measure::Absolute,
            LINEAR_RESPONSE_TOL,
            WHY_LINEAR,
        );
    }
    Ok(g.into_checks())
}

/// The time-domain mean load power as a function of `ln R`, negated for the minimiser.
struct NegPower<'a> {
    device: &'a Device,
    accel_rms_g: f64,
    freq_hz: f64,
    failed: &'a std::sync::Mutex<Option<ValidationError>>,
}

impl NegPower<'_> {
    fn power(&self, r_ohm: f64) -> Result<f64, ValidationError> {
        let d = self
            .device
            .with_param("transducer.load_resistance_ohm", r_ohm)
            .map_err(|e| ValidationError::Device(e.to_string()))?;
        Ok(steady_response(&d, self.accel_rms_g, self.freq_hz)?.mean_power_w)
    }
}

impl CostFunction for NegPower<'_> {
    type Param = f64;
    type Output = f64;

    fn cost(&self, ln_r: &f64) -> Result<f64, ArgminError> {
        match self.power(ln_r.exp()) {
            Ok(p) => Ok(-p),
            Err(e) => {
                let msg = e.to_string();
                *self.failed.lock().expect("not poisoned") = Some(e);
                Err(ArgminError::msg(msg))
            }
        }
    }
}

/// The load that maximises the time-domain mean power of `device` at `freq_hz`, searched in
/// `[r_lo_ohm, r_hi_ohm]`: the largest of `scan` logarithmically spaced loads brackets the
/// maximum, which Brent's method then locates in `ln R`. Returns `(R, P(R))`.
pub fn time_domain_optimal_load(
    device: &Device,
    accel_rms_g: f64,
    freq_hz: f64,
    (r_lo_ohm, r_hi_ohm): (f64, f64),
    scan: usize,
) -> Result<(f64, f64), ValidationError> {
    let failed = std::sync::Mutex::new(None);
    let f = NegPower {
        device,
        accel_rms_g,
        freq_hz,
        failed: &failed,
    };
    let (a, b) = (r_lo_ohm.ln(), r_hi_ohm.ln());
    let grid: Vec<f64> = (0..scan)
        .map(|i| a + (b - a) * i as f64 / (scan - 1) as f64)
        .collect();
    let mut best = (0, f64::NEG_INFINITY);
    for (i, x) in grid.iter().enumerate() {
        let p = f.power(x.exp())?;
        if p > best.1 {
            best = (i, p);
        }
    }
    let i = best.0;
    if i == 0 || i + 1 == scan {
        return Err(ValidationError::Device(format!(
            "{}: the power is largest at the end of the load range [{r_lo_ohm:e}, {r_hi_ohm:e}] \
             ohm",
            device.name
        )));
    }
    let solver = BrentOpt::new(grid[i - 1], grid[i + 1]).set_tolerance(f64::EPSILON.sqrt(), 1e-9);
    let res = Executor::new(f, solver)
        .configure(|s| s.max_iters(200))
        .run();
    if let Some(e) = failed.lock().expect("not poisoned").take() {
        return Err(e);
    }
    let state = res
        .map_err(|e| ValidationError::Device(format!("{}: {e}", device.name)))?
        .state;
    let x = state.best_param.ok_or_else(|| {
        ValidationError::Device(format!("{}: the load search found no point", device.name))
    })?;
    Ok((x.exp(), -state.best_cost))
}

/// The optimal-load checks of `device` at `freq_hz`: the time-domain maximiser
/// ([`time_domain_optimal_load`] over `search_ohm` with `scan` points) and its power against the
/// closed form; `stephen` adds Stephen's `Rc + Phi^2/c` (an electromagnetic device
/// without inductance at its mechanical resonance).
pub fn optimal_load_checks(
    device: &Device,
    accel_rms_g: f64,
    freq_hz: f64,
    search_ohm: (f64, f64),
    scan: usize,
    stephen: bool,
) -> Result<Vec<Check>, ValidationError> {
    let cf = ClosedForm::of(device)?;
    let w = 2.0 * std::f64::consts::PI * freq_hz;
    let r_ref = cf.optimal_load_ohm(w);
    let (r, p) = time_domain_optimal_load(device, accel_rms_g, freq_hz, search_ohm, scan)?;
    let mut g = Group::new(&format!("optimal load: {}", device.name));
    g.add(
        cf.source(),
        &format!("optimal load at {freq_hz:.6} Hz (ohm)"),
        r_ref,
        r,
        Measure::Relative,
        OPTIMAL_LOAD_TOL,
        WHY_LOAD,
    );
    g.add(
        cf.source(),
        &format!("mean power at the optimal load, {freq_hz:.6} Hz (W)"),
        cf.with_load(r_ref).mean_power_w(accel_rms_g * crate::G, w),
        p,
        Measure::Relative,
        TIME_DOMAIN_TOL,
        WHY_TIME_DOMAIN,
    );
    if stephen {
        let ClosedForm::Electromagnetic(e) = cf else {
            return Err(ValidationError::Device(format!(
                "{}: Stephen's optimal load is for an electromagnetic device",
                device.name
            )));
        };
        if e.coil_inductance_h != 0.0 {
            return Err(ValidationError::Device(format!(
                "{}: Stephen's optimal load assumes a coil without inductance",
                device.name
            )));
        }
        g.add(
            "Stephen 2006: R = Rc + Phi^2/c at resonance, L = 0",
            &format!("optimal load at {freq_hz:.6} Hz (ohm)"),
            e.stephen_optimal_load_ohm(),
            r,
            Measure::Relative,
            OPTIMAL_LOAD_TOL,
            WHY_LOAD,
        );
    }
    Ok(g.into_checks())
}

/// Load voltage per acceleration (`V/A`, complex, V s^2/m) at frequencies (Hz).
pub type ResponsePoints = Vec<(f64, Complex<f64>)>;

/// The load voltage per acceleration of a linear harvester on a frequency grid, closed form
/// and, at `time_domain_hz`, the time-domain steady state's: the chapter's plot of the
/// frequency response.
pub fn response_curve(
    device: &Device,
    accel_rms_g: f64,
    grid_hz: &[f64],
    time_domain_hz: &[f64],
) -> Result<(ResponsePoints, ResponsePoints), ValidationError> {
    let cf = ClosedForm::of(device)?;
    let closed = grid_hz
        .iter()
        .map(|&f| (f, cf.voltage_per_accel(2.0 * std::f64::consts::PI * f)))
        .collect();
    let ours = time_domain_hz
        .iter()
        .map(|&f| {
            Ok((
                f,
                steady_response(device, accel_rms_g, f)?.voltage_per_accel,
            ))
        })
        .collect::<Result<_, ValidationError>>()?;
    Ok((closed, ours))
}

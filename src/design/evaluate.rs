//! One design evaluated: its periodic steady state at each frequency of the vibration, the DC
//! power it delivers and the limits its orbit reaches (largest impact speed, largest contact
//! force, largest displacement, impacts per second).
//!
//! At each frequency the steady state is found by shooting ([`crate::study::periodic`]),
//! starting from rest at the first frequency and from the previous frequency's orbit at the
//! next (a stepped sine upward, which follows one branch). The limits are read from one period
//! of the orbit found ([`OrbitLimits`]):
//!
//! * the impact speed is the mass's speed at the end of the step before each impact switch
//!   (a compliant stop's contact entry, a rigid stop's rebound or sticking), the speed the
//!   located event hands over;
//! * the contact force is the stop's force on the mass, `m (v'(mode) - v'(mode apart))` with
//!   the drive's acceleration at that instant, sampled at the quarter points of every step
//!   in contact; a rigid stop's impact has no finite force and contributes only its resting
//!   reaction;
//! * the displacement is the largest `|x|` at the step ends and midpoints.

use nalgebra::SVector;

use crate::device::Device;
use crate::drive::{Excitation, Sine};
use crate::model::{Mode, Model, SwitchKind};
use crate::ode::{Observer, SolverError, Step};
use crate::study::flow::SineFlow;
use crate::study::periodic::{state_of, steady_state, PeriodicError, SteadySettings};

/// What a design delivers and what its orbit reaches, over the vibration's frequencies.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct Performance {
    /// The objective: the smallest mean DC power over the frequencies (W); at one frequency,
    /// its power.
    pub power_w: f64,
    /// The frequency of that smallest power (Hz).
    pub worst_freq_hz: f64,
    /// The largest power over the frequencies (W).
    pub best_power_w: f64,
    /// Largest impact speed over the frequencies (m/s); zero without impacts.
    pub impact_speed_m_s: f64,
    /// Largest contact force over the frequencies (N); zero without contact.
    pub contact_force_n: f64,
    /// Largest |x| over the frequencies (m).
    pub displacement_m: f64,
    /// Largest number of impacts per second over the frequencies.
    pub impacts_per_s: f64,
}

/// Limits read from one period of an orbit (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OrbitLimits {
    /// Largest impact speed (m/s).
    pub impact_speed_m_s: f64,
    /// Largest contact force (N).
    pub contact_force_n: f64,
    /// Largest |x| (m).
    pub displacement_m: f64,
    /// Impacts over the period.
    pub impacts: u32,
}

/// Observes one period for [`OrbitLimits`].
struct LimitMeter<'m, M> {
    model: &'m M,
    sine: Sine,
    mass_kg: f64,
    last_v: f64,
    limits: OrbitLimits,
}

impl<M: Model<N>, const N: usize> Observer<SVector<f64, N>, Mode> for LimitMeter<'_, M> {
    fn step(&mut self, st: &Step<SVector<f64, N>>, mode: Mode) {
        let l = &mut self.limits;
        for y in [st.y1, st.at_theta(0.5)] {
            l.displacement_m = l.displacement_m.max(y[0].abs());
        }
        if mode.in_contact() {
            for th in [0.0, 0.25, 0.5, 0.75, 1.0] {
                let y = st.at_theta(th);
                let a = self.sine.accel(st.t0 + th * st.h);
                let with = self.model.rhs(mode, &y, a)[1];
                let apart = self.model.rhs(mode.without_contacts(), &y, a)[1];
                l.contact_force_n = l.contact_force_n.max((self.mass_kg * (with - apart)).abs());
            }
        }
        self.last_v = st.y1[1];
    }

    fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
        if SwitchKind::between(from, to).is_impact() {
            self.limits.impacts += 1;
            self.limits.impact_speed_m_s = self.limits.impact_speed_m_s.max(self.last_v.abs());
        }
    }
}

/// The limits of the period from the section state `y` of an orbit of `model` under `sine`
/// (the first mass of `mass_kg`).
pub fn orbit_limits<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: &SVector<f64, N>,
    mass_kg: f64,
    rtol: f64,
) -> Result<OrbitLimits, SolverError> {
    let mode = model.mode_of(y);
    let mut meter = LimitMeter {
        model,
        sine,
        mass_kg,
        last_v: y[1],
        limits: OrbitLimits {
            displacement_m: y[0].abs(),
            ..Default::default()
        },
    };
    let mut flow = SineFlow::new(model, sine, 0.0, *y, mode, rtol);
    flow.integrate_observed(sine.period_s(), &mut meter)?;
    Ok(meter.limits)
}

/// Why a design could not be evaluated.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum EvalError {
    /// No periodic steady state at a frequency.
    #[error("no steady state at {freq_hz} Hz: {source}")]
    Steady {
        /// The frequency (Hz).
        freq_hz: f64,
        /// Why.
        source: PeriodicError,
    },
    /// The steady state found is unstable (a Floquet multiplier outside the unit circle): the
    /// harvester would not stay on it.
    #[error("the steady state at {freq_hz} Hz is unstable (largest multiplier {multiplier})")]
    Unstable {
        /// The frequency (Hz).
        freq_hz: f64,
        /// Largest multiplier modulus.
        multiplier: f64,
    },
    /// The orbit's period could not be integrated again for its limits.
    #[error("integration failed at {freq_hz} Hz: {source}")]
    Solver {
        /// The frequency (Hz).
        freq_hz: f64,
        /// Why.
        source: SolverError,
    },
    /// The device's parts do not assemble into a model.
    #[error(transparent)]
    Device(#[from] crate::physics::harvester::AssemblyError),
}

/// The performance of `model` (of a device whose first mass is `mass_kg`) under sines of
/// `accel_rms_g` at each of `freqs_hz` in order (see the module docs).
pub fn performance_on<M: Model<N>, const N: usize>(
    model: &M,
    mass_kg: f64,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    settings: &SteadySettings,
) -> Result<Performance, EvalError> {
    let mut start = model.rest_state();
    let mut perf = Performance {
        power_w: f64::INFINITY,
        worst_freq_hz: f64::NAN,
        best_power_w: 0.0,
        impact_speed_m_s: 0.0,
        contact_force_n: 0.0,
        displacement_m: 0.0,
        impacts_per_s: 0.0,
    };
    for &freq_hz in freqs_hz {
        let sine = Sine::from_rms_g(accel_rms_g, freq_hz);
        let s = steady_state(model, sine, &start, settings)
            .map_err(|source| EvalError::Steady { freq_hz, source })?;
        if !s.is_stable() {
            return Err(EvalError::Unstable {
                freq_hz,
                multiplier: s.max_multiplier,
            });
        }
        start = state_of(&s);
        let l = orbit_limits(model, sine, &start, mass_kg, settings.rtol)
            .map_err(|source| EvalError::Solver { freq_hz, source })?;
        if s.p_dc_w < perf.power_w {
            perf.power_w = s.p_dc_w;
            perf.worst_freq_hz = freq_hz;
        }
        perf.best_power_w = perf.best_power_w.max(s.p_dc_w);
        perf.impact_speed_m_s = perf.impact_speed_m_s.max(l.impact_speed_m_s);
        perf.contact_force_n = perf.contact_force_n.max(l.contact_force_n);
        perf.displacement_m = perf.displacement_m.max(l.displacement_m.max(s.x_peak_m));
        perf.impacts_per_s = perf.impacts_per_s.max(f64::from(l.impacts) * freq_hz);
    }
    Ok(perf)
}

/// [`performance_on`] for a device's assembled model.
pub fn performance(
    device: &Device,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    settings: &SteadySettings,
) -> Result<Performance, EvalError> {
    let mass_kg = device.mechanics.mass_kg;
    crate::with_harvester!(device, |h| performance_on(
        &h,
        mass_kg,
        freqs_hz,
        accel_rms_g,
        settings
    ))
}

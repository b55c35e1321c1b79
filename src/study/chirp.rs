//! Sweeps whose answer does not depend on their step: the device's half-power band that sets
//! the default step and the default rate of the phase-continuous ramp that joins two steps of
//! a stepped sweep ([`crate::study::ramp`]), and the swept sine at a stated rate (a chirp, as a
//! lab sweeps).
//!
//! # The default step
//! [`default_step_hz`] is a quarter of the linear half-power width ([`half_power_band`]),
//! rounded down to 1, 2 or 5 times a power of ten: the steps resolve the resonance, and the
//! ramps make the transitions independent of them.

use nalgebra::SVector;

use crate::device::Device;
use crate::drive::{Chirp, Profile, Sine};
use crate::model::{Driven, Mode, Model, SwitchKind, MAX_OUTPUTS};
use crate::num::roots::{illinois, RootOptions, Sample};
use crate::ode::{Dopri5, Observer, SolverError, Stats, Step};
use crate::physics::linear::{open_circuit_resonance_hz, LinearResponse};
use crate::study::mass_peaks::MassPeaks;
use crate::study::steady::{steady_state, SettleSettings};

/// The resonance and half-power width of a device's linear response (the displacement per
/// unit base acceleration of the model linearised about rest, transducer and loads included).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfPowerBand {
    /// The frequency of the largest displacement (Hz).
    pub peak_hz: f64,
    /// The width between the frequencies where the displacement is 1/sqrt(2) of its peak (Hz).
    pub width_hz: f64,
}

/// Default steps per half-power width.
pub const STEPS_PER_BAND: f64 = 4.0;

/// How far the frequency moves per ring-up time 1/(pi w) during a ramp, in half-power widths.
pub const RAMP_BANDS_PER_RING: f64 = 0.02;

/// The linear half-power band of `device`: the displacement's peak searched from a tenth to
/// ten times the open-circuit resonance on a grid of 0.1 % steps and refined by golden
/// section, the half-power frequencies on either side by the root finder to 1e-9 of the peak
/// frequency. `None` when either half-power frequency lies outside the searched range (an
/// overdamped device).
///
/// ```
/// use endstop::device::Device;
/// use endstop::physics::linear::open_circuit_resonance_hz;
/// use endstop::study::chirp::half_power_band;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// let band = half_power_band(&device).unwrap();
/// // The loaded element stiffens the suspension by less than open circuit does: the peak lies
/// // between the short-circuit resonance sqrt(k/m) / 2 pi and the open-circuit one (damping
/// // moves it below the undamped frequency by a relative zeta^2 = 1e-4; 1e-3 allows it).
/// let short_hz = (2842.0f64 / 5e-3).sqrt() / (2.0 * std::f64::consts::PI);
/// assert!(band.peak_hz > short_hz * (1.0 - 1e-3) && band.peak_hz < open_circuit_resonance_hz(&device));
/// // The load only adds damping: the band is wider than the mechanics' own, b / (2 pi m).
/// assert!(band.width_hz > 0.0754 / (2.0 * std::f64::consts::PI * 5e-3));
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn half_power_band(device: &Device) -> Option<HalfPowerBand> {
    let lin = LinearResponse::of(device);
    let x = |f: f64| lin.displacement_per_accel(f);
    let f_oc = open_circuit_resonance_hz(device);
    let (lo, hi) = (0.1 * f_oc, 10.0 * f_oc);
    let ratio: f64 = 1.001;
    let n = ((hi / lo).ln() / ratio.ln()).ceil() as usize;
    let grid = |i: usize| lo * ratio.powi(i as i32);
    let k = (0..=n).max_by(|&a, &b| x(grid(a)).total_cmp(&x(grid(b))))?;
    if k == 0 || k == n {
        return None;
    }
    // Golden section on the bracket around the grid's peak.
    let (mut a, mut b) = (grid(k - 1), grid(k + 1));
    let g = 0.5 * (5f64.sqrt() - 1.0);
    for _ in 0..100 {
        let (c, d) = (b - g * (b - a), a + g * (b - a));
        if x(c) > x(d) {
            b = d;
        } else {
            a = c;
        }
    }
    let peak_hz = 0.5 * (a + b);
    let half = x(peak_hz) / std::f64::consts::SQRT_2;
    let h = |f: f64| x(f) - half;
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-9 * peak_hz,
        x_tol_rel: 0.0,
        max_iter: 200,
    };
    let root = |a: f64, b: f64| -> Option<f64> {
        if (h(a) > 0.0) == (h(b) > 0.0) {
            return None;
        }
        let r = illinois(
            |f| -> Result<(f64, ()), ()> { Ok((h(f), ())) },
            Sample::new(a, h(a), ()),
            Sample::new(b, h(b), ()),
            &opts,
        )
        .ok()?;
        Some(0.5 * (r.positive.x + r.non_positive.x))
    };
    let f_lo = root(lo, peak_hz)?;
    let f_hi = root(peak_hz, hi)?;
    Some(HalfPowerBand {
        peak_hz,
        width_hz: f_hi - f_lo,
    })
}

/// The largest of 1, 2 and 5 times a power of ten not above `x` (> 0).
fn round_down_nice(x: f64) -> f64 {
    let p = 10f64.powf(x.log10().floor());
    [5.0, 2.0, 1.0]
        .into_iter()
        .map(|m| m * p)
        .find(|&v| v <= x * (1.0 + 1e-12))
        .unwrap_or(p)
}

/// The default frequency step of a sweep of `device` over `from_hz..to_hz` (Hz): a quarter of
/// its half-power width rounded down to 1, 2 or 5 times a power of ten, at most a tenth of
/// the range, and at least the range over [`crate::study::sweep::MAX_STEPS`] steps; a
/// hundredth of the range for a device without a half-power band.
pub fn default_step_hz(device: &Device, from_hz: f64, to_hz: f64) -> f64 {
    let span = (to_hz - from_hz).abs();
    let step = half_power_band(device).map_or(0.01 * span, |b| {
        round_down_nice(b.width_hz / STEPS_PER_BAND)
    });
    step.min(0.1 * span)
        .max(span / crate::study::sweep::MAX_STEPS as f64)
}

/// The default ramp rate of `device` (Hz/s): [`RAMP_BANDS_PER_RING`] half-power widths per
/// ring-up time 1/(pi w), that is pi w^2 / 50; `None` without a half-power band.
pub fn default_ramp_rate_hz_per_s(device: &Device) -> Option<f64> {
    half_power_band(device)
        .map(|b| RAMP_BANDS_PER_RING * std::f64::consts::PI * b.width_hz * b.width_hz)
}

/// A swept sine: the drive's frequency moves linearly at `rate_hz_per_s` from `from_hz` to
/// `to_hz` (either way), at a continuous phase, from the steady state at `from_hz`.
#[derive(Debug, Clone, PartialEq)]
pub struct ChirpSweep {
    /// First frequency (Hz).
    pub from_hz: f64,
    /// Last frequency (Hz).
    pub to_hz: f64,
    /// The sweep rate (Hz/s, positive).
    pub rate_hz_per_s: f64,
    /// Cycles per reported window.
    pub window_cycles: usize,
    /// The steady state at the first frequency, and the integrator's tolerance.
    pub cfg: SettleSettings,
}

/// One window of a swept sine.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChirpWindow {
    /// The drive's frequency at the window's middle (Hz).
    pub freq_hz: f64,
    /// RMS voltage of load 1 over the window (V).
    pub v1_rms_v: f64,
    /// RMS voltage of load 2 over the window (V).
    pub v2_rms_v: f64,
    /// Mean power of the loads over the window (W).
    pub p_total_w: f64,
    /// Largest |x| (m).
    pub x_peak_m: f64,
    /// Each mass's largest |x| and |v| in the window for a model of several masses (at the
    /// ends and midpoints of the steps, as `x_peak_m`); none for one mass.
    pub mass_peaks: MassPeaks,
    /// True when the mass touched a stop in the window.
    pub contact: bool,
}

/// A swept sine's windows and where it starts and stops touching the stops.
#[derive(Debug, Clone, PartialEq)]
pub struct ChirpReport {
    /// The sweep.
    pub sweep: ChirpSweep,
    /// The windows in time order.
    pub windows: Vec<ChirpWindow>,
    /// The frequency of the first window in contact after one without (Hz).
    pub first_contact_hz: Option<f64>,
    /// The frequency of the window in contact before the last one without (Hz): where a
    /// sweep up leaves the impacting orbits for good.
    pub last_contact_hz: Option<f64>,
    /// Integrator counters.
    pub stats: Stats,
}

/// Sums over the windows of a swept sine.
struct Windows<'m, M, const N: usize> {
    model: &'m M,
    chirp: Chirp,
    cycles: f64,
    current: Option<i64>,
    acc: [f64; 5],
    peaks: MassPeaks,
    /// Per output, the integrals of its square and of itself over the window.
    squares: Vec<f64>,
    integrals: Vec<f64>,
    t0: f64,
    out: Vec<ChirpWindow>,
}

impl<M: Model<N>, const N: usize> Windows<'_, M, N> {
    fn close(&mut self, t1: f64) {
        let dur = t1 - self.t0;
        if self.current.is_some() && dur > 0.0 {
            let [v1sq, v2sq, x_peak, contact, _] = self.acc;
            let layout = self.model.layout();
            self.out.push(ChirpWindow {
                freq_hz: self.chirp.freq_hz(0.5 * (self.t0 + t1)),
                v1_rms_v: (v1sq / dur).sqrt(),
                v2_rms_v: (v2sq / dur).sqrt(),
                p_total_w: layout.load_power(&self.squares, &self.integrals, dur),
                x_peak_m: x_peak,
                mass_peaks: self.peaks,
                contact: contact > 0.0,
            });
        }
        self.acc = [0.0; 5];
        self.peaks = MassPeaks::of(self.model.layout());
        self.squares.iter_mut().for_each(|v| *v = 0.0);
        self.integrals.iter_mut().for_each(|v| *v = 0.0);
        self.t0 = t1;
    }
}

impl<M: Model<N>, const N: usize> Observer<SVector<f64, N>, Mode> for Windows<'_, M, N> {
    fn step(&mut self, st: &Step<SVector<f64, N>>, mode: Mode) {
        let two_pi = 2.0 * std::f64::consts::PI;
        let mid = st.t0 + 0.5 * st.h;
        let k = (self.chirp.phase(mid) / (two_pi * self.cycles)).floor() as i64;
        if self.current != Some(k) {
            self.close(st.t0);
            self.current = Some(k);
        }
        let model = self.model;
        let n_out = self.squares.len();
        // The outputs' squares and values by 3-point Gauss-Legendre on the dense output, as
        // `Step::integrate` sums each.
        let (mut sq, mut li) = ([0.0; MAX_OUTPUTS], [0.0; MAX_OUTPUTS]);
        for (x, w) in crate::ode::GAUSS_LEGENDRE_3 {
            let mut out = [0.0; MAX_OUTPUTS];
            model.outputs(mode, &st.at_theta(x), &mut out[..n_out]);
            for i in 0..n_out {
                sq[i] += w * out[i].powi(2);
                li[i] += w * out[i];
            }
        }
        self.acc[0] += sq[0] * st.h;
        self.acc[1] += sq[1] * st.h;
        for i in 0..n_out {
            self.squares[i] += sq[i] * st.h;
            self.integrals[i] += li[i] * st.h;
        }
        let ym = st.at_theta(0.5);
        self.acc[2] = self.acc[2].max(st.y1[0].abs()).max(ym[0].abs());
        if self.peaks.len > 0 {
            self.peaks.see(model.layout(), st.y1.as_slice());
            self.peaks.see(model.layout(), ym.as_slice());
        }
        if mode.in_contact() {
            self.acc[3] += 1.0;
        }
    }

    fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
        if SwitchKind::between(from, to).is_impact() {
            self.acc[3] += 1.0;
        }
    }
}

impl ChirpSweep {
    /// Runs the swept sine on `device` at `accel_rms_g` (g rms).
    pub fn run(&self, device: &Device, accel_rms_g: f64) -> Result<ChirpReport, SolverError> {
        crate::with_harvester!(device, |h| self.run_on(&h, accel_rms_g))
    }

    /// Runs the swept sine on a model at `accel_rms_g` (g rms).
    pub fn run_on<M: Model<N>, const N: usize>(
        &self,
        base: &M,
        accel_rms_g: f64,
    ) -> Result<ChirpReport, SolverError> {
        let rest = base.rest_state();
        let (_, y, mode, mut stats) = steady_state(
            base,
            Sine::from_rms_g(accel_rms_g, self.from_hz),
            rest,
            base.mode_of(&rest),
            accel_rms_g,
            &self.cfg,
        )?;
        let duration_s = (self.to_hz - self.from_hz).abs() / self.rate_hz_per_s;
        let amp = std::f64::consts::SQRT_2 * accel_rms_g * crate::G;
        let chirp = Chirp {
            f0_hz: self.from_hz,
            f1_hz: self.to_hz,
            a0_m_s2: amp,
            a1_m_s2: amp,
            duration_s,
            phase_rad: 0.0,
            profile: Profile::Linear,
        };
        let n_out = base.layout().outputs.len();
        let model = Driven::new(base, chirp);
        let mut w: Windows<M, N> = Windows {
            model: base,
            chirp,
            cycles: self.window_cycles.max(1) as f64,
            current: None,
            acc: [0.0; 5],
            peaks: MassPeaks::of(base.layout()),
            squares: vec![0.0; n_out],
            integrals: vec![0.0; n_out],
            t0: 0.0,
            out: Vec::new(),
        };
        let mut ode = Dopri5::new(0.0, y, mode, base.solver_options(self.cfg.rtol));
        // In pieces of a second: the integrator's budget of steps is per call, and a stiff
        // contact can take many steps per period over a long sweep.
        let mut t = 0.0;
        while t < duration_s {
            t = (t + 1.0).min(duration_s);
            ode.integrate_observed(&model, t, &mut w)?;
        }
        w.close(duration_s);
        stats += ode.stats();
        let windows = w.out;
        let first_contact_hz = windows
            .windows(2)
            .find(|p| !p[0].contact && p[1].contact)
            .map(|p| p[1].freq_hz);
        let last_contact_hz = windows
            .windows(2)
            .rfind(|p| p[0].contact && !p[1].contact)
            .map(|p| p[0].freq_hz);
        Ok(ChirpReport {
            sweep: self.clone(),
            windows,
            first_contact_hz,
            last_contact_hz,
            stats,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn nice_rounding_keeps_1_2_5() {
        assert_eq!(round_down_nice(0.37), 0.2);
        assert_eq!(round_down_nice(1.0), 1.0);
        assert_eq!(round_down_nice(7.3), 5.0);
        assert_eq!(round_down_nice(0.019), 0.01);
    }
}

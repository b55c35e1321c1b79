//! Steady state of the harvester under a sinusoidal drive.
//!
//! The drive starts at phase zero from a given state (every measurement ends on a whole number
//! of periods, so a sweep that continues from the final state keeps the drive phase
//! continuous). The model is integrated for `settle_blocks` blocks of `block_periods` periods,
//! then measured block by block; the steady state is reached when the RMS voltages of two
//! successive blocks differ by less than `rel_change_tol` (relative). Blocks of about the
//! mechanical ring-up time 2m/b ([`settle_settings`]) leave a transient of the order of the
//! tolerance. The last block is the measurement.
//!
//! # Near a fold
//! Past a saddle-node fold of the response there is no orbit on the branch any more, but the
//! state leaves it slowly: the *ghost* of the two orbits that have just merged holds it for a
//! passage time that grows like the inverse square root of the distance from the fold. Two
//! blocks of the ring-up time see a state that barely changes and accept it, so a sweep with
//! such blocks leaves the branch late. The criterion accepts a state no sooner than
//! `settle_blocks + 2` blocks (its *horizon*); a state that falls off the branch within the
//! horizon makes two successive blocks differ by far more than the tolerance and is not
//! accepted before it has fallen. A sweep that must leave a branch at its fold within its
//! refinement bracket therefore needs a horizon longer than the ghost's passage time at the
//! bracket's width from the fold: [`settle_settings_across_folds`] gives blocks of at least
//! [`FOLD_BLOCK_PERIODS`] periods, whose horizon outlasts prototype 1's ghost 0.1 Hz past its
//! folds (the book's response chapter measures the passage time; a test checks the
//! inequality). Closer to the fold than that the passage time still grows without bound: no
//! fixed block resolves a fold better than the bracket it was chosen for.

use nalgebra::SVector;

use crate::device::Device;
use crate::drive::Sine;
use crate::model::{Load, Mode, Model, SwitchKind, MAX_OUTPUTS};
use crate::ode::{Observer, SolverError, Stats, Step};
use crate::study::flow::SineFlow;
use crate::study::mass_peaks::MassPeaks;

/// Minimum block length in periods for the default steady-state settings.
pub const MIN_BLOCK_PERIODS: usize = 5;

/// Minimum block length in periods for sweeps that cross a saddle-node fold
/// ([`settle_settings_across_folds`]; see the module docs): the horizon of three such blocks (192
/// periods) outlasts the ghost of prototype 1's folds 0.1 Hz past them (the response
/// chapter's ghost table: under 100 periods for either parameter set), by nearly a factor of
/// two; the response chapter's convergence table repeats the sweeps with half the block and
/// finds the branch end moved by less than the bracket.
pub const FOLD_BLOCK_PERIODS: usize = 64;

/// Steady-state measurement settings.
#[derive(Debug, Clone, PartialEq)]
pub struct SettleSettings {
    /// Integrator relative tolerance.
    pub rtol: f64,
    /// Periods per block.
    pub block_periods: usize,
    /// Blocks simulated before the first measured block.
    pub settle_blocks: usize,
    /// Convergence: relative change of RMS voltages between successive blocks.
    pub rel_change_tol: f64,
    /// Maximum measured blocks per step (the step is flagged unconverged beyond).
    pub max_blocks: usize,
}

impl SettleSettings {
    /// Settings for a device: blocks of about the ring-up time 2m/b at `freq_hz`, at least
    /// `min_periods`.
    pub fn for_ring_time(ring_time_s: f64, freq_hz: f64, min_periods: usize) -> Self {
        let periods = (ring_time_s * freq_hz).ceil() as usize;
        Self {
            rtol: 1e-8,
            block_periods: periods.max(min_periods),
            settle_blocks: 1,
            rel_change_tol: 1e-3,
            max_blocks: 60,
        }
    }

    /// The same criterion with half the integrator tolerance and half the steady-state
    /// tolerance (the numerics of a convergence repetition).
    pub fn halved(&self) -> Self {
        Self {
            rtol: 0.5 * self.rtol,
            rel_change_tol: 0.5 * self.rel_change_tol,
            ..self.clone()
        }
    }
}

/// Default steady-state settings for a device driven near `freq_hz`: blocks of about the
/// mechanical ring-up time 2m/b, at least [`MIN_BLOCK_PERIODS`] periods, see
/// [`SettleSettings::for_ring_time`].
///
/// ```
/// use endstop::device::Device;
/// use endstop::study::steady::{horizon_periods, settle_settings, MIN_BLOCK_PERIODS};
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype1.toml"));
/// let device = Device::from_toml_str(text, "prototype1.toml")?;
/// // 2m/b = 2 (2.8e-6 kg) / (3.75e-3 N s/m) = 1.49 ms: 1.8 periods at 1200 Hz, so the
/// // floor of MIN_BLOCK_PERIODS periods decides; at 10 kHz the ring-up time does (15 periods).
/// assert_eq!(settle_settings(&device, 1200.0).block_periods, MIN_BLOCK_PERIODS);
/// let cfg = settle_settings(&device, 10e3);
/// assert_eq!(cfg.block_periods, 15);
/// // The horizon: one settling block and two measured ones.
/// assert_eq!(horizon_periods(&cfg), 45);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn settle_settings(device: &Device, freq_hz: f64) -> SettleSettings {
    let ring_s = 2.0 * device.mechanics.mass_kg / device.mechanics.damping_n_s_per_m;
    SettleSettings::for_ring_time(ring_s, freq_hz, MIN_BLOCK_PERIODS)
}

/// Steady-state settings for a sweep that must leave a branch at its saddle-node fold within
/// its refinement bracket: as [`settle_settings`], with blocks of at least
/// [`FOLD_BLOCK_PERIODS`] periods (see the module docs).
pub fn settle_settings_across_folds(device: &Device, freq_hz: f64) -> SettleSettings {
    let ring_s = 2.0 * device.mechanics.mass_kg / device.mechanics.damping_n_s_per_m;
    SettleSettings::for_ring_time(ring_s, freq_hz, FOLD_BLOCK_PERIODS)
}

/// The horizon of a criterion: the fewest periods it simulates before it can accept a state
/// (the settling blocks and two measured blocks).
pub fn horizon_periods(cfg: &SettleSettings) -> usize {
    (cfg.settle_blocks + 2) * cfg.block_periods
}

/// Steady-state response at one drive.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Measurement {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// Drive RMS acceleration (g).
    pub accel_rms_g: f64,
    /// RMS voltage of load 1 (V).
    pub v1_rms_v: f64,
    /// RMS voltage of load 2 (V).
    pub v2_rms_v: f64,
    /// RMS of the differential voltage V2 - V1 (V).
    pub vdiff_rms_v: f64,
    /// Mean power in load 1 (W).
    pub p1_w: f64,
    /// Mean power in load 2 (W).
    pub p2_w: f64,
    /// Largest |x| (m).
    pub x_peak_m: f64,
    /// Each mass's largest |x| and |v| for a model of several masses (at the ends and
    /// midpoints of the measured block's steps, as `x_peak_m`); none for one mass.
    pub mass_peaks: MassPeaks,
    /// Fraction of time past a stop.
    pub contact_fraction: f64,
    /// Impacts (contact entries) per period.
    pub impacts_per_period: f64,
    /// Measured blocks needed.
    pub blocks: usize,
    /// Relative change between the last two blocks.
    pub last_rel_change: f64,
    /// True when the convergence criterion was met.
    pub converged: bool,
}

impl Measurement {
    /// Power of both loads (W).
    pub fn p_total_w(&self) -> f64 {
        self.p1_w + self.p2_w
    }
}

/// Accumulates whole-period averages over accepted steps.
/// The sums of one block of periods: an observer of its steps and of its rebounds off rigid
/// stops (impacts without a contact phase).
struct Block<'m, M> {
    model: &'m M,
    /// The integral of the first output (for a battery's power).
    v1: f64,
    v1sq: f64,
    v2sq: f64,
    vdsq: f64,
    x_peak: f64,
    peaks: MassPeaks,
    contact_time: f64,
    impacts: u64,
    prev_mode_free: bool,
}

impl<M: Model<N>, const N: usize> Observer<SVector<f64, N>, Mode> for Block<'_, M> {
    fn step(&mut self, st: &Step<SVector<f64, N>>, m: Mode) {
        let model = self.model;
        let k = model.layout().outputs.len().min(MAX_OUTPUTS);
        let [v1sq, v2sq, vdsq, v1] = st.integrate_each(|y: &SVector<f64, N>| {
            let mut out = [0.0; MAX_OUTPUTS];
            model.outputs(m, y, &mut out[..k]);
            let v = [out[0], out[1]];
            [v[0].powi(2), v[1].powi(2), (v[1] - v[0]).powi(2), v[0]]
        });
        self.v1 += v1;
        self.v1sq += v1sq;
        self.v2sq += v2sq;
        self.vdsq += vdsq;
        let ym = st.at_theta(0.5);
        self.x_peak = self.x_peak.max(st.y1[0].abs()).max(ym[0].abs());
        if self.peaks.len > 0 {
            let layout = model.layout();
            self.peaks.see(layout, st.y1.as_slice());
            self.peaks.see(layout, ym.as_slice());
        }
        if m.in_contact() {
            self.contact_time += st.h;
            if self.prev_mode_free {
                self.impacts += 1;
            }
        }
        self.prev_mode_free = !m.in_contact();
    }

    fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
        if SwitchKind::between(from, to) == SwitchKind::Rebound {
            self.impacts += 1;
        }
    }
}

/// The state moved onto the periodic orbit by shooting ([`crate::study::periodic`]) when the
/// model has a time constant longer than a block ([`Model::slow_time_constant_s`]): blocks
/// would accept a state still approaching it. Where shooting finds no orbit the blocks start
/// from the state given (and say by `converged` whether they settled).
fn onto_slow_orbit<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: SVector<f64, N>,
    mode: Mode,
    block_t: f64,
    cfg: &SettleSettings,
) -> (SVector<f64, N>, Mode) {
    match model.slow_time_constant_s() {
        Some(tau) if tau > block_t => {
            let settings = crate::study::periodic::SteadySettings {
                rtol: cfg.rtol,
                ..Default::default()
            };
            match crate::study::periodic::steady_state(model, sine, &y, &settings) {
                Ok(p) => {
                    let y = crate::study::periodic::state_of(&p);
                    (y, model.mode_of(&y))
                }
                Err(_) => (y, mode),
            }
        }
        _ => (y, mode),
    }
}

/// Integrates `model` from (y, mode) at phase zero to steady state and measures it (by
/// [`SineFlow`]: exactly where the device is affine, by Dormand-Prince elsewhere).
/// Returns the measurement, the final state and mode (at a whole period), and the counters.
///
/// A piezoelectric cantilever driven far below its stopper is linear, so its steady voltage
/// has a closed form: with the load's admittance `Y = 1/R + j w Cp`, the displacement is
/// `X = m A / |k - m w^2 + j w b + j w theta^2 / Y|` and the voltage `V = w theta X / |Y|`.
///
/// ```
/// use endstop::device::Device;
/// use endstop::drive::Sine;
/// use endstop::model::Model;
/// use endstop::study::steady::{settle_settings, steady_state};
/// use nalgebra::Complex;
///
/// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
/// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
/// let (f, g) = (115.0, 0.01);
/// let m = endstop::with_harvester!(&device, |h| {
///     let rest = h.rest_state();
///     let cfg = settle_settings(&device, f);
///     steady_state(&h, Sine::from_rms_g(g, f), rest, h.mode_of(&rest), g, &cfg).map(|r| r.0)
/// })?;
/// // The file's m, k, b, theta, Cp and R.
/// let (mass, k, b, theta, cp, r) = (5e-3, 2842.0, 0.0754, 2.67e-3, 50e-9, 26.5e3);
/// let w = 2.0 * std::f64::consts::PI * f;
/// let y = Complex::new(1.0 / r, w * cp);
/// let z = Complex::new(k - mass * w * w, w * b) + Complex::new(0.0, w * theta * theta) / y;
/// let x_amp = mass * 2f64.sqrt() * g * endstop::G / z.norm();
/// let v_rms = w * theta * x_amp / y.norm() / 2f64.sqrt();
/// assert!(m.converged && m.contact_fraction == 0.0 && m.x_peak_m < 0.1e-3);
/// // The criterion stops when two blocks of about 2m/b differ by under 1e-3 and the
/// // transient left shrinks by about e per block, so the last block is within about 1e-3
/// // of the orbit: 5e-3 leaves room for that.
/// assert!((m.v1_rms_v / v_rms - 1.0).abs() < 5e-3);
/// // The load's power is V^2 / R (to rounding).
/// assert!((m.p1_w / (m.v1_rms_v * m.v1_rms_v / r) - 1.0).abs() < 1e-12);
/// # Ok::<(), Box<dyn std::error::Error>>(())
/// ```
pub fn steady_state<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: SVector<f64, N>,
    mode: Mode,
    accel_rms_g: f64,
    cfg: &SettleSettings,
) -> Result<(Measurement, SVector<f64, N>, Mode, Stats), SolverError> {
    let block_t = cfg.block_periods as f64 * sine.period_s();
    let (y, mode) = onto_slow_orbit(model, sine, y, mode, block_t, cfg);
    settle_and_measure(model, sine, y, mode, accel_rms_g, cfg)
}

/// The blocks of [`steady_state`] from (y, mode) as given, without putting the state on a slow
/// orbit first: for a state already on its periodic orbit (then `cfg.settle_blocks` may be
/// zero) or a model without a slow time constant.
pub fn settle_and_measure<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: SVector<f64, N>,
    mode: Mode,
    accel_rms_g: f64,
    cfg: &SettleSettings,
) -> Result<(Measurement, SVector<f64, N>, Mode, Stats), SolverError> {
    let block_t = cfg.block_periods as f64 * sine.period_s();
    let mut ode = SineFlow::new(model, sine, 0.0, y, mode, cfg.rtol);
    let mut t_end = 0.0;
    for _ in 0..cfg.settle_blocks {
        t_end += block_t;
        ode.advance(t_end)?;
    }
    let mut prev: Option<(f64, f64)> = None;
    let mut blocks = 0;
    let mut last_change = f64::INFINITY;
    loop {
        let t_start = t_end;
        t_end += block_t;
        let mut b = Block {
            model,
            prev_mode_free: !ode.mode().in_contact(),
            v1: 0.0,
            v1sq: 0.0,
            v2sq: 0.0,
            vdsq: 0.0,
            x_peak: 0.0,
            peaks: MassPeaks::of(model.layout()),
            contact_time: 0.0,
            impacts: 0,
        };
        ode.integrate_observed(t_end, &mut b)?;
        blocks += 1;
        let dur = t_end - t_start;
        let v1 = (b.v1sq / dur).sqrt();
        let v2 = (b.v2sq / dur).sqrt();
        let converged = if let Some((p1, p2)) = prev {
            let rel = |a: f64, b: f64| (a - b).abs() / a.abs().max(b.abs()).max(1e-300);
            last_change = rel(v1, p1).max(rel(v2, p2));
            last_change < cfg.rel_change_tol
        } else {
            false
        };
        prev = Some((v1, v2));
        if converged || blocks >= cfg.max_blocks {
            let power = |i: usize, sq: f64, int: f64| match model
                .layout()
                .outputs
                .get(i)
                .and_then(|o| o.load)
            {
                Some(Load::Resistor(r)) => sq / dur / r,
                Some(l) => l.mean_power(int / dur, sq / dur),
                None => 0.0,
            };
            let m = Measurement {
                freq_hz: sine.freq_hz,
                accel_rms_g,
                v1_rms_v: v1,
                v2_rms_v: v2,
                vdiff_rms_v: (b.vdsq / dur).sqrt(),
                p1_w: power(0, b.v1sq, b.v1),
                p2_w: power(1, b.v2sq, f64::NAN),
                x_peak_m: b.x_peak,
                mass_peaks: b.peaks,
                contact_fraction: b.contact_time / dur,
                impacts_per_period: b.impacts as f64 / cfg.block_periods as f64,
                blocks,
                last_rel_change: last_change,
                converged,
            };
            return Ok((m, ode.y(), ode.mode(), ode.stats()));
        }
    }
}

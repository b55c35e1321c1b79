//! Our side of a case: the state both simulators start from, our steady state over the span
//! and its comparison window, the netlist ngspice runs over the same span, and our waveform
//! over the last period.

use super::{
    Case, CrosscheckError, Setting, Start, MIN_SPAN_PERIODS, OUTPUT_STEPS_PER_PERIOD,
    REL_CHANGE_TOL,
};
use crate::drive::Sine;
use crate::model::{Driven, Mode, Model};
use crate::ode::{Dopri5, SolverError, Stats};
use crate::physics::harvester::Harvester;
use crate::physics::transducer::State;
use crate::progress::Silent;
use crate::spice::{
    netlist, InitialCondition, SpiceDrive, SpiceOptions, Transient, HERTZ_NEWTON_STEPS,
};
use crate::study::steady::{settle_settings, steady_state, Measurement, SettleSettings};
use crate::study::stepped::{linspace_step, SteppedDrive};

/// A case ready to run: the model, the steady-state criterion and the state both simulators
/// start from.
#[derive(Debug, Clone)]
pub struct Prepared {
    /// The case.
    pub case: Case,
    /// The device's model (the paper's, four components).
    pub model: Harvester<4>,
    /// The case's drive.
    pub sine: Sine,
    /// Our steady-state criterion: blocks of the ring-up time, [`REL_CHANGE_TOL`], and enough
    /// settling blocks to span [`MIN_SPAN_PERIODS`].
    pub cfg: SettleSettings,
    /// The initial state.
    pub y0: State,
    /// The initial contact mode.
    pub mode0: Mode,
    /// Where the state comes from, for the book.
    pub start_label: String,
}

/// Prepares a case: the initial state is rest, or the end of our up-sweep at the case
/// frequency (the upper branch).
pub fn prepare(case: &Case) -> Result<Prepared, SolverError> {
    let (f, a) = (case.freq_hz, case.accel_rms_g);
    let model = Harvester::<4>::new(&case.device)?;
    let sine = Sine::from_rms_g(a, f);
    let mut cfg = settle_settings(&case.device, f);
    cfg.rel_change_tol = REL_CHANGE_TOL;
    let (y0, mode0, start_label) = match case.start {
        Start::Rest => (model.rest_state(), Mode::FREE, "rest".to_string()),
        Start::UpSweep { from_hz, step_hz } => {
            let c = SteppedDrive {
                base: &model,
                drive: move |ff: f64| (ff, a),
                cfg: cfg.clone(),
            };
            let sweep = c.run(&linspace_step(from_hz, f, step_hz), &Silent)?;
            let last = sweep
                .steps
                .last()
                .expect("a sweep up to the case frequency has a step");
            (
                State::from_column_slice(last.state.as_slice()),
                last.mode,
                format!("up-sweep {from_hz}-{f} Hz in {step_hz} Hz steps (ours)"),
            )
        }
    };
    cfg.settle_blocks = MIN_SPAN_PERIODS.div_ceil(cfg.block_periods).max(1);
    Ok(Prepared {
        case: case.clone(),
        model,
        sine,
        cfg,
        y0,
        mode0,
        start_label,
    })
}

/// Our side of a case: the steady state over the span, measured over its last block.
#[derive(Debug, Clone)]
pub struct Ours {
    /// The measurement over the comparison window.
    pub measurement: Measurement,
    /// The integrator's work.
    pub stats: Stats,
    /// The span, from 0 (s).
    pub t_end_s: f64,
    /// The comparison window (s): the last block.
    pub window_s: (f64, f64),
}

impl Ours {
    /// The length of the comparison window (s).
    pub fn window_length_s(&self) -> f64 {
        self.window_s.1 - self.window_s.0
    }
}

impl Prepared {
    /// Our steady state from the initial state over at least [`MIN_SPAN_PERIODS`] periods,
    /// measured over the last block; an error unless it converged.
    pub fn ours(&self) -> Result<Ours, CrosscheckError> {
        let a = self.case.accel_rms_g;
        let (m, _, _, stats) =
            steady_state(&self.model, self.sine, self.y0, self.mode0, a, &self.cfg)?;
        if !m.converged {
            return Err(CrosscheckError::NotSteady {
                case: self.case.key,
            });
        }
        let block_s = self.cfg.block_periods as f64 * self.case.period_s();
        let t_end_s = (self.cfg.settle_blocks + m.blocks) as f64 * block_s;
        Ok(Ours {
            measurement: m,
            stats,
            t_end_s,
            window_s: (t_end_s - block_s, t_end_s),
        })
    }

    /// Our RMS voltage of load 1 from rest at the same drive (the lower branch where the drive
    /// is bistable), with the sweeps' steady-state criterion (V); for a case without impacts,
    /// `ours`'s own.
    pub fn v1_from_rest(&self, ours: &Ours) -> Result<f64, SolverError> {
        if !self.case.impacting {
            return Ok(ours.measurement.v1_rms_v);
        }
        let cfg = settle_settings(&self.case.device, self.case.freq_hz);
        let rest = self.model.rest_state();
        let (m, ..) = steady_state(
            &self.model,
            self.sine,
            rest,
            Mode::FREE,
            self.case.accel_rms_g,
            &cfg,
        )?;
        Ok(m.v1_rms_v)
    }

    /// The options of the netlist of `setting` over `ours`'s span, writing its waveforms to
    /// `wrdata_file`.
    pub fn spice_options(
        &self,
        ours: &Ours,
        setting: Setting,
        wrdata_file: String,
    ) -> SpiceOptions {
        let period = self.case.period_s();
        SpiceOptions {
            title: format!(
                "endstop crosscheck: {} [{}]",
                self.case.label,
                setting.label()
            ),
            initial: InitialCondition::from_state(&self.case.device, &self.y0),
            solver: setting.solver(period),
            transient: Transient {
                stop_s: ours.t_end_s,
                step_s: period / OUTPUT_STEPS_PER_PERIOD,
                save_from_s: (ours.window_s.0 - period).max(0.0),
                wrdata_file: Some(wrdata_file),
            },
            hertz_newton_steps: HERTZ_NEWTON_STEPS,
        }
    }

    /// The netlist of `setting` over `ours`'s span, writing its waveforms to `wrdata_file`.
    pub fn netlist(&self, ours: &Ours, setting: Setting, wrdata_file: String) -> String {
        let drive = SpiceDrive {
            accel_rms_g: self.case.accel_rms_g,
            freq_hz: self.case.freq_hz,
        };
        netlist(
            &self.case.device,
            &drive,
            &self.spice_options(ours, setting, wrdata_file),
        )
    }

    /// Our V1 over the last period of `ours`'s span, sampled at `n` + 1 points, as (phase in
    /// periods, V1) (the book's plot).
    pub fn last_period(&self, ours: &Ours, n: usize) -> Result<Vec<(f64, f64)>, SolverError> {
        let model = &self.model;
        let period = self.case.period_s();
        let t_end = ours.t_end_s;
        let t_start = t_end - period;
        let times: Vec<f64> = (0..=n)
            .map(|i| t_start + period * i as f64 / n as f64)
            .collect();
        let mut pts = Vec::with_capacity(n + 1);
        let mut k = 0;
        let opts = model.solver_options(self.cfg.rtol);
        let mut ode = Dopri5::new(0.0, self.y0, self.mode0, opts);
        let mut out = [0.0; 2];
        ode.integrate(&Driven::new(model, self.sine), t_end, |st, m| {
            while k < times.len() && times[k] <= st.t1() {
                if times[k] >= st.t0 {
                    let y = st.at(times[k]);
                    model.outputs(m, &y, &mut out);
                    pts.push(((times[k] - t_start) / period, out[0]));
                }
                k += 1;
            }
        })?;
        Ok(pts)
    }
}

//! Amplitude sweeps at a fixed frequency (stepped RMS acceleration, Figure 9) with the impact
//! onset refined, and their convergence comparison.

use crate::device::Device;
use crate::model::Model;
use crate::ode::SolverError;
use crate::progress::Progress;
use crate::study::steady::{Measurement, SettleSettings};
use crate::study::stepped::{
    continue_sweep, first_contact, in_contact, values_beyond, with_midpoints, SteppedDrive, Sweep,
    Transition,
};

/// An amplitude continuation at fixed frequency (Figure 9) with its refined impact onset.
#[derive(Debug, Clone)]
pub struct AmplitudeReport {
    /// The coarse continuation (values in g rms), including any extension.
    pub sweep: Sweep,
    /// Index of the first step beyond the requested range (`None`: not extended).
    pub extended_from: Option<usize>,
    /// Impact onset bracket (g rms); `None` if no contact, or contact from the first step.
    pub onset: Option<Transition>,
    /// True when the first step is already in contact.
    pub contact_at_start: bool,
}

impl AmplitudeReport {
    /// The measurement at the largest requested amplitude (the saturated power of Figure 9).
    pub fn at_stop(&self) -> &Measurement {
        let n = self.extended_from.unwrap_or(self.sweep.steps.len());
        &self.sweep.steps[n - 1].measurement
    }

    /// The coarse measurements inside the requested range (without the extension).
    pub fn measurements_in_range(&self) -> impl Iterator<Item = &Measurement> {
        let n = self.extended_from.unwrap_or(self.sweep.steps.len());
        self.sweep.steps[..n].iter().map(|s| &s.measurement)
    }
}

/// Settings of an amplitude continuation (Figure 9).
#[derive(Debug, Clone, PartialEq)]
pub struct AmplitudeSettings {
    /// Drive frequency (Hz).
    pub freq_hz: f64,
    /// RMS accelerations (g, increasing), the requested range.
    pub accels_rms_g: Vec<f64>,
    /// If no step of the requested range touches a stop, the continuation goes on with the
    /// same spacing until it does or this amplitude is passed (g rms), so that the onset is
    /// found even beyond the paper's range.
    pub extend_to_g: f64,
    /// Steady-state criterion.
    pub cfg: SettleSettings,
    /// Bracket width of the refined onset (g).
    pub refine_tol_g: f64,
}

impl AmplitudeSettings {
    /// Half the amplitude step, the integrator tolerance, the steady-state tolerance and the
    /// refinement bracket (convergence check).
    pub fn halved(&self) -> Self {
        Self {
            freq_hz: self.freq_hz,
            accels_rms_g: with_midpoints(&self.accels_rms_g),
            extend_to_g: self.extend_to_g,
            cfg: self.cfg.halved(),
            refine_tol_g: 0.5 * self.refine_tol_g,
        }
    }

    /// Runs the continuation for `device` and refines the onset (see [`AmplitudeReport`]).
    ///
    /// Off its stopper a piezoelectric cantilever is linear, so the onset of impacts is the
    /// amplitude at which its linear displacement reaches the gap.
    ///
    /// ```
    /// use endstop::device::Device;
    /// use endstop::physics::linear::LinearResponse;
    /// use endstop::progress::Silent;
    /// use endstop::study::amplitude::AmplitudeSettings;
    /// use endstop::study::steady::settle_settings;
    ///
    /// let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/examples/piezo_cantilever.toml"));
    /// let device = Device::from_toml_str(text, "piezo_cantilever.toml")?;
    /// let f = 120.0;
    /// let settings = AmplitudeSettings {
    ///     freq_hz: f,
    ///     accels_rms_g: vec![0.1, 0.15, 0.2, 0.25, 0.3],
    ///     extend_to_g: 0.3,
    ///     cfg: settle_settings(&device, f),
    ///     refine_tol_g: 1e-3,
    /// };
    /// let report = settings.run(&device, &Silent)?;
    /// let onset = report.onset.expect("the stopper is reached within the range");
    /// // The gap (0.1 mm) over the displacement per peak acceleration, in g rms.
    /// let per_accel = LinearResponse::of(&device).displacement_per_accel(f);
    /// let predicted = 0.1e-3 / per_accel / (2f64.sqrt() * endstop::G);
    /// // The bracket's half-width, and the steady state's error (the criterion's 1e-3,
    /// // relative) on the amplitude at which the peak displacement crosses the gap.
    /// assert!((onset.value() - predicted).abs() < onset.half_width() + 2e-3 * predicted);
    /// # Ok::<(), Box<dyn std::error::Error>>(())
    /// ```
    pub fn run(
        &self,
        device: &Device,
        progress: &dyn Progress,
    ) -> Result<AmplitudeReport, SolverError> {
        crate::with_harvester!(device, |h| self.run_on(&h, progress))
    }

    /// As [`AmplitudeSettings::run`] on a model.
    pub fn run_on<M: Model<N>, const N: usize>(
        &self,
        base: &M,
        progress: &dyn Progress,
    ) -> Result<AmplitudeReport, SolverError> {
        let f = self.freq_hz;
        let acc = &self.accels_rms_g;
        let cont = SteppedDrive {
            base,
            drive: move |a: f64| (f, a),
            cfg: self.cfg.clone(),
        };
        let mut sweep = cont.run(acc, progress)?;
        let n = sweep.steps.len();
        let mut extended_from = None;
        if first_contact(&sweep).is_none() && n >= 2 {
            let step = acc[n - 1] - acc[n - 2];
            let more = values_beyond(acc[n - 1], step, self.extend_to_g);
            continue_sweep(base, |a| (f, a), &self.cfg, &mut sweep, more, in_contact)?;
            if sweep.steps.len() > n {
                extended_from = Some(n);
            }
        }
        let k_on = first_contact(&sweep);
        let onset = match k_on {
            Some(k) if k > 0 => {
                Some(cont.refine(&sweep, k, |m| !in_contact(m), self.refine_tol_g)?)
            }
            _ => None,
        };
        Ok(AmplitudeReport {
            sweep,
            extended_from,
            onset,
            contact_at_start: k_on == Some(0),
        })
    }
}

/// Runs an amplitude continuation of `device` at `freq_hz` over `accels_rms_g` (increasing;
/// each step starts from the previous final state) and refines the impact onset by bisection
/// to a bracket narrower than `refine_tol_g` (Figure 9). No extension beyond the range.
pub fn amplitude_sweep_report(
    device: &Device,
    freq_hz: f64,
    accels_rms_g: &[f64],
    cfg: &SettleSettings,
    refine_tol_g: f64,
    progress: &dyn Progress,
) -> Result<AmplitudeReport, SolverError> {
    AmplitudeSettings {
        freq_hz,
        accels_rms_g: accels_rms_g.to_vec(),
        extend_to_g: f64::NEG_INFINITY,
        cfg: cfg.clone(),
        refine_tol_g,
    }
    .run(device, progress)
}

/// Differences between an amplitude continuation and its refined repetition.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct AmplitudeComparison {
    /// Absolute change of the onset (g; `None` if either has none).
    pub onset_abs_g: Option<f64>,
    /// Relative change of the power of both loads at the last requested amplitude.
    pub p_rel: f64,
    /// Largest relative change of the RMS voltage of load 1 at the common amplitudes.
    pub max_v1_rel: f64,
}

/// Compares two amplitude continuations (see [`AmplitudeComparison`]).
pub fn compare_amplitude(
    reference: &AmplitudeReport,
    refined: &AmplitudeReport,
) -> AmplitudeComparison {
    let rel = |a: f64, b: f64| (a - b).abs() / a.abs().max(b.abs()).max(1e-300);
    let mut max_v1_rel: f64 = 0.0;
    for ma in reference.measurements_in_range() {
        if let Some(mb) = refined
            .measurements_in_range()
            .find(|m| (m.accel_rms_g - ma.accel_rms_g).abs() <= 1e-9)
        {
            max_v1_rel = max_v1_rel.max(rel(ma.v1_rms_v, mb.v1_rms_v));
        }
    }
    AmplitudeComparison {
        onset_abs_g: match (reference.onset, refined.onset) {
            (Some(a), Some(b)) => Some((a.value() - b.value()).abs()),
            _ => None,
        },
        p_rel: rel(
            reference.at_stop().p_total_w(),
            refined.at_stop().p_total_w(),
        ),
        max_v1_rel,
    }
}

//! Prototype 1's stepped-sine protocol (Figure 8): drive levels, frequency range and sweep
//! settings, shared by the figure ([`crate::paper::figures::fig08`]), the calibration
//! ([`crate::paper::calibration`]), which fits the end-stop gap to the impact onset of the
//! same sweep, and the whole-response study ([`crate::paper::response`]).

use crate::device::Device;
use crate::study::steady::settle_settings_across_folds;
use crate::study::stepped;
use crate::study::sweep::{SweepSettings, REFINE_TOL_HZ};

/// Prototype 1, Figure 8: the low acceleration, no impacts (g rms).
pub const P1_LOW_ACCEL_RMS_G: f64 = 4.1;

/// Prototype 1, Figure 8: the high acceleration, with impacts (g rms).
pub const P1_HIGH_ACCEL_RMS_G: f64 = 5.5;

/// Prototype 1, Figure 8: first frequency of the up-sweep (Hz).
pub const P1_SWEEP_START_HZ: f64 = 900.0;

/// Prototype 1, Figure 8: last frequency of the up-sweep (Hz).
pub const P1_SWEEP_STOP_HZ: f64 = 1600.0;

/// Prototype 1: default frequency step of the up-sweeps (Hz).
pub const P1_SWEEP_STEP_HZ: f64 = 10.0;

/// Prototype 1, Figure 8: 900-1600 Hz in 10 Hz steps (extended to 2400 Hz if needed),
/// [`settle_settings_across_folds`] at 1220 Hz (blocks that outlast the ghost of the upper fold
/// at the bracket's width past it), brackets of [`REFINE_TOL_HZ`].
pub fn sweep_settings(device: &Device) -> SweepSettings {
    SweepSettings {
        freqs_hz: stepped::linspace_step(P1_SWEEP_START_HZ, P1_SWEEP_STOP_HZ, P1_SWEEP_STEP_HZ),
        extend_to_hz: 2400.0,
        cfg: settle_settings_across_folds(device, 1220.0),
        refine_tol_hz: REFINE_TOL_HZ,
    }
}

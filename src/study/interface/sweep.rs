//! Sweeps of the steady state of a device with an interface: over the drive frequency, and over
//! the DC load resistance. Each point starts from the previous point's steady state (its
//! section state), so that a sweep follows one branch, as a stepped-sine measurement does.
//! A point where shooting finds no period-one orbit (the response may be of a longer period,
//! or not periodic, with impacts and switches) is kept as its error, and the sweep goes on from
//! the last point found.

use crate::device::Device;
use crate::drive::Sine;
use crate::physics::harvester::State;
use crate::progress::Progress;

use super::{steady_state, IfSteady, InterfaceError, SteadySettings};

/// The steady states at each frequency (Hz) in order, at `accel_rms_g`, from rest (storage at
/// zero) for the first; `progress` is told of each point.
pub fn frequency_sweep(
    device: &Device,
    freqs_hz: &[f64],
    accel_rms_g: f64,
    settings: &SteadySettings,
    progress: &dyn Progress,
) -> Vec<Result<IfSteady, InterfaceError>> {
    let mut out = Vec::with_capacity(freqs_hz.len());
    let mut start = State::zeros();
    for &f in freqs_hz {
        let s = steady_state(device, Sine::from_rms_g(accel_rms_g, f), &start, settings);
        if let Ok(s) = &s {
            start = State::from(s.state);
        }
        progress.tick();
        out.push(s);
    }
    out
}

/// The steady states at each DC load resistance (ohm) in order, at one drive; every point
/// starts from rest with the storage at `vs_start_v` (a different load moves the DC voltage
/// far, so a neighbour's state is no better a start); `progress` is told of each point.
pub fn load_sweep(
    device: &Device,
    loads_ohm: &[f64],
    sine: Sine,
    settings: &SteadySettings,
    progress: &dyn Progress,
) -> Vec<Result<IfSteady, InterfaceError>> {
    let mut out = Vec::with_capacity(loads_ohm.len());
    for &r in loads_ohm {
        let mut d = device.clone();
        d.interface = d.interface.with_load_resistance(r);
        let s = steady_state(&d, sine, &State::zeros(), settings);
        progress.tick();
        out.push(s);
    }
    out
}

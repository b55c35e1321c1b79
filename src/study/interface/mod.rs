//! The interface circuits' own studies, moving into the studies written once over every model
//! ([`crate::study::periodic`] for the steady state and its sweeps).

pub mod charging;
mod linear_modes;
pub mod record;

use thiserror::Error;
use crate::device::Device;
use crate::ode::SolverError;
use crate::physics::interface::Interfaced;

/// A failed study of a device with an interface.
#[derive(Debug, Error, Clone, PartialEq)]
pub enum InterfaceError {
    /// The device's interface is resistive: the resistive studies apply.
    #[error("device `{0}` has a resistive load, not an interface circuit")]
    Resistive(String),
    /// The storage has no load: it only charges, and there is no periodic steady state.
    #[error(
        "device `{0}`: the storage has an open load (interface.load.kind = \"open\"), so it \
         charges towards the open-circuit limit and has no periodic steady state; use the \
         charging study"
    )]
    OpenLoad(String),
    /// The integrator failed.
    #[error("integration failed: {0}")]
    Solver(#[from] SolverError),
    /// A conduction mode is too stiff for the explicit integrator: its time constant is below
    /// [`STIFF_LIMIT`] of the suspension's period.
    #[error(
        "device `{name}`: a conduction mode's time constant {tau_s:e} s is below {STIFF_LIMIT:e} \
         of the suspension's period {period_s:e} s: the integrator would take more than \
         1e5 steps a period; use interface.diode.on_resistance_ohm = 0 (ideal with a drop) or \
         a larger one"
    )]
    Stiff {
        /// The device.
        name: String,
        /// The time constant (s).
        tau_s: f64,
        /// The suspension's period (s).
        period_s: f64,
    },
    /// The drive could not be made.
    #[error("drive: {0}")]
    Drive(String),
    /// Newton's method did not converge.
    #[error(
        "shooting did not converge in {iterations} Newton steps (scaled residual {residual:e}, \
         tolerance {tol:e})"
    )]
    NoConvergence {
        /// Newton steps taken.
        iterations: usize,
        /// Last scaled residual.
        residual: f64,
        /// Tolerance.
        tol: f64,
    },
}

/// The smallest conduction time constant accepted, relative to the suspension's period.
pub const STIFF_LIMIT: f64 = 1e-5;

/// Refuses a device whose conduction modes are too stiff (see [`InterfaceError::Stiff`]).
pub fn check_stiffness<E: crate::drive::Excitation>(
    device: &Device,
    model: &Interfaced<E>,
) -> Result<(), InterfaceError> {
    let period_s = 2.0 * std::f64::consts::PI / device.suspension_omega_rad_s();
    let tau_s = model.circuit.conduction_time_constant_s();
    if tau_s < STIFF_LIMIT * period_s {
        return Err(InterfaceError::Stiff {
            name: device.name.clone(),
            tau_s,
            period_s,
        });
    }
    Ok(())
}

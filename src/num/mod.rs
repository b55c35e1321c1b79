//! Generic numerical helpers: one bracketing root finder ([`roots`]), sample statistics
//! ([`stats`]), variance-based global sensitivity ([`sensitivity`]), multi-start minimax
//! fitting ([`minimax`]), Pareto fronts ([`pareto`]), Gaussian-process emulators ([`gp`]) with
//! their Sobol indices ([`gp_sensitivity`]) and history matching in waves ([`history`]).

pub mod gp;
pub mod gp_sensitivity;
pub mod history;
pub mod minimax;
pub mod pareto;
pub mod roots;
pub mod sensitivity;
pub mod stats;

//! Generic numerical helpers: one bracketing root finder ([`roots`]), sample statistics
//! ([`stats`]), variance-based global sensitivity ([`sensitivity`]), multi-start minimax
//! fitting ([`minimax`]) and Pareto fronts ([`pareto`]).

pub mod minimax;
pub mod pareto;
pub mod roots;
pub mod sensitivity;
pub mod stats;

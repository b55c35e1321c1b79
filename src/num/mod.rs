//! Generic numerical helpers: one bracketing root finder ([`roots`]), sample statistics
//! ([`stats`]), variance-based global sensitivity ([`sensitivity`]) and multi-start minimax
//! fitting ([`minimax`]).

pub mod minimax;
pub mod roots;
pub mod sensitivity;
pub mod stats;

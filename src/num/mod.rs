//! Generic numerical helpers: one bracketing root finder ([`roots`]), sample statistics
//! ([`stats`]) and variance-based global sensitivity ([`sensitivity`]).

pub mod roots;
pub mod sensitivity;
pub mod stats;

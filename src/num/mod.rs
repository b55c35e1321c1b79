//! Generic numerical helpers: one bracketing root finder ([`roots`]) and sample statistics
//! ([`stats`]).

pub mod roots;
pub mod stats;

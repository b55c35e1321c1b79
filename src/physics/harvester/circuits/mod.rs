//! The interface circuits a transducer's port can sit behind. Each circuit kind is one file:
//! its modes, guards, switches and linearisation written against one another.
//!
//! * [`bridge`]: a diode bridge into a storage capacitor and DC load, with the synchronous
//!   switches (parallel and series SSHI, SECE) acting at the displacement extrema.
//! * [`sece_inductor`]: a SECE whose transfer runs through its buck-boost inductor, the
//!   inductor current a state of its own.
//! * [`sshi_inductor`]: a parallel SSHI whose inversion rings through its inductor, the
//!   inductor current a state of its own.
//! * [`parts`]: the diodes' law, the DC load and the synchronous switch it is built from
//!   (with the inductor the circuits with an inductor hold).

pub mod bridge;
pub mod parts;
pub mod sece_inductor;
pub mod sshi_inductor;

pub use bridge::*;
pub use parts::Inverter;
pub use parts::{BuckBoost, DiodeLaw, Inductor, Sink, Switch};

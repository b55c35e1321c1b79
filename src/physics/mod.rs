//! The physics of the harvester: the force laws of its mechanical parts (Hertz line contact
//! [`hertz`], eqs 3-6 and 19; the end-stops and their laws [`contact`], eqs 1-2; the
//! suspension's restoring force [`suspension`]; all three live in [`crate::laws`], below the
//! device, and are re-exported here), the transducers ([`transducer`], eqs 8-10 for the
//! paper's), the harvester assembled from a device's parts ([`harvester`], eqs 7-10: a
//! [`crate::model::Model`] with its free flight split for the exponential integrator and its
//! energy ledger, and the interface circuits between a transducer and a DC load: diode
//! bridges, SSHI, SECE), the static equilibria of any device ([`statics`]), the linear response of any device
//! ([`linear`]) and the paper's linear two-port theory ([`two_port`], eqs 11-18 and 21-22), and
//! the closed forms the model is validated against ([`closed_forms`], [`interface_closed_forms`]).
//!
//! ```
//! use endstop::device::Device;
//! use endstop::drive::{Excitation, Sine};
//! use endstop::model::{Contact, Mode, Model};
//! use endstop::physics::harvester::Harvester;
//! use endstop::physics::harvester::stops::contact_of;
//! use endstop::physics::contact::Side;
//! use endstop::physics::linear::white_noise_power_w;
//! use endstop::physics::two_port::eq21_power_w;
//!
//! let text = include_str!(concat!(env!("CARGO_MANIFEST_DIR"), "/data/prototype2.toml"));
//! let device = Device::from_toml_str(text, "prototype2.toml")?;
//!
//! // Eq 7 under 0.1 g rms at 700 Hz: at rest, a quarter period in, the drive alone
//! // accelerates the mass, by +sqrt(2) 0.1 g (towards the upper stop, +x).
//! let h = Harvester::<4>::new(&device)?;
//! let rest = h.rest_state();
//! let a = Sine::from_rms_g(0.1, 700.0).accel(0.25 / 700.0);
//! let dydt = h.rhs(Mode::FREE, &rest, a);
//! assert!((dydt[1] / (2f64.sqrt() * 0.1 * endstop::G) - 1.0).abs() < 1e-9);
//!
//! // Pressed 0.1 um into the upper stop (at x = +gap), the stop pushes it back, towards -x.
//! let gap = device.stops.upper.as_ref().unwrap().gap_m;
//! let mut y = rest;
//! y[0] = gap + 1e-7;
//! let pressed = Mode::FREE.with_contact(contact_of(Side::Upper), Contact::Pressed);
//! assert!(h.rhs(pressed, &y, 0.0)[1] < 0.0);
//!
//! // The linearised model under white noise of 1e-4 g^2/Hz (two-sided) over a band far wider
//! // than the resonance gives the power of eq 21.
//! let sa = 1e-4 * endstop::G * endstop::G;
//! let p = white_noise_power_w(&device, sa, 1.0, 1e6);
//! assert!((p / eq21_power_w(&device, 1e-4) - 1.0).abs() < 1e-3);
//! # Ok::<(), Box<dyn std::error::Error>>(())
//! ```

pub mod closed_forms;
pub mod harvester;
pub mod interface_closed_forms;
pub mod linear;
pub mod statics;
pub mod transducer;
pub mod two_port;

pub use crate::laws::{contact, hertz, suspension};

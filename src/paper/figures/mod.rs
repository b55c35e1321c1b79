//! The figures and tables of the paper, one module each, every one a
//! [`Figure`](crate::paper::Figure): its setup (the devices it runs on), `run`, and `claims`.
//! The protocols that several figures share are the paper layer's other modules
//! ([`crate::paper`]); no figure imports another.
//!
//! | module | figure | claims |
//! |---|---|---|
//! | [`fig05`] | Hertz line contact, eq 19 | F5-a, F5-b |
//! | [`table3`] | coupling, Qm, eq 21 | T3-a, T3-b, F14-a (eq 21) |
//! | [`fig08`] | prototype 1, frequency up-sweeps | F8-a to F8-f |
//! | [`fig09`] | prototype 1, amplitude sweeps | F9-a, F9-b |
//! | [`fig10`] | the random excitation | F10 |
//! | [`fig11`] | prototype 1, low-level random vibration | F11 |
//! | [`fig12`] | prototype 1, high-level random vibration | F12 |
//! | [`fig13`] | prototype 2, frequency up-sweeps | F13 |
//! | [`fig14`] | prototype 2, power and efficiency against the level | F14-a, F14-b |
//! | [`fig15`] | prototype 2, output spectra | F15-a to F15-c |

pub mod fig05;
pub mod fig08;
pub mod fig09;
pub mod fig10;
pub mod fig11;
pub mod fig12;
pub mod fig13;
pub mod fig14;
pub mod fig15;
pub mod table3;

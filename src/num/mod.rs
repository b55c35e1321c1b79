//! Generic numerical helpers: one bracketing root finder ([`roots`]), sample statistics
//! ([`stats`]), one number against a reference with its verdict ([`compare`]), variance-based
//! global sensitivity ([`sensitivity`]), multi-start minimax fitting ([`minimax`]), Pareto
//! fronts ([`pareto`]), standard normal draws ([`gaussian`]), a quadratic's roots and a
//! cubic's range ([`polynomial`]), Gaussian-process emulators ([`gp`]) with their Sobol
//! indices ([`gp_sensitivity`]) and history matching in waves ([`history`]).
//!
//! ```
//! use endstop::num::roots::{illinois, RootOptions, Sample};
//! use endstop::num::stats::MeanCi;
//!
//! // The root of x^2 - 2 between 1 and 2, to 1e-12.
//! let f = |x: f64| Ok::<_, ()>((x * x - 2.0, ()));
//! let opts = RootOptions { f_tol: None, x_tol_abs: 1e-12, x_tol_rel: 0.0, max_iter: 100 };
//! let root = illinois(f, Sample::new(1.0, -1.0, ()), Sample::new(2.0, 2.0, ()), &opts).unwrap();
//! assert!((root.best.x - 2f64.sqrt()).abs() < 1e-12);
//!
//! // A mean with its 95 % interval: t(0.975, 4 dof) = 2.7764 times s / sqrt(n).
//! let m = MeanCi::of(&[1.0, 2.0, 3.0, 4.0, 5.0]);
//! assert_eq!((m.mean, m.n), (3.0, 5));
//! assert!((m.ci95 - 2.776_445 * 2.5f64.sqrt() / 5f64.sqrt()).abs() < 1e-5);
//! ```

pub mod compare;
pub mod dense;
pub mod gaussian;
pub mod gp;
pub mod gp_sensitivity;
pub mod history;
pub mod minimax;
pub mod pareto;
pub mod polynomial;
pub mod roots;
pub mod sensitivity;
pub mod stats;

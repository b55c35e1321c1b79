//! The outputs of each figure, study and `endstop` command: the Parquet rows in the project's
//! column names, the plots and the book's tables and sentences, written through
//! [`crate::Experiment`]; and the readers of measured files. Each `*_io` module serves the
//! programs its doc names; the shared ones are [`sweep_io`] (the sine-sweep figures 8, 9 and
//! 13 and `endstop sweep`), [`record_io`] (the random-vibration figures 11, 12, 14 and 15) and
//! [`branch_io`] (continued branches and diagrams, for the response experiment and
//! `endstop response`).

pub mod band_limit_io;
pub mod basins_io;
pub mod branch_io;
pub mod calibration_io;
pub mod crosscheck_io;
pub mod deviations_io;
pub mod fig05_io;
pub mod fig08_io;
pub mod fig09_io;
pub mod fig10_io;
pub mod fig11_io;
pub mod fig12_io;
pub mod fig13_io;
pub mod fig14_io;
pub mod fig15_io;
pub mod fit_csv;
pub mod fit_io;
pub mod history_io;
pub mod interfaces_io;
pub mod measured_io;
pub mod record_io;
pub mod response_io;
pub mod spectrum_io;
pub mod springs_io;
pub mod sweep_io;
pub mod table3_io;
pub mod validation_io;

//! What the integration tests share: the parameter files as devices, the claims file and the
//! calibrated prototype 1 (each costly value computed once per test binary), and the setups
//! the figures run on. The test binary (`tests/all.rs`) holds one copy, which each test file
//! reaches with `use crate::common;`.
#![allow(dead_code)]

pub mod interface_checks;
pub mod layout;
pub mod linearisation;
pub mod validation;

use std::sync::OnceLock;

use endstop::device::Device;
use endstop::paper::calibration::{calibrate_prototype1, Calibration};
use endstop::paper::claims::Claims;
use endstop::paper::setups::{Prototype1Sets, Prototypes};

/// The text of `data/<name>.toml`.
pub fn device_text(name: &str) -> String {
    let path = format!("{}/data/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path}: {e}"))
}

/// `data/<name>.toml` as a validated device.
pub fn device(name: &str) -> Device {
    Device::from_toml_str(&device_text(name), &format!("data/{name}.toml"))
        .unwrap_or_else(|e| panic!("data/{name}.toml: {e}"))
}

/// Prototype 1 as published.
pub fn prototype1() -> Device {
    device("prototype1")
}

/// Prototype 2 as published.
pub fn prototype2() -> Device {
    device("prototype2")
}

/// Both prototypes as published (the setup of Figure 5 and Table 3).
pub fn prototypes() -> Prototypes {
    Prototypes {
        prototype1: prototype1(),
        prototype2: prototype2(),
    }
}

/// The claims file compiled into the crate.
pub fn claims() -> &'static Claims {
    static CLAIMS: OnceLock<Claims> = OnceLock::new();
    CLAIMS.get_or_init(|| Claims::bundled().expect("data/claims.toml parses"))
}

/// The calibration of prototype 1, computed once per test binary.
pub fn calibration() -> &'static Calibration {
    static CAL: OnceLock<Calibration> = OnceLock::new();
    CAL.get_or_init(|| calibrate_prototype1(&prototype1()).expect("the calibration converges"))
}

/// Prototype 1 under both parameter sets (the published file and its calibration), as the
/// figures of prototype 1 take it.
pub fn prototype1_sets() -> Prototype1Sets {
    Prototype1Sets {
        published: prototype1(),
        calibrated: calibration().device.clone(),
    }
}

/// The energy ledger of `model` driven by `sine` from rest over `t_end_s` (Dormand-Prince at
/// rtol 1e-9), as the interface tests close it.
pub fn from_rest_ledger<M: endstop::model::Model<N>, const N: usize>(
    model: &M,
    sine: endstop::drive::Sine,
    t_end_s: f64,
) -> Result<endstop::model::Ledger, endstop::study::periodic::PeriodicError> {
    use endstop::model::{Books, Driven};
    let y0 = model.rest_state();
    let mut books = Books::new(model, sine);
    let mut ode =
        endstop::ode::Dopri5::new(0.0, y0, model.mode_of(&y0), model.solver_options(1e-9));
    ode.integrate_observed(&Driven::new(model, sine), t_end_s, &mut books)?;
    Ok(books.ledger())
}

/// The up-converter, `data/examples/upconverter.toml`.
pub fn upconverter() -> Device {
    Device::from_toml_str(
        include_str!("../../data/examples/upconverter.toml"),
        "upconverter.toml",
    )
    .expect("the file loads")
}

/// The step of the up-converter's resumption past a branch's end: the stepped sweep's default
/// step for it over `endstop response --from 10 --to 40` (a quarter of the driver's
/// half-power width, rounded down).
pub const UPCONVERTER_RESUME_STEP_HZ: f64 = 0.1;

/// The up-converter's (`data/examples/upconverter.toml`) response at 0.05 g from `from_hz` to
/// `to_hz`, as `endstop response` computes it: continuation steps of at most 0.3 Hz, the
/// resumption past a branch's end in [`UPCONVERTER_RESUME_STEP_HZ`] after transients of 200
/// periods (as the diagram's first orbit from rest).
pub fn upconverter_response(from_hz: f64, to_hz: f64) -> endstop::study::continuation::Response {
    use endstop::study::continuation::{
        response_from_rest, ContinuationSettings, ResumeSettings, STEPPED_MEASURE_PERIODS,
    };
    let device = upconverter();
    let start = endstop::study::orbit::Forcing {
        freq_hz: from_hz,
        accel_rms_g: 0.05,
    };
    let settings = ContinuationSettings::frequency(from_hz, to_hz, 0.3);
    let resume = ResumeSettings {
        step: UPCONVERTER_RESUME_STEP_HZ,
        transient_periods: 200,
        measure_periods: STEPPED_MEASURE_PERIODS,
    };
    response_from_rest(
        &device,
        start,
        &settings,
        &resume,
        &endstop::progress::Silent,
    )
    .expect("the response reaches the end of the range")
}

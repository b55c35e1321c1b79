//! What the validation tests share: the validation devices and the assertion of a set of
//! checks.

use std::collections::HashMap;

use std::f64::consts::{SQRT_2, TAU};

use endstop::device::Device;
use endstop::model::Model;
use endstop::num::compare::{Comparison, Measure};
use endstop::ode::Stats;
use endstop::physics::harvester::masses::MassChain;
use endstop::progress::Silent;
use endstop::study::continuation::{
    continue_branch_until, first_orbit, Branch, ContinuationSettings, Event,
};
use endstop::study::orbit::{Forcing, Orbit, OrbitError, Parameter, Shooter, ShootingOptions};
use endstop::validation::Check;

/// A two-mass device under a peer tool's harmonic force on one mass: the force `F cos(w t)` on
/// mass `k` is the inertial force of a base acceleration of peak `F / m_k` on that mass alone
/// (the device file sets `drive_mass`).
pub struct ForcedChain {
    pub model: MassChain<6>,
    pub accel_rms_g: f64,
}

impl ForcedChain {
    /// The device under a force of peak `force_n` on mass `mass`.
    pub fn new(device: &Device, mass: usize, force_n: f64) -> Self {
        let model = MassChain::<6>::new(device).unwrap();
        let m = device.masses.as_ref().unwrap().bodies[mass].mass_kg;
        Self {
            model,
            accel_rms_g: force_n / m / SQRT_2 / endstop::G,
        }
    }

    pub fn shooter(&self) -> Shooter<'_, MassChain<6>, 6> {
        Shooter::new(&self.model, ShootingOptions::default())
    }

    pub fn forcing(&self, omega_rad_s: f64) -> Forcing {
        Forcing {
            freq_hz: omega_rad_s / TAU,
            accel_rms_g: self.accel_rms_g,
        }
    }

    /// The orbit reached from rest after a transient of 200 periods at `omega_rad_s`.
    pub fn settled(&self, omega_rad_s: f64) -> Orbit {
        let mut stats = Stats::default();
        first_orbit(
            &self.shooter(),
            &self.forcing(omega_rad_s),
            Parameter::Frequency,
            self.model.rest_state(),
            200,
            &mut stats,
        )
        .unwrap()
    }

    /// The branch through `first` from `from` to `to` (rad/s), in steps of at most `max_step`
    /// with events located to `locate_tol` (rad/s).
    pub fn branch(
        &self,
        first: Orbit,
        range: [f64; 2],
        max_step: f64,
        locate_tol: f64,
    ) -> Result<Branch, OrbitError> {
        self.branch_until(first, range, max_step, locate_tol, |_| false)
    }

    /// [`Self::branch`], ending at the point after the first event for which `until` is true.
    pub fn branch_until(
        &self,
        first: Orbit,
        [from, to]: [f64; 2],
        max_step: f64,
        locate_tol: f64,
        until: impl FnMut(&Event) -> bool,
    ) -> Result<Branch, OrbitError> {
        let mut settings = ContinuationSettings::frequency(from / TAU, to / TAU, max_step / TAU);
        settings.locate_tol = locate_tol / TAU;
        continue_branch_until(&self.model, first, &settings, &Silent, until)
    }
}

/// The repository's root.
pub fn root() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).to_path_buf()
}

/// The rows of the reference file `data/references/<folder>/<file>` (comma-separated, a
/// header line of column names), each by column name.
pub fn reference_rows(folder: &str, file: &str) -> Vec<HashMap<String, String>> {
    let path = root().join("data/references").join(folder).join(file);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{path:?}: {e}"));
    let mut lines = text.lines();
    let header: Vec<String> = lines
        .next()
        .unwrap_or_default()
        .split(',')
        .map(str::to_string)
        .collect();
    lines
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            header
                .iter()
                .cloned()
                .zip(l.split(',').map(str::to_string))
                .collect()
        })
        .collect()
}

/// The number in column `key` of a reference row.
pub fn reference_num(r: &HashMap<String, String>, key: &str) -> f64 {
    r.get(key)
        .and_then(|v| v.parse().ok())
        .unwrap_or_else(|| panic!("column {key} missing or not a number in {r:?}"))
}

/// A judged check of `group` against `source` by absolute difference.
pub fn absolute_check(
    [group, source]: [&str; 2],
    quantity: String,
    theirs: f64,
    ours: f64,
    tolerance: f64,
    reason: &str,
) -> Check {
    Check {
        group: group.into(),
        source: source.into(),
        quantity,
        compared: Comparison {
            ours,
            reference: theirs,
            measure: Measure::Absolute,
            tolerance,
        },
        reason: reason.into(),
        open: None,
    }
}

/// The validation device `data/validation/<name>.toml`.
pub fn device(name: &str) -> Device {
    let rel = format!("data/validation/{name}.toml");
    let text = std::fs::read_to_string(root().join(&rel)).unwrap();
    Device::from_toml_str(&text, &rel).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

/// Prints every check and asserts each one that is judged (an open question is printed, not
/// judged).
pub fn assert_all(checks: &[Check]) {
    assert!(!checks.is_empty(), "no checks");
    for c in checks {
        eprintln!(
            "{} | {} | {} | theirs {:e} | ours {:e} | difference {:e} (tolerance {:e}){}",
            c.group,
            c.source,
            c.quantity,
            c.compared.reference,
            c.compared.ours,
            c.difference(),
            c.compared.tolerance,
            if c.is_open() { " [open question]" } else { "" }
        );
    }
    for c in checks.iter().filter(|c| !c.is_open()) {
        assert!(
            c.passes(),
            "{}: {} against {}: difference {:e} above {:e} ({})",
            c.group,
            c.quantity,
            c.source,
            c.difference(),
            c.compared.tolerance,
            c.reason
        );
    }
}

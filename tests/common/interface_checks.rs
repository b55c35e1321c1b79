//! What the tests of the interface circuits share: the check of the analytic Jacobian against
//! differences of the vector field (with a state for the circuits with an inductor), the
//! energy ledger closing from rest and the checks of the device's description.

use std::f64::consts::PI;

use endstop::device::Device;
use endstop::drive::Sine;
use endstop::model::{Ledger, Mode, Model};
use endstop::study::periodic::PeriodicError;
use nalgebra::SVector;

/// A state of a circuit with an inductor (x, v, Vp, Vs and the inductor current) at which to
/// compare Jacobians: the displacement `x_m`, a velocity of -0.03 m/s and each electrical
/// component a different fraction of its scale.
pub fn jacobian_state<M: Model<N>, const N: usize>(m: &M, x_m: f64) -> SVector<f64, N> {
    assert_eq!(N, 5, "x, v, Vp, Vs and the inductor current");
    let sc = m.scales();
    let mut y = SVector::<f64, N>::zeros();
    y[0] = x_m;
    y[1] = -0.03;
    y[2] = 0.17 * sc[2];
    y[3] = 0.11 * sc[3];
    y[4] = 0.23 * sc[4];
    y
}

/// Asserts that the analytic Jacobian of `m` in `mode` at `y` equals central differences of
/// the vector field at the drive's acceleration `a` (steps of 1e-6 of the scales), each entry
/// within 1e-6 of its scale: the larger of the two values' sum and the row's scale times the
/// examples' suspension's 754 rad/s over the column's. `label` names the mode in a failure.
/// Returns the number of entries compared.
pub fn assert_jacobian_matches_differences<M: Model<N>, const N: usize>(
    m: &M,
    mode: Mode,
    y: &SVector<f64, N>,
    a: f64,
    label: &str,
) -> usize {
    let sc = m.scales();
    let j = m.jacobian(mode, y);
    let mut checked = 0;
    for c in 0..N {
        let h = 1e-6 * sc[c];
        let (mut yp, mut ym) = (*y, *y);
        yp[c] += h;
        ym[c] -= h;
        let fd = (m.rhs(mode, &yp, a) - m.rhs(mode, &ym, a)) / (2.0 * h);
        for r in 0..N {
            // A rate's scale: the row's scale times the suspension's 754 rad/s over the
            // column's.
            let scale = (fd[r].abs() + j[(r, c)].abs()).max(754.0 * sc[r] / sc[c]);
            assert!(
                (fd[r] - j[(r, c)]).abs() <= 1e-6 * scale,
                "{label} ({r},{c}): {} vs {}",
                j[(r, c)],
                fd[r]
            );
            checked += 1;
        }
    }
    checked
}

/// Over 20 periods from rest at 1 g at the suspension's frequency (the stop is struck), the
/// ledger of `d` shows contact and something in each of `element`, `diodes` and `dc_load`,
/// and closes to 1e-6 of the drive's work, as for every other interface (rtol 1e-9 over 20
/// periods with events).
pub fn assert_ledger_closes_from_rest(d: &Device) {
    let f = d.suspension_omega_rad_s() / (2.0 * PI);
    let sine = Sine::from_rms_g(1.0, f);
    let l: Result<Ledger, PeriodicError> =
        endstop::with_harvester!(d, |h| super::from_rest_ledger(&h, sine, 20.0 / f));
    let l = l.unwrap();
    eprintln!("{l:?} relative residual {:e}", l.relative_residual());
    assert!(l.stop_absorbed() + l.impact_losses() > 0.0, "no contact");
    for term in ["element", "diodes", "dc_load"] {
        assert!(l.get(term) > 0.0, "nothing in {term}: {l:?}");
    }
    assert!(l.relative_residual().abs() < 1e-6, "{l:?}");
}

/// The description of `data/<stem>.toml` (the device `d`): it round-trips through TOML and
/// needs `dimension` components; each edit `(from, to, field)` of the file's text (`from`
/// replaced by `to`) is an error naming `field`.
pub fn assert_description_checked(
    d: &Device,
    stem: &str,
    dimension: usize,
    edits: &[(&str, &str, &str)],
) {
    let back = Device::from_toml_str(&d.to_toml_string(), "b.toml").unwrap();
    assert_eq!(*d, back);
    assert_eq!(endstop::physics::harvester::dimension(d), Ok(dimension));
    let text = super::device_text(stem);
    for &(from, to, field) in edits {
        let e = Device::from_toml_str(&text.replace(from, to), "bad.toml").unwrap_err();
        eprintln!("{e}");
        assert_eq!(e.field(), Some(field), "{e}");
    }
}

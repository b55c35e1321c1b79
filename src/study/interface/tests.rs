use super::*;
use crate::physics::interface::closed_forms::Element;

fn device() -> Device {
    let text = include_str!("../../../data/validation/piezo_bridge.toml");
    Device::from_toml_str(text, "piezo_bridge.toml").unwrap()
}

#[test]
fn explore_standard_bridge() {
    let d = device();
    let f = d.suspension_omega_rad_s() / (2.0 * std::f64::consts::PI);
    let sine = Sine::from_rms_g(0.1, f);
    let t = std::time::Instant::now();
    let s = steady_state(&d, sine, &State::zeros(), &SteadySettings::default()).unwrap();
    let e = Element {
        theta: 2.67e-4,
        cp: 50e-9,
        w: 2.0 * std::f64::consts::PI * f,
        vf: 0.0,
    };
    let v = e.standard_vdc(s.x1_m, 41.7e3);
    eprintln!("{:?} {:?}", s, t.elapsed());
    eprintln!(
        "closed V {v} P {} ours V {} P {}",
        v * v / 41.7e3,
        s.vdc_v,
        s.p_dc_w
    );
    eprintln!("ledger rel {}", s.ledger.relative_residual());
}

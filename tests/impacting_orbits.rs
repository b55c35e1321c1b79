//! The bifurcation diagram of devices with rigid stops (`study::continuation::impacting`):
//! the grazing bifurcations of the example device with symmetric rigid stops, its
//! symmetry-breaking pitchfork and the absence of any period doubling; every multiplier set
//! against finite differences of the period map; and an impact oscillator whose genuine
//! period doubling and period-two branch are checked against a long integration.

use endstop::device::Device;
use endstop::drive::Sine;
use endstop::model::{Driven, Mode, Model, SwitchKind};
use endstop::num::roots::{illinois, RootOptions, Sample};
use endstop::ode::{Dopri5, Observer, Step};
use endstop::physics::harvester::Harvester;
use endstop::physics::linear::LinearResponse;
use endstop::physics::transducer::State;
use endstop::progress::Silent;
use endstop::study::continuation::impacting::{rigid_diagram, Closure, DiagramSettings};
use endstop::study::continuation::{
    frequency_diagram, BranchKind, ContinuationSettings, Diagram, DiagramEventKind, DiagramPoint,
    EndKind,
};
use endstop::study::orbit::{multipliers, Forcing, Shooter, ShootingOptions};
use nalgebra::{Complex, Matrix4};

fn example(name: &str) -> Device {
    let path = format!("{}/data/examples/{name}.toml", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&path).unwrap();
    Device::from_toml_str(&text, &path).unwrap()
}

/// The coefficients of prod (lambda - mu_i) after the leading one: a set of multipliers
/// compared by them is compared without pairing its members, and without the
/// ill-conditioning of eigenvalues near a double one.
fn char_poly(mu: &[Complex<f64>]) -> Vec<f64> {
    let mut c = vec![Complex::new(1.0, 0.0)];
    for &m in mu {
        let mut next = vec![Complex::new(0.0, 0.0); c.len() + 1];
        for (k, &ck) in c.iter().enumerate() {
            next[k] += ck;
            next[k + 1] -= ck * m;
        }
        c = next;
    }
    c[1..].iter().map(|x| x.re).collect()
}

/// The largest difference of the characteristic coefficients of two multiplier sets, the
/// k-th relative to max(1, rho)^k with rho the largest modulus.
fn multiplier_distance(a: &[Complex<f64>], b: &[Complex<f64>]) -> f64 {
    let rho = a.iter().map(|m| m.norm()).fold(1.0, f64::max);
    char_poly(a)
        .iter()
        .zip(char_poly(b))
        .enumerate()
        .map(|(k, (x, y))| (x - y).abs() / rho.powi(k as i32 + 1))
        .fold(0.0, f64::max)
}

/// The multipliers of a point's whole orbit by central differences of the event-located
/// period map (of the device with its stops) at its section, with steps of `eps` in each
/// scaled coordinate (the map of an orbit of m periods is the product of m period maps).
fn fd_multipliers(
    shooter: &Shooter<'_, Harvester<4>, 4>,
    p: &DiagramPoint,
    eps: f64,
) -> Vec<Complex<f64>> {
    let (mut phase, y) = p.section.clone().expect("a section");
    let mut y = State::from_column_slice(y.as_slice());
    let mut m = Matrix4::identity();
    for _ in 0..p.periods {
        m = shooter.monodromy_fd(&p.forcing, phase, y, eps).unwrap() * m;
        y = shooter.period_map(&p.forcing, phase, y).unwrap();
        phase = phase.rem_euclid(2.0 * std::f64::consts::PI);
    }
    multipliers(&m).unwrap()
}

/// The frequencies at which the linear response of a device (its model linearised about
/// rest, without stops) reaches the gap `gap_m` under `accel_rms_g`, searched over `lo..hi`
/// on a 0.1 Hz grid and refined to 1e-9 Hz.
fn linear_grazings(device: &Device, accel_rms_g: f64, gap_m: f64, lo: f64, hi: f64) -> Vec<f64> {
    let lin = LinearResponse::of(device);
    let amp = std::f64::consts::SQRT_2 * accel_rms_g * endstop::G;
    let g = |f: f64| lin.displacement_per_accel(f) * amp - gap_m;
    let opts = RootOptions {
        f_tol: None,
        x_tol_abs: 1e-9,
        x_tol_rel: 0.0,
        max_iter: 200,
    };
    let n = ((hi - lo) / 0.1) as usize;
    let mut out = Vec::new();
    for i in 0..n {
        let (a, b) = (lo + 0.1 * i as f64, lo + 0.1 * (i + 1) as f64);
        if (g(a) > 0.0) != (g(b) > 0.0) {
            let r = illinois(
                |f| -> Result<(f64, ()), ()> { Ok((g(f), ())) },
                Sample::new(a, g(a), ()),
                Sample::new(b, g(b), ()),
                &opts,
            )
            .unwrap();
            out.push(0.5 * (r.positive.x + r.non_positive.x));
        }
    }
    out
}

/// Every multiplier set of a diagram's points away from grazing (every impact faster than a
/// tenth of w0 times the smallest gap, every free flight at least a hundredth of the gap from
/// a stop, and the multipliers below 30 in modulus, where the period map is smooth over the
/// differences' steps) equals central differences of the
/// event-located period map, to 1e-5 in the characteristic coefficients (steps of 1e-5 and
/// rtol 1e-12: the truncation, eps^2 times the map's curvature, and the noise of the
/// adaptive steps and located events, about rtol / eps, both below 1e-6 there; steps of
/// 1e-6 show that noise at 1e-5 on some orbits). Returns the points checked and the largest
/// difference.
fn check_multipliers(device: &Device, d: &Diagram, every: usize) -> (usize, f64) {
    let h = Harvester::<4>::new(device).unwrap();
    let cfg = ShootingOptions {
        rtol: 1e-12,
        ..ShootingOptions::default()
    };
    let shooter = Shooter::new(&h, cfg);
    let w0 = (h.km / h.mass_kg).sqrt();
    let slow = 0.1 * w0 * h.x_scale_m;
    let (mut n, mut worst) = (0, 0.0f64);
    for b in &d.branches {
        for p in b.points.iter().step_by(every) {
            let away = p.impact_speeds_m_s.iter().all(|&s| s > slow)
                && p.clearance_m > 0.01 * h.x_scale_m
                && p.max_multiplier_abs() < 30.0
                && p.section.is_some();
            if !away {
                continue;
            }
            let fd = fd_multipliers(&shooter, p, 1e-5);
            let diff = multiplier_distance(&p.multipliers, &fd);
            assert!(
                diff < 1e-5,
                "{} at {} Hz: multipliers {:?}, finite differences {:?} ({diff:e})",
                b.label,
                p.forcing.freq_hz,
                p.multipliers,
                fd
            );
            n += 1;
            worst = worst.max(diff);
        }
    }
    (n, worst)
}

/// The example device with symmetric rigid stops at 0.3 g rms: the non-impacting orbit
/// grazes both stops at once below and above resonance, where the linear response (computed
/// here independently of the diagram) reaches the gap; the symmetric two-impact branch runs
/// from the low grazing through a symmetry-breaking pitchfork (a multiplier of its half-period
/// map at -1) and the upper fold back down to the high grazing, ending there with its impact
/// speed at zero; the one-impact branches born at the low grazing end where their flight
/// reaches the other stop; and no period-one branch has a period doubling.
#[test]
fn symmetric_rigid_stops_grazing_pitchfork_and_no_period_doubling() {
    let device = example("rigid_restitution");
    let (g, gap) = (0.3, 8e-6);
    let d = frequency_diagram(&device, g, 550.0, 750.0, 2.0, &Silent).unwrap();
    let linear = linear_grazings(&device, g, gap, 580.0, 660.0);
    assert_eq!(linear.len(), 2, "{linear:?}");
    // The locations are the continuation's to 1e-4 Hz at most (its event tolerance); the
    // electrostatic force's nonlinearity moves the grazing by far less.
    for (e, f) in d.events_of(DiagramEventKind::Grazing).zip(&linear) {
        eprintln!("grazing {} Hz, linear response {f} Hz", e.param);
        assert!(
            (e.param - f).abs() < 1e-3,
            "grazing {} vs linear {f}",
            e.param
        );
    }
    assert_eq!(d.events_of(DiagramEventKind::Grazing).count(), 2);
    assert_eq!(d.events_of(DiagramEventKind::PeriodDoubling).count(), 0);
    let sym = d
        .branch("symmetric, 2 impacts a period")
        .expect("the symmetric branch");
    // Its ends: the two grazings of the non-impacting orbit, each with its impact speed at
    // zero to the locator's tolerance.
    for (end, f) in [(&sym.start, linear[0]), (&sym.end, linear[1])] {
        assert_eq!(end.kind, EndKind::Grazing);
        assert!((end.param - f).abs() < 1e-3, "{} vs {f}", end.param);
        assert!(
            end.residual.abs() < 1e-9,
            "impact speed {} m/s",
            end.residual
        );
    }
    // The high end is reached with the speed falling linearly to zero and no fold on the
    // way: the frequencies of its last points decrease monotonically.
    let tail: Vec<f64> = sym.points[sym.points.len() - 10..]
        .iter()
        .map(|p| p.forcing.freq_hz)
        .collect();
    assert!(tail.windows(2).all(|w| w[1] < w[0]), "{tail:?}");
    let pitchforks: Vec<_> = d.events_of(DiagramEventKind::SymmetryBreaking).collect();
    assert_eq!(pitchforks.len(), 1);
    let pf = pitchforks[0];
    let half = pf
        .point
        .half_multipliers
        .clone()
        .expect("a symmetric orbit");
    let to_minus_one = half
        .iter()
        .map(|m| (m + 1.0).norm())
        .fold(f64::INFINITY, f64::min);
    assert!(to_minus_one < 1e-3, "half-period multipliers {half:?}");
    assert_eq!(pf.stable, [false, true], "unstable below, stable above");
    let folds: Vec<_> = d.events_of(DiagramEventKind::Fold).collect();
    assert_eq!(folds.len(), 1);
    assert!(folds[0].param > 740.0);
    // Both one-impact branches start at the low grazing and end where their flight reaches
    // the other stop, just above the pitchfork; every orbit on them is unstable.
    for side in ["upper", "lower"] {
        let b = d
            .branch(&format!("1 impact a period ({side})"))
            .expect("a one-impact branch");
        assert_eq!(b.start.kind, EndKind::Grazing);
        assert!((b.start.param - linear[0]).abs() < 1e-3);
        assert_eq!(b.end.kind, EndKind::NewContact);
        assert!(b.end.param > pf.param && b.end.param - pf.param < 0.01);
        assert!(b.points.iter().all(|p| !p.is_stable()));
    }
    // The asymmetric pair joins those ends to the pitchfork.
    let asym: Vec<_> = d
        .branches
        .iter()
        .filter(|b| b.label.starts_with("asymmetric"))
        .collect();
    assert_eq!(asym.len(), 2);
    for b in asym {
        assert_eq!(b.end.kind, EndKind::Symmetric);
        assert!((b.end.param - pf.param).abs() < 1e-4);
    }
    let (checked, worst) = check_multipliers(&device, &d, 4);
    eprintln!("{checked} multiplier sets checked, largest difference {worst:e}");
    assert!(
        checked >= 40,
        "{checked} points checked (largest difference {worst:e})"
    );
}

/// A one-stop impact oscillator (1 g, 32 Hz, Q = 50, a rigid stop 1 mm above rest, e = 0.8)
/// driven at 10 g: its one-impact branch has genuine period doublings, and the period-two
/// branch born at the upper one is stable. At a frequency between them the period-one orbit
/// is unstable, and a long integration started next to it settles on a period-two orbit
/// with the branch's impacts, and the branch's multipliers equal finite differences of the
/// two-period map.
#[test]
fn impact_oscillator_period_doubling_and_its_period_two_branch() {
    let device = Device::from_toml_str(
        "name = \"bouncer\"\nparams = \"test\"\ndescription = \"one rigid stop\"\n\
         [mechanics]\nmass_kg = 1e-3\nstiffness_n_per_m = 40.0\ndamping_n_s_per_m = 4e-3\n\
         [stops.upper]\ngap_m = 1e-3\nlaw = \"restitution\"\ncoefficient = 0.8\n\
         [transducer]\nkind = \"none\"\n",
        "bouncer.toml",
    )
    .unwrap();
    let g = 10.0;
    let start = Forcing {
        freq_hz: 30.0,
        accel_rms_g: g,
    };
    let settings = ContinuationSettings::frequency(30.0, 40.0, 1.0);
    let options = DiagramSettings {
        period_two: true,
        ..DiagramSettings::default()
    };
    let d = rigid_diagram(&device, start, &settings, &options, &Silent).unwrap();
    let one = d.branch("1 impact a period (upper)").expect("period one");
    let pds: Vec<_> = d
        .events_of(DiagramEventKind::PeriodDoubling)
        .filter(|e| d.branches[e.branches[0]].label == one.label)
        .collect();
    assert_eq!(
        pds.len(),
        2,
        "{:?}",
        pds.iter().map(|e| e.param).collect::<Vec<_>>()
    );
    let upper_pd = pds[1];
    eprintln!(
        "period doublings at {} and {} Hz",
        pds[0].param, upper_pd.param
    );
    let mu = &upper_pd.point.multipliers;
    let to_minus_one = mu
        .iter()
        .map(|m| (m + 1.0).norm())
        .fold(f64::INFINITY, f64::min);
    assert!(to_minus_one < 1e-3, "{mu:?}");
    // The period-two branch born there, with its own (stable) multipliers.
    let two = d
        .branches
        .iter()
        .find(|b| {
            matches!(&b.kind, BranchKind::Impacting(q) if q.closure == Closure::Periodic(2))
                && (b.points[0].forcing.freq_hz - upper_pd.param).abs() < 1e-6
        })
        .expect("the period-two branch of the upper period doubling");
    assert_eq!(two.start.kind, EndKind::Bifurcation);
    let p = &two.points[two.points.len() / 2];
    assert!(p.is_stable() && p.periods == 2, "{:?}", p.multipliers);
    let f = p.forcing.freq_hz;
    assert!(f < upper_pd.param && f > pds[0].param);
    // The period-one orbit there is unstable.
    let nearest = one
        .points
        .iter()
        .min_by(|a, b| {
            (a.forcing.freq_hz - f)
                .abs()
                .total_cmp(&(b.forcing.freq_hz - f).abs())
        })
        .unwrap();
    assert!(!nearest.is_stable());

    let h = Harvester::<4>::new(&device).unwrap();
    let cfg = ShootingOptions {
        rtol: 1e-12,
        ..ShootingOptions::default()
    };
    let shooter = Shooter::new(&h, cfg);
    // Finite differences of the two-period map at the branch's orbit.
    let fd = fd_multipliers(&shooter, p, 1e-5);
    let diff = multiplier_distance(&p.multipliers, &fd);
    assert!(diff < 1e-5, "{:?} vs {fd:?} ({diff:e})", p.multipliers);

    // Brute force: 600 periods (about 30 ring-up times 2m/b) from the unstable period-one
    // orbit, nudged, at the same frequency; then two periods recorded.
    let (phase, y) = nearest.section.clone().unwrap();
    let model = Driven::new(
        &h,
        Sine {
            phase_rad: phase,
            ..Sine::from_rms_g(g, f)
        },
    );
    let mut y0 = State::from_column_slice(y.as_slice());
    y0[0] += 1e-3 * h.x_scale_m;
    let mut ode = Dopri5::new(0.0, y0, h.mode_of(&y0), h.solver_options(1e-11));
    let period = 1.0 / f;
    // Sampled at the drive phase of the branch orbit's section.
    let (phase2, y2) = p.section.clone().unwrap();
    let y2 = State::from_column_slice(y2.as_slice());
    let w = 2.0 * std::f64::consts::PI * f;
    let t0 = 600.0 * period + (phase2 - phase).rem_euclid(2.0 * std::f64::consts::PI) / w;
    let strobe: Vec<State> = (0..4)
        .map(|k| {
            ode.integrate(&model, t0 + k as f64 * period, |_, _| {})
                .unwrap();
            ode.y()
        })
        .collect();
    let sc = h.scales();
    let dist = |a: &State, b: &State| (a - b).component_div(&sc).norm();
    assert!(dist(&strobe[0], &strobe[2]) < 1e-6, "period two");
    assert!(dist(&strobe[1], &strobe[3]) < 1e-6, "period two");
    assert!(dist(&strobe[0], &strobe[1]) > 1e-2, "not period one");
    // One of the two settled states is the branch orbit's at its section.
    let to_branch = dist(&strobe[0], &y2).min(dist(&strobe[1], &y2));
    assert!(to_branch < 1e-6, "{to_branch:e}");
    // The impacts of the settled orbit over two periods, against the branch's.
    struct Impacts {
        last: State,
        speeds: Vec<f64>,
    }
    impl Observer<State, Mode> for Impacts {
        fn step(&mut self, st: &Step<State>, _: Mode) {
            self.last = st.y1;
        }
        fn switched(&mut self, _t: f64, from: Mode, to: Mode) {
            assert_eq!(SwitchKind::between(from, to), SwitchKind::Rebound);
            self.speeds.push(self.last[1].abs());
        }
    }
    let mut obs = Impacts {
        last: ode.y(),
        speeds: Vec::new(),
    };
    ode.integrate_observed(&model, t0 + 5.0 * period, &mut obs)
        .unwrap();
    let mut brute = obs.speeds;
    let mut ours = p.impact_speeds_m_s.clone();
    brute.sort_by(f64::total_cmp);
    ours.sort_by(f64::total_cmp);
    assert_eq!(brute.len(), ours.len(), "{brute:?} vs {ours:?}");
    for (a, b) in brute.iter().zip(&ours) {
        assert!(
            (a - b).abs() < 1e-6 * b,
            "impact speeds {brute:?} vs {ours:?}"
        );
    }

    let (checked, worst) = check_multipliers(&device, &d, 3);
    eprintln!("{checked} multiplier sets checked, largest difference {worst:e}");
    assert!(
        checked >= 10,
        "{checked} points checked (largest difference {worst:e})"
    );
}

//! The exact propagation of several masses between their events (the affine modes of
//! `physics::harvester::masses::MassChain`): the up-converter under a sine and under noise
//! follows Dormand-Prince to Dormand-Prince's own error, and two undamped masses that strike
//! each other with restitution 1 keep their energy, and each impact their momentum, over
//! thousands of impacts on the exact steps; a resting pair's mode is affine in the state and
//! the drive, its release a guard on both.

use endstop::device::Device;
use endstop::drive::Sine;
use endstop::model::{Contact, DrivenAffine, Mode, Model};
use endstop::physics::harvester::masses::MassChain;
use endstop::study::flow::{SineFlow, SineScheme};
use endstop::study::record::{simulate_record, FreeFlightPath, Record, Scheme};
use nalgebra::SVector;

use crate::masses::{two_masses, NO_TRANSDUCER};

const UPCONVERTER: &str = include_str!("../data/examples/upconverter.toml");

fn upconverter() -> Device {
    Device::from_toml_str(UPCONVERTER, "upconverter.toml").unwrap()
}

/// The up-converter under a sine at its driver's resonance, from rest until just before its
/// masses first come to rest together (after a chattering sequence; how many rebounds precede
/// that rest depends on the stick criterion met within rounding, so it is no measure of the
/// propagation), by the exact steps and by Dormand-Prince throughout. Each scheme runs at
/// rtol 1e-11 and Dormand-Prince also at 1e-9: Dormand-Prince's own error at 1e-9 is the
/// distance between its two runs (its error at 1e-11 is far smaller), and the exact steps,
/// exact between events with the events located to 1e-14 s, must lie at most that distance
/// (doubled for the estimate's own spread, plus 1e-12 of the scales for rounding) from the
/// finer reference. The impacts are the same events in all three.
#[test]
fn two_masses_under_a_sine_follow_dormand_prince_to_its_error() {
    let d = upconverter();
    let h = MassChain::<6>::new(&d).unwrap();
    assert!(h.affine(Mode::FREE).is_some(), "the free flight is affine");
    let sine = Sine::from_rms_g(0.5, 20.0);
    let flow = |scheme, rtol| {
        let opts = h.solver_options(rtol);
        SineFlow::with(&h, sine, 0.0, h.rest_state(), Mode::FREE, opts, scheme)
    };
    let mut first_rest = 0.25f64;
    flow(SineScheme::Dopri5, 1e-11)
        .integrate(0.25, |st, mode| {
            if mode.contact(0) == Contact::Resting {
                first_rest = first_rest.min(st.t0);
            }
        })
        .unwrap();
    let t_end = 0.99 * first_rest;
    let run = |scheme, rtol| {
        let mut f = flow(scheme, rtol);
        let exact = f.is_exact();
        f.integrate(t_end, |_, _| {}).unwrap();
        (f.y(), f.stats().events, exact)
    };
    let (ye, ne, exact) = run(SineScheme::Exact, 1e-11);
    let (yc, nc, _) = run(SineScheme::Dopri5, 1e-9);
    let (yd, nd, _) = run(SineScheme::Dopri5, 1e-11);
    assert!(exact, "the up-converter's modes are propagated exactly");
    assert!(nd >= 5, "{nd} impacts before {t_end} s");
    assert_eq!(ne, nd, "events");
    assert_eq!(nc, nd, "events of the coarser reference");
    let sc = h.scales();
    let own = (yc - yd).component_div(&sc).amax();
    let diff = (ye - yd).component_div(&sc).amax();
    println!(
        "{nd} impacts to {t_end:.4} s: exact vs Dormand-Prince {diff:.2e}, its own error {own:.2e}"
    );
    assert!(
        diff <= 2.0 * own + 1e-12,
        "final states differ by {diff:e}, Dormand-Prince's own error {own:e}"
    );
}

/// A 0.5 s record of the up-converter (0.05 s pre-roll) at 1e-3 g^2/Hz.
fn record(rtol: f64, scheme: Scheme) -> Record {
    let d = upconverter();
    let mut spec = endstop::paper::setups::paper_record(&d, 1e-3);
    spec.transient_s = 0.05;
    spec.noise.duration_s = 0.5;
    spec.rtol = rtol;
    spec.scheme = scheme;
    simulate_record(&d, &spec, 2012, 0).unwrap()
}

/// The largest difference between two records' outputs at the same samples, each output
/// divided by its largest magnitude in `b`.
fn output_distance(a: &Record, b: &Record) -> f64 {
    let series = |r: &Record| -> Vec<Vec<f64>> {
        let mut s = vec![r.v1_v.clone(), r.v2_v.clone()];
        s.extend(r.more_v.iter().cloned());
        s.into_iter().filter(|v| !v.is_empty()).collect()
    };
    let (sa, sb) = (series(a), series(b));
    assert_eq!(sa.len(), sb.len());
    sa.iter()
        .zip(&sb)
        .map(|(x, y)| {
            let scale = y.iter().fold(0.0f64, |m, v| m.max(v.abs()));
            x.iter()
                .zip(y)
                .fold(0.0f64, |m, (p, q)| m.max((p - q).abs() / scale))
        })
        .fold(0.0, f64::max)
}

/// The up-converter's noise record by its exact affine steps against Dormand-Prince
/// throughout at rtol 1e-11: the same impacts, most of them rebounds located on the exact
/// solution inside the sample intervals (fewer of the exact record's switches are events of
/// Dormand-Prince than half its impacts), and outputs (the generator's voltage, each
/// mass's position, each divided by its largest magnitude) within Dormand-Prince's truncation
/// error. A record's Dormand-Prince steps are bounded by the 10 us sample interval `h`, far
/// inside its tolerance in free flight, so its error there is that of a fifth-order step:
/// at most about `(h w)^6` of the motion per step, `w` the spectral radius of the free flight's
/// matrix, summed over the record's `n` intervals without cancellation, `n (h w)^6`. The exact
/// steps carry Dormand-Prince's error only on the intervals where a stop may be met.
#[test]
fn a_two_mass_record_on_exact_steps_follows_dormand_prince() {
    let exact = record(1e-11, Scheme::Exponential);
    let fine = record(1e-11, Scheme::Dopri5);
    assert_eq!(exact.summary.free_flight, FreeFlightPath::Affine);
    // 0.55 s at 100 kHz: 55 000 intervals, most of them far from the stop.
    let n = 55_000.0;
    assert!(
        exact.summary.exponential_steps as f64 > n / 2.0,
        "most intervals by the exact steps: {}",
        exact.summary.exponential_steps
    );
    let impacts = fine.summary.impacts;
    assert!(impacts >= 20, "{impacts} impacts");
    println!(
        "impacts: exact {}, Dormand-Prince {impacts}",
        exact.summary.impacts
    );
    assert_eq!(exact.summary.impacts, impacts, "impacts");
    let on_dopri = exact.summary.stats.events;
    assert!(
        2 * on_dopri < impacts,
        "{on_dopri} of {impacts} impacts are Dormand-Prince's events"
    );
    // An interval goes to Dormand-Prince only where the walk across its switches fails (more
    // than 16 impacts in it, a switch due at a sample instant), so such intervals are fewer
    // than the impacts; the resting phases, which span many intervals each, are not among
    // them.
    let dopri_intervals = n as u64 - 1 - exact.summary.exponential_steps;
    assert!(
        dopri_intervals < impacts,
        "{dopri_intervals} intervals on Dormand-Prince, {impacts} impacts"
    );
    let h = MassChain::<6>::new(&upconverter()).unwrap();
    let l = h.affine(Mode::FREE).unwrap().l;
    let w = l
        .complex_eigenvalues()
        .iter()
        .fold(0.0f64, |m, e| m.max(e.norm()));
    let bound = n * (1e-5 * w).powi(6);
    let diff = output_distance(&exact, &fine);
    println!(
        "{impacts} impacts ({on_dopri} events of Dormand-Prince in the exact record, \
         {dopri_intervals} intervals): exact vs Dormand-Prince {diff:.2e}, bound {bound:.2e}; \
         contact fraction {:.6} vs {:.6}",
        exact.summary.contact_fraction, fine.summary.contact_fraction
    );
    assert!(diff <= bound, "outputs differ by {diff:e} > {bound:e}");
}

/// Two undamped masses of 1 g and 0.2 g on springs to the frame (50 and 80 Hz alone) with a
/// rigid stop of restitution 1 on both sides between them, released from rest apart from the
/// first mass's velocity, no drive, no transducer.
fn undamped_pair() -> Device {
    let stop = |side: &str| {
        format!(
            "[[stops]]\nmasses = [1, 0]\nside = \"{side}\"\ngap_m = 1e-4\nlaw = \"restitution\"\ncoefficient = 1.0\n"
        )
    };
    let text = two_masses(&format!(
        "[[springs]]\nmasses = [0]\nstiffness_n_per_m = 98.7\n\
         [[springs]]\nmasses = [1]\nstiffness_n_per_m = 50.5\n{}{}{NO_TRANSDUCER}",
        stop("upper"),
        stop("lower")
    ));
    Device::from_toml_str(&text, "undamped_pair.toml").unwrap()
}

/// Energy over thousands of impacts on the exact steps, and momentum across each impact. Each
/// exact step is one product of the state with the mode's propagator, whose entries carry the
/// rounding of the scaling and squaring of the matrix exponential; the energy is a quadratic
/// form of the state, so a step moves it by at most a few tens of eps of itself. An impact
/// changes the energy and the momentum by at most 32 eps (the two masses' new velocities in
/// six roundings each; see `tests/masses.rs`), and a located event's projection onto the stop
/// moves a mass by at most its relative speed times the 1e-14 s event tolerance. The bound,
/// 64 eps per step and per impact summed without cancellation, holds for both.
#[test]
fn impacts_on_exact_steps_conserve_energy_and_momentum() {
    let d = undamped_pair();
    let h = MassChain::<6>::new(&d).unwrap();
    let idx = h.layout().masses.clone();
    let masses = [1e-3, 2e-4];
    let mut y0 = SVector::<f64, 6>::zeros();
    y0[idx[0].1] = 0.1;
    let momentum = |y: &SVector<f64, 6>| -> f64 { (0..2).map(|k| masses[k] * y[idx[k].1]).sum() };
    let e0 = h.stored_energy(Mode::FREE, &y0);
    let p_scale = masses[0] * 0.1;
    let sine = Sine {
        amplitude_m_s2: 0.0,
        freq_hz: 20.0,
        phase_rad: 0.0,
    };
    let mut flow = SineFlow::new(&h, sine, 0.0, y0, Mode::FREE, 1e-10);
    assert!(flow.is_exact());
    let (mut worst_e, mut worst_p, mut switches) = (0.0f64, 0.0f64, 0usize);
    let mut last: Option<SVector<f64, 6>> = None;
    flow.integrate(40.0, |st, mode| {
        worst_e = worst_e.max((h.stored_energy(mode, &st.y1) - e0).abs() / e0);
        if let Some(prev) = last {
            if prev != st.y0 {
                switches += 1;
                worst_p = worst_p.max((momentum(&st.y0) - momentum(&prev)).abs() / p_scale);
            }
        }
        last = Some(st.y1);
    })
    .unwrap();
    let stats = flow.stats();
    let impacts = stats.events as f64;
    assert!(impacts > 2000.0, "{impacts} impacts");
    assert!(switches > 0, "the observer sees the resets");
    let bound = 64.0 * (stats.steps() as f64 + impacts) * f64::EPSILON;
    println!(
        "{impacts} impacts, {} steps: energy {worst_e:.2e}, momentum per impact {worst_p:.2e}, \
         bound {bound:.2e}",
        stats.steps()
    );
    assert!(worst_e < bound, "energy drifts by {worst_e:e} > {bound:e}");
    assert!(
        worst_p < 64.0 * f64::EPSILON,
        "an impact moves the momentum by {worst_p:e}"
    );
}

/// A resting contact's mode: the form with its guards on the state and the drive
/// ([`Model::driven_affine`]) gives the model's own right-hand side and release guard (the
/// holding force's negative) at states and drives about the contact, to rounding (1e-12 of the
/// largest term: each side is a sum of a few products of the same numbers in another order);
/// the form the sine flow uses ([`Model::affine`]) leaves the mode out. Returns the release's
/// coefficient on the drive.
fn resting_is_affine(h: &MassChain<6>) -> f64 {
    let mode = Mode::FREE.with_contact(0, Contact::Resting);
    assert!(h.affine(mode).is_none());
    let DrivenAffine { affine, drive } = h.driven_affine(mode).expect("a resting mode is affine");
    assert_eq!(affine.guards.len(), drive.len());
    let release = affine
        .guards
        .iter()
        .position(|g| g.index == 1)
        .expect("the release is a guard");
    let sc = h.scales();
    let pattern = [0.3, -0.7, 0.45, 0.2, -0.55, 0.35, -0.25, 0.6, -0.15];
    let mut g = vec![0.0; h.guard_count()];
    for p in 0..5 {
        let y = SVector::<f64, 6>::from_fn(|i, _| pattern[(i + 2 * p) % 9] * sc[i]);
        let a = 20.0 * pattern[(p + 4) % 9];
        let f = h.rhs(mode, &y, a);
        let lin = affine.l * y + affine.c * a + affine.d;
        for i in 0..6 {
            let size = (0..6).map(|j| (affine.l[(i, j)] * y[j]).abs()).sum::<f64>()
                + (affine.c[i] * a).abs()
                + affine.d[i].abs()
                + f[i].abs();
            assert!(
                (f[i] - lin[i]).abs() <= 1e-12 * size,
                "row {i}: {} vs {}",
                f[i],
                lin[i]
            );
        }
        h.guards(mode, &y, || a, &mut g);
        let piece = &affine.guards[release];
        let value = piece.at(&y) + drive[release] * a;
        let size = piece
            .n
            .iter()
            .zip(y.iter())
            .map(|(n, y)| (n * y).abs())
            .sum::<f64>()
            + (drive[release] * a).abs()
            + piece.g0.abs();
        assert!(
            (g[1] - value).abs() <= 1e-12 * size,
            "release guard {} vs {value}",
            g[1]
        );
    }
    drive[release]
}

/// The up-converter's masses resting together, whose release does not depend on the drive
/// (the base's acceleration moves both alike), and a mass held on a frame stop, whose release
/// does (the base's inertial force `m a` pulls it off): both modes are affine in the state and
/// the drive ([`resting_is_affine`]).
#[test]
fn resting_contacts_are_affine_in_the_state_and_the_drive() {
    let pair = MassChain::<6>::new(&upconverter()).unwrap();
    assert_eq!(resting_is_affine(&pair), 0.0);
    let text = two_masses(&format!(
        "[[springs]]\nmasses = [0]\nstiffness_n_per_m = 98.7\n\
         [[springs]]\nmasses = [1, 0]\nstiffness_n_per_m = 50.5\n\
         [[dampers]]\nmasses = [1]\ndamping_n_s_per_m = 1e-3\n\
         [[stops]]\nmasses = [1]\nside = \"lower\"\ngap_m = 1e-4\nlaw = \"restitution\"\n\
         coefficient = 0.5\n{NO_TRANSDUCER}"
    ));
    let device = Device::from_toml_str(&text, "held.toml").unwrap();
    let held = MassChain::<6>::new(&device).unwrap();
    // The mass of 0.2 g on its lower stop (side -1): the holding force is -F, its guard F,
    // whose drive term is the mass times the drive.
    let w = resting_is_affine(&held);
    assert!((w - 2e-4).abs() <= 1e-18, "{w:e}");
}

/// A resting pair released where an integrator that moves both masses has left their
/// separation a rounding past the gap (the up-converter's driver on its generator): the
/// release puts the pair back on the contact's surface, so that the free mode starts with its
/// penetration at most zero and no strike at zero relative speed is read at the release; the
/// velocities and the struck mass's position are kept, and the mover moves by rounding only
/// (a few ulps of its position).
#[test]
fn a_released_pair_leaves_from_the_contact_surface() {
    let h = MassChain::<6>::new(&upconverter()).unwrap();
    let c = h.contacts()[0];
    let struck = h.layout().masses[c.mass];
    let mover = h.layout().masses[c.other.expect("a contact between two masses")];
    let mut y = h.rest_state();
    y[struck.0] = 6.8e-6;
    y[struck.1] = -0.103;
    y[mover.1] = y[struck.1];
    y[mover.0] = y[struck.0] + c.side * c.gap;
    let a = -4.7;
    let mut g = vec![0.0; h.guard_count()];
    let penetration = |y: &SVector<f64, 6>, g: &mut Vec<f64>| {
        h.guards(Mode::FREE, y, || a, g);
        g[0]
    };
    while penetration(&y, &mut g) <= 0.0 {
        y[mover.0] = if c.side > 0.0 {
            y[mover.0].next_up()
        } else {
            y[mover.0].next_down()
        };
    }
    let before = y;
    let resting = Mode::FREE.with_contact(0, Contact::Resting);
    let next = h.switch(resting, 1, &mut y, a);
    assert_eq!(next, Mode::FREE);
    let after = penetration(&y, &mut g);
    assert!(after <= 0.0, "penetration {after:e} after the release");
    assert_eq!(y[struck.0], before[struck.0]);
    assert_eq!(
        (y[struck.1], y[mover.1]),
        (before[struck.1], before[mover.1])
    );
    let moved = (y[mover.0] - before[mover.0]).abs();
    assert!(
        moved <= 8.0 * f64::EPSILON * before[mover.0].abs(),
        "the mover moved by {moved:e}"
    );
}

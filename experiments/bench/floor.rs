//! The record engine against its floor: a minimal exact kernel for one case, timed beside the
//! general engine's record of the same case.
//!
//! * **The sine case**: a 1-DOF oscillator (f0 = 1 kHz, ζ = 0.005) between rigid restitution
//!   stops at ±10 um (e = 0.6), driven from rest by `a(t) = -10 cos(2π 1000 t)` m/s² for 10 s
//!   and written at 50 kHz. The floor is `bench/floor_kernel.rs` (closed-form propagation,
//!   Hermite guard, Newton on the closed form); the engine is `study::record` on the assembled
//!   `Harvester` of a device with no transducer (whose record runs on `(x, v)` alone), under
//!   the cosine sampled at 50 kHz (read between samples by linear interpolation, as every
//!   sampled drive is). Their impact counts and positions at the samples are compared.
//! * **Prototype 2's noise record** (Sa = 1.69e-3 g²/Hz, the paper's 10 s after its pre-roll,
//!   seed 2012, stream 0): the floor is a lower bound, the exact propagation of the free
//!   flight's linear part `L` under the same samples, one 4 x 4 product and two drive columns
//!   per sample (no remainder, no contacts, no outputs).
//!
//! The runs alternate (engine, floor, engine, ...) so that a drift of the machine's speed hits
//! both; the table gives each one's median processor time and the median of the per-round
//! ratios with their range.

use std::sync::Arc;

use anyhow::{bail, Result};
use endstop::device::Device;
use endstop::model::Model;
use endstop::ode::phi::phi_functions;
use endstop::paper::setups::paper_record;
use endstop::physics::harvester::Harvester;
use endstop::study::record::{simulate_drive, SampledDrive, Scheme, DEFAULT_RTOL};
use endstop_experiments as common;

use common::fmt_sig;

use crate::examples::{cpu, median};
use crate::floor_kernel::{self, SineCase};

/// The sine case: a 1 kHz oscillator between rigid restitution stops, driven at resonance.
pub const SINE_CASE: SineCase = SineCase {
    f0_hz: 1000.0,
    zeta: 0.005,
    gap_m: 10e-6,
    restitution: 0.6,
    accel_m_s2: 10.0,
    freq_hz: 1000.0,
    sample_rate_hz: 50e3,
    duration_s: 10.0,
};

/// Mass of the sine case's device (kg): any mass gives the same motion.
const MASS_KG: f64 = 1e-3;

/// Seed of the prototype 2 record.
const SEED: u64 = 2012;

/// The level of the prototype 2 record (g^2/Hz): Figure 14's.
const P2_PSD_G2_PER_HZ: f64 = 1.69e-3;

/// One case's alternated runs.
pub struct FloorCost {
    /// What ran.
    pub case: String,
    /// The engine's processor times (s): median, smallest, largest.
    pub engine_s: (f64, f64, f64),
    /// The floor's.
    pub floor_s: (f64, f64, f64),
    /// Per-round ratios engine / floor: median, smallest, largest.
    pub ratios: (f64, f64, f64),
    /// What the two found, compared.
    pub note: String,
}

/// The sine case as a device file: no transducer, the same rigid stop on both sides.
pub fn sine_device(case: &SineCase) -> Result<Device> {
    let w0 = 2.0 * std::f64::consts::PI * case.f0_hz;
    let k = MASS_KG * w0 * w0;
    let b = 2.0 * case.zeta * MASS_KG * w0;
    let text = format!(
        "name = \"floor_sine\"\nparams = \"hypothetical\"\n\
         description = \"the bench's floor case: a sine-driven oscillator between restitution stops\"\n\
         [mechanics]\nmass_kg = {MASS_KG:e}\nstiffness_n_per_m = {k:e}\n\
         damping_n_s_per_m = {b:e}\n\
         [stops.both]\ngap_m = {:e}\nlaw = \"restitution\"\ncoefficient = {}\n\
         [transducer]\nkind = \"none\"\n",
        case.gap_m, case.restitution
    );
    Ok(Device::from_toml_str(&text, "floor_sine")?)
}

/// The sine case's drive sampled at its rate, from t = 0 to its end, without a pre-roll.
pub fn sine_drive(case: &SineCase) -> SampledDrive {
    let n = (case.duration_s * case.sample_rate_hz).round() as usize;
    let w = 2.0 * std::f64::consts::PI * case.freq_hz;
    let accel: Arc<[f64]> = (0..=n)
        .map(|k| -case.accel_m_s2 * (w * k as f64 / case.sample_rate_hz).cos())
        .collect();
    SampledDrive {
        accel,
        sample_rate_hz: case.sample_rate_hz,
        transient_samples: 0,
    }
}

/// Runs `rounds` alternated rounds of both cases on the calling thread.
pub fn measure(rounds: usize) -> Result<Vec<FloorCost>> {
    Ok(vec![sine(rounds)?, prototype2(rounds)?])
}

fn sine(rounds: usize) -> Result<FloorCost> {
    let device = sine_device(&SINE_CASE)?;
    let drive = sine_drive(&SINE_CASE);
    let (mut engine, mut floor, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    let (mut rec, mut run) = (None, None);
    for _ in 0..rounds.max(1) {
        let (r, a) = cpu(|| {
            Ok(simulate_drive(
                &device,
                &drive,
                DEFAULT_RTOL,
                Scheme::Exponential,
            )?)
        })?;
        let (f, b) = cpu(|| floor_kernel::run(&SINE_CASE))?;
        engine.push(a);
        floor.push(b);
        ratios.push(a / b);
        (rec, run) = (Some(r), Some(f));
    }
    let (rec, run) = (rec.expect("a round ran"), run.expect("a round ran"));
    let n = run.x_m.len() as f64;
    let x_rms = (run.x_m.iter().map(|x| x * x).sum::<f64>() / n).sqrt();
    let s = rec.summary;
    Ok(FloorCost {
        case: format!(
            "1-DOF, f0 = {} Hz, zeta = {}, rigid stops at +-{} um (e = {}), a = -{} cos(2 pi {} t) \
             m/s^2, {} s at {} kHz",
            SINE_CASE.f0_hz,
            SINE_CASE.zeta,
            SINE_CASE.gap_m * 1e6,
            SINE_CASE.restitution,
            SINE_CASE.accel_m_s2,
            SINE_CASE.freq_hz,
            SINE_CASE.duration_s,
            SINE_CASE.sample_rate_hz / 1e3
        ),
        engine_s: median(engine),
        floor_s: median(floor),
        ratios: median(ratios),
        note: format!(
            "impacts: engine {}, floor {}; x rms: engine {:.6e} m, floor {:.6e} m (relative difference \
             {:.1e}, the engine's drive being the cosine's linear interpolant)",
            s.impacts,
            run.impacts,
            s.x_rms_m,
            x_rms,
            (s.x_rms_m - x_rms).abs() / x_rms
        ),
    })
}

fn prototype2(rounds: usize) -> Result<FloorCost> {
    let p2 = common::load_device("prototype2")?.device;
    let spec = paper_record(&p2, P2_PSD_G2_PER_HZ);
    let drive = SampledDrive::noise(&spec, SEED, 0)?;
    let h = Harvester::<4>::new(&p2)?;
    let Some(l) = h.flight_matrix() else {
        bail!("prototype 2 has no free-flight matrix");
    };
    let dt = 1.0 / drive.sample_rate_hz;
    let phi = phi_functions(&(l * dt), 2, &h.scales());
    // y(h) = φ0 y0 + h (φ1 - φ2) c a0 + h φ2 c a1, with c the drive column e_1.
    let g0 = (phi[1] - phi[2]).column(1) * dt;
    let g1 = phi[2].column(1) * dt;
    let (p, g0, g1) = (phi[0], g0.into_owned(), g1.into_owned());
    let floor_run = || -> Result<f64> {
        let mut y = h.rest_state();
        let mut sx2 = 0.0;
        for a in drive.accel.windows(2) {
            y = p * y + g0 * a[0] + g1 * a[1];
            sx2 += y[0] * y[0];
        }
        Ok(sx2)
    };
    let (mut engine, mut floor, mut ratios) = (Vec::new(), Vec::new(), Vec::new());
    let mut impacts = 0;
    for _ in 0..rounds.max(1) {
        let (r, a) = cpu(|| Ok(simulate_drive(&p2, &drive, spec.rtol, spec.scheme)?))?;
        let (sx2, b) = cpu(floor_run)?;
        std::hint::black_box(sx2);
        engine.push(a);
        floor.push(b);
        ratios.push(a / b);
        impacts = r.summary.impacts;
    }
    Ok(FloorCost {
        case: format!(
            "prototype 2, noise record at Sa = {P2_PSD_G2_PER_HZ:e} g^2/Hz ({} s after a {} s \
             pre-roll at 100 kHz)",
            spec.noise.duration_s, spec.transient_s
        ),
        engine_s: median(engine),
        floor_s: median(floor),
        ratios: median(ratios),
        note: format!(
            "floor: the linear part's exact propagation alone, a lower bound; the engine's \
             record has {impacts} impacts"
        ),
    })
}

/// The table of `costs` over `rounds` rounds.
pub fn table(costs: &[FloorCost], rounds: usize) -> String {
    let mut md = format!(
        "The record engine against its floor (`bench --floor`, `bench/floor.rs`): processor \
         time on one thread, median of {rounds} alternated rounds, at commit `{}`; the ratio \
         is taken within each round.\n\n\
         | case | engine (s) | floor (s) | engine / floor, median (range) | compared |\n\
         |---|---|---|---|---|\n",
        common::git_commit()
    );
    for c in costs {
        md.push_str(&format!(
            "| {} | {} | {} | {} ({} to {}) | {} |\n",
            c.case,
            fmt_sig(c.engine_s.0, 3),
            fmt_sig(c.floor_s.0, 3),
            fmt_sig(c.ratios.0, 3),
            fmt_sig(c.ratios.1, 3),
            fmt_sig(c.ratios.2, 3),
            c.note
        ));
    }
    md
}

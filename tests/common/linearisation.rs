//! The shooting's linearisation of a period against central differences of the period map:
//! the monodromy (scaled by the state scales) and the derivative in the drive frequency.

use endstop::drive::{Parameter, Sine};
use endstop::model::Model;
use endstop::ode::Stats;
use endstop::study::orbit::{Linearised, Shooter, ShootingOptions};
use endstop::study::periodic::period_map;
use nalgebra::{SMatrix, SVector};

/// The linearisation at `y` and its relative differences from central differences.
pub struct Against<const N: usize> {
    /// The shooting's linearisation (integrated at `rtol`).
    pub lin: Linearised<N>,
    /// Its integration counts (events over the period).
    pub stats: Stats,
    /// `max |M - M_fd| / max |M|`, both scaled by the state scales.
    pub monodromy_rel: f64,
    /// `max |dP/df - fd| / max |dP/df|`, scaled.
    pub dp_rel: f64,
}

/// [`Against`] for `model` at `y` under `sine`, the period map integrated at `rtol` and
/// differenced with steps of 1e-5 of each state scale and 1e-5 Hz.
pub fn against_differences<M: Model<N>, const N: usize>(
    model: &M,
    sine: Sine,
    y: SVector<f64, N>,
    rtol: f64,
) -> Against<N> {
    let shooter = Shooter::new(
        model,
        ShootingOptions {
            rtol,
            ..ShootingOptions::default()
        },
    );
    let mut stats = Stats::default();
    let lin = shooter
        .linearise_sine(sine, Parameter::Frequency, y, sine.period_s(), &mut stats)
        .unwrap();
    let sc = model.scales();
    let scaled = |m: &SMatrix<f64, N, N>| {
        SMatrix::<f64, N, N>::from_diagonal(&sc.map(|v| 1.0 / v))
            * m
            * SMatrix::<f64, N, N>::from_diagonal(&sc)
    };
    let exact = scaled(&lin.monodromy);
    let mut fd = SMatrix::<f64, N, N>::zeros();
    for c in 0..N {
        let h = 1e-5 * sc[c];
        let (mut yp, mut ym) = (y, y);
        yp[c] += h;
        ym[c] -= h;
        let col = (period_map(model, sine, &yp, rtol).unwrap()
            - period_map(model, sine, &ym, rtol).unwrap())
            / (2.0 * h);
        fd.set_column(c, &col);
    }
    let monodromy_rel = (exact - scaled(&fd)).amax() / exact.amax();
    let (f, df) = (sine.freq_hz, 1e-5);
    let p_at = |f: f64| period_map(model, Sine { freq_hz: f, ..sine }, &y, rtol).unwrap();
    let dp_fd = ((p_at(f + df) - p_at(f - df)) / (2.0 * df)).component_div(&sc);
    let dp = lin.dp.component_div(&sc);
    let dp_rel = (dp - dp_fd).amax() / dp.amax();
    Against {
        lin,
        stats,
        monodromy_rel,
        dp_rel,
    }
}

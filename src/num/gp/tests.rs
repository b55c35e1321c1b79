//! The emulator's unit tests.

use super::*;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn points(n: usize, d: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    (0..n)
        .map(|_| (0..d).map(|_| rng.random::<f64>()).collect())
        .collect()
}

fn branin_like(x: &[f64]) -> f64 {
    // Smooth in x0 and x1, linear in x2, independent of x3.
    (3.0 * x[0]).sin() + (x[1] - 0.3).powi(2) * 4.0 + 0.5 * x[2]
}

#[test]
fn a_smooth_function_is_emulated_within_its_stated_uncertainty() {
    let x = points(60, 4, 1);
    let y: Vec<f64> = x.iter().map(|p| branin_like(p)).collect();
    let gp = Gp::fit(&x, &y, &vec![0.0; 60], GpSettings::default()).unwrap();
    // Irrelevant input: its length scale runs far longer than the relevant ones'.
    let l = &gp.hyper().lengthscales;
    assert!(l[3] > 3.0 * l[0].max(l[1]), "{l:?}");
    // Held-out points: standardised errors N(0, 1) if the variance is right; with 200 of
    // them, at most 5 % beyond 3 allows the tails of a slightly misfitted variance
    // (N(0, 1) puts 0.3 % there) and rejects one ten times too small.
    let test = points(200, 4, 2);
    let mut beyond = 0;
    let mut worst_abs: f64 = 0.0;
    for p in &test {
        let (m, v) = gp.predict(p);
        let e = branin_like(p) - m;
        worst_abs = worst_abs.max(e.abs());
        if e.abs() > 3.0 * v.sqrt() + 1e-9 {
            beyond += 1;
        }
    }
    assert!(beyond <= 10, "{beyond} of 200 beyond 3 sd");
    // Accuracy: the function spans about 3; 60 points of 4 inputs emulate it to 0.1.
    assert!(worst_abs < 0.1, "{worst_abs}");
}

#[test]
fn leave_one_out_in_closed_form_equals_refitting_without_the_point() {
    // With fixed hyperparameters Dubrule's formulas equal the emulator built on the other
    // points: to rounding (1e-8 of the outputs' scale, the conditioning of K).
    let x = points(25, 2, 3);
    let y: Vec<f64> = x.iter().map(|p| (4.0 * p[0]).sin() + p[1]).collect();
    let noise: Vec<f64> = (0..25).map(|i| 1e-3 * (1 + i % 3) as f64).collect();
    let gp = Gp::fit(&x, &y, &noise, GpSettings::default()).unwrap();
    let (mean, scale, full) = (gp.y_mean, gp.y_scale, gp.hyper().clone());
    let y_std: Vec<f64> = y.iter().map(|v| (v - mean) / scale).collect();
    let n_std: Vec<f64> = noise.iter().map(|v| v / (scale * scale)).collect();
    for i in [0, 7, 24] {
        let drop = |v: &[f64]| -> Vec<f64> {
            v.iter()
                .enumerate()
                .filter(|(j, _)| *j != i)
                .map(|(_, v)| *v)
                .collect()
        };
        let xs: Vec<Vec<f64>> = x
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != i)
            .map(|(_, p)| p.clone())
            .collect();
        let (m, v) = direct_prediction(&xs, &drop(&y_std), &drop(&n_std), &full, &x[i]);
        let pred = mean + scale * m;
        let sd = scale * (v + n_std[i] + full.nugget_var).sqrt();
        let loo = gp.loo()[i];
        assert!(
            (loo.predicted - pred).abs() < 1e-8,
            "{} vs {pred}",
            loo.predicted
        );
        assert!(
            (loo.sd - sd).abs() < 1e-8 * sd.max(1.0),
            "{} vs {sd}",
            loo.sd
        );
    }
}

/// Universal kriging of `y` (already in the units of `hy`) at `p`, written out directly.
fn direct_prediction(
    x: &[Vec<f64>],
    y: &[f64],
    noise: &[f64],
    hy: &Hyper,
    p: &[f64],
) -> (f64, f64) {
    let n = x.len();
    let k = DMatrix::from_fn(n, n, |i, j| {
        hy.signal_var * matern52(scaled_r(&x[i], &x[j], &hy.lengthscales)).0
            + if i == j {
                noise[i] + hy.nugget_var
            } else {
                0.0
            }
    });
    let h = DMatrix::from_fn(
        n,
        p.len() + 1,
        |i, j| if j == 0 { 1.0 } else { x[i][j - 1] },
    );
    let kinv = k.try_inverse().unwrap();
    let hkh = (h.transpose() * &kinv * &h).try_inverse().unwrap();
    let yv = DVector::from_column_slice(y);
    let beta = &hkh * h.transpose() * &kinv * &yv;
    let kx = DVector::from_fn(n, |i, _| {
        hy.signal_var * matern52(scaled_r(&x[i], p, &hy.lengthscales)).0
    });
    let hx = DVector::from_iterator(p.len() + 1, basis(p));
    let m = hx.dot(&beta) + kx.dot(&(&kinv * (&yv - &h * &beta)));
    let r = &hx - h.transpose() * &kinv * &kx;
    let v = hy.signal_var - kx.dot(&(&kinv * &kx)) + r.dot(&(&hkh * &r));
    (m, v)
}

#[test]
fn the_nugget_follows_each_points_variance() {
    // sin(6x) on [0, 1]: ten exact points on the left half, ten with sampling variance
    // 0.04 (sd 0.2) on the right. The emulator interpolates the exact ones (residual below
    // 1e-3 of the function's range), smooths the noisy ones (an interpolant's residual is
    // 0; a smoother's is a fair share of the noise: above 0.05 rms) and is far less sure on
    // the right (variance ten times the left's at mirrored points).
    let mut rng = ChaCha8Rng::seed_from_u64(5);
    let f = |x: f64| (6.0 * x).sin();
    let mut x = Vec::new();
    let mut y = Vec::new();
    let mut noise = Vec::new();
    for k in 0..10 {
        let u = 0.025 + 0.05 * k as f64;
        x.push(vec![u]);
        y.push(f(u));
        noise.push(0.0);
        let w = 0.5 + u;
        let e: f64 = (0..12).map(|_| rng.random::<f64>()).sum::<f64>() - 6.0;
        x.push(vec![w]);
        y.push(f(w) + 0.2 * e);
        noise.push(0.04);
    }
    let gp = Gp::fit(&x, &y, &noise, GpSettings::default()).unwrap();
    let mut exact = 0.0f64;
    let mut smoothed = 0.0;
    for ((p, y), v) in x.iter().zip(&y).zip(&noise) {
        let r = y - gp.mean(p);
        if *v == 0.0 {
            exact = exact.max(r.abs());
        } else {
            smoothed += r * r / 10.0;
        }
    }
    assert!(exact < 2e-3, "{exact}");
    assert!(smoothed.sqrt() > 0.05, "{}", smoothed.sqrt());
    let (_, v_left) = gp.predict(&[0.26]);
    let (_, v_right) = gp.predict(&[0.76]);
    assert!(v_right > 10.0 * v_left, "{v_right} vs {v_left}");
}

#[test]
fn bad_training_data_are_named_errors() {
    let x = points(10, 2, 6);
    assert!(matches!(
        Gp::fit(&x, &[0.0; 9], &[0.0; 10], GpSettings::default()),
        Err(GpError::Shape(_))
    ));
    let mut y = vec![1.0; 10];
    y[3] = f64::NAN;
    assert!(matches!(
        Gp::fit(&x, &y, &[0.0; 10], GpSettings::default()),
        Err(GpError::NotFinite { index: 3, .. })
    ));
    assert!(matches!(
        Gp::fit(&x[..4], &[0.0; 4], &[0.0; 4], GpSettings::default()),
        Err(GpError::TooFew { got: 4, need: 5 })
    ));
}

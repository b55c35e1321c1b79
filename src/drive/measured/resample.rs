//! The resampler behind [`super::MeasuredRecord::resampled`]: the windowed-sinc interpolant
//! of the module docs, with its weights computed once per record instead of once per tap.
//!
//! The output instant `t_j = j / fs` sits at `u_j = j fs_in / fs` input samples; its taps are
//! the input samples within [`HALF_TAPS`]` / r` of it. Four plans, chosen by [`Plan::choose`]:
//! - **Identity**: equal rates (within [`drift_tol_samples`] over the record). The samples are
//!   the drive, unfiltered: the interpolant at the sample instants is the samples themselves
//!   up to the kernel's pass-band ripple (about 3e-5 at Kaiser beta 8.6), and nothing above the
//!   record's Nyquist frequency exists to remove.
//! - **Polyphase**: `fs / fs_in = p / q` in lowest terms with `p` at most [`MAX_PHASES`]
//!   (2x up is `2 / 1`, 48 to 50 kHz is `25 / 24`). Output `j` sits at `(j q) / p` and its
//!   fractional position is one of the `p` phases `φ / p`: one table of exact kernel values per
//!   phase serves every output, and each output is one dot product.
//! - **Table**: any other ratio. The kernel is tabulated at `P` phases per input sample and an
//!   output at fractional position `f` is the linear interpolation, in `f`, of the two dot
//!   products of the neighbouring phases. `P` is the smallest count whose worst-case
//!   interpolation error, `(1/P)^2 / 8` times a bound on the kernel's second derivative per tap,
//!   over all taps, is at most [`TABLE_TOL`] of the record's largest sample (120 dB down, 30 dB
//!   under the kernel's own stop band).
//! - **Direct**: the kernel is wider than twice the record (a record downsampled to a few
//!   outputs): the sum evaluated tap by tap, as the module docs write it.
//!
//! Past the record's ends the samples are zero (a zero-padded copy of the record, so that
//! every output is a dot product of the same length).

use std::sync::Arc;

use super::{HALF_TAPS, KAISER_BETA};

/// Largest worst-case error of the table plan, relative to the record's largest sample.
pub(super) const TABLE_TOL: f64 = 1e-6;

/// Most phases a polyphase or interpolated table may have.
pub(super) const MAX_PHASES: usize = 16384;

/// How a record is resampled (see the module docs).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Plan {
    /// The samples as they are.
    Identity,
    /// `p` output samples for each `q` input samples, one weight table per phase.
    Polyphase {
        /// Output samples per period of the ratio.
        p: u64,
        /// Input samples per period of the ratio.
        q: u64,
    },
    /// Weights at `phases` fractional positions per input sample, interpolated linearly.
    Table {
        /// Phases per input sample.
        phases: usize,
    },
    /// The sum tap by tap.
    Direct,
}

/// The windowed-sinc kernel of the module docs: `h(d) = r sinc(r d) w(d / W)` for
/// `|d| <= W = HALF_TAPS / r` (input samples), zero outside.
#[derive(Debug, Clone, Copy)]
pub(super) struct Kernel {
    /// Cut-off in units of the input's Nyquist frequency.
    pub(super) r: f64,
    /// Half-width `W` in input samples.
    pub(super) half_width: f64,
    /// `I0(KAISER_BETA)`, the window's normalisation.
    i0_beta: f64,
}

impl Kernel {
    /// The kernel for input rate `fs_in` and output rate `fs`.
    pub(super) fn new(fs_in: f64, fs: f64) -> Self {
        let r = 0.9 * (fs / fs_in).min(1.0);
        Self {
            r,
            half_width: HALF_TAPS / r,
            i0_beta: bessel_i0(KAISER_BETA),
        }
    }

    /// `h(d)`.
    pub(super) fn at(&self, d: f64) -> f64 {
        if d.abs() > self.half_width {
            return 0.0;
        }
        let z = d / self.half_width;
        let w = bessel_i0(KAISER_BETA * (1.0 - z * z).max(0.0).sqrt()) / self.i0_beta;
        self.r * sinc(self.r * d) * w
    }

    /// The taps each output reads: input positions `k0 - K ..= k0 + K + 1` for an output at
    /// `k0 + f`, `0 <= f < 1`, with `K = ceil(W)`.
    fn taps(&self) -> usize {
        2 * self.half_width.ceil() as usize + 2
    }

    /// `K = ceil(W)`: zeros before the record in the padded copy.
    fn lead(&self) -> usize {
        self.half_width.ceil() as usize
    }

    /// Bounds on `|w'|` and `|w''|` of the Kaiser window `w(z) = I0(beta sqrt(1 - z^2)) /
    /// I0(beta)` on `|z| <= 1`, from its power series in `g = beta^2 (1 - z^2) / 4`:
    /// `w = sum_k g^k / (k!)^2 / I0(beta)` with `0 <= g <= q = beta^2 / 4`, `|g'| <= 2 q`,
    /// `|g''| = 2 q`.
    fn window_derivative_bounds(&self) -> (f64, f64) {
        let q = 0.25 * KAISER_BETA * KAISER_BETA;
        let (mut a, mut w1, mut w2) = (1.0f64, 0.0, 0.0);
        for k in 1..200 {
            let kf = k as f64;
            a *= q / (kf * kf); // q^k / (k!)^2
            w1 += 2.0 * kf * a;
            w2 += (4.0 * kf * (kf - 1.0) + 2.0 * kf) * a;
            if a < 1e-17 * w2 {
                break;
            }
        }
        (w1 / self.i0_beta, w2 / self.i0_beta)
    }

    /// A bound on `|h'|` inside the kernel, by the product rule with `|sinc| <= 1`,
    /// `|sinc'| <= pi / 2` (the sinc is the Fourier transform of the unit box) and `|w| <= 1`.
    pub(super) fn slope_bound(&self) -> f64 {
        let (w1, _) = self.window_derivative_bounds();
        let pi = std::f64::consts::PI;
        self.r * self.r * pi / 2.0 + self.r * w1 / self.half_width
    }

    /// A bound on `|h''|` inside the kernel, as [`Kernel::slope_bound`] with
    /// `|sinc''| <= pi^2 / 3`.
    pub(super) fn curvature_bound(&self) -> f64 {
        let (w1, w2) = self.window_derivative_bounds();
        let pi = std::f64::consts::PI;
        let (r, hw) = (self.r, self.half_width);
        r.powi(3) * pi * pi / 3.0 + 2.0 * r * r * pi / 2.0 * w1 / hw + r * w2 / (hw * hw)
    }

    /// The kernel's slope just inside its edge, `|h'(W-)| = r^2 / (HALF_TAPS I0(beta))`
    /// (there `sinc(r W) = sinc(HALF_TAPS) = 0` and `w = 1 / I0(beta)`): outside the kernel is
    /// zero, so the slope jumps by this much at `|d| = W`.
    pub(super) fn edge_slope(&self) -> f64 {
        self.r * self.r / (HALF_TAPS * self.i0_beta)
    }

    /// Phases per input sample for the table plan, at most [`MAX_PHASES`]: the smallest `P`
    /// whose worst-case interpolation error, relative to the record's largest sample, is at
    /// most [`TABLE_TOL`]: `L H2 / (8 P^2)` over the `L` taps of curvature at most `H2`, plus
    /// `J / (2 P)` for the two taps whose interval straddles an edge of the kernel, where its
    /// slope jumps by `J` (linear interpolation across a kink of `J` errs by at most `J / (4
    /// P)`).
    pub(super) fn table_phases(&self) -> usize {
        let (a, b) = (
            self.taps() as f64 * self.curvature_bound() / 8.0,
            self.edge_slope() / 2.0,
        );
        // The positive root of TABLE_TOL P^2 - b P - a = 0.
        let need = (b + (b * b + 4.0 * TABLE_TOL * a).sqrt()) / (2.0 * TABLE_TOL);
        (need.ceil() as usize).clamp(1, MAX_PHASES)
    }
}

/// The largest drift, in input samples over the whole record, by which a rational ratio's
/// output positions may differ from `j fs_in / fs` and still be used: the slope bound times
/// the taps times the drift stays within [`TABLE_TOL`] of the record's largest sample.
pub(super) fn drift_tol_samples(kernel: &Kernel) -> f64 {
    TABLE_TOL / (kernel.slope_bound() * kernel.taps() as f64)
}

impl Plan {
    /// The plan for `n` input samples at `fs_in` resampled to `m` outputs at `fs`.
    pub(super) fn choose(n: usize, m: usize, fs_in: f64, fs: f64) -> Self {
        let kernel = Kernel::new(fs_in, fs);
        if kernel.taps() > (2 * n).max(4096) {
            return Plan::Direct;
        }
        let span = m.saturating_sub(1) as f64;
        let tol = drift_tol_samples(&kernel);
        if let Some((p, q)) = rational(fs / fs_in, MAX_PHASES as u64, |p, q| {
            span * (q as f64 / p as f64 - fs_in / fs).abs() <= tol
        }) {
            return if p == 1 && q == 1 {
                Plan::Identity
            } else {
                Plan::Polyphase { p, q }
            };
        }
        Plan::Table {
            phases: kernel.table_phases(),
        }
    }
}

/// The first continued-fraction convergent `p / q` of `c > 0` with `p <= max_p` that `close`
/// accepts, if any.
fn rational(c: f64, max_p: u64, close: impl Fn(u64, u64) -> bool) -> Option<(u64, u64)> {
    // Convergents p_k / q_k of c = a0 + 1/(a1 + 1/(a2 + ...)).
    let (mut p_prev, mut q_prev, mut p, mut q) = (1u64, 0u64, c.floor() as u64, 1u64);
    let mut rest = c - c.floor();
    for _ in 0..64 {
        if p >= 1 && p <= max_p && close(p, q) {
            return Some((p, q));
        }
        if p > max_p || rest < 1e-300 {
            return None;
        }
        let inv = 1.0 / rest;
        let a = inv.floor();
        rest = inv - a;
        if a.is_nan() || a >= 1e15 {
            return None;
        }
        let a = a as u64;
        let (pn, qn) = (a.checked_mul(p)? + p_prev, a.checked_mul(q)? + q_prev);
        (p_prev, q_prev, p, q) = (p, q, pn, qn);
    }
    None
}

/// `x` at `fs_in` resampled to `m` outputs at `fs` by `plan`, shared (the record engine reads
/// its drive through an `Arc`): at equal rates a copy of the samples (a whole record shares
/// its own instead, [`super::MeasuredRecord::resampled`]).
pub(super) fn resample(x: &[f64], fs_in: f64, fs: f64, m: usize, plan: Plan) -> Arc<[f64]> {
    let kernel = Kernel::new(fs_in, fs);
    match plan {
        Plan::Identity => Arc::from(&x[..m.min(x.len())]),
        Plan::Direct => direct(x, fs_in, fs, m, &kernel).into(),
        Plan::Polyphase { p, q } => {
            let (lead, taps) = (kernel.lead(), kernel.taps());
            let table = weights(&kernel, p as usize, p as usize);
            let xp = padded(x, lead, taps);
            (0..m as u64)
                .map(|j| {
                    let (k0, phase) = ((j * q / p) as usize, (j * q % p) as usize);
                    dot(&table[phase * taps..(phase + 1) * taps], &xp[k0..k0 + taps])
                })
                .collect()
        }
        Plan::Table { phases } => {
            let (lead, taps) = (kernel.lead(), kernel.taps());
            let table = weights(&kernel, phases + 1, phases);
            let xp = padded(x, lead, taps);
            (0..m)
                .map(|j| {
                    let u = j as f64 * fs_in / fs;
                    let k0 = u.floor();
                    let s = (u - k0) * phases as f64;
                    let phase = (s.floor() as usize).min(phases - 1);
                    let alpha = s - phase as f64;
                    let k0 = k0 as usize;
                    let xs = &xp[k0..k0 + taps];
                    let lo = dot(&table[phase * taps..(phase + 1) * taps], xs);
                    let hi = dot(&table[(phase + 1) * taps..(phase + 2) * taps], xs);
                    lo + alpha * (hi - lo)
                })
                .collect()
        }
    }
}

/// The sum tap by tap (the module docs' formula): each weight evaluated where it is used.
pub(super) fn direct(x: &[f64], fs_in: f64, fs: f64, m: usize, kernel: &Kernel) -> Vec<f64> {
    let half_width = kernel.half_width;
    (0..m)
        .map(|j| {
            let u = j as f64 * fs_in / fs;
            let k_lo = (u - half_width).ceil().max(0.0) as usize;
            let k_hi = ((u + half_width).floor().max(0.0) as usize).min(x.len() - 1);
            let mut acc = 0.0;
            for (k, &xk) in x.iter().enumerate().take(k_hi + 1).skip(k_lo) {
                acc += xk * kernel.at(u - k as f64);
            }
            acc
        })
        .collect()
}

/// `rows` rows of `kernel.taps()` weights at `per_sample` phases per input sample: row `i`
/// holds `h(i / per_sample + K - t)` for tap `t`. The kernel is even, so the row of phase
/// `1 - f` is the row of phase `f` reversed (`h(1 - f + K - t) = h(f + K - (2K + 1 - t))`,
/// and `2K + 1 - t` is tap `t` counted from the end): half the rows are evaluated.
fn weights(kernel: &Kernel, rows: usize, per_sample: usize) -> Vec<f64> {
    let (lead, taps) = (kernel.lead() as f64, kernel.taps());
    let mut table = vec![0.0; rows * taps];
    for i in 0..rows {
        let (row, done) = table.split_at_mut(i * taps);
        let row_i = &mut done[..taps];
        match per_sample.checked_sub(i) {
            Some(mirror) if mirror < i => {
                let source = &row[mirror * taps..(mirror + 1) * taps];
                row_i
                    .iter_mut()
                    .zip(source.iter().rev())
                    .for_each(|(w, s)| *w = *s);
            }
            _ => {
                let f = i as f64 / per_sample as f64;
                for (t, w) in row_i.iter_mut().enumerate() {
                    *w = kernel.at(f + lead - t as f64);
                }
            }
        }
    }
    table
}

/// `x` with `lead` zeros before it and enough after it that the last output's taps fit.
fn padded(x: &[f64], lead: usize, taps: usize) -> Vec<f64> {
    let mut xp = vec![0.0; lead];
    xp.extend_from_slice(x);
    xp.resize(x.len() + lead + taps + 1, 0.0);
    xp
}

/// `sum_i a_i b_i` over four running sums (which the compiler keeps in vector registers).
fn dot(a: &[f64], b: &[f64]) -> f64 {
    let mut acc = [0.0f64; 4];
    let (ca, cb) = (a.chunks_exact(4), b.chunks_exact(4));
    let tail: f64 = ca
        .remainder()
        .iter()
        .zip(cb.remainder())
        .map(|(x, y)| x * y)
        .sum();
    for (x, y) in ca.zip(cb) {
        for i in 0..4 {
            acc[i] += x[i] * y[i];
        }
    }
    (acc[0] + acc[1]) + (acc[2] + acc[3]) + tail
}

/// `sin(pi z) / (pi z)`.
fn sinc(z: f64) -> f64 {
    if z.abs() < 1e-12 {
        1.0
    } else {
        let p = std::f64::consts::PI * z;
        p.sin() / p
    }
}

/// The modified Bessel function of the first kind of order zero, by its power series (which
/// converges for every argument; the window needs arguments up to [`KAISER_BETA`]).
fn bessel_i0(x: f64) -> f64 {
    let q = 0.25 * x * x;
    let (mut term, mut sum) = (1.0f64, 1.0f64);
    for k in 1..64 {
        term *= q / (k * k) as f64;
        sum += term;
        if term < 1e-17 * sum {
            break;
        }
    }
    sum
}

#[cfg(test)]
mod tests {
    use super::*;
    use rand::{Rng, SeedableRng};
    use rand_chacha::ChaCha8Rng;

    /// Named constant seed, so that the random records are the same on every run.
    const SEED: u64 = 50;

    /// A record of `n` samples uniform in [-1, 1].
    fn record(n: usize) -> Vec<f64> {
        let mut rng = ChaCha8Rng::seed_from_u64(SEED);
        (0..n).map(|_| rng.random_range(-1.0..=1.0)).collect()
    }

    /// The sum as the module docs write it, tap by tap, with every weight evaluated from the
    /// window and the sinc where it is used: the slow, obviously correct reference.
    fn reference(x: &[f64], fs_in: f64, fs: f64, m: usize) -> Vec<f64> {
        let r = 0.9 * (fs / fs_in).min(1.0);
        let half_width = HALF_TAPS / r;
        let i0 = bessel_i0(KAISER_BETA);
        (0..m)
            .map(|j| {
                let u = j as f64 * fs_in / fs;
                let k_lo = (u - half_width).ceil().max(0.0) as usize;
                let k_hi = ((u + half_width).floor().max(0.0) as usize).min(x.len() - 1);
                let mut acc = 0.0;
                for (k, &xk) in x.iter().enumerate().take(k_hi + 1).skip(k_lo) {
                    let d = u - k as f64;
                    let z = d / half_width;
                    let w = bessel_i0(KAISER_BETA * (1.0 - z * z).max(0.0).sqrt()) / i0;
                    acc += xk * r * sinc(r * d) * w;
                }
                acc
            })
            .collect()
    }

    /// Outputs of `n` samples at `fs_in` resampled to `fs`, as `MeasuredRecord::resampled`
    /// counts them.
    fn outputs(n: usize, fs_in: f64, fs: f64) -> usize {
        ((n - 1) as f64 / fs_in * fs + 1e-9).floor() as usize + 1
    }

    /// Each output's tolerance against the reference: with `S_j` the sum of `|x_k|` over the
    /// taps output `j` reads,
    /// - positions: both compute `d = u - k` in floating point, to within `(|u| + W + 1)
    ///   2^-51` input samples, which moves a weight by at most the slope bound times that;
    /// - weights: a kernel value carries the rounding of its sinc and of two Bessel series of
    ///   at most 64 terms each, under 200 units of 2^-53 (of `r <= 1`), in either sum;
    /// - sums: `L` terms each, at most `L 2^-53 S_j` apart;
    /// - the table plan's linear interpolation between phases `1/P` apart: `(1/P)^2 / 8` times
    ///   the curvature bound per tap, and for the (at most two) taps whose interval straddles
    ///   the kernel's edge, where its slope jumps by `edge_slope`, `edge_slope / (4 P)` times
    ///   the largest sample.
    fn tolerance(x: &[f64], fs_in: f64, fs: f64, j: usize, plan: Plan) -> f64 {
        let kernel = Kernel::new(fs_in, fs);
        let u = j as f64 * fs_in / fs;
        let w = kernel.half_width;
        let taps: Vec<f64> = x
            .iter()
            .enumerate()
            .filter(|(k, _)| (u - *k as f64).abs() <= w + 1.0)
            .map(|(_, v)| v.abs())
            .collect();
        let s: f64 = taps.iter().sum();
        let largest = taps.iter().copied().fold(0.0, f64::max);
        let eps = 2f64.powi(-53);
        let l = kernel.taps() as f64;
        let rounding =
            s * (kernel.slope_bound() * (u.abs() + w + 1.0) * 4.0 * eps + 200.0 * eps + l * eps);
        let interpolation = match plan {
            Plan::Table { phases } => {
                let step = 1.0 / phases as f64;
                s * step * step / 8.0 * kernel.curvature_bound()
                    + 2.0 * largest * kernel.edge_slope() * step / 4.0
            }
            _ => 0.0,
        };
        rounding + interpolation
    }

    /// The bounds the tolerances rest on hold: the kernel's slope and curvature, estimated by
    /// central differences on a fine grid inside the kernel, stay under them (a difference
    /// quotient of step 1e-3 differs from the derivative by under 1e-6 of the bound here).
    #[test]
    fn the_kernel_derivative_bounds_hold() {
        for (fs_in, fs) in [(1e3, 2e3), (1e3, 1e3), (5e4, 4.41e4), (1e3, 300.0)] {
            let k = Kernel::new(fs_in, fs);
            let h = 1e-3;
            let (mut h1, mut h2) = (0.0f64, 0.0f64);
            let n = 20000;
            for i in 0..=n {
                let d = -k.half_width + h + (2.0 * k.half_width - 2.0 * h) * i as f64 / n as f64;
                h1 = h1.max(((k.at(d + h) - k.at(d - h)) / (2.0 * h)).abs());
                h2 = h2.max(((k.at(d + h) - 2.0 * k.at(d) + k.at(d - h)) / (h * h)).abs());
            }
            assert!(
                h1 <= k.slope_bound(),
                "slope {h1} > bound {}",
                k.slope_bound()
            );
            assert!(
                h2 <= k.curvature_bound(),
                "curvature {h2} > {}",
                k.curvature_bound()
            );
            let edge = (k.at(k.half_width - h) / h).abs();
            assert!(
                (edge / k.edge_slope() - 1.0).abs() < 1e-2,
                "edge slope {edge:e}"
            );
        }
    }

    /// At equal rates, or rates equal within the rounding of a CSV's mean step, the resampled
    /// record is the record, sample for sample.
    #[test]
    fn equal_rates_give_the_samples() {
        let x = record(3000);
        for fs_in in [1e3, 5e4, 1.0 / (9.99998 / 499_999.0)] {
            let fs = if fs_in == 1e3 { 1e3 } else { 5e4 };
            let m = outputs(x.len(), fs_in, fs);
            assert_eq!(m, x.len());
            let plan = Plan::choose(x.len(), m, fs_in, fs);
            assert_eq!(plan, Plan::Identity, "{fs_in} to {fs}");
            assert_eq!(&resample(&x, fs_in, fs, m, plan)[..], &x[..]);
        }
    }

    /// On a random record (full band: the hardest case for the kernel's tails), each plan
    /// matches the reference sum, output by output, within the tolerance its weights and
    /// positions allow (see `tolerance`): 2x up and a non-integer rational up and down
    /// (polyphase), an irrational ratio up and down (the interpolated table).
    #[test]
    fn every_plan_matches_the_direct_sum() {
        let x = record(3000);
        // The plan each case must take: the polyphase table named, or (None) the
        // interpolated table.
        let cases = [
            (1e3, 2e3, Some(Plan::Polyphase { p: 2, q: 1 })),
            (48e3, 50e3, Some(Plan::Polyphase { p: 25, q: 24 })),
            (50e3, 44.1e3, Some(Plan::Polyphase { p: 441, q: 500 })),
            (1e3, 1e3 * 2f64.sqrt(), None),
            (1e3, 2e3 / std::f64::consts::PI, None),
        ];
        for (fs_in, fs, expected) in cases {
            let m = outputs(x.len(), fs_in, fs);
            let plan = Plan::choose(x.len(), m, fs_in, fs);
            let taken = match expected {
                Some(p) => plan == p,
                None => matches!(plan, Plan::Table { .. }),
            };
            assert!(taken, "{fs_in} to {fs}: {plan:?}");
            let fast = resample(&x, fs_in, fs, m, plan);
            let slow = reference(&x, fs_in, fs, m);
            assert_eq!(fast.len(), slow.len());
            let mut worst = 0.0f64;
            for (j, (a, b)) in fast.iter().zip(&slow).enumerate() {
                let tol = tolerance(&x, fs_in, fs, j, plan);
                assert!(
                    (a - b).abs() <= tol,
                    "{fs_in} to {fs} ({plan:?}): output {j}: {a} against {b}, tolerance {tol:e}"
                );
                worst = worst.max((a - b).abs() / tol);
            }
            eprintln!("{fs_in} to {fs} ({plan:?}): largest error {worst:.2e} of its tolerance");
        }
    }

    /// A kernel wider than twice the record (a record downsampled to a few outputs) is summed
    /// tap by tap.
    #[test]
    fn a_kernel_wider_than_the_record_is_summed_directly() {
        let x = record(100);
        let (fs_in, fs) = (1e5, 50.0);
        let m = outputs(x.len(), fs_in, fs);
        let plan = Plan::choose(x.len(), m, fs_in, fs);
        assert_eq!(plan, Plan::Direct);
        let (fast, slow) = (
            resample(&x, fs_in, fs, m, plan),
            reference(&x, fs_in, fs, m),
        );
        assert_eq!(fast.len(), slow.len());
        for (j, (a, b)) in fast.iter().zip(&slow).enumerate() {
            let tol = tolerance(&x, fs_in, fs, j, plan);
            assert!(
                (a - b).abs() <= tol,
                "output {j}: {a} against {b}, tolerance {tol:e}"
            );
        }
    }

    /// The continued fraction finds the ratio's lowest terms, and none past the phase limit.
    #[test]
    fn rational_ratios_are_found_in_lowest_terms() {
        let exact = |c: f64| move |p: u64, q: u64| (p as f64 / q as f64 - c).abs() < 1e-12;
        assert_eq!(rational(2.0, 100, exact(2.0)), Some((2, 1)));
        assert_eq!(rational(0.882, 1000, exact(0.882)), Some((441, 500)));
        assert_eq!(
            rational(100.0 / 44.1, 1000, exact(100.0 / 44.1)),
            Some((1000, 441))
        );
        assert_eq!(rational(100.0 / 44.1, 999, exact(100.0 / 44.1)), None);
        let c = 2f64.sqrt();
        assert_eq!(rational(c, MAX_PHASES as u64, exact(c)), None);
    }
}

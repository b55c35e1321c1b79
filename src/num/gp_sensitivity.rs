//! Sobol indices of an emulated output with the emulator's uncertainty (Oakley and O'Hagan
//! 2004, by sampling): the indices of the emulator's mean on a large Saltelli design (the
//! emulator costs `O(n d)` per point, so the design's own sampling error is negligible), and
//! their interval from the indices of joint draws of the emulator's posterior on a smaller
//! design (the spread of what the output could be, given the runs, plus that design's sampling
//! error).

use nalgebra::DVector;
use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;

use super::gaussian::box_muller;
use super::gp::Gp;
use super::sensitivity::{Bootstrap, Index, Saltelli, SensitivityError};
use super::stats::quantile;

/// How the emulated indices are computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct EmulatedSobol {
    /// Base rows of the design of the mean's indices (a power of two).
    pub mean_base: usize,
    /// Base rows of the design of the draws (a power of two; `base (d + 2)` points are drawn
    /// jointly, a Cholesky factor of that size).
    pub draw_base: usize,
    /// Posterior draws.
    pub draws: usize,
    /// Coverage of the interval.
    pub level: f64,
    /// Seed of the designs' scramble and of the draws.
    pub seed: u32,
}

impl Default for EmulatedSobol {
    /// 4096 base rows for the mean, 64 for 200 draws, 95 %.
    fn default() -> Self {
        Self {
            mean_base: 1 << 12,
            draw_base: 1 << 6,
            draws: 200,
            level: 0.95,
            seed: 13,
        }
    }
}

/// First-order and total indices of an emulated output: `value` of the emulator's mean,
/// `lo..hi` over its posterior draws.
#[derive(Debug, Clone, PartialEq)]
pub struct EmulatedIndices {
    /// First-order index of each input.
    pub first: Vec<Index>,
    /// Total index of each input.
    pub total: Vec<Index>,
}

/// The indices of the output emulated by `gp` over the unit cube of `d` inputs, each point
/// mapped by `input` before the emulator sees it (a switch snapped to its half); `None` when
/// the emulator's mean does not vary.
pub fn emulated_indices(
    gp: &Gp,
    d: usize,
    input: &(dyn Fn(&[f64]) -> Vec<f64> + Sync),
    s: EmulatedSobol,
) -> Result<Option<EmulatedIndices>, SensitivityError> {
    let no_boot = Bootstrap {
        resamples: 0,
        level: s.level,
        seed: 0,
    };
    let big = Saltelli::new(s.mean_base, d, s.seed)?;
    let means: Vec<f64> = big.points().iter().map(|p| gp.mean(&input(p))).collect();
    let mean = match big.indices(&means, no_boot) {
        Ok(i) => i,
        Err(SensitivityError::NoVariance) => return Ok(None),
        Err(e) => return Err(e),
    };
    let small = Saltelli::new(s.draw_base, d, s.seed.wrapping_add(1))?;
    let pts: Vec<Vec<f64>> = small.points().iter().map(|p| input(p)).collect();
    let (mu, mut cov) = gp.covariance(&pts);
    // Points that coincide once switches are snapped make the covariance singular: a jitter
    // of 1e-10 of its largest diagonal (far below any variance that matters) restores it.
    let jitter = 1e-10 * cov.diagonal().max().max(1e-300);
    for k in 0..cov.nrows() {
        cov[(k, k)] += jitter;
    }
    let Some(chol) = cov.cholesky() else {
        return Err(SensitivityError::NoVariance);
    };
    let l = chol.l();
    let mut rng = ChaCha8Rng::seed_from_u64(u64::from(s.seed));
    let mut first = vec![Vec::new(); d];
    let mut total = vec![Vec::new(); d];
    let mu = DVector::from_vec(mu);
    for _ in 0..s.draws {
        let mut z = DVector::zeros(pts.len());
        for k in (0..pts.len()).step_by(2) {
            let (a, b) = box_muller(&mut rng);
            z[k] = a;
            if k + 1 < pts.len() {
                z[k + 1] = b;
            }
        }
        let y = &mu + &l * z;
        if let Ok(ix) = small.indices(y.as_slice(), no_boot) {
            for (draws, x) in first.iter_mut().zip(&ix.first) {
                draws.push(x.value);
            }
            for (draws, x) in total.iter_mut().zip(&ix.total) {
                draws.push(x.value);
            }
        }
    }
    let tail = (1.0 - s.level) / 2.0;
    let index = |value: f64, draws: &mut Vec<f64>| {
        draws.sort_by(f64::total_cmp);
        Index {
            value,
            lo: quantile(draws, tail),
            hi: quantile(draws, 1.0 - tail),
        }
    };
    Ok(Some(EmulatedIndices {
        first: (0..d)
            .map(|i| index(mean.first[i].value, &mut first[i]))
            .collect(),
        total: (0..d)
            .map(|i| index(mean.total[i].value, &mut total[i]))
            .collect(),
    }))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::num::gp::GpSettings;

    #[test]
    fn the_emulated_indices_of_an_additive_function_are_its_own() {
        // f = x0 + 0.5 x1^2 + 0 x2 on the unit cube: additive, so first = total;
        // Var(x0) = 1/12, Var(0.5 x1^2) = 0.25 (1/5 - 1/9) = 1/45; shares 0.789 and 0.211.
        // 60 runs emulate it to 1e-3, so the mean's indices are within 0.02 and the
        // draws' interval holds them.
        let d = 3usize;
        let x: Vec<Vec<f64>> = (0..60)
            .map(|k| {
                (0..d)
                    .map(|j| f64::from(sobol_burley::sample(k, j as u32, 3)))
                    .collect()
            })
            .collect();
        let y: Vec<f64> = x.iter().map(|p| p[0] + 0.5 * p[1] * p[1]).collect();
        let gp = Gp::fit(&x, &y, &vec![0.0; 60], GpSettings::default()).unwrap();
        let ix = emulated_indices(&gp, d, &|p| p.to_vec(), EmulatedSobol::default())
            .unwrap()
            .unwrap();
        let (v0, v1) = (1.0 / 12.0, 1.0 / 45.0);
        let want = [v0 / (v0 + v1), v1 / (v0 + v1), 0.0];
        for (i, w) in want.iter().enumerate() {
            for x in [ix.first[i], ix.total[i]] {
                assert!((x.value - w).abs() < 0.02, "{i}: {x:?} vs {w}");
                assert!(x.lo <= w + 0.02 && w - 0.02 <= x.hi, "{i}: {x:?}");
            }
        }
    }
}

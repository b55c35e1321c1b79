//! The search for a non-implausible point between the pool's points: Nelder-Mead on the
//! emulators' cut statistic, written here in a few lines (the statistic is a cheap closure
//! over the waves, and argmin's solver would need a problem type for it).

use super::HistoryMatch;

impl HistoryMatch {
    /// A non-implausible point found by minimising the statistic from `x0` (at most 400
    /// Nelder-Mead iterations inside the cube), if any.
    pub(super) fn descend(&self, x0: &[f64]) -> Option<Vec<f64>> {
        let cost = |x: &[f64]| {
            let inside: Vec<f64> = x.iter().map(|u| u.clamp(0.0, 1.0)).collect();
            // Outside the cube: the clamped point's statistic plus the distance, so the
            // simplex turns back.
            let out: f64 = x.iter().map(|u| (u - u.clamp(0.0, 1.0)).abs()).sum();
            (self.statistics(&inside).0 + 10.0 * out, inside)
        };
        let d = x0.len();
        let mut simplex: Vec<(f64, Vec<f64>)> = (0..=d)
            .map(|k| {
                let mut x = x0.to_vec();
                if k > 0 {
                    x[k - 1] += if x[k - 1] < 0.5 { 0.05 } else { -0.05 };
                }
                (cost(&x).0, x)
            })
            .collect();
        for _ in 0..400 {
            simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
            if simplex[0].0 <= self.settings.cut {
                return Some(cost(&simplex[0].1).1);
            }
            let centroid: Vec<f64> = (0..d)
                .map(|j| simplex[..d].iter().map(|s| s.1[j]).sum::<f64>() / d as f64)
                .collect();
            let along = |t: f64| -> Vec<f64> {
                centroid
                    .iter()
                    .zip(&simplex[d].1)
                    .map(|(c, w)| c + t * (w - c))
                    .collect()
            };
            let r = along(-1.0);
            let fr = cost(&r).0;
            if fr < simplex[0].0 {
                let e = along(-2.0);
                let fe = cost(&e).0;
                simplex[d] = if fe < fr { (fe, e) } else { (fr, r) };
            } else if fr < simplex[d - 1].0 {
                simplex[d] = (fr, r);
            } else {
                let c = along(0.5);
                let fc = cost(&c).0;
                if fc < simplex[d].0 {
                    simplex[d] = (fc, c);
                } else {
                    let best = simplex[0].1.clone();
                    for s in simplex.iter_mut().skip(1) {
                        s.1 =
                            s.1.iter()
                                .zip(&best)
                                .map(|(x, b)| b + 0.5 * (x - b))
                                .collect();
                        s.0 = cost(&s.1).0;
                    }
                }
            }
        }
        simplex.sort_by(|a, b| a.0.total_cmp(&b.0));
        (simplex[0].0 <= self.settings.cut).then(|| cost(&simplex[0].1).1)
    }
}

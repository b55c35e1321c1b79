//! Space-filling designs over the unit cube: the maximin Latin hypercube of wave 1 and the
//! maximin subset of the non-implausible points that later waves run.

use rand::Rng;
use rand_chacha::ChaCha8Rng;

fn min_distance(points: &[Vec<f64>]) -> f64 {
    let mut best = f64::INFINITY;
    for (a, p) in points.iter().enumerate() {
        for q in &points[a + 1..] {
            best = best.min(p.iter().zip(q).map(|(x, y)| (x - y).powi(2)).sum::<f64>());
        }
    }
    best.sqrt()
}

/// The Latin hypercube of `n` points over `dim` inputs with the largest least distance
/// between its points, among 100 random ones.
pub fn maximin_lhs(n: usize, dim: usize, rng: &mut ChaCha8Rng) -> Vec<Vec<f64>> {
    let mut best: Option<(f64, Vec<Vec<f64>>)> = None;
    for _ in 0..100 {
        let mut pts = vec![vec![0.0; dim]; n];
        for d in 0..dim {
            let mut perm: Vec<usize> = (0..n).collect();
            for k in (1..n).rev() {
                perm.swap(k, rng.random_range(0..=k));
            }
            for (p, s) in pts.iter_mut().zip(perm) {
                p[d] = (s as f64 + rng.random::<f64>()) / n as f64;
            }
        }
        let m = min_distance(&pts);
        if best.as_ref().is_none_or(|b| m > b.0) {
            best = Some((m, pts));
        }
    }
    best.map(|b| b.1).unwrap_or_default()
}

/// `n` of `points` chosen greedily to spread them: the first point, then each time the point
/// farthest from those chosen (all of them when there are at most `n`).
pub fn maximin_subset(points: &[Vec<f64>], n: usize) -> Vec<Vec<f64>> {
    if points.len() <= n {
        return points.to_vec();
    }
    let d2 = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| (x - y).powi(2)).sum::<f64>();
    let mut chosen = vec![0usize];
    let mut near: Vec<f64> = points.iter().map(|p| d2(p, &points[0])).collect();
    while chosen.len() < n {
        let (k, _) = near
            .iter()
            .enumerate()
            .max_by(|a, b| a.1.total_cmp(b.1))
            .expect("points");
        chosen.push(k);
        for (m, p) in points.iter().enumerate() {
            near[m] = near[m].min(d2(p, &points[k]));
        }
    }
    chosen.into_iter().map(|k| points[k].clone()).collect()
}

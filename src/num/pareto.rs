//! Pareto fronts: the points of a set of pairs that no other point beats on both coordinates.

/// Indices of the non-dominated points of `points` (minimising both coordinates; ties keep
/// the first), by increasing first coordinate.
pub fn pareto_front(points: &[(f64, f64)]) -> Vec<usize> {
    let mut order: Vec<usize> = (0..points.len()).collect();
    order.sort_by(|&i, &j| {
        points[i]
            .0
            .total_cmp(&points[j].0)
            .then(points[i].1.total_cmp(&points[j].1))
            .then(i.cmp(&j))
    });
    let mut front = Vec::new();
    let mut best_b = f64::INFINITY;
    for i in order {
        if points[i].1 < best_b {
            best_b = points[i].1;
            front.push(i);
        }
    }
    front
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_pareto_front_keeps_the_non_dominated_points() {
        let pts = [
            (3.0, 1.0),
            (1.0, 3.0),
            (2.0, 2.0),
            (2.5, 2.5),
            (1.0, 4.0),
            (4.0, 1.0),
        ];
        // (2.5, 2.5) is beaten by (2, 2); (1, 4) by (1, 3); (4, 1) by (3, 1).
        assert_eq!(pareto_front(&pts), vec![1, 2, 0]);
        assert!(pareto_front(&[]).is_empty());
    }
}

//! Thinning a dense line to what a pixel column can show: of the points that fall in one
//! column, a line drawn through the first, the lowest, the highest and the last (in their
//! order) covers the same pixels of that column as the line through all of them, and joins
//! its neighbours at the same points. A one-sample spike is a column's highest point: it
//! stays. (The scheme is the "M4" aggregation of Jugel et al. 2014, "M4: a
//! visualization-oriented time series data aggregation", Proc. VLDB Endowment 7(10).)

/// The points of the polyline `points` to draw: of each run of consecutive points whose
/// `column` (their pixel column) is the same, the first, the lowest, the highest and the
/// last, in their order; a run of up to four points is kept whole.
pub fn min_max_per_column(
    points: &[(f64, f64)],
    column: impl Fn((f64, f64)) -> i32,
) -> Vec<(f64, f64)> {
    let mut kept = Vec::new();
    let mut start = 0;
    while start < points.len() {
        let col = column(points[start]);
        let len = points[start..]
            .iter()
            .position(|&p| column(p) != col)
            .unwrap_or(points.len() - start);
        let run = &points[start..start + len];
        if len <= 4 {
            kept.extend_from_slice(run);
        } else {
            let by_y = |a: &&(f64, f64), b: &&(f64, f64)| a.1.total_cmp(&b.1);
            let lo = run.iter().enumerate().min_by(|a, b| by_y(&a.1, &b.1));
            let hi = run.iter().enumerate().max_by(|a, b| by_y(&a.1, &b.1));
            let (lo, hi) = (lo.map_or(0, |m| m.0), hi.map_or(0, |m| m.0));
            let mut at = [0, lo.min(hi), lo.max(hi), len - 1];
            at.sort_unstable();
            let mut last = None;
            for i in at {
                if last != Some(i) {
                    kept.push(run[i]);
                    last = Some(i);
                }
            }
        }
        start += len;
    }
    kept
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Columns of ten points each (x in units of a tenth of a column).
    fn column(p: (f64, f64)) -> i32 {
        (p.0 / 10.0).floor() as i32
    }

    /// A spike of one sample among 10 000 survives the thinning at its full height (and a dip
    /// at its full depth); every column keeps at most four points, its first and its last.
    #[test]
    fn a_spike_of_one_sample_survives() {
        let mut pts: Vec<(f64, f64)> = (0..10_000)
            .map(|k| (k as f64, (k as f64 * 0.01).sin()))
            .collect();
        pts[4321].1 = 50.0;
        pts[7777].1 = -50.0;
        let kept = min_max_per_column(&pts, column);
        assert!(kept.len() <= 4 * 1000, "{}", kept.len());
        assert!(kept.contains(&pts[4321]), "the spike");
        assert!(kept.contains(&pts[7777]), "the dip");
        for c in 0..1000 {
            let run = &pts[10 * c..10 * c + 10];
            let in_col: Vec<_> = kept.iter().filter(|p| column(**p) == c as i32).collect();
            assert!(in_col.len() <= 4);
            assert_eq!(*in_col[0], run[0]);
            assert_eq!(**in_col.last().unwrap(), run[9]);
            // The same extent in y as the column's points.
            let ext = |v: &mut dyn Iterator<Item = f64>| {
                v.fold((f64::MAX, f64::MIN), |(lo, hi), y| (lo.min(y), hi.max(y)))
            };
            assert_eq!(
                ext(&mut in_col.iter().map(|p| p.1)),
                ext(&mut run.iter().map(|p| p.1))
            );
        }
        // The kept points are in their order.
        assert!(kept.windows(2).all(|w| w[0].0 < w[1].0));
    }

    /// Sparse points (a run of at most four per column) are kept as they are.
    #[test]
    fn sparse_points_are_kept() {
        let pts: Vec<(f64, f64)> = (0..100).map(|k| (k as f64 * 2.5, k as f64)).collect();
        assert_eq!(min_max_per_column(&pts, column), pts);
        assert!(min_max_per_column(&[], column).is_empty());
    }
}

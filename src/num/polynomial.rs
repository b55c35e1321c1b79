//! Two small polynomial facts the integrators use on every step: the real roots of a quadratic
//! without cancellation, and the range of a cubic Hermite interpolant over its interval (where
//! a sampled trajectory may have gone between two samples).

/// The real roots of `a u² + b u + c`, `None` where there is none: the root of larger
/// magnitude as `q / a` with `q = -(b + sign(b) sqrt(b² - 4ac)) / 2` and the other as `c / q`,
/// so neither loses digits to cancellation (Press et al., Numerical Recipes, 3rd ed., §5.6);
/// the one root `-c / b` of a linear equation (`a = 0`).
///
/// ```
/// use endstop::num::polynomial::quadratic_roots;
/// // u² - 3u + 2 = (u - 1)(u - 2).
/// assert_eq!(quadratic_roots(1.0, -3.0, 2.0), [Some(2.0), Some(1.0)]);
/// assert_eq!(quadratic_roots(0.0, 2.0, -1.0), [Some(0.5), None]);
/// assert_eq!(quadratic_roots(1.0, 0.0, 1.0), [None, None]);
/// ```
#[inline]
pub fn quadratic_roots(a: f64, b: f64, c: f64) -> [Option<f64>; 2] {
    if a == 0.0 {
        let linear = if b != 0.0 { Some(-c / b) } else { None };
        return [linear, None];
    }
    let disc = b * b - 4.0 * a * c;
    if disc < 0.0 {
        return [None, None];
    }
    let q = -0.5 * (b + b.signum() * disc.sqrt());
    let other = if q != 0.0 { Some(c / q) } else { None };
    [Some(q / a), other]
}

/// The smallest and the largest value over `0 <= θ <= 1` of the cubic Hermite interpolant
/// with end values `x0`, `x1` and end slopes (times the interval) `m0`, `m1`: the larger of
/// the ends and of its interior extrema, the roots of its derivative in `(0, 1)`.
///
/// ```
/// use endstop::num::polynomial::hermite_range;
/// // θ(1 - θ) scaled: ends 0, slopes 1 and -1 -> the cubic 0 + θ - θ², largest 1/4 at θ = 1/2.
/// let (lo, hi) = hermite_range(0.0, 1.0, 0.0, -1.0);
/// assert_eq!(lo, 0.0);
/// assert!((hi - 0.25).abs() < 1e-15);
/// ```
#[inline]
pub fn hermite_range(x0: f64, m0: f64, x1: f64, m1: f64) -> (f64, f64) {
    // p(θ) = x0 + m0 θ + b θ² + c θ³, p'(θ) = m0 + 2 b θ + 3 c θ².
    let b = 3.0 * (x1 - x0) - 2.0 * m0 - m1;
    let c = 2.0 * (x0 - x1) + m0 + m1;
    let p = |th: f64| x0 + th * (m0 + th * (b + th * c));
    let (mut min, mut max) = (x0.min(x1), x0.max(x1));
    for th in quadratic_roots(3.0 * c, 2.0 * b, m0).into_iter().flatten() {
        if th > 0.0 && th < 1.0 {
            let v = p(th);
            max = max.max(v);
            min = min.min(v);
        }
    }
    (min, max)
}

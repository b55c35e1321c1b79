//! Butcher tableaus of explicit Runge-Kutta methods, as data: the nodes `c`, the stage
//! coefficients `a`, the weights `b`, and where the method has them the embedded error weights
//! and the dense-output coefficients (the layout of Hairer, Norsett and Wanner's codes and of
//! diffsol's tableaus).
//!
//! A method is a type implementing [`Method`], whose tableau is an associated constant: the
//! drivers ([`crate::ode::Adaptive`], [`crate::ode::FixedStep`]) are compiled once per method,
//! so that every coefficient is a constant the compiler folds into the stage sums and every
//! zero coefficient drops out of them (the stage sums are in `runge_kutta.rs`).

/// The tableau of an explicit `S`-stage Runge-Kutta method (`a` strictly lower triangular).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Tableau<const S: usize> {
    /// Nodes: stage `i` is evaluated at `t + c[i] h` (`c[0] = 0`).
    pub c: [f64; S],
    /// Stage coefficients: stage `i` at `y + h sum_{j<i} a[i][j] k_j`.
    pub a: [[f64; S]; S],
    /// Weights of the step: `y1 = y + h sum_j b[j] k_j`.
    pub b: [f64; S],
    /// Error weights `b - b_hat` of an embedded method: the local error estimate is
    /// `h sum_j error[j] k_j`. None for a method without an error estimate.
    pub error: Option<[f64; S]>,
    /// Order of the error estimate's leading term less one (the lower order of the pair): the
    /// step-size rule scales the step by `err^(-1/(error_order + 1))`.
    pub error_order: u32,
    /// Dense-output coefficients `d` in the form of Hairer's DOPRI5 (`contd5`): over the step,
    /// `y(t0 + theta h)` is the cubic Hermite interpolant of `y0, y1, f0, f1` plus
    /// `theta^2 (1 - theta)^2 h sum_j d[j] k_j`. It needs the last stage to be `f(t1, y1)`
    /// ([`Tableau::is_fsal`]). None for a method without dense output.
    pub dense: Option<[f64; S]>,
}

impl<const S: usize> Tableau<S> {
    /// Whether the last stage is evaluated at the step's end state (first same as last): its
    /// row of `a` is `b` and its node is 1, so it is the derivative at the start of the next
    /// step.
    pub const fn is_fsal(&self) -> bool {
        if S == 0 || self.c[S - 1] != 1.0 {
            return false;
        }
        let mut j = 0;
        while j < S {
            if self.a[S - 1][j] != self.b[j] {
                return false;
            }
            j += 1;
        }
        true
    }
}

/// An explicit Runge-Kutta method: a type that names a tableau.
pub trait Method<const S: usize> {
    /// The method's tableau.
    const TABLEAU: Tableau<S>;
}

/// The Dormand-Prince 5(4) pair (Dormand and Prince, J. Comput. Appl. Math. 6, 1980) with the
/// 4th-order dense output of Hairer, Norsett and Wanner (Solving Ordinary Differential
/// Equations I, 2nd ed., section II.6; the coefficients of their DOPRI5 code): seven stages,
/// the last first-same-as-last.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DormandPrince54;

impl Method<7> for DormandPrince54 {
    const TABLEAU: Tableau<7> = Tableau {
        c: [0.0, 1.0 / 5.0, 3.0 / 10.0, 4.0 / 5.0, 8.0 / 9.0, 1.0, 1.0],
        a: [
            [0.0; 7],
            [1.0 / 5.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [3.0 / 40.0, 9.0 / 40.0, 0.0, 0.0, 0.0, 0.0, 0.0],
            [44.0 / 45.0, -56.0 / 15.0, 32.0 / 9.0, 0.0, 0.0, 0.0, 0.0],
            [
                19372.0 / 6561.0,
                -25360.0 / 2187.0,
                64448.0 / 6561.0,
                -212.0 / 729.0,
                0.0,
                0.0,
                0.0,
            ],
            [
                9017.0 / 3168.0,
                -355.0 / 33.0,
                46732.0 / 5247.0,
                49.0 / 176.0,
                -5103.0 / 18656.0,
                0.0,
                0.0,
            ],
            DP5_B,
        ],
        b: DP5_B,
        error: Some([
            71.0 / 57600.0,
            0.0,
            -71.0 / 16695.0,
            71.0 / 1920.0,
            -17253.0 / 339200.0,
            22.0 / 525.0,
            -1.0 / 40.0,
        ]),
        error_order: 4,
        dense: Some([
            -12715105075.0 / 11282082432.0,
            0.0,
            87487479700.0 / 32700410799.0,
            -10690763975.0 / 1880347072.0,
            701980252875.0 / 199316789632.0,
            -1453857185.0 / 822651844.0,
            69997945.0 / 29380423.0,
        ]),
    };
}

/// The 5th-order weights of Dormand-Prince 5(4), which are also its last stage's row.
const DP5_B: [f64; 7] = [
    35.0 / 384.0,
    0.0,
    500.0 / 1113.0,
    125.0 / 192.0,
    -2187.0 / 6784.0,
    11.0 / 84.0,
    0.0,
];

/// The classical 4th-order Runge-Kutta method (Kutta 1901): four stages, no error estimate,
/// no dense output; for fixed steps ([`crate::ode::FixedStep`]).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct ClassicalRk4;

impl Method<4> for ClassicalRk4 {
    const TABLEAU: Tableau<4> = Tableau {
        c: [0.0, 0.5, 0.5, 1.0],
        a: [
            [0.0; 4],
            [0.5, 0.0, 0.0, 0.0],
            [0.0, 0.5, 0.0, 0.0],
            [0.0, 0.0, 1.0, 0.0],
        ],
        b: [1.0 / 6.0, 1.0 / 3.0, 1.0 / 3.0, 1.0 / 6.0],
        error: None,
        error_order: 0,
        dense: None,
    };
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Checks the order conditions up to order `p` that a quadrature and the simplest tree of
    /// each order give: `sum b c^(q-1) = 1/q` and `sum b A c^(q-2) = 1/(q (q-1))`, and that the
    /// rows of `a` sum to `c`.
    fn check<const S: usize>(t: &Tableau<S>, p: i32) {
        for i in 0..S {
            let row: f64 = t.a[i].iter().sum();
            assert!(
                (row - t.c[i]).abs() < 1e-14,
                "row {i}: {row} vs c = {}",
                t.c[i]
            );
            for j in i..S {
                assert_eq!(t.a[i][j], 0.0, "a[{i}][{j}] above the diagonal");
            }
        }
        for q in 1..=p {
            let quad: f64 = (0..S).map(|j| t.b[j] * t.c[j].powi(q - 1)).sum();
            assert!(
                (quad - 1.0 / q as f64).abs() < 1e-14,
                "quadrature order {q}"
            );
            if q >= 2 {
                let tree: f64 = (0..S)
                    .map(|i| t.b[i] * (0..S).map(|j| t.a[i][j] * t.c[j].powi(q - 2)).sum::<f64>())
                    .sum();
                let want = 1.0 / (q * (q - 1)) as f64;
                assert!((tree - want).abs() < 1e-14, "tree of order {q}");
            }
        }
    }

    #[test]
    fn dormand_prince_is_of_order_five_with_a_consistent_error_estimate() {
        let t = DormandPrince54::TABLEAU;
        check(&t, 5);
        assert!(t.is_fsal());
        // The embedded method is consistent too: its weights b - error sum to one.
        let e = t.error.unwrap();
        assert!(e.iter().sum::<f64>().abs() < 1e-15);
        // The dense output's correction vanishes for y' = 1 (every stage 1): the Hermite cubic
        // is already exact there.
        assert!(t.dense.unwrap().iter().sum::<f64>().abs() < 1e-14);
    }

    #[test]
    fn classical_rk4_is_of_order_four() {
        let t = ClassicalRk4::TABLEAU;
        check(&t, 4);
        assert!(!t.is_fsal());
    }
}

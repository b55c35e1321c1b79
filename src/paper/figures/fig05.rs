//! Figure 5: the Hertz line-contact law (eq 6) in normalised form, delta0 of both prototypes
//! (claim F5-a), and the linear end-stop stiffness of eq 19 (claim F5-b).

use std::convert::Infallible;

use crate::device::Device;
use crate::laws::hertz::{
    normalised_delta, HertzLine, LinearFits, EQ19_FIT_RANGE_M, EQ19_FIT_SAMPLES,
};
use crate::paper::claims::{keys, Claims, ClaimsError, Value};
use crate::paper::setups::{hertz_stop, with_hertz, ParamSet, Prototypes};
use crate::paper::Figure;
use crate::progress::Progress;

/// Samples of the normalised curve of Figure 5, uniform in the normalised force.
pub const CURVE_SAMPLES: usize = 2001;

/// Largest normalised force F/F0 of the curve.
pub const CURVE_MAX_FORCE: f64 = 0.02;

/// Elastic constants (E in Pa, nu) of the sensitivity table: the usual range of silicon's
/// in-plane modulus and Poisson ratio, with the parameter files' 169 GPa and 0.22.
pub const ELASTIC_CONSTANTS: [(f64, f64); 5] = [
    (130e9, 0.28),
    (150e9, 0.17),
    (169e9, 0.22),
    (169e9, 0.064),
    (188e9, 0.26),
];

/// The coefficient of one reading of the fit, read from a [`LinearFits`].
pub type Coefficient = fn(&LinearFits) -> f64;

/// The readings of "least-squares fit over 0-0.5 um" behind eq 19's coefficient, in table
/// order: label and coefficient.
pub const FIT_READINGS: [(&str, Coefficient); 5] = [
    ("least squares through origin, uniform in delta", |f| {
        f.through_origin
    }),
    ("least squares with intercept (slope)", |f| f.with_intercept),
    ("secant F(0.5 um)/0.5 um", |f| f.secant),
    ("least squares through origin, uniform in force", |f| {
        f.force_sampled
    }),
    ("least squares of delta on F (errors in delta)", |f| {
        f.inverse
    }),
];

/// One prototype's contact law and eq 19 fits.
#[derive(Debug, Clone, PartialEq)]
pub struct Prototype {
    /// `prototype 1` or `prototype 2`.
    pub label: &'static str,
    /// The contact law (eq 6).
    pub hertz: HertzLine,
    /// The eq 19 coefficient under every reading of the fit, over 0-0.5 um.
    pub fits: LinearFits,
    /// The parameter file's linear end-stop stiffness of eq 19 (N/m).
    pub k_im_n_per_m: f64,
}

impl Prototype {
    /// The linear stiffness `c t / lambda` (N/m) of an eq 19 coefficient `c`.
    pub fn stiffness_of_coefficient(&self, c: f64) -> f64 {
        c * self.hertz.length_m / self.hertz.lambda_per_pa
    }

    /// The fit range 0.5 um in units of delta0.
    pub fn fit_range_over_delta0(&self) -> f64 {
        EQ19_FIT_RANGE_M / self.hertz.delta_scale_m()
    }

    /// The eq 19 line of coefficient `c` over the fit range in Figure 5's normalised units:
    /// `k = c t/lambda` and `F0/delta0 = t/(2 lambda)`, so `F/F0 = 2 c delta/delta0`.
    pub fn normalised_eq19_line(&self, c: f64) -> [(f64, f64); 2] {
        let d = self.fit_range_over_delta0();
        [(0.0, 0.0), (d, 2.0 * c * d)]
    }
}

/// The sensitivity of eq 19's stiffness to the elastic constants (prototype 1).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sensitivity {
    /// Young's modulus (Pa).
    pub youngs_modulus_pa: f64,
    /// Poisson ratio.
    pub poisson_ratio: f64,
    /// k_im of eq 19 (N/m).
    pub k_im_n_per_m: f64,
    /// Relative to the parameter file's k_im.
    pub relative: f64,
}

/// Figure 5's numbers.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    /// The normalised law d = f (1 - ln f): (delta/delta0, F/F0).
    pub curve: Vec<(f64, f64)>,
    /// Prototypes 1 and 2.
    pub prototypes: [Prototype; 2],
    /// k_im of prototype 1 over [`ELASTIC_CONSTANTS`].
    pub sensitivity: Vec<Sensitivity>,
}

/// Evaluates Figure 5 for the two prototypes' parameter files.
fn evaluate(prototype1: &Device, prototype2: &Device) -> Run {
    let curve = (0..CURVE_SAMPLES)
        .map(|i| {
            let f = CURVE_MAX_FORCE * i as f64 / (CURVE_SAMPLES - 1) as f64;
            (normalised_delta(f), f)
        })
        .collect();
    let prototype = |label, d: &Device| {
        let hertz = HertzLine::of_stop(hertz_stop(d));
        Prototype {
            label,
            hertz,
            fits: hertz.linear_fits(EQ19_FIT_RANGE_M, EQ19_FIT_SAMPLES),
            k_im_n_per_m: hertz_stop(d).linear_stiffness_n_per_m(),
        }
    };
    let k_ref = hertz_stop(prototype1).linear_stiffness_n_per_m();
    let sensitivity = ELASTIC_CONSTANTS
        .iter()
        .map(|&(e, nu)| {
            let d = with_hertz(prototype1, |h| {
                h.youngs_modulus_pa = e;
                h.poisson_ratio = nu;
            });
            let k = hertz_stop(&d).linear_stiffness_n_per_m();
            Sensitivity {
                youngs_modulus_pa: e,
                poisson_ratio: nu,
                k_im_n_per_m: k,
                relative: k / k_ref,
            }
        })
        .collect();
    Run {
        curve,
        prototypes: [
            prototype("prototype 1", prototype1),
            prototype("prototype 2", prototype2),
        ],
        sensitivity,
    }
}

/// Figure 5: the normalised Hertz law, delta0 of both prototypes and eq 19's coefficient.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Fig05;

impl Figure for Fig05 {
    const NAME: &'static str = "fig05";
    type Setup = Prototypes;
    type Run = Run;
    type Error = Infallible;

    fn work(_: &Prototypes) -> usize {
        0
    }

    /// Evaluates Figure 5 for the two prototypes' parameter files (no simulation).
    fn run(setup: &Prototypes, _: &dyn Progress) -> Result<Run, Infallible> {
        Ok(evaluate(&setup.prototype1, &setup.prototype2))
    }

    /// Claims F5-a (delta0 = t²/R of both prototypes) and F5-b (eq 19's coefficient under our
    /// reading of "least-squares fit": a line through the origin fitted to eq 6 sampled
    /// uniformly in delta over 0-0.5 um, for prototype 1, whose Figure 8 first used it).
    fn claims(run: &Run, claims: &Claims) -> Result<Vec<Value>, ClaimsError> {
        let [p1, p2] = &run.prototypes;
        let set = ParamSet::Published;
        claims.known(vec![
            Value::new(
                keys::F5A_DELTA0_P1,
                set,
                p1.hertz.delta_scale_m() * 1e6,
                None,
                "t^2/R from Table 1",
            ),
            Value::new(
                keys::F5A_DELTA0_P2,
                set,
                p2.hertz.delta_scale_m() * 1e6,
                None,
                "t^2/R from Table 1",
            ),
            Value::new(
                keys::F5B_EQ19_COEFFICIENT,
                set,
                p1.fits.paper_reading(),
                None,
                "least squares through the origin, uniform in delta, prototype 1",
            ),
        ])
    }
}

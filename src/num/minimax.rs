//! Multi-start minimax fitting on the unit cube: find the point where the worst of several
//! normalised deviations is smallest.
//!
//! The caller's model maps a point of `[0, 1]^d` to deviations `d_j = (ours_j - target_j) /
//! tolerance_j`; a point meets every target when `max_j |d_j| <= 1`. The objective
//! `max_j |d_j|` is not smooth (its minimum sits where two deviations cross), so a
//! derivative-free method is used: argmin's Nelder-Mead, from several starts taken from an
//! Owen-scrambled Sobol sequence (deterministic, spread over the cube), run in parallel with the
//! results kept in start order. The box is kept by evaluating the model at the point clamped to
//! the cube and adding the distance outside it to the objective, so the simplex is pushed back
//! without the model ever seeing an invalid point.

use argmin::core::{CostFunction, Error as ArgminError, Executor, State};
use argmin::solver::neldermead::NelderMead;
use rayon::prelude::*;

/// How the search runs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MinimaxSettings {
    /// Number of starts (Sobol points of the cube).
    pub starts: usize,
    /// Iteration cap of each Nelder-Mead run.
    pub max_iters: u64,
    /// Edge of the initial simplex, in unit-cube coordinates.
    pub simplex_size: f64,
    /// Stop when the standard deviation of the simplex's objective values is below this.
    pub sd_tolerance: f64,
    /// Scramble of the start sequence.
    pub seed: u32,
}

impl Default for MinimaxSettings {
    fn default() -> Self {
        Self {
            starts: 8,
            max_iters: 400,
            simplex_size: 0.15,
            sd_tolerance: 1e-6,
            seed: 0,
        }
    }
}

/// The result of one start.
#[derive(Debug, Clone, PartialEq)]
pub struct Fit {
    /// Index of the start.
    pub start: usize,
    /// Best point found (inside the cube).
    pub point: Vec<f64>,
    /// The deviations at that point.
    pub deviations: Vec<f64>,
    /// `max_j |d_j|` at that point.
    pub worst: f64,
    /// Nelder-Mead iterations taken.
    pub iterations: u64,
    /// Model evaluations that failed (scored as infinitely bad).
    pub failures: usize,
}

/// Why the search could not run.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum MinimaxError {
    /// Settings out of range.
    #[error("minimax settings: {0}")]
    Settings(String),
    /// The optimiser failed on a start.
    #[error("Nelder-Mead failed on start {start}: {message}")]
    Solver {
        /// Index of the start.
        start: usize,
        /// The optimiser's message.
        message: String,
    },
    /// No start reached a point where the model could be evaluated.
    #[error("the model failed at every point the search tried")]
    NoEvaluation,
}

/// The worst absolute deviation.
pub fn worst(deviations: &[f64]) -> f64 {
    deviations
        .iter()
        .map(|d| if d.is_nan() { f64::INFINITY } else { d.abs() })
        .fold(0.0, f64::max)
}

struct Objective<'a, F> {
    model: &'a F,
    failures: &'a std::sync::atomic::AtomicUsize,
}

impl<F, E> CostFunction for Objective<'_, F>
where
    F: Fn(&[f64]) -> Result<Vec<f64>, E>,
{
    type Param = Vec<f64>;
    type Output = f64;

    fn cost(&self, p: &Vec<f64>) -> Result<f64, ArgminError> {
        let clamped: Vec<f64> = p.iter().map(|u| u.clamp(0.0, 1.0)).collect();
        let outside: f64 = p.iter().zip(&clamped).map(|(u, c)| (u - c).abs()).sum();
        Ok(match (self.model)(&clamped) {
            Ok(d) => worst(&d) + outside,
            Err(_) => {
                self.failures
                    .fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                f64::INFINITY
            }
        })
    }
}

/// The starts of [`minimise_worst`], in start order: the `given` points (e.g. the published
/// point), then `settings.starts` points of the scrambled Sobol sequence. Checks the settings.
pub fn starts(
    dims: usize,
    settings: MinimaxSettings,
    given: &[Vec<f64>],
) -> Result<Vec<Vec<f64>>, MinimaxError> {
    if let Some(bad) = given
        .iter()
        .find(|g| g.len() != dims || g.iter().any(|u| !(0.0..=1.0).contains(u)))
    {
        return Err(MinimaxError::Settings(format!(
            "a given start must be a point of the unit cube of {dims} dimensions, got {bad:?}"
        )));
    }
    let total = settings.starts + given.len();
    if dims == 0 || dims > 256 || total == 0 || total > 1 << 16 {
        return Err(MinimaxError::Settings(format!(
            "need 1..=256 dimensions and 1..=65536 starts, got {dims} and {total}"
        )));
    }
    if !(settings.simplex_size > 0.0 && settings.simplex_size <= 0.5) {
        return Err(MinimaxError::Settings(format!(
            "simplex_size = {} must be in (0, 0.5]",
            settings.simplex_size
        )));
    }
    let sobol = (0..settings.starts).map(|i| {
        (0..dims)
            .map(|d| f64::from(sobol_burley::sample(i as u32, d as u32, settings.seed)))
            .collect::<Vec<f64>>()
    });
    Ok(given.iter().cloned().chain(sobol).collect())
}

/// Minimises `max_j |model(u)_j|` over `u` in `[0, 1]^dims` from the [`starts`] (the `given`
/// points, then `settings.starts` points of the scrambled Sobol sequence); returns every
/// start's fit, best first (ties kept in start order; start `i < given.len()` is `given[i]`).
/// The starts run in parallel; [`minimise_from`] runs one (e.g. as one task of a cluster).
pub fn minimise_worst<F, E>(
    dims: usize,
    model: F,
    settings: MinimaxSettings,
    given: &[Vec<f64>],
) -> Result<Vec<Fit>, MinimaxError>
where
    F: Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
{
    let fits = starts(dims, settings, given)?
        .into_par_iter()
        .enumerate()
        .map(|(start, x0)| run_start(dims, &model, settings, start, x0))
        .collect::<Result<Vec<_>, _>>()?;
    best_first(fits)
}

/// One start of [`minimise_worst`]: the Nelder-Mead search from `x0` (start number `start`,
/// a point of [`starts`]) with `settings`' simplex, iterations and tolerance.
pub fn minimise_from<F, E>(
    model: F,
    settings: MinimaxSettings,
    start: usize,
    x0: Vec<f64>,
) -> Result<Fit, MinimaxError>
where
    F: Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
{
    let dims = x0.len();
    starts(
        dims,
        MinimaxSettings {
            starts: 0,
            ..settings
        },
        std::slice::from_ref(&x0),
    )?;
    run_start(dims, &model, settings, start, x0)
}

/// The fits of several starts, best first (ties in start order), without the starts at
/// which the model never evaluated; the error when no start did.
pub fn best_first(mut fits: Vec<Fit>) -> Result<Vec<Fit>, MinimaxError> {
    fits.retain(|f| f.worst.is_finite());
    if fits.is_empty() {
        return Err(MinimaxError::NoEvaluation);
    }
    fits.sort_by(|a, b| a.worst.total_cmp(&b.worst).then(a.start.cmp(&b.start)));
    Ok(fits)
}

fn run_start<F, E>(
    dims: usize,
    model: &F,
    s: MinimaxSettings,
    start: usize,
    x0: Vec<f64>,
) -> Result<Fit, MinimaxError>
where
    F: Fn(&[f64]) -> Result<Vec<f64>, E> + Sync,
{
    let fail = |e: ArgminError| MinimaxError::Solver {
        start,
        message: e.to_string(),
    };
    // The simplex: the start and one step along each axis, stepping inwards near a face.
    let mut simplex = vec![x0.clone()];
    for d in 0..dims {
        let mut v = x0.clone();
        v[d] += if v[d] + s.simplex_size <= 1.0 {
            s.simplex_size
        } else {
            -s.simplex_size
        };
        simplex.push(v);
    }
    let failures = std::sync::atomic::AtomicUsize::new(0);
    let objective = Objective {
        model,
        failures: &failures,
    };
    let solver = NelderMead::new(simplex)
        .with_sd_tolerance(s.sd_tolerance)
        .map_err(fail)?;
    let result = Executor::new(objective, solver)
        .configure(|state| state.max_iters(s.max_iters))
        .run()
        .map_err(fail)?;
    let state = result.state();
    let best = state
        .get_best_param()
        .cloned()
        .unwrap_or(x0)
        .iter()
        .map(|u| u.clamp(0.0, 1.0))
        .collect::<Vec<_>>();
    let iterations = state.get_iter();
    let deviations = model(&best).unwrap_or_default();
    let worst = if deviations.is_empty() {
        f64::INFINITY
    } else {
        worst(&deviations)
    };
    Ok(Fit {
        start,
        point: best,
        deviations,
        worst,
        iterations,
        failures: failures.into_inner(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_reachable_target_is_met_and_the_point_recovered() {
        // Deviations of a smooth, identifiable model: zero exactly at u* = (0.3, 0.7, 0.55).
        let target = [0.3, 0.7, 0.55];
        let model = |u: &[f64]| -> Result<Vec<f64>, ()> {
            Ok(vec![
                (u[0] - target[0]) / 0.01,
                (u[0] + u[1] - target[0] - target[1]) / 0.01,
                (u[2] * u[2] - target[2] * target[2]) / 0.01,
            ])
        };
        let fits = minimise_worst(3, model, MinimaxSettings::default(), &[]).unwrap();
        let best = &fits[0];
        // Every target within its tolerance, and the point within a tolerance's reach of u*
        // (each deviation of 1 is 0.01 in u here).
        assert!(best.worst <= 1.0, "{best:?}");
        for (u, t) in best.point.iter().zip(target) {
            assert!((u - t).abs() < 0.02, "{best:?}");
        }
    }

    #[test]
    fn the_optimum_on_a_face_of_the_cube_is_found_without_leaving_it() {
        // The unconstrained optimum (u0 = 1.4) lies outside; the best in the cube is u0 = 1.
        let model = |u: &[f64]| -> Result<Vec<f64>, ()> {
            assert!(u.iter().all(|u| (0.0..=1.0).contains(u)));
            Ok(vec![(u[0] - 1.4) / 0.1, (u[1] - 0.5) / 0.1])
        };
        let best = &minimise_worst(2, model, MinimaxSettings::default(), &[]).unwrap()[0];
        assert!((best.point[0] - 1.0).abs() < 1e-3, "{best:?}");
        assert!((best.worst - 4.0).abs() < 1e-2, "{best:?}");
    }

    #[test]
    fn a_given_start_comes_first_and_its_fit_is_no_worse_than_the_start() {
        // A ridge the Sobol starts sit far from: the given start is on it.
        let model = |u: &[f64]| -> Result<Vec<f64>, ()> {
            Ok(vec![(u[0] - 0.9) / 0.01, (u[1] - 0.05) / 0.01])
        };
        let given = vec![vec![0.91, 0.06]];
        let settings = MinimaxSettings {
            starts: 0,
            max_iters: 50,
            ..MinimaxSettings::default()
        };
        let fits = minimise_worst(2, model, settings, &given).unwrap();
        assert_eq!(fits.len(), 1);
        assert_eq!(fits[0].start, 0);
        // Nelder-Mead keeps its best vertex: never worse than the start's own deviation.
        let at_start = worst(&model(&given[0]).unwrap());
        assert!(fits[0].worst <= at_start, "{:?} vs {at_start}", fits[0]);
        let outside = minimise_worst(2, model, settings, &[vec![1.2, 0.0]]);
        assert!(matches!(outside, Err(MinimaxError::Settings(_))));
    }

    #[test]
    fn results_are_the_same_for_one_and_many_threads() {
        let model = |u: &[f64]| -> Result<Vec<f64>, ()> {
            Ok(vec![(u[0] - 0.2).sin() / 0.05, (u[1] * u[0] - 0.1) / 0.05])
        };
        let one = rayon::ThreadPoolBuilder::new()
            .num_threads(1)
            .build()
            .unwrap()
            .install(|| minimise_worst(2, model, MinimaxSettings::default(), &[]).unwrap());
        let many = minimise_worst(2, model, MinimaxSettings::default(), &[]).unwrap();
        assert_eq!(format!("{one:?}"), format!("{many:?}"));
    }

    #[test]
    fn a_model_failing_in_part_of_the_cube_is_fitted_elsewhere_and_one_always_failing_is_an_error()
    {
        let never = |_: &[f64]| -> Result<Vec<f64>, ()> { Err(()) };
        assert_eq!(
            minimise_worst(2, never, MinimaxSettings::default(), &[]),
            Err(MinimaxError::NoEvaluation)
        );
        let half = |u: &[f64]| -> Result<Vec<f64>, ()> {
            if u[0] > 0.8 {
                Err(())
            } else {
                Ok(vec![(u[0] - 0.5) / 0.1])
            }
        };
        let fits = minimise_worst(1, half, MinimaxSettings::default(), &[]).unwrap();
        assert!(fits[0].worst < 1e-2);
        assert!(matches!(
            minimise_worst(0, half, MinimaxSettings::default(), &[]),
            Err(MinimaxError::Settings(_))
        ));
    }
}

//! Standard normal draws from uniform ones (Box-Muller), the one place the crate turns a
//! random stream into Gaussian samples: the noise drive's spectral coefficients, the
//! emulator's posterior draws and the fit family's perturbations all draw here.
//!
//! ```
//! use endstop::num::gaussian::{box_muller, box_muller_cosine};
//! use rand::SeedableRng;
//! use rand_chacha::ChaCha8Rng;
//!
//! // The mean of many draws is near 0 and their mean square near 1: for n = 20000 iid
//! // standard normals the standard error of the mean is 1/sqrt(n) = 0.007, and of the mean
//! // square sqrt(2/n) = 0.01; the bounds are five of those.
//! let mut rng = ChaCha8Rng::seed_from_u64(7);
//! let draws: Vec<f64> = (0..10_000)
//!     .flat_map(|_| {
//!         let (a, b) = box_muller(&mut rng);
//!         [a, b]
//!     })
//!     .collect();
//! let n = draws.len() as f64;
//! let mean = draws.iter().sum::<f64>() / n;
//! let square = draws.iter().map(|g| g * g).sum::<f64>() / n;
//! assert!(mean.abs() < 5.0 / n.sqrt());
//! assert!((square - 1.0).abs() < 5.0 * (2.0 / n).sqrt());
//! assert!(box_muller_cosine(&mut rng).is_finite());
//! ```

use rand::Rng;

/// Two independent standard normals from two uniforms (Box-Muller, basic form).
pub fn box_muller<R: Rng>(rng: &mut R) -> (f64, f64) {
    // random::<f64>() is in [0, 1); 1 - u is in (0, 1], so ln never sees 0.
    let u1 = 1.0 - rng.random::<f64>();
    let u2 = rng.random::<f64>();
    let r = (-2.0 * u1.ln()).sqrt();
    let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
    (r * c, r * s)
}

/// One standard normal from two uniforms: the cosine branch of Box-Muller, with the first
/// uniform kept off 0 by a floor at the smallest positive normal number (a stream of its own,
/// distinct from [`box_muller`]'s for the same seed).
pub fn box_muller_cosine<R: Rng>(rng: &mut R) -> f64 {
    let u1: f64 = rng.random::<f64>().max(f64::MIN_POSITIVE);
    let u2: f64 = rng.random();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

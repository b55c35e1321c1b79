//! Integration tests of `endstop::signal` (Welch PSD, bandwidths) and `endstop::drive::noise`
//! (band-limited white noise, Figure 10). Each tolerance is stated with its reason.

use endstop::drive::noise::NoiseSpec;
use endstop::paper::setups::paper_noise;
use endstop::signal::hann_periodic;
use endstop::signal::welch;
use endstop::signal::Psd;
use endstop::signal::WelchOptions;
use endstop::G;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rustfft::num_complex::Complex;
use rustfft::FftPlanner;

/// Named constant seed, so that the statistical tests are deterministic.
const SEED: u64 = 20120704;

/// `n` iid standard normals (Box-Muller), independent of `endstop::drive::noise::generate`.
fn white(n: usize, seed: u64) -> Vec<f64> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut out = Vec::with_capacity(n + 1);
    while out.len() < n {
        let u1 = 1.0 - rng.random::<f64>();
        let u2 = rng.random::<f64>();
        let r = (-2.0 * u1.ln()).sqrt();
        let (s, c) = (std::f64::consts::TAU * u2).sin_cos();
        out.push(r * c);
        out.push(r * s);
    }
    out.truncate(n);
    out
}

fn rel(a: f64, b: f64) -> f64 {
    (a - b).abs() / b.abs()
}

/// Slow, obviously correct Welch: naive DFT of each detrended, windowed segment.
fn welch_naive(x: &[f64], fs: f64, nperseg: usize, noverlap: usize) -> Vec<f64> {
    let w = hann_periodic(nperseg);
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let step = nperseg - noverlap;
    let n_bins = nperseg / 2 + 1;
    let mut acc = vec![0.0; n_bins];
    let mut segs = 0;
    let mut start = 0;
    while start + nperseg <= x.len() {
        let seg = &x[start..start + nperseg];
        let mean = seg.iter().sum::<f64>() / nperseg as f64;
        for (k, a) in acc.iter_mut().enumerate() {
            let mut c = Complex::new(0.0, 0.0);
            for (i, (&v, &wi)) in seg.iter().zip(&w).enumerate() {
                let ph = -std::f64::consts::TAU * (k * i % nperseg) as f64 / nperseg as f64;
                c += Complex::from_polar(wi * (v - mean), ph);
            }
            let two = if k == 0 || (nperseg.is_multiple_of(2) && k == nperseg / 2) {
                1.0
            } else {
                2.0
            };
            *a += two * c.norm_sqr() / (fs * s2);
        }
        segs += 1;
        start += step;
    }
    acc.iter().map(|a| a / segs as f64).collect()
}

#[test]
fn welch_matches_naive_dft_even_and_odd() {
    // Tolerance 1e-12 relative to the largest bin: both are the same sums, differing only in
    // floating-point rounding (~1e-15 per operation over a few hundred terms).
    let x = white(1000, SEED);
    for (nperseg, noverlap) in [(64, 32), (63, 21), (100, 0)] {
        let fast = welch(&x, 250.0, &WelchOptions { nperseg, noverlap }).unwrap();
        let slow = welch_naive(&x, 250.0, nperseg, noverlap);
        assert_eq!(fast.density.len(), slow.len());
        assert_eq!(fast.segments, (1000 - nperseg) / (nperseg - noverlap) + 1);
        let max = slow.iter().cloned().fold(0.0, f64::max);
        for (k, (a, b)) in fast.density.iter().zip(&slow).enumerate() {
            assert!(
                (a - b).abs() <= 1e-12 * max,
                "nperseg {nperseg} bin {k}: {a} vs {b}"
            );
        }
        assert!((fast.freq_hz[1] - 250.0 / nperseg as f64).abs() < 1e-12);
    }
}

#[test]
fn parseval_exact_identity() {
    // With density scaling the one-sided integral equals the mean over segments of the
    // window-weighted variance sum w^2 (x - mean)^2 / sum w^2, exactly (Parseval). Tolerance
    // 1e-12: rounding only.
    let x = white(50_000, SEED + 1);
    let (fs, cfg) = (1e3, WelchOptions::half_overlap(1024));
    let psd = welch(&x, fs, &cfg).unwrap();
    let w = hann_periodic(cfg.nperseg);
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let step = cfg.nperseg - cfg.noverlap;
    let mut direct = 0.0;
    for j in 0..psd.segments {
        let seg = &x[j * step..j * step + cfg.nperseg];
        let m = seg.iter().sum::<f64>() / seg.len() as f64;
        direct += seg
            .iter()
            .zip(&w)
            .map(|(v, wi)| (wi * (v - m)).powi(2))
            .sum::<f64>()
            / s2;
    }
    direct /= psd.segments as f64;
    let r = rel(psd.integral(), direct);
    println!(
        "parseval exact: integral {} direct {direct} rel {r:e}",
        psd.integral()
    );
    assert!(r < 1e-12);
}

#[test]
fn parseval_white_noise_variance() {
    // Unit-variance white noise: the PSD integral is a weighted mean of x^2 with weights
    // a[n] = sum over the segments covering n of w^2. For Gaussian x its relative standard
    // deviation is sqrt(2 sum a^2) / sum a (about 0.5 % here); we allow 5 of those
    // (about 2.6 %: "within a few %").
    let n = 100_000;
    let x = white(n, SEED + 2);
    let cfg = WelchOptions::half_overlap(2048);
    let psd = welch(&x, 1.0, &cfg).unwrap();
    let w = hann_periodic(cfg.nperseg);
    let mut a = vec![0.0; n];
    for j in 0..psd.segments {
        for (i, wi) in w.iter().enumerate() {
            a[j * (cfg.nperseg - cfg.noverlap) + i] += wi * wi;
        }
    }
    let sa: f64 = a.iter().sum();
    let sigma = (2.0 * a.iter().map(|v| v * v).sum::<f64>()).sqrt() / sa;
    let r = rel(psd.integral(), 1.0);
    println!(
        "parseval white: integral {} (K = {}), rel err {r:.4}, 1-sigma {sigma:.4}",
        psd.integral(),
        psd.segments
    );
    assert!(r < 5.0 * sigma, "{r} vs 5 x {sigma}");
}

#[test]
fn pure_tone_power_in_main_lobe() {
    // A bin-centred tone under a periodic Hann window occupies exactly three DFT bins
    // (coefficients 1/2, -1/4, -1/4), each segment holds whole cycles (mean 0), so the power in
    // bins k0-1..=k0+1 is A^2/2 exactly. Tolerance 1e-10: rounding only.
    let (fs, nperseg, k0, amp) = (100e3, 4096, 100, 1.7);
    let f0 = k0 as f64 * fs / nperseg as f64;
    let x: Vec<f64> = (0..20 * nperseg)
        .map(|n| amp * (std::f64::consts::TAU * f0 * n as f64 / fs).sin())
        .collect();
    let psd = welch(&x, fs, &WelchOptions::half_overlap(nperseg)).unwrap();
    let lobe: f64 = psd.density[k0 - 1..=k0 + 1].iter().sum::<f64>() * psd.df();
    let r = rel(lobe, amp * amp / 2.0);
    let outside = psd.integral() - lobe;
    println!(
        "tone: main lobe {lobe}, A^2/2 = {}, rel {r:e}, outside {outside:e}",
        amp * amp / 2.0
    );
    assert!(r < 1e-10);
    assert!(outside.abs() < 1e-10 * lobe);
    let (fp, _) = psd.peak();
    assert_eq!(fp, f0);
    assert_eq!(psd.segments, 39);
}

#[test]
fn white_noise_level_in_band() {
    // iid noise of variance s2 at fs has two-sided level s2 / fs. The band mean of M bins
    // from K segments has relative std 1/sqrt(M K) times a correlation factor: adjacent
    // Hann bins have power correlation (2/3)^2 and next-adjacent (1/6)^2, so the variance
    // of a band mean grows by 1 + 2(4/9 + 1/36) = 1.94; 50 % overlapped Hann segments have
    // power correlation (1/6)^2, a factor 1 + 2/36 = 1.06. Tolerance: 4 such sigmas.
    let (fs, s2): (f64, f64) = (20e3, 3.0);
    let x: Vec<f64> = white(400_000, SEED + 3)
        .iter()
        .map(|v| v * s2.sqrt())
        .collect();
    let psd = welch(&x, fs, &WelchOptions::half_overlap(1024)).unwrap();
    let (lo, hi) = (500.0, 9000.0);
    let m = psd
        .freq_hz
        .iter()
        .filter(|f| (lo..=hi).contains(*f))
        .count();
    let sigma = (1.94 * 1.06 / (m * psd.segments) as f64).sqrt();
    let level = psd.two_sided_level_in_band(lo, hi);
    let r = rel(level, s2 / fs);
    println!(
        "white level: {level:e} vs {:e}, rel {r:.5}, sigma {sigma:.5} (M = {m}, K = {})",
        s2 / fs,
        psd.segments
    );
    assert!(r < 4.0 * sigma);
}

#[test]
fn matches_scipy_reference() {
    // Reference values from an independent implementation, scipy 1.17.1 / numpy 2.4.6:
    //   fs = 100e3; N = 100000; n = np.arange(N)
    //   x = 1.5*np.sin(2*np.pi*1000*n/fs) + 0.5*np.cos(2*np.pi*3333.3*n/fs) + 1e-3*n/N
    //   f, P = scipy.signal.welch(x, fs=fs, nperseg=4096, noverlap=2048)
    //   P[:20], P.sum()*(f[1]-f[0])
    // Tolerance 1e-9 relative per bin: these low bins are 1e-12 of the peak (window
    // leakage), so FFT rounding (~1e-15 of the peak amplitude) is the limit.
    const P20: [f64; 20] = [
        4.98262281054691e-08,
        2.4855653985021814e-08,
        8.797344638567234e-14,
        2.870492262186271e-14,
        2.7269597879567345e-14,
        2.949048539835885e-14,
        3.294712054798844e-14,
        3.750636097593159e-14,
        4.3339823360563804e-14,
        5.07388274967794e-14,
        6.01068396772203e-14,
        7.198814139546513e-14,
        8.711684594107762e-14,
        1.0648933593827064e-13,
        1.3146991979681698e-13,
        1.6394609760791736e-13,
        2.0655958040495356e-13,
        2.63055046004235e-13,
        3.3881509094564235e-13,
        4.4169520437405457e-13,
    ];
    const INTEGRAL: f64 = 1.2500018232825956;
    let (fs, n) = (100e3, 100_000);
    let x: Vec<f64> = (0..n)
        .map(|i| {
            let t = i as f64;
            1.5 * (2.0 * std::f64::consts::PI * 1000.0 * t / fs).sin()
                + 0.5 * (2.0 * std::f64::consts::PI * 3333.3 * t / fs).cos()
                + 1e-3 * t / n as f64
        })
        .collect();
    let cfg = WelchOptions {
        nperseg: 4096,
        noverlap: 2048,
    };
    let psd = welch(&x, fs, &cfg).unwrap();
    assert_eq!(psd.density.len(), 2049);
    let mut worst: f64 = 0.0;
    for (k, (a, b)) in psd.density.iter().zip(P20).enumerate() {
        let r = rel(*a, b);
        worst = worst.max(r);
        assert!(r < 1e-9, "bin {k}: ours {a:e} scipy {b:e} rel {r:e}");
    }
    let ri = rel(psd.integral(), INTEGRAL);
    println!("scipy: worst bin rel {worst:e}, integral rel {ri:e}");
    assert!(ri < 1e-9);
}

#[test]
fn lorentzian_half_power_width() {
    // Analytic Lorentzian 1 / (1 + ((f - f0)/g)^2): FWHM = 2g, and the quarter-power
    // (half-amplitude) width is 2g sqrt(3). On a 0.5 Hz grid, linear interpolation of the
    // edges errs by well under 1 % for a 14.9 Hz width. Tolerance 1 %, above that error.
    let (f0, g) = (675.3, 7.45);
    let freq_hz: Vec<f64> = (0..4000).map(|i| 0.5 * i as f64).collect();
    let density = freq_hz
        .iter()
        .map(|f| 1.0 / (1.0 + ((f - f0) / g).powi(2)))
        .collect();
    let psd = Psd {
        freq_hz,
        density,
        segments: 0,
    };
    let bw = endstop::signal::width_at_fraction(&psd, 0.5).unwrap();
    let r = rel(bw.width_hz, 2.0 * g);
    println!(
        "lorentzian: 3 dB width {} vs {}, rel {r:e}",
        bw.width_hz,
        2.0 * g
    );
    assert!(r < 0.01);
    assert!(rel(bw.f_lo_hz, f0 - g) < 1e-3 && rel(bw.f_hi_hz, f0 + g) < 1e-3);
    assert_eq!(bw.peak_hz, 675.5);
    let bw6 = endstop::signal::width_at_fraction(&psd, 0.25).unwrap();
    assert!(rel(bw6.width_hz, 2.0 * g * 3f64.sqrt()) < 0.01);
}

// ---------------------------------------------------------------------------------------------
// noise

#[test]
fn noise_zero_mean_and_variance_matches_its_spectrum() {
    let spec = paper_noise(1e-2);
    let x = endstop::drive::noise::generate(&spec, SEED, 3).unwrap();
    let coeffs = endstop::drive::noise::spectrum(&spec, SEED, 3).unwrap();
    let n = x.len();
    assert_eq!(n, 1_000_000);
    assert_eq!(coeffs.len(), 100_001);
    let nf = n as f64;
    let rms = endstop::drive::noise::rms_si(&spec);

    // Zero mean: X_0 = 0, so only rounding (~1e-16 rms per sample) remains. Tolerance 1e-12 rms.
    let mean = x.iter().sum::<f64>() / nf;
    println!("noise mean {mean:e} (rms {rms})");
    assert!(mean.abs() < 1e-12 * rms);

    // Variance = (2/N^2) sum |X_k|^2 (Parseval), tolerance 1e-12 relative: rounding only.
    let var = x.iter().map(|v| v * v).sum::<f64>() / nf;
    let implied = 2.0 * coeffs.iter().map(|c| c.norm_sqr()).sum::<f64>() / (nf * nf);
    let r = rel(var, implied);
    println!("noise variance {var} implied {implied} rel {r:e}");
    assert!(r < 1e-12);

    // The forward FFT of the record returns the coefficients in band and zero outside it.
    // Tolerance 1e-10 of the largest coefficient: FFT rounding over 1e6 points.
    let mut buf: Vec<Complex<f64>> = x.iter().map(|&v| Complex::new(v, 0.0)).collect();
    FftPlanner::new().plan_fft_forward(n).process(&mut buf);
    let cmax = coeffs.iter().map(|c| c.norm()).fold(0.0, f64::max);
    for (k, b) in buf.iter().enumerate().take(n / 2 + 1) {
        let want = coeffs.get(k).copied().unwrap_or_default();
        assert!((b - want).norm() < 1e-10 * cmax, "bin {k}");
    }

    // Against the specification: E[x^2] = 2 B Sa_SI; the realised variance is a mean of
    // K = 1e5 exponential |X_k|^2, relative std 1/sqrt(K) = 0.32 %. Tolerance 5 sigma.
    let want = 2.0 * spec.bandwidth_hz * spec.psd_g2_per_hz * G * G;
    let sigma = 1.0 / (coeffs.len() as f64 - 1.0).sqrt();
    println!(
        "noise variance / (2 B Sa) - 1 = {:.5} (sigma {sigma:.5})",
        var / want - 1.0
    );
    assert!(rel(var, want) < 5.0 * sigma);
    assert!(rel(rms * rms, want) < 1e-12);
}

#[test]
fn noise_welch_level_and_stopband() {
    // Figure 10: flat two-sided PSD Sa up to 10 kHz. Welch with nperseg 4096 (24.4 Hz bins),
    // 50 % overlap: the band mean over 100 Hz..9.5 kHz averages M ~ 385 bins x K = 487
    // segments; sigma as in white_noise_level_in_band (correlation factor 1.94 x 1.06).
    // Tolerance 4 sigma (about 1.3 %). Stop band: the record has no content above 10 kHz,
    // only Hann leakage, which 500 Hz (20 bins) past the edge is far below -40 dB.
    let sa = 1e-2;
    let spec = paper_noise(sa);
    let x = endstop::drive::noise::generate(&spec, SEED, 0).unwrap();
    let psd = welch(&x, spec.sample_rate_hz, &WelchOptions::half_overlap(4096)).unwrap();
    let (lo, hi) = (100.0, 9.5e3);
    let m = psd
        .freq_hz
        .iter()
        .filter(|f| (lo..=hi).contains(*f))
        .count();
    let sigma = (1.94 * 1.06 / (m * psd.segments) as f64).sqrt();
    let level_g2 = psd.two_sided_level_in_band(lo, hi) / (G * G);
    let r = rel(level_g2, sa);
    let stop = psd
        .freq_hz
        .iter()
        .zip(&psd.density)
        .filter(|(f, _)| **f >= 10.5e3)
        .map(|(_, d)| *d)
        .fold(0.0, f64::max);
    let atten_db = 10.0 * (stop / (2.0 * sa * G * G)).log10();
    println!(
        "noise welch: level {level_g2:e} g^2/Hz, rel {r:.5}, sigma {sigma:.5} (M = {m}, K = {}); \
         max above 10.5 kHz {atten_db:.1} dB re band",
        psd.segments
    );
    assert!(r < 4.0 * sigma);
    assert!(atten_db < -40.0);
}

#[test]
fn noise_is_deterministic_per_stream() {
    let spec = NoiseSpec {
        duration_s: 0.5,
        ..paper_noise(1e-3)
    };
    let bits = |v: Vec<f64>| v.into_iter().map(f64::to_bits).collect::<Vec<_>>();
    let a = bits(endstop::drive::noise::generate(&spec, 7, 1).unwrap());
    let b = bits(endstop::drive::noise::generate(&spec, 7, 1).unwrap());
    let c = bits(endstop::drive::noise::generate(&spec, 7, 2).unwrap());
    let d = bits(endstop::drive::noise::generate(&spec, 8, 1).unwrap());
    assert_eq!(a, b);
    assert_ne!(a, c);
    assert_ne!(a, d);
}

#[test]
fn noise_golden_first_samples() {
    // Golden values: seed 42, stream 0, paper_noise(1e-2) (m/s^2). If this fails, the RNG
    // stream (rand / rand_chacha version, Box-Muller) or the synthesis (scaling, bin order,
    // normalisation) changed: every published random-excitation result changes with it.
    // Tolerance 1e-12 of the rms (139 m/s^2) rather than bit equality, to allow last-bit
    // differences between platform libms (ln, sin, cos); any real change is far larger.
    const GOLDEN: [f64; 5] = [
        251.84773182384973,
        237.89794772432737,
        199.6497306723594,
        147.29970070459112,
        93.15278623360747,
    ];
    let spec = paper_noise(1e-2);
    let x = endstop::drive::noise::generate(&spec, 42, 0).unwrap();
    let rms = endstop::drive::noise::rms_si(&spec);
    println!("golden: {:?}", &x[..5]);
    for (k, (a, b)) in x.iter().zip(GOLDEN).enumerate() {
        assert!((a - b).abs() < 1e-12 * rms, "sample {k}: {a:e} vs {b:e}");
    }
}

#[test]
fn noise_spec_errors() {
    let mut spec = paper_noise(1e-2);
    spec.sample_rate_hz = f64::INFINITY;
    let msg = endstop::drive::noise::generate(&spec, 0, 0)
        .unwrap_err()
        .to_string();
    assert!(msg.contains("sample_rate_hz = inf"), "{msg}");
    let spec = NoiseSpec {
        bandwidth_hz: 60e3,
        ..paper_noise(1e-2)
    };
    let msg = spec.validate().unwrap_err().to_string();
    assert!(
        msg.contains("bandwidth_hz = 60000") && msg.contains("= 50000"),
        "{msg}"
    );
}

//! The synthesizer's random numbers: a versioned counter-based generator and the three
//! distributions it needs (uniform, Gaussian, Poisson), written out here so that a dataset made
//! from a seed is the same bytes on every machine and every future build.
//!
//! Generator: ChaCha8 (`rand_chacha` 0.9) keyed by the seed (u64 little-endian, zero-padded to the
//! 32-byte key) with one ChaCha *stream* per purpose ([`Stream`]), so for example adding outliers
//! to a dataset leaves its Gaussian noise draws unchanged. `StdRng` is not used: its algorithm may
//! change between `rand` releases. The distributions are hand-written for the same reason
//! (`rand_distr` does not promise value stability across versions).

use rand_chacha::rand_core::{RngCore, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// What a generator is for; its discriminant is the ChaCha stream id and is part of the file
/// format (changing one changes every dataset made with that seed).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stream {
    /// Random rig directions (`sphere`).
    Angles = 0,
    /// Photon (Poisson) noise.
    Photon = 1,
    /// Relative Gaussian noise.
    Relative = 2,
    /// Additive Gaussian floor.
    Floor = 3,
    /// Outlier selection and factors.
    Outliers = 4,
}

/// The generator for `seed` and `stream`: ChaCha8, key = seed LE zero-padded, stream id = `stream`.
pub fn generator(seed: u64, stream: Stream) -> ChaCha8Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    let mut rng = ChaCha8Rng::from_seed(key);
    rng.set_stream(stream as u64);
    rng
}

/// Uniform in [0, 1): the top 53 bits of one `u64`.
pub fn uniform(rng: &mut impl RngCore) -> f64 {
    (rng.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Uniform in (0, 1]: safe under `ln`.
pub fn uniform_open0(rng: &mut impl RngCore) -> f64 {
    ((rng.next_u64() >> 11) + 1) as f64 * (1.0 / (1u64 << 53) as f64)
}

/// Standard normal by Box–Muller (cosine branch only): exactly two `u64` per draw, so the draw
/// count never depends on the values.
pub fn normal(rng: &mut impl RngCore) -> f64 {
    let u1 = uniform_open0(rng);
    let u2 = uniform(rng);
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// Poisson(λ) sample as f64 (λ ≥ 0 finite): multiplication method below λ = 10, Hörmann's
/// transformed rejection (PTRS, 1993) above — the split NumPy uses.
pub fn poisson(rng: &mut impl RngCore, lambda: f64) -> f64 {
    if lambda <= 0.0 {
        0.0
    } else if lambda < 10.0 {
        poisson_multiplication(rng, lambda)
    } else {
        poisson_ptrs(rng, lambda)
    }
}

/// Knuth's multiplication method: count uniforms until their product drops below e^{−λ}.
fn poisson_multiplication(rng: &mut impl RngCore, lambda: f64) -> f64 {
    let limit = (-lambda).exp();
    let mut k = 0.0;
    let mut product = uniform(rng);
    while product > limit {
        k += 1.0;
        product *= uniform(rng);
    }
    k
}

/// Hörmann's PTRS (transformed rejection with squeeze) for λ ≥ 10.
fn poisson_ptrs(rng: &mut impl RngCore, lambda: f64) -> f64 {
    let slam = lambda.sqrt();
    let loglam = lambda.ln();
    let b = 0.931 + 2.53 * slam;
    let a = -0.059 + 0.02483 * b;
    let inv_alpha = 1.1239 + 1.1328 / (b - 3.4);
    let v_r = 0.9277 - 3.6224 / (b - 2.0);
    loop {
        let u = uniform(rng) - 0.5;
        let v = uniform_open0(rng);
        let us = 0.5 - u.abs();
        let k = ((2.0 * a / us + b) * u + lambda + 0.43).floor();
        if us >= 0.07 && v <= v_r {
            return k;
        }
        if k < 0.0 || (us < 0.013 && v > us) {
            continue;
        }
        if v.ln() + inv_alpha.ln() - (a / (us * us) + b).ln()
            <= -lambda + k * loglam - log_gamma(k + 1.0)
        {
            return k;
        }
    }
}

/// ln Γ(x) for x > 0 by the Stirling series (shifted up to x ≥ 7), accurate to ~1e-15 relative.
pub fn log_gamma(x: f64) -> f64 {
    const A: [f64; 10] = [
        8.333333333333333e-02,
        -2.777777777777778e-03,
        7.936507936507937e-04,
        -5.952380952380952e-04,
        8.417508417508418e-04,
        -1.917526917526918e-03,
        6.41025641025641e-03,
        -2.955065359477124e-02,
        1.796443723688307e-01,
        -1.39243221690590e+00,
    ];
    if x == 1.0 || x == 2.0 {
        return 0.0;
    }
    let shift = if x <= 7.0 { (7.0 - x).floor() } else { 0.0 };
    let mut x0 = x + shift;
    let x2 = 1.0 / (x0 * x0);
    let mut series = A[9];
    for &c in A[..9].iter().rev() {
        series = series * x2 + c;
    }
    let mut gl = series / x0 + 0.5 * std::f64::consts::TAU.ln() + (x0 - 0.5) * x0.ln() - x0;
    for _ in 0..shift as u32 {
        x0 -= 1.0;
        gl -= x0.ln();
    }
    gl
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_gamma_matches_factorials() {
        // ln((n-1)!) computed by summing logs; 1e-13 relative is far looser than the series'
        // ~1e-15 yet far tighter than anything PTRS's acceptance test could notice.
        for n in 1..60u32 {
            let exact: f64 = (1..n).map(|k| (k as f64).ln()).sum();
            let got = log_gamma(n as f64);
            assert!(
                (got - exact).abs() <= 1e-13 * exact.abs().max(1.0),
                "n={n}: {got} vs {exact}"
            );
        }
        // Γ(1/2) = √π.
        let half = log_gamma(0.5);
        assert!((half - std::f64::consts::PI.sqrt().ln()).abs() < 1e-13);
    }

    #[test]
    fn streams_are_independent_and_seeded() {
        let a: Vec<u64> = {
            let mut r = generator(7, Stream::Relative);
            (0..4).map(|_| r.next_u64()).collect()
        };
        let b: Vec<u64> = {
            let mut r = generator(7, Stream::Floor);
            (0..4).map(|_| r.next_u64()).collect()
        };
        let c: Vec<u64> = {
            let mut r = generator(7, Stream::Relative);
            (0..4).map(|_| r.next_u64()).collect()
        };
        assert_ne!(a, b);
        assert_eq!(a, c);
    }

    #[test]
    fn uniform_ranges() {
        let mut r = generator(1, Stream::Angles);
        for _ in 0..10_000 {
            let u = uniform(&mut r);
            assert!((0.0..1.0).contains(&u));
            let v = uniform_open0(&mut r);
            assert!(v > 0.0 && v <= 1.0);
        }
    }

    /// Sample mean and variance of Poisson draws. With n draws the standard error of the mean is
    /// sqrt(λ/n) and of the variance ≈ λ·sqrt(2/n) (plus a λ² term of order 1/n); a 5-standard-
    /// error band fails by chance with probability < 1e-6.
    fn check_poisson(lambda: f64, n: usize) {
        let mut r = generator(42, Stream::Photon);
        let xs: Vec<f64> = (0..n).map(|_| poisson(&mut r, lambda)).collect();
        assert!(xs.iter().all(|&x| x >= 0.0 && x.fract() == 0.0));
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        let se_mean = (lambda / n as f64).sqrt();
        let se_var = (lambda * (2.0 * lambda + 1.0) / n as f64).sqrt();
        assert!(
            (mean - lambda).abs() < 5.0 * se_mean,
            "λ={lambda}: mean {mean}"
        );
        assert!((var - lambda).abs() < 5.0 * se_var, "λ={lambda}: var {var}");
    }

    #[test]
    fn poisson_moments_small_and_large() {
        check_poisson(0.3, 50_000);
        check_poisson(3.0, 50_000);
        check_poisson(9.99, 50_000);
        check_poisson(10.0, 50_000);
        check_poisson(250.0, 50_000);
        check_poisson(1e6, 50_000);
    }

    #[test]
    fn poisson_small_lambda_matches_pmf() {
        // P(X = 0) = e^{-λ}: with n = 100k the binomial standard error is < 0.0016; 5 of them.
        let lambda = 2.0;
        let n = 100_000;
        let mut r = generator(3, Stream::Photon);
        let zeros = (0..n).filter(|_| poisson(&mut r, lambda) == 0.0).count();
        let p = (-lambda).exp();
        let se = (p * (1.0 - p) / n as f64).sqrt();
        assert!(((zeros as f64 / n as f64) - p).abs() < 5.0 * se);
    }

    #[test]
    fn normal_moments() {
        // n = 100k: s.e. of the mean 0.0032, of the variance 0.0045; 5 standard errors.
        let n = 100_000;
        let mut r = generator(5, Stream::Relative);
        let xs: Vec<f64> = (0..n).map(|_| normal(&mut r)).collect();
        let mean = xs.iter().sum::<f64>() / n as f64;
        let var = xs.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64;
        assert!(mean.abs() < 5.0 * (1.0 / n as f64).sqrt());
        assert!((var - 1.0).abs() < 5.0 * (2.0 / n as f64).sqrt());
    }
}

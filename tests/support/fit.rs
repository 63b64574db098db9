//! Shared helpers of the fit tests: seeded parameter sets over MODEL.md's typical ranges, rig
//! geometries, noise-free / noisy synthetic data from the model itself, and data synthesized
//! through `hairfit::synth` from rig and noise specs (as `hairfit synth` would).
#![allow(dead_code)]

use hairfit::families::marschner::fit::synthetic::synthesize;
use hairfit::families::marschner::{ModelConfig, Params};
use hairfit::fit::design::SplitMix64;
use hairfit::fit::FitData;
use hairfit::geometry::Angles;

/// A parameter set drawn uniformly from MODEL.md's typical ranges (η at its default).
pub fn random_params(seed: u64, nc: usize) -> Params<f64> {
    let mut r = SplitMix64::new(seed);
    let mut u = |a: f64, b: f64| a + (b - a) * r.uniform();
    Params {
        eta: 1.55,
        sigma_a: (0..nc).map(|_| u(0.05, 2.0)).collect(),
        alpha_r: u(-10.0, -5.0).to_radians(),
        beta_r: u(5.0, 10.0).to_radians(),
        k_g: u(0.5, 5.0),
        w_c: u(10.0, 25.0).to_radians(),
        eccentricity: u(0.85, 0.99),
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

/// Azimuthal scans: incidences θ_i ∈ {−25, 0, 20}°, θ_r ∈ {−40..40 by 20}°, φ_r all round by 6°,
/// source azimuth 0° or 50°.
pub fn azimuthal_scans() -> Vec<Angles> {
    let mut v = Vec::new();
    for (k, ti) in [-25.0, 0.0, 20.0].into_iter().enumerate() {
        for tr in [-40.0, -20.0, 0.0, 20.0, 40.0] {
            for j in -29..=30 {
                let pi = if k == 1 { 50.0 } else { 0.0 };
                v.push(Angles::from_degrees(ti, pi, tr, j as f64 * 6.0));
            }
        }
    }
    v
}

/// Longitudinal scans: θ_r from −80° to 80° by 4° at several fixed azimuths, two incidences.
pub fn longitudinal_scans() -> Vec<Angles> {
    let mut v = Vec::new();
    for ti in [-30.0, 10.0] {
        for pr in [
            0.0, 25.0, 40.0, 60.0, 90.0, 120.0, 150.0, 170.0, 180.0, -35.0, -140.0,
        ] {
            for j in -20..=20 {
                let pi = if pr as i64 % 20 == 0 { 0.0 } else { 30.0 };
                v.push(Angles::from_degrees(ti, pi, j as f64 * 4.0, pr + pi));
            }
        }
    }
    v
}

/// `n` directions pairs uniform on the sphere (|θ| < 85°), seeded.
pub fn random_sphere(n: usize, seed: u64) -> Vec<Angles> {
    let mut r = SplitMix64::new(seed);
    let dir = |r: &mut SplitMix64| {
        let t = (2.0 * r.uniform() - 1.0).asin().clamp(-1.48, 1.48);
        let p = (2.0 * r.uniform() - 1.0) * std::f64::consts::PI;
        (t, p)
    };
    (0..n)
        .map(|_| {
            let (ti, pi) = dir(&mut r);
            let (tr, pr) = dir(&mut r);
            Angles {
                theta_i: ti,
                phi_i: pi,
                theta_r: tr,
                phi_r: pr,
            }
        })
        .collect()
}

/// The three rig geometries by index.
pub fn geometry(k: usize, seed: u64) -> (&'static str, Vec<Angles>) {
    match k % 3 {
        0 => ("azimuthal", azimuthal_scans()),
        1 => ("longitudinal", longitudinal_scans()),
        _ => ("sphere", random_sphere(900, seed)),
    }
}

/// Per-channel scales used by the tests (arbitrary exposures).
pub fn scales(nc: usize) -> Vec<f64> {
    [3.0, 0.7, 1.9, 1.2][..nc].to_vec()
}

/// Data from the model at `truth` (all effects on), relative noise `noise`.
pub fn data(truth: &Params<f64>, angles: &[Angles], noise: f64, seed: u64) -> FitData {
    let nc = truth.sigma_a.len();
    synthesize(
        truth,
        &ModelConfig::default(),
        angles,
        &scales(nc),
        noise,
        seed,
    )
}

/// A parameter set drawn from well beyond MODEL.md's typical ranges (the start design's box),
/// where a single start is more likely to end in a wrong basin.
pub fn wide_params(seed: u64, nc: usize) -> Params<f64> {
    let mut r = SplitMix64::new(seed ^ 0xabcdef);
    let mut u = |a: f64, b: f64| a + (b - a) * r.uniform();
    Params {
        eta: 1.55,
        sigma_a: (0..nc).map(|_| u(0.02, 4.0)).collect(),
        alpha_r: u(-14.0, -2.0).to_radians(),
        beta_r: u(3.0, 14.0).to_radians(),
        k_g: u(0.2, 8.0),
        w_c: u(6.0, 35.0).to_radians(),
        eccentricity: u(0.8, 0.99),
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

/// `truth` synthesized through `hairfit::synth` on `rig` (a `--rig` spec) with `noise` (a
/// `--noise` spec) and one channel scale `scale`, loaded as fit data.
pub fn synthesized(truth: &Params<f64>, rig: &str, noise: &str, scale: f64, seed: u64) -> FitData {
    use hairfit::synth::{Noise, Rig};
    let (ds, _) = hairfit::families::marschner::fit::synthetic::synthesize_rig(
        truth,
        &ModelConfig::default(),
        &Rig::parse(rig).unwrap(),
        &Noise::parse(noise).unwrap(),
        &[scale],
        hairfit::geometry::Measurement::S,
        seed,
    )
    .unwrap();
    hairfit::fit::fit_data(&ds)
}

//! Helpers shared by the model tests: parameter sets and per-lobe azimuthal values.
#![allow(dead_code)]

use hairfit::families::marschner::bravais::bravais_indices;
use hairfit::families::marschner::fresnel::{
    absorption, chord, cos_gamma_t, fresnel, fresnel_attenuation,
};
use hairfit::families::marschner::longitudinal::longitudinal;
use hairfit::families::marschner::{
    scattering, scattering_by_lobe, Effects, Lobes, ModelConfig, Params, RootMode,
};
use hairfit::geometry::Angles;

/// MODEL.md's known-values parameter set.
pub fn table_params() -> Params<f64> {
    Params {
        eta: 1.55,
        sigma_a: vec![0.4],
        alpha_r: (-7.0f64).to_radians(),
        beta_r: 8.0f64.to_radians(),
        k_g: 2.0,
        w_c: 15.0f64.to_radians(),
        eccentricity: 0.9,
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

pub fn config(mode: RootMode, lobes: Lobes, glints: bool, eccentricity: bool) -> ModelConfig {
    ModelConfig {
        mode,
        effects: Effects {
            lobes,
            glints,
            eccentricity,
        },
    }
}

pub fn only(p: usize) -> Lobes {
    Lobes {
        r: p == 0,
        tt: p == 1,
        trt: p == 2,
    }
}

/// S of channel 0.
pub fn s(params: &Params<f64>, cfg: &ModelConfig, a: &Angles) -> f64 {
    let mut out = vec![0.0; params.sigma_a.len()];
    scattering(params, cfg, a, &mut out);
    out[0]
}

/// `N_p(θ_d, φ)` alone (channel 0), recovered from S at θ_h = 0, φ_h = φ/2:
/// `N_p = S_p · cos²θ_d / M_p(0)`.
pub fn n_p(params: &Params<f64>, cfg: &ModelConfig, p: usize, theta_d: f64, phi: f64) -> f64 {
    let a = Angles {
        theta_i: -theta_d,
        phi_i: 0.0,
        theta_r: theta_d,
        phi_r: phi,
    };
    let mut out = vec![[0.0; 3]; params.sigma_a.len()];
    scattering_by_lobe(params, cfg, &a, &mut out);
    let m = longitudinal(p, 0.0, &params.alpha_r, &params.beta_r);
    out[0][p] * theta_d.cos().powi(2) / m
}

/// `A(p, h)` for channel 0 at `θ_d` with index η (no eccentricity), straight from MODEL.md.
pub fn attenuation(params: &Params<f64>, p: usize, theta_d: f64, h: f64) -> f64 {
    let br = bravais_indices(&params.eta, theta_d.sin(), theta_d.cos());
    let cos_gi = (1.0 - h * h).max(0.0).sqrt();
    let cos_gt = cos_gamma_t(&h, &br.eta_p);
    let f = fresnel(&br.eta_p, &br.eta_pp, &cos_gi, &cos_gt);
    fresnel_attenuation(p, f) * absorption(p, &params.sigma_a[0], &chord(&cos_gt, &br.cos_theta_t))
}

/// ∫_a^b f by tanh-sinh quadrature: exact to ~1e-12 for smooth f and robust to integrable
/// endpoint singularities (the 1/sqrt at φ_c), so callers split the range at every singularity.
pub fn tanh_sinh(f: impl Fn(f64) -> f64, a: f64, b: f64) -> f64 {
    let half = 0.5 * (b - a);
    let step = 1.0 / 64.0;
    let mut sum = 0.0;
    let n = (4.0 / step) as i64;
    for i in -n..=n {
        let t = i as f64 * step;
        let u = std::f64::consts::FRAC_PI_2 * t.sinh();
        let w = std::f64::consts::FRAC_PI_2 * t.cosh() / u.cosh().powi(2);
        // Distance from the nearer end, computed without cancellation: half·(1 − tanh|u|).
        let d = half * 2.0 / (1.0 + (2.0 * u.abs()).exp());
        let x = if u < 0.0 { a + d } else { b - d };
        if x <= a || x >= b {
            continue;
        }
        sum += w * f(x);
    }
    sum * half * step
}

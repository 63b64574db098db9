//! The d'Eon 2011 model written separately from the implementation, straight from the published
//! formulas as docs/deon.md states them, for the deon tests (`crate::support::deon`).
//! Nothing here calls the implementation's helpers.
#![allow(dead_code)] // each test crate uses a different subset

use std::f64::consts::PI;

use hairfit::families::deon::DEon;
use hairfit::families::table::{TableFamily, TableParams};
use hairfit::geometry::Angles;

/// One parameter set in file units.
#[derive(Clone, Copy)]
pub struct Set {
    pub eta: f64,
    pub sigma_a: f64,
    pub beta_r_deg: f64,
    pub beta_n_deg: f64,
    pub alpha_deg: f64,
}

/// The implementation's parameters for `s` (one channel).
pub fn table_params(s: &Set) -> TableParams<f64> {
    let mut p = TableParams::defaults(DEon::PARAMETERS, 1);
    for (k, fact) in DEon::PARAMETERS.iter().enumerate() {
        let file_value = match fact.name {
            "eta" => s.eta,
            "sigma_a" => s.sigma_a,
            "beta_r_deg" => s.beta_r_deg,
            "beta_n_deg" => s.beta_n_deg,
            "alpha_deg" => s.alpha_deg,
            other => panic!("a parameter this test does not know: {other}"),
        };
        p.values[k][0] = fact.unit.to_model(file_value);
    }
    p
}

/// The published formulas, straight-line.
pub mod reference {
    use super::*;

    /// `I₀(x) = Σ_k (x²/4)^k / (k!)²`.
    pub fn bessel_i0(x: f64) -> f64 {
        let q = 0.25 * x * x;
        let (mut term, mut sum) = (1.0, 1.0);
        for k in 1..2000 {
            term *= q / (k * k) as f64;
            sum += term;
            if term < 1e-18 * sum {
                break;
            }
        }
        sum
    }

    /// d'Eon's Eq. 7: `M = exp(−sin θ_i sin θ_o / v) I₀(cos θ_i cos θ_o / v) / (2v sinh(1/v))`.
    pub fn longitudinal(theta_i: f64, theta_o: f64, v: f64) -> f64 {
        (-theta_i.sin() * theta_o.sin() / v).exp() * bessel_i0(theta_i.cos() * theta_o.cos() / v)
            / (2.0 * v * (1.0 / v).sinh())
    }

    /// Unpolarised reflectance of a dielectric of index `eta` at incidence cosine `c`.
    pub fn fresnel(eta: f64, c: f64) -> f64 {
        let sin_t = (1.0 - c * c).sqrt() / eta;
        let cos_t = (1.0 - sin_t * sin_t).sqrt();
        let rs = (c - eta * cos_t) / (c + eta * cos_t);
        let rp = (eta * c - cos_t) / (eta * c + cos_t);
        0.5 * (rs * rs + rp * rp)
    }

    /// Normal density of standard deviation `b` summed over 17 turns of the circle.
    pub fn detector(x: f64, b: f64) -> f64 {
        (-8..=8)
            .map(|k| {
                let y = x + 2.0 * PI * k as f64;
                (-y * y / (2.0 * b * b)).exp() / (b * (2.0 * PI).sqrt())
            })
            .sum()
    }

    /// What one entry offset h sees at half difference angle θ_d: the Fresnel factor, the
    /// refraction angle γ_t (Bravais index η') and the transmittance of one chord.
    pub struct Ray {
        pub f: f64,
        pub gamma_i: f64,
        pub gamma_t: f64,
        pub t: f64,
    }

    pub fn ray(s: &Set, theta_d: f64, h: f64) -> Ray {
        let eta_prime = (s.eta * s.eta - theta_d.sin().powi(2)).sqrt() / theta_d.cos();
        let cos_theta_t = (1.0 - (theta_d.sin() / s.eta).powi(2)).sqrt();
        let gamma_t = (h / eta_prime).asin();
        Ray {
            f: fresnel(s.eta, theta_d.cos() * (1.0 - h * h).sqrt()),
            gamma_i: h.asin(),
            gamma_t,
            t: (-s.sigma_a * 2.0 * gamma_t.cos() / cos_theta_t).exp(),
        }
    }

    /// `A_p = F` (p = 0), `(1 − F)² F^{p−1} T^p` (p ≥ 1).
    pub fn attenuation(p: i32, r: &Ray) -> f64 {
        if p == 0 {
            return r.f;
        }
        (1.0 - r.f).powi(2) * r.f.powi(p - 1) * r.t.powi(p)
    }

    /// `Φ_p = 2pγ_t − 2γ_i + pπ`.
    pub fn exit(p: i32, r: &Ray) -> f64 {
        let p = p as f64;
        2.0 * p * r.gamma_t - 2.0 * r.gamma_i + p * PI
    }

    /// `½∫₋₁¹ g(h) dh = ½∫ g(sin γ) cos γ dγ` by the midpoint rule on n and 2n points,
    /// Richardson-extrapolated (the integrand is smooth in γ; the error falls as Δγ⁴).
    pub fn width_average(g: impl Fn(f64) -> f64) -> f64 {
        let midpoint = |n: usize| {
            let d = PI / n as f64;
            (0..n)
                .map(|j| {
                    let gamma = -0.5 * PI + (j as f64 + 0.5) * d;
                    g(gamma.sin()) * gamma.cos() * d
                })
                .sum::<f64>()
                * 0.5
        };
        let n = 3000;
        (4.0 * midpoint(2 * n) - midpoint(n)) / 3.0
    }

    /// The width averages `⟨A_p⟩_h` of R, TT, TRT and of all orders p ≥ 3 together
    /// (`Σ_{p≥3} A_p = A_3/(1 − FT)`): each term's share of the light at half angle `theta_d`.
    pub fn shares(s: &Set, theta_d: f64) -> [f64; 4] {
        let residual = |r: &Ray| attenuation(3, r) / (1.0 - r.f * r.t);
        std::array::from_fn(|k| {
            width_average(|h| {
                let r = ray(s, theta_d, h);
                if k < 3 {
                    attenuation(k as i32, &r)
                } else {
                    residual(&r)
                }
            })
        })
    }

    /// The terms of S: `M_k N_k / cos θ_i` for R, TT, TRT and the residual (p = 3 with its
    /// azimuth, `Σ_{p≥4} A_p = A_3 FT/(1 − FT)` spread as 1/(2π)).
    pub fn terms(s: &Set, a: &Angles) -> [f64; 4] {
        let theta_d = 0.5 * (a.theta_r - a.theta_i);
        let phi = a.phi_r - a.phi_i;
        let b = s.beta_n_deg.to_radians();
        let lobe = |p: i32| {
            width_average(|h| {
                let r = ray(s, theta_d, h);
                attenuation(p, &r) * detector(phi - exit(p, &r), b)
            })
        };
        let residual = width_average(|h| {
            let r = ray(s, theta_d, h);
            let tail = attenuation(3, &r) * r.f * r.t / (1.0 - r.f * r.t);
            attenuation(3, &r) * detector(phi - exit(3, &r), b) + tail / (2.0 * PI)
        });
        let n = [lobe(0), lobe(1), lobe(2), residual];
        // v_R = (2β_R)²; TT, TRT and the residual at ¼, 4, 4 times; θ_r turned by (−2, 1, 3, 0)·α.
        let v_r = (2.0 * s.beta_r_deg.to_radians()).powi(2);
        let scale = [1.0, 0.25, 4.0, 4.0];
        let tilt = [-2.0, 1.0, 3.0, 0.0];
        let alpha = s.alpha_deg.to_radians();
        std::array::from_fn(|k| {
            let m = longitudinal(a.theta_i, a.theta_r + tilt[k] * alpha, v_r * scale[k]);
            m * n[k] / a.theta_i.cos()
        })
    }
}

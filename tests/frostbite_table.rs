//! The frostbite family's pre-integrated azimuthal table against direct integration of the
//! integral it holds (`N_p = ½∫ D_s(φ − Φ_p(h)) dh`, Gauss–Legendre with 8192 nodes in
//! γ = asin h), at off-grid points; its normalisation; and how far HDRP's own 64³ table (a
//! 20-sample sum in h, as its generator computes it) is from the same integral — the numbers
//! docs/frostbite.md quotes. `cargo test --release --test frostbite_table -- --nocapture`
//! prints them.

use std::f64::consts::PI;

use hairfit::table_family::frostbite::azimuthal::{
    exit_azimuth_at, integrate_directly, inverse_modified_index, AzimuthalLut,
};

/// Direct integration nodes: the narrowest logistic in the domain (β_N = 0.1, s = 0.024 rad)
/// spans ≥ 6 nodes of this rule everywhere, so it is exact to far below the table's error.
const DIRECT_NODES: usize = 8192;

/// A deterministic spread of off-grid points in [0, 1).
fn halton(i: usize, base: usize) -> f64 {
    let (mut f, mut r, mut n) = (1.0, 0.0, i);
    while n > 0 {
        f /= base as f64;
        r += f * (n % base) as f64;
        n /= base;
    }
    r
}

/// Largest error of the table relative to the lobe's peak over φ (at that θ_d and β_N), over
/// `points` off-grid (φ, θ_d) for each lobe.
fn worst_error(beta_n: f64, points: usize) -> [f64; 3] {
    let lut = AzimuthalLut::shared();
    let mut worst = [0.0f64; 3];
    for i in 1..=points {
        let phi = PI * halton(i, 2);
        let theta_d = 1.5 * halton(i, 3) - 0.01;
        let c = theta_d.cos();
        let at = lut.locate(phi, c, &beta_n);
        for (p, w) in worst.iter_mut().enumerate() {
            let peak = (0..=90)
                .map(|k| integrate_directly(p, PI * k as f64 / 90.0, c, beta_n, 2048))
                .fold(0.0, f64::max);
            let direct = integrate_directly(p, phi, c, beta_n, DIRECT_NODES);
            let e = (lut.value(p, &at) - direct).abs() / peak;
            *w = w.max(e);
        }
    }
    worst
}

/// The documented bound: relative to each lobe's peak, the table is within 3e-4 at β_N ≥ 0.2
/// and within 1e-3 down to β_N = 0.1 (Radial Smoothness 0.9), where the TRT caustics are a few
/// table steps wide (measured worst: 3.1e-4 at 0.1, 9e-5 elsewhere; the bounds leave ×3).
#[test]
fn table_matches_direct_integration_within_the_documented_bound() {
    for (beta_n, bound) in [
        (0.1, 1e-3),
        (0.15, 5e-4),
        (0.2, 3e-4),
        (0.3, 3e-4),
        (0.5, 3e-4),
        (0.8, 3e-4),
        (1.0, 3e-4),
    ] {
        let worst = worst_error(beta_n, 60);
        println!(
            "beta_N {beta_n}: worst |table - direct| / peak: R {:.1e}, TT {:.1e}, TRT {:.1e}",
            worst[0], worst[1], worst[2]
        );
        for (p, w) in worst.iter().enumerate() {
            assert!(
                *w < bound,
                "beta_N {beta_n} lobe {p}: {w:.2e} >= {bound:.0e}"
            );
        }
    }
}

/// Each N_p is a distribution over φ: the table integrates to 1 over (−π, π] within 1e-3
/// (trapezoid at 0.25°, both halves by evenness).
#[test]
fn table_lobes_integrate_to_one() {
    let lut = AzimuthalLut::shared();
    for beta_n in [0.1, 0.3, 0.9] {
        for theta_d in [0.0f64, 0.6, 1.3] {
            for p in 0..3 {
                let n = 720;
                let total: f64 = (0..=n)
                    .map(|k| {
                        let phi = PI * k as f64 / n as f64;
                        let w = if k == 0 || k == n { 0.5 } else { 1.0 };
                        let at = lut.locate(phi, theta_d.cos(), &beta_n);
                        w * lut.value(p, &at)
                    })
                    .sum::<f64>()
                    * 2.0
                    * PI
                    / n as f64;
                assert!(
                    (total - 1.0).abs() < 1e-3,
                    "beta_N {beta_n} theta_d {theta_d} lobe {p}: {total}"
                );
            }
        }
    }
}

/// HDRP's generator: at its texel centres, `½ Σ D_s(φ − Φ_p(h)) · 0.1` over the 20 offsets
/// h = −1, −0.9, …, 0.9 (its loop `for (h = −1; h < 1; h += 0.1)`), with exact arcsines.
fn hdrp_texel(p: usize, phi: f64, c: f64, beta_n: f64) -> f64 {
    let s = hairfit::chiang::azimuthal::logistic_scale(&beta_n);
    let norm = hairfit::chiang::azimuthal::trimmed_logistic_norm(&s);
    let x = inverse_modified_index(c);
    (0..20)
        .map(|k| {
            let h = -1.0 + 0.1 * k as f64;
            let d = hairfit::model::angles::wrap(phi - exit_azimuth_at(p, h, x));
            0.5 * 0.1 * hairfit::chiang::azimuthal::trimmed_logistic(&d, &(1.0 / s), &norm)
        })
        .sum()
}

/// What HDRP's own table holds, against the integral: its 20-sample sum in h is within 5% of
/// the integral (relative to the lobe's peak) at its texels with β_N ≥ 0.5, but at HDRP's
/// default β_N = 0.3 it is off by more than 10% somewhere — so Unity renders with azimuthal
/// lobes that differ from this family's (and from Chiang's) by that much. Printed for the docs.
#[test]
fn hdrp_texels_differ_from_the_integral_by_the_documented_amount() {
    let texel = |i: usize| (i as f64 + 0.5) / 64.0;
    let mut report = Vec::new();
    for (k, beta_n) in [(19usize, texel(19)), (44, texel(44))] {
        let mut worst = 0.0f64;
        for j in [8usize, 32, 60] {
            let c = texel(j);
            for p in 0..3 {
                let peak = (0..=90)
                    .map(|q| integrate_directly(p, PI * q as f64 / 90.0, c, beta_n, 2048))
                    .fold(0.0, f64::max);
                for i in 32..48 {
                    let phi = 4.0 * PI * texel(i) - 2.0 * PI;
                    let direct = integrate_directly(p, phi, c, beta_n, DIRECT_NODES);
                    worst = worst.max((hdrp_texel(p, phi, c, beta_n) - direct).abs() / peak);
                }
            }
        }
        println!("HDRP texel beta_N {beta_n:.3} (texel {k}): worst deviation / peak {worst:.3}");
        report.push(worst);
    }
    assert!(report[0] > 0.1, "beta_N 0.30: {}", report[0]);
    assert!(report[1] < 0.05, "beta_N 0.70: {}", report[1]);
}

//! The node sums of [`super::azimuthal`]'s rule on f64 vectors: each piece's eight
//! Gauss–Legendre nodes at once (one AVX-512 register, two AVX2 registers, or two `wide::f64x4`),
//! with the shared lanes' exp, sin/cos and asin (within 1 ulp of libm). Each node costs five
//! transcendental functions, which were two thirds of a Frostbite fit's time in libm one node at
//! a time. The sums agree with the scalar loop's to ~1e-15 relative (the functions' last bits
//! and the order of summation); `tests/families/frostbite_azimuthal.rs` holds both to the
//! direct integral.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use wide::f64x4;

use crate::families::shared::lanes::functions::LaneFunctions;
use crate::families::shared::lanes::vector::{Lane, Pair};
#[cfg(target_arch = "x86_64")]
use crate::families::shared::lanes::{avx2, avx512};

/// One piece of the rule in v: nodes at `mid + half·x_n`, where `γ = g0 + ℓ sinh v`.
#[derive(Clone, Copy)]
pub(super) struct Piece {
    pub mid: f64,
    pub half: f64,
    pub g0: f64,
    pub ell: f64,
}

/// What the nodes of one lobe share: `u(γ) = φ − 2p asin(x sin γ) + 2γ − pπ` and the logistic's
/// `k = 1/s`.
#[derive(Clone, Copy)]
pub(super) struct NodeLobe {
    pub p: f64,
    pub phi: f64,
    pub x: f64,
    pub inv_s: f64,
}

/// `Σ_pieces Σ_n w_n · ½ half ℓ cosh v cos γ · [f₀, f₁, f₂](wrap u(γ))` over the nodes inside
/// (−π/2, π/2), with `f` the logistic's Taylor terms in k ([`super::azimuthal`]'s `taylor`);
/// `nodes`/`weights` the rule on [−1, 1] (a multiple of 8 of them).
pub(super) fn node_sums(
    lobe: NodeLobe,
    pieces: &[Piece],
    nodes: &[f64],
    weights: &[f64],
) -> [f64; 3] {
    assert_eq!(nodes.len() % 8, 0, "the rule fills whole vectors");
    #[cfg(target_arch = "x86_64")]
    {
        if avx512::available() {
            // SAFETY: the CPU has AVX-512F and AVX-512DQ.
            return unsafe { sums_avx512(lobe, pieces, nodes, weights) };
        }
        if avx2::available() {
            // SAFETY: the CPU has AVX2.
            return unsafe { sums_avx2(lobe, pieces, nodes, weights) };
        }
    }
    sums::<f64x4>(lobe, pieces, nodes, weights)
}

/// [`sums`] compiled for AVX-512 (every helper is `#[inline(always)]`, so its intrinsics are
/// single instructions here).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512dq")]
unsafe fn sums_avx512(
    lobe: NodeLobe,
    pieces: &[Piece],
    nodes: &[f64],
    weights: &[f64],
) -> [f64; 3] {
    sums::<avx512::F64x8>(lobe, pieces, nodes, weights)
}

/// [`sums`] on two AVX2 registers, compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn sums_avx2(lobe: NodeLobe, pieces: &[Piece], nodes: &[f64], weights: &[f64]) -> [f64; 3] {
    sums::<Pair<avx2::F64x4>>(lobe, pieces, nodes, weights)
}

#[inline(always)]
fn sums<V: Lane>(lobe: NodeLobe, pieces: &[Piece], nodes: &[f64], weights: &[f64]) -> [f64; 3] {
    let n = V::LANES;
    let mut total = [V::ZERO; 3];
    for piece in pieces {
        for (xn, wn) in nodes.chunks_exact(n).zip(weights.chunks_exact(n)) {
            let xn = V::from_fn(|l| xn[l]);
            let wn = V::from_fn(|l| wn[l]);
            let v = xn * piece.half + piece.mid;
            let ev = v.exp();
            let inv = V::ONE / ev;
            let (sinh, cosh) = ((ev - inv) * 0.5, (ev + inv) * 0.5);
            let g = sinh * piece.ell + piece.g0;
            let inside = g.cmp_gt(V::splat(-FRAC_PI_2)) & g.cmp_lt(V::splat(FRAC_PI_2));
            let (sin_g, cos_g) = g.sin_cos();
            // ½∫ … cos γ dγ, dγ = ℓ cosh v dv.
            let weight = wn * (0.5 * piece.half) * piece.ell * cosh * cos_g;
            let u = (V::splat(lobe.phi) - (sin_g * lobe.x).asin() * (2.0 * lobe.p) + g * 2.0)
                - lobe.p * PI;
            let f = taylor(wrap(u), lobe.inv_s);
            for (t, fk) in total.iter_mut().zip(f) {
                *t = *t + inside.blend(fk * weight, V::ZERO);
            }
        }
    }
    total.map(|t| t.to_array().as_ref().iter().sum())
}

/// `x` in [−π, π] (only |x| matters to the logistic, which is even and equal at ±π).
#[inline(always)]
fn wrap<V: Lane>(x: V) -> V {
    x - (x * (1.0 / TAU)).round() * TAU
}

/// `e/(1 + e)²` with `e = exp(−k|d|)` at `k = 1/s`, and its first two derivatives in k halved
/// as Taylor coefficients: `D_s(d) = norm·(f₀ + f₁δ + f₂δ²)` for `k = k₀ + δ`. Summing these
/// three in f64 over the nodes and forming the number type once per lobe
/// (`azimuthal::Logistic::series`) gives the value and the first and second derivatives of the
/// sum exactly, where the number type at every node cost a dual `exp` and division per node.
#[inline(always)]
fn taylor<V: Lane>(d: V, inv_s: f64) -> [V; 3] {
    let x = d.abs();
    let e = (-(x * inv_s)).exp();
    let q = V::ONE / (e + 1.0);
    let f0 = e * q * q;
    let f1 = -x * f0 * (-e + 1.0) * q;
    let f2 = x * 0.5 * x * f0 * ((e * -4.0 + 1.0) + e * e) * q * q;
    [f0, f1, f2]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::shared::quadrature::GaussLegendre;

    /// The sums one node at a time in libm's functions, as the scalar loop took them.
    fn scalar(lobe: NodeLobe, pieces: &[Piece], rule: &GaussLegendre) -> ([f64; 3], [f64; 3]) {
        let (mut total, mut size) = ([0.0; 3], [0.0; 3]);
        for piece in pieces {
            for (&xn, &wn) in rule.nodes.iter().zip(&rule.weights) {
                let v = piece.mid + piece.half * xn;
                let (sinh, cosh) = (v.sinh(), v.cosh());
                let g = piece.g0 + piece.ell * sinh;
                if g <= -FRAC_PI_2 || g >= FRAC_PI_2 {
                    continue;
                }
                let weight = 0.5 * piece.half * wn * piece.ell * cosh * g.cos();
                let u = lobe.phi - 2.0 * lobe.p * (lobe.x * g.sin()).asin() + 2.0 * g - lobe.p * PI;
                let x = crate::geometry::angles::wrap(u).abs();
                let e = (-(lobe.inv_s * x)).exp();
                let q = 1.0 / (1.0 + e);
                let f0 = e * q * q;
                let f = [
                    f0,
                    -x * f0 * (1.0 - e) * q,
                    0.5 * x * x * f0 * (1.0 - 4.0 * e + e * e) * q * q,
                ];
                for k in 0..3 {
                    total[k] += f[k] * weight;
                    size[k] += (f[k] * weight).abs();
                }
            }
        }
        (total, size)
    }

    /// Every kernel this CPU runs agrees with the scalar loop to 1e-13 of the sum of the terms'
    /// sizes, over the lobes, absorbing widths and pieces a fit reaches (pieces straddling
    /// γ = ±π/2, whose outer nodes are left out). The lanes' functions are within 1 ulp of libm
    /// and the sums are taken in another order: ~1e-16 per term, far inside 1e-13.
    #[test]
    fn every_kernel_matches_the_scalar_loop() {
        let rule = GaussLegendre::new(8);
        type Kernel = fn(NodeLobe, &[Piece], &[f64], &[f64]) -> [f64; 3];
        let mut kernels: Vec<(&str, Kernel)> = vec![("wide", sums::<f64x4>)];
        #[cfg(target_arch = "x86_64")]
        {
            if avx2::available() {
                kernels.push(("avx2", |l, p, n, w| unsafe { sums_avx2(l, p, n, w) }));
            }
            if avx512::available() {
                kernels.push(("avx512", |l, p, n, w| unsafe { sums_avx512(l, p, n, w) }));
            }
        }
        let mut checked = 0;
        for p in [0.0, 1.0, 2.0] {
            for phi in [0.0, 0.4, 1.9, PI] {
                for x in [0.3, 0.62, 0.9] {
                    for inv_s in [1.5, 8.0, 60.0] {
                        let lobe = NodeLobe { p, phi, x, inv_s };
                        let pieces: Vec<Piece> = (0..5)
                            .map(|i| Piece {
                                mid: -1.6 + 0.7 * i as f64,
                                half: 0.35,
                                g0: -0.4 + 0.3 * p,
                                ell: 0.05 + 0.8 * x,
                            })
                            .collect();
                        let (want, size) = scalar(lobe, &pieces, &rule);
                        for (name, kernel) in &kernels {
                            let got = kernel(lobe, &pieces, &rule.nodes, &rule.weights);
                            for k in 0..3 {
                                assert!(
                                    (got[k] - want[k]).abs() <= 1e-13 * size[k],
                                    "{name}: p {p} φ {phi} x {x} k {inv_s}: f{k} {} vs {}",
                                    got[k],
                                    want[k]
                                );
                            }
                            checked += 1;
                        }
                    }
                }
            }
        }
        assert!(checked >= 108);
    }
}

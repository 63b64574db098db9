//! Azimuthal scattering `N_p`: R in closed form, TT and TRT summed over every root, and the TRT
//! glint replacement with its fade past the caustic merge.
//!
//! The geometry (Bravais indices, map, roots, Fresnel factors, caustic) runs in the scalar type
//! `E = T::Scalar` (derivative with respect to the lobe's index `eta` only) and is mapped to `T`
//! by [`ModelNum::chain`] where it meets the other parameters.

use num_dual::{DualNum, DualStruct};

use super::angles::wrap_t;
use super::bravais::Bravais;
use super::chain::ModelNum;
use super::exit_angle::ExitMap;
use super::fresnel::{absorbed, chord, cos_gamma_t, fresnel, fresnel_attenuation};
use super::instrument;
use super::longitudinal::INV_SQRT_TAU;
use super::roots::{exit_roots, lift_root};
use super::RootMode;

/// Smallest `|2 dΦ/dγ|` used. Next to a fold `|2Φ'| ≈ 2·sqrt(2|Φ''|δ)`, so this is reached only
/// within δ ≈ 1e-17 of φ_c, below the f64 resolution of φ, where a root's Φ' is rounding noise
/// (the root itself is only known to ~sqrt(ε)); it keeps N finite and of the size the exact map has
/// one ulp away. With glints on, the fade (~δ²) makes the product vanish anyway.
pub(super) const MIN_DENOM: f64 = 1e-8;

/// Where each lobe's contributions go: per channel, per lobe (0 = R, 1 = TT, 2 = TRT).
pub trait Sink<T> {
    fn add(&mut self, channel: usize, lobe: usize, value: T);
}

/// `N_R(φ) = F(h)·cos γ/4` at the single exact root `γ = −φ/2` (both modes), times `scale`;
/// `br` is at index `eta`.
pub fn add_r<T: ModelNum, S: Sink<T>>(
    br: &Bravais<T::Scalar>,
    eta: &T,
    phi: f64,
    n_channels: usize,
    scale: &T,
    sink: &mut S,
) {
    let (h, cos_gi) = (-0.5 * phi).sin_cos();
    let (h, cos_gi) = (T::Scalar::from(h), T::Scalar::from(cos_gi));
    let cos_gt = cos_gamma_t(&h, &br.eta_p);
    let f = fresnel(&br.eta_p, &br.eta_pp, &cos_gi, &cos_gt);
    // |2 dΦ/dγ| = 4 for p = 0.
    let v = T::chain(&(f * cos_gi * 0.25), eta) * scale.clone();
    for c in 0..n_channels {
        sink.add(c, 0, v.clone());
    }
}

/// `N_p(φ) = Σ_roots A(p, h)/|2 dΦ/dh|` (as `A cos γ / |2 dΦ/dγ|`), times `scale`, for p ≥ 1;
/// `map` and `br` are at index `eta`.
#[allow(clippy::too_many_arguments)]
pub fn add_root_sum<T: ModelNum, S: Sink<T>>(
    p: usize,
    map: &ExitMap<T::Scalar>,
    br: &Bravais<T::Scalar>,
    eta: &T,
    phi: f64,
    sigma_a: &[T],
    scale: &T,
    sink: &mut S,
) {
    let map_f = map.real();
    let roots = exit_roots(&map_f, phi);
    for i in 0..roots.n {
        let g0 = roots.gamma[i];
        let g = lift_root(map, g0, roots.target[i], || map_f.slope(&g0));
        let (h, cos_gi) = g.sin_cos();
        let slope = map.slope(&g);
        let mut denom = if slope.re() < 0.0 { -slope } else { slope } * 2.0;
        if denom.re() < MIN_DENOM {
            denom = T::Scalar::from(MIN_DENOM);
        }
        let cos_gt = cos_gamma_t(&h, &br.eta_p);
        let f = fresnel(&br.eta_p, &br.eta_pp, &cos_gi, &cos_gt);
        let base = T::chain(&(fresnel_attenuation(p, f) * cos_gi / denom), eta) * scale.clone();
        let ch = T::chain(&chord(&cos_gt, &br.cos_theta_t), eta);
        for (c, s) in sigma_a.iter().enumerate() {
            sink.add(c, p, absorbed(p, &base, s, &ch));
        }
    }
}

/// The TRT caustic as the glint sees it: fade `t`, `φ_c`, `(h_c, cos γ_c) = (sin γ_c, cos γ_c)`
/// (in the scalar type `E` of the lobe's index) and `Δh`.
#[derive(Debug, Clone)]
pub struct Glint<T, E> {
    pub t: T,
    pub phi_c: T,
    pub sin_cos_gc: (E, E),
    pub delta_h: T,
}

/// `smoothstep(e0, e1, x)`: 0 below e0, 1 above e1, `u²(3 − 2u)` between.
#[inline]
pub fn smoothstep<T: DualNum<f64>>(e0: f64, e1: &T, x: &T) -> T {
    let u = (x.clone() - e0) / (e1.clone() - e0);
    if u.re() <= 0.0 {
        T::from(0.0)
    } else if u.re() >= 1.0 {
        T::from(1.0)
    } else {
        u.clone() * u.clone() * (-(u * 2.0) + 3.0)
    }
}

/// The glint's parameters, with `1/w_c` computed once per batch.
#[derive(Debug, Clone)]
pub struct GlintParams<T> {
    pub k_g: T,
    pub w_c: T,
    pub inv_w_c: T,
    pub delta_eta_prime: T,
    pub delta_h_m: T,
}

impl<T: DualNum<f64>> GlintParams<T> {
    pub fn new(k_g: &T, w_c: &T, delta_eta_prime: &T, delta_h_m: &T) -> Self {
        GlintParams {
            k_g: k_g.clone(),
            w_c: w_c.clone(),
            inv_w_c: w_c.recip(),
            delta_eta_prime: delta_eta_prime.clone(),
            delta_h_m: delta_h_m.clone(),
        }
    }
}

/// Glint geometry of MODEL.md "TRT: glints": below the merge (η' < 2) the fold of the same map
/// the roots use; at or past it `φ_c = h_c = 0`, `Δh = Δh_M`, `t = 1 − smoothstep(2, 2+Δη', η')`.
/// `map` is at index `eta`.
pub fn glint_geometry<T: ModelNum>(
    map: &ExitMap<T::Scalar>,
    eta: &T,
    glint: &GlintParams<T>,
) -> Glint<T, T::Scalar> {
    let (w_c, delta_h_m) = (&glint.w_c, &glint.delta_h_m);
    instrument::count_caustic();
    if map.eta_p.re() < 2.0 {
        if let Some(gc) = map.caustic() {
            let phi_c = wrap_t(map.value(&gc));
            let phi_c = if phi_c.re() < 0.0 { -phi_c } else { phi_c };
            // sin/cos of γ_c once: the curvature and the glint's A(2, h_c) share them.
            let sin_cos_gc = gc.sin_cos();
            let d2 = map.curvature_at_caustic(&gc, &sin_cos_gc);
            let d2 = if d2.re() < 0.0 { -d2 } else { d2 };
            // Δh = min(Δh_M, 2·sqrt(2w_c/|Φ''|)), compared without dividing by a vanishing Φ''.
            let dhm = delta_h_m.re();
            let delta_h = if 8.0 * w_c.re() < dhm * dhm * d2.re() {
                (w_c.clone() * 2.0 / T::chain(&d2, eta)).sqrt() * 2.0
            } else {
                delta_h_m.clone()
            };
            return Glint {
                t: T::from(1.0),
                phi_c: T::chain(&phi_c, eta),
                sin_cos_gc,
                delta_h,
            };
        }
    }
    let upper = glint.delta_eta_prime.clone() + 2.0;
    Glint {
        t: -smoothstep(2.0, &upper, &T::chain(&map.eta_p, eta)) + 1.0,
        phi_c: T::from(0.0),
        sin_cos_gc: (T::Scalar::from(0.0), T::Scalar::from(1.0)),
        delta_h: delta_h_m.clone(),
    }
}

/// Unnormalised `G(x) = exp(−x²/(2w_c²))`, from `1/w_c`.
#[inline]
fn bump<T: DualNum<f64>>(x: T, inv_w_c: &T) -> T {
    let z = x * inv_w_c.clone();
    (z.clone() * z * (-0.5)).exp()
}

/// `N_TRT` with glints, times `scale`: `N_2·(1 − tG(φ−φ_c))(1 − tG(φ+φ_c))` +
/// `t·k_G·A(2, h_c)·Δh·(g(φ−φ_c; w_c) + g(φ+φ_c; w_c))`; `map` and `br` are at index `eta`.
#[allow(clippy::too_many_arguments)]
pub fn add_trt_with_glints<T: ModelNum, S: Sink<T>>(
    map: &ExitMap<T::Scalar>,
    br: &Bravais<T::Scalar>,
    eta: &T,
    phi: f64,
    sigma_a: &[T],
    glint: &GlintParams<T>,
    scale: &T,
    sink: &mut S,
) {
    let gl = glint_geometry(map, eta, glint);
    let dm = wrap_t(-gl.phi_c.clone() + phi);
    let dp = wrap_t(gl.phi_c.clone() + phi);
    // At φ = ±φ_c with t = 1 this factor is exactly 0, so N_2 (∞ there) contributes 0.
    let (g_m, g_p) = (bump(dm, &glint.inv_w_c), bump(dp, &glint.inv_w_c));
    let fade = (-(gl.t.clone() * g_m.clone()) + 1.0) * (-(gl.t.clone() * g_p.clone()) + 1.0);
    add_root_sum(2, map, br, eta, phi, sigma_a, &(fade * scale.clone()), sink);
    if gl.t.re() == 0.0 {
        return;
    }
    // Glint lobes: A(2, h_c) with the exact γ_t at h_c.
    let (h_c, cos_gc) = gl.sin_cos_gc;
    let cos_gt = cos_gamma_t(&h_c, &br.eta_p);
    let f = fresnel(&br.eta_p, &br.eta_pp, &cos_gc, &cos_gt);
    // g(x; w_c) = G(x)/(w_c·√(2π)): reuse the two G values of the fade.
    let lobes = (g_m + g_p) * glint.inv_w_c.clone() * INV_SQRT_TAU;
    let base = T::chain(&fresnel_attenuation(2, f), eta)
        * gl.t
        * glint.k_g.clone()
        * gl.delta_h
        * lobes
        * scale.clone();
    let ch = T::chain(&chord(&cos_gt, &br.cos_theta_t), eta);
    for (c, s) in sigma_a.iter().enumerate() {
        sink.add(c, 2, absorbed(2, &base, s, &ch));
    }
}

/// The root mode's TRT map for a lobe, exposed for tests: `(φ_c, h_c)` of the glint geometry.
pub fn caustic_position(mode: RootMode, eta_p: f64) -> Option<(f64, f64)> {
    let map = ExitMap::new(mode, 2, eta_p);
    if eta_p >= 2.0 {
        return None;
    }
    let gc = map.caustic()?;
    let phi_c = super::angles::wrap(map.value(&gc)).abs();
    Some((phi_c, gc.sin()))
}

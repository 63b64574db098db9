//! One group's `S` on the lanes ([`Lanes::group`]): the half angles, then each lobe's Fresnel
//! attenuation and absorption along its roots of the exit-angle map, and the TRT glints; the
//! lanes off the common path are reported for the scalar model.

use std::f64::consts::FRAC_PI_2;

use super::super::azimuthal::MIN_DENOM;
use super::super::longitudinal::INV_SQRT_TAU;
use super::super::{Angles, ModelConfig, Params, Prepared};
use super::cubic::{piece_root, Cubic, Piece};
use super::functions::LaneFunctions;
use super::steps::{
    bits, bravais, bump, cos_gamma_t, fresnel, gaussian_inv, keep, wrap, BravaisLanes,
};
use super::vector::Lane;

/// The batch's parameters, their parameter-only factors and the effects, for the groups.
pub(super) struct Lanes<'a> {
    pub(super) params: &'a Params<f64>,
    pub(super) prepared: &'a Prepared<f64>,
    pub(super) config: &'a ModelConfig,
}

impl Lanes<'_> {
    /// `M_p(θ_h)`.
    #[inline(always)]
    fn longitudinal<V: Lane>(&self, p: usize, theta_h: V) -> V {
        let (alpha, inv_beta) = self.prepared.shapes[p];
        gaussian_inv(theta_h - alpha, inv_beta)
    }

    /// Add a path through the fiber entering at `h = sin γ_i`: its Fresnel attenuation
    /// `A(p, h)` times `weight`, absorbed along its chord `exp(−p σ_a · 2cos γ_t/cos θ_t)` per
    /// channel, where `mask` is set.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_through_fiber<V: Lane>(
        &self,
        p: usize,
        br: BravaisLanes<V>,
        h: V,
        cos_gi: V,
        weight: V,
        mask: V,
        sums: &mut [V],
    ) {
        let cos_gt = cos_gamma_t(h, br.inv_eta_p);
        let f = fresnel(br.eta_p, br.eta_pp, cos_gi, cos_gt);
        let t = -f + 1.0;
        let attenuation = if p == 1 { t * t } else { t * t * f };
        let base = attenuation * weight;
        let chord = cos_gt * 2.0 * br.inv_cos_theta_t;
        for (sum, &sigma) in sums.iter_mut().zip(&self.params.sigma_a) {
            let e = (chord * sigma * -(p as f64)).exp();
            *sum = *sum + keep(mask, base * e);
        }
    }

    /// Add one lobe's roots: `A cos γ / |2Φ'|` times `scale`, absorbed, where `valid`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_root<V: Lane>(
        &self,
        p: usize,
        map: &Cubic<V>,
        br: BravaisLanes<V>,
        g: V,
        valid: V,
        scale: V,
        sums: &mut [V],
    ) {
        let (h, cos_gi) = g.sin_cos();
        let denom = map.slope(g).abs() * 2.0;
        let denom = denom
            .cmp_lt(V::splat(MIN_DENOM))
            .blend(V::splat(MIN_DENOM), denom);
        self.add_through_fiber(p, br, h, cos_gi, cos_gi / denom * scale, valid, sums);
    }

    /// `S` of `V::LANES` samples into `sums` (one vector per channel); returns the lanes the
    /// scalar model must evaluate instead, as bits.
    #[inline(always)]
    pub(super) fn group<V: Lane>(&self, angles: &[Angles], sums: &mut [V]) -> u32 {
        let angles = &angles[..V::LANES];
        // `half_angles` on the lanes (the same operations, so the same bits); a φ_r − φ_i
        // beyond ±4π, which `wrap` would need its fmod for, is the scalar model's.
        let theta_i = V::from_fn(|l| angles[l].theta_i);
        let theta_r = V::from_fn(|l| angles[l].theta_r);
        let phi_i = V::from_fn(|l| angles[l].phi_i);
        let phi_r = V::from_fn(|l| angles[l].phi_r);
        let theta_h = (theta_i + theta_r) * 0.5;
        let theta_d = (theta_r - theta_i) * 0.5;
        let (phi, far) = wrap(phi_r - phi_i);
        let phi_h = (phi_i + phi_r) * 0.5;
        let mut irregular = bits(far);
        let (sin_td, cos_td) = theta_d.sin_cos();
        let inv_cos_td = V::ONE / cos_td;
        let inv_cos2 = inv_cos_td * inv_cos_td;
        let lobes = self.config.effects.lobes;
        let all = V::splat(f64::from_bits(u64::MAX));
        sums.fill(V::ZERO);

        if lobes.r || lobes.tt {
            let br = bravais(V::splat(self.params.eta), sin_td, cos_td, inv_cos_td);
            if lobes.r {
                let m = self.longitudinal(0, theta_h) * inv_cos2;
                let (h, cos_gi) = (phi * -0.5).sin_cos();
                let cos_gt = cos_gamma_t(h, br.inv_eta_p);
                let f = fresnel(br.eta_p, br.eta_pp, cos_gi, cos_gt);
                let v = f * cos_gi * 0.25 * m;
                for sum in sums.iter_mut() {
                    *sum = *sum + v;
                }
            }
            if lobes.tt {
                let m = self.longitudinal(1, theta_h) * inv_cos2;
                let map = Cubic::new(1, br.inv_eta_p);
                // A TT fold (η' < 1.155) splits the map: the scalar model's case.
                irregular |= bits(map.folds() | !br.eta_p.cmp_ge(V::ONE));
                let whole = Piece {
                    lo: V::splat(-FRAC_PI_2),
                    hi: V::splat(FRAC_PI_2),
                    f_lo: map.value(V::splat(-FRAC_PI_2)),
                    f_hi: map.value(V::splat(FRAC_PI_2)),
                    j: 1.0,
                };
                let (g, valid, bad) = piece_root(&map, &whole, V::ZERO, phi, all);
                irregular |= bits(bad);
                if bits(valid) != 0 {
                    self.add_root(1, &map, br, g, valid, m, sums);
                }
            }
        }
        if lobes.trt {
            let eta = if self.config.effects.eccentricity {
                let (sum, diff) = self.prepared.eccentric;
                (V::splat(diff) * (phi_h * 2.0).cos() + sum) * 0.5
            } else {
                V::splat(self.params.eta)
            };
            let br = bravais(eta, sin_td, cos_td, inv_cos_td);
            irregular |= bits(!br.eta_p.cmp_ge(V::ONE));
            let m = self.longitudinal(2, theta_h) * inv_cos2;
            let map = Cubic::new(2, br.inv_eta_p);
            let (r, has_caustic) = map.caustic();
            let gc = keep(has_caustic, r);
            let glint = if self.config.effects.glints {
                let (glint, bad) = self.glint_geometry(&map, br.eta_p, gc, has_caustic, phi);
                irregular |= bad;
                Some(glint)
            } else {
                None
            };
            let scale = glint.as_ref().map_or(m, |gl| gl.fade * m);
            // Pieces in γ order: below −γ_c, between ±γ_c (the whole domain without a caustic),
            // above γ_c.
            let half_pi = V::splat(FRAC_PI_2);
            let (f_bottom, f_top) = (map.value(-half_pi), map.value(half_pi));
            let (f_minus, f_plus) = (map.value(-gc), map.value(gc));
            let pieces = [
                (
                    Piece {
                        lo: -half_pi,
                        hi: -gc,
                        f_lo: f_bottom,
                        f_hi: f_minus,
                        j: 2.0,
                    },
                    has_caustic,
                ),
                (
                    Piece {
                        lo: has_caustic.blend(-gc, -half_pi),
                        hi: has_caustic.blend(gc, half_pi),
                        f_lo: has_caustic.blend(f_minus, f_bottom),
                        f_hi: has_caustic.blend(f_plus, f_top),
                        j: 1.0,
                    },
                    all,
                ),
                (
                    Piece {
                        lo: gc,
                        hi: half_pi,
                        f_lo: f_plus,
                        f_hi: f_top,
                        j: 0.0,
                    },
                    has_caustic,
                ),
            ];
            for (piece, active) in &pieces {
                if bits(*active) == 0 {
                    continue;
                }
                let (g, valid, bad) = piece_root(&map, piece, r, phi, *active);
                irregular |= bits(bad);
                if bits(valid) != 0 {
                    self.add_root(2, &map, br, g, valid, scale, sums);
                }
            }
            if let Some(gl) = glint {
                self.add_glint(&gl, br, m, sums);
            }
        }
        irregular
    }

    /// `glint_geometry` and the fade of `add_trt_with_glints` on the lanes; the second value
    /// flags lanes whose `φ_c` the two-branch wrap does not cover.
    #[inline(always)]
    fn glint_geometry<V: Lane>(
        &self,
        map: &Cubic<V>,
        eta_p: V,
        gc: V,
        has_caustic: V,
        phi: V,
    ) -> (GlintLanes<V>, u32) {
        let below = eta_p.cmp_lt(V::splat(2.0)) & has_caustic;
        let (phi_c, bad_wrap) = wrap(map.value(gc));
        let phi_c = keep(below, phi_c.abs());
        let (sin_gc, cos_gc) = gc.sin_cos();
        let d2 = (map.a * gc * 6.0 / (cos_gc * cos_gc)).abs();
        let glint = &self.prepared.glint;
        let (w_c, dhm) = (glint.w_c, glint.delta_h_m);
        let narrow = V::splat(8.0 * w_c).cmp_lt(d2 * (dhm * dhm));
        let delta_h_caustic = narrow.blend((V::splat(w_c * 2.0) / d2).sqrt() * 2.0, V::splat(dhm));
        // Past the merge: t = 1 − smoothstep(2, 2 + Δη', η').
        let upper = glint.delta_eta_prime + 2.0;
        let u = (eta_p - 2.0) / (upper - 2.0);
        let smooth = u.cmp_le(V::ZERO).blend(
            V::ZERO,
            u.cmp_ge(V::ONE).blend(V::ONE, u * u * (-(u * 2.0) + 3.0)),
        );
        let t = below.blend(V::ONE, -smooth + 1.0);
        let (dm, bad_m) = wrap(-phi_c + phi);
        let (dp, bad_p) = wrap(phi_c + phi);
        let (g_m, g_p) = (bump(dm, glint.inv_w_c), bump(dp, glint.inv_w_c));
        let fade = (-(t * g_m) + 1.0) * (-(t * g_p) + 1.0);
        let bad = bits((below & bad_wrap) | bad_m | bad_p);
        (
            GlintLanes {
                t,
                h_c: keep(below, sin_gc),
                cos_gc: below.blend(cos_gc, V::ONE),
                delta_h: below.blend(delta_h_caustic, V::splat(dhm)),
                g_sum: g_m + g_p,
                fade,
            },
            bad,
        )
    }

    /// The glint lobes `t·k_G·A(2, h_c)·Δh·(g(φ−φ_c) + g(φ+φ_c))` times `m`.
    #[inline(always)]
    fn add_glint<V: Lane>(&self, gl: &GlintLanes<V>, br: BravaisLanes<V>, m: V, sums: &mut [V]) {
        let on = gl.t.cmp_ne(V::ZERO);
        if bits(on) == 0 {
            return;
        }
        let glint = &self.prepared.glint;
        let lobes = gl.g_sum * glint.inv_w_c * INV_SQRT_TAU;
        let weight = gl.t * glint.k_g * gl.delta_h * lobes * m;
        self.add_through_fiber(2, br, gl.h_c, gl.cos_gc, weight, on, sums);
    }
}

/// The TRT glint on the lanes.
struct GlintLanes<V> {
    t: V,
    h_c: V,
    cos_gc: V,
    delta_h: V,
    /// `G(φ−φ_c) + G(φ+φ_c)`.
    g_sum: V,
    /// `(1 − tG(φ−φ_c))(1 − tG(φ+φ_c))`.
    fade: V,
}

#[cfg(test)]
mod tests {
    use wide::f64x4;

    use super::super::steps::uniform;
    use super::*;

    /// The fast path is the common path: on random directions with typical parameters (all
    /// effects) fewer than 1% of the samples go to the scalar model. (Agreement with the scalar
    /// model is tested in tests/families/marschner_lanes.rs; this catches a fast path that silently hands
    /// everything back, which would stay correct but lose the speed.)
    #[test]
    fn few_samples_leave_the_fast_path() {
        // The demo's parameters: mid-range values, three channels.
        let params = crate::families::marschner::demo::demo_truth();
        let mut state = 0x9E37_79B9_7F4A_7C15;
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * uniform(&mut state);
        let angles: Vec<Angles> = (0..20_000)
            .map(|_| {
                Angles::from_degrees(
                    u(-85.0, 85.0),
                    u(-360.0, 360.0),
                    u(-85.0, 85.0),
                    u(-360.0, 360.0),
                )
            })
            .collect();
        let config = ModelConfig::default();
        let prepared = Prepared::new(&params);
        let lanes = Lanes {
            params: &params,
            prepared: &prepared,
            config: &config,
        };
        let mut sums = vec![f64x4::ZERO; 3];
        let fell_back: u32 = angles
            .chunks_exact(f64x4::LANES)
            .map(|g| lanes.group(g, &mut sums).count_ones())
            .sum();
        assert!(
            (fell_back as usize) * 100 < angles.len(),
            "{fell_back} of {} samples left the fast path",
            angles.len()
        );
    }
}

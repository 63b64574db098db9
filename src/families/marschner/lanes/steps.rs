//! The small per-lane steps the lobes share, each the vector form of a scalar model's function
//! with the same IEEE operations: masks as values and bits ([`keep`], [`bits`]), [`ceil`], the
//! azimuth's [`wrap`], the Gaussians, the Bravais indices and Fresnel's `F`.

use std::f64::consts::{PI, TAU};

use super::super::longitudinal::INV_SQRT_TAU;
use super::functions::LaneFunctions;
use super::vector::Lane;

/// `x` where `mask` is set, else 0.
#[inline(always)]
pub(super) fn keep<V: Lane>(mask: V, x: V) -> V {
    mask.blend(x, V::ZERO)
}

/// Lanes set in `mask`, as bits.
#[inline(always)]
pub(super) fn bits<V: Lane>(mask: V) -> u32 {
    mask.move_mask() as u32
}

/// `ceil` without libm, as [`super::functions::floor`].
#[inline(always)]
pub(super) fn ceil<V: Lane>(x: V) -> V {
    let r = x.round();
    r + keep(r.cmp_lt(x), V::ONE)
}

/// `angles::wrap` for `|x| < 4π` (the same bits); lanes outside that range (and at exactly −2π,
/// where fmod gives −0) are reported in the second value. On (−4π, −2π) `wrap` takes
/// `fmod(x, 2π)`, which is exact, and `x + 2π` is exact there too (Sterbenz), so they agree.
#[inline(always)]
pub(super) fn wrap<V: Lane>(x: V) -> (V, V) {
    let inside = x.abs().cmp_lt(V::splat(TAU));
    let once = x.cmp_ge(V::splat(TAU)) & x.cmp_lt(V::splat(2.0 * TAU));
    let once_below = x.cmp_gt(V::splat(-2.0 * TAU)) & x.cmp_lt(V::splat(-TAU));
    let r = inside.blend(x, once_below.blend(x + TAU, x - TAU));
    let y = r.cmp_lt(V::ZERO).blend(r + TAU, r);
    let y = y.cmp_gt(V::splat(PI)).blend(y - TAU, y);
    (y, !(inside | once | once_below))
}

/// The glint's unnormalised Gaussian `exp(−(x/w)²/2)`, `inv_w = 1/w`.
#[inline(always)]
pub(super) fn bump<V: Lane>(x: V, inv_w: f64) -> V {
    let z = x * inv_w;
    (z * z * -0.5).exp()
}

/// `gaussian_inv(x, inv_s)`.
#[inline(always)]
pub(super) fn gaussian_inv<V: Lane>(x: V, inv_s: f64) -> V {
    let z = x * inv_s;
    (z * z * -0.5).exp() * inv_s * INV_SQRT_TAU
}

/// The Bravais indices of [`super::super::bravais::bravais_indices`] with the reciprocals the lobes
/// divide by, all from one division: `root = sqrt(η² − sin²θ_d)`, `η' = root/cos θ_d`,
/// `η'' = η² cos θ_d/root`, `cos θ_t = root/η`.
#[derive(Clone, Copy)]
pub(super) struct BravaisLanes<V> {
    pub(super) eta_p: V,
    pub(super) eta_pp: V,
    pub(super) inv_eta_p: V,
    pub(super) inv_cos_theta_t: V,
}

#[inline(always)]
pub(super) fn bravais<V: Lane>(eta: V, sin_td: V, cos_td: V, inv_cos_td: V) -> BravaisLanes<V> {
    let s2 = sin_td * sin_td;
    let eta2 = eta * eta;
    let root = (eta2 - s2).sqrt();
    let inv_root = V::ONE / root;
    BravaisLanes {
        eta_p: root * inv_cos_td,
        eta_pp: eta2 * cos_td * inv_root,
        inv_eta_p: cos_td * inv_root,
        inv_cos_theta_t: eta * inv_root,
    }
}

/// `cos γ_t = sqrt(1 − (h/η')²)`.
#[inline(always)]
pub(super) fn cos_gamma_t<V: Lane>(h: V, inv_eta_p: V) -> V {
    let x = h * inv_eta_p;
    (-(x * x) + 1.0).sqrt()
}

/// Fresnel `F` as [`super::super::fresnel::fresnel`].
#[inline(always)]
pub(super) fn fresnel<V: Lane>(eta_p: V, eta_pp: V, cos_gi: V, cos_gt: V) -> V {
    let a = eta_p * cos_gt;
    let b = eta_pp * cos_gi;
    let (n_s, d_s) = (cos_gi - a, cos_gi + a);
    let (n_p, d_p) = (b - cos_gt, b + cos_gt);
    let (s, q) = (n_s * d_p, n_p * d_s);
    let d = d_s * d_p;
    (s * s + q * q) / (d * d) * 0.5
}

/// xorshift64 in [0, 1), for the lanes' tests.
#[cfg(test)]
pub(super) fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

#[cfg(test)]
mod tests {
    use wide::f64x4;

    use super::*;

    /// The lanes' `wrap` gives `angles::wrap`'s bits wherever it does not hand the lane back,
    /// and hands back only |x| ≥ 4π and −2π itself.
    #[test]
    fn wrap_gives_the_scalar_bits() {
        let mut state = 0x2545_F491_4F6C_DD1D;
        let mut xs: Vec<f64> = (0..40_000)
            .map(|_| (uniform(&mut state) - 0.5) * 9.0 * PI)
            .collect();
        for edge in [-2.0 * TAU, -TAU, -PI, 0.0, PI, TAU, 2.0 * TAU] {
            xs.extend([edge, edge.next_up(), edge.next_down()]);
        }
        xs.extend([-0.0, 0.0]);
        for c in xs.chunks(4) {
            let lanes: [f64; 4] = std::array::from_fn(|l| *c.get(l).unwrap_or(&c[0]));
            let (y, far) = wrap(f64x4::new(lanes));
            let (y, far) = (y.to_array(), far.to_array());
            for l in 0..4 {
                let x = lanes[l];
                let handed_back = far[l].to_bits() != 0;
                assert_eq!(handed_back, x.abs() >= 2.0 * TAU || x == -TAU, "{x}");
                if !handed_back {
                    assert_eq!(
                        y[l].to_bits(),
                        super::super::super::angles::wrap(x).to_bits(),
                        "{x}"
                    );
                }
            }
        }
    }
}

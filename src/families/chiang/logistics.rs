//! The azimuthal logistic of every width node of one exit direction on f64 vectors (one AVX-512
//! register, two AVX2 registers, or a `wide::f64x4`), with the shared lanes' `exp` (within 1 ulp
//! of libm). One `exp` per node and lobe was a third of a Chiang fit at narrow β_n, where a
//! direction has hundreds of nodes; [`super::fixed_eta`] sums these weighted values into its
//! lobe table. Every kernel gives the same bits; the tests hold them to the scalar formula.

use std::f64::consts::TAU;

use crate::families::shared::lanes::functions::LaneFunctions;
use crate::families::shared::lanes::slices::dispatch;
use crate::families::shared::lanes::vector::Lane;

/// The trimmed logistic at one β_n: `ℓ(x) = norm·e/(1 + e)²`, `e = exp(−|x|/s)`, and what its
/// β_n-derivative needs, `∂ℓ/∂β_n = ℓ·(∂ ln norm/∂s + u·tanh(u/2)/s)·∂s/∂β_n`, `u = |x|/s`.
#[derive(Clone, Copy, Debug)]
pub(super) struct LogisticShape {
    pub inv_s: f64,
    pub norm: f64,
    /// `∂ ln norm/∂s`.
    pub d_ln_norm: f64,
    /// `∂s/∂β_n`.
    pub ds: f64,
}

dispatch!(
    /// `value[k] = w_k·ℓ(−Φ_k − φ)` for every node `k` (`exit` the nodes' exit azimuths `Φ_k`,
    /// `weight` their weights, `value` as long), and with `slope` its β_n-derivative likewise.
    /// The values do not depend on whether slopes are asked for.
    pub(super) weighted_logistics,
    logistics,
    (
        shape: LogisticShape,
        phi: f64,
        exit: &[f64],
        weight: &[f64],
        value: &mut [f64],
        slope: Option<&mut [f64]>
    )
);

#[inline(always)]
fn logistics<V: Lane>(
    shape: LogisticShape,
    phi: f64,
    exit: &[f64],
    weight: &[f64],
    value: &mut [f64],
    mut slope: Option<&mut [f64]>,
) {
    assert!(exit.len() == weight.len() && value.len() == exit.len());
    assert!(slope.as_ref().is_none_or(|s| s.len() == exit.len()));
    let lanes = V::LANES;
    let mut start = 0;
    while start < exit.len() {
        // The last vector is padded with zero weights (their lanes are discarded).
        let n = lanes.min(exit.len() - start);
        let at = |xs: &[f64], l: usize| if l < n { xs[start + l] } else { 0.0 };
        let x = wrap(-V::from_fn(|l| at(exit, l)) - phi);
        let w = V::from_fn(|l| at(weight, l));
        let u = x.abs() * shape.inv_s;
        let e = (-u).exp();
        let inv_d = V::ONE / (e + 1.0);
        let l = e * shape.norm * inv_d * inv_d;
        let v = (l * w).to_array();
        value[start..start + n].copy_from_slice(&v.as_ref()[..n]);
        if let Some(s) = slope.as_deref_mut() {
            let d = l * ((u * (-e + 1.0) * inv_d * shape.inv_s) + shape.d_ln_norm) * shape.ds * w;
            s[start..start + n].copy_from_slice(&d.to_array().as_ref()[..n]);
        }
        start += n;
    }
}

/// `x` wrapped to [−π, π] by its nearest whole turn (only |x| matters: ℓ is even and equal at
/// ±π).
#[inline(always)]
fn wrap<V: Lane>(x: V) -> V {
    x - (x * (1.0 / TAU)).round() * TAU
}

#[cfg(test)]
mod tests {
    use super::*;
    #[cfg(target_arch = "x86_64")]
    use crate::families::shared::lanes::{avx2, avx512, vector::Pair};
    use std::f64::consts::PI;
    use wide::f64x4;

    /// The scalar formula, with libm's `exp`.
    fn scalar(shape: LogisticShape, x: f64) -> (f64, f64) {
        let x = x - (x / TAU).round() * TAU;
        let u = x.abs() * shape.inv_s;
        let e = (-u).exp();
        let inv_d = 1.0 / (e + 1.0);
        let l = e * shape.norm * inv_d * inv_d;
        let d = l * (u * (1.0 - e) * inv_d * shape.inv_s + shape.d_ln_norm) * shape.ds;
        (l, d)
    }

    fn run<V: Lane>(
        shape: LogisticShape,
        phi: f64,
        exit: &[f64],
        weight: &[f64],
        slopes: bool,
    ) -> (Vec<f64>, Vec<f64>) {
        let mut v = vec![0.0; exit.len()];
        let mut s = vec![0.0; exit.len()];
        logistics::<V>(
            shape,
            phi,
            exit,
            weight,
            &mut v,
            slopes.then_some(&mut s[..]),
        );
        (v, s)
    }

    /// Every kernel this CPU runs gives the same bits, with or without slopes; each value is
    /// the scalar formula's to 1e-14 relative (the `exp` within 1 ulp, amplified at most by
    /// `u ≤ π/s` ≈ 170 at the narrowest β_n in the last bits of `e`'s argument), for partial
    /// vectors and exit azimuths several turns out.
    #[test]
    fn kernels_match_the_scalar_formula() {
        for s in [0.02, 0.1, 0.6] {
            let shape = LogisticShape {
                inv_s: 1.0 / s,
                norm: 1.0 / (4.0 * s),
                d_ln_norm: -0.3,
                ds: 0.7,
            };
            for len in [1, 7, 8, 9, 23, 64] {
                let exit: Vec<f64> = (0..len)
                    .map(|k| -3.0 * PI + 6.5 * PI * k as f64 / len as f64)
                    .collect();
                let weight: Vec<f64> = (0..len).map(|k| 0.01 + 1e-3 * k as f64).collect();
                let phi = 0.3;
                let (v, d) = run::<f64x4>(shape, phi, &exit, &weight, true);
                let (v_only, _) = run::<f64x4>(shape, phi, &exit, &weight, false);
                assert_eq!(v, v_only, "values do not depend on the slopes");
                #[cfg(target_arch = "x86_64")]
                {
                    if avx2::available() {
                        assert_eq!((v.clone(), d.clone()), unsafe {
                            avx2_run(shape, phi, &exit, &weight)
                        });
                    }
                    if avx512::available() {
                        assert_eq!((v.clone(), d.clone()), unsafe {
                            avx512_run(shape, phi, &exit, &weight)
                        });
                    }
                }
                for k in 0..len {
                    let (l, dl) = scalar(shape, -exit[k] - phi);
                    let (l, dl) = (l * weight[k], dl * weight[k]);
                    assert!(
                        (v[k] - l).abs() <= 1e-14 * l.abs(),
                        "s {s} k {k}: {} vs {l}",
                        v[k]
                    );
                    assert!(
                        (d[k] - dl).abs() <= 1e-14 * dl.abs().max(l.abs()),
                        "s {s} k {k}: {} vs {dl}",
                        d[k]
                    );
                }
            }
        }
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2")]
    unsafe fn avx2_run(
        shape: LogisticShape,
        phi: f64,
        exit: &[f64],
        weight: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        run::<Pair<avx2::F64x4>>(shape, phi, exit, weight, true)
    }

    #[cfg(target_arch = "x86_64")]
    #[target_feature(enable = "avx2,avx512f,avx512dq")]
    unsafe fn avx512_run(
        shape: LogisticShape,
        phi: f64,
        exit: &[f64],
        weight: &[f64],
    ) -> (Vec<f64>, Vec<f64>) {
        run::<avx512::F64x8>(shape, phi, exit, weight, true)
    }
}

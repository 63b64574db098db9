//! Renderer variants of the Chiang model: where a renderer's formulation differs from pbrt-v4's
//! (CHIANG.md "Sign of α", "Renderer parameter names"), the variant's `S` in the project's
//! convention, generic over the number type like the rest of the module so a variant can be
//! FITTED with exact Jacobians instead of converted by a formula.
//!
//! Two differences are modelled, everything else is reused from pbrt-v4's evaluator (the width
//! integral `Ñ_p`, `Ā₃` does not see either):
//! - the cuticle tilt on the incidence θ_i, `θ'_i = θ_i + (+2α, −α, −4α, 0)_p` (pbrt-v3 before
//!   2019, Cycles, MaterialX), instead of on the exit θ_r;
//! - a constant factor on `f` (MaterialX's extra `1/π`) with a fitted grey gain (MaterialX's
//!   `tint_R = tint_TT = tint_TRT`; the residual p ≥ 3 uses `tint_TRT`).

use nalgebra::{Const, U1};
use num_dual::{DualDVec64, DualNum, DualSVec64};

use super::evaluator::for_each_with_table;
use super::jacobian::split_duals;
use super::longitudinal::{base_variance, longitudinal};
use super::{combine, ChiangModel, ChiangParams};
use crate::families::shared::longitudinal::{lobe_variance, longitudinal_lobe};
use crate::geometry::Angles;

/// Tilt of the incidence per lobe in units of α for the θ_i-tilt renderers:
/// `θ'_i = θ_i + INCIDENCE_TILT[p]·α` (R +2α, TT −α, TRT −4α, residual 0).
pub const INCIDENCE_TILT: [f64; 4] = [2.0, -1.0, -4.0, 0.0];

/// Which inclination carries the cuticle tilt.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Tilt {
    /// pbrt-v4 (and pbrt-v3 after c65c588): on θ_r.
    Exit,
    /// pbrt-v3 before c65c588, Cycles, MaterialX: on θ_i.
    Incidence,
}

/// How one renderer's `f` differs from pbrt-v4's.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Formulation {
    pub tilt: Tilt,
    /// Constant factor the renderer puts on `f` (MaterialX: 1/π).
    pub factor: f64,
    /// Whether the renderer has a per-lobe tint that can carry a fitted gain.
    pub gain: bool,
}

impl Formulation {
    /// pbrt-v4's `hair`: the reference, no difference.
    pub const PBRT_V4: Formulation = Formulation {
        tilt: Tilt::Exit,
        factor: 1.0,
        gain: false,
    };
    /// Blender Cycles' Principled Hair BSDF (Chiang): θ_i tilt, no tint on the Chiang lobes.
    pub const CYCLES: Formulation = Formulation {
        tilt: Tilt::Incidence,
        factor: 1.0,
        gain: false,
    };
    /// MaterialX `chiang_hair_bsdf`: θ_i tilt, `f/π`, grey tints as a gain.
    pub const MATERIALX: Formulation = Formulation {
        tilt: Tilt::Incidence,
        factor: std::f64::consts::FRAC_1_PI,
        gain: true,
    };
}

/// A variant's parameters: pbrt-v4's set (α in radians, with the variant's own sign meaning)
/// and the gain (1 where the renderer has none).
#[derive(Debug, Clone, PartialEq)]
pub struct VariantParams<T> {
    pub chiang: ChiangParams<T>,
    pub gain: T,
}

/// `(sin θ'_i, |cos θ'_i|)` with `θ'_i = θ_i + INCIDENCE_TILT[p]·α`.
#[inline]
pub fn tilted_incidence<T: DualNum<f64>>(p: usize, theta_i: f64, alpha: &T) -> (T, T) {
    let (s, c) = (alpha.clone() * INCIDENCE_TILT[p] + theta_i).sin_cos();
    let c = if c.re() < 0.0 { -c } else { c };
    (s, c)
}

/// `M_p` with the tilt on the incidence: `M(θ'_i, θ_r; v_p)`. `M(a, b; v)` is symmetric in a
/// and b, so pbrt-v4's lobe is reused with the untilted θ_r in the plain slot.
#[inline]
pub fn longitudinal_incidence_tilt<T: DualNum<f64>>(
    p: usize,
    theta_i: f64,
    theta_r: f64,
    alpha: &T,
    v0: &T,
) -> T {
    let (sin_r, cos_r) = theta_r.sin_cos();
    let (sin_i, cos_i) = tilted_incidence(p, theta_i, alpha);
    longitudinal_lobe(sin_r, cos_r, &sin_i, &cos_i, &lobe_variance(p, v0))
}

/// `M_p` for p = 0..3 under `tilt` (0 where the model's effects switch a term off).
pub fn variant_longitudinal_terms<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    model: &ChiangModel,
    tilt: Tilt,
    theta_i: f64,
    theta_r: f64,
) -> [T; 4] {
    let e = &model.effects;
    let on = [e.r, e.tt, e.trt, e.residual];
    let v0 = base_variance(&params.beta_m);
    std::array::from_fn(|p| match (on[p], tilt) {
        (false, _) => T::from(0.0),
        (true, Tilt::Exit) => longitudinal(p, theta_i, theta_r, &params.alpha, &v0),
        (true, Tilt::Incidence) => {
            longitudinal_incidence_tilt(p, theta_i, theta_r, &params.alpha, &v0)
        }
    })
}

/// The variant's `S` for a batch, `out[k·n + c]` (n channels), with one width integral per
/// distinct (θ_r, |φ|) as in [`super::scattering_batch`]: `factor · gain · S_variant`.
pub fn variant_scattering_batch<T: DualNum<f64>>(
    params: &VariantParams<T>,
    formulation: &Formulation,
    model: &ChiangModel,
    angles: &[Angles],
    out: &mut [T],
) {
    let chiang = &params.chiang;
    let scale = params.gain.clone() * formulation.factor;
    for_each_with_table(chiang, model, angles, out, |a, table, row| {
        let m = variant_longitudinal_terms(chiang, model, formulation.tilt, a.theta_i, a.theta_r);
        let cos_i = a.theta_i.cos();
        for (c, o) in row.iter_mut().enumerate() {
            *o = combine(&m, &table.lobes[c], &table.residual[c], cos_i) * scale.clone();
        }
    });
}

/// Values and Jacobian of the variant's `S` with respect to `x`, where `to_params` builds the
/// variant's parameters from the free variables (e.g. through a positivity transform):
/// `jac[k·n + c][j] = ∂S/∂x_j`, exact by forward-mode AD.
pub fn variant_jacobian(
    x: &[f64],
    to_params: impl Fn(&[DualDVec64]) -> VariantParams<DualDVec64>,
    formulation: &Formulation,
    model: &ChiangModel,
    angles: &[Angles],
) -> (Vec<f64>, Vec<Vec<f64>>) {
    let k = x.len();
    let seeded: Vec<DualDVec64> = x
        .iter()
        .enumerate()
        .map(|(j, &v)| DualDVec64::from_re(v).derivative(k, j))
        .collect();
    let params = to_params(&seeded);
    let n = params.chiang.sigma_a.len();
    let mut out = vec![DualDVec64::from_re(0.0); angles.len() * n];
    variant_scattering_batch(&params, formulation, model, angles, &mut out);
    split_duals(out, k)
}

/// The same with `N` free variables known at compile time (stack duals: no allocation per
/// operation, the fast path for a mapping fit).
pub fn variant_jacobian_static<const N: usize>(
    x: &[f64; N],
    to_params: impl Fn(&[DualSVec64<N>]) -> VariantParams<DualSVec64<N>>,
    formulation: &Formulation,
    model: &ChiangModel,
    angles: &[Angles],
) -> (Vec<f64>, Vec<[f64; N]>) {
    let seeded: Vec<DualSVec64<N>> = x
        .iter()
        .enumerate()
        .map(|(j, &v)| DualSVec64::<N>::from_re(v).derivative(j))
        .collect();
    let params = to_params(&seeded);
    let n = params.chiang.sigma_a.len();
    let mut out = vec![DualSVec64::<N>::from_re(0.0); angles.len() * n];
    variant_scattering_batch(&params, formulation, model, angles, &mut out);
    let values = out.iter().map(|d| d.re).collect();
    let jac = out
        .iter()
        .map(|d| {
            let mut row = [0.0; N];
            row.copy_from_slice(d.eps.unwrap_generic(Const::<N>, U1).as_slice());
            row
        })
        .collect();
    (values, jac)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::chiang::{scattering_batch, ChiangEffects};

    fn params(alpha_deg: f64) -> ChiangParams<f64> {
        ChiangParams {
            eta: 1.55,
            sigma_a: vec![0.4, 1.2],
            beta_m: 0.3,
            beta_n: 0.3,
            alpha: alpha_deg.to_radians(),
        }
    }

    fn rig() -> Vec<Angles> {
        let mut out = Vec::new();
        for ti in [-50.0, -10.0, 20.0, 60.0] {
            for tr in [-40.0, 5.0, 35.0] {
                for phi in [0.0, 30.0, 100.0, 180.0] {
                    out.push(Angles::from_degrees(ti, 0.0, tr, phi));
                }
            }
        }
        out
    }

    /// The pbrt-v4 formulation with gain 1 is pbrt-v4's evaluator, bit for bit.
    #[test]
    fn pbrt_formulation_is_the_reference_evaluator() {
        let model = ChiangModel::new(ChiangEffects::default(), 256).unwrap();
        let p = params(2.0);
        let angles = rig();
        let mut a = vec![0.0; angles.len() * 2];
        let mut b = a.clone();
        scattering_batch(&p, &model, &angles, &mut a);
        let v = VariantParams {
            chiang: p,
            gain: 1.0,
        };
        variant_scattering_batch(&v, &Formulation::PBRT_V4, &model, &angles, &mut b);
        assert_eq!(a, b);
    }

    /// With α = 0 there is no tilt, so every formulation agrees up to its factor (1e-15: only
    /// the argument order of M differs).
    #[test]
    fn without_tilt_the_variants_differ_only_by_their_factor() {
        let model = ChiangModel::new(ChiangEffects::default(), 256).unwrap();
        let angles = rig();
        let v = VariantParams {
            chiang: params(0.0),
            gain: 1.0,
        };
        let mut pbrt = vec![0.0; angles.len() * 2];
        let mut mx = pbrt.clone();
        variant_scattering_batch(&v, &Formulation::PBRT_V4, &model, &angles, &mut pbrt);
        variant_scattering_batch(&v, &Formulation::MATERIALX, &model, &angles, &mut mx);
        for (a, b) in pbrt.iter().zip(&mx) {
            assert!(
                (a / std::f64::consts::PI - b).abs() <= 1e-13 * b.abs(),
                "{a} {b}"
            );
        }
    }

    /// The R lobe of the θ_i-tilt variant peaks at θ_h = −α (CHIANG.md), pbrt-v4's at +α:
    /// at β_m = 0.05 the peak of `S·cos θ_i` over θ_i (R only) for θ_r = 10° sits within 0.05°.
    #[test]
    fn incidence_tilt_puts_r_at_minus_alpha() {
        let effects = ChiangEffects {
            r: true,
            tt: false,
            trt: false,
            residual: false,
        };
        let model = ChiangModel::new(effects, 256).unwrap();
        let mut p = params(3.0);
        p.beta_m = 0.05;
        p.sigma_a = vec![0.4];
        let v = VariantParams {
            chiang: p,
            gain: 1.0,
        };
        let theta_r = 10.0;
        for (formulation, expect) in [(Formulation::PBRT_V4, 3.0), (Formulation::CYCLES, -3.0)] {
            let grid: Vec<f64> = (0..4001).map(|k| -40.0 + 0.01 * k as f64).collect();
            let angles: Vec<Angles> = grid
                .iter()
                .map(|&t| Angles::from_degrees(t, 0.0, theta_r, 0.0))
                .collect();
            let mut s = vec![0.0; angles.len()];
            variant_scattering_batch(&v, &formulation, &model, &angles, &mut s);
            let (k, _) = s
                .iter()
                .zip(&grid)
                .map(|(s, t)| s * t.to_radians().cos())
                .enumerate()
                .fold((0, f64::MIN), |b, (k, x)| if x > b.1 { (k, x) } else { b });
            let theta_h = 0.5 * (grid[k] + theta_r);
            assert!(
                (theta_h - expect).abs() < 0.05,
                "{formulation:?}: {theta_h}"
            );
        }
    }

    /// The AD Jacobian agrees with central differences to 1e-6 relative (step 1e-6: the
    /// truncation error is ~1e-12, rounding ~1e-10 relative).
    #[test]
    fn jacobian_matches_central_differences() {
        let model = ChiangModel::new(ChiangEffects::default(), 256).unwrap();
        let angles = rig();
        let build = |x: &[DualDVec64]| VariantParams {
            chiang: ChiangParams {
                eta: x[0].clone(),
                sigma_a: vec![x[1].clone(), x[1].clone() * 2.0],
                beta_m: x[2].clone(),
                beta_n: x[3].clone(),
                alpha: x[4].clone(),
            },
            gain: x[5].exp(),
        };
        let x = [1.55, 0.4, 0.3, 0.35, 0.04, 0.2];
        let (v, jac) = variant_jacobian(&x, build, &Formulation::MATERIALX, &model, &angles);
        let h = 1e-6;
        for j in 0..x.len() {
            let eval = |d: f64| {
                let mut y = x;
                y[j] += d;
                variant_jacobian(&y, build, &Formulation::MATERIALX, &model, &angles).0
            };
            let (plus, minus) = (eval(h), eval(-h));
            for k in 0..v.len() {
                let fd = (plus[k] - minus[k]) / (2.0 * h);
                let scale = jac.iter().map(|r| r[j].abs()).fold(0.0, f64::max);
                assert!(
                    (fd - jac[k][j]).abs() <= 1e-6 * scale.max(1e-12),
                    "param {j} sample {k}: {fd} vs {}",
                    jac[k][j]
                );
            }
        }
    }
}

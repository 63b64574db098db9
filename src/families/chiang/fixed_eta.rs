//! The fit's evaluator when η is held fixed (every fit without `--free eta`): `S` and its exact
//! derivatives in σ_a, β_m, β_n and α, in plain f64 with the chain rule written out.
//!
//! Why not dual numbers: the width integral's per-node work splits by what it depends on —
//! Fresnel, γ_t, the exit azimuths `Φ_p` and the chord on (θ_r, η); the attenuations `A_p` on
//! (θ_r, σ_a[c]); the logistics on (φ, β_n). With η fixed the first two are computed once per
//! distinct θ_r of a batch ([`ExitColumn`]) and shared by every azimuth, and each derivative of a
//! table entry is in one channel's σ_a or in β_n only. Dual numbers carrying every free direction
//! through every node (the generic path, still used with `--free eta`) do several times the
//! arithmetic for the same numbers. The tests check this path against the dual-number Jacobian.

use std::f64::consts::{FRAC_PI_2, PI};

use num_dual::DualSVec64;

use super::logistics::{weighted_logistics, LogisticShape};
use super::longitudinal::{base_variance, longitudinal};
use super::{
    combine, ChiangEffects, ChiangModel, ChiangParamName, ChiangParams, WidthScratch, WidthSet,
};
use crate::families::shared::cylinder::{attenuations, exit_azimuth, fresnel, ExitRefraction};
use crate::families::shared::lanes::slices;
use crate::families::shared::logistic::{logistic_scale, trimmed_logistic_norm};
use crate::families::shared::quadrature::WidthNode;
use crate::geometry::angles::wrap;
use crate::geometry::Angles;

/// `ds/dβ_n` of [`logistic_scale`].
fn logistic_scale_slope(beta_n: f64) -> f64 {
    const SQRT_PI_OVER_8: f64 = 0.626_657_068_657_750_1;
    SQRT_PI_OVER_8 * (0.265 + 2.0 * 1.194 * beta_n + 22.0 * 5.372 * beta_n.powi(21))
}

/// The per-node quantities of one exit inclination θ_r (η and σ_a fixed): the weight, `F`, the
/// exit azimuths `Φ_p`, and per channel `A_1..A_3` with their σ_a-derivatives; plus the residual
/// `Ā₃ = ⟨A₃⟩_h` (azimuthally uniform) and its σ_a-derivative per channel.
struct ExitColumn {
    /// The exit direction's (θ_r, |φ|) bits; |φ| only when the width nodes depend on it.
    key: (u64, u64),
    weight: Vec<f64>,
    fresnel: Vec<f64>,
    /// The exit azimuths `Φ_p` of every node, by lobe p.
    exit: [Vec<f64>; 3],
    /// `[A_1, A_2]` of node k, channel c at `k·n + c`.
    atten: Vec<[f64; 2]>,
    /// `[∂A_1/∂σ_a, ∂A_2/∂σ_a]`, same layout.
    d_atten: Vec<[f64; 2]>,
    residual: Vec<f64>,
    d_residual: Vec<f64>,
}

impl ExitColumn {
    /// The column over `rule.lobes`; the residual too when the rule is plain (one node set),
    /// else [`ExitColumn::residual`] fills it from `Ā₃` over the residual's own nodes.
    fn new(
        p: &ChiangParams<f64>,
        effects: &ChiangEffects,
        rule: WidthSet,
        key: (u64, u64),
    ) -> Self {
        let n = p.sigma_a.len();
        let exit = ExitGeometry::new(p.eta, f64::from_bits(key.0));
        let residual = effects.residual && std::ptr::eq(rule.lobes, rule.residual);
        let any_lobe = effects.r || effects.tt || effects.trt;
        let nodes = if any_lobe || residual {
            rule.lobes.len()
        } else {
            0
        };
        let transmitted = effects.tt || effects.trt || residual;
        let mut col = ExitColumn {
            key,
            weight: Vec::with_capacity(nodes),
            fresnel: Vec::with_capacity(nodes),
            exit: std::array::from_fn(|_| Vec::with_capacity(nodes)),
            atten: Vec::with_capacity(if transmitted { nodes * n } else { 0 }),
            d_atten: Vec::with_capacity(if transmitted { nodes * n } else { 0 }),
            residual: vec![0.0; n],
            d_residual: vec![0.0; n],
        };
        let rule_nodes = &rule.lobes[..nodes];
        let mut sin_gt = Vec::with_capacity(nodes);
        for node in rule_nodes {
            let (f, s) = exit.fresnel_and_sin_gamma_t(p.eta, node);
            col.weight.push(node.weight);
            col.fresnel.push(f);
            sin_gt.push(s);
        }
        // γ_t and the transmittances on the lanes, every node at once.
        let mut gamma_t = vec![0.0; nodes];
        slices::asin(&sin_gt, &mut gamma_t);
        for (node, gt) in rule_nodes.iter().zip(&gamma_t) {
            for (q, exit) in col.exit.iter_mut().enumerate() {
                exit.push(exit_azimuth(q, node.gamma, gt));
            }
        }
        if !transmitted {
            return col;
        }
        let chord: Vec<f64> = sin_gt.iter().map(|&s| exit.chord(s)).collect();
        let mut t = vec![0.0; nodes];
        col.atten.resize(nodes * n, [0.0; 2]);
        col.d_atten.resize(nodes * n, [0.0; 2]);
        for c in 0..n {
            slices::exp_scaled(-p.sigma_a[c], &chord, &mut t);
            for k in 0..nodes {
                let (f, t, chord) = (col.fresnel[k], t[k], chord[k]);
                // A₁ = (1−F)²T, A₂ = A₁TF as `attenuations`; A₃ (a division) only when used here.
                let a1 = (1.0 - f) * (1.0 - f) * t;
                let a2 = a1 * (t * f);
                col.atten[k * n + c] = [a1, a2];
                col.d_atten[k * n + c] = [-chord * a1, -2.0 * chord * a2];
                if residual {
                    let (a3, d3) = residual_term(t, f, chord);
                    col.residual[c] += a3 * col.weight[k];
                    col.d_residual[c] += d3 * col.weight[k];
                }
            }
        }
        col
    }

    /// `Ā₃ = ⟨A₃⟩_h` and its σ_a-derivative per channel over `nodes` (a plain rule), for the
    /// column's θ_r: what a composite rule's columns share across every azimuth.
    fn residual(p: &ChiangParams<f64>, nodes: &[WidthNode], theta_r: f64) -> [Vec<f64>; 2] {
        let n = p.sigma_a.len();
        let exit = ExitGeometry::new(p.eta, theta_r);
        let (mut value, mut slope) = (vec![0.0; n], vec![0.0; n]);
        let (fresnel, chord): (Vec<f64>, Vec<f64>) = nodes
            .iter()
            .map(|node| {
                let (f, sin_gt) = exit.fresnel_and_sin_gamma_t(p.eta, node);
                (f, exit.chord(sin_gt))
            })
            .unzip();
        let mut t = vec![0.0; nodes.len()];
        for ((sigma, v), d) in p.sigma_a.iter().zip(&mut value).zip(&mut slope) {
            slices::exp_scaled(-sigma, &chord, &mut t);
            for (k, node) in nodes.iter().enumerate() {
                let (a3, d3) = residual_term(t[k], fresnel[k], chord[k]);
                *v += a3 * node.weight;
                *d += d3 * node.weight;
            }
        }
        [value, slope]
    }
}

/// What every node of one exit inclination shares (η fixed): `cos θ_r`, `1/η'`, `2/cos θ_t`.
struct ExitGeometry {
    cos_theta_r: f64,
    inv_eta_prime: f64,
    two_over_cos_tt: f64,
}

impl ExitGeometry {
    fn new(eta: f64, theta_r: f64) -> Self {
        let refraction = ExitRefraction::new(&eta, theta_r);
        ExitGeometry {
            cos_theta_r: refraction.cos_theta_r,
            inv_eta_prime: refraction.eta_prime.recip(),
            two_over_cos_tt: refraction.cos_theta_t.recip() * 2.0,
        }
    }

    /// `(F, sin γ_t)` at `node`.
    #[inline]
    fn fresnel_and_sin_gamma_t(&self, eta: f64, node: &WidthNode) -> (f64, f64) {
        (
            fresnel(&eta, self.cos_theta_r * node.cos_gamma),
            self.inv_eta_prime * node.h,
        )
    }

    /// The chord `2cos γ_t/cos θ_t`.
    #[inline]
    fn chord(&self, sin_gamma_t: f64) -> f64 {
        (-sin_gamma_t.powi(2) + 1.0).sqrt() * self.two_over_cos_tt
    }
}

/// `(A₃, ∂A₃/∂σ_a)` for transmittance `t`: with T = e^{−σ·chord} and q = TF, `A₃ = A₂q/(1−q)`
/// gives `∂A₃ = −chord·A₃·(2 + 1/(1−q))` (as `∂A₁ = −chord·A₁`, `∂A₂ = −2chord·A₂`).
#[inline]
fn residual_term(t: f64, f: f64, chord: f64) -> (f64, f64) {
    let a3 = attenuations(&f, &t)[3];
    let one_minus = 1.0 - t * f;
    let slope = if one_minus == 0.0 {
        0.0
    } else {
        -chord * a3 * (2.0 + one_minus.recip())
    };
    (a3, slope)
}

/// The width-averaged lobes of one exit direction per channel with their derivatives:
/// `lobes[c][p] = Ñ_p`, `d_sigma[c][p] = ∂Ñ_p/∂σ_a[c]`, `d_beta_n[c][p] = ∂Ñ_p/∂β_n`.
struct LobeTable {
    lobes: Vec<[f64; 3]>,
    d_sigma: Vec<[f64; 3]>,
    d_beta_n: Vec<[f64; 3]>,
}

/// The logistic's scale and normalisation at β_n, with what their derivatives need
/// (`∂ ln norm/∂s = (2t/sinh 2t − 1)/s`, `t = π/(2s)`).
fn logistic_shape(beta_n: f64) -> LogisticShape {
    let s = logistic_scale(&beta_n);
    let t = FRAC_PI_2 / s;
    // 2t/sinh 2t → 0 for small s (sinh overflows to ∞ harmlessly), → 1 for large s.
    let ratio = if t < 1e-8 {
        1.0
    } else {
        2.0 * t / (2.0 * t).sinh()
    };
    LogisticShape {
        inv_s: s.recip(),
        norm: trimmed_logistic_norm(&s),
        d_ln_norm: (ratio - 1.0) / s,
        ds: logistic_scale_slope(beta_n),
    }
}

/// Per lobe, the weighted logistic of every node and its β_n-derivative
/// ([`super::logistics::weighted_logistics`]), reused across exit directions.
#[derive(Default)]
struct LogisticScratch {
    value: [Vec<f64>; 3],
    slope: [Vec<f64>; 3],
}

fn lobe_table(
    col: &ExitColumn,
    effects: &ChiangEffects,
    logistic: LogisticShape,
    n: usize,
    phi: f64,
    want_slopes: bool,
    scratch: &mut LogisticScratch,
) -> LobeTable {
    let mut t = LobeTable {
        lobes: vec![[0.0; 3]; n],
        d_sigma: vec![[0.0; 3]; n],
        d_beta_n: vec![[0.0; 3]; n],
    };
    let on = [effects.r, effects.tt, effects.trt];
    let transmitted = !col.atten.is_empty();
    let nodes = col.weight.len();
    let lobes = on.iter().zip(&col.exit);
    for ((value, slope), (&lobe_on, exit)) in
        scratch.value.iter_mut().zip(&mut scratch.slope).zip(lobes)
    {
        value.clear();
        slope.clear();
        value.resize(if lobe_on { nodes } else { 0 }, 0.0);
        slope.resize(if lobe_on && want_slopes { nodes } else { 0 }, 0.0);
        if lobe_on {
            weighted_logistics(
                logistic,
                phi,
                exit,
                &col.weight,
                value,
                want_slopes.then_some(&mut slope[..]),
            );
        }
    }
    let (lv, ls) = (&scratch.value, &scratch.slope);
    let slope_at = |q: usize, k: usize| if want_slopes { ls[q][k] } else { 0.0 };
    for (k, &f) in col.fresnel.iter().enumerate() {
        if effects.r {
            let (r, dr) = (f * lv[0][k], f * slope_at(0, k));
            for c in 0..n {
                t.lobes[c][0] += r;
                t.d_beta_n[c][0] += dr;
            }
        }
        if !transmitted {
            continue;
        }
        for c in 0..n {
            let a = col.atten[k * n + c];
            let da = col.d_atten[k * n + c];
            for q in 1..3 {
                if on[q] {
                    t.lobes[c][q] += a[q - 1] * lv[q][k];
                    t.d_sigma[c][q] += da[q - 1] * lv[q][k];
                    t.d_beta_n[c][q] += a[q - 1] * slope_at(q, k);
                }
            }
        }
    }
    t
}

/// `S` per sample and channel (`out[k·n + c]`), and with `grad` the derivative rows
/// `grad[(k·n + c)·free.len() + j] = ∂S/∂free[j]` (per radian for α). η must not be in `free`
/// (it is held at `params.eta`); values alone are valid for any parameters.
pub fn batch(
    params: &ChiangParams<f64>,
    model: &ChiangModel,
    angles: &[Angles],
    free: &[ChiangParamName],
    out: &mut [f64],
    mut grad: Option<&mut [f64]>,
) {
    let n = params.sigma_a.len();
    let nf = free.len();
    assert_eq!(
        out.len(),
        angles.len() * n,
        "one output per sample and channel"
    );
    assert!(
        !free.contains(&ChiangParamName::Eta),
        "the fixed-η path has no η derivative"
    );
    if let Some(g) = grad.as_deref() {
        assert_eq!(g.len(), out.len() * nf, "one derivative row per output");
    }
    let effects = &model.effects;
    let want_slopes = grad.is_some();
    let logistic = logistic_shape(params.beta_n);
    // Samples by exit direction (θ_r, |φ|) — θ_r first, so one column serves a run of keys.
    let key = |a: &Angles| (a.theta_r, wrap(a.phi_r - a.phi_i).abs());
    let mut order: Vec<usize> = (0..angles.len()).collect();
    order.sort_by(|&i, &j| {
        let (a, b) = (key(&angles[i]), key(&angles[j]));
        a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1))
    });
    // Longitudinal lobes with derivatives in (β_m, α) only: two-direction duals.
    let beta_m = DualSVec64::<2>::from_re(params.beta_m).derivative(0);
    let alpha = DualSVec64::<2>::from_re(params.alpha).derivative(1);
    let v0 = base_variance(&beta_m);
    let v0_value = base_variance(&params.beta_m);
    let on = [effects.r, effects.tt, effects.trt, effects.residual];

    let mut column: Option<ExitColumn> = None;
    let mut scratch = WidthScratch::default();
    let per_direction = model.width().per_direction();
    // A composite rule's `Ā₃` per θ_r: (θ_r bits, [Ā₃, ∂Ā₃/∂σ_a] per channel).
    let mut residual: Option<(u64, [Vec<f64>; 2])> = None;
    let mut table: Option<((u64, u64), LobeTable)> = None;
    let mut logistics = LogisticScratch::default();
    for &i in &order {
        let a = &angles[i];
        let (theta_r, phi) = key(a);
        // A plain rule's column serves every azimuth of θ_r; a composite rule's nodes move with φ.
        let column_key = (
            theta_r.to_bits(),
            if per_direction { phi.to_bits() } else { 0 },
        );
        if column.as_ref().is_none_or(|c| c.key != column_key) {
            let nodes =
                model.width_nodes_for(params.eta, params.beta_n, theta_r, phi, &mut scratch);
            let mut col = ExitColumn::new(params, effects, nodes, column_key);
            if effects.residual && !std::ptr::eq(nodes.lobes, nodes.residual) {
                if residual.as_ref().is_none_or(|r| r.0 != column_key.0) {
                    let r = ExitColumn::residual(params, nodes.residual, theta_r);
                    residual = Some((column_key.0, r));
                }
                let [r, d] = &residual.as_ref().expect("set above").1;
                col.residual.clone_from(r);
                col.d_residual.clone_from(d);
            }
            column = Some(col);
        }
        let col = column.as_ref().expect("set above");
        let bits = (theta_r.to_bits(), phi.to_bits());
        if table.as_ref().is_none_or(|(k, _)| *k != bits) {
            let t = lobe_table(col, effects, logistic, n, phi, want_slopes, &mut logistics);
            table = Some((bits, t));
        }
        let t = &table.as_ref().expect("set above").1;
        let m_value: [f64; 4] = std::array::from_fn(|q| {
            if on[q] {
                longitudinal(q, a.theta_i, a.theta_r, &params.alpha, &v0_value)
            } else {
                0.0
            }
        });
        let cos_i = a.theta_i.cos();
        for c in 0..n {
            out[i * n + c] = combine(&m_value, &t.lobes[c], &col.residual[c], cos_i);
        }
        let Some(g) = grad.as_deref_mut() else {
            continue;
        };
        let m: [DualSVec64<2>; 4] = std::array::from_fn(|q| {
            if on[q] {
                longitudinal(q, a.theta_i, a.theta_r, &alpha, &v0)
            } else {
                DualSVec64::from_re(0.0)
            }
        });
        let dm =
            |q: usize, d: usize| m[q].eps.unwrap_generic(nalgebra::Const::<2>, nalgebra::U1)[d];
        let res_factor = 0.5 / PI;
        for c in 0..n {
            let row = &mut g[(i * n + c) * nf..(i * n + c + 1) * nf];
            let lobes = &t.lobes[c];
            for (slot, name) in row.iter_mut().zip(free) {
                let d = match *name {
                    ChiangParamName::SigmaA(cc) if cc == c => {
                        m_value[1] * t.d_sigma[c][1]
                            + m_value[2] * t.d_sigma[c][2]
                            + m_value[3] * col.d_residual[c] * res_factor
                    }
                    ChiangParamName::SigmaA(_) => 0.0,
                    ChiangParamName::BetaN => (0..3).map(|q| m_value[q] * t.d_beta_n[c][q]).sum(),
                    ChiangParamName::BetaM | ChiangParamName::Alpha => {
                        let d = usize::from(*name == ChiangParamName::Alpha);
                        (0..3).map(|q| dm(q, d) * lobes[q]).sum::<f64>()
                            + dm(3, d) * col.residual[c] * res_factor
                    }
                    ChiangParamName::Eta => unreachable!("checked above"),
                };
                *slot = d / cos_i;
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::chiang::{batch_jacobian, scattering_batch};

    fn angles() -> Vec<Angles> {
        let mut v = Vec::new();
        for (tr, phi) in [
            (25.0, 30.0),
            (-5.0, 170.0),
            (45.0, -80.0),
            (25.0, -30.0),
            (25.0, 0.0),
        ] {
            for ti in [-60.0, -20.0, 10.0] {
                v.push(Angles::from_degrees(ti, 10.0, tr, phi + 10.0));
            }
        }
        v
    }

    /// Values agree with the dual-free batch to rounding, derivatives with the dual-number
    /// Jacobian to 1e-12 relative (the same quantities, summed in the same order; only the
    /// derivative formulas differ in their rounding), for every term switch and β_n from the
    /// narrow-peak to the wide end. This path's `asin` (γ_t) and `exp` are the lanes' (within
    /// 1 ulp of libm), so its exit azimuths differ by a few ulp (~1e-15 rad), and a logistic of
    /// width s moves by that over s: values agree to max(1e-14, 2e-15/s) relative (1.2e-13 at
    /// β_n = 0.05).
    #[test]
    fn matches_the_dual_number_jacobian() {
        let free = [
            ChiangParamName::SigmaA(0),
            ChiangParamName::SigmaA(1),
            ChiangParamName::SigmaA(2),
            ChiangParamName::BetaM,
            ChiangParamName::BetaN,
            ChiangParamName::Alpha,
        ];
        let a = angles();
        for terms in ["R,TT,TRT,residual", "R", "TT,residual", "TRT", "residual"] {
            for beta_n in [0.05, 0.3, 0.9] {
                let p = ChiangParams {
                    eta: 1.55,
                    sigma_a: vec![0.2, 0.5, 1.1],
                    beta_m: 0.25,
                    beta_n,
                    alpha: 3f64.to_radians(),
                };
                let model = ChiangModel::new(ChiangEffects::parse(terms).unwrap(), 256).unwrap();
                let (want, jac) = batch_jacobian(&p, &model, &a, &free);
                let mut plain = vec![0.0; want.len()];
                scattering_batch(&p, &model, &a, &mut plain);
                let mut got = vec![0.0; want.len()];
                let mut grad = vec![0.0; want.len() * free.len()];
                batch(&p, &model, &a, &free, &mut got, Some(&mut grad));
                let s = crate::families::shared::logistic::logistic_scale(&beta_n);
                let tolerance = (2e-15 / s).max(1e-14);
                for k in 0..want.len() {
                    assert!(
                        (got[k] - plain[k]).abs() <= tolerance * plain[k].abs(),
                        "{terms} β_n {beta_n} row {k}: {} vs {}",
                        got[k],
                        plain[k]
                    );
                    let scale = jac[k].iter().fold(1e-300f64, |m, v| m.max(v.abs()));
                    for j in 0..free.len() {
                        let g = grad[k * free.len() + j];
                        assert!(
                            (g - jac[k][j]).abs() <= 1e-12 * scale,
                            "{terms} β_n {beta_n} row {k} {}: {g} vs {}",
                            free[j],
                            jac[k][j]
                        );
                    }
                }
                let mut values_only = vec![0.0; want.len()];
                batch(&p, &model, &a, &[], &mut values_only, None);
                assert_eq!(values_only, got);
            }
        }
    }
}

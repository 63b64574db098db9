//! The least-squares problem: data prepared for a fit space, the exact Jacobian of the model by
//! forward-mode AD, the variable-projected per-channel scale, robust losses, and the argmin
//! `Operator` + `Jacobian` the solvers run on.
//!
//! Scale: variable projection. The per-channel scale enters linearly (linear space) or additively
//! (log space), so its optimum given the shape parameters is closed-form; projecting it out removes
//! `n_channels` dimensions from the multi-start design (no start value is needed for an exposure
//! whose magnitude is arbitrary) and conditions the problem better (Golub–Pereyra). With a robust
//! loss the closed form is no longer the optimum of the robust cost, so the scale then becomes an
//! explicit parameter (its logarithm, started at the projected value) instead.
//!
//! Determinism: samples are processed in fixed chunks of [`CHUNK`]; every sum over samples is a
//! per-chunk partial sum, added in chunk order. Results are bit-identical for any thread count.

use nalgebra::{allocator::Allocator, Const, DMatrix, DVector, DefaultAllocator, Dim, Dyn, U1};
use num_dual::{Derivative, DualNum, DualVec64};
use rayon::prelude::*;
use serde::Serialize;

use super::bounds::Bound;
use super::loss::Loss;
use crate::model::{
    scattering, scattering_by_lobe, Angles, Measurement, ModelConfig, ParamName, Params,
};

/// Samples per parallel work item and per partial sum (fixed: part of the result's bit pattern).
pub const CHUNK: usize = 256;
/// Model values below this are floored before taking logarithms (S underflow far from every lobe).
const MODEL_FLOOR: f64 = 1e-300;
/// Stand-in for a non-finite residual: a step that produces one is rejected, never accepted.
const BAD_RESIDUAL: f64 = 1e100;

/// Residual space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// `w (y − s·S)`.
    Linear,
    /// `w (ln y − ln s − ln S)`: radiance spans orders of magnitude, so relative errors matter.
    #[default]
    Log,
}

impl std::str::FromStr for Space {
    type Err = crate::Error;
    fn from_str(s: &str) -> crate::Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "linear" => Ok(Space::Linear),
            "log" => Ok(Space::Log),
            other => Err(crate::Error::Other(format!(
                "unknown space `{other}`: use `linear` or `log`"
            ))),
        }
    }
}

impl std::fmt::Display for Space {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Space::Linear => "linear",
            Space::Log => "log",
        })
    }
}

/// Samples to fit: angles (radians) and values row-major `i * n_channels + c`.
#[derive(Debug, Clone, Default)]
pub struct FitData {
    pub channels: Vec<String>,
    pub angles: Vec<Angles>,
    pub values: Vec<f64>,
    /// Standard deviation of each value, same layout as `values`.
    pub sigma: Option<Vec<f64>>,
    /// Weight of each value, same layout as `values`.
    pub weight: Option<Vec<f64>>,
    /// Source line of each sample (1-based), for reports.
    pub line: Vec<u64>,
}

impl FitData {
    /// Number of samples.
    pub fn len(&self) -> usize {
        self.angles.len()
    }

    /// True when there are no samples.
    pub fn is_empty(&self) -> bool {
        self.angles.is_empty()
    }

    /// Number of colour channels.
    pub fn n_channels(&self) -> usize {
        self.channels.len()
    }

    /// The samples at `idx` (in that order).
    pub fn subset(&self, idx: &[usize]) -> FitData {
        let nc = self.n_channels();
        let rows = |v: &Vec<f64>| -> Vec<f64> {
            idx.iter()
                .flat_map(|&i| v[i * nc..(i + 1) * nc].iter().copied())
                .collect()
        };
        FitData {
            channels: self.channels.clone(),
            angles: idx.iter().map(|&i| self.angles[i]).collect(),
            values: rows(&self.values),
            sigma: self.sigma.as_ref().map(rows),
            weight: self.weight.as_ref().map(rows),
            line: idx
                .iter()
                .map(|&i| self.line.get(i).copied().unwrap_or(i as u64 + 1))
                .collect(),
        }
    }
}

/// The forward model seen by the fit: values and exact gradients for a chunk of samples.
pub trait Forward: Sync {
    /// `out[k * nc + c]` = model value of sample `k`, channel `c`.
    fn values(&self, p: &Params<f64>, angles: &[Angles], out: &mut [f64]);
    /// Values, and `grad[(k * nc + c) * nf + j]` = ∂value/∂`free[j]` (natural units).
    fn gradients(
        &self,
        p: &Params<f64>,
        free: &[ParamName],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    );
    /// Per-lobe values `[R, TT, TRT]` per channel (for curves.csv); `None` when not available.
    fn by_lobe(&self, _p: &Params<f64>, _angles: &Angles, _out: &mut [[f64; 3]]) -> bool {
        false
    }
}

/// The Marschner model of [`crate::model`] under one configuration, as the data measure it:
/// `S`, or `S · cos θ_i` for radiance ([`Measurement`]).
#[derive(Debug, Clone, Copy)]
pub struct ModelForward {
    pub config: ModelConfig,
    pub measurement: Measurement,
}

impl ModelForward {
    /// Multiply each sample's `width` consecutive numbers in `rows` by its measurement factor.
    /// The factor depends on θ_i only, so values and gradients scale alike (exact Jacobian).
    fn apply_measurement(&self, angles: &[Angles], rows: &mut [f64], width: usize) {
        if self.measurement == Measurement::S || width == 0 {
            return;
        }
        for (a, row) in angles.iter().zip(rows.chunks_mut(width)) {
            let f = self.measurement.factor(a);
            row.iter_mut().for_each(|v| *v *= f);
        }
    }
}

impl Forward for ModelForward {
    fn values(&self, p: &Params<f64>, angles: &[Angles], out: &mut [f64]) {
        let nc = p.sigma_a.len();
        for (a, o) in angles.iter().zip(out.chunks_mut(nc)) {
            scattering(p, &self.config, a, o);
        }
        self.apply_measurement(angles, out, nc);
    }

    fn gradients(
        &self,
        p: &Params<f64>,
        free: &[ParamName],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        let cfg = &self.config;
        macro_rules! dispatch {
            ($($n:literal)*) => {
                match free.len() {
                    $($n => gradients_dim(Const::<$n>, cfg, p, free, angles, out, grad),)*
                    nf => gradients_dim(Dyn(nf), cfg, p, free, angles, out, grad),
                }
            };
        }
        // Static dual sizes avoid a heap allocation per arithmetic operation; every realistic
        // free-parameter count (≤ η + 3σ_a + 5 shape = 9, plus headroom) has one.
        dispatch!(1 2 3 4 5 6 7 8 9 10 11 12);
        let nc = p.sigma_a.len();
        self.apply_measurement(angles, out, nc);
        self.apply_measurement(angles, grad, nc * free.len());
    }

    fn by_lobe(&self, p: &Params<f64>, angles: &Angles, out: &mut [[f64; 3]]) -> bool {
        scattering_by_lobe(p, &self.config, angles, out);
        let f = self.measurement.factor(angles);
        out.iter_mut().flatten().for_each(|v| *v *= f);
        true
    }
}

/// Forward-mode AD of `S` w.r.t. `free` with `dim`-sized dual numbers.
fn gradients_dim<D: Dim>(
    dim: D,
    cfg: &ModelConfig,
    p: &Params<f64>,
    free: &[ParamName],
    angles: &[Angles],
    out: &mut [f64],
    grad: &mut [f64],
) where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    let nf = free.len();
    let nc = p.sigma_a.len();
    let mut pd: Params<DualVec64<D>> = p.map(|&v| DualVec64::from_re(v));
    for (j, &name) in free.iter().enumerate() {
        let seed = Derivative::derivative_generic(dim, U1, j);
        pd.set(name, DualVec64::new(p.get(name), seed));
    }
    let mut o: Vec<DualVec64<D>> = vec![DualVec64::from_re(0.0); nc];
    for (k, a) in angles.iter().enumerate() {
        scattering(&pd, cfg, a, &mut o);
        for (c, v) in o.iter().enumerate() {
            out[k * nc + c] = v.re;
            let e = v.eps.clone().unwrap_generic(dim, U1);
            let row = &mut grad[(k * nc + c) * nf..(k * nc + c + 1) * nf];
            row.copy_from_slice(e.as_slice());
        }
    }
}

/// How the per-channel scale enters an evaluation.
#[derive(Debug, Clone, Copy)]
pub enum ScaleMode<'a> {
    /// Closed-form optimum inside the residual (variable projection).
    Projected,
    /// `ln s_c` are the trailing parameters.
    ExplicitLog(&'a [f64]),
    /// Fixed `s_c`, with Jacobian columns `∂r/∂s_c` appended (for standard errors).
    FixedNatural(&'a [f64]),
}

/// One evaluation of the residual vector.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// Loss-adjusted residuals `r̃`, row `i * nc + c`.
    pub residual: Vec<f64>,
    /// Residuals before the loss (normalised, in the fit space).
    pub raw: Vec<f64>,
    /// Final robust-loss weights `ρ′` (1 = not down-weighted).
    pub robust_weight: Vec<f64>,
    /// Model values `S` (times `cos θ_i` for radiance; without scale).
    pub model: Vec<f64>,
    /// Per-channel scale `s_c`.
    pub scale: Vec<f64>,
    /// Jacobian, row-major `(i * nc + c) * n_cols + j`, when asked for.
    pub jacobian: Option<Vec<f64>>,
    /// Number of Jacobian columns.
    pub n_cols: usize,
}

impl Evaluation {
    /// `½‖r̃‖²`.
    pub fn cost(&self) -> f64 {
        0.5 * chunked_sum(&self.residual, |r| r * r)
    }
}

/// Sum `f(x)` over `xs` in fixed chunks added in order (deterministic for any thread count).
pub fn chunked_sum(xs: &[f64], f: impl Fn(f64) -> f64 + Sync) -> f64 {
    xs.par_chunks(CHUNK * 4)
        .map(|c| c.iter().map(|&x| f(x)).sum::<f64>())
        .collect::<Vec<_>>()
        .into_iter()
        .sum()
}

/// Data prepared for one fit space plus everything fixed during a fit.
pub struct Evaluator<'f, F: Forward> {
    pub forward: &'f F,
    pub angles: Vec<Angles>,
    pub n_channels: usize,
    pub space: Space,
    pub loss: Loss,
    pub loss_scale: f64,
    /// `y` (linear) or `ln y` (log; `y` itself for linear-fallback rows).
    target: Vec<f64>,
    /// Residual weight `1/σ` (log: `y/σ`), `√weight`, or 1.
    w: Vec<f64>,
    /// Log space only: rows whose value is not significantly positive (`y ≤ 0`, or `y < 2σ`),
    /// fitted as linear residuals `w (y − s·S)` — a log would turn a zero reading into an
    /// arbitrary, hugely weighted outlier. They do not enter the closed-form scale.
    lin: Vec<bool>,
    /// Fixed parameters (and the start values of free ones).
    pub base: Params<f64>,
    pub free: Vec<ParamName>,
    pub bounds: Vec<Bound>,
    /// Scale is explicit (robust loss) rather than projected.
    pub explicit_scale: bool,
}

/// A reading below this many σ is not significantly positive: its log is not approximately
/// Gaussian (the log-normal approximation σ_log = σ/y needs y ≫ σ), so it is fitted linearly.
pub const LOG_MIN_SNR: f64 = 5.0;

/// Values a log-space fit cannot take the logarithm of (fit.json `options.log_floored`).
pub use crate::files::Floored;

impl<'f, F: Forward> Evaluator<'f, F> {
    /// Prepare `data` for `space`; in log space values that are not significantly positive
    /// become linear residuals (see `lin`), counted in the returned [`Floored`].
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        forward: &'f F,
        data: &FitData,
        space: Space,
        loss: Loss,
        loss_scale: f64,
        base: Params<f64>,
        free: Vec<ParamName>,
    ) -> crate::Result<(Self, Floored)> {
        let nc = data.n_channels();
        let mut floored = Floored {
            count: vec![0; nc],
            floor: vec![0.0; nc],
        };
        if space == Space::Log {
            for c in 0..nc {
                let min_pos = (0..data.len())
                    .map(|i| data.values[i * nc + c])
                    .filter(|&v| v > 0.0 && v.is_finite())
                    .fold(f64::INFINITY, f64::min);
                if !min_pos.is_finite() {
                    return Err(crate::Error::Other(format!(
                        "channel `{}` has no positive value: a log-space fit is impossible; use --space linear",
                        data.channels[c]
                    )));
                }
                floored.floor[c] = 0.5 * min_pos;
            }
        }
        let mut target = Vec::with_capacity(data.values.len());
        let mut w = Vec::with_capacity(data.values.len());
        let mut lin = Vec::with_capacity(data.values.len());
        for (k, &y) in data.values.iter().enumerate() {
            let c = k % nc;
            let sigma = data.sigma.as_ref().map(|s| s[k]);
            let weight = data.weight.as_ref().map(|wt| wt[k].max(0.0).sqrt());
            let fallback =
                space == Space::Log && (y <= 0.0 || sigma.is_some_and(|s| y < LOG_MIN_SNR * s));
            let wk = match (space, fallback) {
                (Space::Linear, _) | (Space::Log, true) => match (sigma, weight) {
                    (Some(s), _) => 1.0 / s,
                    (None, Some(wt)) if space == Space::Linear => wt,
                    (None, Some(wt)) => wt / floored.floor[c],
                    (None, None) if space == Space::Linear => 1.0,
                    (None, None) => 1.0 / floored.floor[c],
                },
                (Space::Log, false) => match (sigma, weight) {
                    (Some(s), _) => y / s,
                    (None, Some(wt)) => wt,
                    (None, None) => 1.0,
                },
            };
            if fallback {
                floored.count[c] += 1;
            }
            target.push(if space == Space::Log && !fallback {
                y.ln()
            } else {
                y
            });
            w.push(if wk.is_finite() { wk } else { 0.0 });
            lin.push(fallback);
        }
        let bounds = free.iter().map(|&n| Bound::of(n)).collect();
        Ok((
            Evaluator {
                forward,
                angles: data.angles.clone(),
                n_channels: nc,
                space,
                loss,
                loss_scale,
                target,
                w,
                lin,
                base,
                free,
                bounds,
                explicit_scale: loss != Loss::L2,
            },
            floored,
        ))
    }

    /// Number of residuals.
    pub fn n_residuals(&self) -> usize {
        self.target.len()
    }

    /// Number of solver parameters (free shape parameters, plus scales when explicit).
    pub fn n_params(&self) -> usize {
        self.free.len()
            + if self.explicit_scale {
                self.n_channels
            } else {
                0
            }
    }

    /// Residual weights (for reports).
    pub fn weights(&self) -> &[f64] {
        &self.w
    }

    /// Natural values of the free parameters for internal `u`.
    pub fn natural(&self, u: &[f64]) -> Vec<f64> {
        self.bounds
            .iter()
            .zip(u)
            .map(|(b, &v)| b.to_natural(v))
            .collect()
    }

    /// Internal `u` of natural free values `x` (scale entries, when explicit, appended as given).
    pub fn internal(&self, x: &[f64]) -> Vec<f64> {
        self.bounds
            .iter()
            .zip(x)
            .map(|(b, &v)| b.to_internal(v))
            .collect()
    }

    /// Full parameter set with free values `x` (natural units).
    pub fn params_at(&self, x: &[f64]) -> Params<f64> {
        let mut p = self.base.clone();
        for (&n, &v) in self.free.iter().zip(x) {
            p.set(n, v);
        }
        p
    }

    /// Evaluate at solver parameters `u` (transforms applied; scale per `explicit_scale`).
    pub fn eval_internal(&self, u: &[f64], jac: bool) -> Evaluation {
        let nf = self.free.len();
        let x = self.natural(&u[..nf]);
        let dxdu: Vec<f64> = self
            .bounds
            .iter()
            .zip(u)
            .map(|(b, &v)| b.derivative(v))
            .collect();
        let mode = if self.explicit_scale {
            ScaleMode::ExplicitLog(&u[nf..])
        } else {
            ScaleMode::Projected
        };
        self.evaluate(&x, &dxdu, mode, jac)
    }

    /// Evaluate at natural free values `x`; Jacobian columns are `∂r/∂x_j · col_factor[j]`
    /// (`col_factor` = `dx/du` for solver parameters, `1/report_factor` for reporting units).
    pub fn evaluate(
        &self,
        x: &[f64],
        col_factor: &[f64],
        mode: ScaleMode<'_>,
        jac: bool,
    ) -> Evaluation {
        let nc = self.n_channels;
        let nf = self.free.len();
        let n = self.angles.len();
        let p = self.params_at(x);

        // Model pass: q = S (linear) or ln S (log), dq = ∂q/∂u (row (i,c), column j).
        let mut model = vec![0.0; n * nc];
        let mut dq = if jac {
            vec![0.0; n * nc * nf]
        } else {
            Vec::new()
        };
        if jac && nf > 0 {
            model
                .par_chunks_mut(CHUNK * nc)
                .zip(dq.par_chunks_mut(CHUNK * nc * nf))
                .zip(self.angles.par_chunks(CHUNK))
                .for_each(|((m, g), a)| {
                    self.forward.gradients(&p, &self.free, a, m, g);
                    for (k, row) in g.chunks_mut(nf).enumerate() {
                        for (gj, cf) in row.iter_mut().zip(col_factor) {
                            *gj *= cf;
                        }
                        if self.space == Space::Log {
                            let mk = m[k];
                            for gj in row.iter_mut() {
                                *gj = if mk > MODEL_FLOOR { *gj / mk } else { 0.0 };
                            }
                        }
                    }
                });
        } else {
            model
                .par_chunks_mut(CHUNK * nc)
                .zip(self.angles.par_chunks(CHUNK))
                .for_each(|(m, a)| self.forward.values(&p, a, m));
        }
        let q: Vec<f64> = match self.space {
            Space::Linear => model.clone(),
            Space::Log => model.iter().map(|&m| m.max(MODEL_FLOOR).ln()).collect(),
        };

        // Scale: s_c (linear) or ln s_c (log), and its derivative ds[c*nf+j] when projected.
        let (scale_q, ds) = match mode {
            ScaleMode::Projected => self.project(&q, &dq, jac),
            ScaleMode::ExplicitLog(ls) => (
                match self.space {
                    Space::Linear => ls.iter().map(|v| v.exp()).collect(),
                    Space::Log => ls.to_vec(),
                },
                vec![0.0; nc * nf],
            ),
            ScaleMode::FixedNatural(s) => (
                match self.space {
                    Space::Linear => s.to_vec(),
                    Space::Log => s.iter().map(|v| v.max(MODEL_FLOOR).ln()).collect(),
                },
                vec![0.0; nc * nf],
            ),
        };
        let scale: Vec<f64> = match self.space {
            Space::Linear => scale_q.clone(),
            Space::Log => scale_q.iter().map(|v| v.exp()).collect(),
        };
        let extra = match mode {
            ScaleMode::Projected => 0,
            _ => nc,
        };
        let n_cols = nf + extra;

        // Residual pass.
        let rows = n * nc;
        let mut residual = vec![0.0; rows];
        let mut raw = vec![0.0; rows];
        let mut robust_weight = vec![0.0; rows];
        let mut jacobian = if jac {
            vec![0.0; rows * n_cols]
        } else {
            Vec::new()
        };
        let space = self.space;
        let (loss, cscale) = (self.loss, self.loss_scale);
        let fill = |k: usize, r: &mut f64, rw: &mut f64, rr: &mut f64, jrow: Option<&mut [f64]>| {
            let c = k % nc;
            let (w, y, qk) = (self.w[k], self.target[k], q[k]);
            let lin_row = self.lin[k];
            // A linear-fallback row of a log fit: w (y − s·S), with S = e^q and s = e^{ln s}.
            let sm = scale[c] * model[k];
            let res = match space {
                Space::Linear => w * (y - scale_q[c] * qk),
                Space::Log if lin_row => w * (y - sm),
                Space::Log => w * (y - scale_q[c] - qk),
            };
            let (rt, factor, drho) = loss.apply(res, cscale);
            let ok = rt.is_finite();
            *r = if ok { rt } else { BAD_RESIDUAL };
            *rr = res;
            *rw = drho;
            if let Some(jrow) = jrow {
                let f = if ok { factor } else { 0.0 };
                let g = if nf > 0 {
                    &dq[k * nf..(k + 1) * nf]
                } else {
                    &[][..]
                };
                for j in 0..nf {
                    let d = match space {
                        Space::Linear => -w * (scale_q[c] * g[j] + qk * ds[c * nf + j]),
                        // g = ∂ln S, ds = ∂ln s: ∂(s·S) = s·S·(g + ds).
                        Space::Log if lin_row => -w * sm * (g[j] + ds[c * nf + j]),
                        Space::Log => -w * (g[j] + ds[c * nf + j]),
                    };
                    jrow[j] = f * d;
                }
                if extra > 0 {
                    let d = match (space, mode) {
                        (Space::Linear, ScaleMode::ExplicitLog(_)) => -w * scale_q[c] * qk,
                        (Space::Log, ScaleMode::ExplicitLog(_)) if lin_row => -w * sm,
                        (Space::Log, ScaleMode::ExplicitLog(_)) => -w,
                        (Space::Linear, _) => -w * qk,
                        (Space::Log, _) if lin_row => -w * model[k],
                        (Space::Log, _) => -w / scale[c],
                    };
                    jrow[nf + c] = f * d;
                }
                for v in jrow.iter_mut() {
                    if !v.is_finite() {
                        *v = 0.0;
                    }
                }
            }
        };
        if jac {
            residual
                .par_chunks_mut(CHUNK * nc)
                .zip(robust_weight.par_chunks_mut(CHUNK * nc))
                .zip(raw.par_chunks_mut(CHUNK * nc))
                .zip(jacobian.par_chunks_mut(CHUNK * nc * n_cols.max(1)))
                .enumerate()
                .for_each(|(ci, (((r, rw), rr), jr))| {
                    for k in 0..r.len() {
                        let jrow = &mut jr[k * n_cols..(k + 1) * n_cols];
                        fill(
                            ci * CHUNK * nc + k,
                            &mut r[k],
                            &mut rw[k],
                            &mut rr[k],
                            Some(jrow),
                        );
                    }
                });
        } else {
            residual
                .par_chunks_mut(CHUNK * nc)
                .zip(robust_weight.par_chunks_mut(CHUNK * nc))
                .zip(raw.par_chunks_mut(CHUNK * nc))
                .enumerate()
                .for_each(|(ci, ((r, rw), rr))| {
                    for k in 0..r.len() {
                        fill(ci * CHUNK * nc + k, &mut r[k], &mut rw[k], &mut rr[k], None);
                    }
                });
        }
        Evaluation {
            residual,
            raw,
            robust_weight,
            model,
            scale,
            jacobian: jac.then_some(jacobian),
            n_cols,
        }
    }

    /// Variable projection: optimal scale per channel and its derivative w.r.t. the columns of `dq`.
    /// Linear: `s* = ⟨wy,wq⟩/⟨wq,wq⟩`, `ds*/dθ = (⟨wy,w∂q⟩ − 2s*⟨wq,w∂q⟩)/⟨wq,wq⟩`.
    /// Log: `ln s* = ⟨w,w(y − q)⟩/⟨w,w⟩`, `d ln s*/dθ = −⟨w,w∂q⟩/⟨w,w⟩`.
    fn project(&self, q: &[f64], dq: &[f64], jac: bool) -> (Vec<f64>, Vec<f64>) {
        let nc = self.n_channels;
        let nf = if jac { self.free.len() } else { 0 };
        // Per channel: [A, B, C_0..C_nf, D_0..D_nf] (linear) or [W, L, E_0..E_nf, unused] (log).
        let width = 2 + 2 * nf;
        let space = self.space;
        let partial: Vec<Vec<f64>> = (0..q.len().div_ceil(CHUNK * nc))
            .into_par_iter()
            .map(|ci| {
                let mut acc = vec![0.0; nc * width];
                let lo = ci * CHUNK * nc;
                let hi = (lo + CHUNK * nc).min(q.len());
                for k in lo..hi {
                    if self.lin[k] {
                        continue;
                    }
                    let c = k % nc;
                    let a = &mut acc[c * width..(c + 1) * width];
                    let (w2, y, qk) = (self.w[k] * self.w[k], self.target[k], q[k]);
                    match space {
                        Space::Linear => {
                            a[0] += w2 * y * qk;
                            a[1] += w2 * qk * qk;
                            for j in 0..nf {
                                let g = dq[k * nf + j];
                                a[2 + j] += w2 * y * g;
                                a[2 + nf + j] += w2 * qk * g;
                            }
                        }
                        Space::Log => {
                            a[0] += w2;
                            a[1] += w2 * (y - qk);
                            for j in 0..nf {
                                a[2 + j] += w2 * dq[k * nf + j];
                            }
                        }
                    }
                }
                acc
            })
            .collect();
        let mut tot = vec![0.0; nc * width];
        for p in &partial {
            for (t, v) in tot.iter_mut().zip(p) {
                *t += v;
            }
        }
        let nfa = self.free.len();
        let mut sq = vec![0.0; nc];
        let mut ds = vec![0.0; nc * nfa];
        for c in 0..nc {
            let a = &tot[c * width..(c + 1) * width];
            let denom = match space {
                Space::Linear => a[1],
                Space::Log => a[0],
            };
            if denom == 0.0 {
                // No information on this channel's scale (all weights or model values zero):
                // s = 0 (linear) or ln s = 0 (log), with no dependence on the parameters.
                continue;
            }
            match space {
                Space::Linear => {
                    let s = a[0] / a[1];
                    sq[c] = s;
                    for j in 0..nf {
                        ds[c * nfa + j] = (a[2 + j] - 2.0 * s * a[2 + nf + j]) / a[1];
                    }
                }
                Space::Log => {
                    sq[c] = a[1] / a[0];
                    for j in 0..nf {
                        ds[c * nfa + j] = -a[2 + j] / a[0];
                    }
                }
            }
        }
        (sq, ds)
    }
}

/// The argmin problem over solver parameters `u`.
pub struct LsqProblem<'e, 'f, F: Forward> {
    pub ev: &'e Evaluator<'f, F>,
}

impl<F: Forward> argmin::core::Operator for LsqProblem<'_, '_, F> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, u: &DVector<f64>) -> Result<DVector<f64>, argmin::core::Error> {
        Ok(DVector::from_vec(
            self.ev.eval_internal(u.as_slice(), false).residual,
        ))
    }
}

impl<F: Forward> argmin::core::Jacobian for LsqProblem<'_, '_, F> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, u: &DVector<f64>) -> Result<DMatrix<f64>, argmin::core::Error> {
        let e = self.ev.eval_internal(u.as_slice(), true);
        let m = e.residual.len();
        Ok(DMatrix::from_row_slice(
            m,
            e.n_cols,
            e.jacobian.as_deref().unwrap_or(&[]),
        ))
    }
}

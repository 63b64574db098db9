//! Variable projection of the per-channel scale. The scale enters linearly (linear space) or
//! additively (log space), so its optimum given the shape parameters is closed-form; projecting it
//! out removes `n_channels` dimensions from the multi-start design (no start value is needed for
//! an exposure whose magnitude is arbitrary) and conditions the problem better (Golub–Pereyra).
//! With a robust loss the closed form is no longer the optimum of the robust cost, so the scale
//! is then an explicit parameter (its logarithm, started at the projected value) instead.
//!
//! The log-space optimum of the scale is a weighted *geometric* mean of `y/S`, biased for noise
//! that is Gaussian in `y` (and more so when the log weights `y/σ` grow with the noise itself:
//! +1.5σ_rel², 1.5% at 10% relative noise). It is still the scale reported: every reported number
//! comes from the cost the fit minimised. [`Evaluator::linear_noise_scale`] gives the linear
//! noise model's estimate beside it (fit.json `scale[].linear_noise_value`).

use rayon::prelude::*;

use super::evaluation::{Evaluation, ScaleMode, CHUNK};
use super::evaluator::{Evaluator, Space};
use super::forward::Forward;

impl<F: Forward> Evaluator<'_, F> {
    /// Variable projection: optimal scale per channel and its derivative w.r.t. the columns of `dq`.
    /// Linear: `s* = ⟨wy,wq⟩/⟨wq,wq⟩`, `ds*/dθ = (⟨wy,w∂q⟩ − 2s*⟨wq,w∂q⟩)/⟨wq,wq⟩`.
    /// Log: `ln s* = ⟨w,w(y − q)⟩/⟨w,w⟩`, `d ln s*/dθ = −⟨w,w∂q⟩/⟨w,w⟩`.
    pub(super) fn project(&self, q: &[f64], dq: &[f64], jac: bool) -> (Vec<f64>, Vec<f64>) {
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

    /// For a log-space evaluation `e`: each channel's scale under a linear noise model at the
    /// same shape, the weighted least-squares `s = Σ λ²ρ′·y·S / Σ λ²ρ′·S²` with linear weights
    /// `λ = 1/σ` (a `sigma` column), else `λ ∝ √weight / S` (a log fit without σ assumes constant
    /// relative errors: `s` is then the weighted mean of `y/S`). `ρ′` are the robust-loss weights
    /// of `e`. Reported beside the fit's own scale, never instead of it: it minimises another cost
    /// (on data no model made, one that a few over-predicted dim rows can decide). `None` for
    /// linear-space evaluations, whose scale is this estimate already.
    pub fn linear_noise_scale(&self, e: &Evaluation, has_sigma: bool) -> Option<Vec<f64>> {
        if self.space != Space::Log {
            return None;
        }
        let nc = self.n_channels;
        // Per channel [Σ λ²ρ′yS, Σ λ²ρ′S²], chunked in order (deterministic).
        let partial: Vec<Vec<f64>> = (0..self.target.len().div_ceil(CHUNK * nc))
            .into_par_iter()
            .map(|ci| {
                let mut acc = vec![0.0; 2 * nc];
                let lo = ci * CHUNK * nc;
                let hi = (lo + CHUNK * nc).min(self.target.len());
                for k in lo..hi {
                    let (s, w) = (e.model[k], self.w[k]);
                    let y = if self.lin[k] {
                        self.target[k]
                    } else {
                        self.target[k].exp()
                    };
                    // Linear weight: w already is 1/σ on a fallback row; y/σ (σ given) or the
                    // relative weight (no σ) on a log row.
                    let lambda = if self.lin[k] {
                        w
                    } else if has_sigma {
                        w / y
                    } else {
                        w / s
                    };
                    let l2 = lambda * lambda * e.robust_weight[k];
                    if l2.is_finite() && s.is_finite() && s > 0.0 {
                        let c = k % nc;
                        acc[2 * c] += l2 * y * s;
                        acc[2 * c + 1] += l2 * s * s;
                    }
                }
                acc
            })
            .collect();
        let mut tot = vec![0.0; 2 * nc];
        for p in &partial {
            for (t, v) in tot.iter_mut().zip(p) {
                *t += v;
            }
        }
        Some((0..nc).map(|c| tot[2 * c] / tot[2 * c + 1]).collect())
    }

    /// Start values `ln s_c` for an explicit (robust-loss) scale at natural shape values `x`: the
    /// per-channel median of `ln(y/S)`. The projected optimum is a (weighted) mean, which the
    /// outliers a robust loss is for drag away (10% of values ×5–50 move it by ~30%), and a
    /// robust loss with a small scale cannot pull the scale back from there: every inlier then
    /// looks like an outlier.
    pub fn median_log_scale(&self, x: &[f64]) -> Vec<f64> {
        let nc = self.n_channels;
        let ones = vec![1.0; x.len()];
        let e = self.evaluate(x, &ones, ScaleMode::Projected, false);
        (0..nc)
            .map(|c| {
                let mut r: Vec<f64> = (c..self.target.len())
                    .step_by(nc)
                    .filter(|&k| !self.lin[k] && self.w[k] > 0.0 && e.model[k] > 0.0)
                    .map(|k| match self.space {
                        Space::Log => self.target[k] - e.model[k].ln(),
                        Space::Linear => (self.target[k] / e.model[k]).ln(),
                    })
                    .filter(|v| v.is_finite())
                    .collect();
                if r.is_empty() {
                    return e.scale[c].max(1e-300).ln();
                }
                let mid = r.len() / 2;
                *r.select_nth_unstable_by(mid, f64::total_cmp).1
            })
            .collect()
    }
}

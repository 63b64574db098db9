//! Variable projection of the per-channel scale. The scale enters linearly (linear space) or
//! additively (log space), so its optimum given the shape parameters is closed-form; projecting it
//! out removes `n_channels` dimensions from the multi-start design (no start value is needed for
//! an exposure whose magnitude is arbitrary) and conditions the problem better (Golub–Pereyra).
//! With a robust loss the closed form is no longer the optimum of the robust cost, so the scale
//! is then an explicit parameter (its logarithm, started at the projected value) instead.

use rayon::prelude::*;

use super::evaluator::{Evaluator, Space};
use super::forward::Forward;
use super::residual::CHUNK;

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
}

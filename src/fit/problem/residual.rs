//! The residual vector and its Jacobian at one point: model pass, per-channel scale (projected,
//! explicit or fixed), residuals in the fit space, and the robust loss.
//!
//! Determinism: samples are processed in fixed chunks of [`CHUNK`]; every sum over samples is a
//! per-chunk partial sum, added in chunk order. Results are bit-identical for any thread count.

use rayon::prelude::*;

use super::evaluation::{Evaluation, ScaleMode, CHUNK};
use super::evaluator::{Evaluator, Space};
use super::forward::Forward;

/// Model values below this are floored before taking logarithms (S underflow far from every lobe).
const MODEL_FLOOR: f64 = 1e-300;
/// Stand-in for a non-finite residual: a step that produces one is rejected, never accepted.
const BAD_RESIDUAL: f64 = 1e100;

impl<F: Forward> Evaluator<'_, F> {
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
        let mut model: Vec<f64>;
        let mut dq = if jac {
            vec![0.0; n * nc * nf]
        } else {
            Vec::new()
        };
        if jac && nf > 0 {
            model = vec![0.0; n * nc];
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
            model = self
                .model_values(&p, None)
                .expect("no cancel flag: the pass runs to the end");
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
}

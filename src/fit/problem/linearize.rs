//! The fit's linearisation without its Jacobian: a small matrix `M` and vector `t` with
//! `MᵀM = JᵀJ`, `Mᵀt = Jᵀr̃` and `‖t‖ = ‖r̃‖`, accumulated over chunks of samples, so memory is
//! linear in samples × channels instead of samples × channels × parameters. Also the cost alone,
//! in chunks, without storing any residual.
//!
//! Block structure: channel `c`'s rows depend on the shared parameters, on its own local parameter
//! (`σ_a[c]`, [`FitParam::channel`]) and on its scale `s_c` only. Each chunk's values and exact
//! gradients come from [`Forward::gradients_compressed`] (every channel's local parameter in one
//! column, so the AD cost does not grow with the channel count), and each channel keeps its own
//! Householder QR of its rows `[∂r/∂scale | ∂r/∂shared, ∂r/∂local | r̃]` — never the normal
//! matrix, so the conditioning of `J` is not squared and the SVD-based LM step and covariance keep
//! their accuracy.
//!
//! Variable projection: with the scale projected, `J = B + a·dsᵀ` per channel, where `a` is
//! `∂r/∂scale`, `B` the Jacobian at fixed scale and `ds` the derivative of the optimal scale —
//! known only after all rows are seen. `[a | B | r] = QR` gives `J = Q (R_B + R_a dsᵀ)`, so the
//! chunks are reduced first and `ds` applied to the small triangle at the end.
//!
//! The result stays by channel ([`BlockSystem`]): the dense `M` would be
//! `channels·(shared+3) × (shared+channels)`, quadratic in channels, while the LM step and the
//! covariance eliminate each channel's own columns block by block (`crate::lm::blocks`).
//!
//! Determinism: chunks of [`CHUNK`] samples are reduced in parallel, in fixed rounds, and merged in
//! chunk order, so results are bit-identical for any thread count.

use std::sync::atomic::AtomicBool;

use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;

use super::evaluation::{ScaleMode, CHUNK};
use super::evaluator::{Evaluator, Space};
use super::forward::{Forward, ParamSet};
use super::passes::{cancelled, chunk_model, Layout};
use crate::lm::{Block, BlockSystem, Linearized, ParameterCovariance, System};

/// Model values below this are floored before taking logarithms (as in the residual pass).
const MODEL_FLOOR: f64 = 1e-300;
/// Stand-in for a non-finite residual (as in the residual pass).
const BAD_RESIDUAL: f64 = 1e100;
/// Chunks reduced in parallel per round before they are merged in order: bounds the partial
/// triangles held at once while leaving enough work items for every thread (scaled down with
/// many channels, so at most `ROUND²` channel triangles are held; results do not depend on it).
const ROUND: usize = 64;

/// The accumulated linearisation of the residuals at one point.
#[derive(Debug, Clone)]
pub struct Linearization {
    /// `(M, t)` by channel: `MᵀM = JᵀJ`, `Mᵀt = Jᵀr̃`, `‖t‖ = ‖r̃‖`; each channel's block has the
    /// shared columns and its own (its local parameter, its explicit scale), so the storage is
    /// linear in channels.
    pub system: BlockSystem,
    /// Number of residuals `m` that `M` stands for.
    pub rows: usize,
    /// Per-channel scale `s_c` used.
    pub scale: Vec<f64>,
    /// The extra columns `e` asked of [`Evaluator::linearize_with`], transformed alike: with `Q`
    /// the orthogonal factor, `[M | t | E] = Qᵀ[J | r̃ | e]` (rows of `M` as in
    /// [`Linearization::matrix`]), so every inner product among Jacobian columns, residuals and
    /// extras is kept.
    pub extra: DMatrix<f64>,
}

/// Largest number of columns for which the LM solver gets the dense `M` (one SVD per Jacobian,
/// a truncated-SVD Gauss–Newton step) rather than the block system: a few channels cost nothing
/// dense, and their results stay those of the dense solver. Above it the dense `M` grows as
/// channels².
pub const DENSE_MAX_COLUMNS: usize = 32;

impl Linearization {
    /// Dense `M` (rows in channel order): `O(channels²)` memory, for small systems.
    pub fn matrix(&self) -> DMatrix<f64> {
        self.system.to_dense().0
    }

    /// `t` (rows in channel order).
    pub fn rhs(&self) -> DVector<f64> {
        DVector::from_iterator(
            self.system.nrows(),
            self.system
                .blocks
                .iter()
                .flat_map(|b| b.rhs.iter().copied()),
        )
    }

    /// Whether the dense form is small enough to be the one used ([`DENSE_MAX_COLUMNS`]).
    pub fn is_small(&self) -> bool {
        self.system.ncols <= DENSE_MAX_COLUMNS
    }

    /// Whether column `j` of `M` is zero at every row.
    pub fn zero_columns(&self) -> Vec<bool> {
        let mut nonzero = vec![false; self.system.ncols];
        for b in &self.system.blocks {
            for (k, col) in b.matrix.column_iter().enumerate() {
                let j = match self.system.shared.get(k) {
                    Some(&j) => j,
                    None => b.local[k - self.system.shared.len()],
                };
                nonzero[j] |= col.iter().any(|v| *v != 0.0);
            }
        }
        nonzero.into_iter().map(|n| !n).collect()
    }

    /// Covariance `s²(MᵀM)⁺` with `s² = ‖t‖²/dof` (dense when small, else by blocks) and each
    /// column's weight in the null space (see [`crate::lm::null_space_weights`]).
    pub fn covariance(&self, dof: usize) -> (Option<ParameterCovariance>, Vec<f64>) {
        let ss = self.rhs().norm_squared();
        if self.is_small() {
            let jm = self.matrix();
            let cov = crate::lm::covariance(&jm, ss, dof).map(ParameterCovariance::dense);
            (cov, crate::lm::null_space_weights(&jm))
        } else {
            let cov = crate::lm::block_covariance(&self.system, ss, dof, crate::lm::DEFAULT_RCOND);
            let null = match &cov {
                Some(c) => c.null_weights.clone(),
                None => vec![0.0; self.system.ncols],
            };
            (cov.map(ParameterCovariance::Blocks), null)
        }
    }

    /// The LM solver's linearisation: dense when small, else by blocks.
    pub fn into_lm(self) -> Linearized {
        let rows = self.rows;
        let system = if self.is_small() {
            let (matrix, residuals) = self.system.to_dense();
            System::Dense { matrix, residuals }
        } else {
            System::Blocks(self.system)
        };
        Linearized {
            system,
            rows,
            flatness: None,
        }
    }
}

/// One chunk's reduction: per channel the R factor of its rows, and the projection sums.
struct ChunkPart {
    tri: Vec<DMatrix<f64>>,
    sums: Vec<f64>,
}

/// The R factor of `[top; bottom]` (at most `ncols` rows).
fn stack_r(top: &DMatrix<f64>, bottom: &DMatrix<f64>) -> DMatrix<f64> {
    if top.nrows() == 0 {
        return triangle(bottom.clone());
    }
    let w = top.ncols();
    let mut s = DMatrix::zeros(top.nrows() + bottom.nrows(), w);
    s.rows_mut(0, top.nrows()).copy_from(top);
    s.rows_mut(top.nrows(), bottom.nrows()).copy_from(bottom);
    triangle(s)
}

/// The R factor of `a` (Householder QR), `min(m, n) × n`.
fn triangle(a: DMatrix<f64>) -> DMatrix<f64> {
    if a.nrows() == 0 {
        return a;
    }
    a.qr().r()
}

impl<F: Forward> Evaluator<'_, F> {
    /// Per-channel scale in the fit space (`s` linear, `ln s` log) for `mode`; the projected one
    /// from the model values `model`, by the same sums in the same order as
    /// [`Evaluator::evaluate`].
    fn scale_q(&self, model: &[f64], mode: ScaleMode<'_>) -> Vec<f64> {
        let nc = self.n_channels;
        match mode {
            ScaleMode::ExplicitLog(ls) => match self.space {
                Space::Linear => ls.iter().map(|v| v.exp()).collect(),
                Space::Log => ls.to_vec(),
            },
            ScaleMode::FixedNatural(s) => match self.space {
                Space::Linear => s.to_vec(),
                Space::Log => s.iter().map(|v| v.max(MODEL_FLOOR).ln()).collect(),
            },
            ScaleMode::Projected => {
                let partial: Vec<Vec<f64>> = model
                    .par_chunks(CHUNK * nc)
                    .enumerate()
                    .map(|(ci, m)| {
                        let mut acc = vec![0.0; nc * 2];
                        let lo = ci * CHUNK * nc;
                        for (i, &mk) in m.iter().enumerate() {
                            let k = lo + i;
                            if self.lin[k] {
                                continue;
                            }
                            let c = k % nc;
                            let (w2, y) = (self.w[k] * self.w[k], self.target[k]);
                            match self.space {
                                Space::Linear => {
                                    acc[2 * c] += w2 * y * mk;
                                    acc[2 * c + 1] += w2 * mk * mk;
                                }
                                Space::Log => {
                                    let qk = mk.max(MODEL_FLOOR).ln();
                                    acc[2 * c] += w2;
                                    acc[2 * c + 1] += w2 * (y - qk);
                                }
                            }
                        }
                        acc
                    })
                    .collect();
                let mut tot = vec![0.0; nc * 2];
                for part in partial {
                    for (t, v) in tot.iter_mut().zip(part) {
                        *t += v;
                    }
                }
                (0..nc)
                    .map(|c| {
                        let (a0, a1) = (tot[2 * c], tot[2 * c + 1]);
                        match self.space {
                            Space::Linear if a1 != 0.0 => a0 / a1,
                            Space::Log if a0 != 0.0 => a1 / a0,
                            _ => 0.0,
                        }
                    })
                    .collect()
            }
        }
    }

    /// The residual `r̃` of row `k` (sample-major) with model value `mk` and fit-space scale `sq`:
    /// `(r̃, raw residual, loss factor)`; a non-finite `r̃` becomes [`BAD_RESIDUAL`] with factor 0.
    fn row_residual(&self, k: usize, mk: f64, sq: f64, s: f64) -> (f64, f64) {
        let (w, y) = (self.w[k], self.target[k]);
        let res = match self.space {
            Space::Linear => w * (y - sq * mk),
            Space::Log if self.lin[k] => w * (y - s * mk),
            Space::Log => w * (y - sq - mk.max(MODEL_FLOOR).ln()),
        };
        let (rt, factor, _) = self.loss.apply(res, self.loss_scale);
        if rt.is_finite() {
            (rt, factor)
        } else {
            (BAD_RESIDUAL, 0.0)
        }
    }

    /// `½‖r̃‖²` at solver parameters `u`, in chunks with nothing stored; `None` when `cancel` is
    /// raised during the pass. Equal to [`Evaluator::eval_internal`]`(u, false).cost()` up to the
    /// order of the sum.
    pub fn cost_internal(&self, u: &[f64], cancel: Option<&AtomicBool>) -> Option<f64> {
        self.cost_and_scale(u, cancel).map(|(cost, _)| cost)
    }

    /// [`Evaluator::cost_internal`] and the fit-space scale it used (projected, or the solver's),
    /// which a linearisation at the same `u` reuses instead of a second pass over the model.
    pub fn cost_and_scale(
        &self,
        u: &[f64],
        cancel: Option<&AtomicBool>,
    ) -> Option<(f64, Vec<f64>)> {
        let (x, _, mode) = self.solver_point(u);
        let p = self.params_at(&x);
        let model = self.model_values(&p, cancel)?;
        let sq = self.scale_q(&model, mode);
        let s = self.natural_scale(&sq);
        let nc = self.n_channels;
        let partial: Vec<f64> = model
            .par_chunks(CHUNK * nc)
            .enumerate()
            .map(|(ci, m)| {
                let lo = ci * CHUNK * nc;
                m.iter()
                    .enumerate()
                    .map(|(i, &mk)| {
                        let c = (lo + i) % nc;
                        let r = self.row_residual(lo + i, mk, sq[c], s[c]).0;
                        r * r
                    })
                    .sum::<f64>()
            })
            .collect();
        Some((0.5 * partial.iter().sum::<f64>(), sq))
    }

    fn natural_scale(&self, sq: &[f64]) -> Vec<f64> {
        match self.space {
            Space::Linear => sq.to_vec(),
            Space::Log => sq.iter().map(|v| v.exp()).collect(),
        }
    }

    /// [`Evaluator::linearize`] at solver parameters `u` (transforms applied; scale projected or
    /// explicit as in [`Evaluator::eval_internal`]).
    /// `scale`: the fit-space scale [`Evaluator::cost_and_scale`] found at this same `u` (one
    /// model pass fewer); `None` computes it.
    pub fn linearize_internal(
        &self,
        u: &[f64],
        scale: Option<Vec<f64>>,
        cancel: Option<&AtomicBool>,
    ) -> Option<Linearization> {
        let (x, dxdu, mode) = self.solver_point(u);
        self.linearize_at(&x, &dxdu, mode, &[], scale, cancel)
    }

    /// The linearisation at natural free values `x`, columns scaled by `col_factor` as in
    /// [`Evaluator::evaluate`] (with `nc` scale columns appended unless the scale is projected).
    /// `None` when `cancel` is raised during the pass.
    pub fn linearize(
        &self,
        x: &[f64],
        col_factor: &[f64],
        mode: ScaleMode<'_>,
        cancel: Option<&AtomicBool>,
    ) -> Option<Linearization> {
        self.linearize_with(x, col_factor, mode, &[], cancel)
    }

    /// [`Evaluator::linearize`] with `extra` columns (one value per residual row, sample-major)
    /// reduced alongside: projections onto the Jacobian's column space without storing `J`.
    pub fn linearize_with(
        &self,
        x: &[f64],
        col_factor: &[f64],
        mode: ScaleMode<'_>,
        extra: &[&[f64]],
        cancel: Option<&AtomicBool>,
    ) -> Option<Linearization> {
        self.linearize_at(x, col_factor, mode, extra, None, cancel)
    }

    /// [`Evaluator::linearize_with`] given the fit-space scale at `x` when known.
    fn linearize_at(
        &self,
        x: &[f64],
        col_factor: &[f64],
        mode: ScaleMode<'_>,
        extra: &[&[f64]],
        known_scale: Option<Vec<f64>>,
        cancel: Option<&AtomicBool>,
    ) -> Option<Linearization> {
        let nc = self.n_channels;
        let nf = self.free.len();
        let p = self.params_at(x);
        let sq = match (mode, known_scale) {
            (_, Some(sq)) => sq,
            (ScaleMode::Projected, None) => self.scale_q(&self.model_values(&p, cancel)?, mode),
            (_, None) => self.scale_q(&[], mode),
        };
        let s = self.natural_scale(&sq);
        let projected = matches!(mode, ScaleMode::Projected);
        let layout = Layout::of(&self.free, nc);
        let nl = layout.n_cols();
        let ne = extra.len();
        let w = nl + 2 + ne;
        let sum_width = 2 + 2 * nl;
        let n_chunks = self.angles.len().div_ceil(CHUNK);
        let mut tri: Vec<DMatrix<f64>> = vec![DMatrix::zeros(0, w); nc];
        let mut sums = vec![0.0; nc * sum_width];
        // Fewer chunks per round with many channels: each part holds a triangle per channel.
        let per_round = (ROUND * ROUND / nc.max(1)).clamp(2, ROUND);
        // The model's values and gradients: kept from a pass at `p`, or computed now and kept
        // when small enough; else each chunk computes its own.
        let kept = self.kept_gradients(&p, &layout, cancel)?;
        for round in (0..n_chunks).step_by(per_round) {
            let parts: Vec<Option<ChunkPart>> = (round..(round + per_round).min(n_chunks))
                .into_par_iter()
                .map(|ci| {
                    if cancelled(cancel) {
                        return None;
                    }
                    let model = kept.as_deref().map(|g| chunk_model(g, ci, nc, nl));
                    Some(self.chunk_part(
                        &p,
                        &layout,
                        ci,
                        (col_factor, extra),
                        mode,
                        (&sq, &s),
                        model,
                    ))
                })
                .collect();
            for part in parts {
                let part = part?;
                for (acc, t) in tri.iter_mut().zip(&part.tri) {
                    *acc = stack_r(acc, t);
                }
                for (a, v) in sums.iter_mut().zip(&part.sums) {
                    *a += v;
                }
            }
        }
        // Derivative of the projected scale per channel (local columns), as in `project`.
        let ds = |c: usize| -> Vec<f64> {
            let a = &sums[c * sum_width..(c + 1) * sum_width];
            let mut d = vec![0.0; nl];
            if !projected {
                return d;
            }
            match self.space {
                Space::Linear if a[1] != 0.0 => {
                    let sc = a[0] / a[1];
                    for (j, dj) in d.iter_mut().enumerate() {
                        *dj = (a[2 + j] - 2.0 * sc * a[2 + nl + j]) / a[1];
                    }
                }
                Space::Log if a[0] != 0.0 => {
                    for (j, dj) in d.iter_mut().enumerate() {
                        *dj = -a[2 + j] / a[0];
                    }
                }
                _ => {}
            }
            d
        };
        let mut row = 0;
        let n_rows: usize = tri.iter().map(|t| t.nrows()).sum();
        let mut extra_out = DMatrix::zeros(n_rows, ne);
        let ns = layout.shared.len();
        let blocks = tri
            .iter()
            .enumerate()
            .map(|(c, t)| {
                let dc = ds(c);
                // Own columns: the channel's local parameter (if free), then its scale (if
                // explicit).
                let own_local = layout.local[c];
                let mut local: Vec<usize> = own_local.into_iter().collect();
                if !projected {
                    local.push(nf + c);
                }
                let mut matrix = DMatrix::zeros(t.nrows(), ns + local.len());
                let mut rhs = DVector::zeros(t.nrows());
                for i in 0..t.nrows() {
                    let ra = t[(i, 0)];
                    for (l, dl) in dc.iter().enumerate() {
                        let col = if l < ns {
                            Some(l)
                        } else {
                            own_local.map(|_| ns)
                        };
                        if let Some(col) = col {
                            matrix[(i, col)] = t[(i, 1 + l)] + ra * dl;
                        }
                    }
                    if !projected {
                        matrix[(i, ns + local.len() - 1)] = ra;
                    }
                    rhs[i] = t[(i, nl + 1)];
                    for e in 0..ne {
                        extra_out[(row, e)] = t[(i, nl + 2 + e)];
                    }
                    row += 1;
                }
                Block { local, matrix, rhs }
            })
            .collect();
        Some(Linearization {
            system: BlockSystem {
                ncols: nf + if projected { 0 } else { nc },
                shared: layout.shared.clone(),
                blocks,
            },
            rows: self.angles.len() * nc,
            scale: s,
            extra: extra_out,
        })
    }

    /// Rows of chunk `ci`, reduced to one R factor per channel, with the projection sums;
    /// `kept`: the chunk's model values and gradients from a kept pass at `p`.
    #[allow(clippy::too_many_arguments)]
    fn chunk_part(
        &self,
        p: &ParamSet<F>,
        layout: &Layout<F::Param>,
        ci: usize,
        (col_factor, extra): (&[f64], &[&[f64]]),
        mode: ScaleMode<'_>,
        (sq, s): (&[f64], &[f64]),
        kept: Option<(&[f64], &[f64])>,
    ) -> ChunkPart {
        let nc = self.n_channels;
        let nl = layout.n_cols();
        let w = nl + 2 + extra.len();
        let sum_width = 2 + 2 * nl;
        let lo = ci * CHUNK;
        let hi = (lo + CHUNK).min(self.angles.len());
        let n = hi - lo;
        let (mut own_out, mut own_grad);
        let (out, grad): (&[f64], &[f64]) = match kept {
            Some(k) => k,
            None => {
                own_out = vec![0.0; n * nc];
                own_grad = vec![0.0; n * nc * nl];
                self.forward.gradients_compressed(
                    p,
                    &layout.shared_names,
                    &layout.local_names,
                    &self.angles[lo..hi],
                    &mut own_out,
                    &mut own_grad,
                );
                (&own_out, &own_grad)
            }
        };
        // Column factors per channel (the solver transform's derivative; 0 for a fixed local).
        let factors: Vec<Vec<f64>> = (0..nc)
            .map(|c| {
                (0..nl)
                    .map(|l| layout.free_index(c, l).map_or(0.0, |j| col_factor[j]))
                    .collect()
            })
            .collect();
        let mut rows: Vec<DMatrix<f64>> = vec![DMatrix::zeros(n, w); nc];
        let mut sums = vec![0.0; nc * sum_width];
        let mut g = vec![0.0; nl];
        let log = self.space == Space::Log;
        for i in 0..n {
            for c in 0..nc {
                let kl = i * nc + c;
                let k = lo * nc + kl;
                let mk = out[kl];
                for (l, gl) in g.iter_mut().enumerate() {
                    *gl = grad[kl * nl + l] * factors[c][l];
                }
                if log {
                    for gl in g.iter_mut() {
                        *gl = if mk > MODEL_FLOOR { *gl / mk } else { 0.0 };
                    }
                }
                let (wk, y, lin) = (self.w[k], self.target[k], self.lin[k]);
                let qk = if log { mk.max(MODEL_FLOOR).ln() } else { mk };
                let (r, f) = self.row_residual(k, mk, sq[c], s[c]);
                // ∂res/∂(fixed-scale shape) = bmul·g; ∂res/∂(scale parameter) = a.
                let sm = s[c] * mk;
                let bmul = match self.space {
                    Space::Linear => -wk * sq[c],
                    Space::Log if lin => -wk * sm,
                    Space::Log => -wk,
                };
                let a = match (self.space, mode) {
                    (Space::Linear, ScaleMode::ExplicitLog(_)) => -wk * sq[c] * qk,
                    (Space::Linear, _) => -wk * qk,
                    (Space::Log, ScaleMode::FixedNatural(_)) if lin => -wk * mk,
                    (Space::Log, ScaleMode::FixedNatural(_)) => -wk / s[c],
                    (Space::Log, _) if lin => -wk * sm,
                    (Space::Log, _) => -wk,
                };
                let finite0 = |v: f64| if v.is_finite() { v } else { 0.0 };
                let mut rm = rows[c].row_mut(i);
                rm[0] = finite0(f * a);
                for l in 0..nl {
                    rm[1 + l] = finite0(f * bmul * g[l]);
                }
                rm[nl + 1] = r;
                for (e, col) in extra.iter().enumerate() {
                    rm[nl + 2 + e] = finite0(col[k]);
                }
                if matches!(mode, ScaleMode::Projected) && !lin {
                    let acc = &mut sums[c * sum_width..(c + 1) * sum_width];
                    let w2 = wk * wk;
                    match self.space {
                        Space::Linear => {
                            acc[0] += w2 * y * qk;
                            acc[1] += w2 * qk * qk;
                            for l in 0..nl {
                                acc[2 + l] += w2 * y * g[l];
                                acc[2 + nl + l] += w2 * qk * g[l];
                            }
                        }
                        Space::Log => {
                            acc[0] += w2;
                            acc[1] += w2 * (y - qk);
                            for l in 0..nl {
                                acc[2 + l] += w2 * g[l];
                            }
                        }
                    }
                }
            }
        }
        ChunkPart {
            tri: rows.into_iter().map(triangle).collect(),
            sums,
        }
    }
}

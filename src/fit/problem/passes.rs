//! The model passes over every sample: values, and values with the compressed gradients the
//! linearisation reduces ([`Layout`]'s columns), each through the evaluator's memo of recent
//! passes, so a pass at a point already evaluated costs no model evaluation.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;

use rayon::prelude::*;

use super::evaluation::CHUNK;
use super::evaluator::Evaluator;
use super::forward::{FitParam, Forward, ParamSet};
use super::memo::Gradients;

/// A kept gradient pass of an evaluator over family `F`.
type Kept<F> = Arc<Gradients<ParamSet<F>, <F as Forward>::Param>>;

/// Which solver columns one channel's rows touch.
pub(super) struct Layout<P> {
    /// Indices into `free` of the shared parameters, and the parameters.
    pub shared: Vec<usize>,
    pub shared_names: Vec<P>,
    /// Per channel, the index into `free` of its local parameter, and the parameter, if free.
    pub local: Vec<Option<usize>>,
    pub local_names: Vec<Option<P>>,
}

impl<P: FitParam> Layout<P> {
    pub fn of(free: &[P], nc: usize) -> Layout<P> {
        let mut layout = Layout {
            shared: Vec::new(),
            shared_names: Vec::new(),
            local: vec![None; nc],
            local_names: vec![None; nc],
        };
        for (j, &name) in free.iter().enumerate() {
            match name.channel() {
                Some(c) if c < nc => {
                    layout.local[c] = Some(j);
                    layout.local_names[c] = Some(name);
                }
                _ => {
                    layout.shared.push(j);
                    layout.shared_names.push(name);
                }
            }
        }
        layout
    }

    /// Gradient columns per row: shared, then the channel's local one.
    pub fn n_cols(&self) -> usize {
        self.shared.len() + 1
    }

    /// The index into `free` of local column `l` for channel `c`.
    pub fn free_index(&self, c: usize, l: usize) -> Option<usize> {
        self.shared.get(l).copied().or(self.local[c])
    }
}

/// Chunk `ci`'s slices of a kept gradient pass.
pub(super) fn chunk_model<S, P>(
    g: &Gradients<S, P>,
    ci: usize,
    nc: usize,
    nl: usize,
) -> (&[f64], &[f64]) {
    let lo = ci * CHUNK * nc;
    let hi = (lo + CHUNK * nc).min(g.values.len());
    (&g.values[lo..hi], &g.grads[lo * nl..hi * nl])
}

pub(super) fn cancelled(flag: Option<&AtomicBool>) -> bool {
    flag.is_some_and(|f| f.load(Ordering::Relaxed))
}

impl<F: Forward> Evaluator<'_, F> {
    /// Model values of every row (sample-major), in chunks; `None` when cancelled.
    pub(super) fn model_values(
        &self,
        p: &ParamSet<F>,
        cancel: Option<&AtomicBool>,
    ) -> Option<Vec<f64>> {
        if let Some(kept) = self.memo.values_at(p) {
            return Some(kept);
        }
        let nc = self.n_channels;
        // A family whose gradients cost little more than its values (and give the same values)
        // computes them with every value pass, as does an evaluator asked to: the linearisation
        // at an accepted step is then free.
        let fused = self.gradients_with_values || self.forward.cheap_gradients(&self.free);
        if !self.free.is_empty() && fused {
            let layout = Layout::of(&self.free, nc);
            if let Some(pass) = self.kept_gradients(p, &layout, cancel)? {
                return Some(pass.values.clone());
            }
        }
        let mut model = vec![0.0; self.angles.len() * nc];
        let done: Vec<bool> = model
            .par_chunks_mut(CHUNK * nc)
            .zip(self.angles.par_chunks(CHUNK))
            .map(|(m, a)| {
                if cancelled(cancel) {
                    return false;
                }
                self.forward.values(p, a, m);
                true
            })
            .collect();
        if !done.iter().all(|&d| d) {
            return None;
        }
        self.memo.keep_values(p, &model);
        Some(model)
    }

    /// The gradient pass at `p` for `layout`'s columns: the kept one, or computed now and kept;
    /// `Some(None)` when it is too large to keep (each chunk then computes its own), `None`
    /// when cancelled.
    pub(super) fn kept_gradients(
        &self,
        p: &ParamSet<F>,
        layout: &Layout<F::Param>,
        cancel: Option<&AtomicBool>,
    ) -> Option<Option<Kept<F>>> {
        let (shared, local) = (&layout.shared_names, &layout.local_names);
        if let Some(kept) = self.memo.gradients_at(p, shared, local) {
            return Some(Some(kept));
        }
        let entries = self.angles.len() * self.n_channels * (layout.n_cols() + 1);
        if !self.memo.fits(entries) {
            return Some(None);
        }
        self.gradient_pass(p, layout, cancel).map(Some)
    }

    /// Every chunk's values and compressed gradients at `p` for `layout`'s columns, computed in
    /// parallel and kept in the memo; `None` when cancelled.
    fn gradient_pass(
        &self,
        p: &ParamSet<F>,
        layout: &Layout<F::Param>,
        cancel: Option<&AtomicBool>,
    ) -> Option<Kept<F>> {
        let nc = self.n_channels;
        let nl = layout.n_cols();
        let rows = self.angles.len() * nc;
        let mut values = vec![0.0; rows];
        let mut grads = vec![0.0; rows * nl];
        let done: Vec<bool> = values
            .par_chunks_mut(CHUNK * nc)
            .zip(grads.par_chunks_mut(CHUNK * nc * nl))
            .zip(self.angles.par_chunks(CHUNK))
            .map(|((v, g), a)| {
                if cancelled(cancel) {
                    return false;
                }
                let (shared, local) = (&layout.shared_names, &layout.local_names);
                self.forward.gradients_compressed(p, shared, local, a, v, g);
                true
            })
            .collect();
        if !done.iter().all(|&d| d) {
            return None;
        }
        let columns = (&layout.shared_names[..], &layout.local_names[..]);
        Some(self.memo.keep_gradients(p, columns, values, grads))
    }
}

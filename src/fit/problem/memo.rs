//! The most recent model passes, kept for reuse: per-sample model values (a value pass) and
//! values with compressed gradients (a gradient pass), each keyed by the whole parameter set it
//! was evaluated at (and the gradient columns). A later pass at the same point reads them
//! instead of running the model again: a fit's polish ends with a value pass and a gradient pass
//! at its final point, so the standard errors, the residual summary and the curves at the data
//! cost no model evaluation. Each kind is kept only while it is small ([`MEMO_MAX_BYTES`]), so
//! a large fit's memory does not grow. A hit returns exactly the numbers the model would.

use std::collections::VecDeque;
use std::sync::{Arc, Mutex};

/// Largest pass kept (bytes of values plus gradients): 100k samples × 3 channels × 8 columns
/// fits, a million-sample fit's passes are not kept (they stream in chunks instead).
pub const MEMO_MAX_BYTES: usize = 32 << 20;

/// Gradient passes kept at once: enough for every thread's LM run of a parallel multi-start to
/// find its own trial's pass (each run linearises where it last evaluated).
pub const MEMO_MAX_PASSES: usize = 8;

/// One kept value pass.
struct Values<S> {
    params: S,
    values: Vec<f64>,
}

/// One kept gradient pass: values `out[k*nc + c]` and `grad[(k*nc + c)*nl + l]`, as
/// `Forward::gradients_compressed` writes them for the columns `(shared, local)`.
pub struct Gradients<S, P> {
    params: S,
    shared: Vec<P>,
    local: Vec<Option<P>>,
    pub values: Vec<f64>,
    pub grads: Vec<f64>,
}

impl<S, P> Gradients<S, P> {
    fn bytes(&self) -> usize {
        (self.values.len() + self.grads.len()) * std::mem::size_of::<f64>()
    }
}

/// The kept passes of one evaluator: the latest value pass, and the latest gradient passes
/// (most recent first) within [`MEMO_MAX_BYTES`] and [`MEMO_MAX_PASSES`].
pub struct PassMemo<S, P> {
    /// The budget in bytes ([`MEMO_MAX_BYTES`] unless set).
    pub max_bytes: usize,
    values: Mutex<Option<Values<S>>>,
    gradients: Mutex<VecDeque<Arc<Gradients<S, P>>>>,
}

impl<S, P> Default for PassMemo<S, P> {
    fn default() -> Self {
        PassMemo {
            max_bytes: MEMO_MAX_BYTES,
            values: Mutex::new(None),
            gradients: Mutex::new(VecDeque::new()),
        }
    }
}

impl<S: PartialEq + Clone, P: PartialEq + Clone> PassMemo<S, P> {
    /// Whether `entries` f64 values fit in the budget.
    pub fn fits(&self, entries: usize) -> bool {
        entries.saturating_mul(std::mem::size_of::<f64>()) <= self.max_bytes
    }

    /// The model values kept for `params`, if any.
    pub fn values_at(&self, params: &S) -> Option<Vec<f64>> {
        let kept = self.values.lock().ok()?;
        kept.as_ref()
            .filter(|k| k.params == *params)
            .map(|k| k.values.clone())
    }

    /// Keep a value pass at `params` (when within the budget).
    pub fn keep_values(&self, params: &S, values: &[f64]) {
        if !self.fits(values.len()) {
            return;
        }
        if let Ok(mut kept) = self.values.lock() {
            *kept = Some(Values {
                params: params.clone(),
                values: values.to_vec(),
            });
        }
    }

    /// The gradient pass kept for `params` and these columns, if any.
    pub fn gradients_at(
        &self,
        params: &S,
        shared: &[P],
        local: &[Option<P>],
    ) -> Option<Arc<Gradients<S, P>>> {
        let kept = self.gradients.lock().ok()?;
        kept.iter()
            .find(|g| g.params == *params && g.shared == shared && g.local == local)
            .cloned()
    }

    /// Keep a gradient pass (when within the budget), dropping the oldest beyond the limits;
    /// returns it.
    pub fn keep_gradients(
        &self,
        params: &S,
        (shared, local): (&[P], &[Option<P>]),
        values: Vec<f64>,
        grads: Vec<f64>,
    ) -> Arc<Gradients<S, P>> {
        let pass = Arc::new(Gradients {
            params: params.clone(),
            shared: shared.to_vec(),
            local: local.to_vec(),
            values,
            grads,
        });
        if pass.bytes() > self.max_bytes {
            return pass;
        }
        if let Ok(mut kept) = self.gradients.lock() {
            kept.push_front(Arc::clone(&pass));
            let mut total = 0;
            let keep = kept
                .iter()
                .take(MEMO_MAX_PASSES)
                .take_while(|g| {
                    total += g.bytes();
                    total <= self.max_bytes
                })
                .count();
            kept.truncate(keep);
        }
        pass
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_value_pass_is_returned_only_for_its_own_parameters() {
        let memo: PassMemo<Vec<f64>, u8> = PassMemo::default();
        assert!(memo.values_at(&vec![1.0]).is_none());
        memo.keep_values(&vec![1.0], &[3.0, 4.0]);
        assert_eq!(memo.values_at(&vec![1.0]), Some(vec![3.0, 4.0]));
        assert!(memo.values_at(&vec![1.0 + f64::EPSILON]).is_none());
        memo.keep_values(&vec![2.0], &[5.0]);
        assert!(memo.values_at(&vec![1.0]).is_none(), "one pass is kept");
    }

    #[test]
    fn a_gradient_pass_needs_the_same_columns() {
        let memo: PassMemo<Vec<f64>, u8> = PassMemo::default();
        memo.keep_gradients(&vec![1.0], (&[0, 1], &[Some(2)]), vec![1.0], vec![0.5; 3]);
        assert!(memo.gradients_at(&vec![1.0], &[0, 1], &[Some(2)]).is_some());
        assert!(memo.gradients_at(&vec![1.0], &[0], &[Some(2)]).is_none());
        assert!(memo.gradients_at(&vec![1.0], &[0, 1], &[None]).is_none());
        assert!(memo.gradients_at(&vec![1.5], &[0, 1], &[Some(2)]).is_none());
    }

    #[test]
    fn the_latest_gradient_passes_are_kept_up_to_the_limit() {
        let memo: PassMemo<Vec<f64>, u8> = PassMemo::default();
        for k in 0..=MEMO_MAX_PASSES {
            memo.keep_gradients(&vec![k as f64], (&[0], &[None]), vec![1.0], vec![2.0]);
        }
        assert!(
            memo.gradients_at(&vec![0.0], &[0], &[None]).is_none(),
            "the oldest is dropped"
        );
        for k in 1..=MEMO_MAX_PASSES {
            let g = memo
                .gradients_at(&vec![k as f64], &[0], &[None])
                .expect("kept");
            assert_eq!((g.values[0], g.grads[0]), (1.0, 2.0));
        }
        // One pass of most of the budget leaves room for no older one.
        let big = MEMO_MAX_BYTES / 8 - 1;
        memo.keep_gradients(&vec![-1.0], (&[0], &[None]), vec![0.0; big], vec![0.0]);
        assert!(memo.gradients_at(&vec![-1.0], &[0], &[None]).is_some());
        assert!(memo.gradients_at(&vec![1.0], &[0], &[None]).is_none());
    }

    #[test]
    fn a_pass_over_the_budget_is_not_kept() {
        let memo: PassMemo<Vec<f64>, u8> = PassMemo::default();
        let n = MEMO_MAX_BYTES / 8 + 1;
        memo.keep_values(&vec![1.0], &vec![0.0; n]);
        assert!(memo.values_at(&vec![1.0]).is_none());
        memo.keep_gradients(&vec![1.0], (&[0], &[None]), vec![0.0; n], Vec::new());
        assert!(memo.gradients_at(&vec![1.0], &[0], &[None]).is_none());
    }
}

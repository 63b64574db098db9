//! What the LM solver asks of a problem: the residual norm at trial points, and at accepted points
//! a linearisation `(M, t)` with `MᵀM = JᵀJ`, `Mᵀt = Jᵀr` and `‖t‖ = ‖r‖` — the Jacobian itself
//! for small problems ([`Operator`] + [`Jacobian`], every such type qualifies), or a reduced form
//! accumulated in chunks for large ones (the fit's problem), so `J` need never be stored. A
//! reduced form may come by blocks ([`BlockSystem`]) when most columns touch one block of rows
//! only: the solver then eliminates them block by block.

use argmin::core::{Error as ArgminError, Jacobian, Operator};
use nalgebra::{DMatrix, DVector};

use super::blocks::BlockSystem;

/// A linearisation of the residuals at one point.
#[derive(Debug, Clone)]
pub struct Linearized {
    /// `(M, t)` with `MᵀM = JᵀJ`, `Mᵀt = Jᵀr` and `‖t‖ = ‖r‖`.
    pub system: System,
    /// Number of residuals `m` (sets the rounding-level singular-value cutoff).
    pub rows: usize,
    /// Per column, how much flatter than its steepest the problem's parameter transform is at
    /// this point (≥ 1), where a column's norm says less than it would elsewhere: a bounded
    /// parameter sitting on its bound. The solver scales such a column as if the transform were
    /// at its steepest. `None` (or 1): the column norms as they are.
    pub flatness: Option<DVector<f64>>,
}

/// How a linearisation stores `(M, t)`.
#[derive(Debug, Clone)]
pub enum System {
    /// `M` and `t` as they are (`J` and `r` themselves for a dense problem).
    Dense {
        matrix: DMatrix<f64>,
        residuals: DVector<f64>,
    },
    /// By blocks of rows with columns of their own (see [`BlockSystem`]).
    Blocks(BlockSystem),
}

impl Linearized {
    /// Number of columns of `M`.
    pub fn ncols(&self) -> usize {
        match &self.system {
            System::Dense { matrix, .. } => matrix.ncols(),
            System::Blocks(b) => b.ncols,
        }
    }

    /// Whether every entry of `M` is finite.
    pub fn all_finite(&self) -> bool {
        match &self.system {
            System::Dense { matrix, .. } => matrix.iter().all(|v| v.is_finite()),
            System::Blocks(b) => b.all_finite(),
        }
    }

    /// `Mᵀt`.
    pub fn gradient(&self) -> DVector<f64> {
        match &self.system {
            System::Dense { matrix, residuals } => matrix.tr_mul(residuals),
            System::Blocks(b) => b.gradient(),
        }
    }
}

/// A nonlinear least-squares problem `min ½‖r(x)‖²` as the LM solver runs it.
pub trait LeastSquares {
    /// What a trial evaluation keeps for a following [`LeastSquares::linearize`] at the same point.
    type Trial;
    /// `‖r(x)‖` (infinite where `r` is not finite), and what the linearisation may reuse.
    fn trial(&self, x: &DVector<f64>) -> Result<(f64, Self::Trial), ArgminError>;
    /// The linearisation at `x`, where `trial` was the trial evaluation.
    fn linearize(&self, x: &DVector<f64>, trial: Self::Trial) -> Result<Linearized, ArgminError>;
}

impl<O> LeastSquares for O
where
    O: Operator<Param = DVector<f64>, Output = DVector<f64>>
        + Jacobian<Param = DVector<f64>, Jacobian = DMatrix<f64>>,
{
    type Trial = DVector<f64>;

    fn trial(&self, x: &DVector<f64>) -> Result<(f64, DVector<f64>), ArgminError> {
        let r = self.apply(x)?;
        let norm = if r.iter().all(|v| v.is_finite()) {
            r.norm()
        } else {
            f64::INFINITY
        };
        Ok((norm, r))
    }

    fn linearize(&self, x: &DVector<f64>, r: DVector<f64>) -> Result<Linearized, ArgminError> {
        let matrix = self.jacobian(x)?;
        Ok(Linearized {
            rows: r.len(),
            flatness: None,
            system: System::Dense {
                matrix,
                residuals: r,
            },
        })
    }
}

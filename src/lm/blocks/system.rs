//! A block-structured linearisation ([`BlockSystem`]): its blocks of rows, their shared and own
//! columns, and the products and scalings the solvers take of it.

use nalgebra::{DMatrix, DVector};

/// Rows of one block: `[shared columns | its own columns]` and their residuals.
#[derive(Debug, Clone)]
pub struct Block {
    /// Solver indices of the block's own columns (in the order of its matrix's last columns).
    pub local: Vec<usize>,
    /// `rows × (shared + local)`.
    pub matrix: DMatrix<f64>,
    /// Residuals (or their reduced form `t`) of the block's rows.
    pub rhs: DVector<f64>,
}

/// A linearisation `(M, t)` stored by blocks: `M`'s rows are the blocks' rows, each zero outside
/// the shared columns and the block's own ones.
#[derive(Debug, Clone)]
pub struct BlockSystem {
    /// Number of solver columns.
    pub ncols: usize,
    /// Solver indices of the shared columns (in the order of every block's first columns).
    pub shared: Vec<usize>,
    pub blocks: Vec<Block>,
}

/// Blocks merged per round when stacking shared rows: bounds the rows held before a QR.
pub(super) const MERGE: usize = 64;

impl BlockSystem {
    /// Number of rows of `M`.
    pub fn nrows(&self) -> usize {
        self.blocks.iter().map(|b| b.matrix.nrows()).sum()
    }

    /// Whether every entry of `M` and `t` is finite.
    pub fn all_finite(&self) -> bool {
        self.blocks
            .iter()
            .all(|b| b.matrix.iter().all(|v| v.is_finite()) && b.rhs.iter().all(|v| v.is_finite()))
    }

    /// Solver index of column `k` of block `b`'s matrix.
    pub(super) fn index(&self, b: &Block, k: usize) -> usize {
        let s = self.shared.len();
        if k < s {
            self.shared[k]
        } else {
            b.local[k - s]
        }
    }

    /// Euclidean norm of each column of `M`.
    pub fn column_norms(&self) -> DVector<f64> {
        let mut sq = vec![0.0; self.ncols];
        for b in &self.blocks {
            for (k, col) in b.matrix.column_iter().enumerate() {
                sq[self.index(b, k)] += col.norm_squared();
            }
        }
        DVector::from_iterator(self.ncols, sq.into_iter().map(f64::sqrt))
    }

    /// `Mᵀt`.
    pub fn gradient(&self) -> DVector<f64> {
        let mut g = DVector::zeros(self.ncols);
        for b in &self.blocks {
            for (k, col) in b.matrix.column_iter().enumerate() {
                g[self.index(b, k)] += col.dot(&b.rhs);
            }
        }
        g
    }

    /// `‖M z‖²`.
    pub fn apply_norm2(&self, z: &DVector<f64>) -> f64 {
        self.blocks
            .iter()
            .map(|b| {
                let zb = DVector::from_iterator(
                    b.matrix.ncols(),
                    (0..b.matrix.ncols()).map(|k| z[self.index(b, k)]),
                );
                (&b.matrix * zb).norm_squared()
            })
            .sum()
    }

    /// The same system with column `j` divided by `d[j]`.
    pub fn scale_columns(&self, d: &DVector<f64>) -> BlockSystem {
        let blocks = self
            .blocks
            .iter()
            .map(|b| {
                let mut m = b.matrix.clone();
                for (k, mut col) in m.column_iter_mut().enumerate() {
                    col /= d[self.index(b, k)];
                }
                Block {
                    local: b.local.clone(),
                    matrix: m,
                    rhs: b.rhs.clone(),
                }
            })
            .collect();
        BlockSystem {
            ncols: self.ncols,
            shared: self.shared.clone(),
            blocks,
        }
    }

    /// Dense `(M, t)`, rows in block order (for small systems and tests).
    pub fn to_dense(&self) -> (DMatrix<f64>, DVector<f64>) {
        let n = self.nrows();
        let mut m = DMatrix::zeros(n, self.ncols);
        let mut t = DVector::zeros(n);
        let mut row = 0;
        for b in &self.blocks {
            for i in 0..b.matrix.nrows() {
                for k in 0..b.matrix.ncols() {
                    m[(row, self.index(b, k))] = b.matrix[(i, k)];
                }
                t[row] = b.rhs[i];
                row += 1;
            }
        }
        (m, t)
    }
}

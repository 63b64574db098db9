//! Block-structured linearisations and their block elimination. Many columns belong to one block
//! of rows only (a channel's own `σ_a` and scale); a few are shared by every block. The damped
//! LM system and the covariance are solved by eliminating each block's own columns with a small
//! Householder QR of that block (a Schur complement onto the shared columns that never forms the
//! normal matrix, so the conditioning is not squared), then one QR of the shared rows: time and
//! memory `O(blocks · shared²)` instead of `O(blocks²)`.
//!
//! Determinism: blocks are factored in parallel but each independently, and merged in block
//! order, so results do not depend on the thread count.

mod covariance;
mod factor;
mod system;

pub use covariance::{block_covariance, orthogonal_part, BlockCovariance};
pub(super) use factor::block_trust_region_step;
pub use system::{Block, BlockSystem};

#[cfg(test)]
mod tests {
    use nalgebra::{DMatrix, DVector};

    use super::factor::Factor;
    use super::*;

    /// Two shared columns, `nb` blocks with one or two own columns each, pseudo-random entries.
    fn system(nb: usize, seed: u64) -> BlockSystem {
        let mut state = seed;
        let mut next = move || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as f64 / (1u64 << 53) as f64) - 0.5
        };
        let s = 2;
        let mut col = s;
        let blocks = (0..nb)
            .map(|b| {
                let l = 1 + b % 2;
                let local: Vec<usize> = (col..col + l).collect();
                col += l;
                let rows = 3 + b % 3;
                Block {
                    local,
                    matrix: DMatrix::from_fn(rows, s + l, |_, _| next()),
                    rhs: DVector::from_fn(rows, |_, _| next()),
                }
            })
            .collect();
        BlockSystem {
            ncols: col,
            shared: vec![0, 1],
            blocks,
        }
    }

    #[test]
    fn damped_solve_matches_the_dense_normal_equations() {
        let sys = system(7, 3);
        let (m, t) = sys.to_dense();
        for lambda in [0.0, 1e-3, 0.5, 10.0] {
            let f = Factor::of(&sys, lambda);
            let z = f.solve(&sys);
            let h = m.tr_mul(&m) + DMatrix::identity(sys.ncols, sys.ncols) * lambda;
            let expect = -h.clone().lu().solve(&m.tr_mul(&t)).unwrap();
            // A well-conditioned 12-column system: both solves are accurate to ~1e-14.
            assert!(
                (&z - &expect).norm() < 1e-10 * expect.norm(),
                "λ = {lambda}"
            );
            let slope = expect.dot(&h.lu().solve(&expect).unwrap());
            assert!((f.slope(&sys, &z) / slope - 1.0).abs() < 1e-10);
        }
        assert!(
            (sys.apply_norm2(&DVector::repeat(sys.ncols, 1.0))
                - (&m * DVector::repeat(sys.ncols, 1.0)).norm_squared())
            .abs()
                < 1e-12
        );
    }

    #[test]
    fn undamped_step_predicts_the_dense_gauss_newton_decrease() {
        let sys = system(7, 5);
        let (m, t) = sys.to_dense();
        let rows = m.nrows();
        // Dense Gauss–Newton: ‖M p‖² with M p the projection of −t onto M's column space.
        let p = m.clone().svd(true, true).solve(&t, 1e-14).unwrap();
        let dense = (&m * p).norm_squared();
        let step = block_trust_region_step(&sys, f64::INFINITY, 0.0, rows);
        assert_eq!(step.lambda, 0.0);
        // A well-conditioned random system: agreement to rounding of its ~20 columns.
        assert!(
            (step.jp2 - dense).abs() <= 1e-12 * dense,
            "{} vs {dense}",
            step.jp2
        );
    }

    #[test]
    fn block_covariance_matches_the_dense_covariance() {
        let sys = system(9, 11);
        let (m, _) = sys.to_dense();
        let dense = super::super::covariance(&m, 2.0, 5).unwrap();
        let block = block_covariance(&sys, 2.0, 5, super::super::DEFAULT_RCOND).unwrap();
        let scale = dense.matrix.abs().max();
        for i in 0..sys.ncols {
            for j in 0..sys.ncols {
                // Condition ~10 and 15 columns: both agree to ~1e-14 relative to the largest.
                assert!((block.entry(i, j) - dense.matrix[(i, j)]).abs() < 1e-10 * scale);
            }
        }
        assert_eq!(block.rank_deficiency, 0);
        assert!(block.undetermined.iter().all(|u| !u));
    }

    #[test]
    fn orthogonal_part_is_orthogonal_to_every_column() {
        let sys = system(6, 8);
        let (m, _) = sys.to_dense();
        let e = DVector::from_fn(m.nrows(), |i, _| (i as f64).sin());
        let perp = orthogonal_part(&sys, &e, 1e-10);
        // Well conditioned: MᵀM z = Mᵀe holds to rounding (the 1e-20 damping is negligible).
        assert!(m.tr_mul(&perp).norm() < 1e-10 * e.norm());
        assert!(perp.norm() > 0.1 * e.norm());
    }

    #[test]
    fn block_covariance_flags_a_shared_column_copied_into_a_block() {
        let mut sys = system(4, 5);
        // Block 0's own column equals shared column 1: only their sum is determined, and a
        // dropped shared direction carries both.
        let b = &mut sys.blocks[0];
        let s1 = b.matrix.column(1).into_owned();
        b.matrix.set_column(2, &s1);
        for other in sys.blocks.iter_mut().skip(1) {
            other.matrix.column_mut(1).fill(0.0);
        }
        let cov = block_covariance(&sys, 1.0, 3, super::super::DEFAULT_RCOND).unwrap();
        assert!(cov.rank_deficiency >= 1);
        assert!(
            cov.undetermined[1] && cov.undetermined[2],
            "{:?}",
            cov.null_weights
        );
        assert!(!cov.undetermined[0]);
    }
}

//! The detector: the rig's outgoing directions of one incidence as sampling points, each
//! collecting the weight that leaves within a cap of angular radius κ around it, per path
//! order and channel; a grid over (θ, φ) finds the caps an exit falls in.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::optics::{angles_of, dot, V3};
use super::sampler::{Weights, ORDERS};

/// The sampling points of one incidence and the grid that finds them: rows uniform in
/// sin θ, columns uniform in a pseudo-angle of φ (no trigonometry per exit).
#[derive(Debug, Clone)]
pub struct Detector {
    dirs: Vec<V3>,
    cos_kernel: f64,
    n_rows: usize,
    n_cols: usize,
    /// Sample indices per cell, cells row-major: `starts[k]..starts[k+1]`.
    starts: Vec<u32>,
    members: Vec<u32>,
    /// `dirs[members[j]]`, contiguous: a cell's candidates are read in one pass.
    member_dirs: Vec<V3>,
    /// Rows with at least one member: most exits fall in rows no cap reaches (a rig samples a
    /// few inclinations), and are dismissed before the column's arithmetic.
    row_used: Vec<bool>,
}

/// A monotone stand-in for φ ∈ [0, 2π) in [0, 4) from the in-plane components (the "diamond
/// angle"): cells in it are at most twice as wide in φ as the mean. Written with selects, not
/// branches: an exit's quadrant is random, so branches on it mispredict.
fn pseudo_angle(x: f64, y: f64) -> f64 {
    // y/(|x| + |y|) ∈ [−1, 1]; (0, 0) gives 0.
    let a = y / (x.abs() + y.abs()).max(f64::MIN_POSITIVE);
    let left = 2.0 - a;
    let lower = 4.0 + a;
    let v = if y < 0.0 { lower } else { a };
    if x < 0.0 {
        left
    } else {
        v
    }
}

impl Detector {
    /// Points at the unit directions `dirs`, caps of radius `kernel` (radians, in (0, π/2)).
    pub fn new(dirs: Vec<V3>, kernel: f64) -> Detector {
        let n_rows = ((2.0 / kernel.sin()).ceil() as usize).max(1);
        let n_cols = ((TAU / kernel).ceil() as usize).max(1);
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n_rows * n_cols];
        for (s, &d) in dirs.iter().enumerate() {
            let (theta, phi) = angles_of(d);
            let z_lo = (theta - kernel).max(-FRAC_PI_2).sin();
            let z_hi = (theta + kernel).min(FRAC_PI_2).sin();
            let lo = row(z_lo, n_rows).saturating_sub(1);
            let hi = (row(z_hi, n_rows) + 1).min(n_rows - 1);
            let far = theta.abs() + kernel;
            // The cap's half-width in φ at its widest (nearest the pole).
            let half = if far >= FRAC_PI_2 - 1e-9 {
                PI
            } else {
                (kernel.sin() / far.cos()).min(1.0).asin()
            };
            let cols: Vec<usize> = if half >= FRAC_PI_2 {
                (0..n_cols).collect()
            } else {
                let a = col(phi - half, n_cols) as i64 - 1;
                let b = col(phi + half, n_cols) as i64 + 1;
                let n = n_cols as i64;
                let span = (b - a).rem_euclid(n) + 1;
                if span >= n {
                    (0..n_cols).collect()
                } else {
                    (0..span).map(|k| (a + k).rem_euclid(n) as usize).collect()
                }
            };
            for r in lo..=hi {
                for &c in &cols {
                    let list = &mut lists[r * n_cols + c];
                    if list.last() != Some(&(s as u32)) {
                        list.push(s as u32);
                    }
                }
            }
        }
        let mut starts = Vec::with_capacity(lists.len() + 1);
        let mut members = Vec::new();
        for l in &lists {
            starts.push(members.len() as u32);
            members.extend_from_slice(l);
        }
        starts.push(members.len() as u32);
        let member_dirs = members.iter().map(|&s| dirs[s as usize]).collect();
        let row_used = (0..n_rows)
            .map(|r| starts[r * n_cols] != starts[(r + 1) * n_cols])
            .collect();
        Detector {
            dirs,
            cos_kernel: kernel.cos(),
            n_rows,
            n_cols,
            starts,
            members,
            member_dirs,
            row_used,
        }
    }

    pub fn len(&self) -> usize {
        self.dirs.len()
    }

    pub fn is_empty(&self) -> bool {
        self.dirs.is_empty()
    }

    /// Call `hit(s)` for every sampling point `s` whose cap holds the unit direction `d`.
    pub fn visit(&self, d: V3, mut hit: impl FnMut(usize)) {
        let r = row(d[0], self.n_rows);
        if !self.row_used[r] {
            return;
        }
        let c =
            ((pseudo_angle(d[1], d[2]) * 0.25 * self.n_cols as f64) as usize).min(self.n_cols - 1);
        let k = r * self.n_cols + c;
        let (a, b) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        for (&m, &s) in self.member_dirs[a..b].iter().zip(&self.members[a..b]) {
            if dot(m, d) >= self.cos_kernel {
                hit(s as usize);
            }
        }
    }
}

fn row(z: f64, n: usize) -> usize {
    // `as` truncates toward zero and saturates below at 0: the floor here, without a libm call.
    (((z + 1.0) * 0.5 * n as f64) as usize).min(n - 1)
}

fn col(phi: f64, n: usize) -> usize {
    let (s, c) = phi.sin_cos();
    ((pseudo_angle(c, s) * 0.25 * n as f64) as usize).min(n - 1)
}

/// Weight collected per sampling point, order and channel: index `(s·ORDERS + p)·nc + c`.
#[derive(Debug, Clone)]
pub struct Collected {
    pub nc: usize,
    pub sums: Vec<f64>,
}

impl Collected {
    pub fn new(n_points: usize, nc: usize) -> Collected {
        Collected {
            nc,
            sums: vec![0.0; n_points * ORDERS * nc],
        }
    }

    pub fn add(&mut self, s: usize, order: usize, w: &Weights) {
        let base = (s * ORDERS + order.min(ORDERS - 1)) * self.nc;
        for (x, y) in self.sums[base..base + self.nc].iter_mut().zip(w) {
            *x += y;
        }
    }

    pub fn get(&self, s: usize, order: usize, c: usize) -> f64 {
        self.sums[(s * ORDERS + order) * self.nc + c]
    }
}

//! The detector: the rig's outgoing directions of one incidence as sampling points, each
//! collecting the weight that leaves within a cap of angular radius κ around it, per path
//! order and channel; a grid over (θ, φ) finds the caps an exit falls in.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::optics::{angles_of, dot, V3};
use super::sampler::{Weights, ORDERS};

/// The sampling points of one incidence and the grid that finds them.
#[derive(Debug, Clone)]
pub struct Detector {
    dirs: Vec<V3>,
    cos_kernel: f64,
    cell: f64,
    n_theta: usize,
    n_phi: usize,
    /// Sample indices per cell, cells row-major (θ rows, φ columns): `starts[k]..starts[k+1]`.
    starts: Vec<u32>,
    members: Vec<u32>,
}

impl Detector {
    /// Points at the unit directions `dirs`, caps of radius `kernel` (radians, in (0, π/2)).
    pub fn new(dirs: Vec<V3>, kernel: f64) -> Detector {
        let n_theta = ((PI / kernel).ceil() as usize).max(1);
        let n_phi = ((TAU / kernel).ceil() as usize).max(1);
        let cell = PI / n_theta as f64;
        let cell_phi = TAU / n_phi as f64;
        let mut lists: Vec<Vec<u32>> = vec![Vec::new(); n_theta * n_phi];
        for (s, &d) in dirs.iter().enumerate() {
            let (theta, phi) = angles_of(d);
            let lo = row(theta - kernel, cell, n_theta);
            let hi = row(theta + kernel, cell, n_theta);
            let far = theta.abs() + kernel;
            // The cap's half-width in φ, at its widest (nearest the pole); with a cell's margin.
            let half = if far >= FRAC_PI_2 - 1e-9 {
                PI
            } else {
                (kernel.sin() / far.cos()).min(1.0).asin() + cell_phi
            };
            let cols: Vec<usize> = if 2.0 * half >= TAU - cell_phi {
                (0..n_phi).collect()
            } else {
                let a = ((phi - half + PI) / cell_phi).floor() as i64;
                let b = ((phi + half + PI) / cell_phi).floor() as i64;
                (a..=b)
                    .map(|k| k.rem_euclid(n_phi as i64) as usize)
                    .collect()
            };
            for r in lo..=hi {
                for &c in &cols {
                    let list = &mut lists[r * n_phi + c];
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
        Detector {
            dirs,
            cos_kernel: kernel.cos(),
            cell,
            n_theta,
            n_phi,
            starts,
            members,
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
        let (theta, phi) = angles_of(d);
        let r = row(theta, self.cell, self.n_theta);
        let c = (((phi + PI) / (TAU / self.n_phi as f64)).floor() as usize).min(self.n_phi - 1);
        let k = r * self.n_phi + c;
        for &s in &self.members[self.starts[k] as usize..self.starts[k + 1] as usize] {
            if dot(self.dirs[s as usize], d) >= self.cos_kernel {
                hit(s as usize);
            }
        }
    }
}

fn row(theta: f64, cell: f64, n: usize) -> usize {
    (((theta + FRAC_PI_2) / cell).floor().max(0.0) as usize).min(n - 1)
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

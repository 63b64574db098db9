//! The detector: the rig's outgoing directions of one incidence as sampling points, each
//! collecting the weight that leaves within a cap of angular radius κ around it, per path
//! order and channel; a grid over (θ, φ) finds the caps an exit falls in.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::optics::{angles_of, dot, V3};
use super::sampler::{Exits, Weights, ORDERS};

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
#[inline(always)]
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
        let mut n_rows = ((2.0 / kernel.sin()).ceil() as usize).max(1);
        let mut n_cols = ((TAU / kernel).ceil() as usize).max(1);
        // Cells about κ/4 high and κ/2 wide (where the grid stays small) hold fewer caps an
        // exit misses: near the poles a row of height sin κ spans several κ of θ.
        if n_rows * n_cols * 8 <= 1 << 18 {
            n_rows *= 4;
            n_cols *= 2;
        }
        let cos_kernel = kernel.cos();
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
                    // The box above is loose near the poles: keep only cells the cap reaches.
                    if !reaches(theta, phi, cos_kernel, r, c, n_rows, n_cols) {
                        continue;
                    }
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
            cos_kernel,
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
    #[inline(always)]
    pub fn visit(&self, d: V3, mut hit: impl FnMut(usize)) {
        let r = row(d[0], self.n_rows);
        if !self.row_used[r] {
            return;
        }
        // The pseudo-angle is ≥ 0: through i64 as in `row`.
        let c = ((pseudo_angle(d[1], d[2]) * 0.25 * self.n_cols as f64) as i64)
            .min(self.n_cols as i64 - 1) as usize;
        let k = r * self.n_cols + c;
        let (a, b) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        for (&m, &s) in self.member_dirs[a..b].iter().zip(&self.members[a..b]) {
            if dot(m, d) >= self.cos_kernel {
                hit(s as usize);
            }
        }
    }
}

/// φ ∈ [0, 2π) of the pseudo-angle `p` ∈ [0, 4): the inverse of [`pseudo_angle`].
fn phi_of_pseudo(p: f64) -> f64 {
    let (x, y) = if p < 1.0 {
        (1.0 - p, p)
    } else if p < 3.0 {
        let a = 2.0 - p;
        (a.abs() - 1.0, a)
    } else {
        let a = p - 4.0;
        (1.0 - a.abs(), a)
    };
    y.atan2(x).rem_euclid(TAU)
}

/// Whether the cap of cosine radius `cos_k` around (θ, φ) may reach cell (`r`, `c`): the
/// largest cosine to any point of the cell, with a margin far above the rounding of an exit's
/// cell and of its dot product, so no exit inside the cap is ever left out.
fn reaches(theta: f64, phi: f64, cos_k: f64, r: usize, c: usize, nr: usize, nc: usize) -> bool {
    let z = |k: usize| (2.0 * k as f64 / nr as f64 - 1.0).clamp(-1.0, 1.0).asin();
    let (t0, t1) = (z(r), z(r + 1));
    let p0 = phi_of_pseudo(4.0 * c as f64 / nc as f64);
    let p1 = if c + 1 == nc {
        TAU
    } else {
        phi_of_pseudo(4.0 * (c + 1) as f64 / nc as f64)
    };
    let ps = phi.rem_euclid(TAU);
    let circ = |a: f64, b: f64| {
        let d = (a - b).abs().rem_euclid(TAU);
        d.min(TAU - d)
    };
    // Nearest azimuth of the cell: for each θ (cos θ ≥ 0) it maximises the cosine.
    let dphi = if (p0..=p1).contains(&ps) {
        0.0
    } else {
        circ(ps, p0).min(circ(ps, p1))
    };
    // Over θ ∈ [t0, t1], A cos θ + B sin θ peaks at atan2(B, A) or at an end.
    let (a, b) = (theta.cos() * dphi.cos(), theta.sin());
    let f = |t: f64| a * t.cos() + b * t.sin();
    let peak = b.atan2(a);
    let mut best = f(t0).max(f(t1));
    if (t0..=t1).contains(&peak) {
        best = best.max(a.hypot(b));
    }
    best >= cos_k - 1e-9
}

#[inline(always)]
fn row(z: f64, n: usize) -> usize {
    // `as` truncates toward zero (and NaN to 0): the floor here, without a libm call; through
    // i64, one conversion instruction where `as usize` takes two and their fix-up.
    (((z + 1.0) * 0.5 * n as f64) as i64).clamp(0, n as i64 - 1) as usize
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

    /// Add `w`'s first channels (`NC`, or all `nc` when `NC` is 0: a constant unrolls it).
    #[inline(always)]
    pub fn add<const NC: usize>(&mut self, s: usize, order: usize, w: &Weights) {
        debug_assert!(NC == 0 || NC == self.nc);
        let nc = if NC == 0 { self.nc } else { NC };
        let base = (s * ORDERS + order.min(ORDERS - 1)) * nc;
        for (x, y) in self.sums[base..base + nc].iter_mut().zip(w) {
            *x += y;
        }
    }

    pub fn get(&self, s: usize, order: usize, c: usize) -> f64 {
        self.sums[(s * ORDERS + order) * self.nc + c]
    }
}

/// One incidence's detector and its tallies, the sampler's [`Exits`]: an exit adds its weights
/// to every sampling point whose cap holds it. Its method is `#[inline(always)]`, so the
/// detector runs inside the sampler's kernel (AVX2, AVX-512), not as a baseline call from it.
pub struct Tally<'a> {
    pub detector: &'a Detector,
    pub collected: &'a mut Collected,
}

impl Exits for Tally<'_> {
    #[inline(always)]
    fn exit<const NC: usize>(&mut self, order: usize, d: V3, w: &Weights) {
        let collected = &mut *self.collected;
        self.detector.visit(d, |s| collected.add::<NC>(s, order, w));
    }
}

#[cfg(test)]
mod tests {
    use super::super::optics::{add, direction, normalize, scale};
    use super::*;

    /// A fixed xorshift: uniform numbers in [0, 1) without a crate.
    fn uniform(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    #[test]
    fn the_grid_finds_exactly_the_caps_holding_a_direction() {
        let mut st = 0x9e37_79b9_7f4a_7c15u64;
        for kernel_deg in [0.7, 2.0, 9.0, 30.0] {
            let k = f64::to_radians(kernel_deg);
            // A ring near the pole, as an azimuthal rig samples, and scattered points.
            let mut dirs: Vec<V3> = (0..180)
                .map(|j| direction(-1.31, (j as f64 + 1.0) * TAU / 180.0))
                .collect();
            for _ in 0..200 {
                let t = (2.0 * uniform(&mut st) - 1.0).asin() * 0.99;
                dirs.push(direction(t, TAU * uniform(&mut st)));
            }
            let det = Detector::new(dirs.clone(), k);
            let mut probes = Vec::new();
            for _ in 0..20_000 {
                let t = (2.0 * uniform(&mut st) - 1.0).asin();
                probes.push(direction(t, TAU * uniform(&mut st)));
            }
            // Exits on and just beside the caps' rims.
            for &d in &dirs {
                for e in [-1e-12, 0.0, 1e-12] {
                    let a = TAU * uniform(&mut st);
                    let side = normalize([d[1], -d[0], 0.0]);
                    let up = normalize([
                        d[1] * side[2] - d[2] * side[1],
                        d[2] * side[0] - d[0] * side[2],
                        d[0] * side[1] - d[1] * side[0],
                    ]);
                    let off = add(scale(side, a.cos()), scale(up, a.sin()));
                    let r = k * (1.0 + e);
                    probes.push(normalize(add(scale(d, r.cos()), scale(off, r.sin()))));
                }
            }
            for p in probes {
                let mut got = Vec::new();
                det.visit(p, |s| got.push(s));
                let want: Vec<usize> = (0..dirs.len())
                    .filter(|&s| dot(dirs[s], p) >= k.cos())
                    .collect();
                assert_eq!(got, want, "kernel {kernel_deg}°, exit {p:?}");
            }
        }
    }
}

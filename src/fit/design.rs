//! The multi-start design: Latin-hypercube start points and seeded subsamples (random numbers
//! from [`crate::rng`]).

pub use crate::rng::SplitMix64;

/// Latin hypercube of `n` points in the box `ranges`: each axis is cut in `n` strata, each stratum
/// used once, a random point inside it. Returns `n` points of `ranges.len()` coordinates.
pub fn latin_hypercube(n: usize, ranges: &[(f64, f64)], seed: u64) -> Vec<Vec<f64>> {
    let mut rng = SplitMix64::new(seed);
    let mut points = vec![vec![0.0; ranges.len()]; n];
    for (d, &(lo, hi)) in ranges.iter().enumerate() {
        let mut strata: Vec<usize> = (0..n).collect();
        rng.shuffle(&mut strata);
        for (point, &k) in points.iter_mut().zip(&strata) {
            let t = (k as f64 + rng.uniform()) / n as f64;
            point[d] = lo + (hi - lo) * t;
        }
    }
    points
}

/// `k` distinct indices out of `0..n` (sorted), chosen by `seed`; all of them when `k ≥ n`.
pub fn subsample(n: usize, k: usize, seed: u64) -> Vec<usize> {
    let mut idx: Vec<usize> = (0..n).collect();
    if k >= n {
        return idx;
    }
    SplitMix64::new(seed).shuffle(&mut idx);
    idx.truncate(k);
    idx.sort_unstable();
    idx
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latin_hypercube_uses_every_stratum_once() {
        let n = 16;
        let pts = latin_hypercube(n, &[(0.0, 1.0), (-2.0, 2.0)], 7);
        for (d, (lo, hi)) in [(0.0, 1.0), (-2.0, 2.0)].into_iter().enumerate() {
            let mut seen = vec![false; n];
            for p in &pts {
                let k = ((p[d] - lo) / (hi - lo) * n as f64).floor() as usize;
                assert!(!seen[k], "stratum {k} of axis {d} used twice");
                seen[k] = true;
            }
        }
        assert_eq!(pts, latin_hypercube(n, &[(0.0, 1.0), (-2.0, 2.0)], 7));
    }
}

//! Seeded, platform-independent random numbers and the Latin-hypercube start design.

/// SplitMix64: tiny, fast, and identical on every platform (so a seed means the same fit).
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    /// Generator from a seed.
    pub fn new(seed: u64) -> Self {
        SplitMix64(seed)
    }

    /// Next 64 random bits.
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }

    /// Uniform in [0, 1).
    pub fn uniform(&mut self) -> f64 {
        (self.next_u64() >> 11) as f64 * (1.0 / (1u64 << 53) as f64)
    }

    /// Uniform integer in `0..n`.
    pub fn below(&mut self, n: usize) -> usize {
        (self.uniform() * n as f64) as usize % n.max(1)
    }

    /// Standard normal deviate (Box–Muller).
    pub fn normal(&mut self) -> f64 {
        let u1 = 1.0 - self.uniform();
        let u2 = self.uniform();
        (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
    }

    /// Fisher–Yates shuffle.
    pub fn shuffle<T>(&mut self, v: &mut [T]) {
        for i in (1..v.len()).rev() {
            let j = self.below(i + 1);
            v.swap(i, j);
        }
    }
}

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

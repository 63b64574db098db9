//! Deterministic decimation of drawn points, so a report of a million samples renders quickly:
//! only the points drawn are thinned, never the data a statistic is computed from, nor the curve.

/// A uniform-stride subset of `0..n` with at most `max` indices, first and last kept, in order.
pub fn stride_indices(n: usize, max: usize) -> Vec<usize> {
    if n <= max {
        return (0..n).collect();
    }
    if max == 0 {
        return Vec::new();
    }
    if max == 1 {
        return vec![0];
    }
    // k·(n−1)/(max−1) for k = 0..max hits 0 and n−1 and is strictly increasing because n > max.
    (0..max)
        .map(|k| ((k as u128 * (n as u128 - 1)) / (max as u128 - 1)) as usize)
        .collect()
}

/// An envelope subset of `0..ys.len()` with at most `max` indices: the order is cut into `max/2`
/// consecutive bins and each keeps its lowest and highest finite `y`, so extremes (outliers)
/// survive decimation. Non-finite values are never kept.
pub fn envelope_indices(ys: &[f64], max: usize) -> Vec<usize> {
    let n = ys.len();
    if n <= max {
        return (0..n).filter(|&i| ys[i].is_finite()).collect();
    }
    let bins = (max / 2).max(1);
    let mut out = Vec::with_capacity(2 * bins);
    for b in 0..bins {
        let start = b * n / bins;
        let end = (b + 1) * n / bins;
        let mut lo: Option<usize> = None;
        let mut hi: Option<usize> = None;
        for i in start..end {
            if !ys[i].is_finite() {
                continue;
            }
            if lo.is_none_or(|j| ys[i] < ys[j]) {
                lo = Some(i);
            }
            if hi.is_none_or(|j| ys[i] > ys[j]) {
                hi = Some(i);
            }
        }
        match (lo, hi) {
            (Some(a), Some(b)) if a == b => out.push(a),
            (Some(a), Some(b)) => {
                out.push(a.min(b));
                out.push(a.max(b));
            }
            _ => {}
        }
    }
    out.truncate(max);
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stride_keeps_everything_when_small_and_is_bounded_when_large() {
        assert_eq!(stride_indices(5, 10), vec![0, 1, 2, 3, 4]);
        let idx = stride_indices(1_000_003, 1000);
        assert_eq!(idx.len(), 1000);
        assert_eq!(idx[0], 0);
        assert_eq!(*idx.last().unwrap(), 1_000_002);
        assert!(idx.windows(2).all(|w| w[0] < w[1]));
    }

    #[test]
    fn envelope_keeps_the_extremes_and_drops_nan() {
        let mut ys: Vec<f64> = (0..100_000)
            .map(|i| ((i * 7919) % 101) as f64 / 100.0)
            .collect();
        ys[54_321] = 50.0;
        ys[12_345] = -50.0;
        ys[77] = f64::NAN;
        let idx = envelope_indices(&ys, 500);
        assert!(idx.len() <= 500);
        assert!(idx.contains(&54_321) && idx.contains(&12_345));
        assert!(idx.iter().all(|&i| ys[i].is_finite()));
        assert_eq!(idx, envelope_indices(&ys, 500), "deterministic");
    }
}

//! Goodness-of-fit statistics of a fit's residuals: the χ² test when the noise is known, and,
//! when it is not, structure along scan slices (residual runs, lag-1 autocorrelation) and the
//! pure-error lack-of-fit F test on repeated measurements (samples grouped by direction).
//! Pure functions of residuals.

use rayon::prelude::*;
use statrs::distribution::{ChiSquared, ContinuousCDF, FisherSnedecor, Normal};

pub use crate::files::statistics::{Autocorrelation, LackOfFit, RunsTest};

/// Upper-tail probability of a χ² at least `chi2` with `dof` degrees of freedom: the chance that
/// noise alone, as the `sigma` column describes it, gives a fit this poor.
pub fn chi2_p_value(chi2: f64, dof: f64) -> Option<f64> {
    if !(chi2.is_finite() && chi2 >= 0.0 && dof > 0.0) {
        return None;
    }
    Some(ChiSquared::new(dof).ok()?.sf(chi2))
}

fn standard_normal() -> Normal {
    Normal::new(0.0, 1.0).expect("unit normal")
}

/// Runs test over `slices` (each one scan in measurement order; zero residuals are skipped).
/// `None` when no slice has both signs.
pub fn runs_test<'a>(slices: impl IntoIterator<Item = &'a [f64]>) -> Option<RunsTest> {
    let (mut runs, mut expected, mut variance) = (0usize, 0.0, 0.0);
    for slice in slices {
        let signs: Vec<bool> = slice
            .iter()
            .filter(|r| **r != 0.0 && r.is_finite())
            .map(|r| *r > 0.0)
            .collect();
        let pos = signs.iter().filter(|s| **s).count() as f64;
        let neg = signs.len() as f64 - pos;
        let n = pos + neg;
        if pos == 0.0 || neg == 0.0 || n < 2.0 {
            continue;
        }
        runs += 1 + signs.windows(2).filter(|w| w[0] != w[1]).count();
        expected += 1.0 + 2.0 * pos * neg / n;
        variance += 2.0 * pos * neg * (2.0 * pos * neg - n) / (n * n * (n - 1.0));
    }
    if variance <= 0.0 {
        return None;
    }
    let z = (runs as f64 - expected) / variance.sqrt();
    Some(RunsTest {
        runs,
        expected,
        z,
        p_value: standard_normal().cdf(z),
    })
}

/// Pooled lag-1 autocorrelation over `slices`; `None` with fewer than 3 pairs.
pub fn lag1_autocorrelation<'a>(
    slices: impl IntoIterator<Item = &'a [f64]>,
) -> Option<Autocorrelation> {
    let (mut cross, mut square, mut pairs) = (0.0, 0.0, 0usize);
    for slice in slices {
        let s: Vec<f64> = slice.iter().copied().filter(|r| r.is_finite()).collect();
        if s.len() < 2 {
            continue;
        }
        // Centre per slice: an offset (e.g. a scale error) is not neighbour correlation.
        let mean = s.iter().sum::<f64>() / s.len() as f64;
        cross += s
            .windows(2)
            .map(|w| (w[0] - mean) * (w[1] - mean))
            .sum::<f64>();
        square += s.iter().map(|r| (r - mean).powi(2)).sum::<f64>();
        pairs += s.len() - 1;
    }
    if pairs < 3 || square <= 0.0 {
        return None;
    }
    let r1 = cross / square;
    let z = r1 * (pairs as f64).sqrt();
    Some(Autocorrelation {
        r1,
        pairs,
        z,
        p_value: standard_normal().sf(z),
    })
}

/// Lack-of-fit test of `residuals` grouped by `group` (equal ids = the same direction and
/// channel, measured again), for a fit with `n_params` free parameters. `None` without
/// replicates or without degrees of freedom on either side.
pub fn lack_of_fit(residuals: &[f64], group: &[usize], n_params: usize) -> Option<LackOfFit> {
    assert_eq!(residuals.len(), group.len(), "one group id per residual");
    let mut order: Vec<usize> = (0..residuals.len()).collect();
    order.sort_by_key(|&i| group[i]);
    let (mut ss_pe, mut dof_pe, mut distinct) = (0.0, 0usize, 0usize);
    for members in order.chunk_by(|&a, &b| group[a] == group[b]) {
        distinct += 1;
        let n = members.len();
        if n < 2 {
            continue;
        }
        let mean = members.iter().map(|&i| residuals[i]).sum::<f64>() / n as f64;
        ss_pe += members
            .iter()
            .map(|&i| (residuals[i] - mean).powi(2))
            .sum::<f64>();
        dof_pe += n - 1;
    }
    let dof_lof = distinct.checked_sub(n_params)?;
    if dof_pe == 0 || dof_lof == 0 || ss_pe <= 0.0 {
        return None;
    }
    let ss_res: f64 = residuals.iter().map(|r| r * r).sum();
    let ss_lof = (ss_res - ss_pe).max(0.0);
    let f = (ss_lof / dof_lof as f64) / (ss_pe / dof_pe as f64);
    let p_value = FisherSnedecor::new(dof_lof as f64, dof_pe as f64)
        .ok()?
        .sf(f);
    Some(LackOfFit {
        ss_pure_error: ss_pe,
        dof_pure_error: dof_pe,
        ss_lack_of_fit: ss_lof,
        dof_lack_of_fit: dof_lof,
        f,
        p_value,
        pure_error_sd: (ss_pe / dof_pe as f64).sqrt(),
    })
}

/// 1.4826 × the median |r|: the standard deviation of Gaussian residuals, unmoved by a minority
/// of outliers (the residuals of a fit with a scale have median near zero). `None` when empty.
pub fn robust_sd(residuals: &[f64]) -> Option<f64> {
    let mut a: Vec<f64> = residuals
        .iter()
        .filter(|r| r.is_finite())
        .map(|r| r.abs())
        .collect();
    if a.is_empty() {
        return None;
    }
    let mid = a.len() / 2;
    let (_, m, _) = a.select_nth_unstable_by(mid, f64::total_cmp);
    Some(1.4826 * *m)
}

/// P(|z| > 5) for a standard normal.
pub const GAUSSIAN_BEYOND_5SD: f64 = 5.733e-7;

/// P(K ≥ k) for K ~ Poisson(λ) (1 for k = 0), summed directly: k is a count of samples.
pub fn poisson_upper_tail(k: usize, lambda: f64) -> f64 {
    if k == 0 {
        return 1.0;
    }
    // 1 − Σ_{j<k} e^{−λ} λ^j / j!, terms built in log space so λ up to ~1e3 is safe.
    let mut below = 0.0;
    let mut log_term = -lambda;
    for j in 0..k {
        if j > 0 {
            log_term += lambda.ln() - (j as f64).ln();
        }
        below += log_term.exp();
    }
    (1.0 - below).max(0.0)
}

/// Each sample's group of identical directions (angles equal to 1e-6°, φ wrapped), numbered in
/// order of first appearance, and each group's size. Sorting keys rather than hashing them: a
/// million samples group in a parallel sort, where a map of (direction, channel) keys took
/// seconds and ~200 MB.
pub fn direction_groups(angles: &[crate::geometry::Angles]) -> (Vec<usize>, Vec<usize>) {
    // |wrap(φ)| ≤ 180° is at most 1.8e8 units of 1e-6°: an i32 (20 bytes per sample with its
    // index, 200 MB at 10M samples where (i64 × 4, usize) took 400 MB).
    let key = |v: f64| (crate::geometry::angles::wrap_deg(v.to_degrees()) * 1e6).round() as i32;
    // Sample indices fit u32: the curves table numbers samples in u32 too.
    let mut keyed: Vec<([i32; 4], u32)> = angles
        .par_iter()
        .enumerate()
        .map(|(i, a)| ([a.theta_i, a.phi_i, a.theta_r, a.phi_r].map(key), i as u32))
        .collect();
    keyed.par_sort_unstable();
    // The first (smallest) sample index of each sample's run of equal keys.
    let mut first = vec![0u32; angles.len()];
    for run in keyed.chunk_by(|a, b| a.0 == b.0) {
        for &(_, i) in run {
            first[i as usize] = run[0].1;
        }
    }
    drop(keyed);
    let mut group = vec![usize::MAX; angles.len()];
    let mut counts = Vec::new();
    for (i, &f) in first.iter().enumerate() {
        let f = f as usize;
        // A run's first sample opens its group; later ones (f < i) join the group f opened.
        if f == i {
            group[i] = counts.len();
            counts.push(0);
        } else {
            group[i] = group[f];
        }
        counts[group[i]] += 1;
    }
    (group, counts)
}

/// `raw` (row-major, `nc` channels) minus each channel's median finite residual.
pub fn centre_per_channel(raw: &[f64], nc: usize) -> Vec<f64> {
    let nc = nc.max(1);
    let medians: Vec<f64> = (0..nc)
        .map(|c| {
            let mut v: Vec<f64> = raw
                .iter()
                .skip(c)
                .step_by(nc)
                .copied()
                .filter(|r| r.is_finite())
                .collect();
            if v.is_empty() {
                return 0.0;
            }
            let mid = v.len() / 2;
            *v.select_nth_unstable_by(mid, f64::total_cmp).1
        })
        .collect();
    raw.iter()
        .enumerate()
        .map(|(k, r)| r - medians[k % nc])
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// Standard normal draws (Box–Muller) from the project's seeded generator.
    fn normals(seed: u64, n: usize) -> Vec<f64> {
        let mut r = SplitMix64::new(seed);
        (0..n)
            .map(|_| {
                let (u, v) = (r.uniform().max(1e-300), r.uniform());
                (-2.0 * u.ln()).sqrt() * (std::f64::consts::TAU * v).cos()
            })
            .collect()
    }

    #[test]
    fn chi2_p_value_matches_tables() {
        // χ²(0.95; 10) = 18.307 and χ²(0.5; 1) = 0.45494 (standard tables, 5 digits).
        assert!((chi2_p_value(18.307, 10.0).unwrap() - 0.05).abs() < 1e-4);
        assert!((chi2_p_value(0.454_936, 1.0).unwrap() - 0.5).abs() < 1e-5);
        assert!(chi2_p_value(f64::NAN, 3.0).is_none());
        assert!(chi2_p_value(1.0, 0.0).is_none());
    }

    /// Under the null (independent noise) the tests' p-values are uniform: over 400 seeded
    /// samples, the fraction below 0.05 is 0.05 ± 3 binomial sd (0.033).
    #[test]
    fn noise_alone_rejects_at_the_nominal_rate() {
        let (mut runs_rejected, mut acf_rejected, mut lof_rejected) = (0, 0, 0);
        let trials = 400;
        for seed in 0..trials {
            let e = normals(seed, 200);
            let slices: Vec<&[f64]> = e.chunks(40).collect();
            if runs_test(slices.iter().copied()).unwrap().p_value < 0.05 {
                runs_rejected += 1;
            }
            if lag1_autocorrelation(slices.iter().copied())
                .unwrap()
                .p_value
                < 0.05
            {
                acf_rejected += 1;
            }
            // 50 directions measured 4 times each; a 3-parameter model that fits.
            let groups: Vec<usize> = (0..200).map(|i| i / 4).collect();
            if lack_of_fit(&e, &groups, 3).unwrap().p_value < 0.05 {
                lof_rejected += 1;
            }
        }
        let sd = (0.05f64 * 0.95 / trials as f64).sqrt();
        for (name, k) in [
            ("runs", runs_rejected),
            ("lag-1", acf_rejected),
            ("lack of fit", lof_rejected),
        ] {
            let rate = k as f64 / trials as f64;
            assert!(
                (rate - 0.05).abs() < 3.0 * sd + 0.01,
                "{name}: rejected {rate} of null samples"
            );
        }
    }

    /// A smooth misfit (a sine along each slice, amplitude 1.5 noise sd) is caught by all three.
    #[test]
    fn a_systematic_misfit_is_detected() {
        let noise = normals(7, 200);
        let e: Vec<f64> = noise
            .iter()
            .enumerate()
            .map(|(i, n)| n + 1.5 * ((i % 40) as f64 / 40.0 * std::f64::consts::TAU).sin())
            .collect();
        let slices: Vec<&[f64]> = e.chunks(40).collect();
        let runs = runs_test(slices.iter().copied()).unwrap();
        assert!(runs.p_value < 1e-3 && runs.z < 0.0, "{runs:?}");
        let acf = lag1_autocorrelation(slices.iter().copied()).unwrap();
        assert!(acf.p_value < 1e-3 && acf.r1 > 0.3, "{acf:?}");
        // Replicates share the misfit of their direction: the means misfit, the scatter does not.
        let misfit: Vec<f64> = (0..50).map(|g| 1.5 * (g as f64 * 0.7).sin()).collect();
        let groups: Vec<usize> = (0..200).map(|i| i / 4).collect();
        let r: Vec<f64> = (0..200).map(|i| noise[i] + misfit[groups[i]]).collect();
        let lof = lack_of_fit(&r, &groups, 3).unwrap();
        assert!(lof.p_value < 1e-6 && lof.f > 3.0, "{lof:?}");
        assert!((lof.pure_error_sd - 1.0).abs() < 0.15, "{lof:?}");
    }

    #[test]
    fn undefined_cases_say_none() {
        assert!(runs_test([[1.0, 2.0, 3.0].as_slice()]).is_none());
        assert!(lag1_autocorrelation([[1.0, 2.0].as_slice()]).is_none());
        // No replicates: no pure error.
        assert!(lack_of_fit(&[0.1, -0.2, 0.3, 0.4], &[0, 1, 2, 3], 1).is_none());
        // As many directions as parameters: no lack-of-fit degrees of freedom.
        assert!(lack_of_fit(&[0.1, -0.2, 0.3, 0.4], &[0, 0, 1, 1], 2).is_none());
    }
}

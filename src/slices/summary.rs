//! Which rows `--curves summary` keeps: the report's view of the data in a few thousand samples.
//! Deterministic (no randomness, only the table's order), so the same fit writes the same file.

use super::decimate::stride_indices;
use super::{find_slices_by, samples_of};
use crate::files::Curves;

/// Most slice panels a report draws; more slices are sampled evenly.
pub const MAX_PANELS: usize = 12;
/// Most measured points a report draws per channel in one slice panel.
pub const MAX_SLICE_POINTS: usize = 600;

/// Samples of the even spread over the whole table (beyond the slices and outliers).
pub const SUMMARY_SAMPLES: usize = 2000;

/// Row indices (in order) of every sample that is in a slice the report draws (decimated as
/// its panel is), in an even spread of [`SUMMARY_SAMPLES`] samples, or has any value the robust
/// loss down-weighted. A kept sample keeps all its rows, so every outlier row is kept.
pub fn summary_rows(curves: &Curves) -> Vec<usize> {
    let samples = samples_of(curves);
    let keep = kept_samples(
        samples.len(),
        |k| samples[k].angles,
        |k| samples[k].rows.iter().any(|&r| curves.down_weighted(r)),
    );
    let mut rows: Vec<usize> = samples
        .iter()
        .zip(&keep)
        .filter(|&(_, &kept)| kept)
        .flat_map(|(s, _)| s.rows.iter().copied())
        .collect();
    rows.sort_unstable();
    rows
}

/// The samples (in order) whose rows [`summary_rows`] keeps, for a fit's own table before it
/// is built (sample `i` holds rows `i·nc .. (i+1)·nc`): from the `n` samples' angles in degrees
/// and whether any of sample `i`'s values was down-weighted. A fit writing the summary builds only
/// these rows instead of the whole table.
pub fn summary_samples(
    n: usize,
    angles_deg: impl Fn(usize) -> [f64; 4],
    down_weighted: impl Fn(usize) -> bool,
) -> Vec<usize> {
    let keep = kept_samples(n, angles_deg, down_weighted);
    (0..n).filter(|&k| keep[k]).collect()
}

/// Which of `n` samples the summary keeps: slice members as drawn, the even spread, the
/// down-weighted.
fn kept_samples(
    n: usize,
    angles_deg: impl Fn(usize) -> [f64; 4],
    down_weighted: impl Fn(usize) -> bool,
) -> Vec<bool> {
    let (slices, _) = find_slices_by(n, angles_deg);
    let mut keep = vec![false; n];
    for i in stride_indices(slices.len(), MAX_PANELS) {
        let members = &slices[i].samples;
        for k in stride_indices(members.len(), MAX_SLICE_POINTS) {
            keep[members[k]] = true;
        }
    }
    for k in stride_indices(n, SUMMARY_SAMPLES) {
        keep[k] = true;
    }
    for (k, kept) in keep.iter_mut().enumerate() {
        if !*kept && down_weighted(k) {
            *kept = true;
        }
    }
    keep
}

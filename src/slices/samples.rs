//! Samples of a curves table: `curves.csv` rows regrouped by sample, for a report to find their
//! slices and draw them.

use super::{find_slices_by, Slice};
use crate::files::{CurveRow, Curves};

/// One sample (one direction pair) and its rows in `curves.csv`, one per channel.
#[derive(Debug, Clone)]
pub struct Sample {
    pub id: u64,
    /// θ_i, φ_i, θ_r, φ_r in degrees.
    pub angles: [f64; 4],
    /// Indices into the row list, one per channel present.
    pub rows: Vec<usize>,
}

/// Regroup rows by sample id, in order of first appearance.
pub fn collect_samples(rows: &[CurveRow]) -> Vec<Sample> {
    let mut index: std::collections::HashMap<u64, usize> = std::collections::HashMap::new();
    let mut samples: Vec<Sample> = Vec::new();
    for (i, row) in rows.iter().enumerate() {
        let k = *index.entry(row.sample).or_insert_with(|| {
            samples.push(Sample {
                id: row.sample,
                angles: row.angles_deg(),
                rows: Vec::new(),
            });
            samples.len() - 1
        });
        samples[k].rows.push(i);
    }
    samples
}

/// The samples of a curves table, regrouped by sample id in order of first appearance (as
/// [`collect_samples`]; a fit's table has each sample's rows together, so this is one pass).
pub fn samples_of(curves: &Curves) -> Vec<Sample> {
    let mut samples: Vec<Sample> = Vec::with_capacity(curves.n_samples());
    // A fit's table numbers its samples in increasing order: each is new, no lookup needed.
    let increasing = curves.sample_id.windows(2).all(|w| w[0] < w[1]);
    if increasing {
        samples.extend(
            curves
                .sample_id
                .iter()
                .zip(&curves.sample_angles)
                .map(|(&id, &angles)| Sample {
                    id,
                    angles,
                    rows: Vec::new(),
                }),
        );
        for r in 0..curves.len() {
            samples[curves.sample_of(r)].rows.push(r);
        }
        return samples;
    }
    // Only here: allocated up front for a fit's table it cost a page fault per 4 kB unused.
    let mut index: std::collections::HashMap<u64, usize> =
        std::collections::HashMap::with_capacity(curves.n_samples());
    let mut last: Option<(usize, usize)> = None;
    for r in 0..curves.len() {
        let s = curves.sample_of(r);
        let k = match last {
            Some((table, k)) if table == s => k,
            _ => {
                let id = curves.sample_id[s];
                *index.entry(id).or_insert_with(|| {
                    samples.push(Sample {
                        id,
                        angles: curves.sample_angles[s],
                        rows: Vec::new(),
                    });
                    samples.len() - 1
                })
            }
        };
        last = Some((s, k));
        samples[k].rows.push(r);
    }
    samples
}

/// Group samples into slices; returns the slices (sorted by kind and fixed angles) and the
/// indices of samples in no slice.
pub fn find_slices(samples: &[Sample]) -> (Vec<Slice>, Vec<usize>) {
    find_slices_by(samples.len(), |i| samples[i].angles)
}

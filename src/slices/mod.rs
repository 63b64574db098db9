//! Measurement slices: samples grouped into azimuthal scans (fixed θ_i, φ_i, θ_r; φ_r swept)
//! or longitudinal scans (fixed θ_i, φ_i, φ_r; θ_r swept), detected from their angles, with the
//! rest left as scattered; a curves table's rows regrouped by sample ([`samples`]); and which of them a report draws ([`summary`], [`decimate`]). Below
//! both the fit (which reads the scan design from them) and the report (which draws them).

pub mod decimate;
pub mod samples;
pub mod summary;

use std::collections::BTreeMap;

use rayon::slice::ParallelSliceMut;

pub use samples::{collect_samples, find_slices, samples_of, Sample};
pub use summary::{summary_samples, MAX_PANELS, MAX_SLICE_POINTS, SUMMARY_SAMPLES};

/// Fewest distinct swept values that make a slice worth drawing as a curve.
pub const MIN_SLICE_POINTS: usize = 3;

/// Which angle a slice sweeps.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum SliceKind {
    /// φ_r swept at fixed θ_r (degrees); plotted against φ = wrap(φ_r − φ_i).
    Azimuthal { theta_r: f64 },
    /// θ_r swept at fixed φ_r (degrees); plotted against θ_r.
    Longitudinal { phi_r: f64 },
}

/// A set of samples sharing the incidence and one outgoing angle.
#[derive(Debug, Clone, PartialEq)]
pub struct Slice {
    pub kind: SliceKind,
    pub theta_i: f64,
    pub phi_i: f64,
    /// Sample indices, sorted by the swept coordinate.
    pub samples: Vec<usize>,
}

impl Slice {
    /// The plotted coordinate of a sample in degrees: φ for azimuthal slices, θ_r otherwise.
    pub fn x_of(&self, angles: &[f64; 4]) -> f64 {
        match self.kind {
            SliceKind::Azimuthal { .. } => wrap_deg(angles[3] - angles[1]),
            SliceKind::Longitudinal { .. } => angles[2],
        }
    }

    /// Angles (degrees) of the point at plotted coordinate `x` of this slice.
    pub fn angles_at(&self, x: f64) -> [f64; 4] {
        match self.kind {
            SliceKind::Azimuthal { theta_r } => [self.theta_i, self.phi_i, theta_r, self.phi_i + x],
            SliceKind::Longitudinal { phi_r } => [self.theta_i, self.phi_i, x, phi_r],
        }
    }

    /// A title naming the slice: its kind and fixed angles.
    pub fn title(&self) -> String {
        match self.kind {
            SliceKind::Azimuthal { theta_r } => format!(
                "azimuthal: θi={}°, φi={}°, θr={}°",
                short(self.theta_i),
                short(self.phi_i),
                short(theta_r)
            ),
            SliceKind::Longitudinal { phi_r } => format!(
                "longitudinal: θi={}°, φi={}°, φr={}°",
                short(self.theta_i),
                short(self.phi_i),
                short(phi_r)
            ),
        }
    }

    /// The x-axis label with units.
    pub fn x_label(&self) -> &'static str {
        match self.kind {
            SliceKind::Azimuthal { .. } => "φ = φr − φi (deg)",
            SliceKind::Longitudinal { .. } => "θr (deg)",
        }
    }
}

/// An angle in degrees with at most two decimals and no trailing zeros.
pub fn short(v: f64) -> String {
    let s = format!("{v:.2}");
    let s = s.trim_end_matches('0').trim_end_matches('.');
    if s == "-0" {
        "0".into()
    } else {
        s.into()
    }
}

/// MODEL.md's `wrap`, in degrees: to (−180, 180] (the model's one implementation).
pub use crate::geometry::angles::wrap_deg;

/// θ_h = (θ_i + θ_r)/2 in degrees.
pub fn theta_h_deg(angles: &[f64; 4]) -> f64 {
    0.5 * (angles[0] + angles[2])
}

/// A grouping key for an angle in degrees: equal to 1e-6° count as the same setting.
fn key(v: f64) -> i64 {
    (v * 1e6).round() as i64
}

/// The slices of a set of samples (sorted by kind and fixed angles) and the indices of the
/// samples in no slice, as [`find_slices_by`] finds them.
pub type FoundSlices = (Vec<Slice>, Vec<usize>);

/// Group `n` samples whose angles (degrees) `angles(i)` gives into slices.
pub fn find_slices_by(n: usize, angles: impl Fn(usize) -> [f64; 4]) -> FoundSlices {
    // Incidence groups by one sort (in key order, members in sample order, as a map would
    // give them) rather than a map of a Vec per group: scattered data has a group per sample.
    let finite = |i: usize| angles(i).iter().all(|a| a.is_finite());
    let mut keyed: Vec<(i64, i64, usize)> = (0..n)
        .filter(|&i| finite(i))
        .map(|i| {
            let a = angles(i);
            (key(a[0]), key(a[1]), i)
        })
        .collect();
    // In parallel: scattered data (100k samples, a group each) spent most of its report here.
    // The keys end with the sample's index, so they are distinct and any sort orders them alike.
    keyed.par_sort_unstable();
    let mut slices = Vec::new();
    // Incidence groups are disjoint, so one mark array serves them all (allocating it per
    // group made scattered directions, one group per sample, quadratic).
    let mut in_slice = vec![false; n];
    let mut members: Vec<usize> = Vec::new();
    for group in keyed.chunk_by(|a, b| (a.0, a.1) == (b.0, b.1)) {
        // Too few samples for any slice: all scattered, no sub-grouping needed.
        if group.len() < MIN_SLICE_POINTS {
            continue;
        }
        members.clear();
        members.extend(group.iter().map(|g| g.2));
        let members = &members;
        let first = angles(members[0]);
        // Azimuthal candidates share θ_r and sweep φ_r; longitudinal ones share φ_r and sweep θ_r.
        let azimuthal = sub_slices(&angles, members, 2, 3);
        let longitudinal = sub_slices(&angles, members, 3, 2);
        let covered = |c: &Vec<(f64, Vec<usize>)>| c.iter().map(|(_, m)| m.len()).sum::<usize>();
        let (chosen, is_azimuthal) = if covered(&azimuthal) >= covered(&longitudinal) {
            (azimuthal, true)
        } else {
            (longitudinal, false)
        };
        for (fixed, mut m) in chosen {
            let kind = if is_azimuthal {
                SliceKind::Azimuthal { theta_r: fixed }
            } else {
                SliceKind::Longitudinal { phi_r: fixed }
            };
            let slice = Slice {
                kind,
                theta_i: first[0],
                phi_i: first[1],
                samples: Vec::new(),
            };
            m.sort_by(|&a, &b| slice.x_of(&angles(a)).total_cmp(&slice.x_of(&angles(b))));
            m.iter().for_each(|&i| in_slice[i] = true);
            slices.push(Slice {
                samples: m,
                ..slice
            });
        }
    }
    slices.sort_by(|a, b| {
        let rank = |s: &Slice| match s.kind {
            SliceKind::Azimuthal { theta_r } => (0, theta_r),
            SliceKind::Longitudinal { phi_r } => (1, phi_r),
        };
        let (ka, fa) = rank(a);
        let (kb, fb) = rank(b);
        ka.cmp(&kb)
            .then(a.theta_i.total_cmp(&b.theta_i))
            .then(a.phi_i.total_cmp(&b.phi_i))
            .then(fa.total_cmp(&fb))
    });
    // Every sample not in a slice (non-finite angles, small groups, the rest of large ones),
    // in index order: one pass over the marks instead of collecting and sorting them (the
    // scattered 100k-sample fit sorted 100k indices here, in its verdict and in its report).
    let scattered: Vec<usize> = (0..n).filter(|&i| !in_slice[i]).collect();
    (slices, scattered)
}

/// Sub-groups of `members` sharing angle `fixed` whose angle `swept` takes at least
/// [`MIN_SLICE_POINTS`] distinct values: (fixed value, members).
fn sub_slices(
    angles: &impl Fn(usize) -> [f64; 4],
    members: &[usize],
    fixed: usize,
    swept: usize,
) -> Vec<(f64, Vec<usize>)> {
    let mut groups: BTreeMap<i64, Vec<usize>> = BTreeMap::new();
    for &i in members {
        groups.entry(key(angles(i)[fixed])).or_default().push(i);
    }
    groups
        .into_values()
        .filter(|m| {
            let mut values: Vec<i64> = m.iter().map(|&i| key(angles(i)[swept])).collect();
            values.sort_unstable();
            values.dedup();
            values.len() >= MIN_SLICE_POINTS
        })
        .map(|m| (angles(m[0])[fixed], m))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn azimuthal_and_longitudinal_scans_are_told_apart() {
        let mut s: Vec<[f64; 4]> = Vec::new();
        // An azimuthal scan at θ_i = −20, θ_r = 25 over φ_r.
        for k in 0..10 {
            s.push([-20.0, 0.0, 25.0, -90.0 + 20.0 * k as f64]);
        }
        // A longitudinal scan at θ_i = 10, φ_r = 180 over θ_r.
        for k in 0..7 {
            s.push([10.0, 0.0, -60.0 + 20.0 * k as f64, 180.0]);
        }
        // Two isolated samples.
        s.push([33.0, 5.0, 1.0, 2.0]);
        s.push([33.0, 5.0, 7.0, 9.0]);
        let (slices, scattered) = find_slices_by(s.len(), |i| s[i]);
        assert_eq!(slices.len(), 2);
        assert_eq!(slices[0].kind, SliceKind::Azimuthal { theta_r: 25.0 });
        assert_eq!(slices[0].samples.len(), 10);
        assert_eq!(slices[1].kind, SliceKind::Longitudinal { phi_r: 180.0 });
        assert_eq!(slices[1].samples.len(), 7);
        assert_eq!(scattered, vec![17, 18]);
        // Sorted along the swept coordinate.
        let xs: Vec<f64> = slices[1]
            .samples
            .iter()
            .map(|&i| slices[1].x_of(&s[i]))
            .collect();
        assert!(xs.windows(2).all(|w| w[0] <= w[1]));
    }

    #[test]
    fn wrap_maps_into_the_half_open_interval() {
        assert_eq!(wrap_deg(190.0), -170.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(-530.0), -170.0);
    }
}

//! Row validation shared by every format: each parsed row is accepted into the [`Dataset`] or
//! rejected with a [`RejectReason`]; duplicates and kept negatives are settled in [`Rows::finish`].

use rayon::slice::ParallelSliceMut;

use super::dataset::Dataset;
use super::options::AngleUnit;
use super::report::{LoadReport, RejectReason, FIRST_LINES};

/// Accumulates validated rows of one file.
pub(crate) struct Rows {
    ds: Dataset,
    report: LoadReport,
    unit: AngleUnit,
    /// The file or `--angles` said the unit (else degrees were assumed, and checked).
    unit_stated: bool,
    negative_tolerance: Option<f64>,
}

/// A parsed cell: `None` is a missing value.
pub(crate) type Cell = Option<f64>;

/// The cells of the row being parsed, filled column by column (CSV and scan readers alike).
pub(crate) struct RowCells<'a> {
    pub angles: &'a mut [Cell; 4],
    pub radiance: &'a mut [Cell],
    pub sigma: &'a mut [Cell],
    pub weight: &'a mut [Cell],
}

impl RowCells<'_> {
    /// Put `cell` where its column's role says (an unsuffixed sigma/weight goes to every channel).
    pub fn place(&mut self, role: super::options::Role, cell: Cell) {
        use super::options::Role;
        match role {
            Role::Angle(a) => self.angles[a] = cell,
            Role::Radiance(c) => self.radiance[c] = cell,
            Role::Sigma(Some(c)) => self.sigma[c] = cell,
            Role::Sigma(None) => self.sigma.fill(cell),
            Role::Weight(Some(c)) => self.weight[c] = cell,
            Role::Weight(None) => self.weight.fill(cell),
            Role::Ignored => {}
        }
    }
}

/// One row's cells as [`Rows::row`] takes them, for its check and its store.
#[derive(Clone, Copy)]
struct RowValues<'a> {
    angles: [Cell; 4],
    radiance: &'a [Cell],
    sigma: &'a [Cell],
    weight: &'a [Cell],
}

impl Rows {
    /// Rows for `channels`, with per-channel sigma/weight when the file has them.
    pub fn new(
        channels: Vec<String>,
        sigma: bool,
        weight: bool,
        unit: AngleUnit,
        negative_tolerance: Option<f64>,
    ) -> Self {
        Rows {
            ds: Dataset::with_channels(channels, sigma, weight),
            report: LoadReport::default(),
            unit,
            unit_stated: false,
            negative_tolerance,
        }
    }

    /// Whether the unit was stated (a unit line, `--angles`, a format that fixes it); when it
    /// was not, [`Rows::finish`] warns about degrees that look like radians.
    pub fn unit_stated(mut self, stated: bool) -> Self {
        self.unit_stated = stated;
        self
    }

    /// Add a note to the report.
    pub fn note(&mut self, note: String) {
        self.report.notes.push(note);
    }

    /// Metadata carried into the dataset.
    pub fn meta_mut(&mut self) -> &mut serde_json::Map<String, serde_json::Value> {
        &mut self.ds.meta
    }

    /// Reserve room for about `rows` more accepted samples (avoids repeated doubling, whose
    /// copies and fresh page faults dominate large loads).
    pub fn reserve(&mut self, rows: usize) {
        let nc = self.ds.n_channels();
        for_each_column(&mut self.ds, |v, per_row| {
            v.reserve(if per_row { rows } else { rows * nc })
        });
        self.ds.source_line.reserve(rows);
    }

    /// Number of rows seen so far.
    pub fn rows_read(&self) -> u64 {
        self.report.rows_read
    }

    /// Validate one row (angles in the file's unit; `sigma`/`weight` empty when the file has
    /// none, else one per channel) and accept or reject it.
    pub fn row(
        &mut self,
        line: u64,
        angles: [Cell; 4],
        radiance: &[Cell],
        sigma: &[Cell],
        weight: &[Cell],
    ) {
        self.report.rows_read += 1;
        let cells = RowValues {
            angles,
            radiance,
            sigma,
            weight,
        };
        match self.check(&cells) {
            Some(reason) => self.report.reject(reason, line),
            None => self.accept(line, &cells),
        }
    }

    /// The first reason to reject a row, in a fixed order (missing, non-finite, θ, negative,
    /// sigma, weight), or `None` to accept it.
    fn check(&self, cells: &RowValues<'_>) -> Option<RejectReason> {
        let angles = cells.angles;
        let all = || {
            (angles.iter())
                .chain(cells.radiance)
                .chain(cells.sigma)
                .chain(cells.weight)
        };
        if all().any(Option::is_none) {
            return Some(RejectReason::MissingValue);
        }
        if all().any(|c| !c.unwrap_or(0.0).is_finite()) {
            return Some(RejectReason::NonFinite);
        }
        let theta_limit = self.unit.theta_limit();
        if [angles[0], angles[2]]
            .iter()
            .any(|t| t.unwrap_or(0.0).abs() >= theta_limit)
        {
            return Some(RejectReason::ThetaOutOfRange);
        }
        let phi_limit = self.unit.phi_limit();
        if [angles[1], angles[3]]
            .iter()
            .any(|p| p.unwrap_or(0.0).abs() > phi_limit)
        {
            return Some(RejectReason::PhiOutOfRange);
        }
        if let Some(tol) = self.negative_tolerance {
            if cells.radiance.iter().any(|r| r.unwrap_or(0.0) < -tol) {
                return Some(RejectReason::NegativeRadiance);
            }
        }
        if cells.sigma.iter().any(|s| s.unwrap_or(1.0) <= 0.0) {
            return Some(RejectReason::NonPositiveSigma);
        }
        if cells.weight.iter().any(|w| w.unwrap_or(1.0) <= 0.0) {
            return Some(RejectReason::NonPositiveWeight);
        }
        None
    }

    /// Store a row that passed [`Rows::check`] (all cells present and finite).
    fn accept(&mut self, line: u64, cells: &RowValues<'_>) {
        let RowValues {
            angles,
            radiance,
            sigma,
            weight,
        } = *cells;
        let rad = |c: Cell| {
            let v = c.unwrap_or(0.0);
            match self.unit {
                AngleUnit::Deg => v.to_radians(),
                AngleUnit::Rad => v,
            }
        };
        let [ti, pi, tr, pr] = angles.map(rad);
        let ds = &mut self.ds;
        ds.theta_i.push(ti);
        ds.phi_i.push(pi);
        ds.theta_r.push(tr);
        ds.phi_r.push(pr);
        ds.radiance
            .extend(radiance.iter().map(|c| c.unwrap_or(0.0)));
        if let Some(s) = ds.sigma.as_mut() {
            s.extend(sigma.iter().map(|c| c.unwrap_or(0.0)));
        }
        if let Some(w) = ds.weight.as_mut() {
            w.extend(weight.iter().map(|c| c.unwrap_or(0.0)));
        }
        ds.source_line.push(line);
    }

    /// Reject duplicates, count kept negatives, and close the accounting.
    pub fn finish(mut self) -> (Dataset, LoadReport) {
        remove_duplicates(&mut self.ds, &mut self.report);
        count_negative_kept(&self.ds, &mut self.report);
        if !self.unit_stated && self.unit == AngleUnit::Deg {
            self.report
                .warnings
                .extend(super::unit::radians_warning(&self.ds));
        }
        if self.report.replicates.count > 0 {
            self.report.notes.push(format!(
                "{} rows measure again the direction of an earlier row with other values (kept \
                 as replicates; identical lines are rejected as duplicates)",
                self.report.replicates.count
            ));
        }
        self.report.accepted = self.ds.len() as u64;
        shrink_if_loose(&mut self.ds);
        if self.report.negative_kept.count > 0 {
            self.report.notes.push(format!(
                "{} accepted rows have a negative radiance (kept: dark-frame subtraction makes \
                 them real; --negative-tolerance TOL rejects those below -TOL)",
                self.report.negative_kept.count
            ));
        }
        (self.ds, self.report)
    }
}

/// Directions closer than this (radians) are the same direction: an angle written as 370° and
/// as 10° differ in the last bits after conversion and wrapping.
const SAME_DIRECTION_RAD: f64 = 1e-9;

/// An angle as an integer number of [`SAME_DIRECTION_RAD`], azimuths wrapped to [0, 2π) first
/// (so −180°, 180° and 540° are one direction); -0 and +0 are equal.
fn angle_key(x: f64, wrap: bool) -> u64 {
    use std::f64::consts::TAU;
    let x = if wrap { x.rem_euclid(TAU) } else { x };
    let steps = (x / SAME_DIRECTION_RAD).round();
    let turn = (TAU / SAME_DIRECTION_RAD).round();
    let steps = if wrap && steps >= turn { 0.0 } else { steps };
    (steps as i64) as u64
}

/// A 64-bit mix of a sample's four angle keys (FxHash-style multiply-rotate).
fn angles_hash(keys: [u64; 4]) -> u64 {
    keys.iter().fold(0u64, |h, &k| {
        (h.rotate_left(5) ^ k).wrapping_mul(0x517c_c1b7_2722_0a95)
    })
}

/// Whether samples `i` and `j` hold the same values (radiance, sigma, weight), bit for bit.
fn same_values(ds: &Dataset, i: usize, j: usize) -> bool {
    let nc = ds.n_channels();
    let same = |v: &Vec<f64>| {
        let (a, b) = (&v[i * nc..(i + 1) * nc], &v[j * nc..(j + 1) * nc]);
        a.iter()
            .zip(b)
            .all(|(x, y)| (x + 0.0).to_bits() == (y + 0.0).to_bits())
    };
    same(&ds.radiance) && ds.sigma.as_ref().is_none_or(same) && ds.weight.as_ref().is_none_or(same)
}

/// Duplicate rejection: a sample with the same direction (φ compared after wrapping) and the
/// same values as an earlier accepted sample is removed; the same direction with other values
/// is a replicate, kept and counted. Candidates are found by sorting one u64 per sample (hash
/// in the high bits, index in the low bits: 8 bytes per sample, far less than a hash map), then
/// confirmed on the angles.
fn remove_duplicates(ds: &mut Dataset, report: &mut LoadReport) {
    let n = ds.len();
    let key = |i: usize| {
        [
            angle_key(ds.theta_i[i], false),
            angle_key(ds.phi_i[i], true),
            angle_key(ds.theta_r[i], false),
            angle_key(ds.phi_r[i], true),
        ]
    };
    let index_bits = usize::BITS - n.leading_zeros();
    let index_mask = (1u64 << index_bits) - 1;
    let mut order: Vec<u64> = (0..n)
        .map(|i| (angles_hash(key(i)) & !index_mask) | i as u64)
        .collect();
    order.par_sort_unstable();
    let index = |v: u64| (v & index_mask) as usize;
    // (duplicate index, first index with the same line)
    let mut dups: Vec<(usize, usize)> = Vec::new();
    let mut replicates: Vec<usize> = Vec::new();
    let mut start = 0;
    while start < n {
        let hash = order[start] & !index_mask;
        let mut end = start + 1;
        while end < n && order[end] & !index_mask == hash {
            end += 1;
        }
        // Within an equal-hash group (indices ascending), match each member to the earliest
        // member with the same direction; groups are small unless the file is adversarial or
        // holds many replicates of one direction.
        for j in start + 1..end {
            let (ij, kj) = (index(order[j]), key(index(order[j])));
            let mut same_direction = order[start..j]
                .iter()
                .map(|&v| index(v))
                .filter(|&i| key(i) == kj);
            let Some(first) = same_direction.next() else {
                continue;
            };
            match std::iter::once(first)
                .chain(same_direction)
                .find(|&i| same_values(ds, i, ij))
            {
                Some(same) => dups.push((ij, same)),
                None => replicates.push(ij),
            }
        }
        start = end;
    }
    replicates.sort_unstable();
    for &r in &replicates {
        report.replicates.add(ds.source_line[r]);
    }
    if dups.is_empty() {
        return;
    }
    dups.sort_unstable();
    let mut keep = vec![true; n];
    for &(d, first) in &dups {
        keep[d] = false;
        report.reject(RejectReason::Duplicate, ds.source_line[d]);
        if report.duplicate_of.len() < FIRST_LINES {
            report
                .duplicate_of
                .push([ds.source_line[d], ds.source_line[first]]);
        }
    }
    retain_samples(ds, &keep);
}

/// Keep only the samples with `keep[i]`, in order, across every array.
fn retain_samples(ds: &mut Dataset, keep: &[bool]) {
    let nc = ds.n_channels();
    let retain = |v: &mut Vec<f64>| {
        let mut i = 0;
        v.retain(|_| {
            i += 1;
            keep[i - 1]
        });
    };
    retain(&mut ds.theta_i);
    retain(&mut ds.phi_i);
    retain(&mut ds.theta_r);
    retain(&mut ds.phi_r);
    let retain_channels = |v: &mut Vec<f64>| {
        let mut i = 0;
        v.retain(|_| {
            i += 1;
            keep[(i - 1) / nc]
        });
    };
    retain_channels(&mut ds.radiance);
    if let Some(s) = ds.sigma.as_mut() {
        retain_channels(s);
    }
    if let Some(w) = ds.weight.as_mut() {
        retain_channels(w);
    }
    let mut i = 0;
    ds.source_line.retain(|_| {
        i += 1;
        keep[i - 1]
    });
}

/// Give back reserved room when the estimate was well above the accepted count, so memory stays
/// proportional to the accepted samples.
fn shrink_if_loose(ds: &mut Dataset) {
    let loose = |v: &Vec<f64>| v.capacity() > v.len() + v.len() / 8 + 1024;
    if loose(&ds.theta_i) {
        for_each_column(ds, |v, _| v.shrink_to_fit());
        ds.source_line.shrink_to_fit();
    }
}

/// Apply `f` to every numeric column of `ds`: the four angles (`true`: one value per row) and
/// radiance, sigma and weight (`false`: one value per row and channel).
fn for_each_column(ds: &mut Dataset, mut f: impl FnMut(&mut Vec<f64>, bool)) {
    for v in [
        &mut ds.theta_i,
        &mut ds.phi_i,
        &mut ds.theta_r,
        &mut ds.phi_r,
    ] {
        f(v, true);
    }
    for v in [
        Some(&mut ds.radiance),
        ds.sigma.as_mut(),
        ds.weight.as_mut(),
    ]
    .into_iter()
    .flatten()
    {
        f(v, false);
    }
}

/// Count accepted samples with a negative radiance in any channel.
fn count_negative_kept(ds: &Dataset, report: &mut LoadReport) {
    let nc = ds.n_channels().max(1);
    for (i, chunk) in ds.radiance.chunks(nc).enumerate() {
        if chunk.iter().any(|&r| r < 0.0) {
            report.negative_kept.add(ds.source_line[i]);
        }
    }
}

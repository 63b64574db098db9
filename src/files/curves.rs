//! `curves.csv`: the fit at every sample, one row per sample and channel. In memory the file is
//! a [`Curves`] table (columns, channels by index, each sample's angles once), written in
//! parallel-formatted chunks as it streams to disk and read with byte records; [`CurveRow`] is
//! one row as a value (and, through serde, the reference definition of every cell's text).
//! [`CurvesMode`] says how much of the table a fit writes (`--curves`).

use std::path::Path;

use rayon::prelude::*;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};

mod parse;
mod record;

use parse::{csv_error, csv_field, field_error, parse_record, ParsedRow};
pub use record::{CurveRow, CurveValues, CurvesMode, CURVES_HEADER, DOWN_WEIGHT};
/// `curves.csv` in memory: the samples (id, data line, angles in degrees) once each, and per
/// row its sample, its channel (an index into `channels`) and its numbers. About 72 bytes a
/// row plus 48 a sample, against ~180 for a [`CurveRow`] with its own channel `String`.
#[derive(Debug, Clone, Default)]
pub struct Curves {
    pub channels: Vec<String>,
    pub sample_id: Vec<u64>,
    pub sample_line: Vec<u64>,
    pub sample_angles: Vec<[f64; 4]>,
    pub row_sample: Vec<u32>,
    pub row_channel: Vec<u32>,
    pub values: Vec<CurveValues>,
}

/// Rows formatted per parallel task, and tasks per batch handed to the writer: a batch is about
/// 3 MB of text whatever the file's size, and its buffers serve the batch after next, so the
/// text is written from a few warm pages rather than a file's worth of fresh ones.
const ROWS_PER_CHUNK: usize = 4096;
const CHUNKS_PER_BATCH: usize = 4;

impl Curves {
    /// Number of rows.
    pub fn len(&self) -> usize {
        self.values.len()
    }

    pub fn is_empty(&self) -> bool {
        self.values.is_empty()
    }

    /// Number of samples (runs of rows with one sample id).
    pub fn n_samples(&self) -> usize {
        self.sample_id.len()
    }

    /// Add a sample; returns its index for [`Curves::push_row`].
    pub fn push_sample(&mut self, id: u64, line: u64, angles_deg: [f64; 4]) -> usize {
        self.sample_id.push(id);
        self.sample_line.push(line);
        self.sample_angles.push(angles_deg);
        self.sample_id.len() - 1
    }

    /// The last sample if it is this one (same id, line and angles, as a fit's rows of one
    /// sample are), else a new sample: a hand-made file's rows keep their own angles.
    fn sample_for(&mut self, id: u64, line: u64, angles_deg: [f64; 4]) -> usize {
        match self.sample_id.len().checked_sub(1) {
            Some(s)
                if self.sample_id[s] == id
                    && self.sample_line[s] == line
                    && self.sample_angles[s].map(f64::to_bits) == angles_deg.map(f64::to_bits) =>
            {
                s
            }
            _ => self.push_sample(id, line, angles_deg),
        }
    }

    /// Add a row of sample index `sample` in channel `channel` (an index into `channels`).
    pub fn push_row(&mut self, sample: usize, channel: usize, values: CurveValues) {
        self.row_sample.push(sample as u32);
        self.row_channel.push(channel as u32);
        self.values.push(values);
    }

    /// The index of channel `name`, added when new.
    pub fn channel_index(&mut self, name: &str) -> usize {
        match self.channels.iter().position(|c| c == name) {
            Some(k) => k,
            None => {
                self.channels.push(name.to_owned());
                self.channels.len() - 1
            }
        }
    }

    /// The sample index of row `r`.
    pub fn sample_of(&self, r: usize) -> usize {
        self.row_sample[r] as usize
    }

    /// `[θ_i, φ_i, θ_r, φ_r]` of row `r` in degrees.
    pub fn angles_deg(&self, r: usize) -> [f64; 4] {
        self.sample_angles[self.sample_of(r)]
    }

    pub fn channel_name(&self, r: usize) -> &str {
        &self.channels[self.row_channel[r] as usize]
    }

    pub fn sigma(&self, r: usize) -> Option<f64> {
        let s = self.values[r].sigma;
        (!s.is_nan()).then_some(s)
    }

    /// See [`CurveRow::down_weighted`].
    pub fn down_weighted(&self, r: usize) -> bool {
        self.values[r].weight < DOWN_WEIGHT
    }

    /// Row `r` as a value.
    pub fn row(&self, r: usize) -> CurveRow {
        let s = self.sample_of(r);
        let [theta_i, phi_i, theta_r, phi_r] = self.sample_angles[s];
        let v = &self.values[r];
        CurveRow {
            sample: self.sample_id[s],
            line: self.sample_line[s],
            channel: self.channel_name(r).to_owned(),
            theta_i,
            phi_i,
            theta_r,
            phi_r,
            data: v.data,
            sigma: self.sigma(r),
            fit: v.fit,
            fit_r: v.fit_r,
            fit_tt: v.fit_tt,
            fit_trt: v.fit_trt,
            residual: v.residual,
            weight: v.weight,
        }
    }

    /// Every row as a value, in order (allocates a channel name per row: small tables only).
    pub fn iter(&self) -> impl Iterator<Item = CurveRow> + '_ {
        (0..self.len()).map(|r| self.row(r))
    }

    pub fn to_rows(&self) -> Vec<CurveRow> {
        self.iter().collect()
    }

    /// The table of `rows`; consecutive rows with one sample id share the sample.
    pub fn from_rows(rows: &[CurveRow]) -> Curves {
        let mut c = Curves::default();
        for row in rows {
            let s = c.sample_for(row.sample, row.line, row.angles_deg());
            let ch = c.channel_index(&row.channel);
            c.push_row(
                s,
                ch,
                CurveValues {
                    data: row.data,
                    sigma: row.sigma.unwrap_or(f64::NAN),
                    fit: row.fit,
                    fit_r: row.fit_r,
                    fit_tt: row.fit_tt,
                    fit_trt: row.fit_trt,
                    residual: row.residual,
                    weight: row.weight,
                },
            );
        }
        c
    }

    /// The rows `rows` (indices in order) as a table of their own.
    pub fn select(&self, rows: &[usize]) -> Curves {
        let mut c = Curves {
            channels: self.channels.clone(),
            ..Curves::default()
        };
        let mut last: Option<(usize, usize)> = None;
        for &r in rows {
            let s = self.sample_of(r);
            let new_s = match last {
                Some((old, new)) if old == s => new,
                _ => c.push_sample(
                    self.sample_id[s],
                    self.sample_line[s],
                    self.sample_angles[s],
                ),
            };
            last = Some((s, new_s));
            c.push_row(new_s, self.row_channel[r] as usize, self.values[r]);
        }
        c
    }

    /// Put samples fitted in `order` (sample `j` of the table is sample `order[j]` of the data)
    /// back in the data's order, numbered as the data's.
    pub fn restore_sample_order(&mut self, order: &[usize]) {
        let n = self.n_samples();
        let mut first = vec![usize::MAX; n];
        let mut count = vec![0usize; n];
        for (r, &s) in self.row_sample.iter().enumerate() {
            let s = s as usize;
            first[s] = first[s].min(r);
            count[s] += 1;
        }
        let mut back = vec![usize::MAX; order.len()];
        for (j, &i) in order.iter().enumerate() {
            back[i] = j;
        }
        let mut out = Curves {
            channels: std::mem::take(&mut self.channels),
            ..Curves::default()
        };
        for (i, &j) in back.iter().enumerate() {
            if j >= n {
                continue;
            }
            let s = out.push_sample(i as u64, self.sample_line[j], self.sample_angles[j]);
            let start = first[j];
            for r in start..start + count[j] {
                out.push_row(s, self.row_channel[r] as usize, self.values[r]);
            }
        }
        *self = out;
    }

    /// Read `curves.csv` with byte records, checking the header; errors name line and column.
    pub fn read_csv(path: &Path) -> Result<Curves> {
        crate::json_file::check_regular_file(path)?;
        let mut reader = csv::Reader::from_path(path).map_err(|e| csv_error(path, e))?;
        let header = reader.headers().map_err(|e| csv_error(path, e))?.clone();
        for (col, expected) in CURVES_HEADER.iter().enumerate() {
            if header.get(col).map(str::trim) != Some(*expected) {
                return Err(Error::input(
                    path,
                    1,
                    col as u64 + 1,
                    format!(
                        "expected column `{expected}` here; curves.csv's header is `{}`",
                        CURVES_HEADER.join(",")
                    ),
                ));
            }
        }
        let mut c = Curves::default();
        // Records are read in batches (the csv parser is sequential) and their numbers parsed
        // in parallel; samples and channels are then assigned in file order.
        const READ_BATCH: usize = 1 << 15;
        let mut pool: Vec<csv::ByteRecord> = Vec::new();
        let mut parsed: Vec<Result<ParsedRow>> = Vec::new();
        let mut last_channel = usize::MAX;
        loop {
            let mut filled = 0;
            while filled < READ_BATCH {
                if pool.len() == filled {
                    pool.push(csv::ByteRecord::new());
                }
                if !reader
                    .read_byte_record(&mut pool[filled])
                    .map_err(|e| csv_error(path, e))?
                {
                    break;
                }
                filled += 1;
            }
            let records = &pool[..filled];
            records
                .par_iter()
                .map(|r| parse_record(path, r))
                .collect_into_vec(&mut parsed);
            for (record, row) in records.iter().zip(parsed.drain(..)) {
                let row = row?;
                let channel = std::str::from_utf8(record.get(2).unwrap_or_default())
                    .map_err(|_| field_error(path, record, 2, "UTF-8 text"))?;
                let ch = if c.channels.get(last_channel).map(String::as_str) == Some(channel) {
                    last_channel
                } else {
                    c.channel_index(channel)
                };
                last_channel = ch;
                let s = c.sample_for(row.id, row.line, row.angles);
                c.push_row(s, ch, row.values);
            }
            if filled < READ_BATCH {
                break;
            }
        }
        Ok(c)
    }

    /// Write `curves.csv` atomically: [`CURVES_HEADER`], then the rows `only` (indices in
    /// order) or every row. Rows are formatted in parallel chunks a batch at a time, and each
    /// batch is written to the file while the next one is formatted (the writes are a few ms
    /// of copying per 10 MB the cores would otherwise wait for); the text is exactly
    /// [`CurveRow`]'s serde form.
    pub fn write_csv(&self, path: &Path, only: Option<&[usize]>) -> Result<()> {
        let channels: Vec<Vec<u8>> = self.channels.iter().map(|c| csv_field(c)).collect();
        let n = only.map_or(self.len(), <[usize]>::len);
        let row_at = |k: usize| only.map_or(k, |o| o[k]);
        // Batch `start`'s text, formatted in parallel chunks into `chunks` (emptied first).
        let format = |start: usize, mut chunks: Vec<Vec<u8>>| -> Vec<Vec<u8>> {
            let end = (start + ROWS_PER_CHUNK * CHUNKS_PER_BATCH).min(n);
            let starts: Vec<usize> = (start..end).step_by(ROWS_PER_CHUNK).collect();
            chunks.resize_with(starts.len(), Vec::new);
            starts
                .par_iter()
                .zip(chunks.par_iter_mut())
                .for_each(|(&from, out)| {
                    let to = (from + ROWS_PER_CHUNK).min(end);
                    out.clear();
                    out.reserve((to - from) * 200);
                    let mut buf = super::decimal::DigitBuffer::new();
                    for k in from..to {
                        self.format_row(row_at(k), &channels, out, &mut buf);
                    }
                });
            chunks
        };
        write_atomically(path, |w| {
            let mut text = CURVES_HEADER.join(",").into_bytes();
            text.push(b'\n');
            w.write_all(&text).map_err(|e| Error::io(path, e))?;
            let mut write = |chunks: &[Vec<u8>]| -> Result<()> {
                for chunk in chunks {
                    w.write_all(chunk).map_err(|e| Error::io(path, e))?;
                }
                Ok(())
            };
            let batch = ROWS_PER_CHUNK * CHUNKS_PER_BATCH;
            let (mut ready, mut spare): (Vec<Vec<u8>>, Vec<Vec<u8>>) = (Vec::new(), Vec::new());
            for start in (0..n).step_by(batch.max(1)) {
                // The writer is not `Send`: it stays on this thread while the pool formats.
                let mut next = std::mem::take(&mut spare);
                let written = rayon::in_place_scope(|scope| {
                    scope.spawn(|_| next = format(start, std::mem::take(&mut next)));
                    write(&ready)
                });
                written?;
                spare = std::mem::replace(&mut ready, next);
            }
            write(&ready)?;
            w.flush().map_err(|e| Error::io(path, e))
        })
    }

    /// Append row `r` as one line of text (`channels`: the names as csv fields).
    fn format_row(
        &self,
        r: usize,
        channels: &[Vec<u8>],
        out: &mut Vec<u8>,
        buf: &mut super::decimal::DigitBuffer,
    ) {
        use super::decimal::{push_display, push_exponent, push_u64};
        let s = self.sample_of(r);
        push_u64(out, self.sample_id[s]);
        out.push(b',');
        push_u64(out, self.sample_line[s]);
        out.push(b',');
        out.extend_from_slice(&channels[self.row_channel[r] as usize]);
        for &a in &self.sample_angles[s] {
            out.push(b',');
            if a.is_finite() {
                push_display(out, a, buf);
            }
        }
        let v = &self.values[r];
        for x in [
            v.data, v.sigma, v.fit, v.fit_r, v.fit_tt, v.fit_trt, v.residual, v.weight,
        ] {
            out.push(b',');
            if x.is_finite() {
                push_exponent(out, x, buf);
            }
        }
        out.push(b'\n');
    }
}

impl<'a> IntoIterator for &'a Curves {
    type Item = CurveRow;
    type IntoIter = Box<dyn Iterator<Item = CurveRow> + 'a>;
    fn into_iter(self) -> Self::IntoIter {
        Box::new(self.iter())
    }
}

/// Read every row of `curves.csv`, checking the header; errors name line and column.
pub fn read_curves_csv(path: &Path) -> Result<Vec<CurveRow>> {
    Ok(Curves::read_csv(path)?.to_rows())
}

/// Write `rows` as `curves.csv` atomically (see [`Curves::write_csv`]).
pub fn write_curves_csv(path: &Path, rows: &[CurveRow]) -> Result<()> {
    Curves::from_rows(rows).write_csv(path, None)
}
#[cfg(test)]
mod tests {
    use super::*;

    /// The header written is the header serde derives from the type: one definition.
    #[test]
    fn header_matches_the_type() {
        let row = CurveRow {
            sample: 0,
            line: 2,
            channel: "r,g".into(),
            theta_i: 0.0,
            phi_i: -170.0,
            theta_r: 1.5,
            phi_r: 2.0,
            data: 1.0,
            sigma: None,
            fit: f64::NAN,
            fit_r: 0.5,
            fit_tt: 0.25,
            fit_trt: 0.25,
            residual: -0.1,
            weight: 1.0,
        };
        let mut w = csv::Writer::from_writer(Vec::new());
        w.serialize(&row).unwrap();
        let text = String::from_utf8(w.into_inner().unwrap()).unwrap();
        let mut lines = text.lines();
        assert_eq!(lines.next().unwrap(), CURVES_HEADER.join(","));
        // Number formats are the file's; a channel name with a comma is quoted.
        assert_eq!(
            lines.next().unwrap(),
            "0,2,\"r,g\",0,-170,1.5,2,1e0,,,5e-1,2.5e-1,2.5e-1,-1e-1,1e0"
        );
    }

    fn edge_rows() -> Vec<CurveRow> {
        let mut rows = Vec::new();
        let values = [
            1.0,
            -0.0,
            2.43e-7,
            f64::NAN,
            f64::INFINITY,
            123456.789,
            -29.999999999999996,
            1e300,
            5e-324,
        ];
        for (i, &v) in values.iter().enumerate() {
            for (c, name) in ["r", "g,\"b\"", ""].iter().enumerate() {
                let w = values[(i + c) % values.len()];
                // Angles are the sample's (finite: the data's); values vary per channel.
                let finite_or_zero = |x: f64| if x.is_finite() { x } else { 0.0 };
                rows.push(CurveRow {
                    sample: i as u64,
                    line: 10 * i as u64 + 2,
                    channel: (*name).into(),
                    theta_i: finite_or_zero(v),
                    phi_i: -170.0,
                    theta_r: 1e-7 * i as f64,
                    phi_r: finite_or_zero(values[(i + 1) % values.len()]),
                    data: w,
                    sigma: (c == 1).then_some(v),
                    fit: v * 3.0,
                    fit_r: w,
                    fit_tt: 0.25,
                    fit_trt: -v,
                    residual: w / 7.0,
                    weight: if c == 2 { 0.2 } else { 1.0 },
                });
            }
        }
        rows
    }

    /// The streamed writer's bytes are exactly the csv crate's serde form of the rows (the
    /// writer before streaming), including quoted channel names and empty non-finite cells.
    #[test]
    fn streamed_writer_is_byte_identical_to_the_serde_form() {
        let rows = edge_rows();
        let mut w = csv::Writer::from_writer(Vec::new());
        for r in &rows {
            w.serialize(r).unwrap();
        }
        let expected = w.into_inner().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("curves.csv");
        write_curves_csv(&path, &rows).unwrap();
        assert_eq!(
            String::from_utf8(std::fs::read(&path).unwrap()).unwrap(),
            String::from_utf8(expected).unwrap()
        );
        // Read back: every finite number exactly, non-finite ones as NaN (empty cells).
        let back = Curves::read_csv(&path).unwrap();
        assert_eq!(back.len(), rows.len());
        for (a, b) in back.iter().zip(&rows) {
            assert_eq!(
                (a.sample, a.line, &a.channel),
                (b.sample, b.line, &b.channel)
            );
            let same = |x: f64, y: f64| x == y || (x.is_nan() && !y.is_finite());
            assert!(same(a.data, b.data) && same(a.fit, b.fit) && same(a.fit_trt, b.fit_trt));
            assert!(same(a.weight, b.weight) && same(a.residual, b.residual));
        }
        // A selection writes those rows only, whole.
        write_curves_csv(&path, &rows).unwrap();
        let all = Curves::read_csv(&path).unwrap();
        all.write_csv(&path, Some(&[1, 5, 6])).unwrap();
        let some = Curves::read_csv(&path).unwrap();
        assert_eq!(some.len(), 3);
        assert_eq!(some.row(1).sample, rows[5].sample);
        assert_eq!(some.row(2).channel, rows[6].channel);
    }

    #[test]
    fn restoring_the_sample_order_moves_whole_samples() {
        let rows = edge_rows();
        let mut c = Curves::from_rows(&rows);
        let n = c.n_samples();
        let order: Vec<usize> = (0..n).rev().collect();
        c.restore_sample_order(&order);
        assert_eq!(c.len(), rows.len());
        assert_eq!(c.row(0).line, rows[rows.len() - 1].line);
        assert_eq!(c.row(0).sample, 0);
        assert_eq!(c.row(0).channel, "r");
        assert_eq!(c.row(2).channel, "");
    }
}

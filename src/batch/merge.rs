//! `hairfit batch --merge`: one row per manifest item in `DIR/summary.csv` (status, verdict, goodness of
//! fit, every parameter with its standard error, the scales) and `DIR/index.html` linking each
//! item's report. Items not run yet are listed as `missing`, never left out.

use std::path::Path;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::files::{FitJson, Verdict};

use super::Manifest;

/// `DIR/summary.csv`: a header and one row per item; the same type writes and reads it.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SummaryTable {
    pub header: Vec<String>,
    pub rows: Vec<Vec<String>>,
}

impl SummaryTable {
    pub fn write(&self, path: &Path) -> Result<()> {
        write_atomically(path, |w| {
            let mut csv = csv::Writer::from_writer(w);
            let err = |e: csv::Error| Error::Other(format!("{}: {e}", path.display()));
            csv.write_record(&self.header).map_err(err)?;
            for row in &self.rows {
                csv.write_record(row).map_err(err)?;
            }
            csv.flush().map_err(|e| Error::io(path, e))
        })
    }

    pub fn read(path: &Path) -> Result<SummaryTable> {
        let mut reader = csv::Reader::from_path(path)
            .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
        let header = reader
            .headers()
            .map_err(|e| Error::Other(format!("{}: {e}", path.display())))?
            .iter()
            .map(str::to_string)
            .collect();
        let mut rows = Vec::new();
        for r in reader.records() {
            let r = r.map_err(|e| Error::Other(format!("{}: {e}", path.display())))?;
            rows.push(r.iter().map(str::to_string).collect());
        }
        Ok(SummaryTable { header, rows })
    }

    /// The cell of `column` in `row`, if the column exists.
    pub fn cell(&self, row: usize, column: &str) -> Option<&str> {
        let c = self.header.iter().position(|h| h == column)?;
        self.rows.get(row)?.get(c).map(String::as_str)
    }
}

/// The fit status in `dir/fit.json`, if it holds a readable fit.
pub fn fit_status(dir: &Path) -> Option<String> {
    let fit = FitJson::load(&dir.join("fit.json")).ok()?;
    Some(fit.status.as_str().to_string())
}

/// The verdict in `dir/fit.json`, if it holds a readable fit.
pub fn fit_verdict(dir: &Path) -> Option<crate::files::Verdict> {
    Some(FitJson::load(&dir.join("fit.json")).ok()?.verdict)
}

/// What `--merge` found: the items that are not a usable result, by kind, and those whose
/// verdict `--strict` refuses.
#[derive(Debug, Clone, Default)]
pub struct MergeSummary {
    pub items: usize,
    /// Not run yet.
    pub missing: Vec<String>,
    /// fit.json could not be read: (name, error).
    pub unreadable: Vec<(String, String)>,
    /// The last run ended in an error (name, error), or the verdict is `failed` (name, "").
    pub failed: Vec<(String, String)>,
    /// Stopped by a signal: its best so far is there.
    pub interrupted: Vec<String>,
    /// Verdict poor_fit or undetermined (an error with `--strict`).
    pub not_good: Vec<String>,
}

impl MergeSummary {
    /// What is wrong with the batch as one sentence per kind, or nothing when every item has a
    /// usable result.
    pub fn problems(&self) -> Vec<String> {
        let mut lines = Vec::new();
        if !self.failed.is_empty() {
            let named: Vec<String> = self
                .failed
                .iter()
                .map(|(n, e)| match e.as_str() {
                    "" => format!("{n} (verdict failed: see its report)"),
                    e => format!("{n} ({e})"),
                })
                .collect();
            lines.push(format!("failed: {}", named.join("; ")));
        }
        if !self.interrupted.is_empty() {
            lines.push(format!(
                "interrupted (run their shards again to finish them): {}",
                self.interrupted.join(", ")
            ));
        }
        if !self.unreadable.is_empty() {
            let named: Vec<String> = self
                .unreadable
                .iter()
                .map(|(n, e)| format!("{n} ({e})"))
                .collect();
            lines.push(format!(
                "unreadable fit.json (run their shards again): {}",
                named.join("; ")
            ));
        }
        if !self.missing.is_empty() {
            lines.push(format!(
                "missing, not run yet (run their shards, then merge again): {}",
                self.missing.join(", ")
            ));
        }
        lines
    }
}

/// Every digit (shortest round trip), in exponent form where plain digits would run long.
fn number(x: Option<f64>) -> String {
    x.map(crate::error::readable).unwrap_or_default()
}

const FIXED_COLUMNS: [&str; 11] = [
    "name",
    "data",
    "model",
    "status",
    "verdict",
    "n_samples",
    "reduced_chi2",
    "rms",
    "dof",
    "warnings",
    "error",
];

/// The position of fixed column `name`.
fn col(name: &str) -> usize {
    FIXED_COLUMNS
        .iter()
        .position(|c| *c == name)
        .expect("a fixed column")
}

/// One item as merge finds it.
enum Found {
    Missing,
    /// The last run ended in this error (its record says so).
    Error(String),
    Unreadable(String),
    Fit(Box<FitJson>),
}

fn find_item(manifest_item: &super::Item, out: &Path) -> Found {
    if let Some(e) = super::ItemRecord::error_of(out, manifest_item) {
        return Found::Error(e);
    }
    let path = out.join(&manifest_item.name).join("fit.json");
    if !path.exists() {
        return Found::Missing;
    }
    match FitJson::load(&path) {
        Ok(f) => Found::Fit(Box::new(f)),
        Err(e) => Found::Unreadable(e.to_string()),
    }
}

/// Build the summary table of every manifest item under `out`.
pub fn summary_table(manifest: &Manifest, out: &Path) -> (SummaryTable, MergeSummary) {
    let found: Vec<Found> = manifest.items.iter().map(|i| find_item(i, out)).collect();
    let mut summary = MergeSummary {
        items: manifest.items.len(),
        ..MergeSummary::default()
    };
    // Columns: the fixed ones, then every parameter and scale channel in order of first use.
    let mut params: Vec<String> = Vec::new();
    let mut channels: Vec<String> = Vec::new();
    for f in &found {
        let Found::Fit(f) = f else { continue };
        for p in &f.parameters {
            if !params.contains(&p.name) {
                params.push(p.name.clone());
            }
        }
        for s in &f.scale {
            if !channels.contains(&s.channel) {
                channels.push(s.channel.clone());
            }
        }
    }
    let mut header: Vec<String> = FIXED_COLUMNS.iter().map(|s| s.to_string()).collect();
    for p in &params {
        header.extend([p.clone(), format!("{p}_se"), format!("{p}_status")]);
    }
    for c in &channels {
        header.extend([format!("scale_{c}"), format!("scale_{c}_se")]);
    }
    let mut rows = Vec::new();
    for (item, found) in manifest.items.iter().zip(&found) {
        let mut row = vec![String::new(); header.len()];
        row[col("name")] = item.name.clone();
        row[col("data")] = item.data.clone();
        let name = item.name.clone();
        match found {
            Found::Missing => {
                row[col("status")] = "missing".into();
                summary.missing.push(name);
            }
            Found::Error(e) => {
                row[col("status")] = "failed".into();
                row[col("verdict")] = "failed".into();
                row[col("error")] = e.clone();
                summary.failed.push((name, e.clone()));
            }
            Found::Unreadable(e) => {
                row[col("status")] = "unreadable".into();
                row[col("error")] = e.clone();
                summary.unreadable.push((name, e.clone()));
            }
            Found::Fit(f) => {
                match f.verdict {
                    Verdict::Failed => summary.failed.push((name, String::new())),
                    Verdict::Interrupted => summary.interrupted.push(name),
                    Verdict::PoorFit | Verdict::Undetermined => summary.not_good.push(name),
                    Verdict::Good => {}
                }
                fit_cells(&mut row, f, &params, &channels);
            }
        }
        rows.push(row);
    }
    (SummaryTable { header, rows }, summary)
}

/// The cells of a row that come from the item's fit.json.
fn fit_cells(row: &mut [String], f: &FitJson, params: &[String], channels: &[String]) {
    row[col("model")] = f.family().as_str().into();
    row[col("status")] = f.status.as_str().into();
    row[col("verdict")] = f.verdict.as_str().into();
    row[col("n_samples")] = f.data.n_samples.to_string();
    row[col("reduced_chi2")] = number(f.residuals.reduced_chi2);
    row[col("rms")] = number(f.residuals.rms);
    row[col("dof")] = f.residuals.dof.to_string();
    row[col("warnings")] = f.warnings.len().to_string();
    let base = FIXED_COLUMNS.len();
    for p in &f.parameters {
        let k = base + 3 * params.iter().position(|n| n == &p.name).unwrap_or(0);
        row[k] = number(p.value);
        row[k + 1] = number(p.std_error);
        row[k + 2] = p.status.as_str().into();
    }
    let base = base + 3 * params.len();
    for s in &f.scale {
        let k = base + 2 * channels.iter().position(|n| n == &s.channel).unwrap_or(0);
        row[k] = number(s.value);
        row[k + 1] = number(s.std_error);
    }
}

/// The `<title>` prefix of every index.html merge writes: how it knows its own page.
const PAGE_TITLE: &str = "<title>hairfit batch: ";

/// Refuse to replace `path` unless it is absent or merge wrote it (`ours` recognises its text):
/// merge must never overwrite a file of the user's.
fn check_ours(path: &Path, ours: impl Fn(&str) -> bool) -> Result<()> {
    match std::fs::read(path) {
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(()),
        Err(e) => Err(Error::io(path, e)),
        Ok(bytes) if ours(&String::from_utf8_lossy(&bytes)) => Ok(()),
        Ok(_) => Err(Error::Other(format!(
            "{}: not written by `hairfit batch --merge`, which would replace it; move it away, or merge into another --out",
            path.display()
        ))),
    }
}

/// Whether `text` is a summary.csv merge wrote (its header starts with the fixed columns).
fn is_our_summary(text: &str) -> bool {
    let first = text.lines().next().unwrap_or("");
    first.starts_with("name,data,") && first.contains(",status,verdict,n_samples,")
}

/// Write `out/summary.csv` and `out/index.html` for every item of `manifest`, never over a
/// file merge did not write.
pub fn merge(manifest: &Manifest, out: &Path) -> Result<MergeSummary> {
    super::claim_out_dir(out)?;
    let (csv_path, html_path) = (out.join("summary.csv"), out.join("index.html"));
    check_ours(&csv_path, is_our_summary)?;
    check_ours(&html_path, |t| t.contains(PAGE_TITLE))?;
    let (table, summary) = summary_table(manifest, out);
    table.write(&csv_path)?;
    let html = index_html(manifest, &table);
    write_atomically(&html_path, |w| {
        w.write_all(html.as_bytes())
            .map_err(|e| Error::io(&html_path, e))
    })?;
    Ok(summary)
}

fn index_html(manifest: &Manifest, table: &SummaryTable) -> String {
    use crate::plot::escape;
    let shown: Vec<usize> = (0..table.header.len())
        .filter(|&c| c != col("data") && !table.header[c].ends_with("_status"))
        .collect();
    let mut s = String::new();
    s += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
    s += &format!(
        "{PAGE_TITLE}{}</title>\n",
        escape(&manifest.path.display().to_string())
    );
    s += "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}\
          td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;font-size:90%;white-space:nowrap}\
          td:first-child,th:first-child{text-align:left}\
          .missing,.unreadable,.failed,.interrupted,.v-failed,.v-interrupted{color:#b00}\
          .v-poor_fit td:nth-child(4),.v-undetermined td:nth-child(4){background:#fff3cd}</style></head><body>\n";
    s += &format!(
        "<h1>hairfit batch</h1>\n<p>Manifest <code>{}</code>: {} items. Each name links to the item's report; the whole table is <a href=\"summary.csv\">summary.csv</a>.</p>\n<table>\n<tr>",
        escape(&manifest.path.display().to_string()),
        table.rows.len()
    );
    for &c in &shown {
        s += &format!("<th>{}</th>", escape(&table.header[c]));
    }
    s += "</tr>\n";
    for row in &table.rows {
        let status = &row[col("status")];
        let verdict = &row[col("verdict")];
        let has_report = !row[col("model")].is_empty();
        s += &format!("<tr class=\"{} v-{}\">", escape(status), escape(verdict));
        for &c in &shown {
            let cell = &row[c];
            if c == col("name") && has_report {
                s += &format!("<td><a href=\"{0}/index.html\">{0}</a></td>", escape(cell));
            } else if c == col("error") {
                s += &format!(
                    "<td style=\"text-align:left;white-space:normal\">{}</td>",
                    escape(cell)
                );
            } else if let Ok(x) = cell.parse::<f64>() {
                s += &format!("<td>{}</td>", escape(&short(x, cell)));
            } else {
                s += &format!("<td>{}</td>", escape(cell));
            }
        }
        s += "</tr>\n";
    }
    s += "</table>\n</body></html>\n";
    s
}
/// A readable number for the page (the CSV keeps every digit).
fn short(x: f64, text: &str) -> String {
    if !(text.contains('.') || text.contains('e')) {
        text.to_string()
    } else if x != 0.0 && !(1e-3..1e5).contains(&x.abs()) {
        format!("{x:.3e}")
    } else {
        format!("{x:.4}")
    }
}

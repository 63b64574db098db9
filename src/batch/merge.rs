//! `hairfit batch --merge`: one row per manifest item in `DIR/summary.csv` (status, verdict, goodness of
//! fit, every parameter with its standard error, the scales) and `DIR/index.html` linking each
//! item's report. Items not run yet are listed as `missing`, never left out.

use std::path::Path;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::files::FitJson;

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

/// What `--merge` found.
#[derive(Debug, Clone)]
pub struct MergeSummary {
    pub items: usize,
    pub missing: Vec<String>,
    pub unreadable: Vec<(String, String)>,
}

/// Every digit (shortest round trip), in exponent form where plain digits would run long.
fn number(x: Option<f64>) -> String {
    x.map(crate::error::readable).unwrap_or_default()
}

const FIXED_COLUMNS: [&str; 9] = [
    "name",
    "data",
    "status",
    "verdict",
    "n_samples",
    "reduced_chi2",
    "rms",
    "dof",
    "warnings",
];

/// Build the summary table of every manifest item under `out`.
pub fn summary_table(manifest: &Manifest, out: &Path) -> (SummaryTable, MergeSummary) {
    // One entry per item, in manifest order: `None` when it has no fit.json yet.
    let mut missing = Vec::new();
    let mut unreadable = Vec::new();
    let fits: Vec<Option<Result<FitJson>>> = manifest
        .items
        .iter()
        .map(|item| {
            let path = out.join(&item.name).join("fit.json");
            if !path.exists() {
                missing.push(item.name.clone());
                return None;
            }
            let fit = FitJson::load(&path);
            if let Err(e) = &fit {
                unreadable.push((item.name.clone(), e.to_string()));
            }
            Some(fit)
        })
        .collect();
    // Columns: the fixed ones, then every parameter and scale channel in order of first use.
    let mut params: Vec<String> = Vec::new();
    let mut channels: Vec<String> = Vec::new();
    for f in fits.iter().flatten().flatten() {
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
    for (item, fit) in manifest.items.iter().zip(&fits) {
        let data = item.argv.first().cloned().unwrap_or_default();
        let mut row = vec![String::new(); header.len()];
        row[0] = item.name.clone();
        row[1] = data;
        match fit {
            None => row[2] = "missing".into(),
            Some(Err(_)) => row[2] = "unreadable".into(),
            Some(Ok(f)) => {
                row[2] = f.status.as_str().into();
                row[3] = f.verdict.as_str().into();
                row[4] = f.data.n_samples.to_string();
                row[5] = number(f.residuals.reduced_chi2);
                row[6] = number(f.residuals.rms);
                row[7] = f.residuals.dof.to_string();
                row[8] = f.warnings.len().to_string();
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
        }
        rows.push(row);
    }
    let items = manifest.items.len();
    (
        SummaryTable { header, rows },
        MergeSummary {
            items,
            missing,
            unreadable,
        },
    )
}

/// Write `out/summary.csv` and `out/index.html` for every item of `manifest`.
pub fn merge(manifest: &Manifest, out: &Path) -> Result<MergeSummary> {
    let (table, summary) = summary_table(manifest, out);
    table.write(&out.join("summary.csv"))?;
    let html = index_html(manifest, &table);
    let path = out.join("index.html");
    write_atomically(&path, |w| {
        w.write_all(html.as_bytes())
            .map_err(|e| Error::io(&path, e))
    })?;
    Ok(summary)
}

fn index_html(manifest: &Manifest, table: &SummaryTable) -> String {
    use crate::plot::escape;
    let shown: Vec<usize> = (0..table.header.len())
        .filter(|&c| c != 1 && !table.header[c].ends_with("_status"))
        .collect();
    let mut s = String::new();
    s += "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n";
    s += &format!(
        "<title>hairfit batch: {}</title>\n",
        escape(&manifest.path.display().to_string())
    );
    s += "<style>body{font-family:sans-serif;margin:2em}table{border-collapse:collapse}\
          td,th{border:1px solid #ccc;padding:2px 6px;text-align:right;font-size:90%;white-space:nowrap}\
          td:first-child,th:first-child{text-align:left}\
          .missing,.unreadable,.failed,.interrupted,.v-failed,.v-interrupted{color:#b00}\
          .v-poor_fit td:nth-child(3),.v-undetermined td:nth-child(3){background:#fff3cd}</style></head><body>\n";
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
        let status = &row[2];
        let verdict = &row[3];
        s += &format!("<tr class=\"{} v-{}\">", escape(status), escape(verdict));
        for &c in &shown {
            let cell = &row[c];
            if c == 0 && status != "missing" {
                s += &format!("<td><a href=\"{0}/index.html\">{0}</a></td>", escape(cell));
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

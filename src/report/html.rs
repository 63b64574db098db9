//! `index.html`: the whole report on one offline page — summary numbers, warnings, parameter
//! and scale tables, every figure (PNG, linked to its SVG), solver stages and the options used.
//! Inline CSS, relative links only, no scripts and no network resources.

use std::fmt::Write as _;

use super::{ReportOptions, ReportSummary};
use crate::files::{FitJson, FitStatus, ParamStatus};
use crate::plot::{escape, fmt_interval, fmt_num, fmt_value_se};

const STYLE: &str = "body{font-family:'DejaVu Sans',Verdana,sans-serif;margin:24px auto;max-width:1720px;color:#222;background:#fff;padding:0 16px}\
h1{font-size:1.6em;margin-bottom:4px}h2{font-size:1.25em;border-bottom:1px solid #ccc;padding-bottom:4px;margin-top:32px}\
table{border-collapse:collapse;margin:8px 0}td,th{border:1px solid #ccc;padding:4px 10px;text-align:left}\
th{background:#f0f2f5}td.num{text-align:right;font-variant-numeric:tabular-nums}\
.ok{color:#176117;font-weight:bold}.bad{color:#a11;font-weight:bold}.muted{color:#777}\
.warn{background:#fff6e0;border-left:4px solid #e0a000;padding:6px 12px;margin:4px 0}\
.note{background:#eef3fb;border-left:4px solid #5b7fc0;padding:6px 12px;margin:4px 0}\
figure{margin:12px 0}figure img{max-width:100%;height:auto;border:1px solid #ddd}\
figcaption{color:#555;font-size:.9em}pre{background:#f6f6f6;padding:10px;white-space:pre-wrap;overflow-wrap:anywhere;font-size:.85em}\
.grid{display:flex;flex-wrap:wrap;gap:24px;align-items:flex-start}\
.verdict{border:2px solid;border-radius:6px;padding:8px 16px;margin:12px 0}.verdict h2{border:0;margin:4px 0}\
.v-good{border-color:#2a8a2a;background:#eef8ee}.v-poor_fit,.v-undetermined{border-color:#e0a000;background:#fff6e0}\
.v-failed,.v-interrupted{border-color:#a11;background:#fbeaea}";

/// The page for `fit` and the figures in `summary`.
pub fn index_html(fit: &FitJson, summary: &ReportSummary, options: &ReportOptions) -> String {
    let mut h = String::new();
    let file = escape(&fit.data.file);
    let _ = write!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n\
         <title>hairfit report: {file}</title>\n<style>{STYLE}</style>\n</head>\n<body>\n\
         <h1>hairfit fit report</h1>\n<p class=\"muted\">data: {file} — hairfit {} — value axes: {}</p>\n",
        escape(&fit.hairfit_version),
        if options.linear { "linear" } else { "logarithmic" }
    );
    verdict_box(&mut h, fit);
    summary_section(&mut h, fit);
    if !fit.warnings.is_empty() || !summary.notes.is_empty() {
        h.push_str("<h2>Warnings and notes</h2>\n");
        for w in &fit.warnings {
            let _ = writeln!(h, "<div class=\"warn\">{}</div>", escape(w));
        }
        for n in &summary.notes {
            let _ = writeln!(h, "<div class=\"note\">report: {}</div>", escape(n));
        }
    }
    h.push_str("<div class=\"grid\">\n");
    parameter_table(&mut h, fit);
    scale_table(&mut h, fit);
    stage_table(&mut h, fit);
    h.push_str("</div>\n");
    for f in &summary.figures {
        let _ = writeln!(
            h,
            "<h2>{title}</h2>\n<figure><a href=\"{stem}.svg\"><img src=\"{stem}.png\" width=\"{w}\" height=\"{hh}\" alt=\"{title}\"></a>\
             <figcaption>{title} — click for the vector version ({stem}.svg)</figcaption></figure>",
            title = escape(&f.title),
            stem = escape(&f.stem),
            w = f.width,
            hh = f.height
        );
    }
    h.push_str("<h2>Options used by the fit</h2>\n<pre>");
    h.push_str(&escape(
        &serde_json::to_string_pretty(&fit.options).unwrap_or_default(),
    ));
    h.push_str("</pre>\n<h2>Data loading</h2>\n<pre>");
    h.push_str(&escape(
        &serde_json::to_string_pretty(&fit.data.load_report).unwrap_or_default(),
    ));
    h.push_str("</pre>\n</body>\n</html>\n");
    h
}

/// The verdict, its reasons and suggestions, in a box at the top of the page.
fn verdict_box(h: &mut String, fit: &FitJson) {
    let v = fit.verdict.as_str();
    let _ = writeln!(
        h,
        "<div class=\"verdict v-{v}\" id=\"verdict\">\n<h2>Verdict: {v}</h2>"
    );
    if !fit.reasons.is_empty() {
        h.push_str("<ul>\n");
        for r in &fit.reasons {
            let _ = writeln!(h, "<li>{}</li>", escape(r));
        }
        h.push_str("</ul>\n");
    }
    if !fit.suggestions.is_empty() {
        h.push_str("<p><b>What to try</b></p>\n<ul>\n");
        for t in &fit.suggestions {
            let _ = writeln!(
                h,
                "<li><code>{}</code> — {}</li>",
                escape(&t.action),
                escape(&t.evidence)
            );
        }
        h.push_str("</ul>\n");
    }
    h.push_str("</div>\n");
}

/// Optional number for a table cell.
fn opt(v: Option<f64>) -> String {
    v.map_or("—".into(), fmt_num)
}

fn summary_section(h: &mut String, fit: &FitJson) {
    let status_class = if fit.status == FitStatus::Converged {
        "ok"
    } else {
        "bad"
    };
    let r = &fit.residuals;
    h.push_str("<h2>Summary</h2>\n<table>\n");
    let mut row = |k: &str, v: String| {
        let _ = writeln!(h, "<tr><th>{}</th><td>{v}</td></tr>", escape(k));
    };
    row(
        "status",
        format!(
            "<span class=\"{status_class}\">{}</span>",
            fit.status.as_str()
        ),
    );
    row("data file", escape(&fit.data.file));
    row("samples", fit.data.n_samples.to_string());
    row("channels", escape(&fit.data.channels.join(", ")));
    row("model", {
        let items = fit.records().describe();
        // A residual term is drawn in the TRT column (`families::table` says why).
        let residual = items
            .iter()
            .any(|i| i.starts_with("terms ") && i.contains("residual"));
        format!(
            "{}; {}{}",
            fit.family().citation(),
            items.join("; "),
            if residual {
                " (the TRT curve includes the p ≥ 3 residual)"
            } else {
                ""
            }
        )
    });
    row(
        "residuals",
        format!("space {}, loss {}", escape(&r.space), escape(&r.loss)),
    );
    row("RMS normalised residual", opt(r.rms));
    row(
        &super::cost_chi2_label(&r.loss).replace("chi2", "χ²"),
        opt(r.reduced_chi2),
    );
    row("degrees of freedom", r.dof.to_string());
    for c in &r.per_channel {
        row(
            &format!("channel {}", c.channel),
            format!(
                "RMS {}, reduced χ² (cost / dof) {}",
                opt(c.rms),
                opt(c.reduced_chi2)
            ),
        );
    }
    h.push_str("</table>\n");
}

/// A table cell, already HTML: text, or a number aligned right.
enum Cell {
    Text(String),
    Num(String),
}

/// A `<section>` with heading `title` and a table of `head` columns and `rows` of cells.
fn table_section(
    h: &mut String,
    title: &str,
    head: &[&str],
    rows: impl Iterator<Item = Vec<Cell>>,
) {
    let _ = write!(h, "<section><h2>{title}</h2>\n<table>\n<tr>");
    for column in head {
        let _ = write!(h, "<th>{column}</th>");
    }
    h.push_str("</tr>\n");
    for row in rows {
        h.push_str("<tr>");
        for cell in row {
            let _ = match cell {
                Cell::Text(s) => write!(h, "<td>{s}</td>"),
                Cell::Num(s) => write!(h, "<td class=\"num\">{s}</td>"),
            };
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table></section>\n");
}

fn parameter_table(h: &mut String, fit: &FitJson) {
    let rows = fit.parameters.iter().map(|p| {
        // The parameter table knows each unit (σ_a: per fiber radius).
        let unit = fit.family().unit_label(&p.name);
        // Value, error and interval ends all to the error's second significant digit.
        let (value, se_text) = value_se(p.value, p.std_error);
        let err = match p.status {
            ParamStatus::Fixed => "<span class=\"muted\">fixed</span>".to_string(),
            ParamStatus::Undetermined => "<span class=\"bad\">undetermined</span>".to_string(),
            _ => se_text,
        };
        let status = match p.status {
            ParamStatus::Undetermined | ParamStatus::AtBound => {
                format!("<span class=\"bad\">{}</span>", p.status.as_str())
            }
            s => s.as_str().to_string(),
        };
        vec![
            Cell::Text(escape(&with_channel(&p.name, &fit.data.channels))),
            Cell::Num(value),
            Cell::Num(err),
            Cell::Num(interval_cell(p.interval_68.as_ref(), p.value, p.std_error)),
            Cell::Num(interval_cell(p.interval_95.as_ref(), p.value, p.std_error)),
            Cell::Text(unit.into()),
            Cell::Text(status),
        ]
    });
    let head = [
        "parameter",
        "value",
        "std. error",
        "68% profile interval",
        "95% profile interval",
        "unit",
        "status",
    ];
    table_section(h, "Parameters", &head, rows);
}

/// A value and its standard error as table cells ("—" for a missing one), to the error's
/// digits ([`fmt_value_se`]).
fn value_se(v: Option<f64>, se: Option<f64>) -> (String, String) {
    match v {
        Some(v) => {
            let (value, err) = fmt_value_se(v, se);
            (value, err.unwrap_or_else(|| "—".into()))
        }
        None => ("—".into(), opt(se)),
    }
}

/// A profile interval `[lower, upper]` (an open side reads "open"), to the digits of the
/// value's standard error and never showing equal ends ([`fmt_interval`]); "—" when not
/// profiled.
fn interval_cell(i: Option<&crate::files::Interval>, v: Option<f64>, se: Option<f64>) -> String {
    i.map_or("—".into(), |i| {
        let [lo, hi] = fmt_interval(i.lower, i.upper, v.unwrap_or(f64::NAN), se);
        format!("[{lo}, {hi}]")
    })
}

/// `sigma_a[1]` → `sigma_a[1] (g)`: name the channel of a per-channel parameter.
fn with_channel(name: &str, channels: &[String]) -> String {
    let channel = name
        .strip_prefix("sigma_a[")
        .and_then(|r| r.strip_suffix(']'))
        .and_then(|i| i.parse::<usize>().ok())
        .and_then(|i| channels.get(i));
    match channel {
        Some(c) => format!("{name} ({c})"),
        None => name.to_string(),
    }
}

fn scale_table(h: &mut String, fit: &FitJson) {
    if fit.scale.is_empty() {
        return;
    }
    let rows = fit.scale.iter().map(|s| {
        vec![
            Cell::Text(escape(&s.channel)),
            Cell::Num(value_se(s.value, s.std_error).0),
            Cell::Num(value_se(s.value, s.std_error).1),
        ]
    });
    let head = ["channel", "scale", "std. error"];
    table_section(h, "Scale per channel", &head, rows);
}

fn stage_table(h: &mut String, fit: &FitJson) {
    if fit.trace.is_empty() {
        return;
    }
    let rows = fit.trace.iter().map(|t| {
        vec![
            Cell::Text(escape(&t.stage)),
            Cell::Num(t.iterations.to_string()),
            Cell::Num(opt(t.cost)),
        ]
    });
    let head = ["stage", "iterations", "final cost"];
    table_section(h, "Solver stages", &head, rows);
}

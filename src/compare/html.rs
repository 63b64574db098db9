//! DIR/index.html of `hairfit compare`: the verdict in words, the criteria side by side, both
//! parameter tables, the bins where the models differ, the overlay figure, links to each fit's
//! own report. Offline (no scripts, no external resources).

use std::fmt::Write as _;
use std::path::Path;

use super::Comparison;
use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::files::FitJson;
use crate::plot::{escape, fmt_num, FigureInfo};

fn opt(v: Option<f64>) -> String {
    v.map_or("—".into(), fmt_num)
}

/// Write DIR/index.html.
pub fn write_index(
    dir: &Path,
    c: &Comparison,
    fig: &FigureInfo,
    marschner: &FitJson,
    chiang: &FitJson,
) -> Result<()> {
    let mut h = String::new();
    h.push_str("<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>hairfit compare</title>\n<style>body{font-family:sans-serif;max-width:1500px;margin:1em auto}table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;text-align:left}td.n{text-align:right}</style>\n</head><body>\n");
    let _ = writeln!(h, "<h1>Marschner vs Chiang on {}</h1>", escape(&c.data));
    h.push_str("<ul>\n");
    for f in &c.findings {
        let _ = writeln!(h, "<li>{}</li>", escape(f));
    }
    h.push_str("</ul>\n<h2>Criteria</h2>\n<table><tr><th>model</th><th>status</th><th>χ²</th><th>k</th><th>AIC</th><th>BIC</th><th>reduced χ²</th><th>verdict</th><th>report</th></tr>\n");
    for m in &c.models {
        let verdict = m
            .verdict
            .as_ref()
            .map(|v| v.to_string())
            .unwrap_or_else(|| "—".into());
        let _ = writeln!(
            h,
            "<tr><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{:.2}</td><td class=\"n\">{:.2}</td><td class=\"n\">{}</td><td>{}</td><td><a href=\"{}/index.html\">{}/</a></td></tr>",
            m.family,
            escape(&m.status),
            fmt_num(m.chi2),
            m.n_params,
            m.aic,
            m.bic,
            opt(m.reduced_chi2),
            escape(&verdict),
            m.dir,
            m.dir
        );
    }
    let _ = writeln!(
        h,
        "</table>\n<p>{}; ΔAIC = AIC(chiang) − AIC(marschner) = {:.2}, ΔBIC = {:.2}.</p>",
        escape(&c.criterion),
        c.delta_aic,
        c.delta_bic
    );
    let _ = writeln!(h, "<p><b>Scales:</b> {}.</p>", escape(&c.scale_note));
    h.push_str("<h2>Parameters</h2>\n");
    for (name, fit) in [("Marschner", marschner), ("Chiang", chiang)] {
        let _ = writeln!(
            h,
            "<h3>{name}</h3>\n<table><tr><th>parameter</th><th>value</th><th>std. error</th><th>status</th></tr>"
        );
        for p in &fit.parameters {
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
                escape(&p.name),
                opt(p.value),
                opt(p.std_error),
                p.status
            );
        }
        for s in &fit.scale {
            let _ = writeln!(
                h,
                "<tr><td>scale[{}] (not comparable)</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td></td></tr>",
                escape(&s.channel),
                opt(s.value),
                opt(s.std_error)
            );
        }
        h.push_str("</table>\n");
    }
    h.push_str("<h2>Where they differ</h2>\n<table><tr><th>bin</th><th>residuals</th><th>RMS Marschner</th><th>RMS Chiang</th><th>worse</th></tr>\n");
    for r in &c.regions {
        let _ = writeln!(
            h,
            "<tr><td>{} {:.0}±{:.0}°</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td>{}</td></tr>",
            if r.axis == "abs_phi" { "|φ|" } else { "θh" },
            r.centre_deg,
            r.half_width_deg,
            r.n,
            fmt_num(r.rms_marschner),
            fmt_num(r.rms_chiang),
            r.worse().map_or("", |f| f.as_str())
        );
    }
    let _ = writeln!(
        h,
        "</table>\n<h2>{}</h2>\n<img src=\"{}.svg\" width=\"{}\" alt=\"{}\">\n</body></html>",
        escape(&fig.title),
        fig.stem,
        fig.width,
        escape(&fig.title)
    );
    let path = dir.join("index.html");
    write_atomically(&path, |w| {
        w.write_all(h.as_bytes()).map_err(|e| Error::io(&path, e))
    })
}

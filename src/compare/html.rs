//! DIR/index.html of `hairfit compare`: the findings in words, the ranking table, every
//! family's RMS residual per region (lobe regions, then bins of |φ| and θh; a cell is marked
//! where that family misses the data against the region's best), the overlay figure, each
//! family's parameter table and links to each fit's own report. Offline (no scripts, no
//! external resources).

use std::fmt::Write as _;
use std::path::Path;

use super::comparison::{Comparison, Region, AIC_TIE, BIN_RATIO, MIN_RMS_GAP};
use super::findings::and_list;
use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::families::ModelFamily;
use crate::plot::{escape, fmt_num, fmt_value_se, FigureInfo};

const STYLE: &str = "body{font-family:sans-serif;max-width:1500px;margin:1em auto}\
table{border-collapse:collapse;margin:0.5em 0}td,th{border:1px solid #ccc;padding:2px 8px;\
text-align:left}td.n{text-align:right}td.miss{background:#fbd5d5}td.low{font-weight:bold}\
tr.best td{background:#e6f2e6}.key{color:#555}img{max-width:100%;height:auto}";

fn opt(v: Option<f64>) -> String {
    v.map_or("—".into(), fmt_num)
}

/// A value and its standard error to the error's second significant digit, as the fit
/// report prints them ("—" for a missing one).
fn value_se(v: Option<f64>, se: Option<f64>) -> [String; 2] {
    match v {
        Some(v) => {
            let (v, e) = fmt_value_se(v, se);
            [v, e.unwrap_or_else(|| "—".into())]
        }
        None => ["—".into(), opt(se)],
    }
}

/// The ranking: one row per family, best first.
fn ranking(h: &mut String, c: &Comparison) {
    h.push_str("<h2>Ranking</h2>\n<table><tr><th>rank</th><th>model</th><th>status</th><th>χ²</th><th>χ² / best</th><th>k</th><th>AIC</th><th>ΔAIC</th><th>BIC</th><th>ΔBIC</th><th>reduced χ² (cost / dof)</th><th>verdict</th><th>report</th></tr>\n");
    for r in &c.ranking {
        let Some(m) = c.model(r.family) else { continue };
        let verdict = m.verdict_str();
        let _ = writeln!(
            h,
            "<tr{}><td class=\"n\">{}{}</td><td>{}</td><td>{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{}</td><td class=\"n\">{:.2}</td><td class=\"n\">{:.2}</td><td class=\"n\">{:.2}</td><td class=\"n\">{:.2}</td><td class=\"n\">{}</td><td>{}</td><td><a href=\"{}/index.html\">{}/</a></td></tr>",
            if r.rank == 1 { " class=\"best\"" } else { "" },
            r.rank,
            if r.tied_with_best && Some(r.family) != c.best() { " (tie)" } else { "" },
            escape(m.family.title()),
            escape(&m.status),
            fmt_num(m.chi2),
            r.chi2_ratio.map_or("—".into(), fmt_num),
            m.n_params,
            r.aic,
            r.delta_aic,
            r.bic,
            r.delta_bic,
            opt(m.reduced_chi2),
            escape(verdict),
            m.dir,
            m.dir
        );
    }
    for m in c.models.iter().filter(|m| c.rank_of(m.family).is_none()) {
        let _ = writeln!(
            h,
            "<tr><td>not ranked</td><td>{}</td><td>{}</td><td colspan=\"8\">—</td><td class=\"n\">{}</td><td>{}</td><td><a href=\"{}/index.html\">{}/</a></td></tr>",
            escape(m.family.title()),
            escape(&m.status),
            opt(m.reduced_chi2),
            escape(m.verdict_str()),
            m.dir,
            m.dir
        );
    }
    let _ = writeln!(
        h,
        "</table>\n<p class=\"key\">{}. ΔAIC and ΔBIC are against the family with the lowest AIC; \
         a family within ΔAIC &lt; {AIC_TIE} of it is tied with it (rank 1).</p>",
        escape(&c.criterion)
    );
}

/// One table of regions: a column per family; a cell is marked where that family misses the
/// data against the family with the lowest RMS in the region.
fn regions(h: &mut String, c: &Comparison, rows: &[&Region], lobes: bool) {
    let families: Vec<ModelFamily> = c.models.iter().map(|m| m.family).collect();
    h.push_str("<table><tr><th>region</th>");
    if lobes {
        h.push_str("<th>definition</th>");
    }
    h.push_str("<th>residuals</th>");
    for f in &families {
        let _ = write!(h, "<th>RMS {}</th>", escape(f.title()));
    }
    h.push_str("</tr>\n");
    for r in rows {
        let lowest = families
            .iter()
            .copied()
            .min_by(|a, b| {
                let v = |f: ModelFamily| r.rms.get(f).unwrap_or(f64::INFINITY);
                v(*a).total_cmp(&v(*b))
            })
            .unwrap_or_default();
        let _ = write!(h, "<tr><td>{}</td>", escape(&r.name));
        if lobes {
            let _ = write!(h, "<td>{}</td>", escape(&r.definition));
        }
        let _ = write!(h, "<td class=\"n\">{}</td>", r.n);
        for &f in &families {
            let class = if r.misses(f, lowest) {
                "n miss"
            } else if f == lowest && families.len() > 1 && r.rms.get(f).is_some() {
                "n low"
            } else {
                "n"
            };
            let _ = write!(
                h,
                "<td class=\"{class}\">{}</td>",
                r.rms.get(f).map_or("—".into(), fmt_num)
            );
        }
        h.push_str("</tr>\n");
    }
    h.push_str("</table>\n");
}

/// Each family's parameters (and its scales, which are not comparable).
fn parameters(h: &mut String, c: &Comparison) {
    h.push_str("<h2>Parameters</h2>\n");
    for m in &c.models {
        let _ = writeln!(
            h,
            "<h3>{}</h3>\n<table><tr><th>parameter</th><th>value</th><th>std. error</th><th>status</th></tr>",
            escape(m.family.title())
        );
        for p in &m.parameters {
            let [value, se] = value_se(p.value, p.std_error);
            let _ = writeln!(
                h,
                "<tr><td>{}</td><td class=\"n\">{value}</td><td class=\"n\">{se}</td><td>{}</td></tr>",
                escape(&p.name),
                p.status
            );
        }
        for s in &m.scale {
            let [value, se] = value_se(s.value, s.std_error);
            let _ = writeln!(
                h,
                "<tr><td>scale[{}] (not comparable)</td><td class=\"n\">{value}</td><td class=\"n\">{se}</td><td></td></tr>",
                escape(&s.channel),
            );
        }
        h.push_str("</table>\n");
    }
}

/// Write DIR/index.html.
pub fn write_index(dir: &Path, c: &Comparison, fig: &FigureInfo) -> Result<()> {
    let names: Vec<&str> = c.models.iter().map(|m| m.family.title()).collect();
    let mut h = String::new();
    let _ = writeln!(
        h,
        "<!DOCTYPE html>\n<html lang=\"en\"><head><meta charset=\"utf-8\">\n<title>hairfit compare: {}</title>\n<style>{STYLE}</style>\n</head><body>",
        escape(&and_list(&names))
    );
    let _ = writeln!(
        h,
        "<h1>{} on {}</h1>\n<ul>",
        escape(&names.join(" vs ")),
        escape(&c.data)
    );
    for f in &c.findings {
        let _ = writeln!(h, "<li>{}</li>", escape(f));
    }
    h.push_str("</ul>\n");
    ranking(&mut h, c);
    let _ = writeln!(
        h,
        "<h2>Where each model misses</h2>\n<p class=\"key\">RMS of the normalised residuals \
         (samples × channels) over each region, per family. Marked red: that family's RMS is at \
         least {BIN_RATIO}× the region's lowest and larger by {MIN_RMS_GAP} or more; bold: the \
         lowest. φ = φ_r − φ_i (|φ| = 0° backward, 180° forward), θh = (θ_i + θ_r)/2 (θ &gt; 0 \
         toward the tip). A lobe region with fewer than 3 residuals has no RMS (an azimuthal rig, \
         θ_r = −θ_i, measures on the cone only: nothing beside it); such bins are left out.</p>\n<h3>Lobe regions</h3>"
    );
    let by_axis =
        |axis: &str| -> Vec<&Region> { c.regions.iter().filter(|r| r.axis == axis).collect() };
    regions(&mut h, c, &by_axis("lobe"), true);
    h.push_str("<h3>10° bins of |φ|</h3>\n");
    regions(&mut h, c, &by_axis("abs_phi"), false);
    h.push_str("<h3>10° bins of θh</h3>\n");
    regions(&mut h, c, &by_axis("theta_h"), false);
    let _ = writeln!(
        h,
        "<h2>{}</h2>\n<img src=\"{}.svg\" width=\"{}\" alt=\"{}\">",
        escape(&fig.title),
        fig.stem,
        fig.width,
        escape(&fig.title)
    );
    parameters(&mut h, c);
    let _ = writeln!(
        h,
        "<p><b>Scales:</b> {}.</p>\n</body></html>",
        escape(&c.scale_note)
    );
    let path = dir.join("index.html");
    write_atomically(&path, |w| {
        w.write_all(h.as_bytes()).map_err(|e| Error::io(&path, e))
    })
}

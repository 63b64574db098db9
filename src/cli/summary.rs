//! The one-screen summary printed by `hairfit fit` / `hairfit demo`: the verdict, its reasons
//! and suggestions first, then the model, parameters, residuals, stages and warnings; and the
//! progress line on stderr while the fit's files and report are written.

use std::path::Path;

use crate::fit::FitOutcome;
use crate::geometry::Measurement;
use crate::plot::{fmt_interval, fmt_num, fmt_value_se};

/// `v ± e`, both to the error's second significant digit (the report's format,
/// [`fmt_value_se`]); a value without an error reads as [`crate::plot::fmt_num`].
fn pm(v: Option<f64>, e: Option<f64>) -> String {
    match v {
        Some(v) => match fmt_value_se(v, e) {
            (v, Some(e)) => format!("{v:>12} ± {e}"),
            (v, None) => format!("{v:>12}"),
        },
        None => "        null".into(),
    }
}

/// The 68% profile interval column: `  68% [lo, hi]` (an open side reads "open"), to the
/// value's error digits ([`fmt_interval`]); empty when the parameter was not profiled.
fn interval(i: Option<&crate::files::Interval>, v: Option<f64>, se: Option<f64>) -> String {
    i.map_or(String::new(), |i| {
        let [lo, hi] = fmt_interval(i.lower, i.upper, v.unwrap_or(f64::NAN), se);
        format!("  68% [{lo}, {hi}]")
    })
}

/// `verdict: …`, a line per reason and per suggestion (what to try, then why).
pub fn verdict_lines(j: &crate::files::FitJson) -> String {
    let mut s = format!("verdict: {}\n", j.verdict);
    for r in &j.reasons {
        s += &format!("  - {r}\n");
    }
    for t in &j.suggestions {
        s += &format!("  try: {}\n       because {}\n", t.action, t.evidence);
    }
    s
}

/// The summary of `out`; `dir` is where its files were written, if they were.
pub fn summary<P>(out: &FitOutcome<P>, dir: Option<&Path>) -> String {
    let j = &out.json;
    let mut s = String::new();
    s += &verdict_lines(j);
    s += &format!(
        "hairfit fit: {} — {} samples × {} channel(s) from {}\n",
        j.status,
        j.data.n_samples,
        j.data.channels.len(),
        j.data.file
    );
    // How the effects were chosen (`--effects auto`) means something only to a family whose
    // switches are effects; another's terms are what `--terms` says.
    let chosen = if j.family().own_options().contains(&"--lobes") {
        format!(" ({})", j.options.effects_choice)
    } else {
        String::new()
    };
    s += &format!(
        "model: {}, {}{chosen}\n",
        j.family(),
        j.records().describe().join(", "),
    );
    if j.options.measurement == Measurement::Radiance {
        s += "measurement: radiance, the model times cos theta_i (--measurement radiance)\n";
    }
    for r in &j.options.effects_reasons {
        s += &format!("  {r}\n");
    }
    s += "parameters:\n";
    for p in &j.parameters {
        s += &format!(
            "  {:<16} {}  {}{}\n",
            p.name,
            pm(p.value, p.std_error),
            p.status,
            interval(p.interval_68.as_ref(), p.value, p.std_error)
        );
    }
    for c in &j.scale {
        s += &format!(
            "  scale[{}]{:<8} {}\n",
            c.channel,
            "",
            pm(c.value, c.std_error)
        );
    }
    let r = &j.residuals;
    s += &format!(
        "residuals ({} space, {} loss): rms {} {} {} dof {}\n",
        r.space,
        r.loss,
        r.rms.map_or("null".into(), fmt_num),
        crate::report::cost_chi2_label(&r.loss),
        r.reduced_chi2.map_or("null".into(), fmt_num),
        r.dof
    );
    if !j.options.intervals.is_empty() {
        s += &format!(
            "intervals: {} ({})\n",
            j.options.intervals, j.options.intervals_reason
        );
    }
    if let Some(d) = &r.down_weighted {
        let lines: Vec<String> = d.lines.iter().take(12).map(|l| l.to_string()).collect();
        s += &format!(
            "robust loss (scale {:.4e}{}): {} value(s) down-weighted (weight < {}){}{}\n",
            j.options.loss_scale,
            if j.options.loss_scale_auto {
                ", auto"
            } else {
                ""
            },
            d.count,
            d.threshold,
            if lines.is_empty() { "" } else { ", lines " },
            lines.join(", ") + if d.lines.len() > 12 { ", …" } else { "" }
        );
    }
    for t in &j.trace {
        s += &format!(
            "  stage {:<18} iterations {:>5}  cost {:.6e}  {:.2} s\n",
            t.stage,
            t.iterations,
            t.cost.unwrap_or(f64::NAN),
            out.timing.stage(&t.stage)
        );
    }
    // Timed steps that are not solver stages: the statistics after the fit, the profiles.
    let after: Vec<String> = out
        .timing
        .stages
        .iter()
        .filter(|t| !j.trace.iter().any(|s| s.stage == t.stage))
        .map(|t| format!("{} {:.2} s", t.stage.replace('_', " "), t.wall_s))
        .collect();
    if !after.is_empty() {
        s += &format!("  then: {}\n", after.join(", "));
    }
    for w in &j.warnings {
        s += &format!("warning: {w}\n");
    }
    s += &format!("wall time {:.2} s", out.timing.wall_time_s);
    // Before and after the fit: reading the data, writing the files and the report.
    let around: Vec<String> = [
        ("load", out.timing.load_s),
        ("outputs", out.timing.outputs_s),
    ]
    .iter()
    .filter_map(|(what, t)| t.map(|t| format!("{what} {t:.2} s")))
    .collect();
    if !around.is_empty() {
        s += &format!(" (+ {})", around.join(", "));
    }
    if let Some(d) = dir {
        let curves = match j.options.curves {
            crate::files::CurvesMode::Full => ",curves.csv".to_string(),
            crate::files::CurvesMode::Summary if j.options.curves_reason.is_empty() => {
                ",curves.csv (summary)".to_string()
            }
            crate::files::CurvesMode::Summary => format!(
                ",curves.csv (summary: over {} rows; --curves full writes all)",
                crate::fit::AUTO_FULL_CURVES_ROWS
            ),
            crate::files::CurvesMode::None => String::new(),
        };
        s += &format!("; wrote {}/{{fit.json,params.json{curves}}}", d.display());
    }
    s.push('\n');
    s
}

/// A spinner on stderr while the fit's files and report are written (at 1M × 3 that takes ~10 s
/// and showed nothing): hidden when `enabled` is false (`--no-progress`) and, by indicatif,
/// whenever stderr is not a terminal, so piped output and tests never see it.
/// `rows`: curves.csv's rows.
pub fn writing_spinner(enabled: bool, rows: usize) -> indicatif::ProgressBar {
    if !enabled {
        return indicatif::ProgressBar::hidden();
    }
    let bar = indicatif::ProgressBar::new_spinner();
    if bar.is_hidden() {
        return bar;
    }
    bar.set_style(
        indicatif::ProgressStyle::with_template("{spinner} {msg} {elapsed}")
            .unwrap_or_else(|_| indicatif::ProgressStyle::default_spinner()),
    );
    bar.set_message(format!(
        "writing fit.json, curves.csv ({rows} rows) and the report"
    ));
    bar.enable_steady_tick(std::time::Duration::from_millis(200));
    bar
}

#[cfg(test)]
mod progress_tests {
    use std::io::IsTerminal;

    #[test]
    fn the_writing_spinner_shows_only_on_a_terminal_and_never_with_no_progress() {
        assert!(super::writing_spinner(false, 10).is_hidden());
        let bar = super::writing_spinner(true, 10);
        assert_eq!(bar.is_hidden(), !std::io::stderr().is_terminal());
        bar.finish_and_clear();
    }
}

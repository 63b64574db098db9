//! The ledger's output: the Pareto front of each section, the terminal table, and the files
//! cost.csv, cost.json and cost.svg/png.

use std::path::Path;

use super::figure::CostFigure;
use super::{CostLedger, CostRow};
use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::plot::{render, FigureInfo};

/// Mark each section's Pareto front of (time, rms error): no other row of the section is at
/// least as fast and as accurate and strictly better in one. A row without an error (another
/// model, a yardstick) is on no front.
pub fn mark_pareto(rows: &mut [CostRow]) {
    let snapshot = rows.to_vec();
    for r in rows.iter_mut() {
        r.pareto = r.error_rms.is_finite()
            && !snapshot.iter().any(|o| {
                o.section == r.section
                    && o.time_s <= r.time_s
                    && o.error_rms <= r.error_rms
                    && (o.time_s < r.time_s || o.error_rms < r.error_rms)
            });
    }
}

/// The ledger as a table for the terminal.
pub fn summary_text(ledger: &CostLedger) -> String {
    let mut s = format!(
        "{:<9} {:<24} {:<44} {:>11} {:>10} {:>10}  pareto  worst at\n",
        "section", "knob", "setting", "time (s)", "max err", "rms err"
    );
    for r in &ledger.rows {
        s.push_str(&format!(
            "{:<9} {:<24} {:<44} {:>11.3e} {:>10.2e} {:>10.2e}  {:<6}  {}\n",
            r.section,
            r.knob,
            r.setting,
            r.time_s,
            r.error_max,
            r.error_rms,
            if r.pareto { "yes" } else { "" },
            r.worst_at
        ));
    }
    s.push_str(&format!(
        "{} threads, seed {}, {:.1} s in all\n",
        ledger.threads, ledger.seed, ledger.wall_time_s
    ));
    s
}

/// Write the ledger's files.
pub(super) fn write_ledger(out: &Path, ledger: &CostLedger) -> Result<FigureInfo> {
    let csv_path = out.join("cost.csv");
    write_atomically(&csv_path, |w| {
        let mut writer = csv::Writer::from_writer(w);
        for r in &ledger.rows {
            writer
                .serialize(r)
                .map_err(|e| Error::Other(format!("{}: {e}", csv_path.display())))?;
        }
        writer.flush().map_err(|e| Error::io(&csv_path, e))
    })?;
    let json_path = out.join("cost.json");
    write_atomically(&json_path, |w| {
        let mut v = serde_json::to_value(ledger)
            .map_err(|e| Error::Other(format!("{}: {e}", json_path.display())))?;
        // Non-finite numbers become null (serde_json already does; kept explicit for readers).
        scrub_non_finite(&mut v);
        serde_json::to_writer_pretty(&mut *w, &v)
            .map_err(|e| Error::Other(format!("{}: {e}", json_path.display())))?;
        w.write_all(b"\n").map_err(|e| Error::io(&json_path, e))
    })?;
    render(
        out,
        &CostFigure {
            rows: ledger.rows.clone(),
            quick: ledger.quick,
        },
    )
}

fn scrub_non_finite(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Array(a) => a.iter_mut().for_each(scrub_non_finite),
        serde_json::Value::Object(o) => o.values_mut().for_each(scrub_non_finite),
        serde_json::Value::Number(n) if n.as_f64().is_some_and(|x| !x.is_finite()) => {
            *v = serde_json::Value::Null;
        }
        _ => {}
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(section: &str, t: f64, e: f64) -> CostRow {
        CostRow {
            section: section.into(),
            knob: "k".into(),
            setting: "s".into(),
            time_s: t,
            error_max: e,
            error_rms: e,
            worst_at: String::new(),
            pareto: false,
        }
    }

    #[test]
    fn pareto_front_keeps_only_undominated_rows_per_section() {
        let mut rows = vec![
            row("a", 1.0, 1.0),
            row("a", 2.0, 0.5),
            row("a", 3.0, 0.6),      // dominated by (2, 0.5)
            row("a", 2.0, 0.5),      // tie: neither strictly better, both stay
            row("b", 10.0, 10.0),    // alone in its section
            row("c", 1.0, f64::NAN), // no error: on no front
        ];
        mark_pareto(&mut rows);
        let flags: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(flags, [true, true, false, true, true, false]);
    }
}

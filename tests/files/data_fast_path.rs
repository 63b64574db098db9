//! The fast CSV path (large blocks parsed in parallel pieces, eval's hand-split lines) against
//! the csv crate's path, which the readers take from the first quote on: the same dataset,
//! report, errors (file, line, column) and eval output, bit for bit, on files several blocks
//! long with rejections, blanks, comments and CRLF lines spread through them.

use crate::support::cli;

use std::fmt::Write as _;
use std::path::Path;

use cli::{s, write};
use hairfit::data::{load, LoadOptions};

/// Rows: enough for more than one 8 MiB block of the loader.
const ROWS: usize = 140_000;

/// A CSV whose line 3 is a comment: `# "quoted"` sends the whole file through the csv crate,
/// `# plain` lets the fast path read it. `late` replaces the text of one late data row.
fn table(quoted_comment: bool, late: Option<(usize, &str)>) -> String {
    let mut text = String::from("# angles: deg\n");
    text.push_str("theta_i,phi_i,theta_r,phi_r,radiance_r,radiance_g,note,sigma_r,sigma_g\n");
    text.push_str(if quoted_comment {
        "# a \"quoted\" comment\n"
    } else {
        "# a plain comment\n"
    });
    let mut h: u64 = 0x9E37_79B9_7F4A_7C15;
    for i in 0..ROWS {
        h ^= h << 13;
        h ^= h >> 7;
        h ^= h << 17;
        if let Some((at, row)) = late {
            if i == at {
                text.push_str(row);
                text.push('\n');
                continue;
            }
        }
        let theta_i = (i % 161) as f64 - 80.0;
        let theta_r = ((i / 161) % 100) as f64 - 50.5;
        let phi_r = (h % 7200) as f64 / 10.0 - 360.0;
        let value = (h >> 12) as f64 / (1u64 << 52) as f64;
        let _ = match i % 997 {
            // Rejections of every kind, blank and comment lines, CRLF endings, odd spacing.
            1 => writeln!(text, "{theta_i},0,{theta_r},{phi_r},?,1e-3,x,0.1,0.1"),
            2 => writeln!(text, "95,0,{theta_r},{phi_r},0.5,0.25,x,0.1,0.1"),
            3 => writeln!(text, "{theta_i},0,{theta_r},{phi_r},inf,0.25,x,0.1,0.1"),
            4 => writeln!(text, "{theta_i},0,{theta_r},{phi_r},0.5,0.25,x,0,0.1"),
            5 => writeln!(text, "\n   \n# note\r"),
            6 => writeln!(
                text,
                " {theta_i} ,0,{theta_r},{phi_r}, {value:e} ,0.5,x,0.1,0.1\r"
            ),
            7 => writeln!(text, "{theta_i},0,{theta_r},{phi_r},-0.0,.5,,0.1,0.1"),
            _ => writeln!(
                text,
                "{theta_i},{},{theta_r},{phi_r},{value},{:?},id{i},0.{},0.05",
                i % 3,
                value * 0.7,
                1 + i % 9
            ),
        };
    }
    // Duplicates of earlier rows (same line text) at the end.
    text.push_str("-80,0,-50.5,1.5,0.1,0.2,x,0.1,0.1\n-80,0,-50.5,1.5,0.1,0.2,x,0.1,0.1\n");
    text
}

/// Load `text` from `path` and describe the outcome fully (dataset, report, or error text).
fn outcome(path: &Path, text: &str) -> String {
    std::fs::write(path, text).unwrap();
    match load(path, &LoadOptions::default()) {
        Ok((ds, report)) => format!(
            "{ds:?}\n{}",
            serde_json::to_string(&report).expect("report serializes")
        ),
        Err(e) => format!("error: {e}"),
    }
}

#[test]
fn fast_loader_gives_the_csv_crates_dataset_and_report() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("table.csv");
    let fast_text = table(false, None);
    assert!(fast_text.len() > 9 << 20, "the file spans several blocks");
    let fast = outcome(&path, &fast_text);
    let csv = outcome(&path, &table(true, None));
    assert!(
        !fast.starts_with("error"),
        "{}",
        &fast[..fast.len().min(500)]
    );
    assert!(fast == csv, "the fast path's dataset or report differs");
    // The report accounts for the planted rejections (not a vacuous comparison).
    let (_, report) = load(&path, &LoadOptions::default()).unwrap();
    assert!(report.rejected_total() >= 4 * (ROWS / 997) as u64);
    assert!(report.accepted > (ROWS as u64) * 9 / 10);
}

#[test]
fn fast_loader_reports_a_late_error_at_the_same_line_and_column() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("table.csv");
    let late = ROWS - 1234;
    for bad in [
        "1,2,3,4,0.5,0.5x,x,0.1,0.1",
        "1,2,3,4,0.5,0.5,x,0.1",
        "1,2,3,4,0.5,0.5,x,0.1,0.1,9",
        "1,2,3,4,\u{fe}0.5,0.5,x,0.1,0.1",
    ] {
        let fast = outcome(&path, &table(false, Some((late, bad))));
        let csv = outcome(&path, &table(true, Some((late, bad))));
        assert!(fast.starts_with("error"), "{bad}: {}", &fast[..200]);
        assert_eq!(fast, csv, "{bad}");
        // Line: 3 preamble lines, `late` rows before it, and 2 more lines for every planted
        // blank/comment triple (which stands in for a row).
        let extra = 2 * (0..late).filter(|i| i % 997 == 5).count();
        let line = 3 + late + extra + 1;
        assert!(
            fast.contains(&format!("table.csv:{line}:")),
            "{bad}: {fast} (expected line {line})"
        );
    }
}

#[test]
fn a_quote_in_a_late_block_switches_to_the_csv_crate_without_changing_anything() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("table.csv");
    let late = ROWS - 10;
    // A quoted field holding the delimiter and a line break: only the csv crate reads it.
    let row = "10,0,20,30,0.5,0.25,\"a, b\nc\",0.1,0.1";
    let mixed = outcome(&path, &table(false, Some((late, row))));
    let csv = outcome(&path, &table(true, Some((late, row))));
    assert!(!mixed.starts_with("error"), "{}", &mixed[..200]);
    assert_eq!(mixed, csv);
}

/// Angles rows for eval, with a quoted id field in row `quoted_at` (if any).
fn angles_table(quoted_at: Option<usize>) -> String {
    let mut text = String::from("\u{feff}theta_i,phi_i,theta_r,phi_r,id\r\n");
    for i in 0..40_000usize {
        let t = -80.0 + 160.0 * (i as f64 / 40_000.0);
        let id = if Some(i) == quoted_at {
            "\"x, \"\"y\"\"\"".to_string()
        } else {
            format!("r{i}")
        };
        let _ = write!(text, "{t},{},{},{},{id}", i % 360, -t / 2.0, (i * 7) % 360);
        text.push_str(if i % 5 == 0 { "\r\n" } else { "\n" });
        if i % 1000 == 7 {
            text.push_str("# comment\n\n");
        }
    }
    text
}

#[test]
fn eval_output_is_the_same_on_the_fast_and_the_csv_path() {
    let dir = tempfile::tempdir().unwrap();
    let params = cli::shipped("true_rgb.json");
    let run = |name: &str, text: &str| {
        let input = write(dir.path(), name, text);
        let out_path = dir.path().join(format!("{name}.out"));
        cli::hairfit_ok(&[
            "eval",
            "--params",
            s(&params),
            "--input",
            s(&input),
            "--output",
            s(&out_path),
        ]);
        std::fs::read_to_string(out_path).unwrap()
    };
    // A quote in the first row: the csv crate reads everything; late: the switch mid-file.
    let early = run("early.csv", &angles_table(Some(0)));
    let late = run("late.csv", &angles_table(Some(39_000)));
    let lines_early: Vec<&str> = early.lines().collect();
    let lines_late: Vec<&str> = late.lines().collect();
    assert_eq!(lines_early.len(), 40_001);
    assert_eq!(lines_late.len(), 40_001);
    assert_eq!(lines_early[0], "theta_i,phi_i,theta_r,phi_r,id,s_0,s_1,s_2");
    // Quoted fields are written back quoted, exactly as the csv crate writes them.
    assert!(lines_early[1].contains(",\"x, \"\"y\"\"\","));
    assert!(lines_late[39_001].contains(",\"x, \"\"y\"\"\","));
    for (i, (a, b)) in lines_early.iter().zip(&lines_late).enumerate().skip(2) {
        if i != 39_001 {
            assert_eq!(a, b, "line {i}");
        }
    }
    // Same values with the ids unquoted (fast path throughout).
    let plain = run("plain.csv", &angles_table(None));
    let plain: Vec<&str> = plain.lines().collect();
    assert_eq!(plain[2..], lines_early[2..]);
}

#[test]
fn eval_errors_name_the_same_line_on_both_paths() {
    let dir = tempfile::tempdir().unwrap();
    let params = cli::shipped("true_rgb.json");
    for quoted in [false, true] {
        let mut text = angles_table(quoted.then_some(3));
        text.push_str("1,2,x3,4,z\n");
        let input = write(dir.path(), "bad.csv", &text);
        let out = cli::hairfit(&["eval", "--params", s(&params), "--input", s(&input)]);
        // 1 header line, 40 000 rows, two extra lines after every thousandth row.
        cli::assert_fails_with(&out, &["bad.csv:40082:3", "x3"]);
    }
}

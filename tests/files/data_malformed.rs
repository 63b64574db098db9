//! Malformed and hostile input: every case either fails with an error naming file, line and
//! column, or loads with a correct report — never a panic. Ends with a byte fuzzer.

use crate::support::cli;

use cli::write;

use hairfit::data::{load, Dataset, Format, LoadOptions, LoadReport, RejectReason::*};
use proptest::prelude::*;

const HEADER: &str = "theta_i,phi_i,theta_r,phi_r,radiance\n";

/// Load `content` saved as `name`, expecting an error at `line:column`; returns the message.
fn expect_error(name: &str, content: &[u8], line: u64, column: u64) -> String {
    expect_error_with(name, content, &LoadOptions::default(), line, column)
}

fn expect_error_with(
    name: &str,
    content: &[u8],
    options: &LoadOptions,
    line: u64,
    column: u64,
) -> String {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), name, content);
    let msg = match load(&p, options) {
        Ok((_, r)) => panic!("{name}: expected an error, got a report:\n{r}"),
        Err(e) => e.to_string(),
    };
    let place = format!("{}:{line}:{column}:", p.display());
    assert!(msg.starts_with(&place), "want `{place}` in: {msg}");
    msg
}

fn expect_report(name: &str, content: &[u8]) -> (Dataset, LoadReport) {
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), name, content);
    let (ds, r) = load(&p, &LoadOptions::default()).unwrap_or_else(|e| panic!("{name}: {e}"));
    assert_eq!(r.rows_read, r.accepted + r.rejected_total());
    (ds, r)
}

/// A quote that is never closed takes in every line after it: the error names the line and
/// column where it opened (after a comment line, with `\n` or `\r\n`, with or without a last
/// newline), not the end of the file nor "found 2 fields".
#[test]
fn an_unclosed_quote_names_where_it_opened() {
    for (ending, last) in [("\n", "\n"), ("\r\n", "\r\n"), ("\n", "")] {
        let text = format!(
            "{}1,2,3,4,5{ending}# note{ending}1,\"2,3,4,5{ending}6,7,8,9,10{ending}1,2,3,4,5{last}",
            HEADER.replace('\n', ending)
        );
        let msg = expect_error("quote.csv", text.as_bytes(), 4, 2);
        assert!(msg.contains("runs on to line 6"), "{msg}");
        assert!(msg.contains("close the quote"), "{msg}");
    }
    // A quoted field that legitimately spans lines is fine; a later short row gets the plain
    // message at its own line.
    let text = format!("{HEADER}1,2,3,4,\"5\n\"\n1,2,3,4\n");
    let msg = expect_error("spans.csv", text.as_bytes(), 4, 5);
    assert!(msg.contains("expected 5 fields"), "{msg}");
}

#[test]
fn truncated_mid_row_names_the_line_and_first_missing_column() {
    let msg = expect_error(
        "t.csv",
        format!("{HEADER}1,2,3,4,5\n1,2,3").as_bytes(),
        3,
        4,
    );
    assert!(
        msg.contains("expected 5 fields") && msg.contains("found 3"),
        "{msg}"
    );
}

#[test]
fn truncated_mid_number_is_an_unparseable_cell() {
    let msg = expect_error(
        "t.csv",
        format!("{HEADER}1,2,3,4,5\n1,2,3,4,1e").as_bytes(),
        3,
        5,
    );
    assert!(msg.contains("`1e` is not a number"), "{msg}");
}

#[test]
fn unparseable_cell_is_an_error_not_a_rejection() {
    let msg = expect_error("t.csv", format!("{HEADER}1,2,x3,4,5\n").as_bytes(), 2, 3);
    assert!(msg.contains("column `theta_r`"), "{msg}");
}

#[test]
fn too_many_fields_points_past_the_header_width() {
    expect_error("t.csv", format!("{HEADER}1,2,3,4,5,6\n").as_bytes(), 2, 6);
}

#[test]
fn binary_garbage_is_an_error() {
    let garbage: Vec<u8> = (0..512u32)
        .map(|i| (i.wrapping_mul(2_654_435_761) >> 13) as u8)
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "g.csv", &garbage);
    let msg = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}:", p.display())), "{msg}");
    // Also as JSON and as a scan.
    let p = write(dir.path(), "g.json", &garbage);
    let msg = load(&p, &LoadOptions::default()).unwrap_err().to_string();
    assert!(msg.starts_with(&format!("{}:1:", p.display())), "{msg}");
}

/// UTF-16 (what Excel saves as "Unicode text"), with either byte-order mark or none, is named
/// with the fix, for a CSV, a JSON dataset and a scan, not read as a header of NUL-separated
/// letters ("missing columns").
#[test]
fn utf16_text_is_named_with_the_fix() {
    let text = format!("{HEADER}10,0,-10,30,1.5\n");
    let units: Vec<u16> = text.encode_utf16().collect();
    let le: Vec<u8> = units.iter().flat_map(|u| u.to_le_bytes()).collect();
    let be: Vec<u8> = units.iter().flat_map(|u| u.to_be_bytes()).collect();
    let cases = [
        ("le_bom.csv", [&b"\xFF\xFE"[..], &le].concat()),
        ("be_bom.csv", [&b"\xFE\xFF"[..], &be].concat()),
        ("le.csv", le.clone()),
        ("le.json", le),
    ];
    for (name, bytes) in cases {
        let msg = expect_error(name, &bytes, 1, 1);
        assert!(
            msg.contains("UTF-16") && msg.contains("iconv"),
            "{name}: {msg}"
        );
    }
    // The check reads the first line only: a NUL in a later line is that line's error.
    let msg = expect_error(
        "late_nul.csv",
        format!("{HEADER}10,0,-10,30,1\x00\n").as_bytes(),
        2,
        5,
    );
    assert!(!msg.contains("UTF-16"), "{msg}");
}

/// A decimal comma (a `;` table from a German or French locale) is named with its fix; a cell
/// with two commas is not taken for one.
#[test]
fn a_decimal_comma_is_named_with_its_fix() {
    let options = LoadOptions {
        delimiter: Some(";".into()),
        ..LoadOptions::default()
    };
    let text = "theta_i;phi_i;theta_r;phi_r;radiance\n10;0;-10;30;1,5\n";
    let msg = expect_error_with("de.csv", text.as_bytes(), &options, 2, 5);
    assert!(
        msg.contains("`1,5` looks like a decimal comma: write `1.5`"),
        "{msg}"
    );
    let text = "theta_i;phi_i;theta_r;phi_r;radiance\n10;0;-10;30;1,500,000\n";
    let msg = expect_error_with("thousands.csv", text.as_bytes(), &options, 2, 5);
    assert!(!msg.contains("decimal comma"), "{msg}");
}

#[test]
fn non_utf8_cell_names_its_column() {
    let mut content = format!("{HEADER}1,2,3,4,5\n1,2,").into_bytes();
    content.extend_from_slice(b"\xff\xfe,4,5\n");
    let msg = expect_error("u.csv", &content, 3, 3);
    assert!(msg.contains("not UTF-8"), "{msg}");
}

#[test]
fn empty_file_and_header_only_have_no_data_rows() {
    let msg = expect_error("e.csv", b"", 1, 1);
    assert!(msg.contains("no data rows"), "{msg}");
    let msg = expect_error("h.csv", HEADER.as_bytes(), 1, 1);
    assert!(msg.contains("no data rows"), "{msg}");
    let msg = expect_error(
        "h.csv",
        format!("# c\n\n{HEADER}\n# only comments\n").as_bytes(),
        3,
        1,
    );
    assert!(msg.contains("no data rows"), "{msg}");
    let msg = expect_error("e.json", b"", 1, 1);
    assert!(msg.contains("no data rows"), "{msg}");
    let msg = expect_error("e.json", b"{\"samples\": []}", 1, 1);
    assert!(msg.contains("no data rows"), "{msg}");
    let scan = LoadOptions {
        columns: vec!["phi_r".into(), "theta_r".into(), "radiance".into()],
        fixed: vec!["theta_i=0".into(), "phi_i=0".into()],
        ..LoadOptions::default()
    };
    let msg = expect_error_with("e.txt", b"# nothing\n\n", &scan, 2, 1);
    assert!(msg.contains("no data rows"), "{msg}");
}

#[test]
fn one_column_file_says_which_columns_are_required_and_found() {
    let msg = expect_error("one.csv", b"radiance\n1\n2\n", 1, 1);
    assert!(
        msg.contains("no `theta_i` column")
            && msg.contains("required")
            && msg.contains("found: `radiance`"),
        "{msg}"
    );
    let msg = expect_error("one.csv", format!("{HEADER}7\n").as_bytes(), 2, 2);
    assert!(msg.contains("found 1"), "{msg}");
}

#[test]
fn semicolon_separated_header_gets_a_hint() {
    let msg = expect_error(
        "semi.csv",
        b"theta_i;phi_i;theta_r;phi_r;radiance\n1;2;3;4;5\n",
        1,
        1,
    );
    assert!(msg.contains("give --delimiter"), "{msg}");
}

#[test]
fn header_mistakes_name_the_column() {
    let msg = expect_error(
        "d.csv",
        b"theta_i,phi_i,theta_r,phi_r,radiance,phi_i\n1,2,3,4,5,6\n",
        1,
        6,
    );
    assert!(msg.contains("appears twice"), "{msg}");
    let msg = expect_error(
        "d.csv",
        b"theta_i,phi_i,theta_r,phi_r,value\n1,2,3,4,5\n",
        1,
        1,
    );
    assert!(
        msg.contains("no radiance column") && msg.contains("`value`"),
        "{msg}"
    );
    let msg = expect_error(
        "d.csv",
        b"theta_i,phi_i,theta_r,phi_r,radiance_r,sigma_g\n1,2,3,4,5,6\n",
        1,
        6,
    );
    assert!(msg.contains("no matching `radiance_g`"), "{msg}");
}

#[test]
fn huge_numbers_nan_and_inf() {
    let content = format!(
        "{HEADER}1,0,2,0,1e308\n1,0,2,1,1e999\n1,0,2,2,NaN\n1,0,2,3,inf\n1,0,2,4,-Infinity\n\
         1e999,0,2,5,1\n1,0,2,6,-1e308\n"
    );
    let (ds, r) = expect_report("h.csv", content.as_bytes());
    assert_eq!(r.rows_read, 7);
    assert_eq!(r.rejected_count(NonFinite), 5);
    assert_eq!(r.rejected[&NonFinite].first_lines, [3, 4, 5, 6, 7]);
    assert_eq!(ds.radiance, [1e308, -1e308]);
    assert_eq!(r.negative_kept.first_lines, [8]);
}

#[test]
fn blank_and_whitespace_lines_are_not_rows_but_count_as_lines() {
    let content = format!("\n\n{HEADER}\n1,0,2,0,1\n   \n\t\n1,0,2,1,?\n\n");
    let (ds, r) = expect_report("b.csv", content.as_bytes());
    assert_eq!(r.rows_read, 2);
    assert_eq!(ds.source_line, [5]);
    assert_eq!(r.rejected[&MissingValue].first_lines, [8]);
}

#[test]
fn bom_and_crlf_load_like_plain_lf() {
    let plain = format!("# note\n{HEADER}1,0,2,0,1\n\n1,0,2,0,1\n1,0,95,0,3\n");
    let (ds_lf, r_lf) = expect_report("lf.csv", plain.as_bytes());
    let mut crlf = b"\xEF\xBB\xBF".to_vec();
    crlf.extend_from_slice(plain.replace('\n', "\r\n").as_bytes());
    let (ds_crlf, r_crlf) = expect_report("crlf.csv", &crlf);
    assert_eq!(ds_lf.source_line, [3]);
    assert_eq!(r_lf.duplicate_of, [[5, 3]]);
    assert_eq!(r_lf.rejected[&ThetaOutOfRange].first_lines, [6]);
    assert_eq!(ds_crlf, ds_lf);
    assert_eq!(r_crlf.rejected, r_lf.rejected);
    assert_eq!(r_crlf.duplicate_of, r_lf.duplicate_of);
    // A BOM directly before the header, without a comment line.
    let mut bom = b"\xEF\xBB\xBF".to_vec();
    bom.extend_from_slice(format!("{HEADER}1,0,2,0,1\n").as_bytes());
    let (_, r) = expect_report("bom.csv", &bom);
    assert_eq!(r.accepted, 1);
}

#[test]
fn malformed_json_names_line_and_column() {
    let msg = expect_error("t.json", b"{\"samples\": [\n  {\"theta_i\": 1,", 2, 16);
    assert!(msg.contains("EOF"), "{msg}");
    let msg = expect_error(
        "w.json",
        b"{\"samples\": [\n  {\"theta_i\": \"ten\", \"phi_i\": 0}\n]}",
        2,
        19,
    );
    assert!(msg.contains("invalid type"), "{msg}");
    let msg = expect_error(
        "c.json",
        b"{\"samples\": [\n{\"theta_i\":1,\"phi_i\":0,\"theta_r\":2,\"phi_r\":0,\"radiance\":1},\n  {\"theta_i\":1,\"phi_i\":0,\"theta_r\":2,\"phi_r\":1,\"radiance\":[1,2]}\n]}",
        3,
        3,
    );
    assert!(msg.contains("no \"channels\""), "{msg}");
}

#[test]
fn malformed_scans_name_line_and_column() {
    let scan = LoadOptions {
        columns: vec!["phi_r".into(), "theta_r".into(), "radiance".into()],
        fixed: vec!["theta_i=0".into(), "phi_i=0".into()],
        ..LoadOptions::default()
    };
    let msg = expect_error_with("s.txt", b"1 2 3\n# c\n4 5\n", &scan, 3, 3);
    assert!(msg.contains("expected 3 columns"), "{msg}");
    let msg = expect_error_with("s.txt", b"1 2 3\n4 5 six\n", &scan, 2, 3);
    assert!(msg.contains("`six` is not a number"), "{msg}");
    // Empty cell between commas is a missing value, not an error.
    let dir = tempfile::tempdir().unwrap();
    let p = write(dir.path(), "s.txt", b"1,2,\r\n1,3,4\r\n");
    let (_, r) = load(&p, &scan).unwrap();
    assert_eq!(r.rejected[&MissingValue].first_lines, [1]);
    assert_eq!(r.accepted, 1);
}

#[test]
fn scan_only_options_on_csv_are_refused() {
    let options = LoadOptions {
        format: Some(Format::Csv),
        fixed: vec!["theta_i=0".into()],
        ..LoadOptions::default()
    };
    let dir = tempfile::tempdir().unwrap();
    let p = write(
        dir.path(),
        "x.csv",
        format!("{HEADER}1,2,3,4,5\n").as_bytes(),
    );
    let msg = load(&p, &options).unwrap_err().to_string();
    assert!(
        msg.contains("--fixed applies to headerless scan files only"),
        "{msg}"
    );
}

/// Cells a near-valid CSV row is built from: numbers, missing tokens, literals, garbage.
fn cell() -> impl Strategy<Value = String> {
    prop_oneof![
        60 => (-120i32..120).prop_map(|v| v.to_string()),
        30 => (-1e3f64..1e3).prop_map(|v| v.to_string()),
        3 => Just("?".to_string()),
        3 => Just(String::new()),
        3 => prop_oneof![Just("NaN"), Just("inf"), Just("1e999"), Just("-0"), Just("1e308")]
            .prop_map(String::from),
        // Rare, since one unparseable cell makes the whole file an error.
        1 => prop_oneof![Just("abc"), Just("\"3\""), Just("1,"), Just("#"), Just("\""), Just(" 5 ")]
            .prop_map(String::from),
    ]
}

/// A near-valid CSV: a header (sometimes damaged) and rows that mostly match its width, with
/// blank lines, comments and CRLF mixed in.
fn near_valid_csv() -> impl Strategy<Value = Vec<u8>> {
    let header = prop_oneof![
        8 => Just(("theta_i,phi_i,theta_r,phi_r,radiance", 5)),
        2 => Just(("theta_i,phi_i,theta_r,phi_r,radiance,sigma", 6)),
        1 => Just(("theta_i,phi_i,theta_r,radiance", 4)),
        1 => Just(("\u{feff}theta_i,phi_i,theta_r,phi_r,radiance_r,radiance_g", 6)),
    ];
    (header, any::<bool>())
        .prop_flat_map(|((h, width), crlf)| {
            let row = prop_oneof![
                40 => prop::collection::vec(cell(), width..=width).prop_map(|c| c.join(",")),
                1 => prop::collection::vec(cell(), 1..8).prop_map(|c| c.join(",")),
                2 => Just(String::new()),
                2 => Just("# comment".to_string()),
            ];
            (Just((h, crlf)), prop::collection::vec(row, 0..20))
        })
        .prop_map(|((h, crlf), rows)| {
            let eol = if crlf { "\r\n" } else { "\n" };
            let mut s = h.to_string() + eol;
            for r in rows {
                s.push_str(&r);
                s.push_str(eol);
            }
            s.into_bytes()
        })
}

/// Load `bytes` as every format; never panic, and any report must account for every row.
/// Returns how many of the loads gave a report rather than an error.
fn load_all_ways(bytes: &[u8]) -> Result<usize, TestCaseError> {
    let mut reports = 0;
    let dir = tempfile::tempdir().unwrap();
    let scan = LoadOptions {
        columns: vec!["phi_r".into(), "theta_r".into(), "radiance".into()],
        fixed: vec!["theta_i=10".into(), "phi_i=0".into()],
        ..LoadOptions::default()
    };
    for (name, options) in [
        ("f.csv", LoadOptions::default()),
        ("f.json", LoadOptions::default()),
        ("f.txt", scan),
    ] {
        let p = write(dir.path(), name, bytes);
        match load(&p, &options) {
            Ok((ds, r)) => {
                reports += 1;
                prop_assert_eq!(r.rows_read, r.accepted + r.rejected_total());
                prop_assert_eq!(r.accepted as usize, ds.len());
                prop_assert!(ds
                    .theta_i
                    .iter()
                    .all(|t| t.abs() < std::f64::consts::FRAC_PI_2));
                prop_assert!(ds.radiance.iter().all(|v| v.is_finite()));
            }
            Err(e) => {
                let msg = e.to_string();
                // Input errors carry the file name; option errors do not apply to these cases.
                prop_assert!(msg.contains(&p.display().to_string()), "{}", msg);
            }
        }
    }
    Ok(reports)
}

proptest! {
    // Bounded so the suite stays a few seconds: each case writes and loads three small files.
    #![proptest_config(ProptestConfig::with_cases(300))]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        load_all_ways(&bytes)?;
    }
}

#[test]
fn near_valid_csv_never_panics_and_accounts() {
    use std::sync::atomic::{AtomicUsize, Ordering};
    let cases = 300;
    let mut runner = proptest::test_runner::TestRunner::new(ProptestConfig::with_cases(cases));
    let reports = AtomicUsize::new(0);
    runner
        .run(&near_valid_csv(), |bytes| {
            reports.fetch_add(load_all_ways(&bytes)?, Ordering::Relaxed);
            Ok(())
        })
        .unwrap();
    // The fuzzer must reach the accounting code, not only the error paths: at least a third of
    // the cases (one CSV load each) should load; about half do (162 of 300 in one run).
    let n = reports.load(Ordering::Relaxed);
    assert!(
        n >= cases as usize / 3,
        "only {n} of {cases} cases gave a report"
    );
}

//! `hairfit::eval::eval_stream_with` on rows each reading path takes (the in-place fast path, a
//! line split at its commas, the csv crate after a quote): every row's text reaches the output
//! as it was read, and a non-finite value is an error that quotes its row, never a `NaN` in the
//! output. The model here is a stand-in, so the row a value belongs to is known exactly.

use std::path::Path;

use hairfit::eval::{eval_stream_with, output_columns, EvalRequest};
use hairfit::families::{FamilyModel, FamilyParams, ModelFamily};
use hairfit::geometry::Angles;

fn request() -> EvalRequest {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("data/example_params.json");
    let file = FamilyParams::load(&path, ModelFamily::Marschner).unwrap();
    EvalRequest {
        output_columns: output_columns(file.n_channels(), file.sigma_a_is_scalar()),
        model: FamilyModel::new(&file, &Default::default()),
        params: file,
        angles: None,
    }
}

/// θ_r (radians) as every channel's value; NaN where θ_r is 44°.
fn stand_in(angles: &[Angles], out: &mut [f64]) {
    let nc = out.len() / angles.len();
    for (a, row) in angles.iter().zip(out.chunks_mut(nc)) {
        let v = if a.theta_r == radians(44.0) {
            f64::NAN
        } else {
            a.theta_r
        };
        row.fill(v);
    }
}

/// θ_r (degrees) in radians, as the model sees it.
fn radians(theta_r: f64) -> f64 {
    Angles::from_degrees(0.0, 0.0, theta_r, 0.0).theta_r
}

/// `rows` data lines: most plain, some with a space (the split path), and, from `quote_at` on,
/// a quoted label (the csv crate reads the rest).
fn table(rows: usize, quote_at: Option<usize>, bad_at: Option<usize>) -> String {
    let mut text = String::from("theta_i,phi_i,theta_r,phi_r,label\n");
    for i in 0..rows {
        let theta_r = if Some(i) == bad_at {
            44.0
        } else {
            (i % 80) as f64 + 0.25
        };
        let label = match quote_at {
            Some(q) if i == q => format!("\"row, {i}\""),
            _ if i % 7 == 3 => format!(" r{i}"),
            _ => format!("r{i}"),
        };
        text.push_str(&format!(
            "{},{},{theta_r},{},{label}\n",
            -(i as f64 % 60.0),
            i % 300,
            i % 50
        ));
    }
    text
}

fn run(text: &str) -> hairfit::error::Result<String> {
    let mut out = Vec::new();
    eval_stream_with(
        text.as_bytes(),
        Path::new("rows.csv"),
        &mut out,
        &request(),
        &stand_in,
    )?;
    Ok(String::from_utf8(out).unwrap())
}

/// 60,000 rows (about 1.4 MB: a 1 MiB block and part of a second, four evaluation chunks): each
/// output line is its input line and then θ_r (radians, shortest round-trip text) three times,
/// on the fast path, the split path and, with a quote in row 50,000 (the second block), after
/// the csv crate takes over mid-file.
#[test]
fn every_row_keeps_its_text_and_gets_its_own_value() {
    let rows = 60_000;
    for quote_at in [None, Some(50_000)] {
        let text = table(rows, quote_at, None);
        let output = run(&text).unwrap();
        let inputs: Vec<&str> = text.lines().collect();
        let outputs: Vec<&str> = output.lines().collect();
        assert_eq!(outputs.len(), rows + 1);
        assert_eq!(outputs[0], format!("{},s_0,s_1,s_2", inputs[0]));
        for (i, (input, output)) in inputs.iter().zip(&outputs).enumerate().skip(1) {
            let theta_r: f64 = input.split(',').nth(2).unwrap().parse().unwrap();
            let mut digits = ryu::Buffer::new();
            let v = digits.format_finite(radians(theta_r));
            // The csv crate writes a field back as it read it (quoted where it must be).
            let expected = format!("{input},{v},{v},{v}");
            assert_eq!(*output, expected, "line {} (quote at {quote_at:?})", i + 1);
        }
    }
}

/// The error quotes the row the non-finite value belongs to, on each path: a plain row, a row
/// with a space (split path), a row after the csv crate took over in the second block, and a
/// plain row of the second block's last chunk.
#[test]
fn a_non_finite_value_quotes_its_own_row() {
    for (bad_at, quote_at) in [(5, None), (3, None), (55_000, Some(50_000)), (58_001, None)] {
        let text = table(60_000, quote_at, Some(bad_at));
        let row = text.lines().nth(bad_at + 1).unwrap();
        let message = run(&text).unwrap_err().to_string();
        assert!(
            message.contains(&format!("for the row `{}`", row.trim_end())),
            "row {bad_at}: {message}"
        );
        assert!(message.contains("S = NaN"), "{message}");
    }
}

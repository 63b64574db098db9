//! `hairfit fit --curves full|summary|none` through the binary: what curves.csv holds, that
//! fit.json records it, that `report` and `export` work on each, that the streamed full file is
//! the serde form of its rows byte for byte, and that a summary keeps every down-weighted row.

use crate::support::cli;

use std::collections::HashSet;
use std::path::Path;

use cli::{hairfit_ok, s};
use hairfit::files::{read_curves_csv, FitJson, DOWN_WEIGHT};

/// 6000 scattered samples with 2% gross outliers (more samples than a summary's even spread,
/// so the summary really is a subset), fitted three ways.
fn fits(dir: &Path) {
    let data = dir.join("sphere.csv");
    hairfit_ok(&[
        "synth",
        "--params",
        "data/true_1ch.json",
        "--rig",
        "sphere:n=6000:max=85",
        "--noise",
        "relative:0.05+outliers:0.02",
        "--seed",
        "9",
        "--output",
        s(&data),
    ]);
    for mode in ["full", "summary", "none"] {
        hairfit_ok(&[
            "fit",
            s(&data),
            "--loss",
            "cauchy",
            "--starts",
            "4",
            "--intervals",
            "linear",
            "--no-progress",
            "--curves",
            mode,
            "--out",
            s(&dir.join(mode)),
        ]);
    }
}

#[test]
fn curves_modes_write_what_they_say_and_report_and_export_cope() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    fits(dir);
    for mode in ["full", "summary", "none"] {
        let fit = FitJson::load(&dir.join(mode).join("fit.json")).unwrap();
        assert_eq!(fit.options.curves.to_string(), mode);
        assert_eq!(dir.join(mode).join("curves.csv").exists(), mode != "none");
    }

    // Full: every sample, and the streamed text is exactly the csv crate's serde form of the
    // rows it reads back to (the writer before streaming).
    let full_path = dir.join("full/curves.csv");
    let full = read_curves_csv(&full_path).unwrap();
    assert_eq!(full.len(), 6000);
    let mut w = csv::Writer::from_writer(Vec::new());
    for r in &full {
        w.serialize(r).unwrap();
    }
    let full_text = std::fs::read_to_string(&full_path).unwrap();
    assert_eq!(
        String::from_utf8(w.into_inner().unwrap()).unwrap(),
        full_text
    );

    // Summary: a real subset, its lines verbatim from the full file (same fit, same seed), and
    // every down-weighted row kept.
    let summary_path = dir.join("summary/curves.csv");
    let summary = read_curves_csv(&summary_path).unwrap();
    assert!(
        summary.len() < full.len() / 2,
        "summary has {} of {} rows",
        summary.len(),
        full.len()
    );
    let full_lines: HashSet<&str> = full_text.lines().collect();
    let summary_text = std::fs::read_to_string(&summary_path).unwrap();
    assert!(summary_text.lines().all(|l| full_lines.contains(l)));
    // The fit builds only the summary's rows; they are exactly the rows `summary_rows` picks
    // from the whole table (the report's own selection).
    let table = hairfit::files::Curves::from_rows(&full);
    let picked: Vec<(u64, String)> = hairfit::report::summary_rows(&table)
        .into_iter()
        .map(|r| (full[r].sample, full[r].channel.clone()))
        .collect();
    let written: Vec<(u64, String)> = summary
        .iter()
        .map(|r| (r.sample, r.channel.clone()))
        .collect();
    assert_eq!(written, picked);
    let kept: HashSet<(u64, String)> = summary
        .iter()
        .map(|r| (r.sample, r.channel.clone()))
        .collect();
    let outliers: Vec<_> = full.iter().filter(|r| r.weight < DOWN_WEIGHT).collect();
    assert!(outliers.len() > 50, "{} outliers", outliers.len());
    for r in outliers {
        assert!(
            kept.contains(&(r.sample, r.channel.clone())),
            "down-weighted sample {} missing from the summary",
            r.sample
        );
    }

    // The report and the export work on each; without curves the report says why.
    for mode in ["summary", "none"] {
        let out = hairfit_ok(&["report", s(&dir.join(mode))]);
        let html = std::fs::read_to_string(dir.join(mode).join("index.html")).unwrap();
        if mode == "none" {
            assert!(html.contains("--curves none"), "{}", cli::stdout(&out));
            assert!(!dir.join("none/data_vs_fit.svg").exists());
        } else {
            assert!(html.contains("--curves summary"));
            assert!(dir.join("summary/data_vs_fit.svg").exists());
        }
        let exported = dir.join(format!("{mode}.pbrt"));
        let fit_dir = dir.join(mode);
        // The export fits the renderer's model over every measured direction: minutes for
        // the summary's ~2000 on a loaded machine, so a longer bound than one command's.
        let args = [
            "export",
            "--to",
            "pbrt",
            s(&fit_dir),
            "--output",
            s(&exported),
        ];
        cli::succeeded(
            cli::hairfit_within(std::time::Duration::from_secs(900), &args).0,
            &args,
        );
        assert!(std::fs::metadata(&exported).unwrap().len() > 0);
    }

    // A curves.csv removed by hand: the report still draws, and says the file is missing.
    std::fs::remove_file(&full_path).unwrap();
    hairfit_ok(&["report", s(&dir.join("full"))]);
    let html = std::fs::read_to_string(dir.join("full/index.html")).unwrap();
    assert!(html.contains("no curves.csv"));
}

/// Measures (asserts only byte identity) the old and the new curves.csv paths on a real file:
/// `HAIRFIT_CURVES=/tmp/x/curves.csv cargo test --release --test cli curves:: -- --ignored --nocapture`.
/// Old: serde rows through the csv crate (`CurveRow` still derives both); new: [`Curves`].
#[test]
#[ignore]
fn curves_io_speed_old_and_new() {
    use hairfit::files::{CurveRow, Curves};
    use std::time::Instant;
    let Ok(path) = std::env::var("HAIRFIT_CURVES") else {
        eprintln!("set HAIRFIT_CURVES to a curves.csv");
        return;
    };
    let path = Path::new(&path);
    let tmp = tempfile::tempdir().unwrap();
    let t = Instant::now();
    let curves = Curves::read_csv(path).unwrap();
    eprintln!(
        "new read:  {:.2} s, {} rows",
        t.elapsed().as_secs_f64(),
        curves.len()
    );
    let t = Instant::now();
    let new_path = tmp.path().join("new.csv");
    curves.write_csv(&new_path, None).unwrap();
    eprintln!("new write: {:.2} s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let keep = hairfit::report::summary_rows(&curves);
    let summary_path = tmp.path().join("summary.csv");
    curves.write_csv(&summary_path, Some(&keep)).unwrap();
    eprintln!(
        "summary: {:.2} s, {} rows, {} bytes",
        t.elapsed().as_secs_f64(),
        keep.len(),
        std::fs::metadata(&summary_path).unwrap().len()
    );
    drop(curves);
    let t = Instant::now();
    let rows: Vec<CurveRow> = csv::Reader::from_path(path)
        .unwrap()
        .deserialize()
        .collect::<Result<_, _>>()
        .unwrap();
    eprintln!("old read:  {:.2} s", t.elapsed().as_secs_f64());
    let t = Instant::now();
    let old_path = tmp.path().join("old.csv");
    let mut w = csv::Writer::from_writer(std::io::BufWriter::new(
        std::fs::File::create(&old_path).unwrap(),
    ));
    for r in &rows {
        w.serialize(r).unwrap();
    }
    w.flush().unwrap();
    drop(w);
    eprintln!("old write: {:.2} s", t.elapsed().as_secs_f64());
    assert!(
        std::fs::read(&old_path).unwrap() == std::fs::read(&new_path).unwrap(),
        "the new writer's bytes differ from the old writer's"
    );
}

/// `--curves auto` (the default) writes every row up to `AUTO_FULL_CURVES_ROWS` rows and the
/// summary above, and says so in fit.json, on the command line and in the report.
#[test]
fn curves_auto_switches_to_the_summary_above_the_row_limit() {
    let tmp = tempfile::tempdir().unwrap();
    let dir = tmp.path();
    // `n` samples of 3 channels fitted with the default --curves: what it printed, fit.json.
    let synth_and_fit = |name: &str, n: usize| {
        let data = dir.join(format!("{name}.csv"));
        hairfit_ok(&[
            "synth",
            "--params",
            "data/true_rgb.json",
            "--rig",
            &format!("sphere:n={n}:max=60"),
            "--noise",
            "relative:0.05",
            "--seed",
            "4",
            "--output",
            s(&data),
        ]);
        let out = dir.join(name);
        let printed = cli::stdout(&hairfit_ok(&[
            "fit",
            s(&data),
            "--starts",
            "2",
            "--intervals",
            "linear",
            "--no-progress",
            "--out",
            s(&out),
        ]));
        (printed, FitJson::load(&out.join("fit.json")).unwrap())
    };
    // Just over the limit: 3 channels × (limit / 3 + 100) samples.
    let n = hairfit::fit::AUTO_FULL_CURVES_ROWS / 3 + 100;
    let (printed, fit) = synth_and_fit("big", n);
    let out = dir.join("big");
    assert_eq!(fit.options.curves.to_string(), "summary");
    assert!(fit.options.curves_reason.starts_with("auto:"));
    assert!(printed.contains("curves.csv (summary: over"), "{printed}");
    let curves = read_curves_csv(&out.join("curves.csv")).unwrap();
    assert!(curves.len() < 3 * n / 10, "{} rows", curves.len());
    let html = std::fs::read_to_string(out.join("index.html")).unwrap();
    assert!(html.contains("`--curves auto` chose it: "), "{html}");
    // Below the limit the default stays full.
    let (_, fit) = synth_and_fit("small", 3000);
    assert_eq!(fit.options.curves.to_string(), "full");
    assert!(fit.options.curves_reason.is_empty());
}

//! `hairfit export` of a Chiang fit that ran with terms switched off, through the binary: a
//! renderer always renders all four terms, so the export must not pass the fit's parameters on
//! as if it had used them. It refits them to the fit's S and warns, on stderr and in the file's
//! header, with the rms cost of the mismatch before and after the refit. A fit with every term on
//! stays exact and silent.

use crate::support::cli;

use std::path::Path;

use cli::{hairfit_ok, s, stderr, stdout, write};

/// Noise-free Chiang data from `synth` (128 width nodes keep every step to seconds).
fn chiang_data(dir: &Path) -> std::path::PathBuf {
    let truth = write(
        dir,
        "truth.json",
        r#"{"eta": 1.55, "sigma_a": [0.3, 0.5, 0.9], "beta_m": 0.25, "beta_n": 0.35, "alpha_deg": -2.5}"#,
    );
    let data = dir.join("d.csv");
    hairfit_ok(&[
        "synth",
        "--model",
        "chiang",
        "--width-nodes",
        "128",
        "--params",
        s(&truth),
        "--rig",
        "azimuthal:incidences=15,30,45:steps=36",
        "--output",
        s(&data),
    ]);
    data
}

fn fit(data: &Path, out: &Path, terms: &str) {
    hairfit_ok(&[
        "fit",
        s(data),
        "--model",
        "chiang",
        "--terms",
        terms,
        "--width-nodes",
        "128",
        "--starts",
        "2",
        "--intervals",
        "linear",
        "--no-progress",
        "--out",
        s(out),
    ]);
}

/// The first number after `needle` in `text`.
fn number_after(text: &str, needle: &str) -> f64 {
    let rest = &text[text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle}: {text}"))
        + needle.len()..];
    let token: String = rest
        .trim_start()
        .chars()
        .take_while(|c| c.is_ascii_digit() || ".-+e".contains(*c))
        .collect();
    token
        .parse()
        .unwrap_or_else(|_| panic!("{needle} `{token}`: {text}"))
}

#[test]
fn switched_off_terms_are_refitted_and_warned_about_never_exported_silently() {
    let dir = tempfile::tempdir().unwrap();
    let data = chiang_data(dir.path());
    let partial = dir.path().join("r_tt");
    fit(&data, &partial, "R,TT");
    let file = dir.path().join("r_tt.pbrt");
    let out = hairfit_ok(&["export", s(&partial), "--to", "pbrt", "--output", s(&file)]);
    let err = stderr(&out);
    assert!(err.contains("warning:"), "{err}");
    assert!(
        err.contains("terms R+TT only (TRT+residual switched off)"),
        "{err}"
    );
    assert!(err.contains("pbrt always renders all four"), "{err}");
    // The cost of exporting the parameters unchanged, and of the refitted ones written instead:
    // the refit starts from the fit's parameters, so it cannot end worse (up to the 512- vs
    // 1024-node rule the refit and the report use, 1e-3 in ln S).
    let as_is = number_after(&err, "would miss the fit's S by rms |d ln S|");
    let refit = number_after(
        &err,
        "refitted to the fit's S instead and miss it by rms |d ln S|",
    );
    assert!(
        as_is > 0.05,
        "TRT and the residual are visible in S: {as_is}"
    );
    assert!(refit <= as_is + 1e-3, "refit {refit} vs as is {as_is}");
    let text = std::fs::read_to_string(&file).unwrap();
    let header: Vec<&str> = text.lines().take_while(|l| l.starts_with('#')).collect();
    assert!(
        header
            .iter()
            .any(|l| l.starts_with("# WARNING: the fit ran with terms R+TT only")),
        "{header:?}"
    );
    assert!(
        !header.iter().any(|l| l.contains("mapping: exact")),
        "{header:?}"
    );
    assert!(
        header
            .iter()
            .any(|l| l.contains("held by the fit, not fitted from the data: eta = 1.55")),
        "{header:?}"
    );
    // Every renderer says the same (Blender and MaterialX are fitted anyway; the warning is
    // about the terms).
    for to in ["blender", "materialx"] {
        let out = hairfit_ok(&["export", s(&partial), "--to", to]);
        let err = stderr(&out);
        assert!(
            err.contains(&format!("{to} always renders all four")),
            "{to}: {err}"
        );
        assert!(
            stdout(&out).contains("WARNING: the fit ran with terms R+TT only"),
            "{to}"
        );
    }

    // Every term on: the pbrt export is the fit itself, with no warning.
    let full = dir.path().join("all");
    fit(&data, &full, "R,TT,TRT,residual");
    let out = hairfit_ok(&["export", s(&full), "--to", "pbrt"]);
    let err = stderr(&out);
    assert!(!err.contains("warning"), "{err}");
    assert!(err.contains("exact"), "{err}");
    assert!(!stdout(&out).contains("WARNING"));
}

/// An --output that is a directory is refused before the renderer model is fitted (it used to
/// fail with "Is a directory" after the whole fit), naming the option and a file to write.
#[test]
fn an_output_directory_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (to, example) in [("pbrt", "hair.pbrt"), ("blender", "hair.py")] {
        let out = cli::hairfit(&[
            "export",
            "no-such-fit",
            "--to",
            to,
            "--output",
            s(dir.path()),
        ]);
        cli::assert_fails_with(&out, &["--output", "that is a directory", example]);
    }
}

/// `export --to pbrt --output x.mtlx` wrote a pbrt block into a file MaterialX would then fail
/// to load. A name with another renderer's extension is refused before any work, naming both
/// formats and the fix; the renderer's own extension, another one or none are the user's.
#[test]
fn an_output_named_for_another_renderer_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    for (to, name, needles) in [
        (
            "pbrt",
            "x.mtlx",
            &[
                ".mtlx is the extension of a MaterialX document (--to materialx)",
                "--to pbrt writes a pbrt-v4",
                "name the file",
            ][..],
        ),
        (
            "blender",
            "x.PBRT",
            &[
                ".PBRT is the extension of a pbrt-v4",
                "--to blender writes a Blender Python script",
            ][..],
        ),
        (
            "materialx",
            "x.py",
            &[
                ".py is the extension of a Blender Python script (--to blender)",
                "or pass --to blender",
            ][..],
        ),
    ] {
        let file = dir.path().join(name);
        let out = cli::hairfit(&["export", "no-such-fit", "--to", to, "--output", s(&file)]);
        cli::assert_fails_with(&out, needles);
        let renamed = file.with_extension(match to {
            "pbrt" => "pbrt",
            "blender" => "py",
            _ => "mtlx",
        });
        assert!(
            stderr(&out).contains(&format!("name the file {}", s(&renamed))),
            "{}",
            stderr(&out)
        );
        assert!(!file.exists());
    }
    // Accepted names get as far as reading the fit (which does not exist here).
    for (to, name) in [
        ("pbrt", "x.pbrt"),
        ("materialx", "x.MTLX"),
        ("pbrt", "x.txt"),
        ("blender", "x"),
    ] {
        let file = dir.path().join(name);
        let out = cli::hairfit(&["export", "no-such-fit", "--to", to, "--output", s(&file)]);
        let err = stderr(&out);
        assert!(
            !out.status.success() && err.contains("no-such-fit"),
            "{to} {name}: {err}"
        );
        assert!(!err.contains("extension"), "{to} {name}: {err}");
    }
}

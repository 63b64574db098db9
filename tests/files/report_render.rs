//! `hairfit report` on fixtures: every expected file is written, SVGs are well-formed XML with
//! their titles, PNGs have the stated size, index.html is self-contained, no NaN/inf text, and
//! drawn points stay bounded for large inputs.

use std::path::Path;

use hairfit::families::marschner::params::{ParamFile, SigmaA};
use hairfit::families::marschner::ModelConfig;
use hairfit::families::FamilyParams;
use hairfit::files::{
    read_curves_csv, write_curves_csv, Correlation, CurveRow, DataInfo, FitJson, FitStatus,
    LoadReport, OptionsRecord, ParamStatus, ParameterEntry, ResidualSummary, ScaleEntry,
    TraceStage,
};
use hairfit::geometry::Angles;
use hairfit::report::{
    render_report, write_report_with, ReportOptions, ReportSummary, MAX_PANELS, MAX_SCATTER_POINTS,
    MAX_SLICE_POINTS,
};

/// A smooth positive stand-in for the model with the right shape (three lobes, channel-dependent
/// absorption), so rendering is tested independently of the model's correctness.
fn toy_model(a: &Angles, out: &mut [[f64; 3]]) {
    let th = 0.5 * (a.theta_i + a.theta_r);
    let phi = (a.phi_r - a.phi_i).sin().atan2((a.phi_r - a.phi_i).cos());
    let g =
        |x: f64, s: f64| (-x * x / (2.0 * s * s)).exp() / (s * (2.0 * std::f64::consts::PI).sqrt());
    let alpha = -7f64.to_radians();
    let beta = 8f64.to_radians();
    for (c, o) in out.iter_mut().enumerate() {
        let absorb = (-(0.3 + 0.4 * c as f64)).exp();
        o[0] = g(th - alpha, beta) * 0.05 * (phi / 2.0).cos().abs().max(1e-3);
        o[1] = g(th + alpha / 2.0, beta / 2.0)
            * absorb
            * (-(phi.abs() - std::f64::consts::PI).powi(2) / 0.2).exp();
        o[2] = g(th + 1.5 * alpha, 2.0 * beta)
            * absorb
            * absorb
            * (0.2 + (-(phi.abs() - 0.6).powi(2) / 0.05).exp());
    }
}

/// Fixed pseudo-random numbers in [−1, 1] (no RNG dependency, reproducible).
fn noise(i: u64) -> f64 {
    let x = (i.wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11) as f64 / (1u64 << 53) as f64;
    2.0 * x - 1.0
}

const CHANNELS: [&str; 3] = ["r", "g", "b"];
const SCALE: [f64; 3] = [2.0, 1.5, 1.0];

/// The sample directions of a typical measurement: two azimuthal scans, one longitudinal scan
/// and a few scattered samples (degrees).
fn measurement_angles() -> Vec<[f64; 4]> {
    let mut v = Vec::new();
    for (ti, tr) in [(-20.0, 25.0), (10.0, -5.0)] {
        for k in 0..72 {
            v.push([ti, 0.0, tr, -177.5 + 5.0 * k as f64]);
        }
    }
    for k in 0..33 {
        v.push([-10.0, 0.0, -80.0 + 5.0 * k as f64, 30.0]);
    }
    for k in 0..5 {
        v.push([
            40.0 + k as f64,
            7.0 * k as f64,
            -30.0 + 11.0 * k as f64,
            100.0 - 13.0 * k as f64,
        ]);
    }
    v
}

/// curves.csv rows for `angles` under `model`, 5 % noise, a few outliers down-weighted.
fn fixture_rows(
    angles: &[[f64; 4]],
    model: &dyn Fn(&Angles, &mut [[f64; 3]]),
    n_ch: usize,
) -> Vec<CurveRow> {
    let mut rows = Vec::new();
    let mut out = vec![[0.0; 3]; n_ch];
    for (i, a) in angles.iter().enumerate() {
        model(&Angles::from_degrees(a[0], a[1], a[2], a[3]), &mut out);
        for c in 0..n_ch {
            let l = out[c].map(|v| v * SCALE[c]);
            let fit = l[0] + l[1] + l[2];
            let id = (i * n_ch + c) as u64;
            let outlier = i % 97 == 13;
            let data = if outlier {
                fit * 4.0
            } else {
                fit * (1.0 + 0.05 * noise(id))
            };
            let residual = (data.ln() - fit.ln()) / 0.05;
            rows.push(CurveRow {
                sample: i as u64,
                line: i as u64 + 2,
                channel: CHANNELS[c].into(),
                theta_i: a[0],
                phi_i: a[1],
                theta_r: a[2],
                phi_r: a[3],
                data,
                sigma: (i % 2 == 0).then_some(0.05 * data),
                fit,
                fit_r: l[0],
                fit_tt: l[1],
                fit_trt: l[2],
                residual,
                weight: if outlier { 0.2 } else { 1.0 },
            });
        }
    }
    rows
}

fn fixture_fit(n_samples: usize, n_ch: usize) -> FitJson {
    let names = [
        "eta",
        "sigma_a[0]",
        "alpha_r_deg",
        "beta_r_deg",
        "k_g",
        "w_c_deg",
        "eccentricity",
    ];
    let entry = |i: usize, name: &str| ParameterEntry {
        name: name.into(),
        value: Some([1.55, 0.4, -7.0, 8.0, 2.0, 15.0, 0.9][i]),
        std_error: match i {
            0 => None,
            5 => None,
            _ => Some(0.01 * (i as f64 + 1.0)),
        },
        status: match i {
            0 => ParamStatus::Fixed,
            5 => ParamStatus::Undetermined,
            _ => ParamStatus::Free,
        },
        interval_68: None,
        interval_95: None,
        profile: Vec::new(),
        profile_method: None,
    };
    let free: Vec<String> = names[1..].iter().map(|s| s.to_string()).collect();
    let n = free.len();
    let matrix = (0..n)
        .map(|i| {
            (0..n)
                .map(|j| {
                    if free[i] == "w_c_deg" || free[j] == "w_c_deg" {
                        None
                    } else if i == j {
                        Some(1.0)
                    } else {
                        Some(0.9 * noise((i * n + j).min(j * n + i) as u64))
                    }
                })
                .collect()
        })
        .collect();
    FitJson {
        hairfit_version: "0.1.0".into(),
        status: FitStatus::Converged,
        data: DataInfo {
            file: "data/fixture.csv".into(),
            channels: CHANNELS[..n_ch].iter().map(|s| s.to_string()).collect(),
            n_samples,
            load_report: LoadReport {
                rows_read: n_samples as u64,
                accepted: n_samples as u64,
                ..LoadReport::default()
            },
        },
        model: ModelConfig::default(),
        options: OptionsRecord {
            space: hairfit::fit::Space::Log,
            loss: hairfit::fit::Loss::Huber,
            seed: 7,
            ..OptionsRecord::default()
        },
        params: FamilyParams::Marschner(ParamFile {
            eta: 1.55,
            sigma_a: SigmaA::PerChannel(vec![0.3, 0.7, 1.1][..n_ch].to_vec()),
            alpha_r_deg: -7.0,
            beta_r_deg: 8.0,
            k_g: 2.0,
            w_c_deg: 15.0,
            eccentricity: 0.9,
            delta_eta_prime: 0.3,
            delta_h_m: 0.5,
        }),
        parameters: names.iter().enumerate().map(|(i, n)| entry(i, n)).collect(),
        scale: (0..n_ch)
            .map(|c| ScaleEntry {
                channel: CHANNELS[c].into(),
                value: Some(SCALE[c]),
                std_error: Some(0.01),
                linear_noise_value: None,
            })
            .collect(),
        correlation: Correlation {
            names: free,
            matrix,
            ..Correlation::default()
        },
        warnings: vec![
            "k_g: no sample near the glint (|phi - phi_c| < 2 w_c); k_g and w_c are not determined"
                .into(),
        ],
        residuals: ResidualSummary {
            space: "log".into(),
            loss: "huber".into(),
            rms: Some(1.02),
            reduced_chi2: Some(1.04),
            dof: 500,
            per_channel: vec![],
            down_weighted: None,
        },
        trace: vec![
            TraceStage {
                stage: "multistart".into(),
                iterations: 5,
                cost: Some(0.2),
                history: vec![10.0, 3.0, 1.0, 0.5, 0.2],
            },
            TraceStage {
                stage: "lm".into(),
                iterations: 4,
                cost: Some(0.01),
                history: vec![0.2, 0.05, 0.011, 0.01],
            },
        ],
        verdict: hairfit::files::Verdict::Undetermined,
        reasons: vec!["k_g is undetermined — no sample near the glint".into()],
        goodness_of_fit: Default::default(),
        suggestions: vec![],
        family_record: None,
        terms: None,
    }
}

/// Render the toy fixture into a temporary directory.
fn render_toy(options: ReportOptions) -> (tempfile::TempDir, ReportSummary) {
    let dir = tempfile::tempdir().unwrap();
    let angles = measurement_angles();
    let rows = fixture_rows(&angles, &toy_model, 3);
    let fit = fixture_fit(angles.len(), 3);
    let summary = render_report(dir.path(), &fit, &rows, Some(&toy_model), 3, &options).unwrap();
    // HAIRFIT_KEEP_REPORT=DIR keeps a copy to look at (scripts/check_report.sh uses it).
    if let Ok(keep) = std::env::var("HAIRFIT_KEEP_REPORT") {
        let suffix = if options.linear { "linear" } else { "log" };
        let keep = Path::new(&keep).join(suffix);
        std::fs::create_dir_all(&keep).unwrap();
        for f in &summary.files {
            std::fs::copy(dir.path().join(f), keep.join(f)).unwrap();
        }
    }
    (dir, summary)
}

fn png_size(path: &Path) -> (u32, u32) {
    let bytes = std::fs::read(path).unwrap();
    assert_eq!(
        &bytes[..8],
        b"\x89PNG\r\n\x1a\n",
        "{} is not a PNG",
        path.display()
    );
    assert_eq!(&bytes[12..16], b"IHDR");
    let be = |b: &[u8]| u32::from_be_bytes([b[0], b[1], b[2], b[3]]);
    (be(&bytes[16..20]), be(&bytes[20..24]))
}

/// Words that betray an unformatted non-finite number.
fn has_nan_text(text: &str) -> bool {
    text.split(|c: char| !c.is_ascii_alphanumeric())
        .any(|w| w == "NaN" || w == "nan" || w == "inf" || w == "Infinity")
}

#[test]
fn report_writes_every_expected_file() {
    let (dir, summary) = render_toy(ReportOptions::default());
    let stems: Vec<&str> = summary.figures.iter().map(|f| f.stem.as_str()).collect();
    assert_eq!(
        stems,
        [
            "curves",
            "polar",
            "data_vs_fit",
            "residuals",
            "correlation",
            "convergence"
        ]
    );
    for stem in stems {
        for ext in ["svg", "png"] {
            let p = dir.path().join(format!("{stem}.{ext}"));
            assert!(p.is_file(), "{} missing", p.display());
        }
    }
    assert!(dir.path().join("index.html").is_file());
    assert_eq!(summary.files.len(), 2 * summary.figures.len() + 1);
    // Three slices (two azimuthal, one longitudinal), all drawn.
    assert_eq!(summary.slices, 3);
    assert_eq!(summary.panels, 3);
    // The fit column and the re-evaluated model agree: no calibration note.
    assert!(
        summary.notes.iter().all(|n| !n.contains("differs")),
        "{:?}",
        summary.notes
    );
    // No leftover temporary files from the atomic writes.
    for entry in std::fs::read_dir(dir.path()).unwrap() {
        let name = entry.unwrap().file_name().into_string().unwrap();
        assert!(
            !name.starts_with(".hairfit-"),
            "temporary file {name} left behind"
        );
    }
}

#[test]
fn svgs_are_xml_with_their_titles_and_pngs_have_the_stated_size() {
    let (dir, summary) = render_toy(ReportOptions::default());
    for f in &summary.figures {
        let text = std::fs::read_to_string(dir.path().join(format!("{}.svg", f.stem))).unwrap();
        let doc = roxmltree::Document::parse(&text)
            .unwrap_or_else(|e| panic!("{}.svg is not XML: {e}", f.stem));
        let root = doc.root_element();
        assert_eq!(root.tag_name().name(), "svg");
        assert_eq!(root.attribute("width"), Some(f.width.to_string().as_str()));
        assert_eq!(
            root.attribute("height"),
            Some(f.height.to_string().as_str())
        );
        let title = root
            .children()
            .find(|n| n.has_tag_name("title"))
            .and_then(|n| n.text());
        assert_eq!(title, Some(f.title.as_str()), "{}.svg title", f.stem);
        // The title is also drawn as text in the figure.
        let texts: Vec<&str> = doc
            .descendants()
            .filter(|n| n.has_tag_name("text"))
            .filter_map(|n| n.text())
            .collect();
        assert!(
            texts.iter().any(|t| t.contains(&f.title)),
            "{}: title not drawn",
            f.stem
        );
        assert_eq!(
            png_size(&dir.path().join(format!("{}.png", f.stem))),
            (f.width, f.height)
        );
    }
    // Axis labels carry units.
    let curves = std::fs::read_to_string(dir.path().join("curves.svg")).unwrap();
    assert!(curves.contains("φ = φr − φi (deg)") && curves.contains("θr (deg)"));
    assert!(curves.contains("log scale"));
}

#[test]
fn index_html_is_offline_and_links_only_existing_local_files() {
    let (dir, summary) = render_toy(ReportOptions::default());
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(!html.contains("http://") && !html.contains("https://") && !html.contains("//cdn"));
    assert!(!html.contains("<script"), "no scripts needed");
    let mut links = Vec::new();
    for attr in ["src=\"", "href=\""] {
        let mut rest = html.as_str();
        while let Some(i) = rest.find(attr) {
            rest = &rest[i + attr.len()..];
            let end = rest.find('"').unwrap();
            links.push(rest[..end].to_string());
        }
    }
    assert_eq!(links.len(), 2 * summary.figures.len());
    for l in &links {
        assert!(
            !l.contains('/') && !l.contains(':'),
            "link {l} is not a plain relative file"
        );
        assert!(dir.path().join(l).is_file(), "link {l} points to no file");
    }
    // Summary numbers, parameter statuses and warnings are on the page.
    for needle in [
        "converged",
        "undetermined",
        "fixed",
        "alpha_r_deg",
        "sigma_a[0] (r)",
        "reduced χ²",
        "k_g: no sample near the glint",
    ] {
        assert!(html.contains(needle), "index.html lacks {needle}");
    }
}

#[test]
fn outputs_have_no_nan_text_even_with_missing_numbers() {
    let dir = tempfile::tempdir().unwrap();
    let angles = measurement_angles();
    let mut rows = fixture_rows(&angles, &toy_model, 3);
    rows[5].residual = f64::NAN;
    rows[6].data = 0.0;
    let mut fit = fixture_fit(angles.len(), 3);
    fit.residuals.reduced_chi2 = None;
    fit.residuals.rms = None;
    fit.trace[0].history.push(f64::NAN);
    let summary = render_report(
        dir.path(),
        &fit,
        &rows,
        Some(&toy_model),
        3,
        &ReportOptions::default(),
    )
    .unwrap();
    for f in &summary.files {
        if f.ends_with(".svg") || f.ends_with(".html") {
            let text = std::fs::read_to_string(dir.path().join(f)).unwrap();
            assert!(!has_nan_text(&text), "{f} prints a non-finite number");
        }
    }
    assert!(summary.notes.iter().any(|n| n.contains("not finite")));
    assert!(summary
        .notes
        .iter()
        .any(|n| n.contains("cannot be drawn on log axes")));
}

#[test]
fn linear_axes_render_too() {
    let (dir, summary) = render_toy(ReportOptions { linear: true });
    let curves = std::fs::read_to_string(dir.path().join("curves.svg")).unwrap();
    assert!(!curves.contains("log scale"));
    assert!(std::fs::read_to_string(dir.path().join("index.html"))
        .unwrap()
        .contains("value axes: linear"));
    assert_eq!(summary.figures.len(), 6);
}

#[test]
fn a_fit_column_that_disagrees_with_the_model_is_reported() {
    let dir = tempfile::tempdir().unwrap();
    let angles = measurement_angles();
    let mut rows = fixture_rows(&angles, &toy_model, 3);
    // A fit column that is not scale × model within a slice (e.g. other settings were used).
    for (i, r) in rows.iter_mut().enumerate() {
        r.fit *= 1.0 + 0.1 * noise(i as u64).abs();
    }
    let fit = fixture_fit(angles.len(), 3);
    let summary = render_report(
        dir.path(),
        &fit,
        &rows,
        Some(&toy_model),
        3,
        &ReportOptions::default(),
    )
    .unwrap();
    assert!(
        summary
            .notes
            .iter()
            .any(|n| n.contains("differs from curves.csv")),
        "{:?}",
        summary.notes
    );
}

#[test]
fn scattered_data_without_a_model_still_renders() {
    let dir = tempfile::tempdir().unwrap();
    // Every sample its own incidence: no slices.
    let angles: Vec<[f64; 4]> = (0..400)
        .map(|i| {
            let t = i as f64;
            [
                -60.0 + (t * 7.3) % 120.0,
                (t * 13.1) % 360.0 - 180.0,
                -60.0 + (t * 3.7) % 120.0,
                (t * 29.3) % 360.0 - 180.0,
            ]
        })
        .collect();
    let rows = fixture_rows(&angles, &toy_model, 1);
    let fit = fixture_fit(angles.len(), 1);
    let summary =
        render_report(dir.path(), &fit, &rows, None, 1, &ReportOptions::default()).unwrap();
    assert_eq!(summary.slices, 0);
    let stems: Vec<&str> = summary.figures.iter().map(|f| f.stem.as_str()).collect();
    assert_eq!(
        stems,
        ["data_vs_fit", "residuals", "correlation", "convergence"]
    );
    let svg = std::fs::read_to_string(dir.path().join("data_vs_fit.svg")).unwrap();
    assert!(svg.contains("no slices found"));
}

#[test]
fn drawn_points_stay_bounded_for_a_large_input() {
    let dir = tempfile::tempdir().unwrap();
    // 200 000 samples: one dense azimuthal scan plus scattered samples.
    let mut angles: Vec<[f64; 4]> = (0..150_000)
        .map(|k| {
            [
                -20.0,
                0.0,
                25.0,
                -180.0 + 360.0 * (k as f64 + 0.5) / 150_000.0,
            ]
        })
        .collect();
    angles.extend((0..50_000).map(|i| {
        let t = i as f64;
        [
            -60.0 + (t * 7.31) % 120.0,
            (t * 13.1) % 360.0 - 180.0,
            -60.0 + (t * 3.7) % 120.0,
            (t * 29.3) % 360.0 - 180.0,
        ]
    }));
    let rows = fixture_rows(&angles, &toy_model, 1);
    let fit = fixture_fit(angles.len(), 1);
    let summary = render_report(
        dir.path(),
        &fit,
        &rows,
        Some(&toy_model),
        1,
        &ReportOptions::default(),
    )
    .unwrap();
    // Panels + polar per channel, plus the two scatter figures.
    let bound = (MAX_PANELS + 1) * MAX_SLICE_POINTS + 2 * MAX_SCATTER_POINTS;
    assert!(
        summary.drawn_points <= bound,
        "{} > {bound}",
        summary.drawn_points
    );
    assert!(summary.notes.iter().any(|n| n.contains("decimated")));
    // The SVGs stay small enough to open (each drawn point is a few hundred bytes at most).
    for f in &summary.figures {
        let len = std::fs::metadata(dir.path().join(format!("{}.svg", f.stem)))
            .unwrap()
            .len();
        assert!(len < 8_000_000, "{}.svg is {len} bytes", f.stem);
    }
}

#[test]
fn curves_csv_round_trips_and_a_bad_header_names_the_column() {
    let dir = tempfile::tempdir().unwrap();
    let rows = fixture_rows(&measurement_angles()[..10], &toy_model, 3);
    let path = dir.path().join("curves.csv");
    write_curves_csv(&path, &rows).unwrap();
    let back = read_curves_csv(&path).unwrap();
    assert_eq!(back.len(), rows.len());
    assert_eq!(back[3].sigma, None, "odd samples have no sigma");
    assert_eq!(back[0].channel, "r");
    let text = std::fs::read_to_string(&path).unwrap();
    std::fs::write(&path, text.replacen("fit_tt", "fit_xx", 1)).unwrap();
    let err = read_curves_csv(&path).unwrap_err().to_string();
    assert!(err.contains("curves.csv:1:12"), "{err}");
    // A bad number names its line and column.
    std::fs::write(&path, text.replacen("\n0,2,r,-20", "\n0,2,r,abc", 1)).unwrap();
    let err = read_curves_csv(&path).unwrap_err().to_string();
    assert!(err.contains("curves.csv:2:4"), "{err}");
}

#[test]
fn write_report_reads_the_fit_directory() {
    // End to end through the files, with parameters outside the model's domain so the report
    // falls back to the fit column (this path never evaluates the model).
    let dir = tempfile::tempdir().unwrap();
    let angles = measurement_angles();
    let rows = fixture_rows(&angles, &toy_model, 3);
    let mut fit = fixture_fit(angles.len(), 3);
    if let FamilyParams::Marschner(p) = &mut fit.params {
        p.eccentricity = 0.5;
    }
    fit.save(&dir.path().join("fit.json")).unwrap();
    write_curves_csv(&dir.path().join("curves.csv"), &rows).unwrap();
    let summary = write_report_with(dir.path(), &ReportOptions::default()).unwrap();
    assert!(
        summary.notes[0].contains("outside the model's domain"),
        "{:?}",
        summary.notes
    );
    assert!(dir.path().join("index.html").is_file());
}

#[test]
fn report_of_a_real_model_fixture_matches_the_fit_column() {
    // Fixture from the real model at the fitted parameters (as the fit writes it), read back
    // through the files: the dense curves re-evaluated by the report must agree with the fit
    // column to rounding (no calibration note), and every figure is written.
    let dir = tempfile::tempdir().unwrap();
    let fit = fixture_fit(measurement_angles().len(), 3);
    let params = fit.params.marschner().unwrap().to_params();
    let config = fit.model;
    let model = |a: &Angles, out: &mut [[f64; 3]]| {
        hairfit::families::marschner::scattering_by_lobe(&params, &config, a, out)
    };
    let rows = fixture_rows(&measurement_angles(), &model, 3);
    fit.save(&dir.path().join("fit.json")).unwrap();
    write_curves_csv(&dir.path().join("curves.csv"), &rows).unwrap();
    let summary = write_report_with(dir.path(), &ReportOptions::default()).unwrap();
    assert!(
        summary.notes.iter().all(|n| !n.contains("differs")),
        "{:?}",
        summary.notes
    );
    assert_eq!(summary.figures.len(), 6);
    for f in &summary.files {
        assert!(dir.path().join(f).is_file(), "{f} missing");
    }
}

#[test]
fn a_failed_fit_with_no_rows_still_renders() {
    // A failed fit may write an empty curves.csv and no trace or correlation.
    let dir = tempfile::tempdir().unwrap();
    let mut fit = fixture_fit(0, 3);
    fit.status = FitStatus::Failed;
    fit.trace.clear();
    fit.correlation = Correlation::default();
    let summary = render_report(
        dir.path(),
        &fit,
        &[],
        Some(&toy_model),
        3,
        &ReportOptions::default(),
    )
    .unwrap();
    let stems: Vec<&str> = summary.figures.iter().map(|f| f.stem.as_str()).collect();
    assert_eq!(stems, ["data_vs_fit", "residuals"]);
    let html = std::fs::read_to_string(dir.path().join("index.html")).unwrap();
    assert!(html.contains("failed"));
    assert!(!has_nan_text(&html));
}

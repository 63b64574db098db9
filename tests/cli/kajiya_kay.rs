//! `--model kajiya-kay` against Kajiya & Kay 1989 written out again here, straight from the
//! paper's lighting model in hairfit's angles (docs/kajiya-kay.md), with vectors rather than the
//! implementation's angle identities: its values, its invariants and limits, and the command
//! line as a user runs it.

use crate::support::cli;

use cli::{failed, hairfit, hairfit_ok, s as p, stdout, write};
use hairfit::families::table::{TableParams, TermSet};
use hairfit::families::ModelFamily;
use hairfit::geometry::Angles;

/// Unit vector of direction (θ, φ) in the fibre frame: u (the tangent) is the first component.
fn direction(theta: f64, phi: f64) -> [f64; 3] {
    [
        theta.sin(),
        theta.cos() * phi.cos(),
        theta.cos() * phi.sin(),
    ]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

/// The paper's Ψ with vectors: `K_d sin(t,l) + K_s cos^p(e, e′)` where e′ is the direction on
/// the mirror cone (t·e′ = −t·l) in e's plane through t, and the reference's S = Ψ / cos θ_i.
fn reference_s(k_d: f64, k_s: f64, p: f64, a: &Angles) -> f64 {
    let t = [1.0, 0.0, 0.0];
    let l = direction(a.theta_i, a.phi_i);
    let e = direction(a.theta_r, a.phi_r);
    let sin_tl = (1.0 - dot(t, l).powi(2)).sqrt();
    // e′: tangent component −t·l, normal component along e's own normal-plane direction.
    let en = [0.0, e[1], e[2]];
    let en_len = dot(en, en).sqrt();
    let e_mirror = [-dot(t, l), sin_tl * en[1] / en_len, sin_tl * en[2] / en_len];
    let cos_cone = dot(e, e_mirror).max(0.0);
    let psi = k_d * sin_tl + k_s * cos_cone.powf(p);
    psi / a.theta_i.cos()
}

fn params(k_d: &[f64], k_s: f64, p: f64) -> TableParams<f64> {
    TableParams {
        values: vec![k_d.to_vec(), vec![k_s], vec![p]],
        n_channels: k_d.len(),
    }
}

fn s(p: &TableParams<f64>, on: TermSet, a: &Angles) -> Vec<f64> {
    let mut out = vec![0.0; p.n_channels];
    ModelFamily::KajiyaKay
        .table()
        .unwrap()
        .eval_batch(p, on, std::slice::from_ref(a), &mut out);
    out
}

fn grid() -> Vec<Angles> {
    let mut v = Vec::new();
    for ti in [-70.0, -35.0, -5.0, 0.0, 20.0, 55.0, 80.0] {
        for tr in [-75.0, -30.0, 0.0, 10.0, 45.0, 85.0] {
            for (pi, pr) in [(0.0, 0.0), (10.0, 170.0), (-60.0, 45.0), (90.0, -135.0)] {
                v.push(Angles::from_degrees(ti, pi, tr, pr));
            }
        }
    }
    v
}

/// The two transcriptions compute the same numbers by different routes (angle sums against
/// vector dot products): they agree to a few ulps of the largest term, 1e-12 relative.
#[test]
fn values_match_the_papers_lighting_model() {
    let all = TermSet::all(2);
    for (k_d, k_s, pw) in [(0.2, 1.0, 50.0), (0.05, 2.5, 3.0), (1.3, 0.7, 400.0)] {
        let p = params(&[k_d, 2.0 * k_d], k_s, pw);
        for a in grid() {
            let got = s(&p, all, &a);
            for (c, kd) in [k_d, 2.0 * k_d].into_iter().enumerate() {
                let want = reference_s(kd, k_s, pw, &a);
                assert!(
                    (got[c] - want).abs() <= 1e-12 * want.abs().max(1.0),
                    "k_d {kd} k_s {k_s} p {pw} at {a:?}: {} vs {want}",
                    got[c]
                );
            }
        }
    }
}

/// The specular part of f = S cos θ_i is symmetric under ω_i ↔ ω_r and S's diffuse part is the
/// constant K_d; nothing depends on φ. Exact identities of the formula: 1e-13 relative.
#[test]
fn reciprocity_and_azimuthal_independence() {
    let specular = TermSet(0b10);
    let diffuse = TermSet(0b01);
    let p = params(&[0.3], 1.0, 40.0);
    for a in grid() {
        let swapped = Angles {
            theta_i: a.theta_r,
            phi_i: a.phi_r,
            theta_r: a.theta_i,
            phi_r: a.phi_i,
        };
        let f = |on, a: &Angles| s(&p, on, a)[0] * a.theta_i.cos();
        let (x, y) = (f(specular, &a), f(specular, &swapped));
        assert!(
            (x - y).abs() <= 1e-13 * x.abs().max(1e-300),
            "{a:?}: {x} vs {y}"
        );
        assert_eq!(s(&p, diffuse, &a)[0], 0.3);
        let turned = Angles {
            phi_r: a.phi_r + 1.234,
            ..a
        };
        assert_eq!(s(&p, specular, &a), s(&p, specular, &turned));
    }
}

/// Limits the formula states: on the mirror cone the specular S is K_s / cos θ_i for any p; at
/// θ_h = 30° it is K_s 0.5^p / cos θ_i; beyond a right angle from the cone it is 0.
#[test]
fn limits_of_the_exponent() {
    let specular = TermSet(0b10);
    for pw in [0.5, 1.0, 50.0, 5000.0] {
        let p = params(&[0.0], 1.7, pw);
        let on_cone = Angles::from_degrees(25.0, 0.0, -25.0, 90.0);
        let v = s(&p, specular, &on_cone)[0];
        let want = 1.7 / 25f64.to_radians().cos();
        assert!((v - want).abs() <= 1e-14 * want, "p {pw}: {v}");
        let off = Angles::from_degrees(20.0, 0.0, 40.0, 0.0);
        let v = s(&p, specular, &off)[0];
        let want = 1.7 * 0.5f64.powf(pw) / 20f64.to_radians().cos();
        assert!(
            (v - want).abs() <= 1e-12 * want.max(1e-300),
            "p {pw}: {v} vs {want}"
        );
        let far = Angles::from_degrees(60.0, 0.0, 50.0, 0.0);
        assert_eq!(s(&p, specular, &far)[0], 0.0);
    }
}

/// As a user runs it: eval against the reference, fit of synthesized data, and the options
/// and files of other families refused with whose they are.
#[test]
fn command_line() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(
        dir.path(),
        "kk.json",
        r#"{"model": "kajiya-kay", "k_d": [0.1, 0.2, 0.4], "exponent": 60}"#,
    );
    let input = write(
        dir.path(),
        "a.csv",
        "theta_i,phi_i,theta_r,phi_r\n20,0,-15,30\n-40,10,35,-100\n",
    );
    let out = stdout(&hairfit_ok(&[
        "eval",
        "--model",
        "kajiya-kay",
        "--params",
        p(&params),
        "--input",
        p(&input),
    ]));
    let rows: Vec<Vec<f64>> = out
        .lines()
        .skip(1)
        .map(|l| l.split(',').skip(4).map(|x| x.parse().unwrap()).collect())
        .collect();
    for (row, a) in rows.iter().zip([
        Angles::from_degrees(20.0, 0.0, -15.0, 30.0),
        Angles::from_degrees(-40.0, 10.0, 35.0, -100.0),
    ]) {
        for (c, kd) in [0.1, 0.2, 0.4].into_iter().enumerate() {
            let want = reference_s(kd, 1.0, 60.0, &a);
            assert!((row[c] - want).abs() <= 1e-12 * want, "{row:?}");
        }
    }
    // Another family's options are refused, naming whose they are.
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "kajiya-kay",
        "--lobes",
        "R",
        "--params",
        p(&params),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("--lobes") && e.contains("marschner"), "{e}");
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "kajiya-kay",
        "--terms",
        "R",
        "--params",
        p(&params),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("`R`") && e.contains("diffuse, specular"), "{e}");
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "kajiya-kay",
        "--width-nodes",
        "64",
        "--params",
        p(&params),
        "--input",
        p(&input),
    ]));
    assert!(e.contains("--width-nodes") && e.contains("chiang"), "{e}");
    // A Marschner file under --model kajiya-kay, and a misspelt key.
    let m = write(
        dir.path(),
        "m.json",
        r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15}"#,
    );
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "kajiya-kay",
        "--params",
        p(&m),
        "--input",
        p(&input),
    ]));
    assert!(
        e.contains("m.json") && e.contains("--model marschner"),
        "{e}"
    );
    let typo = write(dir.path(), "t.json", r#"{"k_d": 0.1, "exponnent": 60}"#);
    let e = failed(&hairfit(&[
        "eval",
        "--model",
        "kajiya-kay",
        "--params",
        p(&typo),
        "--input",
        p(&input),
    ]));
    assert!(
        e.contains("t.json:1:") && e.contains("did you mean `exponent`"),
        "{e}"
    );
    // Synthesize, then fit with the diffuse term only: the exponent is not fitted and says why.
    let data = dir.path().join("d.csv");
    hairfit_ok(&[
        "synth",
        "--model",
        "kajiya-kay",
        "--params",
        p(&params),
        "--rig",
        "longitudinal:incidences=15,30,45:phi=0,180:steps=41",
        "--output",
        p(&data),
    ]);
    let fit_dir = dir.path().join("fit");
    let summary = stdout(&hairfit_ok(&[
        "fit",
        p(&data),
        "--model",
        "kajiya-kay",
        "--no-progress",
        "--out",
        p(&fit_dir),
    ]));
    assert!(
        summary.contains("model: kajiya-kay, terms diffuse+specular"),
        "{summary}"
    );
    let fit = hairfit::files::FitJson::load(&fit_dir.join("fit.json")).unwrap();
    let exponent = fit
        .parameters
        .iter()
        .find(|e| e.name == "exponent")
        .unwrap();
    assert!(
        (exponent.value.unwrap() - 60.0).abs() <= 1e-6 * 60.0,
        "{exponent:?}"
    );
    let only = dir.path().join("only");
    hairfit_ok(&[
        "fit",
        p(&data),
        "--model",
        "kajiya-kay",
        "--terms",
        "diffuse",
        "--no-progress",
        "--out",
        p(&only),
    ]);
    let fit = hairfit::files::FitJson::load(&only.join("fit.json")).unwrap();
    assert_eq!(fit.terms.as_deref(), Some(&["diffuse".to_string()][..]));
    assert!(
        fit.warnings
            .iter()
            .any(|w| w.starts_with("exponent: not fitted")),
        "{:?}",
        fit.warnings
    );
    // The fit exports: its params.json is a kajiya-kay file the family reads back.
    let back = hairfit::families::FamilyParams::load(
        &fit_dir.join("params.json"),
        hairfit::families::ModelFamily::KajiyaKay,
    )
    .unwrap();
    assert_eq!(back, fit_params(&fit_dir));
}

fn fit_params(dir: &std::path::Path) -> hairfit::families::FamilyParams {
    hairfit::files::FitJson::load(&dir.join("fit.json"))
        .unwrap()
        .params
}

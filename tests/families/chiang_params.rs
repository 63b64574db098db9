//! The Chiang parameter file and effect list: names, defaults, unknown keys, domains, model tag.

use hairfit::families::chiang::{ChiangEffects, ChiangParamFile, ChiangParams};
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::Error;

fn parse(json: &str) -> Result<ChiangParamFile, Error> {
    ChiangParamFile::from_json_str(json, "p.json")
}

#[test]
fn reads_scalar_and_per_channel_sigma_a() {
    let f = parse(r#"{"sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2}"#).unwrap();
    assert_eq!(f.eta, 1.55, "pbrt's default η");
    assert_eq!(f.n_channels(), 1);
    let p = f.to_params();
    assert_eq!(p.sigma_a, vec![0.4]);
    assert!((p.alpha - 2f64.to_radians()).abs() < 1e-16);
    let f = parse(
        r#"{"model": "chiang", "eta": 1.6, "sigma_a": [0.419, 0.697, 1.37],
            "beta_m": 0.2, "beta_n": 0.5, "alpha_deg": -3}"#,
    )
    .unwrap();
    assert_eq!(f.to_params().sigma_a, vec![0.419, 0.697, 1.37]);
    // Written files carry the tag and read back identically.
    let written = serde_json::to_string(&ChiangParamFile::from_params(&f.to_params())).unwrap();
    assert!(written.contains(r#""model":"chiang""#), "{written}");
    let back = parse(&written).unwrap().to_params();
    let p: ChiangParams<f64> = f.to_params();
    assert_eq!(back.sigma_a, p.sigma_a);
    assert!((back.alpha - p.alpha).abs() < 1e-15);
}

fn message(json: &str) -> String {
    parse(json).unwrap_err().to_string()
}

#[test]
fn rejects_unknown_keys_wrong_model_and_bad_domains() {
    let m =
        message(r#"{"sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2, "beta_r": 1}"#);
    assert!(m.contains("p.json:1:") && m.contains("beta_r"), "{m}");
    let m = message(r#"{"sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3}"#);
    assert!(m.contains("alpha_deg"), "{m}");
    let m = message(
        r#"{"model": "marschner", "sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2}"#,
    );
    assert!(m.contains("marschner") && m.contains("chiang"), "{m}");
    for (json, name, range) in [
        (
            r#""eta": 1.0, "sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2"#,
            "eta",
            "(1, 10]",
        ),
        (
            r#""sigma_a": -0.1, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2"#,
            "sigma_a[0]",
            "[0, inf)",
        ),
        (
            r#""sigma_a": [0.1, 0.2, -1], "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2"#,
            "sigma_a[2]",
            "[0, inf)",
        ),
        (
            r#""sigma_a": 0.4, "beta_m": 0.0, "beta_n": 0.3, "alpha_deg": 2"#,
            "beta_m",
            "(0, 1]",
        ),
        (
            r#""sigma_a": 0.4, "beta_m": 0.3, "beta_n": 1.5, "alpha_deg": 2"#,
            "beta_n",
            "(0, 1]",
        ),
        (
            r#""sigma_a": 0.4, "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 90"#,
            "alpha_deg",
            "(-90, 90)",
        ),
    ] {
        let m = message(&format!("{{{json}}}"));
        assert!(m.contains(&format!("`{name}`")) && m.contains(range), "{m}");
    }
    let m = message(r#"{"sigma_a": [], "beta_m": 0.3, "beta_n": 0.3, "alpha_deg": 2}"#);
    assert!(m.contains("empty"), "{m}");
}

#[test]
fn effect_lists() {
    let e = ChiangEffects::parse("r, TT,residual").unwrap();
    assert!(e.r && e.tt && !e.trt && e.residual);
    assert!(ChiangEffects::parse("R,TRT,glints")
        .unwrap_err()
        .to_string()
        .contains("glints"));
    assert!(ChiangEffects::parse(" , ").is_err());
}

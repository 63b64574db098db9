//! The parameter file: names, defaults, unknown keys, positions in errors, domain, round trip.

use hairfit::families::marschner::params::ParamFile;
use hairfit::families::marschner::params::ParameterFile as _;
use hairfit::families::marschner::{Effects, ParamName};
use hairfit::Error;

const FULL: &str =
    r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15}"#;

#[test]
fn defaults_and_conversion() {
    let f = ParamFile::from_json_str(FULL, "p.json").unwrap();
    assert!(f.sigma_a_is_scalar());
    let p = f.to_params();
    assert_eq!(
        (p.eta, p.eccentricity, p.delta_eta_prime, p.delta_h_m),
        (1.55, 1.0, 0.3, 0.5)
    );
    assert_eq!(p.sigma_a, vec![0.4]);
    // Degrees → radians, exactly as f64::to_radians does.
    assert_eq!(p.alpha_r, (-7.0f64).to_radians());
    assert_eq!(p.w_c, 15.0f64.to_radians());
}

#[test]
fn per_channel_sigma_and_round_trip() {
    let text = r#"{"eta": 1.5, "sigma_a": [0.2, 0.4, 0.8], "alpha_r_deg": -6, "beta_r_deg": 7,
                   "k_g": 1, "w_c_deg": 20, "eccentricity": 0.9}"#;
    let f = ParamFile::from_json_str(text, "p.json").unwrap();
    assert!(!f.sigma_a_is_scalar());
    let p = f.to_params();
    assert_eq!(p.sigma_a.len(), 3);
    let back = ParamFile::from_params(&p);
    let json = serde_json::to_string(&back).unwrap();
    let again = ParamFile::from_json_str(&json, "back.json")
        .unwrap()
        .to_params();
    // Degrees → radians → degrees may move the last bit.
    assert!((again.alpha_r - p.alpha_r).abs() < 1e-15);
    assert_eq!(again.sigma_a, p.sigma_a);
    assert_eq!(again.eccentricity, 0.9);
}

#[test]
fn unknown_key_is_an_error_with_position() {
    let text = "{\n  \"sigma_a\": 0.4, \"alpha_r_deg\": -7, \"beta_r_deg\": 8,\n  \"k_g\": 2, \"w_c_deg\": 15, \"colour\": 1\n}";
    match ParamFile::from_json_str(text, "bad.json") {
        Err(Error::Input {
            file,
            line,
            column,
            message,
        }) => {
            assert_eq!(file.to_str(), Some("bad.json"));
            assert_eq!(line, 3);
            assert!(column > 1);
            assert!(message.contains("colour"), "{message}");
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn missing_required_key_is_an_error() {
    let text = r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2}"#;
    match ParamFile::from_json_str(text, "p.json") {
        Err(Error::Input { message, .. }) => assert!(message.contains("w_c_deg"), "{message}"),
        other => panic!("{other:?}"),
    }
}

#[test]
fn domain_errors_name_the_parameter() {
    for (patch, name) in [
        (r#""eccentricity": 0.5"#, "eccentricity"),
        (r#""eta": 0.9"#, "eta"),
        (r#""delta_eta_prime": 0"#, "delta_eta_prime"),
    ] {
        let text = FULL.replace('}', &format!(", {patch}}}"));
        match ParamFile::from_json_str(&text, "p.json") {
            Err(Error::Parameter { name: n, .. }) => assert_eq!(n, name),
            other => panic!("{patch}: {other:?}"),
        }
    }
    let neg = FULL.replace("\"sigma_a\": 0.4", "\"sigma_a\": [0.4, -1]");
    assert!(matches!(
        ParamFile::from_json_str(&neg, "p.json"),
        Err(Error::Parameter { name, .. }) if name == "sigma_a[1]"
    ));
    let empty = FULL.replace("\"sigma_a\": 0.4", "\"sigma_a\": []");
    assert!(matches!(
        ParamFile::from_json_str(&empty, "p.json"),
        Err(Error::Parameter { .. })
    ));
}

#[test]
fn load_reports_missing_file() {
    assert!(matches!(
        ParamFile::load("/nonexistent/params.json"),
        Err(Error::Io { .. })
    ));
}

#[test]
fn json_names_and_lobe_parsing() {
    assert_eq!(ParamName::SigmaA(1).json_name(), "sigma_a[1]");
    assert_eq!(ParamName::AlphaR.json_name(), "alpha_r_deg");
    let l = Effects::parse_lobes("r, Tt").unwrap();
    assert!(l.r && l.tt && !l.trt);
    assert!(Effects::parse_lobes("R,TRX").is_err());
    assert!(Effects::parse_lobes("").is_err());
    assert_eq!(
        "EXACT"
            .parse::<hairfit::families::marschner::RootMode>()
            .unwrap()
            .to_string(),
        "exact"
    );
    // Disabled lobes drop their parameters.
    let e = Effects {
        lobes: Effects::parse_lobes("R").unwrap(),
        glints: true,
        eccentricity: true,
    };
    assert_eq!(
        e.parameters(3),
        vec![ParamName::Eta, ParamName::AlphaR, ParamName::BetaR]
    );
    // η, σ_a[0], σ_a[1], α_R, β_R, k_G, w_c, a, Δη', Δh_M.
    assert_eq!(Effects::default().parameters(2).len(), 10);
}

#[test]
fn angles_on_the_axis_are_rejected() {
    use hairfit::geometry::Angles;
    assert!(Angles::from_degrees(-89.999, 10.0, 45.0, 400.0)
        .validate()
        .is_ok());
    for (a, name) in [
        (Angles::from_degrees(90.0, 0.0, 0.0, 0.0), "theta_i"),
        (Angles::from_degrees(0.0, 0.0, -90.0, 0.0), "theta_r"),
        (Angles::from_degrees(0.0, f64::NAN, 0.0, 0.0), "phi_i"),
    ] {
        assert!(matches!(a.validate(), Err(Error::Parameter { name: n, .. }) if n == name));
    }
}

#[test]
fn model_config_serde_defaults() {
    use hairfit::families::marschner::{ModelConfig, RootMode};
    let c: ModelConfig =
        serde_json::from_str(r#"{"mode": "exact", "effects": {"glints": false}}"#).unwrap();
    assert_eq!(c.mode, RootMode::Exact);
    assert!(!c.effects.glints && c.effects.eccentricity && c.effects.lobes.trt);
    assert_eq!(
        serde_json::to_string(&RootMode::Cubic).unwrap(),
        "\"cubic\""
    );
}

#[test]
fn domain_comes_from_the_table_and_names_the_range() {
    // Non-finite and out-of-range values are errors naming the parameter and the allowed range.
    let with = |patch: &str| FULL.replace('}', &format!(", {patch}}}"));
    for (text, name, range) in [
        (with(r#""eta": 1e155"#), "eta", "(1, 10]"),
        (with(r#""eta": 1"#), "eta", "(1, 10]"),
        (
            with(r#""eccentricity": 1.0000000001"#),
            "eccentricity",
            "(0.70711, 1]",
        ),
        (
            FULL.replace(r#""k_g": 2"#, r#""k_g": -1"#),
            "k_g",
            "[0, inf)",
        ),
        (
            FULL.replace(r#""w_c_deg": 15"#, r#""w_c_deg": 0"#),
            "w_c_deg",
            "(0, inf) deg",
        ),
    ] {
        match ParamFile::from_json_str(&text, "p.json") {
            Err(Error::Parameter {
                name: n, message, ..
            }) => {
                assert_eq!(n, name, "{text}");
                assert!(message.contains(range), "{text}: {message}");
            }
            other => panic!("{text}: {other:?}"),
        }
    }
    // Through the model type too: every value is checked, infinities included.
    let mut p = ParamFile::from_json_str(FULL, "p.json")
        .unwrap()
        .to_params();
    p.beta_r = f64::INFINITY;
    assert!(matches!(p.validate(), Err(Error::Parameter { name, .. }) if name == "beta_r_deg"));
}

#[test]
fn parameter_lists_follow_the_table() {
    use hairfit::families::marschner::parameters::{
        all_parameters, fitted_parameters, used_parameters,
    };
    // Output order: the table's order, σ_a expanded per channel.
    assert_eq!(
        all_parameters(2),
        hairfit::families::marschner::parameters::all_parameters(2)
    );
    for r in [false, true] {
        for tt in [false, true] {
            for trt in [false, true] {
                for glints in [false, true] {
                    for eccentricity in [false, true] {
                        let e = Effects {
                            lobes: hairfit::families::marschner::Lobes { r, tt, trt },
                            glints,
                            eccentricity,
                        };
                        assert_eq!(used_parameters(&e, 3), e.parameters(3));
                        for free_eta in [false, true] {
                            assert_eq!(
                                fitted_parameters(&e, 3, free_eta),
                                hairfit::families::marschner::parameters::fitted_parameters(
                                    &e, 3, free_eta
                                ),
                                "{e:?} free_eta={free_eta}"
                            );
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn units_come_from_the_table() {
    use hairfit::geometry::Unit;
    assert_eq!(ParamName::SigmaA(2).fact().unit, Unit::PerFiberRadius);
    assert_eq!(ParamName::SigmaA(2).fact().unit.label(), "per fiber radius");
    assert_eq!(ParamName::WC.fact().unit.label(), "deg");
    assert_eq!(
        ParamName::from_json_name("sigma_a[2]"),
        Some(ParamName::SigmaA(2))
    );
    assert_eq!(ParamName::from_json_name("w_c_deg"), Some(ParamName::WC));
    assert_eq!(ParamName::from_json_name("w_c"), None);
}

/// serde fills a struct from an array by position; a parameter file written as an array is a
/// mistake and is refused where it starts (issue 11), for both model families.
#[test]
fn a_parameter_file_that_is_an_array_is_refused_at_its_start() {
    let text = "\n  [1.55, 0.4, -7, 7, 2, 15]";
    let e = ParamFile::from_json_str(text, "p.json")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("p.json:2:3:") && e.contains("JSON object"),
        "{e}"
    );
    let e = hairfit::families::chiang::file::ChiangParamFile::from_json_str("[1.55]", "c.json")
        .unwrap_err()
        .to_string();
    assert!(
        e.starts_with("c.json:1:1:") && e.contains("JSON object"),
        "{e}"
    );
}

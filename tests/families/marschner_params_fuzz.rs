//! Fuzzing the parameter-file parser: arbitrary bytes and near-valid JSON never panic, and every
//! rejection is an error that names the file (bounded case counts so it runs in CI in seconds).

use hairfit::families::marschner::params::ParamFile;
use hairfit::families::marschner::params::ParameterFile as _;
use proptest::prelude::*;

const VALID: &str = r#"{"eta": 1.55, "sigma_a": [0.2, 0.4], "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": 0.9}"#;

fn check(text: &str) {
    match ParamFile::from_json_str(text, "fuzz.json") {
        Ok(file) => {
            // Whatever is accepted is inside the model's domain.
            file.to_params()
                .validate()
                .expect("accepted files are valid");
        }
        Err(err) => {
            let msg = err.to_string();
            assert!(!msg.is_empty());
            if let hairfit::Error::Input { file, line, .. } = &err {
                assert_eq!(file.to_str(), Some("fuzz.json"));
                assert!(*line >= 1, "{msg}");
            }
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 2000, .. ProptestConfig::default() })]

    #[test]
    fn arbitrary_bytes_never_panic(bytes in proptest::collection::vec(any::<u8>(), 0..256)) {
        check(&String::from_utf8_lossy(&bytes));
    }

    #[test]
    fn mutated_valid_files_never_panic(
        edits in proptest::collection::vec((0usize..VALID.len(), any::<char>()), 1..6),
    ) {
        let mut chars: Vec<char> = VALID.chars().collect();
        for (pos, c) in edits {
            let pos = pos % chars.len();
            chars[pos] = c;
        }
        check(&chars.into_iter().collect::<String>());
    }

    #[test]
    fn extreme_numbers_are_accepted_only_inside_the_domain(
        eta in prop_oneof![Just(f64::MAX), Just(-1.0), Just(1.0), Just(1e-300), 1.0f64..3.0],
        a in prop_oneof![Just(std::f64::consts::FRAC_1_SQRT_2 - 1e-16), Just(std::f64::consts::FRAC_1_SQRT_2), Just(1.0), Just(1.0000001), 0.0f64..1.2],
        sigma in prop_oneof![Just(0.0), Just(1e308), Just(-1e-300), 0.0f64..10.0],
    ) {
        let text = format!(
            r#"{{"eta": {eta:?}, "sigma_a": {sigma:?}, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2, "w_c_deg": 15, "eccentricity": {a:?}}}"#
        );
        // The parameter table's domains: η in (1, 10], a in (1/√2, 1], σ_a ≥ 0 (all finite).
        let inside = eta > 1.0 && eta <= 10.0 && a > std::f64::consts::FRAC_1_SQRT_2 && a <= 1.0 && sigma >= 0.0;
        let parsed = ParamFile::from_json_str(&text, "fuzz.json");
        prop_assert_eq!(parsed.is_ok(), inside, "{}", text);
    }
}

#[test]
fn numbers_json_cannot_hold_are_errors_not_infinities() {
    // serde_json rejects 1e999 as out of range; it must not become inf silently.
    let text = VALID.replace("\"k_g\": 2", "\"k_g\": 1e999");
    let err = ParamFile::from_json_str(&text, "big.json").unwrap_err();
    assert!(err.to_string().contains("big.json:1:"), "{err}");
}

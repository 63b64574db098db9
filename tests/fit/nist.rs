//! NIST StRD nonlinear regression: the LM solver, run through argmin's Executor, must reach the
//! accuracy targets of hairfit issue 6 on all 27 problems.

use crate::support::nist;

use nist::{data_dir, markdown_table, run_all, solve, NistProblem, NistResult, PROBLEMS};

/// Six correct significant digits is the accuracy the fit needs and NIST's usual bar for a
/// "successful" nonlinear solver.
const MIN_DIGITS: f64 = 6.0;

/// Problems solved to `MIN_DIGITS` from `start`.
fn solved(results: &[NistResult], start: usize) -> Vec<&NistResult> {
    results
        .iter()
        .filter(|r| r.start == start && r.lre_min >= MIN_DIGITS)
        .collect()
}

#[test]
fn nist_strd_accuracy() {
    let results = run_all().expect("the suite's data files parse");
    let table = markdown_table(&results);
    println!("{table}");
    if std::env::var_os("HAIRFIT_WRITE_NIST").is_some() {
        let path = data_dir().join("RESULTS.md");
        std::fs::write(
            &path,
            format!("# NIST StRD results (hairfit LM)\n\n{table}"),
        )
        .expect("RESULTS.md is writable");
    }
    assert_eq!(results.len(), 2 * PROBLEMS.len());
    let s1 = solved(&results, 1).len();
    let s2 = solved(&results, 2).len();
    println!("solved: start 1 {s1}/27, start 2 {s2}/27");
    assert_eq!(s2, 27, "every problem from start 2 to >= 6 digits");
    assert!(s1 >= 25, "at least 25 of 27 from start 1, got {s1}");
}

#[test]
fn malformed_data_is_reported_with_line_and_column() {
    let path = data_dir().join("Misra1a.dat");
    let text = std::fs::read_to_string(&path).unwrap();
    let mut lines: Vec<String> = text.lines().map(String::from).collect();
    // Data starts on line 61 (header: "Data (lines 61 to 74)"); corrupt its x value.
    lines[60] = "      10.07E0      7.7x0E0".into();
    let err = NistProblem::parse("Misra1a", &lines.join("\n"), &path).unwrap_err();
    let msg = err.to_string();
    assert!(msg.contains("Misra1a.dat:61:20:"), "{msg}");
}

#[test]
fn parser_reads_certified_values_and_data_block() {
    let p = NistProblem::load(&data_dir().join("Nelson.dat")).unwrap();
    assert_eq!(p.y.len(), 128);
    assert_eq!(p.x[0], vec![1.0, 180.0]);
    assert_eq!(p.starts[1], vec![2.5, 0.000000005, -0.05]);
    assert_eq!(p.certified[0], 2.5906836021);
    assert_eq!(p.certified_ss, 3.7976833176);
    assert_eq!(p.difficulty, "Average");
}

#[test]
fn ad_jacobian_matches_central_differences() {
    use nalgebra::DVector;
    for name in PROBLEMS {
        let p = NistProblem::load(&data_dir().join(format!("{name}.dat"))).unwrap();
        let b = DVector::from_vec(p.certified.clone());
        let j = p.jacobian(&b);
        for k in 0..b.len() {
            let h = 1e-6 * b[k].abs().max(1e-8);
            let (mut bp, mut bm) = (b.clone(), b.clone());
            bp[k] += h;
            bm[k] -= h;
            let fd = (p.residuals(&bp) - p.residuals(&bm)) / (2.0 * h);
            let scale = fd.abs().max().max(j.column(k).abs().max());
            // Central differences with h ~ 1e-6 relative are accurate to ~1e-8 of the column
            // scale; a wrong hand-written model or AD seed is off by O(1).
            let err = (fd - j.column(k)).abs().max();
            assert!(
                err <= 1e-5 * scale,
                "{name} b{}: err {err:e} scale {scale:e}",
                k + 1
            );
        }
    }
}

#[test]
fn covariance_reproduces_certified_standard_deviations() {
    use hairfit::lm::covariance;
    for name in PROBLEMS {
        let p = NistProblem::load(&data_dir().join(format!("{name}.dat"))).unwrap();
        let r = solve(&p, 2).unwrap();
        let dof = p.y.len() - p.certified.len();
        let j = p.jacobian(&nalgebra::DVector::from_vec(r.param.clone()));
        let cov = covariance(&j, r.ss, dof).expect("every StRD problem has dof > 0");
        assert_eq!(
            cov.rank_deficiency, 0,
            "{name}: all StRD parameters are determined"
        );
        for (k, &sd) in p.certified_sd.iter().enumerate() {
            let ours = cov.matrix[(k, k)].sqrt();
            let rel = (ours / sd - 1.0).abs();
            // Parameters are correct to >= 8 digits, so s²(JᵀJ)⁻¹ matches NIST to ~1e-10 (we see
            // <= 4e-11). Lanczos1's SS (1.4e-25) is rounding noise of y ~ 1, so its s² — and
            // every sd with it — differs from the certified one by ~0.1%.
            let tol = if name == "Lanczos1" { 2e-3 } else { 1e-8 };
            assert!(
                rel <= tol,
                "{name} b{}: sd {ours:e} vs certified {sd:e}",
                k + 1
            );
        }
    }
}

#[test]
fn small_residual_fit_converges_past_the_cost_noise() {
    // Lanczos3: SS = 1.6e-8 on y ~ 1, so the last digits are invisible in the cost. Judging
    // those steps by the gradient lifts it from 6.4 (pure ratio test) to >= 10.5 digits; 9 leaves
    // room for libm differences while still failing if only the ratio test decided.
    let p = NistProblem::load(&data_dir().join("Lanczos3.dat")).unwrap();
    let r = solve(&p, 2).unwrap();
    assert!(r.lre_min >= 9.0, "LRE {}", r.lre_min);
}

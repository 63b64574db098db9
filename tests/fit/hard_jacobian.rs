//! The model's exact (AD) Jacobian at every hard case of MODEL.md, across both root modes, every
//! effect set and parameters at the fit's bounds: every entry finite (no NaN, no ±inf).
//!
//! S itself on these cases is covered by tests/families/marschner_invariants.rs; here the derivative chain is
//! the subject (implicit root derivatives at folds and at h = ±1, `1/cos²θ_d` at grazing, the
//! `∞·0` glint fade at ±φ_c, Gaussians that underflow at the smallest widths).

use std::f64::consts::{FRAC_1_SQRT_2, FRAC_PI_2, PI};

use hairfit::families::marschner::azimuthal::caustic_position;
use hairfit::families::marschner::fit::forward::fit_bound;
use hairfit::families::marschner::parameters::all_parameters;
use hairfit::families::marschner::{
    scattering_jacobian, ModelConfig, ParamName, Params, RootMode, StaticJacobian,
};
use hairfit::fit::bounds::Bound;
use hairfit::geometry::Angles;

const MODES: [RootMode; 2] = [RootMode::Cubic, RootMode::Exact];

/// MODEL.md's known-value parameters, two channels so cross-channel derivatives are exercised.
fn table_params() -> Params<f64> {
    Params {
        eta: 1.55,
        sigma_a: vec![0.4, 0.2],
        alpha_r: (-7f64).to_radians(),
        beta_r: 8f64.to_radians(),
        k_g: 2.0,
        w_c: 15f64.to_radians(),
        eccentricity: 0.9,
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

/// θ_d at which η' = 2 for index η: `cos θ_d = sqrt((η² − 1)/3)`.
fn theta_d_merge(eta: f64) -> f64 {
    ((eta * eta - 1.0) / 3.0).sqrt().acos()
}

/// Symmetric geometry with the given θ_d and φ (θ_h = 0, φ_i = 0).
fn at(theta_d: f64, phi: f64) -> Angles {
    Angles {
        theta_i: -theta_d,
        phi_i: 0.0,
        theta_r: theta_d,
        phi_r: phi,
    }
}

/// Every hard geometry of MODEL.md for index `eta` (glint positions depend on η and the mode).
fn hard_angles(eta: f64) -> Vec<(String, Angles)> {
    let mut v: Vec<(String, Angles)> = Vec::new();
    // θ_d within 1e-6 rad of ±90°, plus 1e-3 (the cubic's leading coefficient ∝ asin(1/η') → 0,
    // the near-degenerate cubic of MODEL.md).
    for d in [1e-6, 1e-3] {
        let g = FRAC_PI_2 - d;
        for phi in [0.0, 0.3, 2.0, PI] {
            v.push((format!("θ_d = +90° − {d:e}, φ = {phi}"), at(g, phi)));
            v.push((format!("θ_d = −90° + {d:e}, φ = {phi}"), at(-g, phi)));
        }
        // Grazing on one side only: θ_h far from the lobes, the Gaussians underflow.
        v.push((
            format!("θ_i = −90° + {d:e}, θ_r = 0"),
            Angles {
                theta_i: -g,
                phi_i: 0.0,
                theta_r: 0.0,
                phi_r: 1.0,
            },
        ));
    }
    // h → ±1: R's root γ = −φ/2 reaches ±π/2 at φ = ∓π; TT's at |φ| = 2c, c = asin(1/η) (θ_d = 0).
    let c = (1.0 / eta).asin();
    for phi in [
        2.0 * c,
        -2.0 * c,
        2.0 * c + 1e-12,
        2.0 * c - 1e-12,
        PI - 4.0 * c,
    ] {
        v.push((format!("h → ±1 (TT), φ = {phi}"), at(0.0, phi)));
    }
    // φ = ±π exactly (both as wrap results and as raw inputs), and φ = 0.
    v.push((
        "φ = π".into(),
        Angles::from_degrees(-10.0, 0.0, 20.0, 180.0),
    ));
    v.push((
        "φ = −π".into(),
        Angles::from_degrees(-10.0, 180.0, 20.0, 0.0),
    ));
    v.push((
        "φ = π, φ_h = π/2".into(),
        Angles::from_degrees(-10.0, -90.0, 20.0, 270.0),
    ));
    v.push(("φ = 0".into(), Angles::from_degrees(-10.0, 0.0, 20.0, 0.0)));
    // η' exactly 2 (for η; the eccentric η* moves it a little) and just either side; for η ≥ 2
    // η' ≥ 2 everywhere and there is no merge angle.
    let tm = theta_d_merge(eta);
    for dt in [0.0, 1e-9, -1e-9].into_iter().filter(|_| tm.is_finite()) {
        for phi in [0.0, 0.1, -0.1, PI] {
            v.push((format!("η' = 2 (θ_d {dt:+e}), φ = {phi}"), at(tm + dt, phi)));
        }
    }
    // φ exactly ±φ_c of each mode's map at θ_d = 0 and at 30°, and a rounding step either side
    // (the cubic's double root: its discriminant is ~0 there).
    for td in [0.0f64, 30f64.to_radians()] {
        let (s, cs) = td.sin_cos();
        let eta_p = (eta * eta - s * s).sqrt() / cs;
        for mode in MODES {
            if let Some((phi_c, _)) = caustic_position(mode, eta_p) {
                for phi in [phi_c, -phi_c, phi_c * (1.0 + 1e-15), phi_c - 1e-9] {
                    v.push((
                        format!("φ = ±φ_c ({mode}), θ_d = {td}, φ = {phi}"),
                        at(td, phi),
                    ));
                }
            }
        }
    }
    // A generic point as a control.
    v.push((
        "generic".into(),
        Angles::from_degrees(-20.0, 0.0, 25.0, 30.0),
    ));
    v
}

/// Named parameter sets: the table values, each fit bound of `parameters::fit_bound`,
/// and MODEL.md's hard parameter values.
fn hard_params() -> Vec<(String, Params<f64>)> {
    let base = table_params();
    let mut v = vec![("table".to_string(), base.clone())];
    let mut with = |name: String, f: &dyn Fn(&mut Params<f64>)| {
        let mut p = base.clone();
        f(&mut p);
        p.validate().unwrap_or_else(|e| panic!("{name}: {e}"));
        v.push((name, p));
    };
    for name in all_parameters(2) {
        let (lo, hi) = match fit_bound(name) {
            Bound::Free => (-(30f64.to_radians()), 30f64.to_radians()),
            Bound::Lower(lo) => (lo, f64::NAN),
            Bound::Both(lo, hi) => (lo, hi),
        };
        for (which, x) in [("lower", lo), ("upper", hi)] {
            if x.is_nan() {
                continue;
            }
            with(
                format!("{} at its {which} fit bound {x}", name.json_name()),
                &|p| p.set(name, x),
            );
        }
    }
    with("σ_a = 0 and 1e6".into(), &|p| p.sigma_a = vec![0.0, 1e6]);
    with("w_c = 0.5°".into(), &|p| p.w_c = 0.5f64.to_radians());
    with("a just above 1/√2".into(), &|p| {
        p.eccentricity = FRAC_1_SQRT_2 + 1e-12
    });
    with("a = 1".into(), &|p| p.eccentricity = 1.0);
    with("η just above 1".into(), &|p| p.eta = 1.0 + 1e-9);
    // Every parameter at its lower bound at once (the corner a fit can reach).
    with("all at lower bounds".into(), &|p| {
        for name in all_parameters(2) {
            if let Bound::Lower(lo) | Bound::Both(lo, _) = fit_bound(name) {
                p.set(name, lo);
            }
        }
    });
    with("all at upper bounds".into(), &|p| {
        for name in all_parameters(2) {
            if let Bound::Both(_, hi) = fit_bound(name) {
                p.set(name, hi);
            }
        }
    });
    v
}

/// Check the full Jacobian (every parameter, both channels) at every hard case; collect failures.
fn sweep(
    params: &[(String, Params<f64>)],
    check: impl Fn(&Params<f64>, &ModelConfig, &Angles) -> Option<String>,
) -> (usize, Vec<String>) {
    let mut failures = Vec::new();
    let mut n = 0;
    for (pname, p) in params {
        let angles = hard_angles(p.eta);
        for mode in MODES {
            for (ename, effects) in hairfit::families::marschner::cost::effect_ladder() {
                let cfg = ModelConfig { mode, effects };
                for (aname, a) in &angles {
                    n += 1;
                    if let Some(msg) = check(p, &cfg, a) {
                        failures.push(format!("[{pname}] [{mode} {ename}] [{aname}]: {msg}"));
                    }
                }
            }
        }
    }
    (n, failures)
}

fn report(n: usize, failures: &[String]) {
    assert!(
        failures.is_empty(),
        "{} of {n} hard cases fail; first ones:\n{}",
        failures.len(),
        failures
            .iter()
            .take(25)
            .cloned()
            .collect::<Vec<_>>()
            .join("\n")
    );
}

#[test]
fn jacobian_finite_at_every_hard_case() {
    let all = all_parameters(2);
    let (n, failures) = sweep(&hard_params(), |p, cfg, a| {
        let (values, jac) = scattering_jacobian(p, cfg, a, &all);
        let ok = values.iter().all(|v| v.is_finite() && *v >= 0.0)
            && jac.iter().flatten().all(|d| d.is_finite());
        (!ok).then(|| format!("S = {values:?}, J = {jac:?}"))
    });
    // Enough cases that the sweep cannot be vacuous.
    assert!(n > 5000, "only {n} cases");
    eprintln!("Jacobian finite at {n} hard cases (11 parameters × 2 channels each)");
    report(n, &failures);
}

/// The fit's fast path (`DualSVec64<N>`) must agree with `DualDVec64` bit for bit: same code,
/// same operations, so any difference would be a seeding bug, not rounding.
#[test]
fn static_and_dynamic_jacobians_agree_at_hard_cases() {
    const NAMES: [ParamName; 6] = [
        ParamName::Eta,
        ParamName::SigmaA(0),
        ParamName::AlphaR,
        ParamName::BetaR,
        ParamName::WC,
        ParamName::Eccentricity,
    ];
    let (n, failures) = sweep(&hard_params()[..4], |p, cfg, a| {
        let (v_dyn, j_dyn) = scattering_jacobian(p, cfg, a, &NAMES);
        let mut sj = StaticJacobian::<6>::new(p, &NAMES);
        let mut v = vec![0.0; 2];
        let mut j = vec![[0.0; 6]; 2];
        sj.eval(cfg, a, &mut v, &mut j);
        let same = v
            .iter()
            .zip(&v_dyn)
            .all(|(x, y)| x.to_bits() == y.to_bits())
            && j.iter()
                .zip(&j_dyn)
                .all(|(r, rd)| r.iter().zip(rd).all(|(x, y)| x.to_bits() == y.to_bits()));
        (!same).then(|| format!("static {v:?} {j:?} vs dynamic {v_dyn:?} {j_dyn:?}"))
    });
    report(n, &failures);
}

/// Where S is smooth in a parameter, the AD derivative must match a central difference even at
/// the bounds (a finite but wrong derivative would steer the fit as badly as a NaN). Checked at
/// the generic point and at grazing θ_d, for each parameter at each bound, one-sided into the
/// domain when the bound is closed.
#[test]
fn jacobian_matches_finite_differences_at_bounds() {
    let all = all_parameters(2);
    let cases = [
        ("generic", Angles::from_degrees(-20.0, 0.0, 25.0, 30.0)),
        ("TT side", Angles::from_degrees(10.0, -40.0, -5.0, 170.0)),
        ("grazing θ_d = 89.9°", at(89.9f64.to_radians(), 2.0)),
    ];
    let mut failures = Vec::new();
    let mut n = 0;
    let mut unresolved = 0;
    for (pname, p) in hard_params() {
        for mode in MODES {
            for (ename, effects) in hairfit::families::marschner::cost::effect_ladder() {
                let cfg = ModelConfig { mode, effects };
                for (aname, a) in &cases {
                    let (v0, jac) = scattering_jacobian(&p, &cfg, a, &all);
                    for (j, &name) in all.iter().enumerate() {
                        let x = p.get(name);
                        // Step 1e-6 of the parameter's own scale: truncation O(h²)·S''' and
                        // rounding O(ε/h)·S both stay near 1e-10·scale, far below the 1e-4
                        // relative tolerance below. η's scale is η − 1 (Fresnel ∝ (η − 1)²).
                        let own = match name {
                            ParamName::Eta => x - 1.0,
                            _ => x.abs().max(1e-2),
                        };
                        // At least ~4500 ulps of x, or the steps themselves are quantised.
                        let h = (1e-6 * own).max(1e-12 * x.abs());
                        let s_at = |xv: f64| {
                            let mut q = p.clone();
                            q.set(name, xv);
                            if q.validate().is_err() {
                                return None;
                            }
                            let mut out = vec![0.0; 2];
                            hairfit::families::marschner::scattering(&q, &cfg, a, &mut out);
                            Some(out)
                        };
                        // Central where the model's domain allows (the fit bounds are narrower
                        // than the domain), else one-sided into the domain.
                        let fd_with = |h: f64| -> Option<Vec<f64>> {
                            let (xm, xp) = match (s_at(x - h), s_at(x + h)) {
                                (Some(_), Some(_)) => (x - h, x + h),
                                (None, Some(_)) => (x, x + h),
                                (Some(_), None) => (x - h, x),
                                (None, None) => return None,
                            };
                            let (sp, sm) = (s_at(xp)?, s_at(xm)?);
                            Some((0..2).map(|c| (sp[c] - sm[c]) / (xp - xm)).collect())
                        };
                        let (Some(fd1), Some(fd4)) = (fd_with(h), fd_with(4.0 * h)) else {
                            continue;
                        };
                        for c in 0..2 {
                            let ad = jac[c][j];
                            let (fd, fd_4) = (fd1[c], fd4[c]);
                            let scale = ad.abs().max(fd.abs()).max(v0[c].abs() * 1e-3);
                            // FD is only a referee where it is resolved: steps h and 4h agree to
                            // 1e-5. Where cancellation inside S (e.g. η* − 1 ~ 1e-9) drowns a
                            // 1e-6 step in rounding, they do not, and AD is the only exact answer.
                            if (fd - fd_4).abs() > 1e-5 * scale + 1e-300 {
                                unresolved += 1;
                                continue;
                            }
                            n += 1;
                            // Central/one-sided differences at h = 1e-6 of the scale have
                            // truncation error ≤ ~1e-6 relative unless the curvature is ~100×
                            // the slope, so 1e-4 relative only flags a wrong derivative.
                            if (fd - ad).abs() > 1e-4 * scale + 1e-300 {
                                failures.push(format!(
                                    "[{pname}] [{mode} {ename}] [{aname}] ∂S_{c}/∂{}: AD {ad:e}, FD {fd:e}",
                                    name.json_name()
                                ));
                            }
                        }
                    }
                }
            }
        }
    }
    eprintln!("AD = FD at {n} resolved comparisons ({unresolved} unresolved by FD, skipped)");
    // The referee must have judged nearly everything, or the test would be vacuous.
    assert!(
        unresolved * 20 < n,
        "FD unresolved at {unresolved} of {} comparisons",
        n + unresolved
    );
    assert!(n > 1000, "only {n} comparisons");
    report(n, &failures);
}

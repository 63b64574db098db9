//! MODEL.md invariants 1–6 and the named hard cases.

use crate::support::model::*;
use hairfit::families::marschner::azimuthal::caustic_position;
use hairfit::families::marschner::exit_angle::ExitMap;
use hairfit::families::marschner::roots::exit_roots;
use hairfit::families::marschner::{
    instrument, scattering, scattering_by_lobe, scattering_jacobian, Effects, Lobes, ModelConfig,
    ParamName, Params, RootMode,
};
use hairfit::geometry::Angles;
use std::f64::consts::{FRAC_1_SQRT_2, PI};

/// A change to a parameter set.
type Patch = fn(&mut Params<f64>);

const MODES: [RootMode; 2] = [RootMode::Cubic, RootMode::Exact];

/// θ_d at which η' = 2 for index η: `cos θ_d = sqrt((η² − 1)/3)`.
fn theta_d_merge(eta: f64) -> f64 {
    ((eta * eta - 1.0) / 3.0).sqrt().acos()
}

// ---------- Invariant 1: energy ----------

/// `∫ N_p dφ` with the range split at every kink/singularity of N_p.
fn energy_lhs(params: &Params<f64>, cfg: &ModelConfig, p: usize, theta_d: f64) -> f64 {
    let eta_p = {
        let (s, c) = theta_d.sin_cos();
        (params.eta * params.eta - s * s).sqrt() / c
    };
    let c = (1.0 / eta_p).asin();
    let mut cuts = vec![-PI, 0.0, PI, 2.0 * c, -2.0 * c, PI - 4.0 * c, 4.0 * c - PI];
    if let Some((phi_c, _)) = caustic_position(cfg.mode, eta_p) {
        cuts.extend([phi_c, -phi_c]);
    }
    cuts.retain(|x| x.abs() <= PI);
    cuts.sort_by(f64::total_cmp);
    cuts.dedup();
    cuts.windows(2)
        .map(|w| tanh_sinh(|phi| n_p(params, cfg, p, theta_d, phi), w[0], w[1]))
        .sum()
}

/// `½ ∫_{−1}^{1} A(p, h) dh`.
fn energy_rhs(params: &Params<f64>, p: usize, theta_d: f64) -> f64 {
    0.5 * tanh_sinh(|h| attenuation(params, p, theta_d, h), -1.0, 1.0)
}

#[test]
fn energy_r_and_tt_both_modes_trt_exact() {
    let mut params = table_params();
    params.eccentricity = 1.0;
    params.alpha_r = 0.0;
    for theta_d in [0.0, 0.3, -0.7, 1.2] {
        for (mode, p) in [
            (RootMode::Cubic, 0),
            (RootMode::Cubic, 1),
            (RootMode::Exact, 0),
            (RootMode::Exact, 1),
            (RootMode::Exact, 2),
            // Not required by MODEL.md, but the cubic map is one consistent map too.
            (RootMode::Cubic, 2),
        ] {
            let cfg = config(mode, only(p), false, false);
            let lhs = energy_lhs(&params, &cfg, p, theta_d);
            let rhs = energy_rhs(&params, p, theta_d);
            // Quadrature on split smooth pieces is good to ~1e-9; 1e-6 relative still catches
            // any missing root, wrong derivative factor (2×) or wrong Jacobian of the map.
            assert!(
                (lhs - rhs).abs() <= 1e-6 * rhs,
                "{mode} p={p} θ_d={theta_d}: ∫N = {lhs:.10e}, ½∫A = {rhs:.10e}"
            );
        }
    }
}

// ---------- Invariant 2, 3: reciprocity and symmetry ----------

#[test]
fn reciprocity_all_effects() {
    let params = table_params();
    for mode in MODES {
        let cfg = config(mode, Lobes::default(), true, true);
        for a in [
            [-20.0, 0.0, 25.0, 30.0],
            [10.0, -40.0, -5.0, 170.0],
            [-60.0, 10.0, 45.0, -80.0],
            [33.0, 123.0, -71.0, -150.0],
            [0.0, 0.0, 0.0, 180.0],
        ] {
            let s1 = s(&params, &cfg, &Angles::from_degrees(a[0], a[1], a[2], a[3]));
            let s2 = s(&params, &cfg, &Angles::from_degrees(a[2], a[3], a[0], a[1]));
            // Swapping only negates θ_d and φ: the roots are mirrored, equal up to rounding.
            assert!(
                (s1 - s2).abs() <= 1e-12 * s1.abs(),
                "{mode} {a:?}: {s1} vs {s2}"
            );
        }
    }
}

#[test]
fn symmetry_in_phi_for_round_fiber() {
    let mut params = table_params();
    params.eccentricity = 1.0;
    for mode in MODES {
        let cfg = config(mode, Lobes::default(), true, true);
        for phi in [5.0, 30.0, 77.0, 120.0, 179.0] {
            let a = Angles::from_degrees(-15.0, 0.0, 35.0, phi);
            let b = Angles::from_degrees(-15.0, 0.0, 35.0, -phi);
            let (sa, sb) = (s(&params, &cfg, &a), s(&params, &cfg, &b));
            // Mirror-image roots: equal to rounding.
            assert!(
                (sa - sb).abs() <= 1e-12 * sa,
                "{mode} φ={phi}: {sa} vs {sb}"
            );
        }
    }
    // And with a ≠ 1 the eccentric index really changes S with φ_h (so the test above is not vacuous).
    let params = table_params();
    let cfg = config(RootMode::Cubic, only(2), true, true);
    let a = s(&params, &cfg, &Angles::from_degrees(-15.0, 0.0, 35.0, 40.0));
    let b = s(
        &params,
        &cfg,
        &Angles::from_degrees(-15.0, 50.0, 35.0, 90.0),
    );
    assert!(
        (a - b).abs() > 1e-3 * a,
        "eccentricity has no effect: {a} vs {b}"
    );
}

// ---------- Invariant 4: continuity across η' = 2, boundedness next to φ_c ----------

#[test]
fn trt_continuous_across_merge() {
    let mut params = table_params();
    params.eccentricity = 1.0;
    let td = theta_d_merge(params.eta);
    for mode in MODES {
        let cfg = config(mode, only(2), true, false);
        for phi in [0.0, 0.05, 0.3, 1.0, 2.5] {
            let at = n_p(&params, &cfg, 2, td, phi);
            for eps in [1e-6, 1e-9] {
                let below = n_p(&params, &cfg, 2, td - eps, phi);
                let above = n_p(&params, &cfg, 2, td + eps, phi);
                // Near the merge φ_c and h_c move like (2 − η')^{1/2}, so a θ_d step of ε may
                // change N by ~C·sqrt(ε); a jump (wrong t, Δh or φ_c branch) would be O(N).
                let tol = 0.02 * at.max(1e-3) * (eps / 1e-6).sqrt() + 1e-12;
                assert!(
                    (below - at).abs() <= tol && (above - at).abs() <= tol,
                    "{mode} φ={phi} ε={eps}: {below} | {at} | {above}"
                );
            }
        }
    }
}

/// The fold of the map the roots use, computed here from MODEL.md's formulas (not the crate's):
/// cubic `γ_c = sqrt(−b/(3a))`, exact `h_c = sqrt((4 − η'²)/3)`.
fn fold_phi(mode: RootMode, eta_p: f64) -> f64 {
    let c = (1.0 / eta_p).asin();
    let phi = match mode {
        RootMode::Cubic => {
            let a = -16.0 * c / PI.powi(3);
            let b = 12.0 * c / PI - 2.0;
            let g = (-b / (3.0 * a)).sqrt();
            a * g.powi(3) + b * g
        }
        RootMode::Exact => {
            let h = ((4.0 - eta_p * eta_p) / 3.0).sqrt();
            4.0 * (h / eta_p).asin() - 2.0 * h.asin()
        }
    };
    phi.abs()
}

#[test]
fn trt_bounded_next_to_caustic_trap() {
    let mut params = table_params();
    params.eccentricity = 1.0;
    for mode in MODES {
        let cfg = config(mode, only(2), true, false);
        for theta_d in [0.0f64, 0.4] {
            let eta_p = (params.eta.powi(2) - theta_d.sin().powi(2)).sqrt() / theta_d.cos();
            let phi_c = fold_phi(mode, eta_p);
            let (crate_phi_c, _) = caustic_position(mode, eta_p).unwrap();
            assert!(
                (phi_c - crate_phi_c).abs() < 1e-12,
                "{mode}: φ_c {phi_c} vs {crate_phi_c}"
            );
            // At the fold the exact value is the glint alone (N_2·0); next to it N_2·(1−G)²
            // behaves like δ^{3/2} → 0, so N_TRT is the smooth glint Gaussian (width w_c = 0.26
            // rad) there: within 2× of its value 0.1 rad away. A map mixed with another mode's
            // caustic spikes like 1/sqrt(δ) there (≥ 1e3 × that bound at δ = 1e-12).
            let bound = 2.0
                * n_p(&params, &cfg, 2, theta_d, phi_c - 0.1).max(n_p(
                    &params,
                    &cfg,
                    2,
                    theta_d,
                    phi_c + 0.1,
                ));
            for sign in [1.0, -1.0] {
                let at = n_p(&params, &cfg, 2, theta_d, sign * phi_c);
                assert!(
                    at.is_finite() && at > 0.0 && at <= bound,
                    "{mode}: N_TRT(φ_c) = {at}"
                );
                for k in 1..=12 {
                    for side in [1.0, -1.0] {
                        let phi = sign * (phi_c + side * 10f64.powi(-k));
                        let v = n_p(&params, &cfg, 2, theta_d, phi);
                        assert!(
                            v.is_finite() && v <= bound,
                            "{mode} θ_d={theta_d} φ={phi}: N_TRT {v} vs bound {bound}"
                        );
                    }
                }
            }
            // The Jacobian stays bounded next to the fold too (the fade's δ² beats the
            // implicit-function 1/δ^{3/2}): within 10× its size 0.1 rad away.
            let which = [
                ParamName::Eta,
                ParamName::SigmaA(0),
                ParamName::AlphaR,
                ParamName::WC,
            ];
            let jac_at = |phi: f64| {
                let a = Angles {
                    theta_i: -theta_d,
                    phi_i: 0.0,
                    theta_r: theta_d,
                    phi_r: phi,
                };
                scattering_jacobian(&params, &cfg, &a, &which).1[0].clone()
            };
            let scale: f64 = jac_at(phi_c - 0.1)
                .iter()
                .map(|d| d.abs())
                .fold(0.0, f64::max);
            for k in 2..=14 {
                for side in [1.0, -1.0] {
                    let j = jac_at(phi_c + side * 10f64.powi(-k));
                    assert!(
                        j.iter().all(|d| d.is_finite() && d.abs() <= 10.0 * scale),
                        "{mode} k={k}: {j:?} vs {scale}"
                    );
                }
            }
            // Exactly at ±φ_c: finite value and finite derivatives.
            for sign in [1.0, -1.0] {
                let a = Angles {
                    theta_i: -theta_d,
                    phi_i: 0.0,
                    theta_r: theta_d,
                    phi_r: sign * crate_phi_c,
                };
                let which = [
                    ParamName::Eta,
                    ParamName::SigmaA(0),
                    ParamName::KG,
                    ParamName::WC,
                ];
                let (v, j) = scattering_jacobian(&params, &cfg, &a, &which);
                assert!(
                    v[0].is_finite() && j[0].iter().all(|d| d.is_finite()),
                    "{v:?} {j:?}"
                );
            }
        }
    }
}

// ---------- Invariant 5: S ≥ 0 and finite on hard cases; domain errors ----------

fn assert_finite_nonneg(params: &Params<f64>, a: &Angles, what: &str) {
    for mode in MODES {
        for glints in [true, false] {
            let cfg = config(mode, Lobes::default(), glints, true);
            let mut out = vec![[0.0; 3]; params.sigma_a.len()];
            scattering_by_lobe(params, &cfg, a, &mut out);
            for lobe in out.iter().flatten() {
                assert!(
                    lobe.is_finite() && *lobe >= 0.0,
                    "{what} {mode} glints={glints}: {out:?}"
                );
            }
        }
    }
}

#[test]
fn hard_cases_finite_and_nonnegative() {
    let base = table_params();
    let grazing = std::f64::consts::FRAC_PI_2 - 1e-6;
    let angle_cases = [
        (
            "θ_d → +90°",
            Angles {
                theta_i: -grazing,
                phi_i: 0.0,
                theta_r: grazing,
                phi_r: 0.3,
            },
        ),
        (
            "θ_d → −90°",
            Angles {
                theta_i: grazing,
                phi_i: 0.0,
                theta_r: -grazing,
                phi_r: 2.0,
            },
        ),
        ("φ = π", Angles::from_degrees(-10.0, 0.0, 20.0, 180.0)),
        ("φ = −π", Angles::from_degrees(-10.0, 180.0, 20.0, 0.0)),
        ("φ = 0", Angles::from_degrees(-10.0, 0.0, 20.0, 0.0)),
    ];
    for (what, a) in &angle_cases {
        assert_finite_nonneg(&base, a, what);
    }
    let generic = Angles::from_degrees(-20.0, 0.0, 25.0, 30.0);
    let variants: [(&str, Patch); 6] = [
        ("σ_a = 0", |p| p.sigma_a = vec![0.0, 1e6]),
        ("σ_a = 1e6", |p| p.sigma_a = vec![1e6]),
        ("w_c = 0.5°", |p| p.w_c = 0.5f64.to_radians()),
        ("a just above 1/√2", |p| {
            p.eccentricity = FRAC_1_SQRT_2 + 1e-12
        }),
        ("a = 1", |p| p.eccentricity = 1.0),
        ("η near 1", |p| p.eta = 1.0 + 1e-9),
    ];
    for (what, f) in variants {
        let mut p = base.clone();
        f(&mut p);
        p.validate().unwrap();
        for (w2, a) in angle_cases.iter().chain([("generic", generic)].iter()) {
            assert_finite_nonneg(&p, a, &format!("{what}, {w2}"));
        }
    }
    // h → ±1: TT roots at the ends of its range, |φ| = 2c (h = ±1 exactly).
    let c = (1.0 / base.eta).asin();
    for phi in [2.0 * c, -2.0 * c, 2.0 * c + 1e-12, PI - 4.0 * c] {
        assert_finite_nonneg(
            &base,
            &Angles {
                theta_i: 0.0,
                phi_i: 0.0,
                theta_r: 0.0,
                phi_r: phi,
            },
            "h → ±1",
        );
    }
    // η' exactly 2 (a = 1 so TRT sees η) and φ exactly ±φ_c.
    let mut round = base.clone();
    round.eccentricity = 1.0;
    let td = theta_d_merge(round.eta);
    for phi in [0.0, 0.1, -0.1, PI] {
        assert_finite_nonneg(
            &round,
            &Angles {
                theta_i: -td,
                phi_i: 0.0,
                theta_r: td,
                phi_r: phi,
            },
            "η' = 2",
        );
    }
    for mode in MODES {
        let (phi_c, _) = caustic_position(mode, round.eta).unwrap();
        for phi in [phi_c, -phi_c] {
            assert_finite_nonneg(
                &round,
                &Angles {
                    theta_i: 0.0,
                    phi_i: 0.0,
                    theta_r: 0.0,
                    phi_r: phi,
                },
                "φ = ±φ_c",
            );
        }
    }
}

#[test]
fn huge_sigma_a_kills_transmission_without_nan() {
    let mut p = table_params();
    p.sigma_a = vec![1e6];
    let a = Angles::from_degrees(-20.0, 0.0, 25.0, 150.0);
    for mode in MODES {
        let cfg = config(mode, Lobes::default(), true, true);
        let mut out = [[0.0; 3]];
        scattering_by_lobe(&p, &cfg, &a, &mut out);
        assert!(
            out[0][0] > 0.0 && out[0][1] == 0.0 && out[0][2] == 0.0,
            "{out:?}"
        );
        let (_, j) = scattering_jacobian(&p, &cfg, &a, &[ParamName::SigmaA(0), ParamName::Eta]);
        assert!(j[0].iter().all(|d| d.is_finite()), "{j:?}");
    }
}

#[test]
fn out_of_domain_parameters_are_errors() {
    let cases: [(&str, Patch); 9] = [
        ("eccentricity", |p| p.eccentricity = 0.5),
        ("eccentricity", |p| p.eccentricity = FRAC_1_SQRT_2),
        ("eccentricity", |p| p.eccentricity = 1.01),
        ("eta", |p| p.eta = 1.0),
        ("beta_r_deg", |p| p.beta_r = 0.0),
        ("w_c_deg", |p| p.w_c = -0.1),
        ("sigma_a[0]", |p| p.sigma_a = vec![-1.0]),
        ("k_g", |p| p.k_g = f64::NAN),
        ("delta_h_m", |p| p.delta_h_m = 0.0),
    ];
    for (name, f) in cases {
        let mut p = table_params();
        f(&mut p);
        match p.validate() {
            Err(hairfit::Error::Parameter {
                name: n, message, ..
            }) => {
                assert_eq!(n, name);
                assert!(!message.is_empty());
            }
            other => panic!("{name}: expected a parameter error, got {other:?}"),
        }
    }
    assert!(table_params().validate().is_ok());
}

// ---------- Invariant 6: disabled lobes and effects cost nothing ----------

fn counts_for(effects: Effects, mode: RootMode) -> instrument::Counts {
    let p = table_params();
    instrument::reset();
    let mut out = [0.0];
    scattering(
        &p,
        &ModelConfig { mode, effects },
        &Angles::from_degrees(-20.0, 0.0, 25.0, 30.0),
        &mut out,
    );
    instrument::counts()
}

#[test]
fn disabled_lobes_and_effects_are_not_computed() {
    let lobes = |r, tt, trt| Lobes { r, tt, trt };
    for mode in MODES {
        let c = counts_for(
            Effects {
                lobes: lobes(true, false, false),
                glints: true,
                eccentricity: true,
            },
            mode,
        );
        assert_eq!(
            c,
            instrument::Counts::default(),
            "R only must solve nothing"
        );
        let c = counts_for(
            Effects {
                lobes: lobes(true, true, false),
                glints: true,
                eccentricity: true,
            },
            mode,
        );
        assert_eq!(
            (
                c.tt_root_solves,
                c.trt_root_solves,
                c.caustics,
                c.eccentricity
            ),
            (1, 0, 0, 0)
        );
        let c = counts_for(
            Effects {
                lobes: lobes(false, false, true),
                glints: false,
                eccentricity: false,
            },
            mode,
        );
        assert_eq!(
            (
                c.tt_root_solves,
                c.trt_root_solves,
                c.caustics,
                c.eccentricity
            ),
            (0, 1, 0, 0)
        );
        let c = counts_for(Effects::default(), mode);
        assert_eq!(
            (
                c.tt_root_solves,
                c.trt_root_solves,
                c.caustics,
                c.eccentricity
            ),
            (1, 1, 1, 1)
        );
    }
}

// ---------- Roots ----------

#[test]
fn cubic_with_vanishing_leading_coefficient_degrades_to_linear() {
    // η' = 1e16 ⇒ c ≈ 1e-16 and the cubic's a ≈ −5e-17: the map is −2γ + pπ to rounding.
    for p in [1, 2] {
        let map = ExitMap::new(RootMode::Cubic, p, 1e16);
        // (φ = 0 for TT is the edge γ = ±π/2 of its range: excluded.)
        for phi in [-3.0, -1.0, 0.5, 3.1, if p == 2 { 0.0 } else { 1.0 }] {
            let r = exit_roots(&map, phi);
            assert_eq!(r.n, 1, "p={p} φ={phi}");
            let lin = hairfit::geometry::angles::wrap(p as f64 * PI - phi) / 2.0;
            // Roots of −2γ + O(1e-16): agree with the linear solution to ~1e-15.
            assert!(
                (r.gamma[0] - lin).abs() < 1e-13,
                "p={p} φ={phi}: {} vs {lin}",
                r.gamma[0]
            );
        }
    }
}

#[test]
fn exact_tt_root_matches_closed_form() {
    // MODEL.md's closed form h = s·cos(φ/2)/sqrt(1 + a² − 2as·sin(φ/2)), a = 1/η'.
    for eta_p in [1.2, 1.55, 3.0] {
        let map = ExitMap::new(RootMode::Exact, 1, eta_p);
        let a = 1.0 / eta_p;
        for phi in [-3.0, -2.0, 1.9, 2.5, 3.1] {
            let r = exit_roots(&map, phi);
            if r.n == 0 {
                assert!(phi.abs() < 2.0 * a.asin(), "missing TT root at φ={phi}");
                continue;
            }
            let s = phi.signum();
            let h = s * (phi / 2.0).cos() / (1.0 + a * a - 2.0 * a * s * (phi / 2.0).sin()).sqrt();
            // Both are the root to ~machine precision; sin γ is well conditioned here.
            assert!((r.gamma[0].sin() - h).abs() < 1e-12, "η'={eta_p} φ={phi}");
            // And the root solves MODEL.md's exact map 2·asin(h/η') − 2·asin(h) + π ≡ φ.
            let phi_out = 2.0 * (h / eta_p).asin() - 2.0 * h.asin() + PI;
            let miss = hairfit::geometry::angles::wrap(phi_out - phi);
            assert!(miss.abs() < 1e-12, "η'={eta_p} φ={phi}: Φ misses by {miss}");
        }
    }
}

#[test]
fn trt_root_counts() {
    for mode in MODES {
        let map = ExitMap::new(mode, 2, 1.55);
        let (phi_c, _) = caustic_position(mode, 1.55).unwrap();
        assert_eq!(exit_roots(&map, 0.5 * phi_c).n, 3, "{mode}");
        assert_eq!(exit_roots(&map, -0.5 * phi_c).n, 3, "{mode}");
        // Past both φ_c and π − 4c (the outer pieces' far ends) no path exits: zero roots, and
        // between them two (φ_c > π − 4c: right piece + middle) or one (left piece only);
        // MODEL.md's "one or three" omits these windows.
        let outer = PI - 4.0 * (1.0f64 / 1.55).asin();
        assert_eq!(exit_roots(&map, phi_c.max(outer) + 0.3).n, 0, "{mode}");
        let (lo, hi) = (phi_c.min(outer), phi_c.max(outer));
        let window = if phi_c > outer { 2 } else { 1 };
        assert_eq!(exit_roots(&map, 0.5 * (lo + hi)).n, window, "{mode}");
        assert_eq!(exit_roots(&map, -0.5 * (lo + hi)).n, window, "{mode}");
        let past = ExitMap::new(mode, 2, 2.5);
        assert_eq!(exit_roots(&past, 0.1).n, 1, "{mode}");
    }
}

#[test]
fn roots_solve_the_map_to_machine_precision() {
    for mode in MODES {
        for p in [1, 2] {
            for eta_p in [1.05, 1.3, 1.55, 1.99, 2.0, 2.2, 5.0, 1e4] {
                let map = ExitMap::new(mode, p, eta_p);
                for i in 0..=720 {
                    let phi = hairfit::geometry::angles::wrap(-PI + i as f64 * PI / 360.0 + 1e-7);
                    let r = exit_roots(&map, phi);
                    for k in 0..r.n {
                        let g = r.gamma[k];
                        let miss = map.value(&g) - r.target[k];
                        // Φ is evaluated with a few ulps of error (|Φ| ≤ 3π): 1e-13 absolute.
                        assert!(
                            miss.abs() <= 1e-13 && g.abs() <= std::f64::consts::FRAC_PI_2,
                            "{mode} p={p} η'={eta_p} φ={phi}: root {g} misses by {miss}"
                        );
                        assert!(hairfit::geometry::angles::wrap(r.target[k] - phi).abs() < 1e-12);
                    }
                }
            }
        }
    }
}

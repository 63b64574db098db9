//! Forward-mode AD Jacobians against central finite differences, for every parameter.

use crate::support::model::*;
use hairfit::families::marschner::{
    scattering, scattering_jacobian, Lobes, ModelConfig, ParamName, Params, RootMode,
    StaticJacobian,
};
use hairfit::geometry::Angles;
use num_dual::DualSVec64;

fn with_value(params: &Params<f64>, name: ParamName, v: f64) -> Params<f64> {
    let mut p = params.clone();
    p.set(name, v);
    p
}

const ALL: [ParamName; 10] = [
    ParamName::Eta,
    ParamName::SigmaA(0),
    ParamName::SigmaA(1),
    ParamName::AlphaR,
    ParamName::BetaR,
    ParamName::KG,
    ParamName::WC,
    ParamName::Eccentricity,
    ParamName::DeltaEtaPrime,
    ParamName::DeltaHM,
];

/// Generic points away from kinks: below the merge (3 TRT roots, glint on), with a root pair not
/// too close to φ_c, and one in the fade window 2 < η' < 2 + Δη' (so Δη' and Δh_M matter).
/// (Last point: φ_h = 90° so η* = η*_2 ≈ 1.81 and θ_d = 40° give η' ≈ 2.21.)
const POINTS: [[f64; 4]; 4] = [
    [-20.0, 0.0, 25.0, 30.0],
    [10.0, -40.0, -5.0, 170.0],
    [-25.0, 30.0, 15.0, 35.0],
    [-35.0, 85.0, 45.0, 95.0],
];

#[test]
fn ad_matches_central_differences() {
    let mut params = table_params();
    params.sigma_a = vec![0.4, 1.3];
    for mode in [RootMode::Cubic, RootMode::Exact] {
        let cfg = config(mode, Lobes::default(), true, true);
        for a in POINTS {
            let angles = Angles::from_degrees(a[0], a[1], a[2], a[3]);
            let (values, jac) = scattering_jacobian(&params, &cfg, &angles, &ALL);
            let mut plain = [0.0; 2];
            scattering(&params, &cfg, &angles, &mut plain);
            // The dual real part is the f64 model up to the one extra Newton step (rounding).
            for c in 0..2 {
                assert!((values[c] - plain[c]).abs() <= 1e-12 * plain[c]);
            }
            if a == POINTS[3] {
                // The fade-window point really exercises Δη' and Δh_M.
                assert!(jac[0][8] != 0.0 && jac[0][9] != 0.0, "{mode}: {:?}", jac[0]);
            }
            for (j, &name) in ALL.iter().enumerate() {
                let x = params.get(name);
                let h = 1e-6 * x.abs().max(1e-2);
                let mut plus = [0.0; 2];
                let mut minus = [0.0; 2];
                scattering(&with_value(&params, name, x + h), &cfg, &angles, &mut plus);
                scattering(&with_value(&params, name, x - h), &cfg, &angles, &mut minus);
                for c in 0..2 {
                    let fd = (plus[c] - minus[c]) / (2.0 * h);
                    let ad = jac[c][j];
                    // Central FD error ≈ ε|S|/h + h²|S'''| ≈ 1e-10|S|: 1e-6 of max(|S'|, |S|)
                    // leaves margin for curvature, while a missing implicit-function term or a
                    // wrong chain-rule factor shows up at ≥ 1e-3.
                    let tol = 1e-6 * ad.abs().max(values[c]);
                    assert!(
                        (ad - fd).abs() <= tol,
                        "{mode} {a:?} ∂S_{c}/∂{name}: AD {ad:.10e} vs FD {fd:.10e}"
                    );
                }
            }
        }
    }
}

#[test]
fn derivative_wrt_other_channel_sigma_is_zero_and_unused_params_zero() {
    let mut params = table_params();
    params.sigma_a = vec![0.4, 1.3];
    let cfg = config(RootMode::Cubic, only(0), true, true);
    let angles = Angles::from_degrees(-20.0, 0.0, 25.0, 30.0);
    let (_, jac) = scattering_jacobian(&params, &cfg, &angles, &ALL);
    // R alone depends on η, α_R, β_R only (Effects::parameters says so too).
    let used = cfg.effects.parameters(2);
    for (j, name) in ALL.iter().enumerate() {
        if !used.contains(name) {
            assert_eq!(jac[0][j], 0.0, "{name}");
        } else {
            assert!(jac[0][j] != 0.0, "{name}");
        }
    }
}

#[test]
fn static_dual_vectors_give_the_same_jacobian() {
    // The generic model takes DualSVec64<N> too (no heap): same numbers as the DualDVec64 helper.
    let params = table_params();
    let cfg = ModelConfig::default();
    let angles = Angles::from_degrees(10.0, -40.0, -5.0, 170.0);
    let which = [ParamName::Eta, ParamName::Eccentricity];
    let (_, jac) = scattering_jacobian(&params, &cfg, &angles, &which);
    let d = |v: f64, i: Option<usize>| match i {
        Some(i) => DualSVec64::<2>::from_re(v).derivative(i),
        None => DualSVec64::<2>::from_re(v),
    };
    let p = Params {
        eta: d(params.eta, Some(0)),
        sigma_a: vec![d(params.sigma_a[0], None)],
        alpha_r: d(params.alpha_r, None),
        beta_r: d(params.beta_r, None),
        k_g: d(params.k_g, None),
        w_c: d(params.w_c, None),
        eccentricity: d(params.eccentricity, Some(1)),
        delta_eta_prime: d(params.delta_eta_prime, None),
        delta_h_m: d(params.delta_h_m, None),
    };
    let mut out = [DualSVec64::<2>::from_re(0.0)];
    scattering(&p, &cfg, &angles, &mut out);
    let eps = out[0].eps.unwrap_generic(nalgebra::U2, nalgebra::U1);
    // Same operations in the same order: equal to rounding.
    assert!((eps[0] - jac[0][0]).abs() <= 1e-12 * jac[0][0].abs());
    assert!((eps[1] - jac[0][1]).abs() <= 1e-12 * jac[0][1].abs());
    // And the reusable StaticJacobian gives the same, too.
    let mut sj = StaticJacobian::<2>::new(&params, &which);
    let (mut v, mut j) = ([0.0], [[0.0; 2]]);
    sj.eval(&cfg, &angles, &mut v, &mut j);
    assert_eq!(j[0], [eps[0], eps[1]]);
    assert_eq!(v[0], out[0].re);
}

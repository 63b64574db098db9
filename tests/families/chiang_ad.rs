//! Chiang's stack-dual Jacobian against the heap-dual one, and the effect switches'
//! bookkeeping (additivity, parameters that drop out); the Jacobian against central
//! differences is the family battery's.

use hairfit::families::chiang::{
    batch_jacobian, batch_jacobian_static, scattering_batch, ChiangEffects, ChiangModel,
    ChiangParamName, ChiangParams,
};
use hairfit::geometry::Angles;

fn three_channels() -> ChiangParams<f64> {
    ChiangParams {
        eta: 1.55,
        sigma_a: vec![0.2, 0.5, 1.1],
        beta_m: 0.25,
        beta_n: 0.4,
        alpha: 3f64.to_radians(),
    }
}

/// Samples with repeated exit directions (the batch cache is exercised) and mirrored φ.
fn angles() -> Vec<Angles> {
    let mut a = Vec::new();
    for (tr, phi) in [(25.0, 30.0), (-5.0, 170.0), (45.0, -80.0), (25.0, -30.0)] {
        for ti in [-60.0, -20.0, 10.0] {
            a.push(Angles::from_degrees(ti, 0.0, tr, phi));
        }
    }
    a
}

const ALL: [ChiangParamName; 7] = [
    ChiangParamName::Eta,
    ChiangParamName::SigmaA(0),
    ChiangParamName::SigmaA(1),
    ChiangParamName::SigmaA(2),
    ChiangParamName::BetaM,
    ChiangParamName::BetaN,
    ChiangParamName::Alpha,
];

fn values(p: &ChiangParams<f64>, m: &ChiangModel, a: &[Angles]) -> Vec<f64> {
    let mut out = vec![0.0; a.len() * p.sigma_a.len()];
    scattering_batch(p, m, a, &mut out);
    out
}

/// The stack-dual path gives the heap-dual Jacobian: the same arithmetic on other storage, so
/// equal to 1e-14 relative (a few ulps of reordering). That the Jacobian is the derivative is
/// the family battery's check (tests/families/battery.rs).
#[test]
fn static_duals_give_the_heap_jacobian() {
    let m = ChiangModel::new(ChiangEffects::default(), 128).unwrap();
    let p = three_channels();
    let a = angles();
    let (v, jac) = batch_jacobian(&p, &m, &a, &ALL);
    // Dual arithmetic rounds slightly differently (powi, exp_m1): real parts agree to 1e-14.
    for (d, f) in v.iter().zip(values(&p, &m, &a)) {
        assert!((d - f).abs() <= 1e-14 * f, "dual real part {d} vs f64 {f}");
    }
    let mut vs = vec![0.0; v.len()];
    let mut js = vec![[0.0; 7]; v.len()];
    batch_jacobian_static(&p, &m, &a, &ALL, &mut vs, &mut js);
    for (x, y) in vs.iter().zip(&v) {
        assert!((x - y).abs() <= 1e-14 * y);
    }
    for k in 0..v.len() {
        for j in 0..7 {
            assert!((js[k][j] - jac[k][j]).abs() <= 1e-14 * jac[k][j].abs().max(1e-300));
        }
    }
}

#[test]
fn terms_add_up_and_switched_off_parameters_drop_out() {
    let p = three_channels();
    let a = angles();
    let one = |r, tt, trt, residual| {
        ChiangModel::new(
            ChiangEffects {
                r,
                tt,
                trt,
                residual,
            },
            128,
        )
        .unwrap()
    };
    let total = values(&p, &one(true, true, true, true), &a);
    let parts: Vec<Vec<f64>> = [
        one(true, false, false, false),
        one(false, true, false, false),
        one(false, false, true, false),
        one(false, false, false, true),
    ]
    .iter()
    .map(|m| values(&p, m, &a))
    .collect();
    for k in 0..total.len() {
        let sum: f64 = parts.iter().map(|v| v[k]).sum();
        assert!((sum - total[k]).abs() <= 1e-14 * total[k], "sample {k}");
        assert!(
            parts.iter().all(|v| v[k] > 0.0),
            "every term contributes at sample {k}"
        );
    }
    // R alone: no σ_a; residual alone: no β_n, no α (azimuthally uniform, untilted).
    for (m, absent) in [
        (one(true, false, false, false), vec![1, 2, 3]),
        (one(false, false, false, true), vec![5, 6]),
    ] {
        let listed = m.effects.parameters(3);
        let (_, jac) = batch_jacobian(&p, &m, &a, &ALL);
        for j in absent {
            assert!(!listed.contains(&ALL[j]), "{} listed", ALL[j]);
            assert!(
                jac.iter().all(|row| row[j] == 0.0),
                "∂S/∂{} not exactly 0",
                ALL[j]
            );
        }
    }
    assert_eq!(ChiangEffects::default().parameters(3), ALL.to_vec());
}

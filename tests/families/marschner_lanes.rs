//! `scattering_lanes` (four or eight samples per vector, what `hairfit eval` runs) against the
//! scalar reference `scattering_batch`, over the whole domain, every effect set, parameter sets
//! that reach the fast path's limits (TT fold, past the glint merge, strong absorption, narrow
//! lobes) and the hard directions (grazing, φ = ±φ_c, φ = ±π).
//!
//! Every lane kernel the CPU runs is tested: wide's vectors on any CPU, the AVX2 one and the
//! eight-lane AVX-512 one where the CPU has them (`scattering_lanes` picks the widest); they do
//! the same IEEE operations, so they must give the same bits.
//!
//! Tolerance: the lanes and the scalar model do the same operations (a few products regrouped)
//! except the transcendental functions (the lanes' own vector sin/cos/exp/asin/acos against
//! libm, each within 1 ulp) and a few divisions replaced by one reciprocal (0.5 ulp each). Along a sample's ~100
//! operations that is ~1e-14 relative. Two places amplify it, in both paths alike: next to a
//! caustic `1/|Φ'|` (bounded by the MIN_DENOM floor), and towards grazing, where
//! `η' = sqrt(η² − sin²θ_d)/cos θ_d` grows without bound and the transmission `1 − F ≈ 4/η'`
//! cancels, so S itself is only known to about `ε·η'` (1e-7 relative at 1e-9 rad from grazing).
//! Far tails amplify too: `exp(−x)` turns an ulp of `x` into `x` ulps of the value, and next to
//! the glint merge (η' → 2) the caustic's position cancels (`b = 6pc/π − 2 → 0`), so glint tails
//! of 1e-29 differ by 2e-11 relative between any two correct implementations. The bound is
//! therefore `1e-11 · (1 + η'_max)` relative plus `1e-15` of the largest S of the comparison
//! (far below the f64 resolution of S at its peak, and below any measurement). Measured worst
//! over these tests: 3e-13 of the relative part. It still fails on any real mistake (a wrong
//! root, a dropped lobe or channel, a wrong fade), which changes S by far more.

use std::f64::consts::PI;

use hairfit::families::marschner::azimuthal::caustic_position;
use hairfit::families::marschner::demo::demo_truth;
use hairfit::families::marschner::eccentricity::eccentric_terms;
use hairfit::families::marschner::{
    scattering_batch, scattering_lanes, scattering_lanes_on, Effects, LaneKernel, Lobes,
    ModelConfig, Params, RootMode,
};
use hairfit::geometry::Angles;

const TOLERANCE: f64 = 1e-11;

/// The kernels this CPU runs: wide's always, the AVX2 one where the CPU has AVX2, the AVX-512
/// one where it has AVX-512F and DQ.
fn kernels() -> Vec<LaneKernel> {
    let kernels = LaneKernel::on_this_cpu();
    if kernels.len() < 3 {
        eprintln!("this CPU runs only {kernels:?}: the others are not tested here");
    }
    kernels
}

/// `1 + η'` at the largest index any lobe of `params` sees at this direction: the conditioning
/// of S towards grazing (see the module note).
fn conditioning(params: &Params<f64>, a: &Angles) -> f64 {
    let (sum, diff) = eccentric_terms(&params.eta, &params.eccentricity);
    let eta = params
        .eta
        .max((sum + diff).abs() / 2.0)
        .max((sum - diff).abs() / 2.0);
    let theta_d = (a.theta_r - a.theta_i) / 2.0;
    1.0 + (eta * eta - theta_d.sin().powi(2)).sqrt() / theta_d.cos()
}

/// xorshift64 in [0, 1).
fn uniform(state: &mut u64) -> f64 {
    *state ^= *state << 13;
    *state ^= *state >> 7;
    *state ^= *state << 17;
    (*state >> 11) as f64 / (1u64 << 53) as f64
}

/// Directions over the whole domain: θ within 1e-9 rad of grazing now and then, φ over ±720°.
fn random_angles(n: usize, seed: u64) -> Vec<Angles> {
    let mut s = seed;
    let theta = |s: &mut u64| {
        let u = uniform(s);
        if u < 0.05 {
            (PI / 2.0 - 1e-9) * if u < 0.025 { 1.0 } else { -1.0 }
        } else {
            (uniform(s) * 2.0 - 1.0) * 89.9f64.to_radians()
        }
    };
    (0..n)
        .map(|_| Angles {
            theta_i: theta(&mut s),
            phi_i: (uniform(&mut s) * 2.0 - 1.0) * 4.0 * PI,
            theta_r: theta(&mut s),
            phi_r: (uniform(&mut s) * 2.0 - 1.0) * 4.0 * PI,
        })
        .collect()
}

/// The demo's parameters (mid-range values) with these absorption coefficients.
fn typical(sigma_a: Vec<f64>) -> Params<f64> {
    Params {
        sigma_a,
        ..demo_truth()
    }
}

/// Parameter sets reaching the limits of the fast path and of the model's domain.
fn parameter_sets() -> Vec<(&'static str, Params<f64>)> {
    let t = typical(vec![0.2, 0.4, 0.8]);
    vec![
        ("typical, 3 channels", t.clone()),
        ("typical, 1 channel", typical(vec![0.4])),
        (
            "5 channels, σ_a = 0 and 1e3",
            typical(vec![0.0, 1e-3, 1.0, 30.0, 1e3]),
        ),
        // η' < 1.155 folds the cubic TT map: those lanes go to the scalar model.
        (
            "eta 1.05 (TT folds)",
            Params {
                eta: 1.05,
                ..t.clone()
            },
        ),
        // Past the merge η' ≥ 2 the glint fades; beyond 2 + Δη' it is gone.
        (
            "eta 2.1 (glint fading)",
            Params {
                eta: 2.1,
                ..t.clone()
            },
        ),
        (
            "eta 3.5 (glint gone)",
            Params {
                eta: 3.5,
                ..t.clone()
            },
        ),
        (
            "a = 0.72, narrow glint",
            Params {
                eccentricity: 0.72,
                w_c: 0.5f64.to_radians(),
                ..t.clone()
            },
        ),
        (
            "narrow lobes",
            Params {
                beta_r: 0.5f64.to_radians(),
                alpha_r: 0.0,
                ..t.clone()
            },
        ),
        (
            "k_g 0, round fiber",
            Params {
                k_g: 0.0,
                eccentricity: 1.0,
                ..t
            },
        ),
    ]
}

fn effect_sets() -> Vec<(&'static str, Effects)> {
    let lobes = |r, tt, trt| Lobes { r, tt, trt };
    let with = |l, glints, eccentricity| Effects {
        lobes: l,
        glints,
        eccentricity,
    };
    vec![
        ("R", with(lobes(true, false, false), false, false)),
        ("TT", with(lobes(false, true, false), false, false)),
        ("TRT", with(lobes(false, false, true), false, false)),
        ("TRT+glints", with(lobes(false, false, true), true, false)),
        (
            "TRT+eccentricity",
            with(lobes(false, false, true), false, true),
        ),
        ("all lobes", with(lobes(true, true, true), false, false)),
        ("all effects", Effects::default()),
    ]
}

/// The worst `|lanes − reference| / (max(|lanes|, |reference|) · conditioning)`; panics at the
/// first value outside the tolerance.
fn compare(params: &Params<f64>, config: &ModelConfig, angles: &[Angles], what: &str) -> f64 {
    kernels()
        .into_iter()
        .map(|kernel| {
            compare_on(
                kernel,
                params,
                config,
                angles,
                &format!("{kernel:?}: {what}"),
            )
        })
        .fold(0.0, f64::max)
}

fn compare_on(
    kernel: LaneKernel,
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    what: &str,
) -> f64 {
    let nc = params.sigma_a.len();
    let mut lanes = vec![f64::NAN; angles.len() * nc];
    let mut reference = vec![f64::NAN; angles.len() * nc];
    scattering_lanes_on(kernel, params, config, angles, &mut lanes);
    scattering_batch(params, config, angles, &mut reference);
    let floor = 1e-15 * reference.iter().fold(0.0f64, |m, v| m.max(v.abs())) + 1e-300;
    let mut worst = 0.0f64;
    for (k, (a, b)) in lanes.iter().zip(&reference).enumerate() {
        assert!(
            a.is_finite() && *a >= 0.0,
            "{what}: S = {a} at {:?}",
            angles[k / nc]
        );
        let diff = (a - b).abs();
        let scale = a.abs().max(b.abs()) * conditioning(params, &angles[k / nc]);
        assert!(
            diff <= TOLERANCE * scale + floor,
            "{what}: lanes {a:e}, reference {b:e} (relative {:e}) at sample {}, channel {}: {:?}",
            diff / scale,
            k / nc,
            k % nc,
            angles[k / nc]
        );
        if diff > floor {
            worst = worst.max(diff / scale);
        }
    }
    worst
}

#[test]
fn lanes_agree_with_the_reference_over_the_domain() {
    let angles = random_angles(4003, 0x9E37_79B9_7F4A_7C15);
    let mut worst = 0.0f64;
    for (pname, params) in parameter_sets() {
        for (ename, effects) in effect_sets() {
            let config = ModelConfig {
                mode: RootMode::Cubic,
                effects,
            };
            let what = format!("{pname}, {ename}");
            worst = worst.max(compare(&params, &config, &angles, &what));
        }
    }
    eprintln!("worst relative difference / conditioning {worst:e}");
}

#[test]
fn lanes_agree_at_the_hard_directions() {
    // φ exactly at the caustic ±φ_c of θ_d = 0 (η' = η there, no eccentricity), at 0 and ±π,
    // each with the neighbouring doubles, at several inclinations including grazing ones.
    let params = Params {
        eccentricity: 1.0,
        ..typical(vec![0.2, 0.4, 0.8])
    };
    let (phi_c, _) = caustic_position(RootMode::Cubic, params.eta).expect("η = 1.55 has a caustic");
    let mut phis = Vec::new();
    for base in [phi_c, -phi_c, 0.0, PI, -PI, PI / 2.0] {
        let mut x = base;
        for _ in 0..3 {
            x = x.next_down();
        }
        for _ in 0..7 {
            phis.push(x);
            x = x.next_up();
        }
    }
    let mut angles = Vec::new();
    for &phi in &phis {
        for theta in [0.0, 0.3, -1.2, PI / 2.0 - 1e-9, -(PI / 2.0 - 1e-9)] {
            // θ_i = θ_r keeps θ_d = 0; the azimuths split φ unevenly.
            angles.push(Angles {
                theta_i: theta,
                phi_i: -0.25,
                theta_r: theta,
                phi_r: phi - 0.25,
            });
        }
    }
    for (ename, effects) in effect_sets() {
        let config = ModelConfig {
            mode: RootMode::Cubic,
            effects,
        };
        compare(&params, &config, &angles, ename);
    }
}

#[test]
fn samples_off_the_fast_path_get_the_reference_bits() {
    // Exact mode runs the scalar model itself.
    let params = typical(vec![0.2, 0.4, 0.8]);
    let angles = random_angles(403, 7);
    let exact = ModelConfig {
        mode: RootMode::Exact,
        effects: Effects::default(),
    };
    let run = |config: &ModelConfig, angles: &[Angles], params: &Params<f64>| {
        let n = angles.len() * params.sigma_a.len();
        let mut reference = vec![0.0; n];
        scattering_batch(params, config, angles, &mut reference);
        let lanes: Vec<Vec<f64>> = kernels()
            .into_iter()
            .map(|kernel| {
                let mut lanes = vec![0.0; n];
                scattering_lanes_on(kernel, params, config, angles, &mut lanes);
                lanes
            })
            .collect();
        (lanes, reference)
    };
    let (lanes, reference) = run(&exact, &angles, &params);
    for lanes in &lanes {
        assert_eq!(bits(lanes), bits(&reference), "exact mode");
    }
    // η < 2/√3 folds the cubic TT map at θ_d = 0: with TT alone every lane falls back there,
    // so every value is the reference's to the bit.
    let folded = Params {
        eta: 1.1,
        ..params.clone()
    };
    let tt = ModelConfig {
        mode: RootMode::Cubic,
        effects: Effects {
            lobes: Lobes {
                r: false,
                tt: true,
                trt: false,
            },
            glints: false,
            eccentricity: false,
        },
    };
    // η' = η at θ_d = 0 (θ_i = θ_r); η' grows with |θ_d|, so other directions need not fold.
    let level: Vec<Angles> = angles
        .iter()
        .map(|a| Angles {
            theta_r: a.theta_i,
            ..*a
        })
        .collect();
    let (lanes, reference) = run(&tt, &level, &folded);
    for lanes in &lanes {
        assert_eq!(bits(lanes), bits(&reference), "TT folded everywhere");
    }
    assert!(
        reference.iter().any(|&v| v > 0.0),
        "TT contributes somewhere"
    );
}

#[test]
fn a_sample_gets_the_same_bits_wherever_it_stands() {
    // Alone, in a short last group, or in any lane of a full group: the same value, so an
    // `eval` row does not depend on the rows around it.
    let params = typical(vec![0.2, 0.4, 0.8]);
    let config = ModelConfig::default();
    let angles = random_angles(403, 11);
    let nc = params.sigma_a.len();
    for kernel in kernels() {
        let run = |angles: &[Angles]| {
            let mut out = vec![0.0; angles.len() * nc];
            scattering_lanes_on(kernel, &params, &config, angles, &mut out);
            out
        };
        let batch = run(&angles);
        let mut rotated = angles.clone();
        rotated.rotate_left(1);
        let shifted = run(&rotated);
        for (k, a) in angles.iter().enumerate() {
            let alone = run(std::slice::from_ref(a));
            let here = &batch[k * nc..(k + 1) * nc];
            let j = (k + angles.len() - 1) % angles.len();
            assert_eq!(
                bits(&alone),
                bits(here),
                "{kernel:?}: sample {k} alone and in the batch"
            );
            assert_eq!(
                bits(&shifted[j * nc..(j + 1) * nc]),
                bits(here),
                "{kernel:?}: sample {k} one lane over"
            );
        }
    }
}

/// `hairfit eval` prints the same digits on any CPU: the AVX2 and AVX-512 kernels give wide's
/// bits, for every effect set and parameter set, channel counts 1, 3 and 5 included.
#[test]
fn every_kernel_gives_the_same_bits() {
    let angles = random_angles(1001, 13);
    for (pname, params) in parameter_sets() {
        for (ename, effects) in effect_sets() {
            let config = ModelConfig {
                mode: RootMode::Cubic,
                effects,
            };
            let n = angles.len() * params.sigma_a.len();
            let (mut picked, mut each) = (vec![0.0; n], Vec::new());
            scattering_lanes(&params, &config, &angles, &mut picked);
            for kernel in kernels() {
                let mut out = vec![0.0; n];
                scattering_lanes_on(kernel, &params, &config, &angles, &mut out);
                each.push(bits(&out));
            }
            for (kernel, out) in kernels().iter().zip(&each) {
                assert_eq!(out, &bits(&picked), "{kernel:?}, {pname}, {ename}");
            }
        }
    }
}

fn bits(v: &[f64]) -> Vec<u64> {
    v.iter().map(|x| x.to_bits()).collect()
}

//! Rig geometry: each rig produces exactly the directions its documentation promises, and bad
//! specs are rejected with a message that names the problem.

use hairfit::synth::random::{generator, Stream};
use hairfit::synth::{Rig, MAX_THETA_DEG};

fn angles(spec: &str, seed: u64) -> Vec<[f64; 4]> {
    let rig = Rig::parse(spec).unwrap();
    let out = rig.angles(&mut generator(seed, Stream::Angles));
    assert_eq!(out.len(), rig.sample_count().unwrap(), "{spec}");
    out
}

fn in_azimuth_range(phi: f64) -> bool {
    phi > -180.0 && phi <= 180.0
}

#[test]
fn azimuthal_is_the_specular_cone_with_the_requested_counts() {
    let a = angles("azimuthal:incidences=15,30,45:steps=180", 0);
    assert_eq!(a.len(), 3 * 180);
    for (n, chunk) in a.chunks(180).enumerate() {
        let t = [15.0, 30.0, 45.0][n];
        for (k, s) in chunk.iter().enumerate() {
            assert_eq!(s[0], t);
            assert_eq!(s[1], 0.0);
            // Exactly, not approximately: the rig writes −θ_i itself.
            assert_eq!(s[2], -s[0]);
            assert!(in_azimuth_range(s[3]));
            // Even steps of 360/steps = 2°, the sweep ending exactly at +180°.
            assert!((s[3] - (-180.0 + 2.0 * (k + 1) as f64)).abs() < 1e-12);
        }
        assert_eq!(chunk[179][3], 180.0);
    }
}

#[test]
fn azimuthal_defaults_are_documented_values() {
    let rig = Rig::parse("azimuthal").unwrap();
    assert_eq!(rig.to_string(), "azimuthal:incidences=15,30,45:steps=180");
    // The canonical form parses back to the same rig.
    assert_eq!(Rig::parse(&rig.to_string()).unwrap(), rig);
}

#[test]
fn longitudinal_sweeps_theta_r_at_fixed_incidence_and_azimuth() {
    let a = angles("longitudinal:incidences=30:phi=0,180:steps=171:max=85", 0);
    assert_eq!(a.len(), 2 * 171);
    for (n, chunk) in a.chunks(171).enumerate() {
        let phi = [0.0, 180.0][n];
        assert_eq!(chunk[0][2], -85.0);
        assert_eq!(chunk[170][2], 85.0);
        // 1° steps; 1e-12 allows the rounding of −max + 2·max·k/(steps−1).
        for (k, s) in chunk.iter().enumerate() {
            assert_eq!((s[0], s[1], s[3]), (30.0, 0.0, phi));
            assert!((s[2] - (-85.0 + k as f64)).abs() < 1e-12);
        }
    }
}

#[test]
fn sphere_is_uniform_in_sin_theta_and_phi_and_avoids_the_axis() {
    let n = 20_000;
    let a = angles(&format!("sphere:n={n}:max=80"), 11);
    let zmax = 80f64.to_radians().sin();
    // Histogram of sin θ (for ω_i and ω_r) in 10 bins over [−zmax, zmax] and of φ in 10 bins:
    // each bin expects 2n/10 = 4000 draws, binomial s.d. ≈ 60; 5 s.d. = 300.
    let mut z_bins = [0usize; 10];
    let mut phi_bins = [0usize; 10];
    for s in &a {
        for (theta, phi) in [(s[0], s[1]), (s[2], s[3])] {
            assert!(theta.abs() <= 80.0);
            assert!(in_azimuth_range(phi));
            let z = theta.to_radians().sin();
            z_bins[(((z + zmax) / (2.0 * zmax) * 10.0) as usize).min(9)] += 1;
            phi_bins[(((phi + 180.0) / 36.0) as usize).min(9)] += 1;
        }
    }
    for count in z_bins.iter().chain(&phi_bins) {
        assert!(
            (*count as f64 - 4000.0).abs() < 300.0,
            "{z_bins:?} {phi_bins:?}"
        );
    }
    // ω_i and ω_r are independent: the correlation of sin θ_i and sin θ_r is ~N(0, 1/n);
    // 5/sqrt(n) = 0.035.
    let corr: f64 = a
        .iter()
        .map(|s| s[0].to_radians().sin() * s[2].to_radians().sin())
        .sum::<f64>()
        / n as f64
        / (zmax * zmax / 3.0);
    assert!(corr.abs() < 0.035, "corr {corr}");
}

#[test]
fn sphere_depends_on_the_seed_only() {
    assert_eq!(angles("sphere:n=50", 1), angles("sphere:n=50", 1));
    assert_ne!(angles("sphere:n=50", 1), angles("sphere:n=50", 2));
}

/// cos of the angle between ω_i and ω_r from fiber-frame angles (degrees).
fn cos_between(s: &[f64; 4]) -> f64 {
    let v = |t: f64, p: f64| {
        let (t, p) = (t.to_radians(), p.to_radians());
        [t.sin(), t.cos() * p.cos(), t.cos() * p.sin()]
    };
    let (a, b) = (v(s[0], s[1]), v(s[2], s[3]));
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[test]
fn photo_is_a_bent_fiber_under_fixed_lights() {
    let a = angles(
        "photo:lights=4:views=31:span=60:light_theta=-20:camera=10",
        0,
    );
    assert_eq!(a.len(), 4 * 31);
    for chunk in a.chunks(31) {
        for (j, s) in chunk.iter().enumerate() {
            // The camera sees the bent fiber at θ_r = camera + β, φ_r = 0, β in 2° steps.
            assert!((s[2] - (10.0 - 30.0 + 2.0 * j as f64)).abs() < 1e-12);
            assert_eq!(s[3], 0.0);
            assert!(s[0].abs() <= 20.0 + 30.0 + 1e-9);
            assert!(in_azimuth_range(s[1]));
        }
        // The light and the camera are fixed in the world, so the angle between ω_i and ω_r
        // cannot change along the strip; bending only moves the fiber frame. 1e-12 is rounding
        // in sin/cos/asin/atan2 of O(1) quantities.
        let c0 = cos_between(&chunk[0]);
        for s in chunk {
            assert!((cos_between(s) - c0).abs() < 1e-12, "{s:?}");
        }
        // ...while the fiber-frame incidence does change (the photo is not a fixed-angle scan).
        assert!(chunk.iter().any(|s| (s[0] - chunk[0][0]).abs() > 1.0));
    }
    // Different lights sit at different azimuths.
    assert_ne!(a[0][1], a[31][1]);
}

#[test]
fn photo_default_is_a_few_hundred_samples() {
    let rig = Rig::parse("photo").unwrap();
    assert_eq!(rig.sample_count(), Some(300));
}

fn rig_error(spec: &str) -> String {
    Rig::parse(spec).unwrap_err().to_string()
}

#[test]
fn bad_rig_specs_get_clear_errors() {
    let cases = [
        ("cylinder", "unknown rig `cylinder`"),
        ("azimuthal:steps", "not KEY=VALUE"),
        (
            "azimuthal:step=10",
            "has no option `step`; its options are incidences, steps",
        ),
        ("azimuthal:steps=0", "steps: `0` is not a whole number >= 1"),
        ("azimuthal:steps=-3", "not a whole number"),
        (
            "azimuthal:incidences=30,abc",
            "`abc` is not a finite number",
        ),
        ("azimuthal:incidences=90", "outside ±89°"),
        ("azimuthal:steps=3:steps=4", "given twice"),
        ("longitudinal:phi=-180", "outside (-180°, 180°]"),
        ("longitudinal:steps=1", ">= 2"),
        ("longitudinal:max=90", "max=90"),
        ("sphere:n=inf", "not a whole number"),
        ("sphere:max=0", "max=0"),
        ("photo:light_theta=70:span=60", "light_theta"),
        ("photo:span=-1", "span=-1"),
        ("azimuthal:incidences=", "not a finite number"),
    ];
    for (spec, expected) in cases {
        let msg = rig_error(spec);
        assert!(msg.contains(expected), "{spec}: {msg}");
        assert!(msg.starts_with(&format!("--rig `{spec}`")), "{msg}");
    }
}

#[test]
fn every_rig_stays_away_from_the_axis() {
    for spec in [
        "azimuthal:incidences=89,-89:steps=7",
        "longitudinal:max=89:steps=3",
        "sphere:n=2000:max=89",
        "photo:light_theta=-59:span=60:camera=59",
    ] {
        for s in angles(spec, 3) {
            assert!(
                s[0].abs() <= MAX_THETA_DEG && s[2].abs() <= MAX_THETA_DEG,
                "{spec} {s:?}"
            );
        }
    }
}

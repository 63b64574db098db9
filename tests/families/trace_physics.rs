//! The tracer's physics (`hairfit::trace`, docs/trace.md), checked against invariants and
//! against the exact optics of a smooth round fibre written out here: energy balance, the
//! specular cone, the Bravais exit map and attenuation per ray, the power per order against a
//! quadrature over h, the tilted R ray, Fresnel's limits, reciprocity, and determinism across
//! thread counts.

use std::f64::consts::PI;

use hairfit::trace::optics::{direction, fresnel};
use hairfit::trace::sampler::{Balance, Sampler, Weights};
use hairfit::trace::section::Section;
use hairfit::trace::{run, Fiber, TraceSetup, ORDERS};
use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;

fn fiber(sigma_a: &[f64]) -> Fiber {
    Fiber {
        eta: 1.55,
        sigma_a: sigma_a.to_vec(),
        tilt: 0.0,
        roughness: 0.0,
        azimuthal_roughness: 0.0,
        eccentricity: 1.0,
        rotation: None,
        max_segments: 16,
    }
}

fn rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

fn wrap(x: f64) -> f64 {
    let y = x.rem_euclid(2.0 * PI);
    if y > PI {
        y - 2.0 * PI
    } else {
        y
    }
}

/// The exact optics of a smooth untilted round fibre at inclination θ (docs/model.md's
/// formulas, which Bravais's theorem makes exact for a cylinder): exit azimuth and weight of
/// order p for the ray entering at h.
struct Exact {
    eta_p: f64,
    eta_pp: f64,
    cos_theta_t: f64,
    sigma: f64,
}

impl Exact {
    fn new(eta: f64, theta: f64, sigma: f64) -> Exact {
        let s2 = theta.sin().powi(2);
        Exact {
            eta_p: (eta * eta - s2).sqrt() / theta.cos(),
            eta_pp: eta * eta * theta.cos() / (eta * eta - s2).sqrt(),
            cos_theta_t: (1.0 - s2 / (eta * eta)).sqrt(),
            sigma,
        }
    }
    fn azimuth(&self, p: usize, h: f64) -> f64 {
        let p = p as f64;
        2.0 * p * (h / self.eta_p).asin() - 2.0 * h.asin() + p * PI
    }
    fn weight(&self, p: usize, h: f64) -> f64 {
        let ci = (1.0 - h * h).sqrt();
        let ct = (1.0 - h * h / (self.eta_p * self.eta_p)).sqrt();
        let rs = (ci - self.eta_p * ct) / (ci + self.eta_p * ct);
        let rp = (self.eta_pp * ci - ct) / (self.eta_pp * ci + ct);
        let f = (rs * rs + rp * rp) / 2.0;
        if p == 0 {
            return f;
        }
        let seg = 2.0 * ct / self.cos_theta_t;
        (1.0 - f).powi(2) * f.powi(p as i32 - 1) * (-(p as f64) * self.sigma * seg).exp()
    }
}

/// Every exit `(order, direction, weights)` of one ray at offset `h`.
fn exits_at(
    s: &Sampler,
    sec: &Section,
    omega_i: [f64; 3],
    h: f64,
    bal: &mut Balance,
) -> Vec<(usize, [f64; 3], Weights)> {
    let mut out = Vec::new();
    s.trace_at(sec, omega_i, h, &mut rng(1), bal, &mut |p, d, w| {
        out.push((p, d, *w))
    });
    out
}

/// Incident = tallied + absorbed + still inside, per ray and over a run, for a rough, tilted,
/// elliptical, absorbing three-channel fibre averaged over rotations. The weights are split,
/// never created or dropped, so only rounding remains: a few ulps per ray, and over 64k rays
/// a sum of that many terms of size ≤ 1 (1e-12 leaves a factor of 100 over 64k·ε).
#[test]
fn energy_balances_to_rounding() {
    let mut f = fiber(&[0.2, 0.6, 1.5]);
    f.tilt = (-3f64).to_radians();
    f.roughness = 8f64.to_radians();
    f.azimuthal_roughness = 4f64.to_radians();
    f.eccentricity = 0.7;
    let s = Sampler::new(&f);
    let mut r = rng(7);
    for k in 0..2000 {
        let omega_i = direction((k as f64 * 0.04) % 1.4 - 0.7, 0.3);
        let mut bal = Balance::default();
        s.trace(omega_i, &mut r, &mut bal, &mut |_, _, _| {});
        for c in 0..3 {
            let sum: f64 = (0..ORDERS).map(|p| bal.tallied[p][c]).sum::<f64>()
                + bal.absorbed[c]
                + bal.inside[c];
            assert!((sum - 1.0).abs() < 1e-14, "ray {k} channel {c}: {sum}");
        }
    }
    let dirs = [
        [0.5, 0.0, -0.5, 1.0],
        [0.5, 0.0, -0.4, 3.0],
        [-0.3, 1.0, 0.2, -2.0],
    ];
    let setup = TraceSetup {
        rays: 32_000,
        seed: 3,
        kernel: 0.05,
    };
    let res = run(&f, &dirs, &setup, &|_| {});
    let n = res.rays_total as f64;
    assert_eq!(n, 64_000.0);
    for c in 0..3 {
        let b = &res.balance;
        let sum: f64 =
            (0..ORDERS).map(|p| b.tallied[p][c]).sum::<f64>() + b.absorbed[c] + b.inside[c];
        assert!(
            (sum / n - 1.0).abs() < 1e-12,
            "channel {c}: {}",
            sum / n - 1.0
        );
        assert!(b.absorbed[c] > 0.0 && b.tallied[1][c] > 0.0);
    }
}

/// A smooth untilted fibre keeps every exit on the specular cone θ_r = −θ_i (the axial
/// component of a direction survives reflection and refraction at a normal with no axial
/// part), round or elliptical at any rotation. Only rounding in the normalisations remains.
#[test]
fn smooth_untilted_exits_lie_on_the_specular_cone() {
    for (a, psi) in [(1.0, 0.0), (0.75, 0.4), (0.5, 2.0)] {
        let mut f = fiber(&[0.1]);
        f.eccentricity = a;
        let s = Sampler::new(&f);
        let sec = Section::new(a, psi);
        for &theta in &[-1.2, -0.4, 0.0, 0.3, 1.3] {
            let omega_i = direction(theta, 0.7);
            let mut bal = Balance::default();
            for k in 0..400 {
                let h = -0.9995 + 1.999 * k as f64 / 399.0;
                for (p, d, _) in exits_at(&s, &sec, omega_i, h, &mut bal) {
                    let err = (d[0] + theta.sin()).abs();
                    assert!(err < 1e-14, "a={a} θ={theta} h={h} p={p}: {err}");
                }
            }
            assert_eq!((bal.mirrored, bal.fallbacks), (0, 0));
        }
    }
}

/// A smooth untilted round fibre: each exit of the ray entering at h leaves at the exact
/// Bravais azimuth Φ(p, h) and carries (1 − F)² F^(p−1) e^(−pσ_a·2cos γ_t/cos θ_t), F the
/// Fresnel factor with η′, η″ (docs/model.md), computed here independently of the tracer's
/// 3-D vectors. Both are deterministic per ray; 1e-11 covers rounding through 16 segments.
#[test]
fn smooth_round_fibre_follows_the_bravais_map_and_attenuation() {
    let sigma = 0.4;
    let f = fiber(&[sigma]);
    let s = Sampler::new(&f);
    let sec = Section::new(1.0, 0.0);
    for &theta in &[0.0, 0.35, -0.8] {
        let exact = Exact::new(1.55, theta, sigma);
        let omega_i = direction(theta, 0.0);
        for k in 0..200 {
            let h = -0.999 + 1.998 * k as f64 / 199.0;
            let mut bal = Balance::default();
            let exits = exits_at(&s, &sec, omega_i, h, &mut bal);
            assert!(exits.len() >= 4, "h={h}: {} exits", exits.len());
            for (p, d, w) in exits {
                let phi = d[2].atan2(d[1]);
                let dphi = wrap(phi - exact.azimuth(p, h));
                assert!(dphi.abs() < 1e-11, "θ={theta} h={h} p={p}: Δφ {dphi}");
                let want = exact.weight(p, h);
                assert!(
                    (w[0] - want).abs() <= 1e-11 * want + 1e-300,
                    "θ={theta} h={h} p={p}: weight {} vs {want}",
                    w[0]
                );
            }
        }
    }
}

/// Power per order of a smooth round fibre under a uniform beam: the tracer's Monte Carlo
/// mean over random h against ½∫A(p, h) dh by Simpson's rule (h = sin γ, 20000 intervals,
/// error far below the Monte Carlo's). Within 3 standard errors of the per-ray spread.
#[test]
fn power_per_order_matches_the_quadrature_over_h() {
    let sigma = 0.3;
    let theta = 0.5;
    let f = fiber(&[sigma]);
    let s = Sampler::new(&f);
    let omega_i = direction(theta, 0.0);
    let n = 200_000;
    let mut r = rng(11);
    let mut sum = [0.0; ORDERS];
    let mut sum2 = [0.0; ORDERS];
    for _ in 0..n {
        let mut per = [0.0; ORDERS];
        let mut bal = Balance::default();
        s.trace(omega_i, &mut r, &mut bal, &mut |p, _, w| {
            per[p.min(ORDERS - 1)] += w[0]
        });
        for p in 0..ORDERS {
            sum[p] += per[p];
            sum2[p] += per[p] * per[p];
        }
    }
    let exact = Exact::new(1.55, theta, sigma);
    let m = 20_000;
    let simpson = |g: &dyn Fn(f64) -> f64| {
        let (a, b) = (-PI / 2.0, PI / 2.0);
        let step = (b - a) / m as f64;
        let mut acc = g(a) + g(b);
        for k in 1..m {
            acc += g(a + k as f64 * step) * if k % 2 == 1 { 4.0 } else { 2.0 };
        }
        acc * step / 3.0
    };
    for p in 0..ORDERS {
        let want = 0.5
            * simpson(&|gamma: f64| {
                let h = gamma.sin();
                let a = if p < 3 {
                    exact.weight(p, h)
                } else {
                    (3..=16).map(|q| exact.weight(q, h)).sum()
                };
                a * gamma.cos()
            });
        let mean = sum[p] / n as f64;
        let se = ((sum2[p] / n as f64 - mean * mean) / (n as f64 - 1.0)).sqrt();
        assert!(
            (mean - want).abs() < 3.0 * se,
            "order {p}: traced {mean} ± {se}, exact {want}"
        );
    }
}

/// A smooth fibre tilted by α sends the central ray (h = 0) back at θ_r = −θ_i + 2α and
/// φ_r = 0: the mirror law at a normal turned by α toward the tip. Exact up to rounding.
#[test]
fn tilted_fibre_reflects_the_central_ray_at_twice_the_tilt() {
    for (alpha_deg, theta_deg) in [(-3.0, 25.0), (5.0, -40.0), (-10.0, 0.0)] {
        let mut f = fiber(&[0.5]);
        f.tilt = f64::to_radians(alpha_deg);
        let s = Sampler::new(&f);
        let omega_i = direction(f64::to_radians(theta_deg), 0.0);
        let mut bal = Balance::default();
        let exits = exits_at(&s, &Section::new(1.0, 0.0), omega_i, 0.0, &mut bal);
        let (p, d, _) = exits[0];
        assert_eq!(p, 0);
        let want = f64::to_radians(-theta_deg + 2.0 * alpha_deg);
        assert!(
            (d[0].asin() - want).abs() < 1e-14,
            "α={alpha_deg}: {}",
            d[0].asin()
        );
        assert!(d[2].abs() < 1e-15 && d[1] > 0.0);
    }
}

/// Fresnel at its limits: normal incidence ((η−1)/(η+1))², 1 at and beyond the critical angle
/// (total internal reflection), 1 at grazing, and the same reflectance from either side of an
/// interface for a ray and its refracted ray (Stokes). All exact up to rounding, which the
/// square roots of `1 − cos²` amplify by up to 1/cos (1e-13 at cos 0.1).
#[test]
fn fresnel_limits_and_total_internal_reflection() {
    let eta: f64 = 1.55;
    let (f0, _) = fresnel(1.0, 1.0, eta);
    assert!((f0 - ((eta - 1.0) / (eta + 1.0)).powi(2)).abs() < 1e-16);
    let critical_cos = (1.0 - 1.0 / (eta * eta)).sqrt();
    for c in [critical_cos * 0.999_999, 0.3, 1e-9, 0.0] {
        assert_eq!(fresnel(c, eta, 1.0), (1.0, 0.0), "cos {c}");
    }
    assert!(fresnel(critical_cos * 1.001, eta, 1.0).0 < 1.0);
    assert_eq!(fresnel(0.0, 1.0, eta).0, 1.0);
    for c in [0.1, 0.5, 0.9] {
        let (f_out, ct) = fresnel(c, 1.0, eta);
        let (f_in, back) = fresnel(ct, eta, 1.0);
        assert!(
            (f_out - f_in).abs() < 1e-13 && (back - c).abs() < 1e-13,
            "cos {c}: {f_out} vs {f_in}, back {back}"
        );
    }
}

/// Reciprocity of an untilted rough fibre: S(i→r) = S(r→i) for hairfit's S (per unit solid
/// angle per unit irradiance, divided by cos θ_i cos θ_r). The two estimates are independent;
/// they must agree within 3 combined standard errors plus 2% for the kernel: each smooths S
/// over a 1.5° cap in its own exit variable, a bias of order (κ/lobe width)² ≈ 1% here.
#[test]
fn untilted_rough_fibre_is_reciprocal() {
    let mut f = fiber(&[0.3]);
    f.roughness = 10f64.to_radians();
    f.azimuthal_roughness = 5f64.to_radians();
    let (ti, tr) = (20f64.to_radians(), -30f64.to_radians());
    for phi_r in [150f64.to_radians(), 40f64.to_radians()] {
        let dirs = [[ti, 0.0, tr, phi_r], [tr, phi_r, ti, 0.0]];
        let setup = TraceSetup {
            rays: 600_000,
            seed: 5,
            kernel: 1.5f64.to_radians(),
        };
        let res = run(&f, &dirs, &setup, &|_| {});
        let value = |k: usize| {
            let inc = res.incidences.iter().find(|i| i.rows == [k]).unwrap();
            let s: f64 = (0..ORDERS).map(|p| inc.s[p]).sum();
            (s, inc.sigma[0])
        };
        let ((a, sa), (b, sb)) = (value(0), value(1));
        assert!(a > 0.0 && b > 0.0);
        let tol = 3.0 * sa.hypot(sb) + 0.02 * a.max(b);
        assert!((a - b).abs() < tol, "φ_r={phi_r}: {a} ± {sa} vs {b} ± {sb}");
    }
}

/// The same seed gives the same bits with one thread or two: rays are split into fixed
/// batches, each with its own generator, combined in order.
#[test]
fn a_seed_gives_the_same_bits_with_any_thread_count() {
    let mut f = fiber(&[0.4, 0.9]);
    f.roughness = 6f64.to_radians();
    f.tilt = -0.05;
    let dirs: Vec<[f64; 4]> = (0..60)
        .map(|k| [0.5, 0.0, -0.5, -PI + 2.0 * PI * (k + 1) as f64 / 60.0])
        .chain([[0.2, 0.0, -0.2, 1.0]])
        .collect();
    let setup = TraceSetup {
        rays: 20_000,
        seed: 9,
        kernel: 0.04,
    };
    let with = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| run(&f, &dirs, &setup, &|_| {}))
    };
    let (one, two) = (with(1), with(2));
    assert_eq!(one.balance, two.balance);
    for (x, y) in one.incidences.iter().zip(&two.incidences) {
        assert_eq!(x.rows, y.rows);
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&x.s), bits(&y.s));
        assert_eq!(bits(&x.sigma), bits(&y.sigma));
    }
}

/// The ziggurat's draws are standard normal: over 10⁶ draws the mean, variance and the share
/// beyond 1, 2 and 3.5 (the last reaches the tail beyond R = 3.44) agree with N(0, 1) within 5
/// standard errors of each statistic.
#[test]
fn ziggurat_draws_are_standard_normal() {
    let mut r = rng(21);
    let n = 1_000_000;
    let (mut s1, mut s2) = (0.0, 0.0);
    let mut beyond = [0usize; 3];
    let cut = [1.0, 2.0, 3.5];
    for _ in 0..n {
        let x = hairfit::trace::normal::normal(&mut r);
        s1 += x;
        s2 += x * x;
        for (b, c) in beyond.iter_mut().zip(cut) {
            *b += usize::from(x.abs() > c);
        }
    }
    let nf = n as f64;
    assert!((s1 / nf).abs() < 5.0 / nf.sqrt(), "mean {}", s1 / nf);
    assert!(
        (s2 / nf - 1.0).abs() < 5.0 * 2f64.sqrt() / nf.sqrt(),
        "var {}",
        s2 / nf
    );
    // P(|x| > c) = erfc(c/√2): 0.3173105, 0.0455003, 4.6525e-4.
    for (k, p) in [0.317_310_5, 0.045_500_26, 4.652_5e-4]
        .into_iter()
        .enumerate()
    {
        let got = beyond[k] as f64 / nf;
        let se = (p * (1.0 - p) / nf).sqrt();
        assert!((got - p).abs() < 5.0 * se, "|x| > {}: {got} vs {p}", cut[k]);
    }
}

/// `normal_and_uniform`'s pair from one `u64`: the normal's mean and variance those of N(0, 1),
/// the uniform's mean 1/2 and variance 1/12, and the two uncorrelated, within 5 standard errors.
#[test]
fn ziggurat_pair_is_normal_and_independent_uniform() {
    let mut r = rng(22);
    let n = 1_000_000;
    let (mut x1, mut x2, mut u1, mut u2, mut xu) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for _ in 0..n {
        let (x, u) = hairfit::trace::normal::normal_and_uniform(&mut r);
        assert!((0.0..1.0).contains(&u));
        x1 += x;
        x2 += x * x;
        u1 += u;
        u2 += u * u;
        xu += x * (u - 0.5);
    }
    let nf = n as f64;
    let se = 1.0 / nf.sqrt();
    assert!((x1 / nf).abs() < 5.0 * se, "mean {}", x1 / nf);
    assert!(
        (x2 / nf - 1.0).abs() < 5.0 * 2f64.sqrt() * se,
        "var {}",
        x2 / nf
    );
    assert!(
        (u1 / nf - 0.5).abs() < 5.0 * se / 12f64.sqrt(),
        "u mean {}",
        u1 / nf
    );
    let uvar = u2 / nf - (u1 / nf).powi(2);
    assert!((uvar - 1.0 / 12.0).abs() < 5.0 * se * 0.075, "u var {uvar}");
    assert!((xu / nf).abs() < 5.0 * se / 12f64.sqrt(), "cov {}", xu / nf);
}

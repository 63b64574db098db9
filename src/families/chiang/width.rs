//! The nodes a Chiang model's width rule ([`WidthNodes`], `--width-nodes auto | N`) gives one
//! exit direction.
//!
//! `N` is CHIANG.md's plain N-node Gauss–Legendre rule in γ, the same nodes for every direction.
//! `auto` (the default) breaks γ where an enabled lobe's trimmed logistic wraps — its kink,
//! which makes the plain rule converge only algebraically for wide logistics — and spends
//! [`crate::families::shared::quadrature::auto_density`] nodes per π of γ: many for β_n's narrow peaks, few for its smooth wide lobes.

use super::azimuthal::wrap_kinks;
use super::ChiangEffects;
use crate::families::shared::cylinder::ExitRefraction;
pub use crate::families::shared::quadrature::WidthNodes;
use crate::families::shared::quadrature::{composite, WidthNode};

/// Plain nodes of the residual `Ā₃ = ⟨A₃⟩_h` under the automatic rule: its integrand has no
/// logistic, only a near-pole of `1/(1 − TF)` just past h = ±1 for small σ_a; 64 nodes keep it
/// within 6.6e-8 relative (128: 9e-10) for σ_a from 1e-4 to 3, η 1.45–1.65, θ_r to 89° against
/// 4096 nodes, the worst at σ_a = 0.01, θ_r = 0.
pub const RESIDUAL_NODES: usize = 64;

/// The composite rule's nodes for exit inclination `theta_r` and azimuth `phi` at `eta`,
/// `beta_n`: broken at every enabled lobe's wrap kink, written into `out`.
pub fn split_nodes(
    effects: &ChiangEffects,
    density: usize,
    eta: f64,
    theta_r: f64,
    phi: f64,
    breaks: &mut Vec<f64>,
    out: &mut Vec<WidthNode>,
) {
    breaks.clear();
    let eta_prime = ExitRefraction::new(&eta, theta_r).eta_prime;
    for (p, on) in [effects.r, effects.tt, effects.trt].into_iter().enumerate() {
        if on {
            wrap_kinks(p, eta_prime, phi, breaks);
        }
    }
    composite(density, breaks, out);
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::shared::cylinder::exit_azimuth;
    use std::f64::consts::{PI, TAU};

    #[test]
    fn parses_and_round_trips_through_json() {
        assert_eq!("auto".parse::<WidthNodes>().unwrap(), WidthNodes::Auto);
        assert_eq!(
            " 512 ".parse::<WidthNodes>().unwrap(),
            WidthNodes::Fixed(512)
        );
        let e = "1k".parse::<WidthNodes>().unwrap_err().to_string();
        assert!(e.contains("`1k`") && e.contains("auto"), "{e}");
        assert!("1".parse::<WidthNodes>().is_err());
        for w in [WidthNodes::Auto, WidthNodes::Fixed(300)] {
            let text = serde_json::to_string(&w).unwrap();
            assert_eq!(
                serde_json::from_str::<WidthNodes>(&text).unwrap(),
                w,
                "{text}"
            );
        }
        assert!(serde_json::from_str::<WidthNodes>("\"fast\"").is_err());
    }

    /// Every kink found is one (the argument is π mod 2π there), and none is missed: a scan of
    /// 20 000 offsets finds a wrap only next to a reported kink (a wrap exactly at γ = ±π/2, as
    /// R's at φ = 0, is the interval's end, not a kink inside it).
    #[test]
    fn kinks_are_exactly_where_the_logistic_wraps() {
        for &(eta_prime, phi) in &[(1.55, 0.3), (1.9, 2.9), (1.2, 1.0), (6.0, 0.0), (1.55, PI)] {
            for p in 0..3 {
                let mut kinks = Vec::new();
                wrap_kinks(p, eta_prime, phi, &mut kinks);
                let arg = |g: f64| {
                    let gt = (g.sin() / eta_prime).asin();
                    -phi - exit_azimuth(p, g, &gt) - PI
                };
                for &k in &kinks {
                    let r = arg(k) / TAU;
                    assert!(
                        (r - r.round()).abs() < 1e-12,
                        "p {p} η' {eta_prime} φ {phi}: {r}"
                    );
                }
                let (n, span) = (20_000, PI - 2e-9);
                for i in 0..n {
                    let (a, b) = (
                        -FRAC_PI_2 + 1e-9 + span * i as f64 / n as f64,
                        -FRAC_PI_2 + 1e-9 + span * (i + 1) as f64 / n as f64,
                    );
                    if (arg(a) / TAU).floor() != (arg(b) / TAU).floor() {
                        assert!(
                            kinks.iter().any(|&k| k >= a - 1e-12 && k <= b + 1e-12),
                            "p {p} η' {eta_prime} φ {phi}: a wrap in [{a}, {b}] not reported ({kinks:?})"
                        );
                    }
                }
            }
        }
    }
    use std::f64::consts::FRAC_PI_2;
}

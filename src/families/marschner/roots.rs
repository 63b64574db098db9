//! Roots of `Φ(p, γ) ≡ φ (mod 2π)` on `γ ∈ [−π/2, π/2]`: bracketing on the monotone pieces between
//! the caustics, then safeguarded Newton, in f64 (cubic mode starts from the cubic's closed-form
//! root, so one Newton step normally confirms it); then one Newton step in the dual number type at
//! the converged root (implicit-function theorem: exact first derivatives).

use num_dual::DualNum;
use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::angles::wrap;
use super::exit_angle::ExitMap;
use super::instrument;
use super::RootMode;

/// At most this many roots per lobe (TRT has 1 or 3; the cubic near η' → 1 may add wrapped ones).
pub const MAX_ROOTS: usize = 8;

/// Roots `γ` of one lobe and the unwrapped target `φ + 2πk` each one solves.
#[derive(Debug, Clone, Copy)]
pub struct Roots {
    pub gamma: [f64; MAX_ROOTS],
    pub target: [f64; MAX_ROOTS],
    pub n: usize,
}

/// `1/(2π)`: the k range of a piece is found by multiplying (a division costs as much as the rest
/// of the enumeration; it could differ only where a root sits exactly on a piece's end).
const INV_TAU: f64 = 1.0 / TAU;

/// The monotone pieces of the map, in γ order: below the caustic `−γ_c`, between `±γ_c` (the
/// whole domain when there is no caustic inside it), above `γ_c`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Piece {
    Lower,
    Middle,
    Upper,
}

/// Every root of `map(γ) = φ + 2πk` over all k, `γ ∈ [−π/2, π/2]`.
pub fn exit_roots(map: &ExitMap<f64>, phi: f64) -> Roots {
    instrument::count_root_solve(map.p);
    let mut roots = Roots {
        gamma: [0.0; MAX_ROOTS],
        target: [0.0; MAX_ROOTS],
        n: 0,
    };
    if map.mode == RootMode::Exact && map.p == 1 {
        if let Some(g) = tt_closed_form(map, phi) {
            roots.gamma[0] = g;
            roots.target[0] = phi + TAU * ((map.value(&g) - phi) / TAU).round();
            roots.n = 1;
            return roots;
        }
    }
    let mut bounds = [-FRAC_PI_2, 0.0, 0.0, FRAC_PI_2];
    let pieces: &[Piece] = match map.caustic() {
        Some(gc) if gc > 0.0 => {
            bounds = [-FRAC_PI_2, -gc, gc, FRAC_PI_2];
            &[Piece::Lower, Piece::Middle, Piece::Upper]
        }
        _ => {
            bounds[1] = FRAC_PI_2;
            &[Piece::Middle]
        }
    };
    let mut f_lo = map.value(&bounds[0]);
    for (i, &piece) in pieces.iter().enumerate() {
        let (lo, hi) = (bounds[i], bounds[i + 1]);
        let f_hi = map.value(&hi);
        let (vmin, vmax) = if f_lo <= f_hi {
            (f_lo, f_hi)
        } else {
            (f_hi, f_lo)
        };
        let (k_min, k_max) = (
            ceil_i64((vmin - phi) * INV_TAU),
            floor_i64((vmax - phi) * INV_TAU),
        );
        for k in k_min..=k_max {
            let y = phi + TAU * k as f64;
            // A root exactly on a shared boundary belongs to the previous piece.
            if i > 0 && y == f_lo {
                continue;
            }
            if roots.n < MAX_ROOTS {
                let start = match map.mode {
                    RootMode::Cubic => cubic_root(map.a, map.b, map.p as f64 * PI - y, piece),
                    RootMode::Exact => f64::NAN,
                };
                roots.gamma[roots.n] = solve_monotone(map, lo, hi, f_lo, f_hi, y, start);
                roots.target[roots.n] = y;
                roots.n += 1;
            }
        }
        f_lo = f_hi;
    }
    roots
}

/// `x.floor() as i64` without the libm call (x86-64's baseline has no rounding instruction):
/// the truncation, one lower for negative non-integers (saturating, as the cast is).
#[inline]
fn floor_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) > x {
        t.saturating_sub(1)
    } else {
        t
    }
}

/// `x.ceil() as i64`, as [`floor_i64`].
#[inline]
fn ceil_i64(x: f64) -> i64 {
    let t = x as i64;
    if (t as f64) < x {
        t.saturating_add(1)
    } else {
        t
    }
}

/// Exact TT root from MODEL.md's closed form `h = s·cos(φ/2)/sqrt(1 + a² − 2as·sin(φ/2))`,
/// `a = 1/η'`, `s = sign φ`, accepted only where `Φ(1, h)` indeed returns φ (else `None`: the
/// bracketing solver decides, normally finding no root since |φ| < 2·asin(1/η')).
fn tt_closed_form(map: &ExitMap<f64>, phi: f64) -> Option<f64> {
    let a = 1.0 / map.eta_p;
    let s = if phi < 0.0 { -1.0 } else { 1.0 };
    let (sh, ch) = (0.5 * phi).sin_cos();
    let h = s * ch / (1.0 + a * a - 2.0 * a * s * sh).sqrt();
    if h.is_nan() || h.abs() > 1.0 {
        return None;
    }
    let g = h.asin();
    let r = wrap(map.value(&g) - phi);
    // The closed form is exact up to rounding where valid; elsewhere it misses by O(1).
    if r.abs() < 1e-9 {
        // One Newton step polishes the last bits (the map's slope is ≤ −2·(1 − 1/η') < 0).
        let d = map.slope(&g);
        let gn = g - r / d;
        Some(if gn.abs() <= FRAC_PI_2 { gn } else { g })
    } else {
        None
    }
}

/// The real root on `piece` of Marschner's cubic `aγ³ + bγ + c₀ = 0` (`c₀ = pπ − y`, `a < 0`), in
/// closed form: with `P = b/a`, `Q = c₀/a` and `Δ = (Q/2)² + (P/3)³`, the one real root for Δ > 0
/// (Cardano, as `u − P/(3u)`, `u = ∛(−Q/2 ± √Δ)` with the sign that avoids cancellation), else
/// Viète's `2r·cos((acos(−Q/(2r³)) − 2πj)/3)`, `r = √(−P/3)`: j = 0, 1, 2 give the upper, middle
/// and lower root (`±r = ±γ_c` separate them). Accurate to rounding away from folds; a start only
/// (next to a fold the acos argument loses digits, and the bracketed solve still decides).
pub fn cubic_root(a: f64, b: f64, c0: f64, piece: Piece) -> f64 {
    let p3 = b / a * (1.0 / 3.0);
    let half_q = 0.5 * c0 / a;
    let disc = half_q * half_q + p3 * p3 * p3;
    if disc > 0.0 {
        let u = cube_root_start(-half_q - disc.sqrt().copysign(half_q));
        if u == 0.0 {
            0.0
        } else {
            u - p3 / u
        }
    } else {
        let r = (-p3).sqrt();
        let third = (-half_q / (r * r * r)).clamp(-1.0, 1.0).acos() * (1.0 / 3.0);
        let j = match piece {
            Piece::Upper => 0.0,
            Piece::Middle => 1.0,
            Piece::Lower => 2.0,
        };
        2.0 * r * (third - j * (TAU / 3.0)).cos()
    }
}

/// `∛s` to ~1e-14 relative for `1e-90 < |s| < 1e90` (a Newton start needs no more; outside that
/// range it is only a start too): the exponent divided by 3 through the bits, then two Halley
/// steps `u ← u(u³ + 2s)/(2u³ + s)`. A quarter of the cost of `f64::cbrt`, which is correctly
/// rounded and was the solve's largest single cost.
fn cube_root_start(s: f64) -> f64 {
    if s == 0.0 || !s.is_finite() {
        return s;
    }
    let m = s.abs();
    let halley = |u: f64| {
        let u3 = u * u * u;
        u * (u3 + 2.0 * m) / (2.0 * u3 + m)
    };
    // Bits of m/3 plus a third of the exponent bias (tuned: the first guess is within 3.2%).
    let u = f64::from_bits(m.to_bits() / 3 + 0x2A9F_7893_0000_0000);
    halley(halley(u)).copysign(s)
}

/// Safeguarded Newton for `map(γ) = y` on `[lo, hi]` where the map is monotone and brackets `y`,
/// from `start` if it lies inside, else from the secant through the piece's ends.
fn solve_monotone(
    map: &ExitMap<f64>,
    lo: f64,
    hi: f64,
    f_lo: f64,
    f_hi: f64,
    y: f64,
    start: f64,
) -> f64 {
    if y == f_lo {
        return lo;
    }
    if y == f_hi {
        return hi;
    }
    let increasing = f_hi > f_lo;
    let (mut a, mut b) = (lo, hi);
    let mut x = if start > lo && start < hi {
        start
    } else {
        lo + (y - f_lo) / (f_hi - f_lo) * (hi - lo)
    };
    if !(x > lo && x < hi) {
        x = 0.5 * (lo + hi);
    }
    for _ in 0..100 {
        let fx = map.value(&x) - y;
        if fx == 0.0 {
            return x;
        }
        if (fx > 0.0) == increasing {
            b = x;
        } else {
            a = x;
        }
        let d = map.slope(&x);
        let newton = x - fx / d;
        let (xn, is_newton) = if newton > a && newton < b {
            (newton, true)
        } else {
            (0.5 * (a + b), false)
        };
        let step = (xn - x).abs();
        x = xn;
        // Newton converges quadratically: once a Newton step is below 1e-9 the new error is
        // ~|Φ''/2Φ'|·step² ≈ 1e-18 away from folds (and within the root's own sqrt(ε)
        // conditioning next to one), so another iteration buys nothing.
        if (is_newton && step <= 1e-9 * x.abs().max(1e-3)) || b - a <= 4.0 * f64::EPSILON {
            break;
        }
    }
    x
}

/// Lift a converged f64 root into `T`: one Newton step `γ − (Φ_T(γ) − y)/Φ'(γ)` whose dual part is
/// the implicit-function derivative `−∂Φ/∂θ / Φ'`. For plain f64 (`NDERIV == 0`) it is the root,
/// and `slope` (the f64 `Φ'(γ)`) is never evaluated: the f64 path computes its slope once, after.
#[inline]
pub fn lift_root<T: DualNum<f64>>(
    map_t: &ExitMap<T>,
    gamma: f64,
    target: f64,
    slope: impl FnOnce() -> f64,
) -> T {
    if T::NDERIV == 0 {
        return T::from(gamma);
    }
    let slope = slope();
    if slope.abs() < 1e-300 {
        return T::from(gamma);
    }
    let g = T::from(gamma);
    let residual = map_t.value(&g) - target;
    g - residual / slope
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Cubic-mode roots agree with a bisection to full precision on every monotone
    /// piece: within 1e-12, the root's conditioning 4ε/|Φ'| for |Φ'| ≥ 1e-3 (nearer a fold
    /// the root itself is only defined to ~sqrt(ε), and such roots are skipped).
    #[test]
    fn cubic_roots_match_bisection() {
        let mut checked = 0;
        for i in 0..60 {
            let eta_p = 1.05 + 0.05 * i as f64;
            for p in [1, 2] {
                let map = ExitMap::new(RootMode::Cubic, p, eta_p);
                for j in 0..97 {
                    let phi = wrap(-3.1 + 0.064 * j as f64);
                    let roots = exit_roots(&map, phi);
                    for r in 0..roots.n {
                        let (g, y) = (roots.gamma[r], roots.target[r]);
                        let slope = map.slope(&g);
                        if slope.abs() < 1e-3 {
                            continue;
                        }
                        // Bisection on the bracket of half-width 0.05 around the root.
                        let f = |x: f64| map.value(&x) - y;
                        let (mut lo, mut hi) =
                            ((g - 0.05).max(-FRAC_PI_2), (g + 0.05).min(FRAC_PI_2));
                        if f(lo).signum() == f(hi).signum() {
                            continue;
                        }
                        for _ in 0..200 {
                            let mid = 0.5 * (lo + hi);
                            if f(mid).signum() == f(lo).signum() {
                                lo = mid;
                            } else {
                                hi = mid;
                            }
                        }
                        assert!(
                            (g - lo).abs() <= 1e-12,
                            "η'={eta_p} p={p} φ={phi}: {g} vs {lo}"
                        );
                        checked += 1;
                    }
                }
            }
        }
        assert!(checked > 5000, "only {checked} roots checked");
    }

    /// The closed-form cubic root solves the cubic on its own piece: residual within 1e-13 (a few
    /// ulps of the O(10) terms) and on the right side of ±γ_c, over TT and TRT maps and targets
    /// spanning each piece's whole range (including wrapped ones).
    #[test]
    fn cubic_closed_form_solves_the_cubic_on_its_piece() {
        let mut checked = 0;
        for i in 0..60 {
            let eta_p = 1.02 + 0.05 * i as f64;
            for p in [1, 2] {
                let map = ExitMap::new(RootMode::Cubic, p, eta_p);
                let gc = map.caustic();
                for j in 0..=400 {
                    let g = -FRAC_PI_2 + PI * j as f64 / 400.0;
                    let piece = match gc {
                        Some(c) if g < -c => Piece::Lower,
                        Some(c) if g > c => Piece::Upper,
                        _ => Piece::Middle,
                    };
                    if gc.is_some_and(|c| (g.abs() - c).abs() < 1e-3) {
                        continue;
                    }
                    let y = map.value(&g);
                    let root = cubic_root(map.a, map.b, p as f64 * PI - y, piece);
                    assert!(
                        (map.value(&root) - y).abs() <= 1e-13,
                        "η'={eta_p} p={p} γ={g}: root {root}"
                    );
                    // The residual over |Φ'| (≥ ~1e-3 a step away from the fold).
                    assert!((root - g).abs() <= 1e-11, "η'={eta_p} p={p} γ={g}: {root}");
                    checked += 1;
                }
            }
        }
        assert!(checked > 40_000, "only {checked} checked");
    }

    /// The Newton start for `∛s` is within 1e-14 of `f64::cbrt` over the range the cubic sees
    /// (and far beyond), keeps the sign and maps 0 to 0.
    #[test]
    fn cube_root_start_matches_cbrt() {
        let mut s = 1e-90;
        while s < 1e90 {
            for v in [s, -s, 1.37 * s, -2.9 * s] {
                let (got, want) = (cube_root_start(v), v.cbrt());
                assert!(
                    (got - want).abs() <= 1e-14 * want.abs(),
                    "{v}: {got} vs {want}"
                );
            }
            s *= 1.01;
        }
        assert_eq!(cube_root_start(0.0), 0.0);
    }

    /// The libm-free rounding agrees with `floor`/`ceil` at integers, halves, tiny and negative
    /// values (the k range of a piece depends on it exactly).
    #[test]
    fn integer_rounding_matches_floor_and_ceil() {
        let mut x = -7.0;
        while x <= 7.0 {
            for v in [
                x,
                x + 1e-12,
                x - 1e-12,
                -0.0,
                1e-300,
                -1e-300,
                f64::INFINITY,
                -f64::INFINITY,
            ] {
                assert_eq!(floor_i64(v), v.floor() as i64, "{v}");
                assert_eq!(ceil_i64(v), v.ceil() as i64, "{v}");
            }
            x += 0.125;
        }
    }
}

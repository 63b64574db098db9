//! The azimuthal distributions of the Frostbite/HDRP hair model: for each lobe p = 0 (R),
//! 1 (TT), 2 (TRT), the trimmed logistic of Chiang 2016 (eq. 8) averaged over the fibre width,
//!
//! `N_p(φ, θ_d; β_N) = ½ ∫₋₁¹ D_s(φ − Φ_p(h)) dh`,  `Φ_p = 2p·asin(h/η′) − 2·asin h + pπ`,
//!
//! with Karis's fit of the modified index `η′ = 1.19/cos θ_d + 0.36 cos θ_d` (η = 1.55) and the
//! logistic scale `s(β_N)` of Chiang eq. 8. HDRP tabulates the integral on a 64³ texture;
//! hairfit evaluates it per direction ([`lobe`]) with a Gauss–Legendre rule fitted to the
//! integrand, so `S` keeps its relative accuracy far into the lobes' tails (a table's error
//! relative to the peak is 10²–10³ times the value there).
//!
//! The rule, in γ = asin h: the integrand `D_s(u(γ)) cos γ`, `u = φ − Φ_p(γ)`, is split where
//! u is not monotone (TRT's caustics) and where the trimmed logistic wraps (u ≡ π mod 2π, a
//! kink). On each segment it is largest at its anchor γ*: the root of u ≡ 0 if the segment has
//! one, else the end nearest to it. The map `γ = γ* + ℓ sinh v`, with ℓ the γ-distance over
//! which u moves by s at γ*, spreads the logistic's peak and its exponential tail evenly over
//! v; Gauss–Legendre pieces in v (each at most [`GAMMA_PIECE`] long in γ) then converge
//! geometrically. The tail beyond `REACH·s` of u from the anchor (below e⁻²⁸ of the anchor's
//! value) is left out, as are whole segments below 1e-14 of the largest anchor's.
//!
//! Cost: the nodes depend on β_N only through the f64 value of s, so the sum is taken in f64
//! as a Taylor series in 1/s (three sums) and the number type is formed once per lobe; and a
//! thread's sums are kept by (p, φ, x, s), as a goniometer's samples repeat (θ_d, |φ|).

use std::cell::RefCell;
use std::collections::HashMap;
use std::f64::consts::{FRAC_PI_2, PI, TAU};
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::OnceLock;

use num_dual::DualNum;

use crate::families::shared::logistic::{logistic_scale, trimmed_logistic, trimmed_logistic_norm};
use crate::families::shared::quadrature::{GaussLegendre, WidthRule};
use crate::geometry::angles::wrap;

use super::nodes::{node_sums, NodeLobe, Piece};

/// Smallest azimuthal roughness β_N the family accepts (radial smoothness 0.95): the accuracy
/// of [`lobe`] is tested down to here (tests/families/frostbite_azimuthal.rs).
pub const BETA_N_MIN: f64 = 0.05;
/// Largest β_N (radial smoothness 0).
pub const BETA_N_MAX: f64 = 1.0;

/// Gauss–Legendre nodes per piece of the rule in v.
const NODES: usize = 8;
/// Longest piece in v (the logistic in v is analytic within ±π/2 of the real axis).
const V_PIECE: f64 = 1.5;
/// Longest piece in γ (where ℓ is large the smooth factors, not the logistic, set the scale).
const GAMMA_PIECE: f64 = 0.7;
/// How far from its anchor a segment is integrated, in units of s of u.
const REACH: f64 = 28.0;
/// Segments whose anchor value is below this fraction of the largest are left out.
const NEGLIGIBLE: f64 = 1e-14;

/// Karis 2016's fit of Bravais' modified index for η = 1.55: `η′ = 1.19/cos θ_d + 0.36 cos θ_d`.
#[inline]
pub fn modified_index(cos_theta_d: f64) -> f64 {
    1.19 / cos_theta_d + 0.36 * cos_theta_d
}

/// `1/η′` without dividing by cos θ_d (finite as cos θ_d → 0).
#[inline]
pub fn inverse_modified_index(cos_theta_d: f64) -> f64 {
    cos_theta_d / (1.19 + 0.36 * cos_theta_d * cos_theta_d)
}

/// `Φ_p(h)` for `x = 1/η′` (Marschner 2003 eq. 3 with γ_t = asin(h x)).
#[inline]
pub fn exit_azimuth_at(p: usize, h: f64, x: f64) -> f64 {
    2.0 * p as f64 * (h * x).asin() - 2.0 * h.asin() + p as f64 * PI
}

/// `N_p(φ, θ_d; β_N)` by a plain Gauss–Legendre rule in γ with `nodes` nodes (a cross-check
/// that needs thousands of nodes at small β_N).
pub fn integrate_directly(p: usize, phi: f64, cos_theta_d: f64, beta_n: f64, nodes: usize) -> f64 {
    let rule = WidthRule::cached(nodes).expect("node count in range");
    let s = logistic_scale(&beta_n);
    let (inv_s, norm) = (s.recip(), trimmed_logistic_norm(&s));
    let x = inverse_modified_index(cos_theta_d);
    rule.nodes
        .iter()
        .map(|n| {
            let d = wrap(phi - exit_azimuth_at(p, n.h, x));
            n.weight * trimmed_logistic(&d, &inv_s, &norm)
        })
        .sum()
}

/// The trimmed logistic of one β_N, shared by the lobes of a direction pair: `s` (its value
/// places the rule's nodes), `1/s` and the normalisation in the number type.
pub struct Logistic<T> {
    s: f64,
    inv_s: T,
    norm: T,
}

impl<T: DualNum<f64>> Logistic<T> {
    pub fn new(beta_n: &T) -> Logistic<T> {
        let s = logistic_scale(beta_n);
        Logistic {
            s: s.re(),
            inv_s: s.recip(),
            norm: trimmed_logistic_norm(&s),
        }
    }

    /// `norm·(f₀ + f₁δ + f₂δ²)`, `δ = 1/s − 1/s₀` (zero in value; the `f` are the node sums of `nodes::taylor`).
    fn series(&self, f: [f64; 3]) -> T {
        let delta = self.inv_s.clone() - self.inv_s.re();
        let series = (delta.clone() * f[2] + f[1]) * delta + f[0];
        series * self.norm.clone()
    }

    /// `D_s(d)·s/norm` in f64: the size that decides which segments matter.
    #[inline]
    fn shape(&self, d: f64) -> f64 {
        let e = (-d.abs() / self.s).exp();
        e / ((1.0 + e) * (1.0 + e))
    }
}

/// One lobe's exit geometry at `x = 1/η′`: `u(γ) = φ − Φ_p(γ)` and its derivatives.
#[derive(Clone, Copy)]
struct Lobe {
    p: f64,
    phi: f64,
    x: f64,
}

impl Lobe {
    #[inline]
    fn u(self, g: f64) -> f64 {
        self.phi - 2.0 * self.p * (self.x * g.sin()).asin() + 2.0 * g - self.p * PI
    }

    /// `du/dγ = 2 − 2p x cos γ/√(1 − x² sin²γ)`.
    #[inline]
    fn slope(self, g: f64) -> f64 {
        let (s, c) = g.sin_cos();
        2.0 - 2.0 * self.p * self.x * c / (1.0 - self.x * self.x * s * s).sqrt()
    }

    /// `d²u/dγ² = 2p x (1 − x²) sin γ/(1 − x² sin²γ)^{3/2}`.
    #[inline]
    fn curvature(self, g: f64) -> f64 {
        let s = g.sin();
        let q = 1.0 - self.x * self.x * s * s;
        2.0 * self.p * self.x * (1.0 - self.x * self.x) * s / (q * q.sqrt())
    }

    /// γ in `[a, b]` where u = `target`, u monotone on `[a, b]` with `u(a) = ua`, `u(b) = ub`:
    /// Newton steps kept inside the bracket (bisection otherwise), to ~1 ulp.
    fn solve(self, target: f64, (a, ua): (f64, f64), (b, ub): (f64, f64)) -> f64 {
        if self.p == 0.0 {
            return ((target - self.phi) * 0.5).clamp(a, b);
        }
        let rising = ub > ua;
        let (mut lo, mut hi) = (a, b);
        let mut g = a + (target - ua) / (ub - ua) * (b - a);
        for _ in 0..100 {
            let f = self.u(g) - target;
            if f == 0.0 {
                return g;
            }
            if (f < 0.0) == rising {
                lo = g;
            } else {
                hi = g;
            }
            let d = self.slope(g);
            let newton = g - f / d;
            let next = if d != 0.0 && newton > lo && newton < hi {
                newton
            } else {
                0.5 * (lo + hi)
            };
            if (next - g).abs() <= 4.0 * f64::EPSILON || hi - lo <= 4.0 * f64::EPSILON {
                return next;
            }
            g = next;
        }
        g
    }
}

/// A stretch of γ on which u is monotone and within π of the centre `c` (a multiple of 2π), with
/// its anchor `g0` (where `|u − c|` is least).
struct Segment {
    a: f64,
    b: f64,
    g0: f64,
    size: f64,
}

fn gauss_legendre() -> &'static GaussLegendre {
    static RULE: OnceLock<GaussLegendre> = OnceLock::new();
    RULE.get_or_init(|| GaussLegendre::new(NODES))
}

/// Most entries [`SUMS`] holds per thread before it starts over (≈ 5 MB).
const CACHE_ENTRIES: usize = 1 << 16;

/// (p, φ, x, s bits) → the three sums of [`lobe_sums`].
type SumsByKey = HashMap<(usize, u64, u64, u64), [f64; 3], BuildHasherDefault<KeyHasher>>;

thread_local! {
    /// The rule's f64 sums by (p, φ, x, s) bits: a goniometer's samples share (θ_d, |φ|) (the
    /// demo's 2,340 samples have 440 distinct pairs), so a pass integrates each pair once. The
    /// sums are a pure function of the key, so a hit returns the very bits a recomputation would.
    static SUMS: RefCell<SumsByKey> =
        RefCell::new(HashMap::default());
}

/// FNV-1a over the key's words: the keys are few and not adversarial.
#[derive(Default)]
struct KeyHasher(u64);

impl Hasher for KeyHasher {
    fn finish(&self) -> u64 {
        self.0
    }
    fn write(&mut self, bytes: &[u8]) {
        for &b in bytes {
            self.0 = (self.0 ^ b as u64).wrapping_mul(0x100_0000_01b3);
        }
    }
    fn write_u64(&mut self, w: u64) {
        self.0 = (self.0 ^ w)
            .wrapping_mul(0x9e37_79b9_7f4a_7c15)
            .rotate_left(29);
    }
    fn write_usize(&mut self, w: usize) {
        self.write_u64(w as u64);
    }
}

/// `N_p(φ, θ_d; β_N)` (p = 0, 1, 2 for R, TT, TRT) for `x = 1/η′`
/// ([`inverse_modified_index`]), φ in radians (N_p is even in φ).
pub fn lobe<T: DualNum<f64>>(p: usize, phi: f64, x: f64, logistic: &Logistic<T>) -> T {
    let key = (p, phi.to_bits(), x.to_bits(), logistic.s.to_bits());
    let cached = SUMS.with(|m| m.borrow().get(&key).copied());
    let sums = cached.unwrap_or_else(|| {
        let sums = lobe_sums(p, phi, x, logistic);
        SUMS.with(|m| {
            let mut m = m.borrow_mut();
            if m.len() >= CACHE_ENTRIES {
                m.clear();
            }
            m.insert(key, sums);
        });
        sums
    });
    logistic.series(sums)
}

/// The rule's three f64 sums of [`Logistic::taylor`] for one lobe.
fn lobe_sums<T: DualNum<f64>>(p: usize, phi: f64, x: f64, logistic: &Logistic<T>) -> [f64; 3] {
    let lobe = Lobe {
        p: p as f64,
        phi: wrap(phi).abs(),
        x: x.clamp(0.0, 1.0),
    };
    let s = logistic.s;
    // Monotone pieces of u: TRT turns at its caustics, sin²γ_c = (4x² − 1)/3x², when x > ½.
    let mut ends = [-FRAC_PI_2, 0.0, 0.0, FRAC_PI_2];
    let mut n_ends = 2;
    if p == 2 && lobe.x > 0.5 {
        let gc = ((4.0 * lobe.x * lobe.x - 1.0) / (3.0 * lobe.x * lobe.x))
            .sqrt()
            .asin();
        ends = [-FRAC_PI_2, -gc, gc, FRAC_PI_2];
        n_ends = 4;
    } else {
        ends[1] = FRAC_PI_2;
    }
    let mut segments: Vec<Segment> = Vec::with_capacity(8);
    for w in ends[..n_ends].windows(2) {
        let (ga, gb) = (w[0], w[1]);
        let (ua, ub) = (lobe.u(ga), lobe.u(gb));
        let (lo, hi) = (ua.min(ub), ua.max(ub));
        // The kinks u = π + 2πk inside the piece, in γ order.
        // A handful of kinks: the cuts, sorted in place, are one allocation.
        let mut cuts = Vec::with_capacity(8);
        cuts.push((ga, ua));
        let first = ((lo - PI) / TAU).ceil() as i64;
        let last = ((hi - PI) / TAU).floor() as i64;
        cuts.extend(
            (first..=last)
                .map(|k| PI + TAU * k as f64)
                .filter(|&t| t > lo && t < hi)
                .map(|t| (lobe.solve(t, (ga, ua), (gb, ub)), t)),
        );
        cuts[1..].sort_by(|l, r| l.0.total_cmp(&r.0));
        cuts.push((gb, ub));
        for c in cuts.windows(2) {
            let ((a, u_a), (b, u_b)) = (c[0], c[1]);
            if b - a <= 4.0 * f64::EPSILON {
                continue;
            }
            let centre = TAU * (0.5 * (u_a + u_b) / TAU).round();
            let (l, h) = (u_a.min(u_b), u_a.max(u_b));
            let g0 = if centre > l && centre < h {
                lobe.solve(centre, (a, u_a), (b, u_b))
            } else if (u_a - centre).abs() <= (u_b - centre).abs() {
                a
            } else {
                b
            };
            let size = logistic.shape(wrap(lobe.u(g0) - centre));
            segments.push(Segment { a, b, g0, size });
        }
    }
    let largest = segments.iter().map(|s| s.size).fold(0.0, f64::max);
    let rule = gauss_legendre();
    let mut pieces = Vec::with_capacity(16);
    for seg in segments.iter().filter(|s| s.size >= NEGLIGIBLE * largest) {
        let (a, b, g0) = (seg.a, seg.b, seg.g0);
        // ℓ: the γ-distance over which u moves by s at the anchor, ½|u''|ℓ² + |u'|ℓ = s.
        let d1 = lobe.slope(g0).abs();
        let d2 = lobe.curvature(g0).abs();
        let ell = 2.0 * s / (d1 + (d1 * d1 + 2.0 * s * d2).sqrt());
        // Beyond REACH·s of u at the segment's slowest |u'| the integrand is negligible; |u'|
        // is monotone in |γ| on each side of 0 (and of TRT's caustics, which end segments).
        let mut slowest = lobe.slope(a).abs().min(lobe.slope(b).abs());
        if a < 0.0 && b > 0.0 {
            slowest = slowest.min(lobe.slope(0.0).abs());
        }
        let reach = if slowest > 0.0 {
            REACH * s / slowest
        } else {
            f64::INFINITY
        };
        let va = -((g0 - a).min(reach) / ell).asinh();
        let vb = ((b - g0).min(reach) / ell).asinh();
        let n_pieces = ((vb - va) / V_PIECE).ceil().max(1.0) as usize;
        let step = (vb - va) / n_pieces as f64;
        for i in 0..n_pieces {
            let w1 = va + step * i as f64;
            let w2 = w1 + step;
            let extent = ell * (w2.sinh() - w1.sinh());
            let parts = (extent / GAMMA_PIECE).ceil().max(1.0) as usize;
            let sub = (w2 - w1) / parts as f64;
            pieces.extend((0..parts).map(|j| Piece {
                mid: w1 + sub * (j as f64 + 0.5),
                half: 0.5 * sub,
                g0,
                ell,
            }));
        }
    }
    let node_lobe = NodeLobe {
        p: lobe.p,
        phi: lobe.phi,
        x: lobe.x,
        inv_s: logistic.inv_s.re(),
    };
    node_sums(node_lobe, &pieces, &rule.nodes, &rule.weights)
}

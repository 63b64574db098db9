//! The cubic exit-angle maps on the lanes: a lobe's map ([`Cubic`]) with its closed-form root
//! (Cardano or Viète, then Halley from the bits for the cube root), and the one root on a
//! monotone piece ([`Piece`], [`piece_root`]) that a settled Newton step confirms.

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use super::functions::{floor, LaneFunctions};
use super::steps::{bits, ceil};
use super::vector::Lane;

/// The cubic exit-angle map `Φ̂ = aγ³ + bγ + pπ` of one lobe on the lanes, with the
/// closed-form root's per-map quantities (`1/a`, `P/3 = b/(3a)`).
pub(super) struct Cubic<V> {
    p: f64,
    pub(super) a: V,
    b: V,
    inv_a: V,
    p3: V,
}

impl<V: Lane> Cubic<V> {
    /// `c = asin(1/η')`, `a = −8pc/π³`, `b = 6pc/π − 2`, as `ExitMap::new`.
    #[inline(always)]
    pub(super) fn new(p: usize, inv_eta_p: V) -> Self {
        let c = inv_eta_p.asin();
        let pf = p as f64;
        let a = c * (-8.0 * pf / (PI * PI * PI));
        let b = c * (6.0 * pf / PI) - 2.0;
        let inv_a = V::ONE / a;
        Cubic {
            p: pf,
            a,
            b,
            inv_a,
            p3: b * inv_a * (1.0 / 3.0),
        }
    }

    #[inline(always)]
    pub(super) fn value(&self, g: V) -> V {
        (self.a * (g * g) + self.b) * g + self.p * PI
    }

    #[inline(always)]
    pub(super) fn slope(&self, g: V) -> V {
        self.a * g * g * 3.0 + self.b
    }

    /// Lanes where the map folds: `b > 0` (`a < 0` always), so `dΦ̂/dγ = 0` at
    /// `γ_c = sqrt(−b/(3a)) = sqrt(−P/3)`.
    #[inline(always)]
    pub(super) fn folds(&self) -> V {
        self.b.cmp_gt(V::ZERO) & self.a.cmp_lt(V::ZERO)
    }

    /// The caustic `γ_c` and the lanes where it lies inside `(0, π/2)`.
    #[inline(always)]
    pub(super) fn caustic(&self) -> (V, V) {
        let g = (-self.p3).sqrt();
        (g, self.folds() & g.cmp_lt(V::splat(FRAC_PI_2)))
    }

    /// `roots::cubic_root` for `c₀ = pπ − y` on the piece whose Viète index is `j` (0 upper,
    /// 1 middle, 2 lower); `r = sqrt(−P/3)` is the caustic where the map folds.
    #[inline(always)]
    fn closed_form_root(&self, y: V, j: f64, r: V) -> V {
        let c0 = -y + self.p * PI;
        let p3 = self.p3;
        let half_q = c0 * 0.5 * self.inv_a;
        let disc = half_q * half_q + p3 * p3 * p3;
        let cardano_lanes = disc.cmp_gt(V::ZERO);
        let mut root = V::ZERO;
        if bits(cardano_lanes) != 0 {
            let s = -half_q - disc.sqrt().copysign(half_q);
            let u = cube_root_start(s);
            let cardano = u.cmp_eq(V::ZERO).blend(V::ZERO, u - p3 / u);
            root = cardano_lanes.blend(cardano, root);
        }
        if bits(cardano_lanes) != V::all_bits() {
            let arg = (-half_q / (r * r * r)).max(V::splat(-1.0)).min(V::ONE);
            let third = arg.acos() * (1.0 / 3.0);
            let viete = r * 2.0 * (third - j * (TAU / 3.0)).cos();
            root = cardano_lanes.blend(root, viete);
        }
        root
    }
}

/// `roots::cube_root_start` per lane: the exponent divided by 3 through the bits, then two
/// Halley steps on the lanes.
#[inline(always)]
fn cube_root_start<V: Lane>(s: V) -> V {
    let m = s.abs();
    let mut guess = m.to_array();
    for v in guess.as_mut() {
        *v = f64::from_bits(v.to_bits() / 3 + 0x2A9F_7893_0000_0000);
    }
    let u = halley(halley(V::new(guess), m), m).copysign(s);
    // 0 and non-finite values pass through, as in the scalar start.
    let pass = s.cmp_eq(V::ZERO) | !s.is_finite();
    pass.blend(s, u)
}

/// One Halley step from `u` towards `∛m` (a function, not a closure: see `super::groups_avx2`).
#[inline(always)]
fn halley<V: Lane>(u: V, m: V) -> V {
    let u3 = u * u * u;
    u * (u3 + m * 2.0) / (u3 * 2.0 + m)
}

/// One monotone piece `[lo, hi]` of a map on the lanes, with the map's values at its ends.
pub(super) struct Piece<V> {
    pub(super) lo: V,
    pub(super) hi: V,
    pub(super) f_lo: V,
    pub(super) f_hi: V,
    /// Viète index of the piece (0 upper, 1 middle, 2 lower).
    pub(super) j: f64,
}

/// The root of `map(γ) = φ + 2πk` on `piece` where there is exactly one (the valid lanes), as
/// `roots::exit_roots` with `roots::solve_monotone` finds it when its first Newton step settles.
/// Lanes with more than one root, a target on a piece's end, a start outside the piece or a
/// Newton step that does not settle are irregular.
#[inline(always)]
pub(super) fn piece_root<V: Lane>(
    map: &Cubic<V>,
    piece: &Piece<V>,
    r: V,
    phi: V,
    active: V,
) -> (V, V, V) {
    let (vmin, vmax) = (piece.f_lo.min(piece.f_hi), piece.f_lo.max(piece.f_hi));
    let k_min = ceil((vmin - phi) * (1.0 / TAU));
    let k_max = floor((vmax - phi) * (1.0 / TAU));
    let one = active & k_min.cmp_eq(k_max);
    let several = active & k_max.cmp_gt(k_min);
    if bits(one) == 0 {
        return (V::ZERO, one, several);
    }
    let y = phi + k_min * TAU;
    let start = map.closed_form_root(y, piece.j, r);
    let x = one.blend(start, V::ZERO);
    let fx = map.value(x) - y;
    let d = map.slope(x);
    let newton = x - fx / d;
    // The bracket after the first evaluation: x replaces the end on fx's side.
    let increasing = piece.f_hi.cmp_gt(piece.f_lo);
    let replaces_hi = !(fx.cmp_gt(V::ZERO) ^ increasing);
    let (a, b) = (
        replaces_hi.blend(piece.lo, x),
        replaces_hi.blend(x, piece.hi),
    );
    let exact = fx.cmp_eq(V::ZERO);
    let settled = newton.cmp_gt(a)
        & newton.cmp_lt(b)
        & (newton - x)
            .abs()
            .cmp_le(newton.abs().max(V::splat(1e-3)) * 1e-9);
    let inside = start.cmp_gt(piece.lo) & start.cmp_lt(piece.hi);
    let on_end = y.cmp_eq(piece.f_lo) | y.cmp_eq(piece.f_hi);
    let ok = inside & !on_end & (exact | settled);
    let root = exact.blend(x, newton);
    (root, one & ok, several | (one & !ok))
}

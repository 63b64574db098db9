//! `S` four or eight samples at a time, for plain f64 in cubic mode (what `hairfit eval` runs):
//! each step of the scalar [`super::evaluate`] done on vectors ([`vector::Lane`]). The vector is
//! chosen at run time: eight lanes in one 512-bit register on CPUs with AVX-512 ([`avx512`]),
//! eight in two 256-bit registers on CPUs with AVX2 ([`avx2`], [`vector::Pair`]), elsewhere four
//! in `wide::f64x4`, which the default x86-64 target builds as two SSE2 halves. All run the
//! lanes' own exp, sin/cos, asin and acos ([`functions`]) and the same IEEE operations, so they
//! give the same bits. Per sample with every effect on (random directions, callgrind): the scalar
//! model takes 2,520 instructions, the four-lane AVX2 kernel about 670 (the README has the
//! times).
//!
//! The lanes take the common path only: at most one root per monotone piece of each map, a Newton
//! step from the closed-form cubic root that settles at once, and no TT fold. A lane off that
//! path is evaluated again by the scalar model, which stays the reference; elsewhere the two agree
//! to ~1e-13 relative (the lanes' and libm's transcendental functions differ in the last bits;
//! tests/model_lanes.rs states the tolerance and why).

use std::f64::consts::{FRAC_PI_2, PI, TAU};

use wide::f64x4;

use super::azimuthal::MIN_DENOM;
use super::longitudinal::INV_SQRT_TAU;
use super::{evaluate_into, scattering_batch, Angles, ModelConfig, Params, Prepared, RootMode};

#[cfg(target_arch = "x86_64")]
mod avx2;
#[cfg(target_arch = "x86_64")]
mod avx512;
mod functions;
mod vector;
use functions::floor;
use vector::{Lane, Pair, MAX_LANES};

/// Which vector type runs the lanes (all give the same bits).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaneKernel {
    /// `wide::f64x4` (two SSE2 halves in the default build), on any CPU.
    Wide,
    /// Eight lanes in two AVX registers where the CPU has AVX2, else `Wide`.
    Avx2,
    /// Eight lanes in one AVX-512 register where the CPU has AVX-512F and DQ, else `Avx2`.
    Avx512,
}

impl LaneKernel {
    /// The kernels this CPU runs as themselves (not by falling back), `Wide` first; the last is
    /// the one `scattering_lanes` picks.
    pub fn on_this_cpu() -> Vec<LaneKernel> {
        let mut kernels = vec![LaneKernel::Wide];
        #[cfg(target_arch = "x86_64")]
        {
            if avx2::available() {
                kernels.push(LaneKernel::Avx2);
            }
            if avx512::available() {
                kernels.push(LaneKernel::Avx512);
            }
        }
        kernels
    }
}

/// [`super::scattering_batch`] for f64: `out[k * nc + c]`. Cubic mode runs four or eight samples
/// per vector (each sample's value depends on that sample only, not on its neighbours or its
/// place in the batch); exact mode runs the scalar model.
pub fn scattering_lanes(
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    out: &mut [f64],
) {
    scattering_lanes_on(LaneKernel::Avx512, params, config, angles, out)
}

/// [`scattering_lanes`] on a chosen kernel (tests and benchmarks compare them).
#[doc(hidden)]
pub fn scattering_lanes_on(
    kernel: LaneKernel,
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    out: &mut [f64],
) {
    let nc = params.sigma_a.len();
    if config.mode != RootMode::Cubic || nc == 0 {
        return scattering_batch(params, config, angles, out);
    }
    assert_eq!(
        out.len(),
        angles.len() * nc,
        "one output per sample and channel"
    );
    let prepared = Prepared::new(params);
    let scalar = |a: &Angles, o: &mut [f64]| evaluate_into(params, &prepared, config, a, o);
    let lanes = Lanes {
        params,
        prepared: &prepared,
        config,
    };
    #[cfg(target_arch = "x86_64")]
    {
        if kernel == LaneKernel::Avx512 && avx512::available() {
            // SAFETY: the CPU has AVX-512F and AVX-512DQ.
            unsafe { groups_avx512(&lanes, angles, out, &scalar) };
            return;
        }
        if kernel != LaneKernel::Wide && avx2::available() {
            // SAFETY: the CPU has AVX2.
            unsafe { groups_avx2(&lanes, angles, out, &scalar) };
            return;
        }
    }
    groups::<f64x4>(&lanes, angles, out, &scalar);
}

/// The groups on two [`avx2::F64x4`] side by side (eight samples: two independent chains of
/// work, 6% less time in eval than one register, measured on an Intel CPU run with AVX2 only),
/// compiled for AVX2 so that its intrinsics inline. Every helper below is `#[inline(always)]`
/// (and none is a closure) for that reason: a helper left out of line has no AVX2 context, and
/// each intrinsic in it becomes a call (eval ran 3× slower).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn groups_avx2(
    lanes: &Lanes<'_>,
    angles: &[Angles],
    out: &mut [f64],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    groups::<Pair<avx2::F64x4>>(lanes, angles, out, scalar)
}

/// The groups on [`avx512::F64x8`], compiled for AVX-512 as `groups_avx2` is for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512dq")]
unsafe fn groups_avx512(
    lanes: &Lanes<'_>,
    angles: &[Angles],
    out: &mut [f64],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    groups::<avx512::F64x8>(lanes, angles, out, scalar)
}

#[inline(always)]
fn groups<V: Lane>(
    lanes: &Lanes<'_>,
    angles: &[Angles],
    out: &mut [f64],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    let nc = lanes.params.sigma_a.len();
    let n = V::LANES;
    let mut sums = vec![V::ZERO; nc];
    let (groups, tail) = angles.split_at(angles.len() / n * n);
    for (group, o) in groups.chunks_exact(n).zip(out.chunks_mut(n * nc)) {
        one_group(lanes, group, n, o, &mut sums, scalar);
    }
    if let Some(last) = tail.last() {
        // A short last group repeats its last sample: a lane's value depends on its own sample
        // only, so every sample gets the same bits wherever it stands in the batch.
        let full: [Angles; MAX_LANES] = std::array::from_fn(|l| *tail.get(l).unwrap_or(last));
        let o = &mut out[groups.len() * nc..];
        one_group(lanes, &full[..n], tail.len(), o, &mut sums, scalar);
    }
}

/// The first `used` samples of `group` into `o` (`o[l * nc + c]`), the lanes off the fast path
/// by the scalar model.
#[inline(always)]
fn one_group<V: Lane>(
    lanes: &Lanes<'_>,
    group: &[Angles],
    used: usize,
    o: &mut [f64],
    sums: &mut [V],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    let nc = sums.len();
    let irregular = lanes.group(group, sums);
    for (c, s) in sums.iter().enumerate() {
        for (l, v) in s.to_array().as_ref().iter().take(used).enumerate() {
            o[l * nc + c] = *v;
        }
    }
    for (l, a) in group.iter().take(used).enumerate() {
        if irregular & (1 << l) != 0 {
            scalar(a, &mut o[l * nc..(l + 1) * nc]);
        }
    }
}

/// The batch's parameters, their parameter-only factors and the effects, for the groups.
struct Lanes<'a> {
    params: &'a Params<f64>,
    prepared: &'a Prepared<f64>,
    config: &'a ModelConfig,
}

/// `x` where `mask` is set, else 0.
#[inline(always)]
fn keep<V: Lane>(mask: V, x: V) -> V {
    mask.blend(x, V::ZERO)
}

/// Lanes set in `mask`, as bits.
#[inline(always)]
fn bits<V: Lane>(mask: V) -> u32 {
    mask.move_mask() as u32
}

/// `ceil` without libm, as [`floor`].
#[inline(always)]
fn ceil<V: Lane>(x: V) -> V {
    let r = x.round();
    r + keep(r.cmp_lt(x), V::ONE)
}

/// `angles::wrap` for `|x| < 4π` (the same bits); lanes outside that range (and at exactly −2π,
/// where fmod gives −0) are reported in the second value. On (−4π, −2π) `wrap` takes
/// `fmod(x, 2π)`, which is exact, and `x + 2π` is exact there too (Sterbenz), so they agree.
#[inline(always)]
fn wrap<V: Lane>(x: V) -> (V, V) {
    let inside = x.abs().cmp_lt(V::splat(TAU));
    let once = x.cmp_ge(V::splat(TAU)) & x.cmp_lt(V::splat(2.0 * TAU));
    let once_below = x.cmp_gt(V::splat(-2.0 * TAU)) & x.cmp_lt(V::splat(-TAU));
    let r = inside.blend(x, once_below.blend(x + TAU, x - TAU));
    let y = r.cmp_lt(V::ZERO).blend(r + TAU, r);
    let y = y.cmp_gt(V::splat(PI)).blend(y - TAU, y);
    (y, !(inside | once | once_below))
}

/// The glint's unnormalised Gaussian `exp(−(x/w)²/2)`, `inv_w = 1/w`.
#[inline(always)]
fn bump<V: Lane>(x: V, inv_w: f64) -> V {
    let z = x * inv_w;
    (z * z * -0.5).exp()
}

/// `gaussian_inv(x, inv_s)`.
#[inline(always)]
fn gaussian_inv<V: Lane>(x: V, inv_s: f64) -> V {
    let z = x * inv_s;
    (z * z * -0.5).exp() * inv_s * INV_SQRT_TAU
}

/// The Bravais indices of [`super::bravais::bravais_indices`] with the reciprocals the lobes
/// divide by, all from one division: `root = sqrt(η² − sin²θ_d)`, `η' = root/cos θ_d`,
/// `η'' = η² cos θ_d/root`, `cos θ_t = root/η`.
#[derive(Clone, Copy)]
struct BravaisLanes<V> {
    eta_p: V,
    eta_pp: V,
    inv_eta_p: V,
    inv_cos_theta_t: V,
}

#[inline(always)]
fn bravais<V: Lane>(eta: V, sin_td: V, cos_td: V, inv_cos_td: V) -> BravaisLanes<V> {
    let s2 = sin_td * sin_td;
    let eta2 = eta * eta;
    let root = (eta2 - s2).sqrt();
    let inv_root = V::ONE / root;
    BravaisLanes {
        eta_p: root * inv_cos_td,
        eta_pp: eta2 * cos_td * inv_root,
        inv_eta_p: cos_td * inv_root,
        inv_cos_theta_t: eta * inv_root,
    }
}

/// `cos γ_t = sqrt(1 − (h/η')²)`.
#[inline(always)]
fn cos_gamma_t<V: Lane>(h: V, inv_eta_p: V) -> V {
    let x = h * inv_eta_p;
    (-(x * x) + 1.0).sqrt()
}

/// Fresnel `F` as [`super::fresnel::fresnel`].
#[inline(always)]
fn fresnel<V: Lane>(eta_p: V, eta_pp: V, cos_gi: V, cos_gt: V) -> V {
    let a = eta_p * cos_gt;
    let b = eta_pp * cos_gi;
    let (n_s, d_s) = (cos_gi - a, cos_gi + a);
    let (n_p, d_p) = (b - cos_gt, b + cos_gt);
    let (s, q) = (n_s * d_p, n_p * d_s);
    let d = d_s * d_p;
    (s * s + q * q) / (d * d) * 0.5
}

/// The cubic exit-angle map `Φ̂ = aγ³ + bγ + pπ` of one lobe on the lanes, with the
/// closed-form root's per-map quantities (`1/a`, `P/3 = b/(3a)`).
struct Cubic<V> {
    p: f64,
    a: V,
    b: V,
    inv_a: V,
    p3: V,
}

impl<V: Lane> Cubic<V> {
    /// `c = asin(1/η')`, `a = −8pc/π³`, `b = 6pc/π − 2`, as `ExitMap::new`.
    #[inline(always)]
    fn new(p: usize, inv_eta_p: V) -> Self {
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
    fn value(&self, g: V) -> V {
        (self.a * (g * g) + self.b) * g + self.p * PI
    }

    #[inline(always)]
    fn slope(&self, g: V) -> V {
        self.a * g * g * 3.0 + self.b
    }

    /// Lanes where the map folds: `b > 0` (`a < 0` always), so `dΦ̂/dγ = 0` at
    /// `γ_c = sqrt(−b/(3a)) = sqrt(−P/3)`.
    #[inline(always)]
    fn folds(&self) -> V {
        self.b.cmp_gt(V::ZERO) & self.a.cmp_lt(V::ZERO)
    }

    /// The caustic `γ_c` and the lanes where it lies inside `(0, π/2)`.
    #[inline(always)]
    fn caustic(&self) -> (V, V) {
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

/// One Halley step from `u` towards `∛m` (a function, not a closure: see `groups_avx2`).
#[inline(always)]
fn halley<V: Lane>(u: V, m: V) -> V {
    let u3 = u * u * u;
    u * (u3 + m * 2.0) / (u3 * 2.0 + m)
}

/// One monotone piece `[lo, hi]` of a map on the lanes, with the map's values at its ends.
struct Piece<V> {
    lo: V,
    hi: V,
    f_lo: V,
    f_hi: V,
    /// Viète index of the piece (0 upper, 1 middle, 2 lower).
    j: f64,
}

/// The root of `map(γ) = φ + 2πk` on `piece` where there is exactly one (the valid lanes), as
/// `roots::exit_roots` with `roots::solve_monotone` finds it when its first Newton step settles.
/// Lanes with more than one root, a target on a piece's end, a start outside the piece or a
/// Newton step that does not settle are irregular.
#[inline(always)]
fn piece_root<V: Lane>(map: &Cubic<V>, piece: &Piece<V>, r: V, phi: V, active: V) -> (V, V, V) {
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

impl Lanes<'_> {
    /// `M_p(θ_h)`.
    #[inline(always)]
    fn longitudinal<V: Lane>(&self, p: usize, theta_h: V) -> V {
        let (alpha, inv_beta) = self.prepared.shapes[p];
        gaussian_inv(theta_h - alpha, inv_beta)
    }

    /// Add a path through the fiber entering at `h = sin γ_i`: its Fresnel attenuation
    /// `A(p, h)` times `weight`, absorbed along its chord `exp(−p σ_a · 2cos γ_t/cos θ_t)` per
    /// channel, where `mask` is set.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_through_fiber<V: Lane>(
        &self,
        p: usize,
        br: BravaisLanes<V>,
        h: V,
        cos_gi: V,
        weight: V,
        mask: V,
        sums: &mut [V],
    ) {
        let cos_gt = cos_gamma_t(h, br.inv_eta_p);
        let f = fresnel(br.eta_p, br.eta_pp, cos_gi, cos_gt);
        let t = -f + 1.0;
        let attenuation = if p == 1 { t * t } else { t * t * f };
        let base = attenuation * weight;
        let chord = cos_gt * 2.0 * br.inv_cos_theta_t;
        for (sum, &sigma) in sums.iter_mut().zip(&self.params.sigma_a) {
            let e = (chord * sigma * -(p as f64)).exp();
            *sum = *sum + keep(mask, base * e);
        }
    }

    /// Add one lobe's roots: `A cos γ / |2Φ'|` times `scale`, absorbed, where `valid`.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    fn add_root<V: Lane>(
        &self,
        p: usize,
        map: &Cubic<V>,
        br: BravaisLanes<V>,
        g: V,
        valid: V,
        scale: V,
        sums: &mut [V],
    ) {
        let (h, cos_gi) = g.sin_cos();
        let denom = map.slope(g).abs() * 2.0;
        let denom = denom
            .cmp_lt(V::splat(MIN_DENOM))
            .blend(V::splat(MIN_DENOM), denom);
        self.add_through_fiber(p, br, h, cos_gi, cos_gi / denom * scale, valid, sums);
    }

    /// `S` of `V::LANES` samples into `sums` (one vector per channel); returns the lanes the
    /// scalar model must evaluate instead, as bits.
    #[inline(always)]
    fn group<V: Lane>(&self, angles: &[Angles], sums: &mut [V]) -> u32 {
        let angles = &angles[..V::LANES];
        // `half_angles` on the lanes (the same operations, so the same bits); a φ_r − φ_i
        // beyond ±4π, which `wrap` would need its fmod for, is the scalar model's.
        let theta_i = V::from_fn(|l| angles[l].theta_i);
        let theta_r = V::from_fn(|l| angles[l].theta_r);
        let phi_i = V::from_fn(|l| angles[l].phi_i);
        let phi_r = V::from_fn(|l| angles[l].phi_r);
        let theta_h = (theta_i + theta_r) * 0.5;
        let theta_d = (theta_r - theta_i) * 0.5;
        let (phi, far) = wrap(phi_r - phi_i);
        let phi_h = (phi_i + phi_r) * 0.5;
        let mut irregular = bits(far);
        let (sin_td, cos_td) = theta_d.sin_cos();
        let inv_cos_td = V::ONE / cos_td;
        let inv_cos2 = inv_cos_td * inv_cos_td;
        let lobes = self.config.effects.lobes;
        let all = V::splat(f64::from_bits(u64::MAX));
        sums.fill(V::ZERO);

        if lobes.r || lobes.tt {
            let br = bravais(V::splat(self.params.eta), sin_td, cos_td, inv_cos_td);
            if lobes.r {
                let m = self.longitudinal(0, theta_h) * inv_cos2;
                let (h, cos_gi) = (phi * -0.5).sin_cos();
                let cos_gt = cos_gamma_t(h, br.inv_eta_p);
                let f = fresnel(br.eta_p, br.eta_pp, cos_gi, cos_gt);
                let v = f * cos_gi * 0.25 * m;
                for sum in sums.iter_mut() {
                    *sum = *sum + v;
                }
            }
            if lobes.tt {
                let m = self.longitudinal(1, theta_h) * inv_cos2;
                let map = Cubic::new(1, br.inv_eta_p);
                // A TT fold (η' < 1.155) splits the map: the scalar model's case.
                irregular |= bits(map.folds() | !br.eta_p.cmp_ge(V::ONE));
                let whole = Piece {
                    lo: V::splat(-FRAC_PI_2),
                    hi: V::splat(FRAC_PI_2),
                    f_lo: map.value(V::splat(-FRAC_PI_2)),
                    f_hi: map.value(V::splat(FRAC_PI_2)),
                    j: 1.0,
                };
                let (g, valid, bad) = piece_root(&map, &whole, V::ZERO, phi, all);
                irregular |= bits(bad);
                if bits(valid) != 0 {
                    self.add_root(1, &map, br, g, valid, m, sums);
                }
            }
        }
        if lobes.trt {
            let eta = if self.config.effects.eccentricity {
                let (sum, diff) = self.prepared.eccentric;
                (V::splat(diff) * (phi_h * 2.0).cos() + sum) * 0.5
            } else {
                V::splat(self.params.eta)
            };
            let br = bravais(eta, sin_td, cos_td, inv_cos_td);
            irregular |= bits(!br.eta_p.cmp_ge(V::ONE));
            let m = self.longitudinal(2, theta_h) * inv_cos2;
            let map = Cubic::new(2, br.inv_eta_p);
            let (r, has_caustic) = map.caustic();
            let gc = keep(has_caustic, r);
            let glint = if self.config.effects.glints {
                let (glint, bad) = self.glint_geometry(&map, br.eta_p, gc, has_caustic, phi);
                irregular |= bad;
                Some(glint)
            } else {
                None
            };
            let scale = glint.as_ref().map_or(m, |gl| gl.fade * m);
            // Pieces in γ order: below −γ_c, between ±γ_c (the whole domain without a caustic),
            // above γ_c.
            let half_pi = V::splat(FRAC_PI_2);
            let (f_bottom, f_top) = (map.value(-half_pi), map.value(half_pi));
            let (f_minus, f_plus) = (map.value(-gc), map.value(gc));
            let pieces = [
                (
                    Piece {
                        lo: -half_pi,
                        hi: -gc,
                        f_lo: f_bottom,
                        f_hi: f_minus,
                        j: 2.0,
                    },
                    has_caustic,
                ),
                (
                    Piece {
                        lo: has_caustic.blend(-gc, -half_pi),
                        hi: has_caustic.blend(gc, half_pi),
                        f_lo: has_caustic.blend(f_minus, f_bottom),
                        f_hi: has_caustic.blend(f_plus, f_top),
                        j: 1.0,
                    },
                    all,
                ),
                (
                    Piece {
                        lo: gc,
                        hi: half_pi,
                        f_lo: f_plus,
                        f_hi: f_top,
                        j: 0.0,
                    },
                    has_caustic,
                ),
            ];
            for (piece, active) in &pieces {
                if bits(*active) == 0 {
                    continue;
                }
                let (g, valid, bad) = piece_root(&map, piece, r, phi, *active);
                irregular |= bits(bad);
                if bits(valid) != 0 {
                    self.add_root(2, &map, br, g, valid, scale, sums);
                }
            }
            if let Some(gl) = glint {
                self.add_glint(&gl, br, m, sums);
            }
        }
        irregular
    }

    /// `glint_geometry` and the fade of `add_trt_with_glints` on the lanes; the second value
    /// flags lanes whose `φ_c` the two-branch wrap does not cover.
    #[inline(always)]
    fn glint_geometry<V: Lane>(
        &self,
        map: &Cubic<V>,
        eta_p: V,
        gc: V,
        has_caustic: V,
        phi: V,
    ) -> (GlintLanes<V>, u32) {
        let below = eta_p.cmp_lt(V::splat(2.0)) & has_caustic;
        let (phi_c, bad_wrap) = wrap(map.value(gc));
        let phi_c = keep(below, phi_c.abs());
        let (sin_gc, cos_gc) = gc.sin_cos();
        let d2 = (map.a * gc * 6.0 / (cos_gc * cos_gc)).abs();
        let glint = &self.prepared.glint;
        let (w_c, dhm) = (glint.w_c, glint.delta_h_m);
        let narrow = V::splat(8.0 * w_c).cmp_lt(d2 * (dhm * dhm));
        let delta_h_caustic = narrow.blend((V::splat(w_c * 2.0) / d2).sqrt() * 2.0, V::splat(dhm));
        // Past the merge: t = 1 − smoothstep(2, 2 + Δη', η').
        let upper = glint.delta_eta_prime + 2.0;
        let u = (eta_p - 2.0) / (upper - 2.0);
        let smooth = u.cmp_le(V::ZERO).blend(
            V::ZERO,
            u.cmp_ge(V::ONE).blend(V::ONE, u * u * (-(u * 2.0) + 3.0)),
        );
        let t = below.blend(V::ONE, -smooth + 1.0);
        let (dm, bad_m) = wrap(-phi_c + phi);
        let (dp, bad_p) = wrap(phi_c + phi);
        let (g_m, g_p) = (bump(dm, glint.inv_w_c), bump(dp, glint.inv_w_c));
        let fade = (-(t * g_m) + 1.0) * (-(t * g_p) + 1.0);
        let bad = bits((below & bad_wrap) | bad_m | bad_p);
        (
            GlintLanes {
                t,
                h_c: keep(below, sin_gc),
                cos_gc: below.blend(cos_gc, V::ONE),
                delta_h: below.blend(delta_h_caustic, V::splat(dhm)),
                g_sum: g_m + g_p,
                fade,
            },
            bad,
        )
    }

    /// The glint lobes `t·k_G·A(2, h_c)·Δh·(g(φ−φ_c) + g(φ+φ_c))` times `m`.
    #[inline(always)]
    fn add_glint<V: Lane>(&self, gl: &GlintLanes<V>, br: BravaisLanes<V>, m: V, sums: &mut [V]) {
        let on = gl.t.cmp_ne(V::ZERO);
        if bits(on) == 0 {
            return;
        }
        let glint = &self.prepared.glint;
        let lobes = gl.g_sum * glint.inv_w_c * INV_SQRT_TAU;
        let weight = gl.t * glint.k_g * gl.delta_h * lobes * m;
        self.add_through_fiber(2, br, gl.h_c, gl.cos_gc, weight, on, sums);
    }
}

/// The TRT glint on the lanes.
struct GlintLanes<V> {
    t: V,
    h_c: V,
    cos_gc: V,
    delta_h: V,
    /// `G(φ−φ_c) + G(φ+φ_c)`.
    g_sum: V,
    /// `(1 − tG(φ−φ_c))(1 − tG(φ+φ_c))`.
    fade: V,
}

#[cfg(test)]
mod tests {
    use super::*;

    /// xorshift64 in [0, 1).
    fn uniform(state: &mut u64) -> f64 {
        *state ^= *state << 13;
        *state ^= *state >> 7;
        *state ^= *state << 17;
        (*state >> 11) as f64 / (1u64 << 53) as f64
    }

    /// The lanes' `wrap` gives `angles::wrap`'s bits wherever it does not hand the lane back,
    /// and hands back only |x| ≥ 4π and −2π itself.
    #[test]
    fn wrap_gives_the_scalar_bits() {
        let mut state = 0x2545_F491_4F6C_DD1D;
        let mut xs: Vec<f64> = (0..40_000)
            .map(|_| (uniform(&mut state) - 0.5) * 9.0 * PI)
            .collect();
        for edge in [-2.0 * TAU, -TAU, -PI, 0.0, PI, TAU, 2.0 * TAU] {
            xs.extend([edge, edge.next_up(), edge.next_down()]);
        }
        xs.extend([-0.0, 0.0]);
        for c in xs.chunks(4) {
            let lanes: [f64; 4] = std::array::from_fn(|l| *c.get(l).unwrap_or(&c[0]));
            let (y, far) = wrap(f64x4::new(lanes));
            let (y, far) = (y.to_array(), far.to_array());
            for l in 0..4 {
                let x = lanes[l];
                let handed_back = far[l].to_bits() != 0;
                assert_eq!(handed_back, x.abs() >= 2.0 * TAU || x == -TAU, "{x}");
                if !handed_back {
                    assert_eq!(
                        y[l].to_bits(),
                        super::super::angles::wrap(x).to_bits(),
                        "{x}"
                    );
                }
            }
        }
    }

    /// The fast path is the common path: on random directions with typical parameters (all
    /// effects) fewer than 1% of the samples go to the scalar model. (Agreement with the scalar
    /// model is tested in tests/model_lanes.rs; this catches a fast path that silently hands
    /// everything back, which would stay correct but lose the speed.)
    #[test]
    fn few_samples_leave_the_fast_path() {
        // The demo's parameters: mid-range values, three channels.
        let params = crate::demo::demo_truth();
        let mut state = 0x9E37_79B9_7F4A_7C15;
        let mut u = |lo: f64, hi: f64| lo + (hi - lo) * uniform(&mut state);
        let angles: Vec<Angles> = (0..20_000)
            .map(|_| {
                Angles::from_degrees(
                    u(-85.0, 85.0),
                    u(-360.0, 360.0),
                    u(-85.0, 85.0),
                    u(-360.0, 360.0),
                )
            })
            .collect();
        let config = ModelConfig::default();
        let prepared = Prepared::new(&params);
        let lanes = Lanes {
            params: &params,
            prepared: &prepared,
            config: &config,
        };
        let mut sums = vec![f64x4::ZERO; 3];
        let fell_back: u32 = angles
            .chunks_exact(f64x4::LANES)
            .map(|g| lanes.group(g, &mut sums).count_ones())
            .sum();
        assert!(
            (fell_back as usize) * 100 < angles.len(),
            "{fell_back} of {} samples left the fast path",
            angles.len()
        );
    }
}

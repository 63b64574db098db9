//! The path sampler: one ray of the collimated beam through the fibre, its weight split at every
//! interface (the escaping part tallied, the rest followed; no Russian roulette), absorbed along
//! the true 3-D path, and what is still inside after the last segment kept apart.

use rand_chacha::rand_core::RngCore;

mod entry;
mod facet;
mod kernel;
mod lane_math;

pub use self::kernel::Kernel;

/// One call of [`Sampler::trace_batch_on`], what a [`kernel`] compiles and runs.
struct Batch<'a, R, E> {
    sampler: &'a Sampler,
    omega_i: V3,
    n: u64,
    rng: &'a mut R,
    balance: &'a mut Balance,
    exit: &'a mut E,
}

impl<R: RngCore, E: Exits> kernel::Body for Batch<'_, R, E> {
    fn channels(&self) -> usize {
        self.sampler.nc
    }
    #[inline(always)]
    fn run<const NC: usize>(self) {
        self.sampler
            .trace_batch_body::<NC>(self.omega_i, self.n, self.rng, self.balance, self.exit)
    }
}

use self::lane_math::{exp_lane, fresnel_lane};
use super::fiber::Fiber;
use super::optics::{dot, reflect, V3};
use super::section::Section;
use crate::synth::random::uniform;

/// Most colour channels a traced fibre may have.
pub const MAX_CHANNELS: usize = 8;
/// Path orders tallied apart: R, TT, TRT, and every higher order together.
pub const ORDERS: usize = 4;
/// A path whose largest channel weight falls below this is stopped and its weight counted
/// as still inside (it could add at most this much per ray to any tally).
pub const WEIGHT_CUTOFF: f64 = 1e-6;
/// Tries at drawing a rough normal the ray can see before falling back to the tilted one.
const NORMAL_TRIES: u32 = 64;

/// Per-channel weights.
pub type Weights = [f64; MAX_CHANNELS];

/// What receives a path's escaping parts: `exit(order, direction, weights)`, from a kernel for
/// `NC` channels (0: any number). Any closure of that shape is one; `trace::run`'s tally
/// implements it with an `#[inline(always)]` method, so the detector is compiled into each
/// [`kernel`] instead of being called from it.
pub trait Exits {
    fn exit<const NC: usize>(&mut self, order: usize, d: V3, w: &Weights);
}

impl<F: FnMut(usize, V3, &Weights)> Exits for F {
    #[inline(always)]
    fn exit<const NC: usize>(&mut self, order: usize, d: V3, w: &Weights) {
        self(order, d, w)
    }
}

/// Where the incident power went (per channel, in units of rays), and the approximations taken.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Balance {
    pub tallied: [Weights; ORDERS],
    pub absorbed: Weights,
    pub inside: Weights,
    /// Rays that missed the section by rounding at its very edge (tallied as grazing R).
    pub grazing: u64,
    /// Reflected or refracted directions that pointed back through the geometric surface and
    /// were mirrored across its tangent plane (no shadowing or masking is modelled).
    pub mirrored: u64,
    /// Interfaces where no perturbed normal faced the ray and the tilted (or geometric) normal
    /// was used.
    pub fallbacks: u64,
}

impl Balance {
    pub fn add(&mut self, o: &Balance) {
        for (a, b) in self.tallied.iter_mut().zip(&o.tallied) {
            add_w(a, b);
        }
        add_w(&mut self.absorbed, &o.absorbed);
        add_w(&mut self.inside, &o.inside);
        self.grazing += o.grazing;
        self.mirrored += o.mirrored;
        self.fallbacks += o.fallbacks;
    }
}

/// `a += b` over the first `nc` channels (the rest are 0 in every weight the sampler makes).
#[inline]
fn add_n(a: &mut Weights, b: &Weights, nc: usize) {
    for (x, y) in a[..nc].iter_mut().zip(&b[..nc]) {
        *x += y;
    }
}

/// `w · f` over the first `nc` channels, 0 in the rest. Not a copy of all of `w` scaled in
/// place: that read 64 bytes just after scalar stores to them, which cannot be forwarded.
#[inline(always)]
fn scaled(w: &Weights, nc: usize, f: f64) -> Weights {
    let mut out: Weights = [0.0; MAX_CHANNELS];
    for (o, x) in out[..nc].iter_mut().zip(&w[..nc]) {
        *o = x * f;
    }
    out
}

fn add_w(a: &mut Weights, b: &Weights) {
    for (x, y) in a.iter_mut().zip(b) {
        *x += y;
    }
}

/// The fibre prepared for sampling.
#[derive(Debug, Clone)]
pub struct Sampler {
    fiber: Fiber,
    nc: usize,
    /// tan α, tan β, tan β_φ and whether either roughness is on.
    slope: f64,
    slope_sd: f64,
    slope_sd_az: f64,
    rough: bool,
}

impl Sampler {
    /// `fiber` must be valid and have at most [`MAX_CHANNELS`] channels.
    pub fn new(fiber: &Fiber) -> Sampler {
        assert!(fiber.sigma_a.len() <= MAX_CHANNELS);
        Sampler {
            nc: fiber.sigma_a.len(),
            fiber: fiber.clone(),
            slope: fiber.tilt.tan(),
            slope_sd: fiber.roughness.tan(),
            slope_sd_az: fiber.azimuthal_roughness.tan(),
            rough: fiber.roughness > 0.0 || fiber.azimuthal_roughness > 0.0,
        }
    }

    pub fn n_channels(&self) -> usize {
        self.nc
    }

    /// The section every ray meets, when the fibre has one rotation (or is round).
    #[inline]
    fn fixed_section(&self) -> Option<Section> {
        match self.fiber.rotation {
            Some(psi) => Some(Section::new(self.fiber.eccentricity, psi)),
            None if self.fiber.eccentricity == 1.0 => Some(Section::new(1.0, 0.0)),
            None => None,
        }
    }

    /// Draw one ray of the beam from `omega_i`: the section it meets (`fixed`, the
    /// [`fixed_section`](Self::fixed_section) computed once per run, or else a rotation weighted
    /// by the width it presents) and its offset `h` ∈ [−1, 1].
    #[inline(always)]
    fn draw_ray(
        &self,
        fixed: Option<Section>,
        omega_i: V3,
        rng: &mut impl RngCore,
    ) -> (Section, f64) {
        let section = match fixed {
            Some(s) => s,
            // Orientations weighted by the width they present: a uniform beam on a random
            // fibre meets a wide one more often (the major half-width, 1, bounds it).
            None => {
                let dir = beam_dir(omega_i);
                loop {
                    let s =
                        Section::new(self.fiber.eccentricity, std::f64::consts::PI * uniform(rng));
                    if uniform(rng) < s.half_width(dir) {
                        break s;
                    }
                }
            }
        };
        let h = 2.0 * uniform(rng) - 1.0;
        (section, h)
    }

    /// Trace one ray arriving from direction `omega_i` (unit, toward the light): its rotation
    /// and its offset uniform over the projected width are drawn from `rng`.
    pub fn trace(
        &self,
        omega_i: V3,
        rng: &mut impl RngCore,
        balance: &mut Balance,
        exit: &mut impl FnMut(usize, V3, &Weights),
    ) {
        let (section, h) = self.draw_ray(self.fixed_section(), omega_i, rng);
        self.trace_at(&section, omega_i, h, rng, balance, exit);
    }

    /// Trace `n` rays from `omega_i` as [`trace`](Self::trace) draws them, [`LANES`] at a
    /// time: the same paths and estimator, but the draws of different rays interleave in
    /// `rng`'s stream (deterministically: the lanes advance in a fixed order). `exit` is any
    /// [`Exits`]: a closure (its arguments' types written out) or `trace::run`'s tally.
    pub fn trace_batch(
        &self,
        omega_i: V3,
        n: u64,
        rng: &mut impl RngCore,
        balance: &mut Balance,
        exit: &mut impl Exits,
    ) {
        self.trace_batch_on(Kernel::best(), omega_i, n, rng, balance, exit);
    }

    /// [`trace_batch`](Self::trace_batch) compiled for `kernel` (the best this CPU runs if it
    /// runs not that one): every kernel gives the same bits.
    pub fn trace_batch_on(
        &self,
        kernel: Kernel,
        omega_i: V3,
        n: u64,
        rng: &mut impl RngCore,
        balance: &mut Balance,
        exit: &mut impl Exits,
    ) {
        let batch = Batch {
            sampler: self,
            omega_i,
            n,
            rng,
            balance,
            exit,
        };
        kernel::run(kernel, batch);
    }

    /// [`trace_batch`](Self::trace_batch)'s body, inlined into each kernel of [`kernel`], for
    /// `NC` channels (0: any number, read from the fibre).
    #[inline(always)]
    fn trace_batch_body<const NC: usize>(
        &self,
        omega_i: V3,
        n: u64,
        rng: &mut impl RngCore,
        balance: &mut Balance,
        exit: &mut impl Exits,
    ) {
        let mut left = n;
        let dir = beam_dir(omega_i);
        // One section for every ray: it and its half-width once, not per ray.
        let fixed = self.fixed_section();
        let fixed_hw = fixed.map(|s| s.half_width(dir));
        self.trace_lanes::<NC, _>(
            omega_i,
            &mut |rng| {
                (left > 0).then(|| {
                    left -= 1;
                    let (section, h) = self.draw_ray(fixed, omega_i, rng);
                    let hw = fixed_hw.unwrap_or_else(|| section.half_width(dir));
                    (section, h * hw)
                })
            },
            rng,
            balance,
            exit,
        );
    }

    /// Trace the ray from `omega_i` that meets `section` at offset `h` ∈ [−1, 1] of its
    /// half-width (h > 0 enters on the side that R sends toward negative azimuths, h = sin γ_i
    /// of docs/model.md for a round fibre). `exit(order, direction, weights)` receives every
    /// escaping part.
    pub fn trace_at(
        &self,
        section: &Section,
        omega_i: V3,
        h: f64,
        rng: &mut impl RngCore,
        balance: &mut Balance,
        exit: &mut impl FnMut(usize, V3, &Weights),
    ) {
        let mut one = Some((*section, h * section.half_width(beam_dir(omega_i))));
        self.trace_lanes::<0, _>(omega_i, &mut |_| one.take(), rng, balance, exit);
    }

    /// The rays `source` gives (their section and offset from the axis, drawn from the
    /// generator it is passed, or not), entered [`LANES`] at a time ([`entry`]) and followed
    /// [`LANES`] at a time in lock step: a lane that finishes takes the next entered ray, in
    /// lane order. The arithmetic of one internal interface runs over all lanes in loops without
    /// branches (independent rays: the divisions, square roots and the Fresnel terms of
    /// different lanes overlap, and the compiler vectorises them); the draws, the exits and
    /// the bookkeeping run lane by lane.
    #[inline(always)]
    fn trace_lanes<const NC: usize, R: RngCore>(
        &self,
        omega_i: V3,
        source: &mut impl FnMut(&mut R) -> Option<(Section, f64)>,
        rng: &mut R,
        balance: &mut Balance,
        exit: &mut impl Exits,
    ) {
        let nc = self.channels::<NC>();
        let eta = self.fiber.eta;
        let sigma_a = &self.fiber.sigma_a[..nc];
        let max_seg = self.fiber.max_segments as usize;
        let mut lanes = Lanes::default();
        let mut queue = entry::Entries::default();
        let mut exhausted = false;
        let dir = beam_dir(omega_i);
        loop {
            // Refill, in lane order, from rays entered LANES at a time.
            let mut any = false;
            for k in 0..LANES {
                if !lanes.active[k] {
                    while queue.is_empty() && !exhausted {
                        exhausted = self.enter_batch::<NC, R>(
                            &mut queue, source, omega_i, dir, rng, balance, exit,
                        );
                    }
                    if !queue.is_empty() {
                        queue.pop_into(&mut lanes, k, nc);
                    }
                }
                any |= lanes.active[k];
            }
            if !any {
                break;
            }
            let l = &mut lanes;
            // The chord to the boundary's other side (the quadratic's second root, its first
            // is 0), the point there and the geometric normal, all lanes.
            for k in 0..LANES {
                let (c, s, ia2) = (l.c[k], l.s[k], l.ia2[k]);
                let (px, py) = (
                    c * l.hit.pv[k] + s * l.hit.pw[k],
                    c * l.hit.pw[k] - s * l.hit.pv[k],
                );
                let (dx, dy) = (c * l.dv[k] + s * l.dw[k], c * l.dw[k] - s * l.dv[k]);
                let qa = dx * dx + dy * dy * ia2;
                let qb = 2.0 * (px * dx + py * dy * ia2);
                let t = -qb / qa;
                // Along the axis (no chord): it never leaves.
                let ok = qa > 0.0 && t.is_finite() && t > 0.0;
                l.ok[k] = ok;
                let t = if ok { t } else { 0.0 };
                l.len[k] = t;
                let (pv, pw) = (l.hit.pv[k] + t * l.dv[k], l.hit.pw[k] + t * l.dw[k]);
                l.hit.pv[k] = pv;
                l.hit.pw[k] = pw;
                let g0 = c * pv + s * pw;
                let g1 = (c * pw - s * pv) * ia2;
                let inv = 1.0 / (g0 * g0 + g1 * g1).sqrt();
                let (g0, g1) = (g0 * inv, g1 * inv);
                let (nv, nw) = (c * g0 - s * g1, s * g0 + c * g1);
                l.hit.nv[k] = nv;
                l.hit.nw[k] = nw;
                // The facet draw's setup (square root, division) here, where lanes overlap.
                let dn = l.dv[k] * nv + l.dw[k] * nw;
                l.hit.dn[k] = dn;
                l.hit.dt[k] = l.dw[k] * nv - l.dv[k] * nw;
                let (a, b, root) = self.tangent_terms(l.du[k], dn);
                l.hit.a[k] = a;
                l.hit.lambda[k] = Self::tangent_lambda(a, b, root);
            }
            // The attenuation along the chord, every channel and lane (vectorised exp).
            for (att, &sigma_a) in l.att.iter_mut().zip(sigma_a) {
                for (att, &len) in att.iter_mut().zip(&l.len) {
                    *att = exp_lane(-sigma_a * len);
                }
            }
            // Absorption and the facet's slopes, lane by lane.
            for k in 0..LANES {
                if !l.active[k] {
                    continue;
                }
                if !l.ok[k] {
                    l.active[k] = false;
                    add_n(&mut balance.inside, &l.w[k], nc);
                    continue;
                }
                for (c, (w, absorbed)) in l.w[k][..nc]
                    .iter_mut()
                    .zip(balance.absorbed.iter_mut())
                    .enumerate()
                {
                    let kept = *w * l.att[c][k];
                    *absorbed += *w - kept;
                    *w = kept;
                }
                (l.hit.sl[k], l.hit.sa[k]) = self.slopes(
                    l.hit.a[k],
                    l.hit.lambda[k],
                    l.du[k],
                    l.hit.dn[k],
                    l.hit.dt[k],
                    rng,
                    balance,
                );
            }
            // Fresnel from inside, the refracted and the reflected directions, all lanes.
            for k in 0..LANES {
                let d = [l.du[k], l.dv[k], l.dw[k]];
                let m = facet([0.0, l.hit.nv[k], l.hit.nw[k]], l.hit.sl[k], l.hit.sa[k]);
                let cos_i = dot(d, m);
                let (f, cos_t) = fresnel_lane(cos_i, eta);
                l.hit.f[k] = f;
                // refract(d, −m, η, cos_i, cos_t) and reflect(d, m), written out.
                let a = eta * cos_i - cos_t;
                for j in 0..3 {
                    l.out[j][k] = d[j] * eta - m[j] * a;
                    l.hit.refl[j][k] = d[j] - 2.0 * cos_i * m[j];
                }
            }
            // Exits and the next segment, lane by lane.
            for k in 0..LANES {
                if !l.active[k] {
                    continue;
                }
                let ng = [0.0, l.hit.nv[k], l.hit.nw[k]];
                let f = l.hit.f[k];
                let seg = l.seg[k];
                if f < 1.0 {
                    let out = [l.out[0][k], l.out[1][k], l.out[2][k]];
                    let out = keep_side(out, ng, true, balance);
                    let we = scaled(&l.w[k], nc, 1.0 - f);
                    add_n(&mut balance.tallied[seg.min(ORDERS - 1)], &we, nc);
                    exit.exit::<NC>(seg, out, &we);
                    l.w[k][..nc].iter_mut().for_each(|x| *x *= f);
                }
                let r = [l.hit.refl[0][k], l.hit.refl[1][k], l.hit.refl[2][k]];
                let d = keep_side(r, ng, false, balance);
                [l.du[k], l.dv[k], l.dw[k]] = d;
                if seg >= max_seg || l.w[k][..nc].iter().all(|&x| x < WEIGHT_CUTOFF) {
                    l.active[k] = false;
                    add_n(&mut balance.inside, &l.w[k], nc);
                }
                l.seg[k] = seg + 1;
            }
        }
    }

    /// The fibre's channels, `NC` when that is not 0: a constant lets the compiler unroll the
    /// loops over channels (with 1 channel, masked AVX-512 loads of a just stored weight cost
    /// ~10% of the time, their stores cannot be forwarded).
    #[inline(always)]
    fn channels<const NC: usize>(&self) -> usize {
        debug_assert!(NC == 0 || NC == self.nc);
        if NC == 0 {
            self.nc
        } else {
            NC
        }
    }

    /// Weight 1 in every channel the fibre has. Built by selects, not a fill of the first
    /// channels: the lane copies it whole at once, which a few scalar stores could not forward.
    #[inline(always)]
    fn unit_weights<const NC: usize>(&self) -> Weights {
        let nc = self.channels::<NC>();
        std::array::from_fn(|c| if c < nc { 1.0 } else { 0.0 })
    }
}

/// The beam's unit in-plane direction of travel (−ω_i's (v, w) part, normalised); once per
/// incidence, not per ray (`hypot` is a libm call).
fn beam_dir(omega_i: V3) -> [f64; 2] {
    let len = omega_i[1].hypot(omega_i[2]);
    [-omega_i[1] / len, -omega_i[2] / len]
}

/// Rays traced at once by [`Sampler::trace_batch`]: four AVX-512 registers per quantity, so a
/// step's chain of divisions, square roots and `exp` runs as four independent chains that
/// overlap (docs/trace.md, Speed).
pub const LANES: usize = 32;

/// The state of [`LANES`] rays inside the fibre, one array per quantity (the lanes' loops
/// vectorise over them). An inactive lane's values are stale and never read as results.
#[derive(Default)]
struct Lanes {
    active: [bool; LANES],
    /// The lane's section: cos ψ, sin ψ, 1/a².
    c: [f64; LANES],
    s: [f64; LANES],
    ia2: [f64; LANES],
    /// Direction, weights, the segment being followed.
    du: [f64; LANES],
    dv: [f64; LANES],
    dw: [f64; LANES],
    w: [Weights; LANES],
    seg: [usize; LANES],
    /// Per step: chord found, its length, the attenuation along it per channel, the refracted
    /// direction.
    ok: [bool; LANES],
    len: [f64; LANES],
    att: [[f64; LANES]; MAX_CHANNELS],
    out: [[f64; LANES]; 3],
    /// Where each ray meets the boundary and what its facet does there.
    hit: Hits,
}

/// Where [`LANES`] rays meet the boundary and what their facets do there, for the rays inside
/// ([`Lanes`]) and those entering (`entry::Entries`) alike: the point, the geometric normal,
/// the ray's components along ng and u × ng, the facet draw's `(A, λ)`, the slopes drawn, the
/// reflectance and R's direction.
#[derive(Default)]
struct Hits {
    pv: [f64; LANES],
    pw: [f64; LANES],
    nv: [f64; LANES],
    nw: [f64; LANES],
    dn: [f64; LANES],
    dt: [f64; LANES],
    a: [f64; LANES],
    lambda: [f64; LANES],
    sl: [f64; LANES],
    sa: [f64; LANES],
    f: [f64; LANES],
    refl: [[f64; LANES]; 3],
}

/// The unit facet normal `ng + s_l·u + s_a·(u × ng)` normalised (`ng` unit with no axial part):
/// tilted toward the tip by atan(s_l / √(1 + s_a²)) and turned about the axis by atan(s_a).
#[inline]
pub fn facet(ng: V3, s_l: f64, s_a: f64) -> V3 {
    let k = 1.0 / (1.0 + s_l * s_l + s_a * s_a).sqrt();
    [
        s_l * k,
        (ng[1] - s_a * ng[2]) * k,
        (ng[2] + s_a * ng[1]) * k,
    ]
}

/// `d` on the side of the geometric surface it should leave toward (`out`: along `ng`),
/// mirrored across the tangent plane when a tilted or rough normal turned it back.
#[inline]
fn keep_side(d: V3, ng: V3, out: bool, balance: &mut Balance) -> V3 {
    let c = dot(d, ng);
    if (c < 0.0) == out && c != 0.0 {
        balance.mirrored += 1;
        reflect(d, ng)
    } else {
        d
    }
}

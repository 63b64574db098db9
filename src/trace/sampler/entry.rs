//! The entry of new rays, [`LANES`] at a time: their offsets drawn first, then the point where
//! each meets the surface, its normal and the facet draw's setup in one branch-free loop over
//! all of them (square roots and divisions a vector at a time, where one ray's were a serial
//! chain), their facets drawn in ray order, then Fresnel from outside, the reflected and the
//! refracted directions in another such loop; R's exits are tallied in ray order. The entered
//! rays wait in [`Entries`] until a lane is free.

use rand_chacha::rand_core::RngCore;

use super::lane_math::fresnel_in_lane;
use super::{add_n, facet, Balance, Exits, Hits, Lanes, Sampler, Weights, LANES};
use crate::trace::optics::V3;
use crate::trace::section::Section;

/// Up to [`LANES`] rays that met the surface, one array per quantity: slots `next..len` wait
/// for a lane (those with `ok` false missed and were tallied as grazing R).
#[derive(Default)]
pub(super) struct Entries {
    len: usize,
    next: usize,
    /// The ray's section (cos ψ, sin ψ, 1/a²) and offset from the axis across the beam.
    c: [f64; LANES],
    s: [f64; LANES],
    ia2: [f64; LANES],
    offset: [f64; LANES],
    /// Met the surface (not a grazing miss).
    ok: [bool; LANES],
    /// The point on the boundary, the geometric normal, the facet draw and R's direction.
    hit: Hits,
    /// The refracted direction, and whether R's and it were mirrored.
    refr: [[f64; LANES]; 3],
    mirror_r: [bool; LANES],
    mirror_t: [bool; LANES],
}

impl Entries {
    /// Whether no entered ray waits.
    #[inline(always)]
    pub(super) fn is_empty(&mut self) -> bool {
        while self.next < self.len && !self.ok[self.next] {
            self.next += 1;
        }
        self.next == self.len
    }

    /// The next entered ray into lane `k` with weight `1 − F` in each of `nc` channels.
    #[inline(always)]
    pub(super) fn pop_into(&mut self, l: &mut Lanes, k: usize, nc: usize) {
        let j = self.next;
        self.next += 1;
        l.active[k] = true;
        l.c[k] = self.c[j];
        l.s[k] = self.s[j];
        l.ia2[k] = self.ia2[j];
        l.hit.pv[k] = self.hit.pv[j];
        l.hit.pw[k] = self.hit.pw[j];
        [l.du[k], l.dv[k], l.dw[k]] = [self.refr[0][j], self.refr[1][j], self.refr[2][j]];
        let t = 1.0 - self.hit.f[j];
        l.w[k] = std::array::from_fn(|c| if c < nc { t } else { 0.0 });
        l.seg[k] = 1;
    }
}

impl Sampler {
    /// Refill the empty `q` with up to [`LANES`] rays `source` gives, entered: R tallied and
    /// `exit`ed, the rest refracted in. Returns whether `source` ran out.
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn enter_batch<const NC: usize, R: RngCore>(
        &self,
        q: &mut Entries,
        source: &mut impl FnMut(&mut R) -> Option<(Section, f64)>,
        omega_i: V3,
        dir: [f64; 2],
        rng: &mut R,
        balance: &mut Balance,
        exit: &mut impl Exits,
    ) -> bool {
        let mut exhausted = false;
        q.len = 0;
        q.next = 0;
        // The offsets first, in ray order.
        while q.len < LANES {
            let Some((section, offset)) = source(rng) else {
                exhausted = true;
                break;
            };
            let j = q.len;
            (q.c[j], q.s[j], q.ia2[j], q.offset[j]) = (section.c, section.s, section.ia2, offset);
            q.len += 1;
        }
        self.entry_points(q, omega_i, dir);
        // The facets, in ray order; a grazing miss leaves as R.
        let nc = self.channels::<NC>();
        let d = [-omega_i[0], -omega_i[1], -omega_i[2]];
        for j in 0..q.len {
            if q.ok[j] {
                (q.hit.sl[j], q.hit.sa[j]) = self.slopes(
                    q.hit.a[j],
                    q.hit.lambda[j],
                    -d[0],
                    q.hit.dn[j],
                    q.hit.dt[j],
                    rng,
                    balance,
                );
            } else {
                let w = self.unit_weights::<NC>();
                balance.grazing += 1;
                add_n(&mut balance.tallied[0], &w, nc);
                exit.exit::<NC>(0, [-omega_i[0], -omega_i[1], -omega_i[2]], &w);
            }
        }
        self.entry_optics(q, d);
        // R's exits, in ray order.
        for j in 0..q.len {
            if !q.ok[j] {
                continue;
            }
            let f = q.hit.f[j];
            let wr: Weights = std::array::from_fn(|c| if c < nc { f } else { 0.0 });
            add_n(&mut balance.tallied[0], &wr, nc);
            exit.exit::<NC>(
                0,
                [q.hit.refl[0][j], q.hit.refl[1][j], q.hit.refl[2][j]],
                &wr,
            );
            balance.mirrored += u64::from(q.mirror_r[j]) + u64::from(q.mirror_t[j]);
        }
        exhausted
    }

    /// Every slot's meeting point with its section (`Section::entry`'s nearer root of the
    /// line–ellipse quadratic, without cancellation), the geometric normal there, and the facet
    /// draw's inputs for the ray seen from outside: all slots in one branch-free loop (a slot
    /// past `q.len` computes stale values no one reads).
    #[inline(always)]
    fn entry_points(&self, q: &mut Entries, omega_i: V3, dir: [f64; 2]) {
        let d = [-omega_i[0], -omega_i[1], -omega_i[2]];
        for j in 0..LANES {
            let (c, s, ia2, off) = (q.c[j], q.s[j], q.ia2[j], q.offset[j]);
            // From 3 half-widths before the axis, across the beam by the offset.
            let (p0v, p0w) = (-off * dir[1] - 3.0 * dir[0], off * dir[0] - 3.0 * dir[1]);
            let (px, py) = (c * p0v + s * p0w, c * p0w - s * p0v);
            let (dx, dy) = (c * d[1] + s * d[2], c * d[2] - s * d[1]);
            let qa = dx * dx + dy * dy * ia2;
            let qb = 2.0 * (px * dx + py * dy * ia2);
            let qc = px * px + py * py * ia2 - 1.0;
            let disc = qb * qb - 4.0 * qa * qc;
            let t = qc / (-0.5 * (qb - disc.max(0.0).sqrt()));
            let ok = disc > 0.0 && qa > 0.0 && t.is_finite() && t > 0.0;
            q.ok[j] = ok;
            let t = if ok { t } else { 0.0 };
            let (pv, pw) = (p0v + t * d[1], p0w + t * d[2]);
            q.hit.pv[j] = pv;
            q.hit.pw[j] = pw;
            let g0 = c * pv + s * pw;
            let g1 = (c * pw - s * pv) * ia2;
            let inv = 1.0 / (g0 * g0 + g1 * g1).sqrt();
            let (g0, g1) = (g0 * inv, g1 * inv);
            let (nv, nw) = (c * g0 - s * g1, s * g0 + c * g1);
            q.hit.nv[j] = nv;
            q.hit.nw[j] = nw;
            // shading_normal's components for a ray from outside: −d·u, −d·ng, −d·(u × ng).
            let dn = -(d[1] * nv + d[2] * nw);
            q.hit.dn[j] = dn;
            q.hit.dt[j] = -(d[2] * nv - d[1] * nw);
            (q.hit.a[j], q.hit.lambda[j]) = self.tangent(-d[0], dn);
        }
    }

    /// Every slot's facet, Fresnel from outside, R's direction and the refracted one (each kept
    /// on its side of the geometric surface), in one branch-free loop.
    #[inline(always)]
    fn entry_optics(&self, q: &mut Entries, d: V3) {
        let eta = self.fiber.eta;
        for j in 0..LANES {
            let ng = [0.0, q.hit.nv[j], q.hit.nw[j]];
            let m = facet(ng, q.hit.sl[j], q.hit.sa[j]);
            let cos_i = -(d[0] * m[0] + d[1] * m[1] + d[2] * m[2]);
            let (f, cos_t) = fresnel_in_lane(cos_i, eta);
            q.hit.f[j] = f;
            // reflect(d, m) and refract(d, m, 1/η, cos_i, cos_t), written out.
            let e = 1.0 / eta;
            let a = e * cos_i - cos_t;
            let r: V3 = std::array::from_fn(|i| d[i] + 2.0 * cos_i * m[i]);
            let t: V3 = std::array::from_fn(|i| d[i] * e + m[i] * a);
            let (r, mr) = side_lane(r, ng, true);
            let (t, mt) = side_lane(t, ng, false);
            for i in 0..3 {
                q.hit.refl[i][j] = r[i];
                q.refr[i][j] = t[i];
            }
            q.mirror_r[j] = mr;
            q.mirror_t[j] = mt;
        }
    }
}

/// [`keep_side`](super::keep_side) without a branch or a counter: `d`, mirrored across the
/// tangent plane when it points to the wrong side, and whether it was.
#[inline(always)]
fn side_lane(d: V3, ng: V3, out: bool) -> (V3, bool) {
    let c = d[0] * ng[0] + d[1] * ng[1] + d[2] * ng[2];
    let flip = (c < 0.0) == out && c != 0.0;
    let k = if flip { -2.0 * c } else { 0.0 };
    (std::array::from_fn(|i| d[i] + k * ng[i]), flip)
}

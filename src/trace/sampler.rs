//! The path sampler: one ray of the collimated beam through the fibre, its weight split at every
//! interface (the escaping part tallied, the rest followed; no Russian roulette), absorbed along
//! the true 3-D path, and what is still inside after the last segment kept apart.

use rand_chacha::rand_core::RngCore;

use super::fiber::Fiber;
use super::normal::normal;
use super::optics::{dot, fresnel, reflect, refract, V3};
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

    /// Trace one ray arriving from direction `omega_i` (unit, toward the light): its rotation
    /// and its offset uniform over the projected width are drawn from `rng`.
    pub fn trace(
        &self,
        omega_i: V3,
        rng: &mut impl RngCore,
        balance: &mut Balance,
        exit: &mut impl FnMut(usize, V3, &Weights),
    ) {
        let d = [-omega_i[0], -omega_i[1], -omega_i[2]];
        let len = d[1].hypot(d[2]);
        let dir = [d[1] / len, d[2] / len];
        let section = match self.fiber.rotation {
            Some(psi) => Section::new(self.fiber.eccentricity, psi),
            None if self.fiber.eccentricity == 1.0 => Section::new(1.0, 0.0),
            // Orientations weighted by the width they present: a uniform beam on a random
            // fibre meets a wide one more often (the major half-width, 1, bounds it).
            None => loop {
                let s = Section::new(self.fiber.eccentricity, std::f64::consts::PI * uniform(rng));
                if uniform(rng) < s.half_width(dir) {
                    break s;
                }
            },
        };
        let h = 2.0 * uniform(rng) - 1.0;
        self.trace_at(&section, omega_i, h, rng, balance, exit);
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
        let nc = self.nc;
        let eta = self.fiber.eta;
        let mut d = [-omega_i[0], -omega_i[1], -omega_i[2]];
        let len = d[1].hypot(d[2]);
        let dir = [d[1] / len, d[2] / len];
        let offset = h * section.half_width(dir);
        let p0 = [
            -offset * dir[1] - 3.0 * dir[0],
            offset * dir[0] - 3.0 * dir[1],
        ];
        let mut w: Weights = [0.0; MAX_CHANNELS];
        w[..nc].fill(1.0);
        let Some(t) = section.entry(p0, [d[1], d[2]]) else {
            // Rounding at the very edge: a grazing hit, where the reflectance is 1.
            balance.grazing += 1;
            add_w(&mut balance.tallied[0], &w);
            exit(0, d, &w);
            return;
        };
        let mut p = [p0[0] + t * d[1], p0[1] + t * d[2]];
        let ng = self.geometric_normal(section, p);
        let m = self.shading_normal(ng, d, true, rng, balance);
        let cos_i = -dot(d, m);
        let (f, cos_t) = fresnel(cos_i, 1.0, eta);
        let r = keep_side(reflect(d, m), ng, true, balance);
        let mut wr = w;
        wr[..nc].iter_mut().for_each(|x| *x *= f);
        add_w(&mut balance.tallied[0], &wr);
        exit(0, r, &wr);
        // From outside the reflectance is below 1 (no total internal reflection there).
        w[..nc].iter_mut().for_each(|x| *x *= 1.0 - f);
        d = keep_side(refract(d, m, 1.0 / eta, cos_i, cos_t), ng, false, balance);

        for seg in 1..=self.fiber.max_segments as usize {
            let Some(l) = section.chord(p, [d[1], d[2]]) else {
                break; // along the axis: it never leaves
            };
            for ((w, sigma_a), absorbed) in w[..nc]
                .iter_mut()
                .zip(&self.fiber.sigma_a)
                .zip(balance.absorbed.iter_mut())
            {
                let kept = *w * (-sigma_a * l).exp();
                *absorbed += *w - kept;
                *w = kept;
            }
            p = [p[0] + l * d[1], p[1] + l * d[2]];
            let ng = self.geometric_normal(section, p);
            let m = self.shading_normal(ng, d, false, rng, balance);
            let cos_i = dot(d, m);
            let (f, cos_t) = fresnel(cos_i, eta, 1.0);
            if f < 1.0 {
                let out = refract(d, [-m[0], -m[1], -m[2]], eta, cos_i, cos_t);
                let out = keep_side(out, ng, true, balance);
                let mut we = w;
                we[..nc].iter_mut().for_each(|x| *x *= 1.0 - f);
                add_w(&mut balance.tallied[seg.min(ORDERS - 1)], &we);
                exit(seg, out, &we);
                w[..nc].iter_mut().for_each(|x| *x *= f);
            }
            d = keep_side(reflect(d, m), ng, false, balance);
            if w[..nc].iter().all(|&x| x < WEIGHT_CUTOFF) {
                break;
            }
        }
        add_w(&mut balance.inside, &w);
    }

    fn geometric_normal(&self, section: &Section, p: [f64; 2]) -> V3 {
        let n = section.normal(p);
        [0.0, n[0], n[1]]
    }

    /// The outward shading normal at an interface with geometric normal `ng`, for a ray `d`
    /// arriving from outside (`outside`) or inside: the facet `ng + s_l·u + s_a·(u × ng)`
    /// (normalised) with longitudinal slope `s_l = tan α + tan β·ξ₁` and azimuthal slope
    /// `s_a = tan β_φ·ξ₂` (ξ standard normal by [`normal`], fresh at every interface), drawn among the facets
    /// `d` can see with probability proportional to the cosine it sees them at (a facet's
    /// projected area).
    fn shading_normal(
        &self,
        ng: V3,
        d: V3,
        outside: bool,
        rng: &mut impl RngCore,
        balance: &mut Balance,
    ) -> V3 {
        let sees = |m: V3| if outside { -dot(d, m) } else { dot(d, m) };
        if self.rough {
            for _ in 0..NORMAL_TRIES {
                let x1 = normal(rng);
                let x2 = if self.slope_sd_az == 0.0 {
                    0.0
                } else {
                    normal(rng)
                };
                let m = facet(ng, self.slope + self.slope_sd * x1, self.slope_sd_az * x2);
                let c = sees(m);
                if c > 0.0 && uniform(rng) < c {
                    return m;
                }
            }
            balance.fallbacks += 1;
        }
        let m = facet(ng, self.slope, 0.0);
        if sees(m) > 0.0 {
            return m;
        }
        if !self.rough {
            balance.fallbacks += 1;
        }
        ng
    }
}

/// The unit facet normal `ng + s_l·u + s_a·(u × ng)` normalised (`ng` unit with no axial part):
/// tilted toward the tip by atan(s_l / √(1 + s_a²)) and turned about the axis by atan(s_a).
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
fn keep_side(d: V3, ng: V3, out: bool, balance: &mut Balance) -> V3 {
    let c = dot(d, ng);
    if (c < 0.0) == out && c != 0.0 {
        balance.mirrored += 1;
        reflect(d, ng)
    } else {
        d
    }
}

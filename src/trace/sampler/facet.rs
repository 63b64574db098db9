//! The facet of a rough or tilted interface: its slopes drawn among the facets a ray sees, in
//! proportion to the cosine it sees them at (docs/trace.md, "visible facets").

use rand_chacha::rand_core::RngCore;

use super::{Balance, Sampler, NORMAL_TRIES};
use crate::trace::normal::{normal, normal_and_uniform};

impl Sampler {
    /// The slopes of the outward shading normal at an interface with geometric normal `ng`,
    /// the facet `ng + s_l·u + s_a·(u × ng)` (normalised, [`facet`](super::facet)): longitudinal slope
    /// `s_l = tan α + tan β·ξ₁`, azimuthal slope `s_a = tan β_φ·ξ₂` (ξ standard normal by
    /// [`normal`], fresh at every interface), drawn among the facets the ray sees with
    /// probability proportional to the cosine it sees them at (a facet's projected area). From
    /// the ray's components ±d·u, ±d·ng, ±d·(u × ng) (`du`, `dn`, `dt`, signed so that a facet
    /// the ray sees has a positive cosine) and [`tangent`](Self::tangent)'s `(A, λ)` for them.
    /// After [`NORMAL_TRIES`] failed tries, the tilted normal (s_l = tan α) if the ray sees it,
    /// else the geometric one (0, 0).
    #[allow(clippy::too_many_arguments)]
    #[inline(always)]
    pub(super) fn slopes(
        &self,
        a: f64,
        lambda: f64,
        du: f64,
        dn: f64,
        dt: f64,
        rng: &mut impl RngCore,
        balance: &mut Balance,
    ) -> (f64, f64) {
        if self.rough {
            let s = if self.slope_sd_az == 0.0 {
                self.slopes_longitudinal(lambda, rng)
            } else {
                self.slopes_rough(du, dn, dt, rng)
            };
            if let Some(s) = s {
                return s;
            }
            balance.fallbacks += 1;
        }
        // The tilted facet's unnormalised cosine is A.
        if a > 0.0 {
            return (self.slope, 0.0);
        }
        if !self.rough {
            balance.fallbacks += 1;
        }
        (0.0, 0.0)
    }

    /// Both roughnesses: ξ₁, ξ₂ from the normal, kept with probability c/1 (c the cosine the
    /// ray sees the facet at), tested before normalising (c·√(1 + s_l² + s_a²) = ±d·(the
    /// unnormalised normal) = c_u): kept when c_u > 0 and x²·(1 + s_l² + s_a²) < c_u².
    #[inline]
    fn slopes_rough(
        &self,
        du: f64,
        dn: f64,
        dt: f64,
        rng: &mut impl RngCore,
    ) -> Option<(f64, f64)> {
        for _ in 0..NORMAL_TRIES {
            let (x1, x) = normal_and_uniform(rng);
            let x2 = normal(rng);
            let (s_l, s_a) = (self.slope + self.slope_sd * x1, self.slope_sd_az * x2);
            // ±d · (s_l, ng_v − s_a·ng_w, ng_w + s_a·ng_v).
            let c = du * s_l + dn + s_a * dt;
            if c > 0.0 && x * x * (1.0 + s_l * s_l + s_a * s_a) < c * c {
                return Some((s_l, s_a));
            }
        }
        None
    }

    /// Longitudinal roughness only, without a bound on the cosine: the density of ξ is
    /// φ(ξ)·(A + Bξ)₊/√(1 + s_l²), `c_u = A + Bξ` (A = dn + du·tan α, B = du·tan β) being the
    /// ray's cosine times √(1 + s_l²). The exponential tangent to the line at ξ = λ covers it:
    /// A + Bξ = h·(1 + y) ≤ h·e^y, y = λ(ξ − λ), when λ = B/h and h = A + Bλ, i.e.
    /// h = (A + √(A² + 4B²))/2 > 0; and φ(ξ)·e^{λξ} ∝ φ(ξ − λ). So ξ = λ + z (z ~ φ) is kept
    /// with probability (1 + y)₊·e^{−y}/√(1 + s_l²): 0.5–0.99 of the tries, where a bound of
    /// c/|d's projection on the plane of u and ng| kept 0.02–0.95 (least at grazing angles).
    #[inline(always)]
    fn slopes_longitudinal(&self, lambda: f64, rng: &mut impl RngCore) -> Option<(f64, f64)> {
        // h = 0 (B = 0, A ≤ 0): the ray sees no facet.
        if !lambda.is_finite() {
            return None;
        }
        for _ in 0..NORMAL_TRIES {
            let (z, x) = normal_and_uniform(rng);
            let s_l = self.slope + self.slope_sd * (lambda + z);
            let y = lambda * z;
            if y > -1.0 {
                let lhs = x * x * (1.0 + s_l * s_l);
                // Squeeze: e^{−y} ≥ 1 − y + y²/2 − y³/6 for every y, so most tries decide
                // without the exponential. y·(1/6), not y/6: no division on every try's path;
                // it rounds differently, which can change a decision only where the squeeze
                // and the exact test below disagree by rounding (|y| < 1e-3, within an ulp).
                let low = (1.0 + y) * (1.0 - y * (1.0 - y * (0.5 - y * (1.0 / 6.0))));
                if low > 0.0 && lhs < low * low {
                    return Some((s_l, 0.0));
                }
                let keep = (1.0 + y) * (-y).exp();
                if lhs < keep * keep {
                    return Some((s_l, 0.0));
                }
            }
        }
        None
    }

    /// `(A, λ)` of [`slopes_longitudinal`](Self::slopes_longitudinal) for a ray with
    /// components `du`, `dn` (λ not finite when no facet is visible), without branches.
    #[inline(always)]
    pub(super) fn tangent(&self, du: f64, dn: f64) -> (f64, f64) {
        let (a, b, root) = self.tangent_terms(du, dn);
        (a, Self::tangent_lambda(a, b, root))
    }

    /// [`tangent`](Self::tangent)'s `A`, `B` and `√(A² + 4B²)`.
    #[inline(always)]
    pub(super) fn tangent_terms(&self, du: f64, dn: f64) -> (f64, f64, f64) {
        let (a, b) = (dn + du * self.slope, du * self.slope_sd);
        (a, b, (a * a + 4.0 * b * b).sqrt())
    }

    /// [`tangent`](Self::tangent)'s λ = B/h from its terms: h = (A + root)/2 when A ≥ 0; when
    /// A < 0 (a ray that sees few facets) the same h without cancellation, 2B²/(root − A), so
    /// λ = (root − A)/(2B). One division either way, chosen by a select, so lanes vectorise.
    #[inline(always)]
    pub(super) fn tangent_lambda(a: f64, b: f64, root: f64) -> f64 {
        let (num, den) = if a >= 0.0 {
            (b, 0.5 * (a + root))
        } else {
            (root - a, 2.0 * b)
        };
        num / den
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::Fiber;
    use rand_chacha::rand_core::SeedableRng;

    /// The tangent sampler draws the density the plain rejection (ξ ~ φ, kept with probability
    /// c/|d's projection|) draws: mean and variance of s_l agree within 5 standard errors, for
    /// rays from near-normal to grazing and from behind the geometric surface.
    #[test]
    fn tangent_sampler_matches_plain_rejection() {
        let fiber = Fiber::brown();
        let s = Sampler::new(&fiber);
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(7);
        for (theta, cg) in [
            (15.0, 1.0),
            (45.0, 0.1),
            (75.0, 0.5),
            (85.0, -0.05),
            (-30.0, 0.1),
        ] {
            let t: f64 = f64::to_radians(theta);
            let (du, dn) = (t.sin(), t.cos() * cg);
            let (a, lambda) = s.tangent(du, dn);
            let b = du * s.slope_sd;
            let n = 200_000;
            let (mut t1, mut t2, mut p1, mut p2, mut np) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for _ in 0..n {
                let (s_l, _) = s.slopes_longitudinal(lambda, &mut rng).unwrap();
                t1 += s_l;
                t2 += s_l * s_l;
            }
            while np < n as f64 {
                let x1 = normal(&mut rng);
                let x = crate::synth::random::uniform(&mut rng);
                let s_l = s.slope + s.slope_sd * x1;
                let c = (a + b * x1) / (1.0 + s_l * s_l).sqrt();
                if x * (du * du + dn * dn).sqrt() < c {
                    p1 += s_l;
                    p2 += s_l * s_l;
                    np += 1.0;
                }
            }
            let nf = n as f64;
            let (mt, mp) = (t1 / nf, p1 / np);
            let (vt, vp) = (t2 / nf - mt * mt, p2 / np - mp * mp);
            let se = (vp / nf).sqrt();
            assert!(
                (mt - mp).abs() < 5.0 * 2f64.sqrt() * se,
                "{theta} {cg}: {mt} {mp}"
            );
            assert!(
                (vt / vp - 1.0).abs() < 5.0 * 2.0 / nf.sqrt(),
                "{theta} {cg}: {vt} {vp}"
            );
        }
    }
}

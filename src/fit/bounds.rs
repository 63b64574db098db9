//! The fit's bounds and the MINUIT-style smooth transforms that keep every iterate inside them.
//! Each family's parameters give their bounds (`FitParam::bound`, from the family's parameter
//! table); this module only turns them into transforms.

/// The bounds of one parameter in its natural (model, radian) units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Bound {
    /// Unbounded: the identity transform.
    Free,
    /// `x ≥ lo`: `x = lo − 1 + sqrt(u² + 1)`.
    Lower(f64),
    /// `lo ≤ x ≤ hi`: `x = lo + (hi − lo)(sin u + 1)/2`.
    Both(f64, f64),
}

impl Bound {
    /// Natural value of internal `u` (MINUIT transform).
    pub fn to_natural(&self, u: f64) -> f64 {
        match *self {
            Bound::Free => u,
            Bound::Lower(lo) => lo - 1.0 + (u * u + 1.0).sqrt(),
            Bound::Both(lo, hi) => lo + (hi - lo) * (u.sin() + 1.0) / 2.0,
        }
    }

    /// `dx/du` of the transform at `u`.
    pub fn derivative(&self, u: f64) -> f64 {
        match *self {
            Bound::Free => 1.0,
            Bound::Lower(_) => u / (u * u + 1.0).sqrt(),
            Bound::Both(lo, hi) => (hi - lo) * u.cos() / 2.0,
        }
    }

    /// How much flatter the transform is at `u` than at its steepest: `max |dx/du| / |dx/du|`
    /// (1 for the identity; infinite where it is flat, on the bound itself).
    pub fn flatness(&self, u: f64) -> f64 {
        let steepest = match *self {
            Bound::Free | Bound::Lower(_) => 1.0,
            Bound::Both(lo, hi) => (hi - lo) / 2.0,
        };
        steepest / self.derivative(u).abs()
    }

    /// Internal `u` of a natural value (clamped into the bounds first).
    pub fn to_internal(&self, x: f64) -> f64 {
        match *self {
            Bound::Free => x,
            Bound::Lower(lo) => {
                let t = x.max(lo) - lo + 1.0;
                (t * t - 1.0).max(0.0).sqrt()
            }
            Bound::Both(lo, hi) => (2.0 * (x.clamp(lo, hi) - lo) / (hi - lo) - 1.0).asin(),
        }
    }

    /// The internal `u` of a natural value nearest `near`: the transforms are even (lower
    /// bound) or periodic (both bounds), so a solver point may sit on any branch, and a start
    /// derived from it must stay on the same one.
    pub fn to_internal_near(&self, x: f64, near: f64) -> f64 {
        let v = self.to_internal(x);
        match *self {
            Bound::Free => v,
            Bound::Lower(_) => v.copysign(near),
            Bound::Both(..) => {
                use std::f64::consts::{PI, TAU};
                [v, PI - v]
                    .into_iter()
                    .map(|c| c + TAU * ((near - c) / TAU).round())
                    .min_by(|a, b| (a - near).abs().total_cmp(&(b - near).abs()))
                    .unwrap_or(v)
            }
        }
    }

    /// Clamp a natural value into the bounds.
    pub fn clamp(&self, x: f64) -> f64 {
        match *self {
            Bound::Free => x,
            Bound::Lower(lo) => x.max(lo),
            Bound::Both(lo, hi) => x.clamp(lo, hi),
        }
    }

    /// True when `x` sits on a bound (relative to the bound's span or magnitude).
    pub fn at_bound(&self, x: f64) -> bool {
        let near = |b: f64, span: f64| (x - b).abs() <= 1e-7 * span.max(1e-12);
        match *self {
            Bound::Free => false,
            Bound::Lower(lo) => near(lo, lo.abs().max(1e-3)),
            Bound::Both(lo, hi) => near(lo, hi - lo) || near(hi, hi - lo),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::FRAC_1_SQRT_2;

    #[test]
    fn the_internal_value_near_a_point_is_on_its_branch() {
        // A solver point on another period of the sine (or the other half of the even lower
        // transform) gets the same natural value back, within one half-period of it.
        for b in [Bound::Lower(0.0), Bound::Both(FRAC_1_SQRT_2, 1.0)] {
            for near in [-40.0, -7.0, -1.0, 0.3, 2.5, 15.9] {
                for x in [0.75, 0.8, 0.99] {
                    let u = b.to_internal_near(x, near);
                    // 1e-12 as the round trip below.
                    assert!((b.to_natural(u) - x).abs() < 1e-12, "{b:?} {x} near {near}");
                    assert!(
                        (u - near).abs() <= std::f64::consts::PI + near.abs().max(1.0) * 1e-12
                            || matches!(b, Bound::Lower(_)),
                        "{b:?} {x} near {near}: {u}"
                    );
                }
            }
        }
        // On the branch of a point that is itself the image of x, the point comes back.
        let b = Bound::Both(0.0, 1.0);
        let u = 0.4 + 6.0 * std::f64::consts::TAU;
        assert!((b.to_internal_near(b.to_natural(u), u) - u).abs() < 1e-9);
        let u = std::f64::consts::PI - 0.4 - 2.0 * std::f64::consts::TAU;
        assert!((b.to_internal_near(b.to_natural(u), u) - u).abs() < 1e-9);
    }

    /// Flatness is 1 where the transform is steepest (everywhere for the identity, mid-range for
    /// both bounds, far above a lower bound), grows as 1/|cos u| or √(u²+1)/|u| toward a bound
    /// and is infinite on it.
    #[test]
    fn flatness_is_one_where_steepest_and_grows_onto_the_bound() {
        use std::f64::consts::FRAC_PI_2;
        let both = Bound::Both(5.0, 90.0);
        assert_eq!(Bound::Free.flatness(-3.0), 1.0);
        assert_eq!(both.flatness(0.0), 1.0);
        assert!((Bound::Lower(0.0).flatness(1e8) - 1.0).abs() < 1e-12);
        for d in [1e-1f64, 1e-3, 1e-6] {
            let want = 1.0 / d.sin();
            let got = both.flatness(-FRAC_PI_2 + d);
            assert!((got / want - 1.0).abs() < 1e-9, "{d}: {got} vs {want}");
            let want = (d * d + 1.0).sqrt() / d;
            assert!((Bound::Lower(0.0).flatness(d) / want - 1.0).abs() < 1e-12);
        }
        assert!(Bound::Lower(0.0).flatness(0.0).is_infinite());
    }

    #[test]
    fn transforms_round_trip_and_stay_inside() {
        for b in [
            Bound::Free,
            Bound::Lower(0.0),
            Bound::Both(FRAC_1_SQRT_2, 1.0),
        ] {
            for x in [0.75, 0.8, 0.99] {
                // 1e-12: asin/sin and sqrt round trips lose a few ulps of the span only.
                assert!(
                    (b.to_natural(b.to_internal(x)) - x).abs() < 1e-12,
                    "{b:?} {x}"
                );
            }
            for u in [-1e3, -3.0, -1.0, 0.0, 0.5, 2.0, 1e3] {
                let x = b.to_natural(u);
                assert_eq!(b.clamp(x), x, "{b:?} u={u} leaves the bounds");
                // Central difference vs analytic derivative; 1e-6 is the O(h²) error for h=1e-4.
                let h = 1e-4;
                let fd = (b.to_natural(u + h) - b.to_natural(u - h)) / (2.0 * h);
                assert!((fd - b.derivative(u)).abs() < 1e-6, "{b:?} u={u}");
            }
        }
    }
}

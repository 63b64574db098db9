//! Angle bookkeeping of MODEL.md "Geometry and angles": wrapping and the half/difference angles.

use num_dual::DualNum;

use crate::error::{Error, Result};
use std::f64::consts::{PI, TAU};

/// `wrap`: map an angle to `(−π, π]`.
#[inline]
pub fn wrap(x: f64) -> f64 {
    // `x.rem_euclid(TAU)` without its fmod where the fmod is plain arithmetic: x itself where
    // |x| < 2π, x − 2π on [2π, 4π) (exact by Sterbenz's lemma; TRT's Φ lives there). The same
    // bits, at a fraction of the cost on the per-sample path.
    let r = if x.abs() < TAU {
        x
    } else if (TAU..2.0 * TAU).contains(&x) {
        x - TAU
    } else {
        x % TAU
    };
    let y = if r < 0.0 { r + TAU } else { r };
    if y > PI {
        y - TAU
    } else {
        y
    }
}

/// `wrap` in degrees: map an angle to `(−180°, 180°]` (for reports and rig geometry, which work
/// in degrees; converting to radians and back would not round-trip exactly).
#[inline]
pub fn wrap_deg(x: f64) -> f64 {
    // `x % 360` is x itself inside ±360: skip the fmod call (same bits).
    let y = if x.abs() < 360.0 { x } else { x % 360.0 };
    if y <= -180.0 {
        y + 360.0
    } else if y > 180.0 {
        y - 360.0
    } else {
        y
    }
}

/// `wrap` for a (dual) number: shift by the multiple of 2π found on the real part.
#[inline]
pub fn wrap_t<T: DualNum<f64>>(x: T) -> T {
    let r = x.re();
    let shift = wrap(r) - r;
    x + shift
}

/// Derived angles `θ_h, θ_d, φ, φ_h` (radians).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HalfAngles {
    pub theta_h: f64,
    pub theta_d: f64,
    pub phi: f64,
    pub phi_h: f64,
}

/// `θ_h = (θ_i+θ_r)/2, θ_d = (θ_r−θ_i)/2, φ = wrap(φ_r−φ_i), φ_h = (φ_i+φ_r)/2`.
#[inline]
pub fn half_angles(theta_i: f64, phi_i: f64, theta_r: f64, phi_r: f64) -> HalfAngles {
    HalfAngles {
        theta_h: 0.5 * (theta_i + theta_r),
        theta_d: 0.5 * (theta_r - theta_i),
        phi: wrap(phi_r - phi_i),
        phi_h: 0.5 * (phi_i + phi_r),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn wrap_maps_into_the_half_open_interval() {
        assert_eq!(wrap(PI), PI);
        assert_eq!(wrap(-PI), PI);
        assert_eq!(wrap(0.25), 0.25);
        assert!((wrap(3.0 * PI / 2.0) + PI / 2.0).abs() < 1e-15);
        assert_eq!(wrap_deg(180.0), 180.0);
        assert_eq!(wrap_deg(-180.0), 180.0);
        assert_eq!(wrap_deg(540.0), 180.0);
        assert_eq!(wrap_deg(-190.0), 170.0);
        assert_eq!(wrap_deg(359.5), -0.5);
    }

    /// The fmod-free fast path returns exactly what `rem_euclid` gives, inside and outside 2π.
    #[test]
    fn wrap_is_bit_identical_to_rem_euclid() {
        let reference = |x: f64| {
            let y = x.rem_euclid(TAU);
            if y > PI {
                y - TAU
            } else {
                y
            }
        };
        let mut x = -20.0;
        while x < 20.0 {
            for v in [
                x,
                -x,
                TAU,
                -TAU,
                PI,
                -PI,
                0.0,
                -0.0,
                f64::NAN,
                f64::INFINITY,
            ] {
                let (a, b) = (wrap(v), reference(v));
                assert!(
                    a.to_bits() == b.to_bits() || (a.is_nan() && b.is_nan()),
                    "{v}"
                );
            }
            x += 0.012_345;
        }
    }
}

/// Incident and reflected directions in the fiber frame, radians.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Angles {
    pub theta_i: f64,
    pub phi_i: f64,
    pub theta_r: f64,
    pub phi_r: f64,
}

impl Angles {
    /// Check `θ ∈ (−90°, 90°)` (|θ| = 90° puts the direction on the fiber axis) and all finite;
    /// the error names the angle and its value in degrees.
    pub fn validate(&self) -> Result<()> {
        let check = |name: &str, v: f64, limit: Option<f64>| {
            let ok = v.is_finite() && limit.is_none_or(|l| v.abs() < l);
            if ok {
                Ok(())
            } else {
                Err(Error::Parameter {
                    name: name.into(),
                    value: v.to_degrees(),
                    message: match limit {
                        Some(_) => {
                            "an inclination must be finite and strictly between -90 and 90 degrees"
                                .into()
                        }
                        None => "an azimuth must be finite".into(),
                    },
                })
            }
        };
        let half_pi = Some(std::f64::consts::FRAC_PI_2);
        check("theta_i", self.theta_i, half_pi)?;
        check("phi_i", self.phi_i, None)?;
        check("theta_r", self.theta_r, half_pi)?;
        check("phi_r", self.phi_r, None)
    }

    /// Angles from degrees.
    pub fn from_degrees(theta_i: f64, phi_i: f64, theta_r: f64, phi_r: f64) -> Angles {
        Angles {
            theta_i: theta_i.to_radians(),
            phi_i: phi_i.to_radians(),
            theta_r: theta_r.to_radians(),
            phi_r: phi_r.to_radians(),
        }
    }
}

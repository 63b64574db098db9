//! What a data file's values are (MODEL.md "From model to measurement"): `scale_c · S` itself,
//! or radiance under a collimated source, `scale_c · S · cos θ_i`. The factor depends on the
//! sample's geometry only, never on a parameter, so a fit carries it as a per-sample constant.

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use super::Angles;
use crate::error::{Error, Result};

/// What a measured value is, up to the per-channel scale.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Measurement {
    /// `scale_c · S`.
    #[default]
    S,
    /// `scale_c · S · cos θ_i`: radiance under a collimated source.
    Radiance,
}

impl Measurement {
    /// The factor from `scale_c · S` to the measured value: 1, or `cos θ_i`.
    #[inline]
    pub fn factor(self, angles: &Angles) -> f64 {
        match self {
            Measurement::S => 1.0,
            Measurement::Radiance => angles.theta_i.cos(),
        }
    }

    /// Multiply each sample's block of `out` — `out.len() / angles.len()` numbers: its
    /// channels' values, per-lobe values or derivative rows — by the factor at its angles. The
    /// factor depends on θ_i only, so values and their derivatives scale alike.
    pub fn apply<T: Clone + std::ops::Mul<f64, Output = T>>(
        self,
        angles: &[Angles],
        out: &mut [T],
    ) {
        if self == Measurement::S || angles.is_empty() {
            return;
        }
        let per_sample = out.len() / angles.len();
        for (a, block) in angles.iter().zip(out.chunks_mut(per_sample.max(1))) {
            let f = self.factor(a);
            block.iter_mut().for_each(|v| *v = v.clone() * f);
        }
    }
}

impl FromStr for Measurement {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "s" => Ok(Measurement::S),
            "radiance" => Ok(Measurement::Radiance),
            other => Err(Error::Other(format!(
                "unknown measurement `{other}`: use `s` (values are scale·S) or `radiance` \
                 (scale·S·cos theta_i, radiance under a collimated source)"
            ))),
        }
    }
}

impl fmt::Display for Measurement {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Measurement::S => "s",
            Measurement::Radiance => "radiance",
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spellings_round_trip_through_text_and_json() {
        for m in [Measurement::S, Measurement::Radiance] {
            assert_eq!(m.to_string().parse::<Measurement>().unwrap(), m);
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(json, format!("\"{m}\""));
            assert_eq!(serde_json::from_str::<Measurement>(&json).unwrap(), m);
        }
        assert!("cos".parse::<Measurement>().is_err());
    }

    #[test]
    fn apply_scales_each_samples_block_by_its_factor() {
        let angles = [
            Angles::from_degrees(0.0, 0.0, 10.0, 20.0),
            Angles::from_degrees(60.0, 0.0, 10.0, 20.0),
        ];
        let mut v = [1.0, 2.0, 1.0, 2.0];
        Measurement::S.apply(&angles, &mut v);
        assert_eq!(v, [1.0, 2.0, 1.0, 2.0]);
        Measurement::Radiance.apply(&angles, &mut v);
        let c = Measurement::Radiance.factor(&angles[1]);
        assert_eq!(v, [1.0, 2.0, c, 2.0 * c]);
        Measurement::Radiance.apply(&angles, &mut [0.0f64; 0]);
    }

    #[test]
    fn radiance_carries_cos_theta_i_only() {
        let a = Angles::from_degrees(60.0, 10.0, -20.0, 170.0);
        assert_eq!(Measurement::S.factor(&a), 1.0);
        // cos 60° = 0.5 up to the rounding of 60° in radians (a few ulps).
        assert!((Measurement::Radiance.factor(&a) - 0.5).abs() < 1e-15);
        let b = Angles::from_degrees(60.0, -90.0, 45.0, 0.0);
        assert_eq!(
            Measurement::Radiance.factor(&a),
            Measurement::Radiance.factor(&b)
        );
    }
}

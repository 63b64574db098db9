//! The traced fibre (`FIBER.json`, [`FiberFile`]): what it is made of and how its surface is
//! shaped, read, checked and written one way; [`Fiber`] is the same in radians for the sampler.

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};
use crate::geometry::SigmaA;
use crate::json_file::ParameterFile;

/// Most internal segments a path may be followed for (`max_segments`).
pub const MAX_SEGMENTS_LIMIT: u32 = 1000;

/// The fibre file: degrees for angles, lengths in units of the cross-section's major
/// semi-axis (the radius of a round fibre), as docs/trace.md describes.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FiberFile {
    /// Refractive index of the cortex (> 1).
    #[serde(default = "default_eta")]
    pub eta: f64,
    /// Absorption per unit radius along the 3-D path, one per colour channel (or one number).
    pub sigma_a: SigmaA,
    /// Tilt of the cuticle's shading normal toward the tip (negative: toward the root, as
    /// docs/model.md's α_R): a smooth fibre's R ray leaves at θ_r = −θ_i + 2α.
    #[serde(default)]
    pub cuticle_tilt_deg: f64,
    /// Standard deviation of the normal's longitudinal perturbation at every interface.
    #[serde(default)]
    pub roughness_deg: f64,
    /// Standard deviation of the normal's azimuthal perturbation at every interface.
    #[serde(default)]
    pub azimuthal_roughness_deg: f64,
    /// Ratio of the cross-section's minor to major axis, in (0, 1]; 1 is round.
    #[serde(default = "default_one")]
    pub eccentricity: f64,
    /// Angle of the major axis from `v` about the fibre axis; absent (`null`): every ray sees
    /// a fresh rotation, uniform over orientations weighted by the width it presents.
    #[serde(default)]
    pub rotation_deg: Option<f64>,
    /// Internal segments a path is followed for; the weight still inside after them is
    /// reported, not tallied.
    #[serde(default = "default_segments")]
    pub max_segments: u32,
}

fn default_eta() -> f64 {
    1.55
}
fn default_one() -> f64 {
    1.0
}
fn default_segments() -> u32 {
    16
}

/// The fibre in the sampler's units (radians).
#[derive(Debug, Clone, PartialEq)]
pub struct Fiber {
    pub eta: f64,
    pub sigma_a: Vec<f64>,
    pub tilt: f64,
    pub roughness: f64,
    pub azimuthal_roughness: f64,
    pub eccentricity: f64,
    pub rotation: Option<f64>,
    pub max_segments: u32,
}

#[cfg(test)]
impl Fiber {
    /// The brown fibre (η 1.55, σ_a 0.5, tilt −3°, roughness 6°), for unit tests.
    pub(crate) fn brown() -> Fiber {
        Fiber {
            eta: 1.55,
            sigma_a: vec![0.5],
            tilt: (-3f64).to_radians(),
            roughness: 6f64.to_radians(),
            azimuthal_roughness: 0.0,
            eccentricity: 1.0,
            rotation: None,
            max_segments: 16,
        }
    }
}

impl FiberFile {
    /// The absorption of every channel.
    pub fn sigma_a_values(&self) -> Vec<f64> {
        match &self.sigma_a {
            SigmaA::Scalar(s) => vec![*s],
            SigmaA::PerChannel(v) => v.clone(),
        }
    }

    /// The sampler's fibre (call after [`ParameterFile::validate`]).
    pub fn fiber(&self) -> Fiber {
        Fiber {
            eta: self.eta,
            sigma_a: self.sigma_a_values(),
            tilt: self.cuticle_tilt_deg.to_radians(),
            roughness: self.roughness_deg.to_radians(),
            azimuthal_roughness: self.azimuthal_roughness_deg.to_radians(),
            eccentricity: self.eccentricity,
            rotation: self.rotation_deg.map(f64::to_radians),
            max_segments: self.max_segments,
        }
    }
}

fn bad(name: &str, value: f64, message: &str) -> Error {
    Error::Parameter {
        name: name.into(),
        value,
        message: message.into(),
    }
}

impl ParameterFile for FiberFile {
    fn hint() -> String {
        "a fibre file is a JSON object with keys eta, sigma_a (number or one per channel), \
         cuticle_tilt_deg, roughness_deg, azimuthal_roughness_deg, eccentricity, rotation_deg \
         (number or null), max_segments (docs/trace.md)"
            .into()
    }

    fn validate(&self) -> Result<()> {
        if !(self.eta.is_finite() && self.eta > 1.0 && self.eta <= 10.0) {
            return Err(bad("eta", self.eta, "give a refractive index in (1, 10]"));
        }
        let sigma = self.sigma_a_values();
        if sigma.is_empty() {
            return Err(Error::Other(
                "sigma_a is an empty array: give one value per colour channel".into(),
            ));
        }
        if let Some(&s) = sigma.iter().find(|s| !(s.is_finite() && **s >= 0.0)) {
            return Err(bad("sigma_a", s, "give a finite absorption ≥ 0 per radius"));
        }
        if !(self.cuticle_tilt_deg.is_finite() && self.cuticle_tilt_deg.abs() <= 45.0) {
            return Err(bad(
                "cuticle_tilt_deg",
                self.cuticle_tilt_deg,
                "give a tilt in [-45, 45] degrees (hair: about -2 to -5)",
            ));
        }
        for (name, v) in [
            ("roughness_deg", self.roughness_deg),
            ("azimuthal_roughness_deg", self.azimuthal_roughness_deg),
        ] {
            if !(v.is_finite() && (0.0..=45.0).contains(&v)) {
                return Err(bad(name, v, "give a standard deviation in [0, 45] degrees"));
            }
        }
        if !(self.eccentricity.is_finite() && self.eccentricity >= 0.1 && self.eccentricity <= 1.0)
        {
            return Err(bad(
                "eccentricity",
                self.eccentricity,
                "give the minor-to-major axis ratio in [0.1, 1]",
            ));
        }
        if let Some(r) = self.rotation_deg.filter(|r| !r.is_finite()) {
            return Err(bad(
                "rotation_deg",
                r,
                "give a finite angle, or null to average",
            ));
        }
        if !(1..=MAX_SEGMENTS_LIMIT).contains(&self.max_segments) {
            return Err(bad(
                "max_segments",
                f64::from(self.max_segments),
                "give 1 to 1000 internal segments",
            ));
        }
        Ok(())
    }
}

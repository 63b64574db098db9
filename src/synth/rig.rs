//! Measurement rigs: the sample geometries `hairfit synth` mirrors, parsed from a compact spec
//! such as `azimuthal:incidences=15,30,45:steps=180` and producing angles in degrees.

use std::fmt;
use std::str::FromStr;

use rand_chacha::rand_core::RngCore;

use super::random::uniform;
use crate::error::{Error, Result};

/// A sample geometry. Angles are degrees in MODEL.md's fiber frame (θ from the normal plane,
/// positive toward the tip; φ about the fiber axis, in (−180°, 180°]).
///
/// | rig | geometry | options (defaults) | samples |
/// |---|---|---|---|
/// | `azimuthal` | specular cone: θ_r = −θ_i, φ_i = 0, φ_r = −180 + 360·k/steps, k = 1..steps | `incidences=15,30,45`, `steps=180` | incidences × steps |
/// | `longitudinal` | φ_i = 0, φ_r = each `phi`, θ_r = −max … max in `steps` even steps, fixed θ_i | `incidences=15,30,45`, `phi=0,180`, `steps=91`, `max=85` | incidences × phi × steps |
/// | `sphere` | ω_i and ω_r independent and uniform on the sphere, \|θ\| > max rejected | `n=1000`, `max=85` | n |
/// | `photo` | a fiber bent in the camera plane, photographed under a ring of lights | `lights=6`, `views=50`, `span=60`, `light_theta=-20`, `camera=0` | lights × views |
#[derive(Debug, Clone, PartialEq)]
pub enum Rig {
    /// Goniometer azimuthal scans on the specular cone (Marschner 2003, Fig. 6): for each
    /// incidence θ_i the detector sweeps φ_r over (−180°, 180°] with θ_r = −θ_i and φ_i = 0.
    Azimuthal { incidences: Vec<f64>, steps: usize },
    /// Longitudinal scans in a fixed azimuthal plane: θ_i fixed, φ_i = 0, φ_r = φ, θ_r swept
    /// from −max to +max (inclusive, `steps` evenly spaced values).
    Longitudinal {
        incidences: Vec<f64>,
        phi: Vec<f64>,
        steps: usize,
        max: f64,
    },
    /// Random directions: ω_i and ω_r independently uniform on the sphere (sin θ uniform in
    /// [−1, 1], φ uniform), redrawing any direction with |θ| > max (too close to the fiber axis).
    Sphere { n: usize, max: f64 },
    /// A photograph of one fiber: the fiber lies in the camera's image plane and bends by
    /// β ∈ [−span/2, span/2] along the `views` pixels of the strip, so the camera sees it at
    /// θ_r = camera + β, φ_r = 0. `lights` point lights sit at inclination `light_theta` from the
    /// unbent fiber's normal plane and azimuths −180 + 360·(k+1)/lights about it; their fiber-frame
    /// (θ_i, φ_i) change along the strip as the fiber bends.
    Photo(PhotoRig),
}

/// The photograph rig's geometry ([`Rig::Photo`]).
#[derive(Debug, Clone, PartialEq)]
pub struct PhotoRig {
    pub lights: usize,
    pub views: usize,
    pub span: f64,
    pub light_theta: f64,
    pub camera: f64,
}

/// Largest |θ| a rig may produce, in degrees: MODEL.md rejects |θ| = 90° and the model is
/// ill-conditioned next to it.
pub const MAX_THETA_DEG: f64 = 89.0;

impl Rig {
    /// Parse a rig spec `KIND[:KEY=VALUE[,VALUE...]]...` (see the table on [`Rig`]).
    pub fn parse(spec: &str) -> Result<Rig> {
        let mut parts = spec.split(':').map(str::trim);
        let kind = parts.next().unwrap_or("").to_ascii_lowercase();
        let allowed: &[&str] = match kind.as_str() {
            "azimuthal" => &["incidences", "steps"],
            "longitudinal" => &["incidences", "phi", "steps", "max"],
            "sphere" => &["n", "max"],
            "photo" => &["lights", "views", "span", "light_theta", "camera"],
            _ => {
                return Err(rig_error(
                    spec,
                    format!(
                        "unknown rig `{kind}`: use azimuthal, longitudinal, sphere or photo, \
                         e.g. `azimuthal:incidences=15,30,45:steps=180`"
                    ),
                ))
            }
        };
        let mut opts = Options {
            spec,
            pairs: Vec::new(),
        };
        for part in parts {
            let Some((key, value)) = part.split_once('=') else {
                return Err(rig_error(
                    spec,
                    format!("option `{part}` is not KEY=VALUE (e.g. `steps=180`)"),
                ));
            };
            let key = key.trim().to_ascii_lowercase();
            if !allowed.contains(&key.as_str()) {
                return Err(rig_error(
                    spec,
                    format!(
                        "`{kind}` has no option `{key}`; its options are {}",
                        allowed.join(", ")
                    ),
                ));
            }
            if opts.pairs.iter().any(|(k, _)| *k == key) {
                return Err(rig_error(spec, format!("option `{key}` is given twice")));
            }
            opts.pairs.push((key, value.trim().to_string()));
        }
        let rig = match kind.as_str() {
            "azimuthal" => Rig::Azimuthal {
                incidences: opts.angles("incidences", &[15.0, 30.0, 45.0])?,
                steps: opts.count("steps", 180, 1)?,
            },
            "longitudinal" => Rig::Longitudinal {
                incidences: opts.angles("incidences", &[15.0, 30.0, 45.0])?,
                phi: opts.azimuths("phi", &[0.0, 180.0])?,
                steps: opts.count("steps", 91, 2)?,
                max: opts.limit("max", 85.0)?,
            },
            "sphere" => Rig::Sphere {
                n: opts.count("n", 1000, 1)?,
                max: opts.limit("max", 85.0)?,
            },
            _ => {
                let photo = PhotoRig {
                    lights: opts.count("lights", 6, 1)?,
                    views: opts.count("views", 50, 1)?,
                    span: opts.number("span", 60.0)?,
                    light_theta: opts.number("light_theta", -20.0)?,
                    camera: opts.number("camera", 0.0)?,
                };
                photo.check(spec)?;
                Rig::Photo(photo)
            }
        };
        if rig.sample_count().is_none() {
            return Err(rig_error(
                spec,
                "the sample count overflows: use smaller sizes",
            ));
        }
        Ok(rig)
    }

    /// Number of samples this rig produces (`None` on overflow).
    pub fn sample_count(&self) -> Option<usize> {
        match self {
            Rig::Azimuthal { incidences, steps } => incidences.len().checked_mul(*steps),
            Rig::Longitudinal {
                incidences,
                phi,
                steps,
                ..
            } => incidences.len().checked_mul(phi.len())?.checked_mul(*steps),
            Rig::Sphere { n, .. } => Some(*n),
            Rig::Photo(p) => p.lights.checked_mul(p.views),
        }
    }

    /// The rig's name (`azimuthal`, ...).
    pub fn kind(&self) -> &'static str {
        match self {
            Rig::Azimuthal { .. } => "azimuthal",
            Rig::Longitudinal { .. } => "longitudinal",
            Rig::Sphere { .. } => "sphere",
            Rig::Photo(_) => "photo",
        }
    }

    /// The sample directions `[θ_i, φ_i, θ_r, φ_r]` in degrees, in a fixed order (outer loop
    /// first as listed on each variant). Only `sphere` draws from `rng`.
    pub fn angles(&self, rng: &mut impl RngCore) -> Vec<[f64; 4]> {
        let mut out = Vec::with_capacity(self.sample_count().unwrap_or(0));
        match self {
            Rig::Azimuthal { incidences, steps } => {
                for &t in incidences {
                    for k in 1..=*steps {
                        out.push([t, 0.0, -t, sweep_azimuth(k, *steps)]);
                    }
                }
            }
            Rig::Longitudinal {
                incidences,
                phi,
                steps,
                max,
            } => {
                for &t in incidences {
                    for &p in phi {
                        for k in 0..*steps {
                            out.push([t, 0.0, sweep_inclination(k, *steps, *max), p]);
                        }
                    }
                }
            }
            Rig::Sphere { n, max } => {
                for _ in 0..*n {
                    let (ti, pi) = sphere_direction(rng, *max);
                    let (tr, pr) = sphere_direction(rng, *max);
                    out.push([ti, pi, tr, pr]);
                }
            }
            Rig::Photo(p) => p.push_angles(&mut out),
        }
        out
    }
}

impl Rig {
    /// Refuse before allocating a dataset that would not fit in memory (an azimuthal rig of
    /// 10⁸ steps aborted at 9.6 GB); the error names the options that set the size.
    pub fn check_memory(&self, n_channels: usize, spec: &str, limit: u64) -> Result<()> {
        let samples = self.sample_count().unwrap_or(usize::MAX) as u64;
        let sizes = match self {
            Rig::Azimuthal { .. } => "incidences or steps",
            Rig::Longitudinal { .. } => "incidences, phi or steps",
            Rig::Sphere { .. } => "n",
            Rig::Photo(_) => "lights or views",
        };
        super::memory::check(samples, n_channels, limit, |why| {
            rig_error(
                spec,
                format!("{why}: use fewer {sizes}, or raise --max-memory"),
            )
        })
    }
}

/// φ_r of step k of n on the azimuthal sweep: (−180°, 180°], ending exactly at 180°.
fn sweep_azimuth(k: usize, steps: usize) -> f64 {
    360.0 * k as f64 / steps as f64 - 180.0
}

/// θ_r of step k of n on the longitudinal sweep, −max … +max inclusive.
fn sweep_inclination(k: usize, steps: usize, max: f64) -> f64 {
    -max + 2.0 * max * k as f64 / (steps - 1) as f64
}

/// Rejection tries before [`sphere_direction`] samples the band directly.
const SPHERE_TRIES: usize = 1024;

/// A direction uniform on the sphere restricted to |θ| ≤ max (sin θ uniform), in degrees.
///
/// Rejection first (what every dataset made so far used, so a seed still gives the same bytes),
/// then, after [`SPHERE_TRIES`] misses, the band |sin θ| ≤ sin(max) sampled directly by its
/// inverse CDF: sin θ uniform in [−sin max, sin max]. Both are the same distribution (a
/// rejection sampler's output is the conditional law whenever it stops), and the direct step
/// bounds the time: `max=1e-8` never finished, `max=1e-5` with n=100 took over 20 s.
fn sphere_direction(rng: &mut impl RngCore, max: f64) -> (f64, f64) {
    for _ in 0..SPHERE_TRIES {
        let z = 2.0 * uniform(rng) - 1.0;
        let phi = 180.0 - 360.0 * uniform(rng);
        let theta = z.asin().to_degrees();
        if theta.abs() <= max {
            return (theta, phi);
        }
    }
    let z = max.to_radians().sin() * (2.0 * uniform(rng) - 1.0);
    let phi = 180.0 - 360.0 * uniform(rng);
    // asin(sin max) can round a hair above max.
    (z.asin().to_degrees().clamp(-max, max), phi)
}

/// Bend angle β of pixel j of the photo strip: evenly spaced over [−span/2, span/2].
fn photo_bend(j: usize, views: usize, span: f64) -> f64 {
    if views == 1 {
        0.0
    } else {
        -span / 2.0 + span * j as f64 / (views - 1) as f64
    }
}

/// Unit vector with inclination θ and azimuth φ (degrees) in the frame (u, v, w).
fn unit_vector(theta: f64, phi: f64) -> [f64; 3] {
    let (st, ct) = theta.to_radians().sin_cos();
    let (sp, cp) = phi.to_radians().sin_cos();
    [st, ct * cp, ct * sp]
}

/// (θ, φ) in degrees of a world direction in the frame of the fiber bent by β about w:
/// u = (cos β, sin β, 0), v = (−sin β, cos β, 0), w = (0, 0, 1).
fn fiber_frame_direction(d: [f64; 3], bend: f64) -> (f64, f64) {
    let (sb, cb) = bend.to_radians().sin_cos();
    let du = d[0] * cb + d[1] * sb;
    let dv = -d[0] * sb + d[1] * cb;
    let theta = du.clamp(-1.0, 1.0).asin().to_degrees();
    (
        theta,
        crate::geometry::angles::wrap_deg(d[2].atan2(dv).to_degrees()),
    )
}

fn rig_error(spec: &str, message: impl fmt::Display) -> Error {
    Error::Other(format!("--rig `{spec}`: {message}"))
}

/// The KEY=VALUE options of one spec, read with defaults.
struct Options<'a> {
    spec: &'a str,
    pairs: Vec<(String, String)>,
}

impl Options<'_> {
    fn get(&self, key: &str) -> Option<&str> {
        self.pairs
            .iter()
            .find(|(k, _)| k == key)
            .map(|(_, v)| v.as_str())
    }

    fn parse_number(&self, key: &str, text: &str) -> Result<f64> {
        match text.trim().parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(rig_error(
                self.spec,
                format!("{key}: `{text}` is not a finite number"),
            )),
        }
    }

    fn number(&self, key: &str, default: f64) -> Result<f64> {
        self.get(key)
            .map_or(Ok(default), |v| self.parse_number(key, v))
    }

    fn list(&self, key: &str, default: &[f64]) -> Result<Vec<f64>> {
        let Some(text) = self.get(key) else {
            return Ok(default.to_vec());
        };
        let values = text
            .split(',')
            .map(|t| self.parse_number(key, t))
            .collect::<Result<Vec<_>>>()?;
        if values.is_empty() || text.trim().is_empty() {
            return Err(rig_error(
                self.spec,
                format!("{key}: give at least one value"),
            ));
        }
        Ok(values)
    }

    /// Inclinations in degrees, each within ±MAX_THETA_DEG.
    fn angles(&self, key: &str, default: &[f64]) -> Result<Vec<f64>> {
        self.checked_list(
            key,
            default,
            |v| v.abs() <= MAX_THETA_DEG,
            || format!("±{MAX_THETA_DEG}° (90° lies on the fiber axis)"),
        )
    }

    /// Azimuths in degrees, each within (−180°, 180°].
    fn azimuths(&self, key: &str, default: &[f64]) -> Result<Vec<f64>> {
        self.checked_list(
            key,
            default,
            |v| v > -180.0 && v <= 180.0,
            || "(-180°, 180°] (write -180 as 180)".into(),
        )
    }

    /// A list whose every value passes `ok`; the error names the first that does not and the
    /// allowed `range`.
    fn checked_list(
        &self,
        key: &str,
        default: &[f64],
        ok: impl Fn(f64) -> bool,
        range: impl Fn() -> String,
    ) -> Result<Vec<f64>> {
        let values = self.list(key, default)?;
        if let Some(bad) = values.iter().find(|v| !ok(**v)) {
            return Err(rig_error(
                self.spec,
                format!("{key}: {bad}° is outside {}", range()),
            ));
        }
        Ok(values)
    }

    /// A limit on |θ| in (0, MAX_THETA_DEG].
    fn limit(&self, key: &str, default: f64) -> Result<f64> {
        let v = self.number(key, default)?;
        if !(v > 0.0 && v <= MAX_THETA_DEG) {
            return Err(rig_error(
                self.spec,
                format!("{key}={v}: use a value in (0, {MAX_THETA_DEG}] degrees"),
            ));
        }
        Ok(v)
    }

    /// A count ≥ `min`.
    fn count(&self, key: &str, default: usize, min: usize) -> Result<usize> {
        let Some(text) = self.get(key) else {
            return Ok(default);
        };
        match text.parse::<usize>() {
            Ok(n) if n >= min => Ok(n),
            _ => Err(rig_error(
                self.spec,
                format!("{key}: `{text}` is not a whole number >= {min}"),
            )),
        }
    }
}

impl FromStr for Rig {
    type Err = Error;
    fn from_str(s: &str) -> Result<Rig> {
        Rig::parse(s)
    }
}

/// The canonical spec with every option spelled out (what the truth file records).
impl fmt::Display for Rig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let list = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(",");
        match self {
            Rig::Azimuthal { incidences, steps } => {
                write!(f, "azimuthal:incidences={}:steps={steps}", list(incidences))
            }
            Rig::Longitudinal {
                incidences,
                phi,
                steps,
                max,
            } => write!(
                f,
                "longitudinal:incidences={}:phi={}:steps={steps}:max={max}",
                list(incidences),
                list(phi)
            ),
            Rig::Sphere { n, max } => write!(f, "sphere:n={n}:max={max}"),
            Rig::Photo(p) => write!(f, "{p}"),
        }
    }
}

impl PhotoRig {
    /// The photo rig's inclinations stay within ±MAX_THETA_DEG: bending by β moves the fiber
    /// axis by |β|, so |θ_i| ≤ |light_theta| + span/2 and |θ_r| ≤ |camera| + span/2.
    fn check(&self, spec: &str) -> Result<()> {
        let PhotoRig {
            span,
            light_theta,
            camera,
            ..
        } = *self;
        if !(0.0..=180.0).contains(&span) {
            return Err(rig_error(
                spec,
                format!("span={span}: use 0 to 180 degrees"),
            ));
        }
        for (name, value) in [("light_theta", light_theta), ("camera", camera)] {
            if value.abs() + span / 2.0 > MAX_THETA_DEG {
                return Err(rig_error(
                    spec,
                    format!(
                        "|{name}| + span/2 = {} exceeds {MAX_THETA_DEG}°: the bent fiber \
                         would be seen too close to its axis; reduce {name} or span",
                        value.abs() + span / 2.0
                    ),
                ));
            }
        }
        Ok(())
    }

    /// Append the directions: for each light, the `views` pixels along the strip.
    fn push_angles(&self, out: &mut Vec<[f64; 4]>) {
        for k in 0..self.lights {
            let light_phi = -180.0 + 360.0 * (k + 1) as f64 / self.lights as f64;
            let light = unit_vector(self.light_theta, light_phi);
            for j in 0..self.views {
                let bend = photo_bend(j, self.views, self.span);
                let (ti, pi) = fiber_frame_direction(light, bend);
                // |θ_i − light_theta| ≤ |β| exactly; clamp away asin's rounding so the
                // documented bound (checked at parse time) holds to the last bit.
                let bound = self.light_theta.abs() + bend.abs();
                out.push([ti.clamp(-bound, bound), pi, self.camera + bend, 0.0]);
            }
        }
    }
}

impl fmt::Display for PhotoRig {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let PhotoRig {
            lights,
            views,
            span,
            light_theta,
            camera,
        } = self;
        write!(
            f,
            "photo:lights={lights}:views={views}:span={span}:light_theta={light_theta}:camera={camera}"
        )
    }
}

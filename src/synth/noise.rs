//! Noise models for synthetic measurements: parsing (`relative:0.02+outliers:0.01`), the seeded
//! noisy values, and the per-value σ each model implies.

use std::fmt;
use std::str::FromStr;

use super::random::{generator, normal, poisson, uniform, Stream};
use crate::error::{Error, Result};

/// Outlier factors are uniform in this range: a stray reflection or a saturated pixel, far
/// enough above the truth that a robust loss can tell it apart from Gaussian noise.
pub const OUTLIER_FACTOR: (f64, f64) = (3.0, 10.0);

/// Above this mean count a Poisson draw is replaced by its Gaussian limit (mean λ, variance λ):
/// the skewness left is 1/sqrt(λ) < 1e-6, and PTRS would lose precision in `k·ln λ − lnΓ(k+1)`.
const POISSON_GAUSSIAN_LIMIT: f64 = 1e12;

/// A combination of noise terms, each at most once; `none` is all `None`. With the clean value
/// ŷ (model × scale), a noisy value is
///
/// `y = P + r·ŷ·z₁ + f·z₂`, then multiplied by a factor in [3, 10] for an outlier sample,
///
/// where `P = Poisson(ŷ·N)/N` for `photon:N` (else ŷ), `r` = `relative`, `f` = `floor`, and
/// z₁, z₂ independent standard normals. The implied σ (written when any of photon, relative,
/// floor is present) is `sqrt(ŷ/N + (r·ŷ)² + f²)`; outliers are deliberately not in σ. An
/// outlier hits a whole sample (every channel), like a bad frame. A clean value of exactly 0
/// under photon or relative noise alone has σ = 0 (the value is exact), which the loader
/// rejects as a non-positive σ; add a `floor` to keep such samples.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Noise {
    /// `photon:N`: value·N is Poisson distributed (N counts at value 1).
    pub photon: Option<f64>,
    /// `relative:r`: Gaussian with σ = r·value.
    pub relative: Option<f64>,
    /// `floor:f`: additive Gaussian with σ = f.
    pub floor: Option<f64>,
    /// `outliers:p`: each sample is an outlier with probability p.
    pub outliers: Option<f64>,
}

/// Noisy values, their σ when the model implies one, and which samples became outliers.
#[derive(Debug, Clone, PartialEq)]
pub struct Noisy {
    /// Row-major like the input (`i * n_channels + c`).
    pub values: Vec<f64>,
    pub sigma: Option<Vec<f64>>,
    /// Sample indices (0-based, ascending) multiplied by an outlier factor.
    pub outliers: Vec<usize>,
}

impl Noise {
    /// Parse `none`, or terms `KIND:VALUE` joined by `+` (kinds: relative, photon, floor,
    /// outliers).
    pub fn parse(spec: &str) -> Result<Noise> {
        let err = |m: String| Error::Other(format!("--noise `{spec}`: {m}"));
        let mut noise = Noise::default();
        if spec.trim().eq_ignore_ascii_case("none") {
            return Ok(noise);
        }
        for term in spec.split('+').map(str::trim) {
            let Some((kind, value)) = term.split_once(':') else {
                return Err(err(format!(
                    "term `{term}` is not KIND:VALUE; write e.g. `relative:0.02`, `photon:1000`, \
                     `floor:1e-3`, `outliers:0.01` (joined by `+`), or `none`"
                )));
            };
            let kind = kind.trim().to_ascii_lowercase();
            let v: f64 = match value.trim().parse() {
                Ok(v) if f64::is_finite(v) => v,
                _ => return Err(err(format!("{kind}: `{value}` is not a finite number"))),
            };
            let (slot, valid, range) = match kind.as_str() {
                "relative" => (&mut noise.relative, v > 0.0, "> 0 (a fraction, 0.02 = 2%)"),
                "photon" => (&mut noise.photon, v > 0.0, "> 0 (counts at value 1)"),
                "floor" => (&mut noise.floor, v > 0.0, "> 0"),
                "outliers" => (
                    &mut noise.outliers,
                    v > 0.0 && v <= 1.0,
                    "in (0, 1] (a fraction of samples)",
                ),
                other => {
                    return Err(err(format!(
                        "unknown noise `{other}`: use relative, photon, floor, outliers or none"
                    )))
                }
            };
            if !valid {
                return Err(err(format!("{kind}:{v}: the value must be {range}")));
            }
            if slot.is_some() {
                return Err(err(format!("`{kind}` appears twice")));
            }
            *slot = Some(v);
        }
        Ok(noise)
    }

    /// True when no term is active.
    pub fn is_none(&self) -> bool {
        *self == Noise::default()
    }

    /// True when the model implies a known σ per value (photon, relative or floor present).
    pub fn implies_sigma(&self) -> bool {
        self.photon.is_some() || self.relative.is_some() || self.floor.is_some()
    }

    /// σ of a noisy value with clean value ŷ: `sqrt(ŷ/N + (r·ŷ)² + f²)` (see [`Noise`]).
    pub fn sigma(&self, clean: f64) -> f64 {
        let photon = self.photon.map_or(0.0, |n| clean / n);
        let relative = self.relative.map_or(0.0, |r| (r * clean).powi(2));
        let floor = self.floor.map_or(0.0, |f| f * f);
        (photon + relative + floor).sqrt()
    }

    /// Apply the noise to clean values (row-major, `n_channels` per sample, each ≥ 0 and
    /// finite) with the generators of `seed`: one stream per term, one draw per value, so a term's
    /// draws do not depend on which other terms are present.
    pub fn apply(&self, clean: &[f64], n_channels: usize, seed: u64) -> Noisy {
        let mut photon_rng = generator(seed, Stream::Photon);
        let mut relative_rng = generator(seed, Stream::Relative);
        let mut floor_rng = generator(seed, Stream::Floor);
        let values: Vec<f64> = clean
            .iter()
            .map(|&y| {
                let mut v = match self.photon {
                    Some(n) => photon_count(&mut photon_rng, y * n) / n,
                    None => y,
                };
                if let Some(r) = self.relative {
                    v += r * y * normal(&mut relative_rng);
                }
                if let Some(f) = self.floor {
                    v += f * normal(&mut floor_rng);
                }
                v
            })
            .collect();
        let sigma = self
            .implies_sigma()
            .then(|| clean.iter().map(|&y| self.sigma(y)).collect());
        let mut noisy = Noisy {
            values,
            sigma,
            outliers: Vec::new(),
        };
        if let Some(p) = self.outliers {
            let mut rng = generator(seed, Stream::Outliers);
            let n_samples = clean.len() / n_channels.max(1);
            for i in 0..n_samples {
                // Two draws per sample whatever the outcome, so sample i's fate depends on i only.
                let hit = uniform(&mut rng) < p;
                let (lo, hi) = OUTLIER_FACTOR;
                let factor = lo + (hi - lo) * uniform(&mut rng);
                if hit {
                    noisy.outliers.push(i);
                    for v in &mut noisy.values[i * n_channels..(i + 1) * n_channels] {
                        *v *= factor;
                    }
                }
            }
        }
        noisy
    }
}

impl Noise {
    /// An error when the noise made a value or σ that is not finite (e.g. `relative:1e308`
    /// overflows): the CSV would hold `inf`, which the loader then rejects row by row.
    pub fn check_finite(&self, noisy: &Noisy) -> Result<()> {
        let bad = |v: &[f64]| v.iter().position(|x| !x.is_finite());
        let found = bad(&noisy.values)
            .map(|i| ("value", i, noisy.values[i]))
            .or_else(|| {
                let s = noisy.sigma.as_deref()?;
                bad(s).map(|i| ("sigma", i, s[i]))
            });
        match found {
            None => Ok(()),
            Some((what, i, v)) => Err(Error::Other(format!(
                "--noise `{self}` makes a {what} of {v} (value {} of the dataset): the noise \
                 overflows; use smaller noise terms",
                i + 1
            ))),
        }
    }
}

/// A Poisson count with mean λ (Gaussian limit above [`POISSON_GAUSSIAN_LIMIT`]).
fn photon_count(rng: &mut impl rand_chacha::rand_core::RngCore, lambda: f64) -> f64 {
    if lambda > POISSON_GAUSSIAN_LIMIT {
        (lambda + lambda.sqrt() * normal(rng)).round()
    } else {
        poisson(rng, lambda)
    }
}

/// A number as plain decimals, or in exponent form where plain decimals would run to hundreds
/// of digits (`1e308`).
fn readable(v: f64) -> String {
    if v != 0.0 && !(1e-6..1e16).contains(&v.abs()) {
        format!("{v:e}")
    } else {
        format!("{v}")
    }
}

impl FromStr for Noise {
    type Err = Error;
    fn from_str(s: &str) -> Result<Noise> {
        Noise::parse(s)
    }
}

/// The canonical spec (`none`, or terms in the order photon, relative, floor, outliers).
impl fmt::Display for Noise {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let terms: Vec<String> = [
            ("photon", self.photon),
            ("relative", self.relative),
            ("floor", self.floor),
            ("outliers", self.outliers),
        ]
        .iter()
        .filter_map(|(k, v)| v.map(|v| format!("{k}:{}", readable(v))))
        .collect();
        if terms.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&terms.join("+"))
        }
    }
}

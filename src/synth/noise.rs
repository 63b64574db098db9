//! Noise models for synthetic measurements: parsing (`relative:0.02+outliers:0.01`), the seeded
//! noisy values, the per-value σ each model implies, and the kinds of outliers real rigs make
//! (spikes, dropouts, sign flips, baseline offsets).

use std::fmt;
use std::str::FromStr;

use super::random::{generator, normal, poisson, uniform, Stream};
use crate::error::{Error, Result};

/// Outlier factors are uniform in this range: a stray reflection or a saturated pixel, far
/// enough above the truth that a robust loss can tell it apart from Gaussian noise.
pub const OUTLIER_FACTOR: (f64, f64) = (3.0, 10.0);

/// What an outlier does to its sample (`outlier_kind:K` in `--noise`, or `hairfit synth
/// --outlier-kind K`); the magnitude is uniform in the kind's range ([`OutlierKind::default_range`],
/// or `outlier_range:LO..HI`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum OutlierKind {
    /// Multiplied by a factor in the range (a stray reflection, a saturated pixel).
    #[default]
    Spike,
    /// Multiplied by a remaining fraction in the range: a near-zero reading (a missed frame, a
    /// shutter that did not open).
    Dropout,
    /// Negated and scaled by the range (a lock-in phase or sign glitch): a negative reading.
    Sign,
    /// Shifted by ± the range × the channel's median clean value (a baseline jump): large
    /// relative to the dark samples, small at the peaks.
    Offset,
    /// Each outlier one of the four above with equal probability, at its default range (a
    /// given range applies to the spikes).
    Mixed,
}

impl OutlierKind {
    /// The magnitude range a kind uses when none is given.
    pub fn default_range(self) -> (f64, f64) {
        match self {
            OutlierKind::Spike | OutlierKind::Mixed => OUTLIER_FACTOR,
            OutlierKind::Dropout => (0.0, 0.01),
            OutlierKind::Sign => (1.0, 1.0),
            OutlierKind::Offset => (1.0, 10.0),
        }
    }

    fn name(self) -> &'static str {
        match self {
            OutlierKind::Spike => "spike",
            OutlierKind::Dropout => "dropout",
            OutlierKind::Sign => "sign",
            OutlierKind::Offset => "offset",
            OutlierKind::Mixed => "mixed",
        }
    }

    /// Whether `(lo, hi)` makes sense for this kind, and the rule when it does not.
    fn check_range(self, (lo, hi): (f64, f64)) -> std::result::Result<(), &'static str> {
        let ok = lo.is_finite()
            && hi.is_finite()
            && lo <= hi
            && match self {
                OutlierKind::Spike | OutlierKind::Mixed => lo >= 1.0,
                OutlierKind::Dropout => lo >= 0.0 && hi < 1.0,
                OutlierKind::Sign | OutlierKind::Offset => lo > 0.0,
            };
        if ok {
            return Ok(());
        }
        Err(match self {
            OutlierKind::Spike | OutlierKind::Mixed => {
                "a spike multiplies by LO..HI with 1 <= LO <= HI (default 3..10)"
            }
            OutlierKind::Dropout => {
                "a dropout keeps a fraction LO..HI of the value with 0 <= LO <= HI < 1 (default 0..0.01)"
            }
            OutlierKind::Sign => "a sign glitch negates and scales by LO..HI with 0 < LO <= HI (default 1..1)",
            OutlierKind::Offset => {
                "an offset adds ± LO..HI times the channel's median value with 0 < LO <= HI (default 1..10)"
            }
        })
    }
}

impl FromStr for OutlierKind {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let all = [
            OutlierKind::Spike,
            OutlierKind::Dropout,
            OutlierKind::Sign,
            OutlierKind::Offset,
            OutlierKind::Mixed,
        ];
        let t = s.trim().to_ascii_lowercase();
        all.into_iter().find(|k| k.name() == t).ok_or_else(|| {
            Error::Other(format!(
                "outlier kind `{s}`: use spike, dropout, sign, offset or mixed"
            ))
        })
    }
}

impl fmt::Display for OutlierKind {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(self.name())
    }
}

/// `--outlier-range LO..HI` (clap's parser; the kind's own rule is checked with the kind).
pub fn parse_outlier_range(text: &str) -> std::result::Result<(f64, f64), String> {
    parse_range(text).ok_or_else(|| format!("`{text}` is not LO..HI (e.g. 5..50)"))
}

/// `LO..HI` (or one number for both) as a range.
fn parse_range(text: &str) -> Option<(f64, f64)> {
    let (lo, hi) = match text.split_once("..") {
        Some((a, b)) => (a.trim().parse().ok()?, b.trim().parse().ok()?),
        None => {
            let v: f64 = text.trim().parse().ok()?;
            (v, v)
        }
    };
    Some((lo, hi))
}

/// Above this mean count a Poisson draw is replaced by its Gaussian limit (mean λ, variance λ):
/// the skewness left is 1/sqrt(λ) < 1e-6, and PTRS would lose precision in `k·ln λ − lnΓ(k+1)`.
const POISSON_GAUSSIAN_LIMIT: f64 = 1e12;

/// A combination of noise terms, each at most once; `none` is all `None`. With the clean value
/// ŷ (model × scale), a noisy value is
///
/// `y = P + r·ŷ·z₁ + f·z₂`, then, for an outlier sample, multiplied by a factor in [3, 10] (or
/// corrupted as its [`OutlierKind`] says),
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
    /// `outlier_kind:K`: what an outlier does (spikes by default).
    pub outlier_kind: OutlierKind,
    /// `outlier_range:LO..HI`: the outliers' magnitude range (the kind's default when `None`).
    pub outlier_range: Option<(f64, f64)>,
}

/// Noisy values, their σ when the model implies one, and which samples became outliers.
#[derive(Debug, Clone, PartialEq)]
pub struct Noisy {
    /// Row-major like the input (`i * n_channels + c`).
    pub values: Vec<f64>,
    pub sigma: Option<Vec<f64>>,
    /// Sample indices (0-based, ascending) made outliers.
    pub outliers: Vec<usize>,
}

impl Noise {
    /// Parse `none`, or terms `KIND:VALUE` joined by `+` (kinds: relative, photon, floor,
    /// outliers).
    pub fn parse(spec: &str) -> Result<Noise> {
        let err = |m: String| Error::Other(format!("--noise `{spec}`: {m}"));
        let mut noise = Noise::default();
        let mut kind_given = false;
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
            let kind = kind.trim().to_ascii_lowercase().replace('-', "_");
            if kind == "outlier_kind" {
                if kind_given {
                    return Err(err("`outlier_kind` appears twice".into()));
                }
                kind_given = true;
                noise.outlier_kind = value.parse()?;
                continue;
            }
            if kind == "outlier_range" {
                if noise.outlier_range.is_some() {
                    return Err(err("`outlier_range` appears twice".into()));
                }
                noise.outlier_range = Some(parse_range(value).ok_or_else(|| {
                    err(format!(
                        "outlier_range: `{value}` is not LO..HI (e.g. 5..50)"
                    ))
                })?);
                continue;
            }
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
                        "unknown noise `{other}`: use relative, photon, floor, outliers \
                         (with outlier_kind, outlier_range) or none"
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
        noise.check_outliers().map_err(err)?;
        Ok(noise)
    }

    /// Set the outliers' kind and range from `hairfit synth --outlier-kind/--outlier-range`
    /// (each at most once: in `--noise` or as an option).
    pub fn with_outlier_options(
        mut self,
        kind: Option<OutlierKind>,
        range: Option<(f64, f64)>,
    ) -> Result<Noise> {
        if let Some(k) = kind {
            if self.outlier_kind != OutlierKind::default() {
                return Err(Error::Other(
                    "--outlier-kind and --noise `outlier_kind:…` both given: give one".into(),
                ));
            }
            self.outlier_kind = k;
        }
        if let Some(r) = range {
            if self.outlier_range.is_some() {
                return Err(Error::Other(
                    "--outlier-range and --noise `outlier_range:…` both given: give one".into(),
                ));
            }
            self.outlier_range = Some(r);
        }
        self.check_outliers().map_err(Error::Other)?;
        Ok(self)
    }

    /// Kind and range need an outlier fraction, and the range must suit the kind.
    fn check_outliers(&self) -> std::result::Result<(), String> {
        let customised =
            self.outlier_kind != OutlierKind::default() || self.outlier_range.is_some();
        if customised && self.outliers.is_none() {
            return Err(
                "an outlier kind or range needs an outlier fraction: add `outliers:P` to --noise"
                    .into(),
            );
        }
        if let Some(r) = self.outlier_range {
            self.outlier_kind
                .check_range(r)
                .map_err(|rule| format!("outlier range {}..{}: {rule}", r.0, r.1))?;
        }
        Ok(())
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
            self.corrupt(&mut noisy, clean, n_channels, p, seed);
        }
        noisy
    }
}

impl Noise {
    /// Make each sample an outlier with probability `p` (every channel of it, like a bad frame).
    /// Spikes take two draws per sample whatever the outcome (the format of files made before
    /// other kinds existed); every other kind four (hit, magnitude, kind, sign), so sample i's
    /// fate depends on i only.
    fn corrupt(&self, noisy: &mut Noisy, clean: &[f64], n_channels: usize, p: f64, seed: u64) {
        let nc = n_channels.max(1);
        let mut rng = generator(seed, Stream::Outliers);
        let n_samples = clean.len() / nc;
        // Offsets are in units of each channel's median clean value.
        let medians: Vec<f64> = (0..nc)
            .map(|c| {
                let mut v: Vec<f64> = clean.iter().skip(c).step_by(nc).copied().collect();
                if v.is_empty() {
                    return 0.0;
                }
                let mid = v.len() / 2;
                *v.select_nth_unstable_by(mid, f64::total_cmp).1
            })
            .collect();
        let base = self.outlier_kind;
        for i in 0..n_samples {
            let hit = uniform(&mut rng) < p;
            let u = uniform(&mut rng);
            let (kind, negative) = if base == OutlierKind::Spike {
                (OutlierKind::Spike, false)
            } else {
                let pick = uniform(&mut rng);
                let negative = uniform(&mut rng) < 0.5;
                let kind = match base {
                    OutlierKind::Mixed => [
                        OutlierKind::Spike,
                        OutlierKind::Dropout,
                        OutlierKind::Sign,
                        OutlierKind::Offset,
                    ][((pick * 4.0) as usize).min(3)],
                    k => k,
                };
                (kind, negative)
            };
            if !hit {
                continue;
            }
            let (lo, hi) = match (
                kind == base || kind == OutlierKind::Spike,
                self.outlier_range,
            ) {
                (true, Some(r)) => r,
                _ => kind.default_range(),
            };
            let m = lo + (hi - lo) * u;
            noisy.outliers.push(i);
            for (c, v) in noisy.values[i * nc..(i + 1) * nc].iter_mut().enumerate() {
                *v = match kind {
                    OutlierKind::Spike | OutlierKind::Dropout | OutlierKind::Mixed => *v * m,
                    OutlierKind::Sign => -*v * m,
                    OutlierKind::Offset => *v + if negative { -m } else { m } * medians[c],
                };
            }
        }
    }

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

/// The canonical spec (`none`, or terms in the order photon, relative, floor, outliers,
/// outlier_kind, outlier_range; the last two only when not the default), which parses back to
/// the same noise.
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
        .chain(
            (self.outlier_kind != OutlierKind::default())
                .then(|| format!("outlier_kind:{}", self.outlier_kind)),
        )
        .chain(
            self.outlier_range
                .map(|(lo, hi)| format!("outlier_range:{}..{}", readable(lo), readable(hi))),
        )
        .collect();
        if terms.is_empty() {
            f.write_str("none")
        } else {
            f.write_str(&terms.join("+"))
        }
    }
}

//! The fit's settings as fit.json's `options` record them and the command line spells them:
//! the residual space, the robust loss and its scale, the global stage. Only their names live
//! here (parsing, display, serde); what each does is the fit's (`fit::loss`, `fit::problem`,
//! `fit::stages`).

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::Error;

/// Which loss `ρ` is applied to the squared residuals.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Loss {
    /// Least squares, `ρ(s) = s`.
    #[default]
    L2,
    /// `ρ(s) = s` for `s ≤ 1`, `2√s − 1` beyond.
    Huber,
    /// `ρ(s) = ln(1 + s)`.
    Cauchy,
    /// `ρ(s) = 2(√(1 + s) − 1)`.
    SoftL1,
}

impl FromStr for Loss {
    type Err = Error;
    /// The [`Display`](fmt::Display) name of a loss, in any case; `_` may stand for `-`.
    fn from_str(s: &str) -> Result<Self, Error> {
        let key = s.trim().to_ascii_lowercase();
        let canonical = key.replace('_', "-");
        Loss::ALL
            .into_iter()
            .find(|l| l.to_string() == canonical)
            .ok_or_else(|| {
                Error::Other(format!(
                    "unknown loss `{key}`: use l2, huber, cauchy or soft-l1"
                ))
            })
    }
}

impl fmt::Display for Loss {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            Loss::L2 => "l2",
            Loss::Huber => "huber",
            Loss::Cauchy => "cauchy",
            Loss::SoftL1 => "soft-l1",
        })
    }
}

/// `--loss-scale`: estimated from the residuals, or given.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub enum LossScale {
    /// [`Loss::tuning`] × the noise level the residuals show ([`noise_mad`]).
    #[default]
    Auto,
    /// This `C`, in normalised residual units.
    Fixed(f64),
}

impl FromStr for LossScale {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        let t = s.trim();
        if t.eq_ignore_ascii_case("auto") {
            return Ok(LossScale::Auto);
        }
        match t.parse::<f64>() {
            Ok(c) if c.is_finite() && c > 0.0 => Ok(LossScale::Fixed(c)),
            _ => Err(Error::Other(format!(
                "--loss-scale `{t}`: use auto or a positive number (normalised residual units)"
            ))),
        }
    }
}

impl fmt::Display for LossScale {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            LossScale::Auto => f.write_str("auto"),
            LossScale::Fixed(c) => write!(f, "{c}"),
        }
    }
}

/// Residual space.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum Space {
    /// `w (y − s·S)`.
    Linear,
    /// `w (ln y − ln s − ln S)`: radiance spans orders of magnitude, so relative errors matter.
    #[default]
    Log,
}

impl std::str::FromStr for Space {
    type Err = Error;
    /// The [`Display`](std::fmt::Display) name of a space, in any case.
    fn from_str(s: &str) -> Result<Self, Error> {
        let key = s.trim().to_ascii_lowercase();
        [Space::Linear, Space::Log]
            .into_iter()
            .find(|space| space.to_string() == key)
            .ok_or_else(|| Error::Other(format!("unknown space `{key}`: use `linear` or `log`")))
    }
}

impl std::fmt::Display for Space {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Space::Linear => "linear",
            Space::Log => "log",
        })
    }
}

/// Optional global stage between the multi-start and the polish.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "kebab-case")]
pub enum Global {
    #[default]
    None,
    /// argmin's Nelder–Mead on the subsample cost, from the best multi-start point.
    NelderMead,
    /// argmin's particle swarm on the subsample cost over the start box (seeded).
    Pso,
}

impl std::fmt::Display for Global {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            Global::None => "none",
            Global::NelderMead => "nelder-mead",
            Global::Pso => "pso",
        })
    }
}

impl std::str::FromStr for Global {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self, Error> {
        match s.trim().to_ascii_lowercase().as_str() {
            "none" => Ok(Global::None),
            "nelder-mead" | "neldermead" | "nm" => Ok(Global::NelderMead),
            "pso" => Ok(Global::Pso),
            other => Err(Error::Other(format!(
                "unknown global stage `{other}`: use none, pso or nelder-mead"
            ))),
        }
    }
}

//! The switches a command line sets for a family's model (`--lobes`, `--no-glints`,
//! `--no-eccentricity`, `--mode`): which lobes and effects are on, and Marschner's root mode.
//! Every family reads the switches it has (a family without glints ignores `glints`); fit.json's
//! `model` record holds them as [`ModelConfig`].

use std::fmt;
use std::str::FromStr;

use serde::{Deserialize, Serialize};

use crate::error::{Error, Result};

/// How the roots of the exit-angle map are found (MODEL.md "Root modes").
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, Default)]
#[serde(rename_all = "lowercase")]
pub enum RootMode {
    /// Marschner's cubic approximation of `γ_t` inside the exit-angle map.
    #[default]
    Cubic,
    /// Exact roots of `Φ(p, h)` to near machine precision.
    Exact,
}

impl FromStr for RootMode {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        match s.trim().to_ascii_lowercase().as_str() {
            "cubic" => Ok(RootMode::Cubic),
            "exact" => Ok(RootMode::Exact),
            other => Err(Error::Other(format!(
                "unknown root mode `{other}`: use `cubic` or `exact`"
            ))),
        }
    }
}

impl fmt::Display for RootMode {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str(match self {
            RootMode::Cubic => "cubic",
            RootMode::Exact => "exact",
        })
    }
}

/// Which lobes contribute to `S`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Lobes {
    pub r: bool,
    pub tt: bool,
    pub trt: bool,
}

impl Default for Lobes {
    fn default() -> Self {
        Lobes {
            r: true,
            tt: true,
            trt: true,
        }
    }
}

/// Lobes and effects switched on; disabled ones are not computed at all.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(default)]
pub struct Effects {
    pub lobes: Lobes,
    pub glints: bool,
    pub eccentricity: bool,
}

impl Default for Effects {
    fn default() -> Self {
        Effects {
            lobes: Lobes::default(),
            glints: true,
            eccentricity: true,
        }
    }
}

impl Effects {
    /// Parse a lobe list such as `"R,TT,TRT"` (case-insensitive); unknown names are an error.
    pub fn parse_lobes(list: &str) -> Result<Lobes> {
        let mut lobes = Lobes {
            r: false,
            tt: false,
            trt: false,
        };
        for item in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
            match item.to_ascii_uppercase().as_str() {
                "R" => lobes.r = true,
                "TT" => lobes.tt = true,
                "TRT" => lobes.trt = true,
                other => {
                    return Err(Error::Other(format!(
                    "unknown lobe `{other}` in `{list}`: use a comma-separated list of R, TT, TRT"
                )))
                }
            }
        }
        if !(lobes.r || lobes.tt || lobes.trt) {
            return Err(Error::Other(format!(
                "lobe list `{list}` is empty: name at least one of R, TT, TRT"
            )));
        }
        Ok(lobes)
    }
}

/// Root mode and effect switches for one evaluation.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(default)]
pub struct ModelConfig {
    pub mode: RootMode,
    pub effects: Effects,
}

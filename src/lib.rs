//! hairfit: fit the Marschner 2003 hair scattering model to measured or synthetic
//! fiber-scattering data.
//!
//! The crate is a library with a thin CLI (`src/main.rs`). Module map:
//! - [`model`]: the forward model of `MODEL.md` (one pure function per equation), generic over
//!   the number type so that forward-mode AD gives exact Jacobians.
//! - [`chiang`]: the Chiang 2016 model of `CHIANG.md` (pbrt-v4's hair BxDF as a whole-fibre S),
//!   generic over the number type like [`model`].
//! - [`family`]: the model families (`--model marschner|chiang`), a parameter file of either.
//! - [`compare`]: `hairfit compare`, both families fitted to the same data, side by side.
//! - [`params`]: the parameter file (`PARAMS.json`) with MODEL.md's names, and its validation.
//! - [`eval`]: `hairfit eval`, streaming angles in and scattering values out.
//! - [`export`]: `hairfit export`, renderer files (pbrt-v4, Blender, MaterialX) fitted to a fit's S.
//! - [`data`]: loading measured or synthetic samples, with a report of every rejected row.
//! - [`fit`]: least squares with exact Jacobians and uncertainties (`hairfit fit`, `demo`).
//! - [`cli`]: the command line's option groups, flag-worded checks and the fit summary.
//! - [`lm`]: Levenberg–Marquardt as an argmin `Solver`, and the covariance of its solution.
//! - [`synth`]: `hairfit synth`, synthetic datasets with known truth.
//! - [`plot`]: the plotting kit (chart set-up, scales, SVG + PNG rendering) of report and cost.
//! - [`report`]: `hairfit report`, plotted fit reports (SVG, PNG, offline index.html).
//! - [`rng`]: the seeded, platform-independent random-number generator.
//! - [`batch`]: `hairfit batch`, many fits from a manifest, sharded for a cluster's scheduler.
//! - [`outdir`]: output directories locked, staged and published as one set.
//! - [`cost`]: `hairfit cost`, the accuracy-vs-time ledger of every accuracy knob.
//! - [`files`]: every on-disk format (fit.json, curves.csv, truth.json, timing.json, the load
//!   report), one Serialize + Deserialize type each.
//! - [`error`]: the error type shared by the library.

pub mod atomic;
pub mod batch;
pub mod chiang;
pub mod cli;
pub mod compare;
pub mod cost;
pub mod data;
pub mod demo;
pub mod error;
pub mod eval;
pub mod export;
pub mod family;
pub mod files;
pub mod fit;
pub mod json_file;
pub mod lm;
pub mod model;
pub mod outdir;
pub mod params;
pub mod plot;
pub mod report;
pub mod rng;
pub mod slices;
pub mod synth;

pub use error::{Error, Result};

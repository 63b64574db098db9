//! hairfit: fit the Marschner 2003 hair scattering model to measured or synthetic
//! fiber-scattering data.
//!
//! The crate is a library with a thin CLI (`src/main.rs`). Module map:
//! - [`model`]: the forward model of `MODEL.md` (one pure function per equation), generic over
//!   the number type so that forward-mode AD gives exact Jacobians.
//! - [`params`]: the parameter file (`PARAMS.json`) with MODEL.md's names, and its validation.
//! - [`eval`]: `hairfit eval`, streaming angles in and scattering values out.
//! - [`data`]: loading measured or synthetic samples, with a report of every rejected row.
//! - [`fit`]: `hairfit fit` / `hairfit demo`: least squares with exact Jacobians and uncertainties.
//! - [`lm`]: Levenberg–Marquardt as an argmin `Solver`.
//! - [`nist`]: the NIST StRD nonlinear-regression suite the solver is validated on.
//! - [`synth`]: `hairfit synth`, synthetic datasets with known truth.
//! - [`report`]: `hairfit report`, plotted fit reports (SVG, PNG, offline index.html).
//! - [`cost`]: `hairfit cost`, the accuracy-vs-time ledger of every accuracy knob.
//! - [`files`]: every on-disk format (fit.json, curves.csv, truth.json, timing.json, the load
//!   report), one Serialize + Deserialize type each.
//! - [`error`]: the error type shared by the library.

pub mod atomic;
pub mod cli;
pub mod cost;
pub mod data;
pub mod error;
pub mod eval;
pub mod files;
pub mod fit;
pub mod lm;
pub mod model;
pub mod nist;
pub mod params;
pub mod report;
pub mod synth;

pub use error::{Error, Result};

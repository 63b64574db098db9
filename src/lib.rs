//! hairfit: fit hair scattering models (Marschner 2003, Chiang 2016 and the models real-time
//! renderers use; [`families::ModelFamily::ALL`] lists them) to measured or synthetic
//! fiber-scattering data.
//!
//! The crate is a library with a thin CLI (`src/main.rs`). Its modules form layers, lowest
//! first; a module imports only its own layer and those below (`tests/files/layering.rs` checks it,
//! docs/architecture.md describes it).
//!
//! Foundations:
//! - [`error`]: the error type shared by the library; [`atomic`]: atomic file output.
//! - [`json_file`]: JSON files read and written one way (errors at line and column).
//! - [`outdir`]: output directories locked, staged and published as one set.
//! - [`rng`]: the seeded, platform-independent random-number generator.
//! - [`lm`]: Levenberg–Marquardt as an argmin `Solver`, and the covariance of its solution.
//! - [`plot`]: the plotting kit (chart set-up, scales, SVG + PNG rendering) of report and cost.
//!
//! Model families ([`families`], one folder each):
//! - [`families::marschner`]: the forward model of `MODEL.md` (one pure function per equation),
//!   generic over the number type so that forward-mode AD gives exact Jacobians; its parameter
//!   file (`PARAMS.json`, [`families::marschner::params`]) and its fit adaptor.
//! - [`families::chiang`]: the Chiang 2016 model of `CHIANG.md` (pbrt-v4's hair BxDF as a
//!   whole-fibre S), generic over the number type like Marschner's.
//! - [`families::table`]: the machinery of the families given as a table of terms
//!   ([`families::kajiya_kay`], [`families::deon`], [`families::karis`], [`families::frostbite`]).
//! - [`families`] itself: every model family (`--model NAME`), and a parameter file of any of them.
//!
//! Files and samples:
//! - [`files`]: every result format (fit.json, curves.csv, truth.json, timing.json, the load
//!   report), one Serialize + Deserialize type each.
//! - [`data`]: loading measured or synthetic samples, with a report of every rejected row.
//! - [`slices`]: scan slices of a dataset and the summary curves a report draws.
//!
//! Fit and synthesis:
//! - [`fit`]: least squares with exact Jacobians and uncertainties; a model family is one type
//!   behind `fit::family::Family`.
//! - [`synth`]: synthetic datasets with known truth.
//! - [`trace`]: `hairfit trace`, a Monte Carlo ray tracer of one fibre: data no model made.
//! - [`eval`]: `hairfit eval`, streaming angles in and scattering values out.
//! - [`export`]: `hairfit export`, the files a renderer or engine loads ([`export::Target::all`]),
//!   fitted to a fit's S.
//!
//! Results:
//! - [`report`]: `hairfit report`, plotted fit reports (SVG, PNG, offline index.html), and
//!   publishing a fit with its report.
//! - [`compare`]: `hairfit compare`, several families fitted to the same data and ranked.
//! - [`demo`]: `hairfit demo`, a synthesized dataset fitted and reported.
//! - [`cost`]: `hairfit cost`, the accuracy-vs-time ledger of every accuracy knob.
//!
//! Commands:
//! - [`cli`]: the command line's option groups, flag-worded checks, the fit summary, and what
//!   `hairfit fit` and `hairfit synth` run, and the help's family and target lists.
//! - [`batch`]: `hairfit batch`, many fits from a manifest, sharded for a cluster's scheduler.

pub mod atomic;
pub mod batch;
pub mod cli;
pub mod compare;
pub mod cost;
pub mod data;
pub mod demo;
pub mod error;
pub mod eval;
pub mod export;
pub mod families;
pub mod files;
pub mod fit;
pub mod geometry;
pub mod json_file;
pub mod lm;
pub mod outdir;
pub mod plot;
pub mod report;
pub mod rng;
pub mod slices;
pub mod synth;
pub mod trace;

pub use error::{Error, Result};

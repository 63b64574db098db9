//! Helpers shared by the test binaries (each includes this module as `support`): running the
//! binary (`cli`), the LM solver and NIST problems (`lm`, `nist`, also used by benches/lm.rs),
//! and per-subject fixtures (`chiang`, `deon`, `model`, `fit`, `hard`, `export`). Each binary
//! uses a different subset.

#![allow(dead_code, unused_imports)]

pub mod chiang;
pub mod cli;
pub mod deon;
pub mod export;
pub mod fit;
pub mod hard;
pub mod lm;
pub mod model;
pub mod nist;

//! The model families: the battery every registered family runs (`battery`), and each
//! family's known values, invariants and derivatives against independent references.
//!
//! One test binary of four (cli, families, fit, files): each links the library once;
//! the former one-file binaries are its modules. Shared helpers: `tests/support/`.

#[path = "../support/mod.rs"]
mod support;

mod battery;
mod chiang_ad;
mod chiang_invariants;
mod chiang_known_values;
mod chiang_params;
mod chiang_quadrature;
mod deon_invariants;
mod deon_values;
mod eval_rows;
mod frostbite;
mod frostbite_table;
mod fuzz_params;
mod karis_model;
mod model_ad;
mod model_docs;
mod model_invariants;
mod model_known_values;
mod model_lanes;
mod model_params;
mod model_proptest;
mod table_families;
mod trace_physics;

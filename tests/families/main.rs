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
mod family_from_a_test;
mod frostbite_azimuthal;
mod frostbite_values;
mod karis_values;
mod marschner_ad;
mod marschner_docs;
mod marschner_invariants;
mod marschner_known_values;
mod marschner_lanes;
mod marschner_params;
mod marschner_params_fuzz;
mod marschner_proptest;
mod registry_docs;
mod table_families;
mod trace_physics;

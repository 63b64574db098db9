//! Fitting: the solver (NIST problems), the fit's stages, standard errors, verdicts and
//! recovery of synthetic truths, through the library and the binary.
//!
//! One test binary of four (cli, families, fit, files): each links the library once;
//! the former one-file binaries are its modules. Shared helpers: `tests/support/`.

#[path = "../support/mod.rs"]
mod support;

mod channels_memory;
mod cost_quick;
mod degenerate;
mod design_caveats;
mod hard_fit;
mod hard_jacobian;
mod hard_proptest;
mod hard_report;
mod honest;
mod jacobian;
mod linearize;
mod lm_solver;
mod measurement;
mod memo;
mod nist;
mod profile;
mod recovery;
mod robust;
mod shipped;
mod stages;
mod synth_noise;
mod synth_rigs;
mod verdict;

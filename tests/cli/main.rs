//! The command line as a user runs it: every subcommand through the built binary
//! (`CARGO_BIN_EXE_hairfit`), its errors, its files and how it stops.
//!
//! One test binary of four (cli, families, fit, files): each links the library once;
//! the former one-file binaries are its modules. Shared helpers: `tests/support/`.

#[path = "../support/mod.rs"]
mod support;

mod adversarial;
mod batch;
mod batch_rules;
mod chiang;
mod compare;
mod curves;
mod data;
mod deon;
mod docs_examples;
mod eval;
mod eval_guards;
mod export_failed;
mod fault_kill;
mod fit;
mod frostbite;
mod full_disk;
mod help_registries;
mod kajiya_kay;
mod karis;
mod outdir;
mod reliability_determinism;
mod reliability_files;
mod reliability_interrupt;
mod report;
mod report_reads_right;
mod synth;
mod synth_outlier_kinds;
mod synth_shipped;
mod trace;
mod units;

//! Files in and out: data loading (malformed and hostile input included), exports to
//! renderers, the report, and the source layering rules.
//!
//! One test binary of four (cli, families, fit, files): each links the library once;
//! the former one-file binaries are its modules. Shared helpers: `tests/support/`.

#[path = "../support/mod.rs"]
mod support;

mod data_fast_path;
mod data_load;
mod data_malformed;
mod export_blender;
mod export_formats;
mod export_materialx;
mod export_terms;
mod export_unity;
mod export_unreal;
mod file_kinds;
mod hostile_files;
mod layering;
mod report_render;

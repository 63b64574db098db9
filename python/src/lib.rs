//! `hairfit._native`: the Python extension module over the hairfit library (PyO3 + rust-numpy).
//!
//! Thin by design: every function parses its options with the command line's own clap types
//! (`ModelArgs`, `LoadOptions`, `FitArgs`, `SynthArgs`, `CompareArgs`, `ExportArgs`) from the
//! argument list `python/hairfit/__init__.py` builds out of keyword arguments, and then calls the
//! same library functions `src/main.rs` calls, so defaults, checks, values and error messages
//! are the CLI's. Work runs with the GIL released; fits and comparisons run on a worker thread
//! while the calling thread polls for Ctrl-C and, on one, sets the fit's cancel flag.
//!
//! The modules: `errors` (the exception, error text, warnings), `args` (option parsing),
//! `interrupt` (work off the GIL, interruptibly), `arrays` (angles and tables ⇄ NumPy),
//! `eval`, `load` (the `Data` class), `fit` (the `Fit` class), `commands` (synth, compare,
//! export) and `registry` (the families and export targets); this file registers what they
//! define.

mod args;
mod arrays;
mod commands;
mod errors;
mod eval;
mod fit;
mod interrupt;
mod load;
mod registry;

use pyo3::prelude::*;

use errors::HairfitError;

/// An allocation the system refuses (a memory limit) becomes `MemoryError` in the call that made
/// it, not an abort that kills the interpreter (see `interrupt`).
#[global_allocator]
static ALLOCATOR: hairfit::cli::oom::CancelOnOom = hairfit::cli::oom::CancelOnOom;

#[pymodule]
fn _native(m: &Bound<'_, PyModule>) -> PyResult<()> {
    hairfit::cli::oom::keep_ballast(interrupt::BALLAST);
    // The worker threads now, while there is room for their stacks: rayon panics at first use
    // when the system refuses them. Already built (another module started it) is fine.
    let _ = rayon::ThreadPoolBuilder::new().build_global();
    m.add("HairfitError", m.py().get_type::<HairfitError>())?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    m.add_class::<load::Data>()?;
    m.add_class::<fit::Fit>()?;
    m.add_function(wrap_pyfunction!(eval::eval, m)?)?;
    m.add_function(wrap_pyfunction!(eval::eval_columns, m)?)?;
    m.add_function(wrap_pyfunction!(load::load, m)?)?;
    m.add_function(wrap_pyfunction!(load::data_from_arrays, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit, m)?)?;
    m.add_function(wrap_pyfunction!(fit::fit_file, m)?)?;
    m.add_function(wrap_pyfunction!(commands::synth, m)?)?;
    m.add_function(wrap_pyfunction!(commands::compare, m)?)?;
    m.add_function(wrap_pyfunction!(commands::export, m)?)?;
    m.add_function(wrap_pyfunction!(registry::families, m)?)?;
    m.add_function(wrap_pyfunction!(registry::export_targets, m)?)?;
    Ok(())
}

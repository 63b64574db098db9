//! Running work off the GIL: interruptibly (a worker thread, Ctrl-C polled on the caller's), and
//! as `MemoryError` when the system refuses an allocation on the way (a memory limit), instead
//! of a dead interpreter (see `hairfit::cli::oom::CancelOnOom`, this extension's allocator).

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use hairfit::cli::oom;
use pyo3::exceptions::{PyMemoryError, PyRuntimeError};
use pyo3::prelude::*;

/// Address space set aside for the work to wind down in once the system refuses (given back at
/// the first refusal, taken again before the next call).
pub(crate) const BALLAST: usize = 64 << 20;

/// The refusal count before a call, once the ballast is set aside (again, after a refusal); a
/// `MemoryError` when the system refuses even that: too little is left to end a call cleanly.
fn start() -> PyResult<usize> {
    if !oom::keep_ballast(BALLAST) {
        return Err(PyMemoryError::new_err(format!(
            "hairfit: out of memory: less than {} of address space is left under the memory limit (ulimit -v, resource.RLIMIT_AS or a cgroup's), which hairfit keeps aside to end a call cleanly; nothing was done. Run with a higher limit, or free memory",
            hairfit::error::readable_bytes(BALLAST as u64)
        )));
    }
    Ok(oom::refusals())
}

/// `MemoryError` if the system refused an allocation since `before` ([`oom::refusals`]).
fn refused_since(before: usize) -> PyResult<()> {
    if oom::refusals() == before {
        return Ok(());
    }
    Err(PyMemoryError::new_err(format!(
        "hairfit: out of memory: the system refused {} (a memory limit: ulimit -v, \
         resource.RLIMIT_AS or a cgroup's); the call was abandoned and nothing it would have \
         written was published. Run with a higher limit, or on less data (fewer rows, fewer \
         channels)",
        hairfit::error::readable_bytes(oom::largest_refused() as u64)
    )))
}

/// Run `work` with the GIL released, the ballast set aside: an allocation the system refuses on
/// the way is served from it, so the work ends as it would have (whole, or with its own error).
pub(crate) fn off_gil<T: Send>(py: Python<'_>, work: impl FnOnce() -> T + Send) -> PyResult<T> {
    start()?;
    Ok(py.allow_threads(work))
}

/// Run `work` on a worker thread with the GIL released; every ~50 ms the calling thread checks
/// for signals. On Ctrl-C (or any exception a signal handler raises) the cancel flag is set, the
/// worker is waited for (a fit stops at its next iteration) and the exception is raised. The
/// allocator raises the same flag when the system refuses memory: then `MemoryError`.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> T + Send,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    let before = start()?;
    let _watch = oom::watch(&cancel);
    let value = std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let flag = cancel.clone();
        std::thread::Builder::new()
            .spawn_scoped(scope, move || {
                let _ = tx.send(work(flag));
            })
            .map_err(|e| {
                PyMemoryError::new_err(format!(
                    "hairfit: cannot start a worker thread ({e}): a memory limit (ulimit -v, \
                     resource.RLIMIT_AS or a cgroup's) leaves no room for its stack; run with a \
                     higher limit"
                ))
            })?;
        let mut rx = rx;
        loop {
            let (back, got) = py.allow_threads(move || {
                let got = rx.recv_timeout(Duration::from_millis(50));
                (rx, got)
            });
            rx = back;
            match got {
                Ok(value) => return Ok(value),
                Err(mpsc::RecvTimeoutError::Timeout) => {
                    if oom::refusals() != before {
                        cancel.store(true, Ordering::SeqCst);
                    }
                    if let Err(signal) = py.check_signals() {
                        cancel.store(true, Ordering::SeqCst);
                        let _ = py.allow_threads(move || rx.recv());
                        return Err(signal);
                    }
                }
                Err(mpsc::RecvTimeoutError::Disconnected) => {
                    return Err(PyRuntimeError::new_err(
                        "hairfit: the worker thread panicked (a bug: please report it)",
                    ))
                }
            }
        }
    })?;
    refused_since(before)?;
    Ok(value)
}

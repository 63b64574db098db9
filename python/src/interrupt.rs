//! Running work off the GIL, interruptibly: a worker thread, Ctrl-C polled on the caller's.

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{mpsc, Arc};
use std::time::Duration;

use pyo3::exceptions::PyRuntimeError;
use pyo3::prelude::*;

/// Run `work` on a worker thread with the GIL released; every ~50 ms the calling thread checks
/// for signals. On Ctrl-C (or any exception a signal handler raises) the cancel flag is set, the
/// worker is waited for (a fit stops at its next iteration) and the exception is raised.
pub(crate) fn interruptible<T: Send>(
    py: Python<'_>,
    work: impl FnOnce(Arc<AtomicBool>) -> T + Send,
) -> PyResult<T> {
    let cancel = Arc::new(AtomicBool::new(false));
    std::thread::scope(|scope| {
        let (tx, rx) = mpsc::channel();
        let flag = cancel.clone();
        scope.spawn(move || {
            let _ = tx.send(work(flag));
        });
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
    })
}

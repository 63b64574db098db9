//! How `hairfit` ends: the exit code of a fit from its verdict (and `--strict`), and the signal
//! handling that lets an interrupted fit write its best so far and then exit as the signal would
//! (128 + its number: 130 after SIGINT, 143 after SIGTERM).

use std::sync::atomic::{AtomicBool, AtomicI32, Ordering};
use std::sync::Arc;

use crate::files::Verdict;

/// `--help` text of the commands that fit (`fit`, `demo`, `batch`).
pub const EXIT_CODES_HELP: &str = "Verdicts (fit.json `verdict`, printed first): good (the model describes the data within \
their noise and every free parameter is determined), poor_fit (a goodness-of-fit test rejects the model: chi2 with a \
sigma column, else structure along scans, outliers or lack of fit against replicates), undetermined (a free parameter \
is not determined by the data), failed (the numbers are not a fit), interrupted (stopped by a signal; best so far).

Exit codes: 0 good, poor_fit or undetermined (a usable result with its reasons); 1 failed or an error; 2 a usage \
error (unknown option, bad value); 3 poor_fit or undetermined with --strict; 130 after SIGINT (Ctrl-C), 143 after SIGTERM (the best so far is written first). A second \
Ctrl-C exits at once.";

/// The exit code of a usable but not good fit under `--strict`: not 2, which clap gives a usage
/// error, so a script tells a mistyped command from a poor fit.
pub const STRICT_EXIT: u8 = 3;

/// The exit code of a finished fit with `verdict`; `signal` is the signal received, if one was.
/// The code follows what was published: a signal the fit acted on made its verdict
/// `interrupted` (128 + the signal); one that came after the fit had finished changed none of
/// its outputs, so the verdict's own code stands (a `good` fit never exits 130).
pub fn exit_code(verdict: Verdict, strict: bool, signal: Option<i32>) -> u8 {
    match verdict {
        Verdict::Good => 0,
        Verdict::PoorFit | Verdict::Undetermined if strict => STRICT_EXIT,
        Verdict::PoorFit | Verdict::Undetermined => 0,
        Verdict::Failed => 1,
        // Without a recorded signal (the flag set by a caller): as Ctrl-C.
        Verdict::Interrupted => signal.map_or(130, signal_exit_code),
    }
}

/// What `hairfit` tells the user when a signal came after the work it would have stopped had
/// finished: the outputs are complete and published, and the exit code is theirs.
pub fn late_signal_note(signal: Option<i32>, verdict: Verdict) -> Option<String> {
    let sig = signal?;
    (verdict != Verdict::Interrupted).then(|| {
        format!(
            "hairfit: note: {} came after the fit had finished: its outputs are complete and published (verdict {verdict}), so the exit code is the verdict's",
            signal_name(sig)
        )
    })
}

/// `SIGINT`, `SIGTERM`, … for the signals hairfit handles.
pub fn signal_name(signal: i32) -> String {
    match signal {
        2 => "SIGINT".into(),
        15 => "SIGTERM".into(),
        1 => "SIGHUP".into(),
        n => format!("signal {n}"),
    }
}

/// 128 + the signal's number, as a shell reports a process the signal ended.
pub fn signal_exit_code(signal: i32) -> u8 {
    u8::try_from(128 + signal).unwrap_or(130)
}

/// The stop request a fit polls: set by the first SIGINT/SIGTERM/SIGHUP, which is recorded.
#[derive(Debug, Clone)]
pub struct StopSignal {
    /// The flag every parallel solver run checks.
    pub flag: Arc<AtomicBool>,
    received: Arc<AtomicI32>,
}

impl StopSignal {
    /// The signal received so far, if any.
    pub fn received(&self) -> Option<i32> {
        match self.received.load(Ordering::SeqCst) {
            0 => None,
            s => Some(s),
        }
    }
}

/// Install the handler of a command that keeps its best so far: the first SIGINT, SIGTERM or
/// SIGHUP sets the flag (the fit stops at the next iteration and writes its result); a second
/// one removes partial files and exits at once with 128 + its number. signal-hook, not ctrlc:
/// ctrlc reports every signal alike, and the exit code must tell SIGINT (130) from SIGTERM (143).
pub fn stop_on_signal() -> StopSignal {
    let stop = StopSignal {
        flag: Arc::new(AtomicBool::new(false)),
        received: Arc::new(AtomicI32::new(0)),
    };
    let (flag, received) = (stop.flag.clone(), stop.received.clone());
    on_signals(move |sig| {
        if flag.swap(true, Ordering::SeqCst) {
            crate::atomic::stop_writing();
            crate::atomic::remove_in_flight();
            crate::outdir::remove_in_flight();
            std::process::exit(i32::from(signal_exit_code(sig)));
        }
        let _ = received.compare_exchange(0, sig, Ordering::SeqCst, Ordering::SeqCst);
    });
    stop
}

/// Install the handler of a command with no best-so-far to keep: remove the partial output's
/// temporary file, then exit as the signal would have.
pub fn exit_on_signal() {
    on_signals(|sig| {
        crate::atomic::stop_writing();
        crate::atomic::remove_in_flight();
        crate::outdir::remove_in_flight();
        std::process::exit(i32::from(signal_exit_code(sig)));
    });
}

/// A file-size limit (`ulimit -f`, `prlimit --fsize`) makes a write that crosses it fail with
/// "File too large" instead of killing the process with SIGXFSZ (call first thing in `main`):
/// the error path then removes the run's staging directory and temporary files and leaves what
/// `--out`/`--output` held, as for a full disk. Python ignores SIGXFSZ itself.
pub fn write_errors_not_signals() {
    // SAFETY: setting a signal's disposition to SIG_IGN touches no Rust state.
    unsafe {
        libc::signal(libc::SIGXFSZ, libc::SIG_IGN);
    }
}

/// Called by `main` before it exits: while a signal handler is removing the partial outputs, wait
/// for it to end the process with the signal's code. Without this, a writer that failed because
/// its staging directory was just removed could print that error and exit 1 first (seen under
/// load after a second Ctrl-C).
pub fn wait_for_signal_exit() {
    if crate::atomic::stopping() {
        loop {
            std::thread::sleep(std::time::Duration::from_millis(100));
        }
    }
}

/// Run `handle` on a dedicated thread for each SIGINT/SIGTERM/SIGHUP (not inside the signal
/// handler, so it may take locks and remove files).
fn on_signals(mut handle: impl FnMut(i32) + Send + 'static) {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    match signal_hook::iterator::Signals::new([SIGINT, SIGTERM, SIGHUP]) {
        Ok(mut signals) => {
            std::thread::spawn(move || {
                for sig in signals.forever() {
                    handle(sig);
                }
            });
        }
        Err(e) => super::tell(format_args!(
            "hairfit: warning: Ctrl-C will not stop cleanly: {e}"
        )),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn verdicts_map_to_documented_codes() {
        assert_eq!(exit_code(Verdict::Good, true, None), 0);
        assert_eq!(exit_code(Verdict::PoorFit, false, None), 0);
        assert_eq!(exit_code(Verdict::Undetermined, false, None), 0);
        assert_eq!(exit_code(Verdict::PoorFit, true, None), 3);
        assert_eq!(exit_code(Verdict::Undetermined, true, None), 3);
        assert_eq!(exit_code(Verdict::Failed, false, None), 1);
        assert_eq!(exit_code(Verdict::Interrupted, false, Some(2)), 130);
        assert_eq!(exit_code(Verdict::Interrupted, false, Some(15)), 143);
        assert_eq!(exit_code(Verdict::Interrupted, false, None), 130);
        // A signal after the fit had finished changed nothing published: the verdict's code.
        assert_eq!(exit_code(Verdict::Good, false, Some(15)), 0);
        assert_eq!(exit_code(Verdict::PoorFit, true, Some(2)), 3);
        assert!(late_signal_note(Some(2), Verdict::Good).is_some());
        assert!(late_signal_note(Some(2), Verdict::Interrupted).is_none());
    }
}

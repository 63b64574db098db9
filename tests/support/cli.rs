//! Running the `hairfit` binary from integration tests, the one way every test binary does it
//! (`crate::support::cli`).
//!
//! Every run is bounded ([`hairfit_within`]): a command that regresses into a hang fails its test
//! instead of hanging the suite. Commands run in the crate root, so shipped files are `data/…`.
#![allow(dead_code)] // each test crate uses a different subset

use std::path::{Path, PathBuf};
use std::process::{Child, Command, Output, Stdio};
use std::time::{Duration, Instant};

/// Longest any single command may run in the default suite before its test fails (generous:
/// the slowest fits take a few seconds on a loaded 2-core machine).
pub const DEFAULT_LIMIT: Duration = Duration::from_secs(180);

/// The crate root (where `data/` and `fits/` are).
pub fn root() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
}

/// A shipped dataset, `data/NAME`, as an absolute path.
pub fn shipped(name: &str) -> PathBuf {
    root().join("data").join(name)
}

/// The binary as a `Command` in the crate root, for tests that set the environment themselves.
pub fn hairfit_command(args: &[&str]) -> Command {
    let mut c = Command::new(env!("CARGO_BIN_EXE_hairfit"));
    c.args(args).current_dir(root());
    c
}

/// Start `command` with piped output and no input, for tests that act on the running process
/// (signals, locks); finish it with [`wait_within`].
pub fn spawn(mut command: Command) -> Child {
    command
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the hairfit binary starts")
}

/// Wait for `child` at most `limit`; one still running then is killed and the test fails naming
/// `what` (a hang is a bug, not a slow pass). Returns the output and the time waited.
pub fn wait_within(mut child: Child, limit: Duration, what: &str) -> (Output, Duration) {
    let start = Instant::now();
    // Drain the pipes on threads so a chatty child cannot block on a full pipe.
    let mut stdout = child.stdout.take().expect("stdout is piped");
    let mut stderr = child.stderr.take().expect("stderr is piped");
    let out_thread = std::thread::spawn(move || {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut stdout, &mut v).ok();
        v
    });
    let err_thread = std::thread::spawn(move || {
        let mut v = Vec::new();
        std::io::Read::read_to_end(&mut stderr, &mut v).ok();
        v
    });
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > limit {
            child.kill().ok();
            child.wait().ok();
            panic!("{what}: still running after {limit:?} (hang?)");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let elapsed = start.elapsed();
    let output = Output {
        status,
        stdout: out_thread.join().unwrap(),
        stderr: err_thread.join().unwrap(),
    };
    (output, elapsed)
}

/// Run `command`; kill it and fail the test after `limit`. Returns the output and the time.
pub fn run_within(command: Command, limit: Duration) -> (Output, Duration) {
    let what = format!("{command:?}");
    wait_within(spawn(command), limit, &what)
}

/// Run hairfit with `args`; kill it and fail after `limit`.
pub fn hairfit_within(limit: Duration, args: &[&str]) -> (Output, Duration) {
    run_within(hairfit_command(args), limit)
}

/// Run hairfit with `args` (bounded by [`DEFAULT_LIMIT`]), whatever its exit status.
pub fn hairfit(args: &[&str]) -> Output {
    hairfit_within(DEFAULT_LIMIT, args).0
}

/// Run hairfit with `args` and fail the test, showing stderr, unless it succeeds.
pub fn hairfit_ok(args: &[&str]) -> Output {
    succeeded(hairfit(args), args)
}

/// `out`, after failing the test (showing stderr) unless it exited 0.
pub fn succeeded(out: Output, args: &[&str]) -> Output {
    assert!(
        out.status.success(),
        "hairfit {args:?} failed ({:?}):\n{}",
        out.status.code(),
        stderr(&out)
    );
    out
}

pub fn stdout(out: &Output) -> String {
    String::from_utf8_lossy(&out.stdout).into_owned()
}

pub fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// The command failed with exit 1 (an error, not a signal or an abort) and a message containing
/// every `needle`.
pub fn assert_fails_with(out: &Output, needles: &[&str]) {
    let err = stderr(out);
    assert_eq!(out.status.code(), Some(1), "expected exit 1; stderr: {err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks `{n}`: {err}");
    }
}

/// The stderr of `out`, after failing the test unless it exited non-zero (for errors whose exit
/// code the test does not pin).
pub fn failed(out: &Output) -> String {
    assert!(
        !out.status.success(),
        "hairfit should have failed; stdout: {}",
        stdout(out)
    );
    stderr(out)
}

/// Write `content` to `dir/name` and return the path.
pub fn write(dir: &Path, name: &str, content: impl AsRef<[u8]>) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, content).unwrap();
    path
}

/// A path as a command-line argument.
pub fn s(p: &Path) -> &str {
    p.to_str().expect("test paths are UTF-8")
}

/// Every file under `dir` with its bytes, sorted: equal snapshots are the same set.
pub fn snapshot(dir: &Path) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for entry in std::fs::read_dir(&d).unwrap() {
            let path = entry.unwrap().path();
            if path.is_dir() {
                stack.push(path);
            } else {
                let rel = path.strip_prefix(dir).unwrap().display().to_string();
                out.push((rel, std::fs::read(&path).unwrap()));
            }
        }
    }
    out.sort();
    out
}

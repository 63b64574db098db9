//! Inputs and outputs whose path is not a plain file.
//!
//! - An output that is a link has the file it names replaced (the link stays); a device, FIFO or
//!   socket is written in place, never replaced. Renaming the temporary file over
//!   `--output /dev/null` used to turn `/dev/null` into a regular file (as root) and a FIFO into
//!   a file its reader never saw.
//! - `eval` reads its input from a pipe (`--input /dev/stdin`) once: the lines read for the unit
//!   line are read again in front of the rest (a second open used to swallow the header). The
//!   data loader reads a file more than once, so it refuses a pipe at once (it used to wait
//!   forever on a FIFO's second open).
//! - A reader that stops early (`eval … | head`) ends eval quietly with 141, not an error.
//!
//! The tests use FIFOs and links in a temporary directory, not `/dev/null`, so a regression
//! cannot damage the machine.

#![cfg(unix)]

use crate::support::cli;

use std::io::{Read, Write};
use std::os::unix::fs::FileTypeExt;
use std::path::{Path, PathBuf};
use std::process::Stdio;
use std::time::Duration;

use cli::{hairfit, hairfit_command, run_within, s, shipped, stderr, write};

const PARAMS: &str = r#"{"sigma_a": 0.4, "alpha_r_deg": -7, "beta_r_deg": 8, "k_g": 2,
  "w_c_deg": 15, "eccentricity": 0.9}"#;

fn mkfifo(path: &Path) {
    let name = std::ffi::CString::new(path.as_os_str().as_encoded_bytes()).unwrap();
    // SAFETY: a valid NUL-terminated path; mkfifo only creates the node.
    assert_eq!(unsafe { libc::mkfifo(name.as_ptr(), 0o644) }, 0, "mkfifo");
}

fn is_fifo(path: &Path) -> bool {
    std::fs::symlink_metadata(path).is_ok_and(|m| m.file_type().is_fifo())
}

/// Entries of `dir` other than the ones named: no temporary may stay behind.
fn others(dir: &Path, known: &[&str]) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !known.contains(&n.as_str()))
        .collect()
}

/// `hairfit eval` of the shipped example angles (parameters `dir/p.json`) into `output`.
fn eval_args(dir: &Path, output: &Path) -> Vec<String> {
    let params = dir.join("p.json");
    if !params.exists() {
        write(dir, "p.json", PARAMS);
    }
    let input = shipped("example_angles.csv");
    [
        "eval",
        "--params",
        s(&params),
        "--input",
        s(&input),
        "--output",
        s(output),
    ]
    .map(String::from)
    .to_vec()
}

fn eval_into(dir: &Path, output: &Path) -> std::process::Output {
    let args = eval_args(dir, output);
    hairfit(&args.iter().map(String::as_str).collect::<Vec<_>>())
}

fn reference(dir: &Path) -> Vec<u8> {
    let plain = dir.join("plain.csv");
    let out = eval_into(dir, &plain);
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::read(&plain).unwrap()
}

#[test]
fn a_fifo_output_is_written_in_place_and_stays_a_fifo() {
    let dir = tempfile::tempdir().unwrap();
    let expected = reference(dir.path());
    let fifo: PathBuf = dir.path().join("pipe.csv");
    mkfifo(&fifo);
    // The reader reports through a channel: if the FIFO were replaced, its open would never
    // return, and the test fails at the timeout below instead of hanging.
    let (sender, received) = std::sync::mpsc::channel();
    {
        let fifo = fifo.clone();
        std::thread::spawn(move || {
            let mut got = Vec::new();
            std::fs::File::open(&fifo)
                .unwrap()
                .read_to_end(&mut got)
                .unwrap();
            sender.send(got).unwrap();
        });
    }
    let args = eval_args(dir.path(), &fifo);
    let mut command = hairfit_command(&args.iter().map(String::as_str).collect::<Vec<_>>());
    command.env("RAYON_NUM_THREADS", "1");
    let (out, _) = run_within(command, Duration::from_secs(60));
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(is_fifo(&fifo), "the FIFO was replaced by a file");
    let got = received
        .recv_timeout(Duration::from_secs(30))
        .expect("the FIFO's reader got no end of file");
    assert_eq!(got, expected, "the reader got other bytes");
    assert_eq!(
        others(dir.path(), &["p.json", "plain.csv", "pipe.csv"]),
        Vec::<String>::new()
    );
}

#[test]
fn a_linked_output_replaces_the_file_the_link_names_and_keeps_the_link() {
    let dir = tempfile::tempdir().unwrap();
    let expected = reference(dir.path());
    let sub = dir.path().join("results");
    std::fs::create_dir(&sub).unwrap();
    let link = dir.path().join("latest.csv");
    // First a dangling link (the file it names is created), then a link to that file (replaced).
    std::os::unix::fs::symlink("results/eval.csv", &link).unwrap();
    for round in ["dangling", "existing"] {
        let out = eval_into(dir.path(), &link);
        assert!(out.status.success(), "{round}: {}", stderr(&out));
        let meta = std::fs::symlink_metadata(&link).unwrap();
        assert!(
            meta.file_type().is_symlink(),
            "{round}: the link was replaced"
        );
        assert_eq!(
            std::fs::read(sub.join("eval.csv")).unwrap(),
            expected,
            "{round}"
        );
        assert_eq!(others(&sub, &["eval.csv"]), Vec::<String>::new(), "{round}");
        assert_eq!(
            others(
                dir.path(),
                &["p.json", "plain.csv", "latest.csv", "results"]
            ),
            Vec::<String>::new(),
            "{round}"
        );
    }
}

#[test]
fn synth_refuses_a_fifo_output_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    let fifo = dir.path().join("pipe.csv");
    mkfifo(&fifo);
    let out = hairfit(&[
        "synth",
        "--params",
        s(&params),
        "--rig",
        "sphere:n=10",
        "--output",
        s(&fifo),
        "--seed",
        "1",
    ]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("pipe.csv") && err.contains("device, FIFO or socket"),
        "{err}"
    );
    assert!(is_fifo(&fifo));
    assert_eq!(
        others(dir.path(), &["p.json", "pipe.csv"]),
        Vec::<String>::new()
    );
}

#[test]
fn a_device_that_refuses_the_write_is_named_in_the_error() {
    let full = Path::new("/dev/full");
    let is_char_device =
        |p: &Path| std::fs::metadata(p).is_ok_and(|m| m.file_type().is_char_device());
    if !is_char_device(full) {
        eprintln!("skipped: no /dev/full on this machine");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    let out = eval_into(dir.path(), full);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("/dev/full") && err.contains("No space left"),
        "{err}"
    );
    assert!(is_char_device(full), "/dev/full was replaced");
}

/// Run eval with `input` written to its standard input (by a thread: the child may stop reading
/// early, so write errors are the child's to report) and `--input /dev/stdin`, then `extra`.
fn eval_from_pipe(dir: &Path, input: Vec<u8>, extra: &[&str]) -> std::process::Output {
    eval_from_stdin(dir, "/dev/stdin", input, extra)
}

/// [`eval_from_pipe`] with `--input name` (`/dev/stdin` or `-`).
fn eval_from_stdin(dir: &Path, name: &str, input: Vec<u8>, extra: &[&str]) -> std::process::Output {
    let params = write(dir, "p.json", PARAMS);
    let mut args = vec!["eval", "--params", s(&params), "--input", name];
    args.extend_from_slice(extra);
    let mut child = hairfit_command(&args)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the hairfit binary starts");
    let mut stdin = child.stdin.take().unwrap();
    std::thread::spawn(move || {
        let _ = stdin.write_all(&input);
    });
    cli::wait_within(child, Duration::from_secs(60), "eval from a pipe").0
}

#[test]
fn eval_reads_a_pipe_once_with_its_unit_line_and_header() {
    let dir = tempfile::tempdir().unwrap();
    // Radians, with a comment and the unit line before the header, rows enough for two of
    // eval's 1 MiB blocks.
    let mut text = String::from("# from a pipe\n# angles: rad\ntheta_i,phi_i,theta_r,phi_r\n");
    for k in 0..40_000 {
        let x = (k as f64 * 0.618_034).fract();
        text += &format!("{:.9},{:.9},{:.9},{:.9}\n", x - 0.5, 2.0 * x, 0.4 - x, -x);
    }
    let file = write(dir.path(), "rad.csv", &text);
    let params = write(dir.path(), "p.json", PARAMS);
    let expected = hairfit(&["eval", "--params", s(&params), "--input", s(&file)]);
    assert!(expected.status.success(), "{}", stderr(&expected));
    // `-` reads standard input as /dev/stdin does (and `--output -` is standard output).
    for (name, extra, shown) in [
        ("/dev/stdin", &[][..], "/dev/stdin"),
        ("-", &["--output", "-"][..], "<stdin>"),
    ] {
        let piped = eval_from_stdin(dir.path(), name, text.clone().into_bytes(), extra);
        assert!(piped.status.success(), "{name}: {}", stderr(&piped));
        assert!(piped.stdout.starts_with(b"# angles: rad\ntheta_i,"));
        assert_eq!(piped.stdout.len(), expected.stdout.len(), "{name}");
        assert!(
            piped.stdout == expected.stdout,
            "{name}: the pipe's output differs"
        );
        assert_eq!(stderr(&piped), "", "{name}");
        // The unit line read from the pipe still meets --angles.
        let unit = "# angles: rad\ntheta_i,phi_i,theta_r,phi_r\n0.1,0.2,0.3,0.4\n";
        let conflict = eval_from_stdin(dir.path(), name, unit.into(), &["--angles", "deg"]);
        assert!(!conflict.status.success());
        let err = stderr(&conflict);
        assert!(err.contains(&format!("{shown}:1:1")), "{name}: {err}");
    }
    assert!(!Path::new("-").exists() && !cli::root().join("-").exists());
}

#[test]
fn eval_refuses_a_pipe_whose_comments_never_end() {
    let dir = tempfile::tempdir().unwrap();
    // 17 MiB of comment lines and no header: kept for a second reading, they would grow
    // without bound; the limit is 16 MiB.
    let line = format!("#{}\n", "x".repeat(1022)); // 1 KiB a line
    let input = line.repeat(17 << 10).into_bytes();
    let out = eval_from_pipe(dir.path(), input, &[]);
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("/dev/stdin:16385:1") && err.contains("16 MiB") && err.contains("save it"),
        "{err}"
    );
}

#[test]
fn the_loader_refuses_a_pipe_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let fifo = dir.path().join("data.csv");
    mkfifo(&fifo);
    // No writer ever opens the FIFO: a loader that opened it would wait forever.
    let (out, _) = run_within(
        hairfit_command(&["fit", s(&fifo), "--out", s(&dir.path().join("fit"))]),
        Duration::from_secs(60),
    );
    assert!(!out.status.success());
    let err = stderr(&out);
    assert!(
        err.contains("data.csv")
            && err.contains("is a pipe or a device")
            && err.contains("> data.csv"),
        "{err}"
    );
    assert!(!dir.path().join("fit").exists());
}

/// `hairfit eval … | head`: when the reader stops early, eval ends quietly with the code of a
/// process SIGPIPE ended (141), as `cat` would, not with "error: Broken pipe".
#[test]
fn a_reader_that_stops_early_ends_eval_quietly() {
    let dir = tempfile::tempdir().unwrap();
    let params = write(dir.path(), "p.json", PARAMS);
    // 200k rows make ~11 MB of output: far more than a pipe holds.
    let mut text = String::from("theta_i,phi_i,theta_r,phi_r\n");
    for k in 0..200_000 {
        let x = (k as f64 * 0.618_034).fract();
        text += &format!(
            "{:.6},{:.6},{:.6},{:.6}\n",
            80.0 * x - 40.0,
            300.0 * x,
            20.0 - 40.0 * x,
            -90.0 * x
        );
    }
    let input = write(dir.path(), "a.csv", &text);
    let mut child = hairfit_command(&["eval", "--params", s(&params), "--input", s(&input)])
        .stdin(Stdio::null())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("the hairfit binary starts");
    let mut stdout = child.stdout.take().unwrap();
    let mut head = [0u8; 100];
    stdout.read_exact(&mut head).unwrap();
    assert!(head.starts_with(b"theta_i,phi_i,theta_r,phi_r,s\n"));
    drop(stdout);
    let (status, err) = wait_quiet(child, "eval into a closed pipe");
    assert_eq!((status.code(), err.as_str()), (Some(141), ""));
}

/// A command whose summary goes to a reader that has already gone (`hairfit load … | true`)
/// ends quietly with 141 too: `print!` used to panic there ("failed printing to stdout").
#[test]
fn a_summary_for_a_reader_that_has_gone_ends_quietly() {
    let (reader, writer) = std::io::pipe().unwrap();
    drop(reader);
    let data = shipped("azimuthal_rgb.csv");
    let child = hairfit_command(&["load", s(&data)])
        .stdin(Stdio::null())
        .stdout(Stdio::from(writer))
        .stderr(Stdio::piped())
        .spawn()
        .expect("the hairfit binary starts");
    let (status, err) = wait_quiet(child, "load into a closed pipe");
    assert_eq!((status.code(), err.as_str()), (Some(141), ""));
}

/// Messages to a stderr whose reader has gone (`hairfit … 2>&1 | true`) are dropped, and the
/// exit code still tells: `eprintln!` used to panic there, so a failed run exited 101 and a
/// finished one too.
#[test]
fn messages_to_a_stderr_that_has_gone_keep_the_exit_code() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("out.csv");
    // Finished: "evaluated 180 rows into …" goes to stderr.
    let finished = eval_args(dir.path(), &output);
    // Failed: the error message goes to stderr.
    let mut failed = finished.clone();
    let input = failed.iter().position(|a| a == "--input").unwrap() + 1;
    failed[input] = s(&dir.path().join("missing.csv")).to_string();
    for (args, code) in [(finished, 0), (failed, 1)] {
        let (reader, writer) = std::io::pipe().unwrap();
        drop(reader);
        let args: Vec<&str> = args.iter().map(String::as_str).collect();
        let status = hairfit_command(&args)
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::from(writer))
            .status()
            .expect("the hairfit binary starts");
        assert_eq!(status.code(), Some(code), "{args:?}");
    }
    let written = std::fs::read_to_string(&output).unwrap();
    let input = std::fs::read_to_string(shipped("example_angles.csv")).unwrap();
    assert_eq!(written.lines().count(), input.lines().count(), "{written}");
    assert!(
        written.starts_with("theta_i,phi_i,theta_r,phi_r,s\n-30,0,35,-170,"),
        "{written}"
    );
}

/// Wait at most 60 s for `child` (its stdout not piped to the test), then its stderr.
fn wait_quiet(mut child: std::process::Child, what: &str) -> (std::process::ExitStatus, String) {
    let mut errors = child.stderr.take().unwrap();
    let start = std::time::Instant::now();
    let status = loop {
        if let Some(status) = child.try_wait().unwrap() {
            break status;
        }
        if start.elapsed() > Duration::from_secs(60) {
            child.kill().unwrap();
            panic!("{what}: still running after 60 s");
        }
        std::thread::sleep(Duration::from_millis(10));
    };
    let mut err = String::new();
    errors.read_to_string(&mut err).unwrap();
    (status, err)
}

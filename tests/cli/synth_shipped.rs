//! The datasets shipped in `data/` are exactly what the commands in `data/README.md` make: every
//! `hairfit synth` line there is rerun into a temporary directory and must give the same CSV
//! bytes and the same truth file, and every shipped synthetic CSV (one with a truth sidecar)
//! must have its line.

use crate::support::cli;

use cli::root;
use std::path::Path;
use std::process::Command;

use hairfit::synth::Truth;

/// The `hairfit synth ...` lines of data/README.md.
fn documented_commands() -> Vec<String> {
    let readme = std::fs::read_to_string(root().join("data/README.md")).unwrap();
    readme
        .lines()
        .filter(|l| l.starts_with("hairfit synth "))
        .map(str::to_string)
        .collect()
}

fn output_of(args: &[&str]) -> String {
    let k = args
        .iter()
        .position(|a| *a == "--output")
        .expect("--output");
    args[k + 1].to_string()
}

#[test]
fn every_documented_command_reproduces_its_shipped_files() {
    let commands = documented_commands();
    assert!(commands.len() >= 5, "expected the five documented datasets");
    let tmp = tempfile::tempdir().unwrap();
    for line in &commands {
        // The commands use no quoting, so whitespace splitting is the shell's splitting.
        let args: Vec<&str> = line.split_whitespace().skip(1).collect();
        let shipped = output_of(&args);
        let fresh = tmp.path().join(Path::new(&shipped).file_name().unwrap());
        let mut rerun: Vec<String> = args.iter().map(|s| s.to_string()).collect();
        let k = rerun.iter().position(|a| a == "--output").unwrap();
        rerun[k + 1] = fresh.to_str().unwrap().to_string();
        let rerun: Vec<&str> = rerun.iter().map(String::as_str).collect();
        cli::hairfit_ok(&rerun);
        let want = std::fs::read(root().join(&shipped)).unwrap();
        let got = std::fs::read(&fresh).unwrap();
        assert!(
            want == got,
            "{shipped} differs from what `{line}` makes now: regenerate the data (see \
             data/README.md) if the change is deliberate"
        );
        let want_truth = Truth::load(&root().join(&shipped).with_extension("truth.json")).unwrap();
        let mut got_truth = Truth::load(&fresh.with_extension("truth.json")).unwrap();
        // The shipped truth records the documented line itself; the rerun differs only in
        // --output.
        assert_eq!(want_truth.command_line.as_deref(), Some(line.as_str()));
        got_truth.command_line = want_truth.command_line.clone();
        assert_eq!(want_truth, got_truth, "{shipped}");
    }
}

#[test]
fn every_shipped_synthetic_csv_is_documented() {
    let documented: Vec<String> = documented_commands()
        .iter()
        .map(|l| output_of(&l.split_whitespace().collect::<Vec<_>>()))
        .collect();
    // A shipped CSV is synthetic when it has a truth sidecar (measured data would not).
    let mut synthetic = 0;
    for entry in std::fs::read_dir(root().join("data")).unwrap() {
        let path = entry.unwrap().path();
        let name = path.file_name().unwrap().to_str().unwrap().to_string();
        if let Some(stem) = name.strip_suffix(".truth.json") {
            synthetic += 1;
            let rel = format!("data/{stem}.csv");
            assert!(
                documented.contains(&rel),
                "{rel} has no command in data/README.md"
            );
            assert!(root().join(&rel).exists(), "{name} has no {rel}");
        }
    }
    assert_eq!(synthetic, documented.len());
}

#[test]
fn shipped_data_cover_both_channel_counts_and_every_rig() {
    let mut rigs = Vec::new();
    let mut channels = Vec::new();
    for line in documented_commands() {
        let args: Vec<&str> = line.split_whitespace().collect();
        let truth =
            Truth::load(&root().join(output_of(&args)).with_extension("truth.json")).unwrap();
        rigs.push(truth.rig.split(':').next().unwrap().to_string());
        channels.push(truth.channels.len());
    }
    for rig in ["azimuthal", "longitudinal", "sphere", "photo"] {
        assert!(rigs.iter().any(|r| r == rig), "no {rig} dataset");
    }
    assert!(channels.contains(&1) && channels.contains(&3));
    // "Keep it small": the whole data/ directory stays under 400 KB.
    let total: u64 = std::fs::read_dir(root().join("data"))
        .unwrap()
        .map(|e| e.unwrap().metadata().unwrap().len())
        .sum();
    assert!(total < 400_000, "data/ is {total} bytes");
}

/// `data/scan_example.txt` is `data/scan_example.csv` rewritten by the documented awk script:
/// rerun it and compare the bytes (the CSV itself is checked with the other synth lines).
#[test]
fn the_scan_example_is_its_documented_rewrite_of_the_synthetic_csv() {
    let readme = std::fs::read_to_string(root().join("data/README.md")).unwrap();
    let line = "awk -f data/scan_example.awk data/scan_example.csv > data/scan_example.txt";
    assert!(
        readme.contains(line),
        "data/README.md lost the command `{line}`"
    );
    let out = Command::new("awk")
        .args(["-f", "data/scan_example.awk", "data/scan_example.csv"])
        .current_dir(root())
        .output()
        .expect("awk runs (POSIX)");
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let shipped = std::fs::read(root().join("data/scan_example.txt")).unwrap();
    assert!(
        out.stdout == shipped,
        "data/scan_example.txt differs from what the awk command makes: regenerate it"
    );
}

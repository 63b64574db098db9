//! The `hairfit` command line: parses arguments and calls the library.
//!
//! Each subcommand is one `Command` variant holding its clap `Args` and one match arm in `run`
//! that calls the library.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

use hairfit::cli::exit::exit_code;
use hairfit::cli::ModelArgs;
use hairfit::eval::{eval_file, output_columns, EvalRequest};
use hairfit::families::{FamilyModel, FamilyParams};
use hairfit::files::Verdict;

/// `eprintln!` without its panic when stderr has gone: see [`hairfit::cli::tell`].
macro_rules! tell {
    ($($arg:tt)*) => {
        hairfit::cli::tell(format_args!($($arg)*))
    };
}

#[derive(Parser)]
// `about`, the family lists and the export targets are filled in from the registries the code
// uses (hairfit::cli::help), so they cannot go stale.
#[command(name = "hairfit", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate S at every row of an angles CSV (theta_i,phi_i,theta_r,phi_r; degrees unless --angles rad or `# angles: rad`).
    Eval(EvalArgs),
    /// Load a data file and report what happened to every row (accepted or why rejected).
    Load(LoadArgs),
    /// Fit the model to a data file; writes fit.json, params.json and curves.csv into --out.
    #[command(after_help = hairfit::cli::exit::EXIT_CODES_HELP)]
    Fit(hairfit::cli::fit::FitCommandArgs),
    /// Fit every item of a manifest (or one shard of it) into --out/NAME; --merge summarises.
    Batch(BatchArgs),
    /// Synthesize a realistic 3-channel dataset, fit it and write data, fit and report to --out.
    #[command(after_help = hairfit::cli::exit::EXIT_CODES_HELP)]
    Demo(DemoArgs),
    /// Synthesize a dataset from known parameters: a rig's directions, the model, seeded noise.
    Synth(hairfit::cli::synth::SynthArgs),
    /// Trace a physical fibre (Monte Carlo light transport) at a rig's directions: data that
    /// no model made, written like `synth`'s (docs/trace.md).
    Trace(hairfit::cli::trace::TraceArgs),
    /// Plot a fit: SVG/PNG figures and an offline index.html in the fit's directory.
    Report {
        /// The fit's directory (holds fit.json and curves.csv, written by `hairfit fit`).
        dir: PathBuf,
        /// Linear instead of logarithmic value axes.
        #[arg(long)]
        linear: bool,
    },
    /// Write what a renderer or engine loads from a fit (the targets: hairfit::cli::help).
    Export(hairfit::cli::export::ExportArgs),
    /// Measure what each accuracy knob costs on this machine: cost.csv, cost.json, cost.svg/png.
    Cost {
        /// Fewer angles, shorter timings, fewer fit variants (under a minute on 2 cores).
        #[arg(long)]
        quick: bool,
        /// Write into a directory hairfit did not mark that holds other files (they are kept).
        #[arg(long)]
        force: bool,
        /// Output directory (the default is untracked; scripts/regenerate-fits.sh rewrites the
        /// committed fits/cost).
        #[arg(long, default_value = "fits/my-cost")]
        out: PathBuf,
        /// `marschner`: its accuracy knobs; `chiang`: its width rule; another family: no knobs of
        /// its own. Every run ends with every family's cost (samples/s/core) side by side.
        #[arg(long = "model", value_enum, default_value_t = hairfit::families::ModelFamily::default())]
        family: hairfit::families::ModelFamily,
    },
    /// Fit several model families to the same data and rank them (hairfit::cli::help).
    Compare(hairfit::cli::compare::CompareArgs),
}

#[derive(clap::Args)]
#[command(
    after_help = "The manifest is a CSV with the header `name,data` and then optional columns named after \
`hairfit fit` options without their dashes (e.g. loss,mode,fix; repeat values with `;`), or a JSON array of \
objects with the same keys. Data paths are relative to the manifest. Item NAME is written to --out/NAME exactly \
as `hairfit fit DATA --out DIR/NAME` would. --out must be a new or empty directory, or one `hairfit batch` made; \
merge never replaces a summary.csv or index.html it did not write. Items already finished with the same options \
and the same, unchanged data file (size and modification time) are skipped; items that failed or were \
interrupted run again; --force runs every item again.

\
Exit codes: 0 all items ran; 1 an item failed or its verdict is `failed` (the others still ran; the failed ones are \
named) or, with --merge, an item is missing, failed or interrupted (summary.csv and index.html are still written); \
2 a usage error; 3 with --strict when an item's verdict is poor_fit or undetermined; 130 after SIGINT, 143 after SIGTERM."
)]
struct BatchArgs {
    /// Manifest (CSV `name,data,OPTION…`, or .json).
    manifest: PathBuf,
    /// Output directory: each item goes to DIR/NAME.
    #[arg(long)]
    out: PathBuf,
    /// Run only shard K of N (0-based K, items K, K+N, K+2N, …), or `auto` from Slurm
    /// (SLURM_ARRAY_TASK_ID/COUNT) or a Kubernetes Indexed Job (JOB_COMPLETION_INDEX with
    /// HAIRFIT_SHARD_COUNT).
    #[arg(long, conflicts_with = "merge")]
    shard: Option<String>,
    /// Do not fit: write DIR/summary.csv and DIR/index.html from the items' fit.json files.
    #[arg(long)]
    merge: bool,
    /// Exit 3 when an item's verdict is poor_fit or undetermined (with --merge: any item's);
    /// every item is fitted as `hairfit fit --strict` would.
    #[arg(long)]
    strict: bool,
    /// Fit every item of the shard again, even those already finished.
    #[arg(long, conflicts_with = "merge")]
    force: bool,
}

#[derive(clap::Args)]
struct DemoArgs {
    #[command(flatten)]
    fit: hairfit::cli::fit::FitArgs,
    /// Output directory (the default is untracked; scripts/regenerate-fits.sh rewrites the
    /// committed fits/demo).
    #[arg(long, default_value = "fits/my-demo")]
    out: PathBuf,
}

#[derive(clap::Args)]
struct EvalArgs {
    /// Parameter file (JSON, docs/model.md's names; docs/chiang.md's with --model chiang), e.g. a fit's
    /// params.json (not its fit.json).
    #[arg(long)]
    params: PathBuf,
    /// Angles CSV with a header (`-`: standard input); other columns are carried through.
    #[arg(long)]
    input: PathBuf,
    /// Output CSV file (written atomically; never --input or --params); stdout when absent or `-`.
    #[arg(long)]
    output: Option<PathBuf>,
    #[command(flatten)]
    model: ModelArgs,
    /// Unit of the input's angles [default: deg, or what a `# angles: rad` line says].
    #[arg(long, value_enum)]
    angles: Option<hairfit::data::AngleUnit>,
}

#[derive(clap::Args)]
struct LoadArgs {
    /// Data file (.csv with a header, .json, or a headerless scan with --columns).
    file: PathBuf,
    #[command(flatten)]
    options: hairfit::data::LoadOptions,
    /// Print the report as JSON instead of a summary.
    #[arg(long)]
    json: bool,
}

/// An allocation the system refuses ends the run as an error (exit 1), not an abort.
#[global_allocator]
static ALLOCATOR: hairfit::cli::oom::ExitOnOom = hairfit::cli::oom::ExitOnOom;

fn main() -> ExitCode {
    hairfit::cli::oom::set_aside();
    hairfit::cli::exit::write_errors_not_signals();
    let command = hairfit::cli::help::with_registries(Cli::command());
    let cli = Cli::from_arg_matches(&command.get_matches()).unwrap_or_else(|e| e.exit());
    if let Err(e) = start_worker_threads() {
        tell!("hairfit: error: {e}");
        return ExitCode::FAILURE;
    }
    let result = run(cli);
    hairfit::cli::exit::wait_for_signal_exit();
    match result {
        Ok(code) => ExitCode::from(code),
        // The reader stopped early (`hairfit eval … | head`): end quietly, with the code of a
        // process SIGPIPE ended (128 + 13), as `cat` would.
        Err(err) if is_broken_pipe(&err) => ExitCode::from(141),
        Err(err) => {
            tell!("hairfit: error: {}", error_text(&err));
            ExitCode::FAILURE
        }
    }
}

/// Start the worker threads now: rayon would panic at their first use when the system refuses
/// them (a memory limit leaves no room for their stacks). One thread is tried before giving up.
fn start_worker_threads() -> Result<(), String> {
    let first = match rayon::ThreadPoolBuilder::new().build_global() {
        Ok(()) => return Ok(()),
        Err(e) => e,
    };
    rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build_global()
        .map_err(|_| {
            format!(
                "cannot start a worker thread ({first}): a memory limit (ulimit -v, prlimit --as \
                 or a cgroup's) leaves no room for its stack; run with a higher limit"
            )
        })
}

/// Write `text` to stdout. `print!` would panic when the reader has gone (`hairfit fit … | true`);
/// this returns the error, which main ends quietly on (see [`is_broken_pipe`]).
fn say(text: impl AsRef<str>) -> anyhow::Result<()> {
    use std::io::Write as _;
    let mut out = std::io::stdout().lock();
    out.write_all(text.as_ref().as_bytes())
        .and_then(|()| out.flush())
        .map_err(|e| hairfit::Error::io("<stdout>", e))?;
    Ok(())
}

/// Whether writing failed because the output's reader went away.
fn is_broken_pipe(err: &anyhow::Error) -> bool {
    err.chain().any(|cause| {
        cause
            .downcast_ref::<std::io::Error>()
            .is_some_and(|e| e.kind() == std::io::ErrorKind::BrokenPipe)
    })
}

/// The error and its causes joined by `: `, each said once: a library error that already quotes
/// its cause (`path: File exists (os error 17)`) would otherwise print the cause twice.
fn error_text(err: &anyhow::Error) -> String {
    let mut text = String::new();
    for cause in err.chain() {
        let part = cause.to_string();
        if text.ends_with(&part) {
            continue;
        }
        if !text.is_empty() {
            text.push_str(": ");
        }
        text.push_str(&part);
    }
    text
}

/// Run the command; its exit code (a fit's follows its verdict, [`hairfit::cli::exit`]).
fn run(cli: Cli) -> anyhow::Result<u8> {
    match cli.command {
        Command::Eval(args) => {
            remove_partial_output_on_interrupt();
            args.model.check_family_options()?;
            if let Some(out) = &args.output {
                hairfit::atomic::refuse_replacing_inputs(
                    "--output",
                    out,
                    &[("--input", &args.input), ("--params", &args.params)],
                )?;
            }
            let file = FamilyParams::load(&args.params, args.model.family)
                .map_err(|e| name_parameter_file(e, &args.params))?;
            for warning in file.warnings() {
                tell!("hairfit: warning: {}: {warning}", args.params.display());
            }
            let request = EvalRequest {
                output_columns: output_columns(file.n_channels(), file.sigma_a_is_scalar()),
                model: FamilyModel::new(&file, &args.model.setup()?),
                params: file,
                angles: args.angles,
            };
            let summary = eval_file(&args.input, args.output.as_deref(), &request)?;
            for warning in &summary.warnings {
                tell!("hairfit: warning: {}: {warning}", args.input.display());
            }
            if let Some(out) = hairfit::eval::output_file(args.output.as_deref()) {
                tell!(
                    "hairfit: evaluated {} rows into {}",
                    summary.rows,
                    out.display()
                );
            }
        }
        Command::Load(args) => {
            let text = hairfit::data::load_command(&args.file, &args.options, args.json)?;
            say(&text)?;
        }
        Command::Synth(args) => {
            remove_partial_output_on_interrupt();
            // argv[0] varies with the install; record the command as a user types it.
            let argv = std::iter::once("hairfit".to_string()).chain(std::env::args().skip(1));
            let command_line = hairfit::cli::synth::command_line_string(argv);
            let summary = hairfit::cli::synth::run(&args, Some(command_line))?;
            tell!(
                "hairfit: wrote {} samples ({} outliers) to {} and the truth to {}",
                summary.n_samples,
                summary.n_outliers,
                summary.csv.display(),
                summary.truth.display()
            );
            for note in &summary.notes {
                tell!("hairfit: note: {note}");
            }
        }
        Command::Trace(args) => {
            remove_partial_output_on_interrupt();
            let argv = std::iter::once("hairfit".to_string()).chain(std::env::args().skip(1));
            let command_line = hairfit::cli::synth::command_line_string(argv);
            let summary = hairfit::cli::trace::run(&args, Some(command_line))?;
            let r = &summary.record;
            tell!(
                "hairfit: traced {} rays per incidence × {} incidences in {:.1} s; wrote {} \
                 samples to {} and the sidecar to {}",
                r.rays_per_incidence,
                r.incidences,
                summary.seconds,
                r.n_samples,
                summary.csv.display(),
                summary.sidecar.display()
            );
            for e in &r.energy {
                tell!(
                    "hairfit: {}: R {:.4}, TT {:.4}, TRT {:.4}, higher {:.4}, absorbed {:.4}, \
                     inside {:.2e}",
                    e.channel,
                    e.tallied[0],
                    e.tallied[1],
                    e.tallied[2],
                    e.tallied[3],
                    e.absorbed,
                    e.inside
                );
            }
        }
        Command::Report { dir, linear } => {
            remove_partial_output_on_interrupt();
            let summary = hairfit::report::write_report_with(
                &dir,
                &hairfit::report::ReportOptions { linear },
            )?;
            for note in &summary.notes {
                tell!("hairfit: note: {note}");
            }
            tell!(
                "hairfit: wrote {} files; open {}",
                summary.files.len(),
                dir.join("index.html").display()
            );
        }
        Command::Cost {
            quick,
            force,
            out,
            family,
        } => {
            remove_partial_output_on_interrupt();
            let options = hairfit::cost::CostOptions {
                quick,
                force,
                family,
            };
            let ledger = hairfit::cost::run_cost(&out, &options)?;
            say(hairfit::cost::summary_text(&ledger))?;
            tell!(
                "hairfit: wrote {}/{{cost.csv,cost.json,cost.svg,cost.png}}",
                out.display()
            );
        }
        Command::Fit(a) => {
            let stop = ctrl_c_flag();
            let cancel = Some(stop.flag.clone());
            let outcome = hairfit::cli::fit::fit_command(&a.data, &a.load, &a.fit, &a.out, cancel)?;
            say(fit_summary_and_report(&outcome, &a.out))?;
            return Ok(finished(
                outcome.outcome.json.verdict,
                a.fit.strict,
                stop.received(),
            ));
        }
        Command::Batch(a) => return batch(a),
        Command::Compare(a) => {
            let stop = ctrl_c_flag();
            let cancel = Some(stop.flag.clone());
            let done = match hairfit::cli::compare::compare_command(&a, cancel)? {
                hairfit::compare::CompareEnd::Published(done) => *done,
                hairfit::compare::CompareEnd::Interrupted(why) => {
                    tell!("hairfit: {why}");
                    return Ok(exit_code(
                        Verdict::Interrupted,
                        a.fit.strict,
                        stop.received(),
                    ));
                }
            };
            for line in &done.report_lines {
                say(line)?;
            }
            say(hairfit::compare::summary_text(&done.comparison, &a.out))?;
            if let Some(sig) = stop.received() {
                tell!(
                    "hairfit: note: {} came after the comparison was published: its outputs are complete, so the exit code is theirs",
                    hairfit::cli::exit::signal_name(sig)
                );
            }
            if let Some(e) = done.no_fit_succeeded(&a.out) {
                return Err(e.into());
            }
            if a.fit.strict {
                if let Some(why) = done.strict_refusal() {
                    tell!("hairfit: {why}");
                    return Ok(hairfit::cli::exit::STRICT_EXIT);
                }
            }
        }
        Command::Export(a) => {
            remove_partial_output_on_interrupt();
            let (summary, text) = hairfit::cli::export::export_command(&a)?;
            say(text.unwrap_or_default())?;
            tell!("hairfit: {summary}");
        }
        Command::Demo(a) => {
            let stop = ctrl_c_flag();
            let cancel = Some(stop.flag.clone());
            let opts = a.fit.options(cancel)?;
            let outcome = hairfit::demo::demo_command(&opts, &a.out, a.fit.force)?;
            say(fit_summary_and_report(&outcome, &a.out))?;
            say(hairfit::demo::truth_line(&a.out, opts.family))?;
            return Ok(finished(
                outcome.outcome.json.verdict,
                a.fit.strict,
                stop.received(),
            ));
        }
    }
    Ok(0)
}

/// `hairfit batch`: run a shard of a manifest, or merge the results.
fn batch(a: BatchArgs) -> anyhow::Result<u8> {
    use hairfit::batch::{merge, run_batch, ItemOutcome, Manifest, RunOptions, Shard};
    let manifest = Manifest::load(&a.manifest)?;
    if a.merge {
        let m = merge::merge(&manifest, &a.out)?;
        tell!(
            "hairfit: {} items: wrote {} and {}",
            m.items,
            a.out.join("summary.csv").display(),
            a.out.join("index.html").display()
        );
        let problems = m.problems();
        if !problems.is_empty() {
            for line in &problems {
                tell!("hairfit: {line}");
            }
            let bad = m.failed.len() + m.interrupted.len() + m.unreadable.len() + m.missing.len();
            anyhow::bail!(
                "{bad} of {} items have no usable result (listed above)",
                m.items
            );
        }
        return Ok(strict_exit(a.strict, &m.not_good));
    }
    let shard = match &a.shard {
        Some(s) => Shard::parse(s)?,
        None => Shard::ALL,
    };
    let stop = ctrl_c_flag();
    let options = RunOptions {
        strict: a.strict,
        rerun: a.force,
    };
    let run = run_batch(
        &manifest,
        &a.out,
        shard,
        options,
        Some(stop.flag.clone()),
        |item, outcome| {
            let what = match outcome {
                ItemOutcome::Fitted {
                    verdict,
                    status,
                    report,
                } => format!("{verdict} ({status}); {report}"),
                ItemOutcome::Skipped(v) => {
                    format!("skipped (already finished with these options and data: {v})")
                }
                ItemOutcome::Failed(e) => format!("FAILED: {e}"),
                ItemOutcome::Interrupted => "interrupted".into(),
            };
            tell!("hairfit: [{shard}] {}: {what}", item.name);
        },
    )?;
    tell!("hairfit: {}", run.summary_line());
    if run.interrupted() {
        return Ok(exit_code(Verdict::Interrupted, a.strict, stop.received()));
    }
    if let Some(sig) = stop.received() {
        tell!(
            "hairfit: note: {} came after the shard's last item had finished: every result is complete and published, so the exit code is theirs",
            hairfit::cli::exit::signal_name(sig)
        );
    }
    let failed = run.failed_names();
    if !failed.is_empty() {
        anyhow::bail!(
            "{} items failed: {} (their errors are above; the others are written)",
            failed.len(),
            failed.join(", ")
        );
    }
    let not_good: Vec<String> = run.not_good_names().into_iter().map(String::from).collect();
    Ok(strict_exit(a.strict, &not_good))
}

/// The exit code of a published fit (see [`exit_code`]), after telling the user when a signal
/// came too late to change it.
fn finished(verdict: Verdict, strict: bool, signal: Option<i32>) -> u8 {
    if let Some(note) = hairfit::cli::exit::late_signal_note(signal, verdict) {
        tell!("{note}");
    }
    exit_code(verdict, strict, signal)
}

/// `--strict` of a batch: as `fit --strict` when an item's verdict is poor_fit or undetermined
/// (named).
fn strict_exit(strict: bool, not_good: &[String]) -> u8 {
    if !strict || not_good.is_empty() {
        return 0;
    }
    tell!(
        "hairfit: --strict: {} items are poor_fit or undetermined: {}",
        not_good.len(),
        not_good.join(", ")
    );
    hairfit::cli::exit::STRICT_EXIT
}

/// The fit's summary, then where its plotted report is.
fn fit_summary_and_report(
    run: &hairfit::report::publish::PublishedFit,
    dir: &std::path::Path,
) -> String {
    hairfit::cli::summary::summary(&run.outcome, Some(dir)) + &run.report_line(dir)
}

/// The stop request set by Ctrl-C/SIGTERM: the fit stops at the next iteration and writes the
/// best so far; a second signal exits at once (after `hairfit::atomic::remove_in_flight()`).
fn ctrl_c_flag() -> hairfit::cli::exit::StopSignal {
    hairfit::cli::exit::stop_on_signal()
}

/// Ctrl-C/SIGTERM in a command with no best-so-far to keep: remove the partial output's
/// temporary file, then exit as the signal would have (130, 143).
fn remove_partial_output_on_interrupt() {
    hairfit::cli::exit::exit_on_signal();
}

/// Domain errors come from the values, not a position in the file: say which file they are in.
fn name_parameter_file(err: hairfit::Error, path: &std::path::Path) -> anyhow::Error {
    match err {
        hairfit::Error::Parameter { .. } => {
            anyhow::Error::new(err).context(format!("in parameter file {}", path.display()))
        }
        other => other.into(),
    }
}

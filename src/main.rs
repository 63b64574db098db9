//! The `hairfit` command line: parses arguments and calls the library.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

use hairfit::cli::ModelArgs;
use hairfit::eval::{eval_file, output_columns, EvalRequest};
use hairfit::params::ParamFile;

#[derive(Parser)]
#[command(
    name = "hairfit",
    version,
    about = "Fit the Marschner 2003 hair scattering model to fiber-scattering data"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Evaluate S at every row of an angles CSV (theta_i,phi_i,theta_r,phi_r in degrees).
    Eval {
        /// Parameter file (JSON, MODEL.md's names).
        #[arg(long)]
        params: PathBuf,
        /// Angles CSV with a header; other columns are carried through.
        #[arg(long)]
        input: PathBuf,
        /// Output CSV (written atomically); stdout when absent.
        #[arg(long)]
        output: Option<PathBuf>,
        #[command(flatten)]
        model: ModelArgs,
    },
    /// Plot a fit: SVG/PNG figures and an offline index.html in the fit's directory.
    Report {
        /// The fit's directory (holds fit.json and curves.csv, written by `hairfit fit`).
        dir: PathBuf,
        /// Linear instead of logarithmic value axes.
        #[arg(long)]
        linear: bool,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    match run(cli) {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("hairfit: error: {err:#}");
            ExitCode::FAILURE
        }
    }
}

fn run(cli: Cli) -> anyhow::Result<()> {
    match cli.command {
        Command::Eval {
            params,
            input,
            output,
            model,
        } => {
            let file = ParamFile::load(&params).map_err(|e| name_parameter_file(e, &params))?;
            let request = EvalRequest {
                output_columns: output_columns(file.n_channels(), file.sigma_a_is_scalar()),
                params: file.to_params(),
                config: model.config()?,
            };
            let summary = eval_file(&input, output.as_deref(), &request)?;
            if let Some(out) = output {
                eprintln!(
                    "hairfit: evaluated {} rows into {}",
                    summary.rows,
                    out.display()
                );
            }
        }
        Command::Report { dir, linear } => {
            let summary = hairfit::report::write_report_with(
                &dir,
                &hairfit::report::ReportOptions { linear },
            )?;
            for note in &summary.notes {
                eprintln!("hairfit: note: {note}");
            }
            eprintln!(
                "hairfit: wrote {} files; open {}",
                summary.files.len(),
                dir.join("index.html").display()
            );
        }
    }
    Ok(())
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

//! The `hairfit` command line: parses arguments and calls the library.

use std::path::PathBuf;
use std::process::ExitCode;

use clap::{Parser, Subcommand};

#[derive(Parser)]
#[command(name = "hairfit", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Load a data file and report what happened to every row (accepted or why rejected).
    Load(LoadArgs),
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

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Load(args) => hairfit::data::load_command(&args.file, &args.options, args.json),
    };
    match result {
        Ok(text) => {
            print!("{text}");
            ExitCode::SUCCESS
        }
        Err(e) => {
            eprintln!("error: {e}");
            ExitCode::FAILURE
        }
    }
}

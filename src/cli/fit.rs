//! The clap options of `hairfit fit` / `hairfit demo` / `hairfit batch` items, their
//! flag-worded checks, and the fit command itself (load, fit, write), so `main.rs` only parses,
//! calls, and hands the result to the report.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use clap::Args;

use super::{MeasurementArgs, ModelArgs};
use crate::data::{load, LoadOptions};
use crate::error::{Error, Result};
use crate::families::ModelFamily;
use crate::files::CurvesMode;
use crate::fit::registry::fit_family;
use crate::fit::{
    into_fit_data, EffectsChoice, FitOptions, Global, Intervals, Loss, LossScale, Space,
};
use crate::geometry::Fitted;
use crate::report::publish::{publish_fit, PublishedFit};

/// Fit options (`hairfit fit`, `hairfit demo`).
#[derive(Debug, Clone, Args)]
pub struct FitArgs {
    /// Residual space: `log` (relative errors; default) or `linear`.
    #[arg(long, default_value = "log")]
    pub space: Space,
    /// Loss: l2, huber, cauchy or soft-l1.
    #[arg(long, default_value = "l2")]
    pub loss: Loss,
    /// Robust-loss scale C in normalised residual units, or `auto`: the loss's tuning constant
    /// (huber/soft-l1 1.345, cauchy 2.385) times the residuals' noise level (1.4826·MAD of a
    /// least-squares fit, refined once from the robust fit); fit.json records the value used.
    #[arg(long, default_value = "auto")]
    pub loss_scale: LossScale,
    /// Parameter intervals: `profile` (profile likelihood, Δχ² = 1 and 3.84, beside the
    /// linearised standard error), `linear` (standard errors only) or `auto` (profile when the
    /// estimated cost is at most a few seconds; fit.json records the choice and why).
    #[arg(long, default_value = "auto")]
    pub intervals: Intervals,
    /// Multi-start points, at most (Latin hypercube over the typical ranges of docs/model.md).
    /// They run 8 at a time, and the stage stops once every run so far ended at one point:
    /// fit.json `options.starts_run` says how many ran.
    #[arg(long, default_value_t = 16)]
    pub starts: usize,
    /// Seed of the start design and the subsample.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Global stage between multi-start and polish: none, pso or nelder-mead.
    #[arg(long, default_value = "none")]
    pub global: Global,
    /// Fix a parameter, NAME=VALUE (docs/model.md's or, with --model chiang, docs/chiang.md's names;
    /// degrees for *_deg); repeatable.
    #[arg(long = "fix")]
    pub fix: Vec<String>,
    /// Free a parameter that is fixed by default (only `eta`).
    #[arg(long = "free")]
    pub free: Vec<String>,
    /// `auto` (default: from the data's geometry) or `all`; --lobes/--no-glints/--no-eccentricity
    /// override both.
    #[arg(long)]
    pub effects: Option<String>,
    /// Samples used by the multi-start stage.
    #[arg(long, default_value_t = 2000)]
    pub subsample: usize,
    /// Best multi-start results polished on all data.
    #[arg(long, default_value_t = 2)]
    pub polish: usize,
    /// LM trial steps per start.
    #[arg(long, default_value_t = 40)]
    pub start_iters: u64,
    /// LM trial steps per polish run.
    #[arg(long, default_value_t = 300)]
    pub polish_iters: u64,
    /// What curves.csv holds: `full` (every sample and channel), `summary` (the samples the
    /// report draws, an even spread of a few thousand more, and every sample with a value the
    /// robust loss down-weighted), `none` (no curves.csv; the report then shows parameters
    /// and verdict only) or `auto` (full up to 1,000,000 rows of samples × channels, the
    /// summary above). fit.json records the mode written (`options.curves`) and why.
    #[arg(long, default_value = "auto")]
    pub curves: CurvesChoice,
    /// Never show a progress bar.
    #[arg(long)]
    pub no_progress: bool,
    /// Write into an output directory hairfit did not mark (no .hairfit file) that holds other
    /// files: they are kept, and a name the result also writes is refused. A batch or compare
    /// directory is never replaced, nor the run's own input data.
    #[arg(long)]
    pub force: bool,
    /// Exit 3 when the verdict is poor_fit or undetermined (0 without --strict).
    #[arg(long)]
    pub strict: bool,
    #[command(flatten)]
    pub model: ModelArgs,
    #[command(flatten)]
    pub measurement: MeasurementArgs,
}

impl FitArgs {
    /// Check these options without the data (for `hairfit batch`, before any item runs): what
    /// [`FitArgs::options`] checks, and every `--fix` name and value. A `sigma_a[k]` is checked
    /// against the data's channel count when the data load (or, in a batch, when the data
    /// file's header gives it up front: [`FitArgs::check_fixes`]).
    pub fn check(&self) -> Result<()> {
        self.options(None)?;
        self.check_fixes(crate::fit::fixes::channels_named(&self.fix)?)
    }

    /// Check every `--fix` against data of `nc` channels (names, values, channel indices).
    pub fn check_fixes(&self, nc: usize) -> Result<()> {
        crate::fit::registry::family_fit(self.model.family).check_fixes(&self.fix, nc)
    }

    /// The fit options these arguments ask for.
    pub fn options(&self, cancel: Option<Arc<AtomicBool>>) -> Result<FitOptions> {
        self.model.check_family_options()?;
        let cfg = self.model.config()?;
        let default_lobes = crate::families::effects::Lobes::default();
        let explicit = cfg.effects.lobes != default_lobes
            || self.model.no_glints
            || self.model.no_eccentricity;
        let effects = if explicit {
            EffectsChoice::Explicit
        } else {
            match self
                .effects
                .as_deref()
                .map(|s| s.trim().to_ascii_lowercase())
            {
                None => EffectsChoice::Auto,
                Some(s) if s == "auto" => EffectsChoice::Auto,
                Some(s) if s == "all" => EffectsChoice::All,
                Some(s) => {
                    return Err(Error::Other(format!(
                    "--effects `{s}`: use auto or all (or --lobes/--no-glints/--no-eccentricity)"
                )))
                }
            }
        };
        let mut free_eta = false;
        let family = self.model.family;
        let on_request = parameters_fitted(family, Fitted::OnRequest);
        for f in &self.free {
            let name = f.trim();
            if on_request.contains(&name) {
                // Every family's one parameter freed on request is η (the fit's `free_eta`).
                free_eta |= name == "eta";
                continue;
            }
            let why = never_fitted(family);
            return Err(Error::Other(match on_request.as_slice() {
                [] => format!(
                    "--free `{name}`: the {} model holds no parameter that --free can free (its fit already varies every parameter the terms in play read{why}); drop --free",
                    family.title()
                ),
                names => format!(
                    "--free `{name}`: only {} can be freed (the fit already varies every other parameter the effects in play depend on{why})",
                    names.iter().map(|n| format!("`{n}`")).collect::<Vec<_>>().join(", ")
                ),
            }));
        }
        if free_eta {
            if let Some(fix) = self
                .fix
                .iter()
                .find(|f| f.split('=').next().map(str::trim) == Some("eta"))
            {
                return Err(Error::Other(format!(
                    "--fix `{fix}` and --free eta contradict each other: give one of them"
                )));
            }
        }
        // Zero of these would be silently raised to one: say so instead.
        for (option, value, what) in [
            ("--starts", self.starts, "multi-start points"),
            (
                "--subsample",
                self.subsample,
                "samples in the multi-start stage",
            ),
            (
                "--polish",
                self.polish,
                "multi-start results polished on all data",
            ),
        ] {
            if value == 0 {
                return Err(Error::Other(format!(
                    "{option} 0: the fit needs at least 1 ({what}); leave the option out for its default"
                )));
            }
        }
        // Each start is an LM run on the subsample; a billion aborted allocating the design.
        const MAX_STARTS: usize = 100_000;
        if self.starts > MAX_STARTS {
            return Err(Error::Other(format!(
                "--starts {}: at most {MAX_STARTS} (each start is a short LM run; the default is 16)",
                self.starts
            )));
        }
        Ok(FitOptions {
            space: self.space,
            loss: self.loss,
            loss_scale: self.loss_scale,
            starts: self.starts,
            agreeing_starts: FitOptions::default().agreeing_starts,
            seed: self.seed,
            global: self.global,
            fix: self.fix.clone(),
            free_eta,
            effects,
            measurement: self.measurement.measurement,
            subsample: self.subsample,
            polish: self.polish,
            start_iters: self.start_iters,
            polish_iters: self.polish_iters,
            cancel,
            progress: !self.no_progress,
            intervals: self.intervals,
            family: self.model.family,
            model: self.model.setup()?,
            curves: self.curves.0,
        })
    }
}

/// `--curves`: a mode, or `auto` (`None`: the fit chooses by the data's size).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct CurvesChoice(pub Option<CurvesMode>);

impl std::str::FromStr for CurvesChoice {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        if s.trim().eq_ignore_ascii_case("auto") {
            return Ok(CurvesChoice(None));
        }
        s.parse().map(|m| CurvesChoice(Some(m))).map_err(|_| {
            Error::Other(format!(
                "unknown curves mode `{}`: use auto, full, summary or none",
                s.trim()
            ))
        })
    }
}

/// `hairfit fit DATA --out DIR`: lock `out`, load, fit, and publish the fit's files with its
/// report as one set (see [`crate::outdir`]).
pub fn fit_command(
    data_path: &Path,
    load_options: &LoadOptions,
    args: &FitArgs,
    out: &Path,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<PublishedFit> {
    let opts = args.options(cancel)?;
    // Shown from the end of the fit until its files and report are published.
    let mut writing = None;
    let published = publish_fit(out, "hairfit fit", args.force, &[data_path], |_| {
        let (ds, report) = load(data_path, load_options)?;
        // --strict: angles that look like radians are an error, not a warning.
        if args.strict {
            if let Some(w) = report
                .warnings
                .iter()
                .find(|w| w.starts_with(crate::data::unit::RADIANS_WARNING))
            {
                return Err(Error::Other(format!(
                    "{}: {w} (--strict makes this an error)",
                    data_path.display()
                )));
            }
        }
        let data = into_fit_data(ds);
        let outcome = fit_family(&data, &data_path.display().to_string(), report, &opts)?;
        writing = Some(super::summary::writing_spinner(
            opts.progress,
            outcome.curves.len(),
        ));
        Ok(outcome)
    });
    if let Some(bar) = writing {
        bar.finish_and_clear();
    }
    published
}

/// Everything `hairfit fit` takes: the data file, the loader's options, the fit's options and
/// the output directory. `hairfit batch` parses each manifest item with this same type, so an
/// item runs exactly as the `fit` command line would.
#[derive(Debug, Clone, Args)]
pub struct FitCommandArgs {
    /// Data file (.csv with a header, .json, or a headerless scan with --columns).
    pub data: std::path::PathBuf,
    #[command(flatten)]
    pub load: LoadOptions,
    #[command(flatten)]
    pub fit: FitArgs,
    /// Output directory (e.g. fits/NAME): the new result replaces what hairfit wrote there as a
    /// whole; files and folders hairfit did not write are kept (see --force).
    #[arg(long)]
    pub out: std::path::PathBuf,
}

/// `; delta_eta_prime and delta_h_m stay fixed`: the parameters of `family` its fit never
/// varies (its table's `Fitted::No` lines), or nothing.
fn never_fitted(family: ModelFamily) -> String {
    match parameters_fitted(family, Fitted::No).as_slice() {
        [] => String::new(),
        [one] => format!("; {one} stays fixed"),
        [rest @ .., last] => format!("; {} and {last} stay fixed", rest.join(", ")),
    }
}

/// The names of `family`'s parameters whose table line says `fitted`.
fn parameters_fitted(family: ModelFamily, fitted: Fitted) -> Vec<&'static str> {
    family
        .facts()
        .parameters()
        .iter()
        .filter(|f| f.fitted == fitted)
        .map(|f| f.name)
        .collect()
}

//! The clap options of `hairfit compare` (the data, the loader's and the fit's options, the
//! output directory) and the command itself: both families with the same options.

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use clap::Args;

use super::fit::FitArgs;
use crate::compare::CompareOutcome;
use crate::data::LoadOptions;
use crate::error::{Error, Result};
use crate::family::ModelFamily;

/// Everything `hairfit compare` takes. The fit options apply to both fits; `--model` is not
/// one of them (both families are fitted), `--terms`/`--width-nodes` set the Chiang fit's
/// model and `--mode`/`--lobes`/`--no-glints`/`--no-eccentricity` the Marschner fit's.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "--fix applies to both fits, so it takes only parameters both families have: sigma_a \
(every channel), sigma_a[c] (one channel) and eta. A parameter of one family (k_g, alpha_r_deg, beta_m, \
alpha_deg, ...) is refused before anything is fitted, naming the family that lacks it; to fix it, fit that \
family alone with `hairfit fit DATA --model FAMILY --fix NAME=VALUE`.

\
--out DIR is published as one set, as `hairfit fit` publishes its --out: DIR is locked (the lock file \
.DIR.hairfit-lock sits beside it), written into a staging directory beside it and swapped in whole, so a \
finished run leaves no lock or staging directory inside DIR. --out must be a directory (new, empty, or an \
earlier hairfit result; --force replaces one holding other files)."
)]
pub struct CompareArgs {
    /// Data file (.csv with a header, .json, or a headerless scan with --columns).
    pub data: PathBuf,
    #[command(flatten)]
    pub load: LoadOptions,
    #[command(flatten)]
    pub fit: FitArgs,
    /// Output directory: DIR/marschner/, DIR/chiang/, DIR/compare.json, DIR/index.html;
    /// replaced as a whole by the new result, as `hairfit fit` replaces its --out (see --force).
    #[arg(long)]
    pub out: PathBuf,
}

/// Run `hairfit compare`.
pub fn compare_command(
    args: &CompareArgs,
    cancel: Option<Arc<AtomicBool>>,
) -> Result<CompareOutcome> {
    if args.fit.model.family != ModelFamily::Marschner {
        return Err(Error::Other(
            "compare fits both model families: drop --model".into(),
        ));
    }
    // Both families' --fix names, before the data load and long before either fit.
    crate::compare::check_fixes(&args.fit.fix, None)?;
    // Each family's own options are checked as that family's fit would check them.
    let mut chiang_args = args.fit.clone();
    chiang_args.model.family = ModelFamily::Chiang;
    chiang_args.model.mode = Default::default();
    chiang_args.model.lobes = "R,TT,TRT".into();
    chiang_args.model.no_glints = false;
    chiang_args.model.no_eccentricity = false;
    let chiang = chiang_args.options(cancel.clone())?.chiang;
    let mut marschner_args = args.fit.clone();
    marschner_args.model.terms = None;
    marschner_args.model.width_nodes = None;
    // The comparison bins every residual of both fits, so both keep their whole curves.
    if let Some(mode) = args
        .fit
        .curves
        .0
        .filter(|&m| m != crate::files::CurvesMode::Full)
    {
        return Err(Error::Other(format!(
            "compare compares every residual of the two fits, so it always writes their full curves: drop --curves {mode}"
        )));
    }
    let opts = crate::fit::FitOptions {
        chiang,
        curves: Some(crate::files::CurvesMode::Full),
        ..marschner_args.options(cancel)?
    };
    crate::compare::compare_command(&args.data, &args.load, &opts, &args.out, args.fit.force)
}

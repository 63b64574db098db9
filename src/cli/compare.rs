//! The clap options of `hairfit compare` (the data, `--models`, the loader's and the fit's
//! options, the output directory) and the command itself: every listed family fitted with the
//! shared fit options, and each with the family-only options it takes ([`args_for`]).

use std::path::PathBuf;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use clap::Args;

use super::family_options::{takes, FAMILY_OPTIONS};
use super::fit::FitArgs;
use crate::compare::CompareEnd;
use crate::data::LoadOptions;
use crate::error::{Error, Result};
use crate::families::ModelFamily;
use crate::files::CurvesMode;

/// The families compared when `--models` is not given.
pub const DEFAULT_MODELS: &str = "marschner,chiang";

/// Everything `hairfit compare` takes. The fit options apply to every listed family; `--model`
/// is not one of them (`--models` lists the families); a family-only option (`--terms`,
/// `--mode`, …) goes to the listed families that take it.
#[derive(Debug, Clone, Args)]
#[command(
    after_help = "--models lists the families to fit and rank (comma-separated, or all); each fit gets the \
shared fit options, and an option only some families take (--mode, --lobes, --no-glints, \
--no-eccentricity, --terms, --width-nodes, ...) goes to the listed families that take it. Such an option \
when no listed family takes it is an error naming the families that do (docs/compare.md).

\
--fix applies to every fit, so it takes only parameters every listed family has (for the default \
marschner,chiang: sigma_a (every channel), sigma_a[c] (one channel) and eta). A parameter some listed family lacks (k_g, \
alpha_r_deg, beta_m, alpha_deg, ...) is refused before anything is fitted, naming the families that lack \
it; to fix it, fit that family alone with `hairfit fit DATA --model FAMILY --fix NAME=VALUE`.

\
--out DIR is published as one set, as `hairfit fit` publishes its --out: DIR is locked (the lock file \
.DIR.hairfit-lock sits beside it while the run lasts), written into a staging directory beside it and \
swapped in whole, so a finished run leaves no lock or staging directory. --out must be new, empty, or an \
earlier compare's DIR (marked by its .hairfit file; never a fit's or a batch's); --force writes into a \
directory of other files, keeping them. Files and folders you add to DIR are kept by later runs."
)]
pub struct CompareArgs {
    /// Data file (.csv with a header, .json, or a headerless scan with --columns).
    pub data: PathBuf,
    /// Model families to fit and rank, comma-separated (marschner, chiang, …), or `all`.
    #[arg(long, default_value = DEFAULT_MODELS)]
    pub models: String,
    #[command(flatten)]
    pub load: LoadOptions,
    #[command(flatten)]
    pub fit: FitArgs,
    /// Output directory: DIR/<family>/ per fit, DIR/compare.json, DIR/index.html; replaced as a
    /// whole by the new result, as `hairfit fit` replaces its --out (see --force).
    #[arg(long)]
    pub out: PathBuf,
}

/// `args` as `family`'s fit takes them: the shared options as given, the family-only options
/// it takes as given, and those it does not take back at their defaults.
pub fn args_for(family: ModelFamily, args: &FitArgs) -> FitArgs {
    let mut a = args.clone();
    a.model.family = family;
    for o in FAMILY_OPTIONS.iter().filter(|o| !takes(family, o.flag)) {
        (o.reset)(&mut a.model);
    }
    a
}

/// A family-only option given when none of `families` takes it would do nothing: an error
/// naming the families that take it.
pub fn check_family_options(families: &[ModelFamily], args: &FitArgs) -> Result<()> {
    for o in &FAMILY_OPTIONS {
        if !(o.given)(&args.model) || families.iter().any(|&f| takes(f, o.flag)) {
            continue;
        }
        let owners: Vec<&str> = ModelFamily::ALL
            .into_iter()
            .filter(|&f| takes(f, o.flag))
            .map(ModelFamily::as_str)
            .collect();
        let listed: Vec<&str> = families.iter().map(|f| f.as_str()).collect();
        return Err(Error::Other(format!(
            "{} applies to --model {} only, and --models lists {}: add {} to --models or drop {}",
            o.flag,
            owners.join("|"),
            listed.join(","),
            if owners.len() == 1 {
                "it"
            } else {
                "one of them"
            },
            o.flag
        )));
    }
    Ok(())
}

/// `e`, the error of `family`'s options, with a hint when a family-only option that several
/// listed families take caused it (each gets the same value: `--terms` naming one family's
/// terms fails for another).
fn shared_option_hint(
    e: Error,
    family: ModelFamily,
    families: &[ModelFamily],
    args: &FitArgs,
) -> Error {
    for o in &FAMILY_OPTIONS {
        let takers: Vec<&str> = families
            .iter()
            .filter(|&&f| takes(f, o.flag))
            .map(|f| f.as_str())
            .collect();
        if !(o.given)(&args.model) || takers.len() < 2 || !takes(family, o.flag) {
            continue;
        }
        let mut without = args_for(family, args);
        (o.reset)(&mut without.model);
        if without.options(None).is_ok() {
            return Error::Other(format!(
                "{e}. compare gives {} to every listed family that takes it ({}), and {family} \
                 refuses this value: compare families that need different values in separate \
                 runs, or fit them alone",
                o.flag,
                takers.join(", ")
            ));
        }
    }
    e
}

/// The families of `--models`.
pub fn families(models: &str) -> Result<Vec<ModelFamily>> {
    ModelFamily::parse_list(models).map_err(|e| Error::Other(format!("--models: {e}")))
}

/// Run `hairfit compare`.
pub fn compare_command(args: &CompareArgs, cancel: Option<Arc<AtomicBool>>) -> Result<CompareEnd> {
    let families = families(&args.models)?;
    if args.fit.model.family != ModelFamily::default() {
        return Err(Error::Other(format!(
            "compare fits the families --models lists: drop --model (--models {} fits that family alone)",
            args.fit.model.family
        )));
    }
    check_family_options(&families, &args.fit)?;
    // Every listed family's --fix names, before the data load and long before any fit.
    crate::compare::check_fixes(&families, &args.fit.fix, None)?;
    // The comparison bins every residual of every fit, so each keeps its whole curves.
    if let Some(mode) = args.fit.curves.0.filter(|&m| m != CurvesMode::Full) {
        return Err(Error::Other(format!(
            "compare compares every residual of the fits, so it always writes their full curves: drop --curves {mode}"
        )));
    }
    // Each family's options are checked as that family's fit would check them.
    let fits = families
        .iter()
        .map(|&family| {
            let opts = args_for(family, &args.fit)
                .options(cancel.clone())
                .map_err(|e| shared_option_hint(e, family, &families, &args.fit))?;
            Ok(crate::fit::FitOptions {
                curves: Some(CurvesMode::Full),
                ..opts
            })
        })
        .collect::<Result<Vec<_>>>()?;
    crate::compare::compare_command(&args.data, &args.load, &fits, &args.out, args.fit.force)
}

#[cfg(test)]
mod tests {
    use super::*;
    use clap::Parser;

    #[derive(Parser)]
    struct Cli {
        #[command(flatten)]
        fit: FitArgs,
    }

    fn fit_args(flags: &[&str]) -> FitArgs {
        Cli::parse_from(std::iter::once("hairfit").chain(flags.iter().copied())).fit
    }

    /// A value each family-only flag is given in these tests.
    fn given(flag: &str) -> Vec<&str> {
        match flag {
            "--mode" => vec![flag, "exact"],
            "--lobes" => vec![flag, "R"],
            "--terms" => vec![flag, "R"],
            "--width-nodes" => vec![flag, "256"],
            _ => vec![flag],
        }
    }

    #[test]
    fn every_family_only_flag_has_a_row_and_each_family_gets_only_its_own() {
        for family in ModelFamily::ALL {
            for flag in family.own_options() {
                assert!(
                    FAMILY_OPTIONS.iter().any(|o| o.flag == *flag),
                    "{family} takes {flag}, which compare's FAMILY_OPTIONS lacks"
                );
            }
        }
        for o in &FAMILY_OPTIONS {
            let args = fit_args(&given(o.flag));
            assert!((o.given)(&args.model), "{}", o.flag);
            for family in ModelFamily::ALL {
                let mine = args_for(family, &args);
                assert_eq!(mine.model.family, family);
                assert_eq!(
                    (o.given)(&mine.model),
                    takes(family, o.flag),
                    "{family} {}",
                    o.flag
                );
                // What args_for hands a family passes that family's own option check; the
                // option as given fails it for a family that does not take it.
                if let Err(e) = mine.model.check_family_options() {
                    assert!(
                        !e.to_string().contains("applies to"),
                        "{family} {}: {e}",
                        o.flag
                    );
                }
                let mut raw = args.clone();
                raw.model.family = family;
                if !takes(family, o.flag) {
                    assert!(
                        raw.model.check_family_options().is_err(),
                        "{family} {}",
                        o.flag
                    );
                }
            }
        }
    }

    #[test]
    fn an_option_no_listed_family_takes_names_the_families_that_do() {
        for o in &FAMILY_OPTIONS {
            let args = fit_args(&given(o.flag));
            let owners: Vec<ModelFamily> = ModelFamily::ALL
                .into_iter()
                .filter(|&f| takes(f, o.flag))
                .collect();
            let others: Vec<ModelFamily> = ModelFamily::ALL
                .into_iter()
                .filter(|&f| !takes(f, o.flag))
                .collect();
            check_family_options(&owners, &args).unwrap();
            check_family_options(&ModelFamily::ALL, &args).unwrap();
            if others.is_empty() {
                continue;
            }
            let e = check_family_options(&others, &args)
                .unwrap_err()
                .to_string();
            assert!(
                e.starts_with(&format!("{} applies to --model", o.flag)),
                "{e}"
            );
            for f in owners {
                assert!(e.contains(f.as_str()), "{e}");
            }
        }
    }

    #[test]
    fn models_lists_are_read_with_their_errors() {
        let default: Vec<&str> = families(DEFAULT_MODELS)
            .unwrap()
            .into_iter()
            .map(ModelFamily::as_str)
            .collect();
        assert_eq!(default, ["marschner", "chiang"]);
        assert_eq!(families("all").unwrap(), ModelFamily::ALL);
        let e = families("marschner,bogus").unwrap_err().to_string();
        assert!(
            e.contains("--models") && e.contains("unknown model family `bogus`"),
            "{e}"
        );
        assert!(e.contains(&ModelFamily::names()), "{e}");
        let e = families("chiang, chiang").unwrap_err().to_string();
        assert!(e.contains("named twice"), "{e}");
        let e = families(" , ").unwrap_err().to_string();
        assert!(e.contains("is empty"), "{e}");
    }
}

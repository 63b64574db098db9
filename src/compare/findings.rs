//! The ranking of the fitted families (by AIC, ties within [`AIC_TIE`]) and the findings in
//! words: who fits best, and for each other family what it loses against the best — ΔAIC,
//! ΔBIC, the χ² ratio and the regions where it misses the data most, with numbers.

use super::comparison::{ModelSummary, Ranked, Region, AIC_TIE, BIN_RATIO, SCALE_NOTE};
use crate::families::ModelFamily;
use crate::plot::fmt_num;

/// Bins (of |φ| or θh) named per family in the findings; lobe regions are always named.
const BINS_NAMED: usize = 3;

/// The families by AIC, lowest first (equal AIC: the order given).
pub fn rank(models: &[ModelSummary]) -> Vec<Ranked> {
    let mut order: Vec<&ModelSummary> = models.iter().filter(|m| m.rankable()).collect();
    order.sort_by(|a, b| a.aic.total_cmp(&b.aic));
    let Some(best) = order.first().copied() else {
        return Vec::new();
    };
    order
        .iter()
        .enumerate()
        .map(|(i, m)| {
            let delta_aic = m.aic - best.aic;
            let tied = delta_aic < AIC_TIE;
            Ranked {
                family: m.family,
                rank: if tied { 1 } else { i + 1 },
                aic: m.aic,
                bic: m.bic,
                delta_aic,
                delta_bic: m.bic - best.bic,
                chi2_ratio: (best.chi2 > 0.0).then(|| m.chi2 / best.chi2),
                tied_with_best: tied,
            }
        })
        .collect()
}

/// Where `family` misses the data compared with `other` ([`Region::misses`]), worst first:
/// the lobe regions, then the [`BINS_NAMED`] worst bins.
pub fn misses(regions: &[Region], family: ModelFamily, other: ModelFamily) -> Vec<&Region> {
    let gap = |r: &Region| r.rms.get(family).unwrap_or(0.0) - r.rms.get(other).unwrap_or(0.0);
    let worst = |lobes: bool| {
        let mut v: Vec<&Region> = regions
            .iter()
            .filter(|r| (r.axis == "lobe") == lobes && r.misses(family, other))
            .collect();
        v.sort_by(|a, b| gap(b).total_cmp(&gap(a)));
        v
    };
    let mut out = worst(true);
    out.extend(worst(false).into_iter().take(BINS_NAMED));
    out
}

/// `place: RMS a vs b (n residuals)` for each region, `; `-separated.
fn places(regions: &[&Region], family: ModelFamily, other: ModelFamily) -> String {
    regions
        .iter()
        .map(|r| {
            format!(
                "{}: RMS {:.3} vs {:.3} ({} residuals)",
                r.place(),
                r.rms.get(family).unwrap_or(f64::NAN),
                r.rms.get(other).unwrap_or(f64::NAN),
                r.n
            )
        })
        .collect::<Vec<_>>()
        .join("; ")
}

/// `A`, `A and B`, `A, B and C`.
pub fn and_list(items: &[&str]) -> String {
    match items {
        [] => String::new(),
        [one] => (*one).into(),
        [rest @ .., last] => format!("{} and {last}", rest.join(", ")),
    }
}

/// The findings: who fits best (or which families tie), then per other family in rank order
/// what it loses against the best and where it misses most, then where the best itself is
/// beaten, then the note on scales.
pub fn findings(models: &[ModelSummary], ranking: &[Ranked], regions: &[Region]) -> Vec<String> {
    let summary = |f: ModelFamily| models.iter().find(|m| m.family == f);
    let unranked: Vec<String> = models
        .iter()
        .filter(|m| !ranking.iter().any(|r| r.family == m.family))
        .map(|m| format!("{} ({})", m.family.title(), m.verdict_str()))
        .collect();
    let (Some(first), Some(best)) = (
        ranking.first(),
        ranking.first().and_then(|r| summary(r.family)),
    ) else {
        return vec![format!(
            "No fit succeeded: {} — nothing is ranked and no family fits best; each fit's reasons are in its fit.json",
            and_list(&unranked.iter().map(String::as_str).collect::<Vec<_>>())
        )];
    };
    let b = best.family.title();
    // A best fit that is not good is only the best of these: say so beside its name.
    let ranked_verdicts: Vec<&str> = ranking
        .iter()
        .filter_map(|r| summary(r.family))
        .map(ModelSummary::verdict_str)
        .collect();
    let caveat = if ranked_verdicts.iter().all(|v| *v == "good") {
        String::new()
    } else if ranked_verdicts.len() > 1 && ranked_verdicts.iter().all(|v| *v != "good") {
        let mut kinds = ranked_verdicts.clone();
        kinds.sort_unstable();
        kinds.dedup();
        format!(" of these, but every fit is {}", kinds.join(" or "))
    } else if best.verdict_str() != "good" {
        format!(" of these, but its verdict is {}", best.verdict_str())
    } else {
        String::new()
    };
    let mut out = Vec::new();
    let tied: Vec<&str> = ranking[1..]
        .iter()
        .filter(|r| r.tied_with_best)
        .map(|r| r.family.title())
        .collect();
    let own = format!(
        "AIC {:.1}, chi2 {:.4e} with {} parameters",
        first.aic, best.chi2, best.n_params
    );
    out.push(match (ranking.get(1), tied.is_empty()) {
        (None, _) if unranked.is_empty() => format!(
            "{b} is the only family listed ({own}): nothing to rank it against{}",
            if best.verdict_str() == "good" {
                String::new()
            } else {
                format!("; its verdict is {}", best.verdict_str())
            }
        ),
        (None, _) => format!(
            "{b} is the only fit that succeeded ({own}): nothing to rank it against{}",
            if best.verdict_str() == "good" {
                String::new()
            } else {
                format!("; its verdict is {}", best.verdict_str())
            }
        ),
        (Some(next), true) => format!(
            "{b} fits best{caveat}: {own}; the next, {}, has ΔAIC {:.1}",
            next.family.title(),
            next.delta_aic
        ),
        (Some(_), false) => {
            let spread = ranking.iter().rfind(|r| r.tied_with_best);
            let mut names = vec![b];
            names.extend(&tied);
            format!(
                "{} fit equally well{caveat}: their AIC lie within {:.2} of each other (< {AIC_TIE}, a tie); {b} has the lowest, {own}",
                and_list(&names),
                spread.map_or(0.0, |r| r.delta_aic)
            )
        }
    });
    for r in &ranking[1..] {
        let Some(m) = summary(r.family) else { continue };
        let t = r.family.title();
        let ratio = r
            .chi2_ratio
            .map_or(String::new(), |x| format!(", {}× {b}'s", fmt_num(x)));
        out.push(format!(
            "{t} {} {b}: ΔAIC {:.1}{}, ΔBIC {:.1}, chi2 {:.4e} vs {:.4e}{ratio}, with {} vs {} parameters",
            if r.tied_with_best { "ties with" } else { "loses against" },
            r.delta_aic,
            if r.tied_with_best {
                format!(" (< {AIC_TIE})")
            } else {
                String::new()
            },
            r.delta_bic,
            m.chi2,
            best.chi2,
            m.n_params,
            best.n_params
        ));
        let worst = misses(regions, r.family, best.family);
        out.push(if worst.is_empty() {
            format!("{t}'s RMS residual is within {BIN_RATIO}× of {b}'s in every region")
        } else {
            format!(
                "{t} misses the data most at {}",
                places(&worst, r.family, best.family)
            )
        });
    }
    // Where the best itself misses compared with another family.
    for r in &ranking[1..] {
        let worst = misses(regions, best.family, r.family);
        if !worst.is_empty() {
            out.push(format!(
                "{b}, though ranked first, misses the data more than {} at {}",
                r.family.title(),
                places(&worst, best.family, r.family)
            ));
        }
    }
    if !unranked.is_empty() {
        out.push(format!(
            "Not ranked: {} — a fit that failed is not a fit (its reasons are in its fit.json)",
            and_list(&unranked.iter().map(String::as_str).collect::<Vec<_>>())
        ));
    }
    out.push(format!("Scales: {SCALE_NOTE}."));
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::compare::comparison::PerFamily;

    fn summary(family: ModelFamily, chi2: f64, k: usize) -> ModelSummary {
        ModelSummary {
            family,
            dir: family.as_str().into(),
            status: "converged".into(),
            chi2,
            n_residuals: 100,
            n_params: k,
            aic: chi2 + 2.0 * k as f64,
            bic: chi2 + k as f64 * 100f64.ln(),
            reduced_chi2: None,
            rms: None,
            verdict: Some(crate::files::Verdict::Good),
            params: serde_json::from_str(
                r#"{"sigma_a": 0.3, "alpha_r_deg": -7, "beta_r_deg": 7.5, "k_g": 2, "w_c_deg": 15}"#,
            )
            .unwrap(),
            parameters: Vec::new(),
            scale: Vec::new(),
        }
    }

    const M: ModelFamily = ModelFamily::Marschner;
    const C: ModelFamily = ModelFamily::Chiang;

    #[test]
    fn the_lowest_aic_ranks_first_and_the_others_say_what_they_lose() {
        let models = [summary(C, 400.0, 7), summary(M, 100.0, 9)];
        let ranking = rank(&models);
        assert_eq!(ranking[0].family, M);
        assert_eq!((ranking[0].rank, ranking[1].rank), (1, 2));
        assert!((ranking[1].delta_aic - 296.0).abs() < 1e-12);
        assert_eq!(ranking[1].chi2_ratio, Some(4.0));
        assert!(!ranking[1].tied_with_best);
        let tt = Region {
            axis: "lobe".into(),
            name: "TT".into(),
            definition: "|φ| > 135°".into(),
            centre_deg: None,
            half_width_deg: None,
            n: 30,
            rms: PerFamily(vec![(C, 3.0), (M, 1.0)]),
        };
        let f = findings(&models, &ranking, &[tt]);
        assert!(f[0].starts_with("Marschner fits best: AIC 118.0"), "{f:?}");
        assert!(
            f[1].starts_with("Chiang loses against Marschner: ΔAIC 296.0"),
            "{f:?}"
        );
        assert!(f[1].contains(", 4× Marschner's"), "{f:?}");
        assert!(
            f[2].starts_with("Chiang misses the data most at the TT region (|φ| > 135°): RMS 3.000 vs 1.000 (30 residuals)"),
            "{f:?}"
        );
    }

    #[test]
    fn within_aic_tie_the_families_tie() {
        let models = [summary(M, 100.0, 9), summary(C, 102.5, 7)];
        let ranking = rank(&models);
        assert_eq!(ranking[0].family, C);
        assert!(ranking[1].tied_with_best && ranking[1].rank == 1);
        let f = findings(&models, &ranking, &[]);
        assert!(
            f[0].starts_with("Chiang and Marschner fit equally well"),
            "{f:?}"
        );
        assert!(
            f[1].starts_with("Marschner ties with Chiang: ΔAIC 1.5 (< 2)"),
            "{f:?}"
        );
        assert!(
            f[2].contains("within 1.5× of Chiang's in every region"),
            "{f:?}"
        );
    }
}

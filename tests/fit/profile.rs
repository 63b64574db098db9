//! Profile-likelihood intervals: coverage of the truth over seeded noisy datasets (synthesized
//! through the library, not the binary), agreement with the linearised SE where the problem is
//! nearly linear, open profiles making a parameter undetermined, Ctrl-C, and determinism across
//! thread counts.
//!
//! Coverage tolerance: with N independent (dataset, parameter) trials the hit rate of a correct
//! 68.27% interval is binomial, so it lies within 0.6827 ± 3·sqrt(0.6827·0.3173/N) with
//! probability 99.7%. Parameters of one dataset are correlated, which widens the true spread a
//! little; the datasets are seeded, so a pass is reproducible.
//!
//! Full sets (60 datasets per rig, ignored in the default suite):
//! `cargo test --release --test fit profile:: -- --ignored --nocapture`

use crate::support;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use hairfit::families::marschner::fit::forward::MarschnerForward;
use hairfit::families::marschner::fit::{fit, MarschnerOutcome};
use hairfit::families::marschner::parameters::report_factor;
use hairfit::families::marschner::{ParamName, Params};
use hairfit::files::{FitStatus, ParamStatus, ProfileMethod};
use hairfit::fit::profile::{self, End, Optimum, Profile};
use hairfit::fit::{
    EffectsChoice, Evaluator, FitData, FitOptions, FitParam, Intervals, Loss, Space,
};
use hairfit::geometry::Measurement;

/// MODEL.md's example hair, one channel.
fn truth() -> Params<f64> {
    support::model::table_params()
}

/// Three azimuthal scans: every free parameter is determined.
const THREE_SCANS: &str = "azimuthal:incidences=15,30,45:steps=60";
/// One azimuthal scan: a hard case, the cost is far from quadratic in several directions.
const ONE_SCAN: &str = "azimuthal:incidences=30:steps=120";

/// Noisy data on `rig` (5% relative noise, σ column written), seeded.
fn dataset(rig: &str, seed: u64) -> FitData {
    dataset_at(rig, "relative:0.05", seed)
}

fn dataset_at(rig: &str, noise: &str, seed: u64) -> FitData {
    support::fit::synthesized(&truth(), rig, noise, 0.8, seed)
}

fn options(intervals: Intervals) -> FitOptions {
    FitOptions {
        effects: EffectsChoice::All,
        starts: 8,
        intervals,
        ..FitOptions::default()
    }
}

/// The Marschner fit of `data` with default fixes and `intervals`.
fn fitted(data: &FitData, intervals: Intervals) -> MarschnerOutcome {
    fit(data, "data", Default::default(), &options(intervals)).unwrap()
}

/// Truth of a parameter in reporting units.
fn true_value(name: &str) -> f64 {
    let p = ParamName::from_json_name(name).unwrap();
    truth().get(p) * report_factor(p)
}

/// Hits over the free parameters of one fit: (profile hits, trials) over all of them, and
/// (profile hits, linearised hits, trials) over those the linearised fit gives a standard error
/// (where the SE makes a claim that can fail).
fn hits(
    profiled: &MarschnerOutcome,
    linear: Option<&MarschnerOutcome>,
) -> ([usize; 2], [usize; 3]) {
    let (mut all, mut se) = ([0; 2], [0; 3]);
    for (k, e) in profiled.json.parameters.iter().enumerate() {
        if e.status == ParamStatus::Fixed {
            continue;
        }
        let t = true_value(&e.name);
        let i = e.interval_68.expect("every free parameter is profiled");
        let inside = i.lower.is_none_or(|lo| lo <= t) && i.upper.is_none_or(|hi| t <= hi);
        all[0] += inside as usize;
        all[1] += 1;
        if let Some(lin) = linear {
            let l = &lin.json.parameters[k];
            if let (Some(v), Some(s)) = (l.value, l.std_error) {
                se[0] += inside as usize;
                se[1] += ((v - t).abs() <= s) as usize;
                se[2] += 1;
            }
        }
    }
    (all, se)
}

/// 3σ binomial band around 0.6827 for `n` trials.
fn band(n: usize) -> (f64, f64) {
    let p: f64 = 0.6827;
    let half = 3.0 * (p * (1.0 - p) / n as f64).sqrt();
    (p - half, p + half)
}

/// Coverage over `n` seeded datasets on `rig` at `noise`: (profile rate, trials) over every
/// free parameter, and (profile rate, linearised rate, trials) where the SE exists.
fn coverage(
    rig: &str,
    noise: &str,
    n: u64,
    with_linear: bool,
) -> ((f64, usize), (f64, f64, usize)) {
    let (mut all, mut se) = ([0; 2], [0; 3]);
    for seed in 0..n {
        let data = dataset_at(rig, noise, 100 + seed);
        let out = fit(&data, rig, Default::default(), &options(Intervals::Profile)).unwrap();
        assert_eq!(out.json.options.intervals, "profile", "seed {seed}");
        let lin = with_linear
            .then(|| fit(&data, rig, Default::default(), &options(Intervals::Linear)).unwrap());
        let (a, b) = hits(&out, lin.as_ref());
        for k in 0..2 {
            all[k] += a[k];
        }
        for k in 0..3 {
            se[k] += b[k];
        }
    }
    let rate = |h: usize, n: usize| h as f64 / n.max(1) as f64;
    (
        (rate(all[0], all[1]), all[1]),
        (rate(se[0], se[2]), rate(se[1], se[2]), se[2]),
    )
}

#[test]
fn profile_68_covers_the_truth_at_68_percent_fast_subset() {
    let ((rate, n), _) = coverage(THREE_SCANS, "relative:0.05", 10, false);
    let (lo, hi) = band(n);
    eprintln!("three scans, 10 datasets: profile coverage {rate:.3} over {n} trials, band [{lo:.3}, {hi:.3}]");
    assert!(
        rate >= lo && rate <= hi,
        "coverage {rate} outside [{lo}, {hi}] ({n} trials)"
    );
}

#[test]
#[ignore = "60 datasets, two fits each: ~3 min on 2 cores"]
fn profile_68_coverage_full_set_three_scans() {
    let ((rate, n), (p_se, lin, n_se)) = coverage(THREE_SCANS, "relative:0.05", 60, true);
    let (lo, hi) = band(n);
    eprintln!("three scans, 5%: profile {rate:.3} over {n} trials, band [{lo:.3}, {hi:.3}]; where an SE exists ({n_se}): profile {p_se:.3}, linearised {lin:.3}");
    assert!(
        rate >= lo && rate <= hi,
        "three scans: {rate} outside [{lo}, {hi}]"
    );
}

/// One azimuthal scan at 10% noise, the hard case. Measured (60 datasets, 360 trials): every
/// free parameter 0.775 (undetermined ones, open to their bounds, always cover), and over the
/// 211 with a standard error the profile 0.673 and the linearised SE 0.711: pooled, the
/// linearised SE does not undercover, so only the profile's coverage is asserted. Per parameter
/// it does: k_g's ±1 SE held the truth in 32% of 120 fits over 200 datasets
/// (`scripts/coverage_single_scan.py`, README "Coverage on single scans"), which the fit's
/// design caveat (`hairfit::fit::scan_design`) now states.
#[test]
#[ignore = "60 datasets, two fits each: ~3 min on 2 cores"]
fn profile_68_coverage_full_set_single_scan() {
    let ((rate, n), (p_se, lin, n_se)) = coverage(ONE_SCAN, "relative:0.1", 60, true);
    let (lo, hi) = band(n_se);
    eprintln!("one scan, 10%: profile {rate:.3} over {n} trials; where an SE exists ({n_se}): profile {p_se:.3}, linearised {lin:.3}, band [{lo:.3}, {hi:.3}]");
    assert!(
        p_se >= lo && p_se <= hi,
        "one scan: {p_se} outside [{lo}, {hi}]"
    );
    // Open (undetermined) intervals reach the bounds: they cover at least as often.
    assert!(
        rate >= p_se - 0.05,
        "all parameters {rate} vs determined {p_se}"
    );
}

#[test]
fn intervals_bracket_the_value_and_match_the_se_where_the_cost_is_nearly_quadratic() {
    // 0.5% noise: the cost is nearly quadratic over ±2 SE (at 5% k_G's SE is 60% of its value
    // and its profile is far from a parabola).
    let data = dataset_at(THREE_SCANS, "relative:0.005", 7);
    let out = fitted(&data, Intervals::Profile);
    assert_eq!(out.json.status, FitStatus::Converged);
    let mut checked = 0;
    for e in out
        .json
        .parameters
        .iter()
        .filter(|e| e.status == ParamStatus::Free)
    {
        let (v, se) = (e.value.unwrap(), e.std_error.unwrap());
        let i68 = e.interval_68.unwrap();
        let i95 = e.interval_95.unwrap();
        let (lo, hi) = (i68.lower.unwrap(), i68.upper.unwrap());
        let (lo95, hi95) = (i95.lower.unwrap(), i95.upper.unwrap());
        assert!(
            lo95 < lo && lo < v && v < hi && hi < hi95,
            "{}: {lo95} {lo} {v} {hi} {hi95}",
            e.name
        );
        // Δχ² = 1 is ±1 SE for a quadratic cost; at 0.5% noise the half-widths agree within 15%
        // (the profile's own crossing tolerance is ~1%).
        let half = 0.5 * (hi - lo);
        assert!(
            (half / se - 1.0).abs() < 0.25,
            "{}: half-width {half} vs SE {se}",
            e.name
        );
        // The stored profile holds the optimum at Δχ² = 0. Each side either reaches the 95%
        // level with re-fits, or (`extrapolated`) holds one re-fit at Δχ² within 0.2% of 1 and
        // takes its 95% end from the local quadratic: h₉₅ = h₁·√(3.84/Δχ²₁) exactly.
        assert!(
            e.profile.iter().any(|q| q[0] == v && q[1] == 0.0),
            "{}",
            e.name
        );
        let m = e
            .profile_method
            .expect("a profiled parameter records its method");
        let sides = [
            (e.profile.first().unwrap(), lo95, m[0]),
            (e.profile.last().unwrap(), hi95, m[1]),
        ];
        for (side, (outer, end95, method)) in sides.into_iter().enumerate() {
            if method == ProfileMethod::Extrapolated {
                let (h1, d1) = (outer[0] - v, outer[1]);
                assert!(
                    (d1.sqrt() - 1.0).abs() < 1e-3,
                    "{} side {side}: {d1}",
                    e.name
                );
                let h95 = h1 * (3.841_458_820_694_124 / d1).sqrt();
                // Both sides of the formula in reporting units: 1e-12 of the offset is rounding.
                assert!(
                    ((end95 - v) - h95).abs() <= 1e-12 * h95.abs(),
                    "{} side {side}: 95% end {end95} vs the quadratic's {}",
                    e.name,
                    v + h95
                );
            } else {
                assert!(outer[1] >= 3.8, "{} side {side}: {outer:?}", e.name);
            }
        }
        checked += 1;
    }
    // α_R and β_R are undetermined on azimuthal scans (θ_h = 0 throughout): four remain.
    assert!(checked >= 4, "only {checked} free parameters");
    // Where the quadratic holds tightly, a side costs one solve (the SE, Δχ² within 0.2% of 1):
    // such a profile stores three points (the optimum and one per side); where it holds to the
    // crossing tolerance, two (the SE and the quadratic's 95% point, accepted as it stands).
    // At 0.5% noise σ_a's profile is quadratic (k_G, w_c and the eccentricity's are not quite,
    // and take the bracket: 9–10 points).
    let points: Vec<(String, usize)> = (out.json.parameters.iter())
        .filter(|e| e.status == ParamStatus::Free)
        .map(|e| (e.name.clone(), e.profile.len()))
        .collect();
    assert!(
        points
            .iter()
            .any(|(name, n)| name == "sigma_a[0]" && *n <= 5),
        "{points:?}"
    );
    // fit.json says which sides the quadratic settled: exactly the sides with one solved point
    // (extrapolated) or two (quadratic) beyond the optimum; a side with a bracket and
    // refinement says `refits`.
    let mut methods = Vec::new();
    for e in out
        .json
        .parameters
        .iter()
        .filter(|e| e.status == ParamStatus::Free)
    {
        let m = e
            .profile_method
            .expect("a profiled parameter records its method");
        let v = e.value.unwrap();
        let below = e.profile.iter().filter(|q| q[0] < v).count();
        let above = e.profile.iter().filter(|q| q[0] > v).count();
        for (method, n) in [(m[0], below), (m[1], above)] {
            match method {
                ProfileMethod::Extrapolated => assert_eq!(n, 1, "{}: {m:?}", e.name),
                ProfileMethod::Quadratic => assert_eq!(n, 2, "{}: {m:?}", e.name),
                ProfileMethod::Refits => assert!(n >= 2, "{}: {m:?}", e.name),
            }
        }
        methods.push((e.name.clone(), m));
    }
    assert!(
        methods
            .iter()
            .any(|(_, m)| m.contains(&ProfileMethod::Extrapolated)),
        "{methods:?}"
    );
    assert!(
        methods
            .iter()
            .any(|(_, m)| m.contains(&ProfileMethod::Refits)),
        "{methods:?}"
    );
    assert!(out
        .json
        .options
        .intervals_reason
        .starts_with("--intervals profile"));
    assert!(
        out.json
            .options
            .intervals_reason
            .contains("sides settled by the local quadratic"),
        "{}",
        out.json.options.intervals_reason
    );
}

/// The optimum of an l2 fit as profiling sees it.
fn optimum<'a>(
    forward: &'a MarschnerForward,
    data: &'a FitData,
    out: &MarschnerOutcome,
    cancel: Option<Arc<AtomicBool>>,
) -> Optimum<'a, MarschnerForward> {
    let free: Vec<ParamName> = out
        .json
        .parameters
        .iter()
        .filter(|e| e.status != ParamStatus::Fixed)
        .map(|e| ParamName::from_json_name(&e.name).unwrap())
        .collect();
    let x: Vec<f64> = free.iter().map(|&p| out.params.get(p)).collect();
    let (ev, _) = Evaluator::new(
        forward,
        data,
        Space::Log,
        Loss::L2,
        1.0,
        out.params.clone(),
        free.clone(),
    )
    .unwrap();
    let u = ev.internal(&x);
    let cost = ev.eval_internal(&u, false).cost();
    let dof = out.json.residuals.dof;
    Optimum {
        forward,
        data,
        space: Space::Log,
        loss: Loss::L2,
        loss_scale: 1.0,
        params: out.params.clone(),
        free,
        u,
        cost,
        chi2_unit: 2.0 * cost / dof as f64,
        dof,
        max_iters: 300,
        cancel,
    }
}

#[test]
fn profiles_are_identical_for_one_and_two_threads_and_ctrl_c_returns_none() {
    let data = dataset(THREE_SCANS, 3);
    let out = fitted(&data, Intervals::Linear);
    assert_eq!(out.json.options.intervals, "linear");
    assert!(out.json.parameters.iter().all(|e| e.interval_68.is_none()));
    let forward = MarschnerForward {
        config: out.json.model,
        measurement: Measurement::S,
    };
    let opt = optimum(&forward, &data, &out, None);
    let run = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap();
        pool.install(|| profile::profile_all(&opt, &vec![Default::default(); opt.free.len()]))
            .unwrap()
            .unwrap()
    };
    #[allow(clippy::type_complexity)]
    let key = |ps: Vec<Profile<ParamName>>| -> Vec<(Vec<(f64, f64)>, [End; 2], [End; 2])> {
        ps.into_iter()
            .map(|p| (p.points, p.end_68, p.end_95))
            .collect()
    };
    assert_eq!(
        key(run(1)),
        key(run(2)),
        "bit-identical for 1 and 2 threads"
    );

    let flag = Arc::new(AtomicBool::new(true));
    let stopped = optimum(&forward, &data, &out, Some(flag));
    let r = profile::profile_all(&stopped, &vec![Default::default(); stopped.free.len()]).unwrap();
    assert!(r.is_none(), "a set cancel flag stops profiling");
}

/// The profile's fast path (each side's first re-fit started on the linearised path, the 95%
/// end extrapolated or aimed by the local shape) finds the intervals a plain search finds (first
/// re-fits from the optimum, bracket and regula falsi), and on a well-determined fit settles
/// each side in at most two re-fits, with at most half the plain search's LM iterations. Tolerance: each search accepts a
/// crossing where `√Δχ²` is within 0.01 of its target, ≤ 1% of the half-width at 68% and ≤ 0.5%
/// at 95% (√Δχ² ≈ |h|/SE there), and an extrapolated 95% end is within 1% (search.rs), so the
/// two searches' ends differ by at most 2% of the half-width.
#[test]
fn path_started_profiles_match_a_plain_search_with_fewer_lm_steps() {
    // Random directions: every free parameter is determined (the azimuthal scans leave α_R
    // and β_R undetermined: they span no θ_h).
    let data = dataset("sphere:n=800:max=85", 3);
    let out = fitted(&data, Intervals::Linear);
    let forward = MarschnerForward {
        config: out.json.model,
        measurement: Measurement::S,
    };
    let opt = optimum(&forward, &data, &out, None);
    let first = profile::first_steps(&out.json, &opt.free);
    assert_eq!(out.json.verdict, hairfit::files::Verdict::Good);
    assert!(first.iter().all(|f| f.slopes.len() == opt.free.len()));
    let fast = profile::profile_all(&opt, &first).unwrap().unwrap();
    let plain = profile::profile_all(&opt, &vec![Default::default(); opt.free.len()])
        .unwrap()
        .unwrap();
    let iterations = |ps: &[Profile<ParamName>]| ps.iter().map(|p| p.iterations).sum::<u64>();
    assert!(
        iterations(&fast) * 2 <= iterations(&plain),
        "the path starts save at least half the LM iterations: {} against {}",
        iterations(&fast),
        iterations(&plain)
    );
    for (f, p) in fast.iter().zip(&plain) {
        let name = f.name.json_name();
        assert!(f.iterations <= 2, "{name}: {} LM iterations", f.iterations);
        assert!(f.solves <= 4, "{name}: {} re-fits", f.solves);
        let x0 = f.name.get(&opt.params);
        for (ends_f, ends_p) in [(f.end_68, p.end_68), (f.end_95, p.end_95)] {
            for side in 0..2 {
                let (End::Closed(a), End::Closed(b)) = (ends_f[side], ends_p[side]) else {
                    panic!("{name}: both sides close ({:?}, {:?})", ends_f, ends_p);
                };
                let half = (b - x0).abs();
                assert!(
                    (a - b).abs() <= 0.02 * half,
                    "{name} side {side}: {a} against {b} (half-width {half})"
                );
            }
        }
    }
}

#[test]
fn a_profile_open_inside_the_bounds_makes_the_parameter_undetermined_naming_the_side() {
    let data = dataset(THREE_SCANS, 5);
    let mut out = fitted(&data, Intervals::Linear);
    let k_g = out.params.k_g;
    let fake = Profile {
        name: ParamName::KG,
        points: vec![(k_g, 0.0), (5.0, 0.3)],
        end_68: [
            End::Closed(k_g - 0.1),
            End::Open {
                at: 5.0,
                dchi2: 0.3,
                bound: true,
            },
        ],
        end_95: [
            End::Closed(k_g - 0.2),
            End::Open {
                at: 5.0,
                dchi2: 0.3,
                bound: true,
            },
        ],
        iterations: 0,
        solves: 1,
        methods: [ProfileMethod::Refits; 2],
    };
    profile::apply(&mut out.json, &[fake.labelled()]);
    let e = out
        .json
        .parameters
        .iter()
        .find(|e| e.name == "k_g")
        .unwrap();
    assert_eq!(e.status, ParamStatus::Undetermined);
    assert_eq!(e.std_error, None);
    let i = e.interval_68.unwrap();
    assert_eq!(i.upper, None);
    assert!((i.lower.unwrap() - (k_g - 0.1)).abs() < 1e-12);
    assert!(
        out.json.warnings.iter().any(|w| w.starts_with(
            "k_g: the 68% profile interval is open above (reaches the bound 5 with Δχ² = 0.30)"
        )),
        "{:#?}",
        out.json.warnings
    );
}

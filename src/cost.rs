//! `hairfit cost`: the accuracy-vs-time ledger. Measures on this machine what each accuracy knob
//! costs — model root mode and effect set (time per evaluation vs error of S against the exact
//! all-effects model), Jacobian by AD vs central differences, and the fit's stages, start count
//! and sample count (wall time vs parameter-recovery error on seeded synthetic data) — and writes
//! cost.csv, cost.json and cost.svg/png (error against time, log axes, Pareto front marked).

use std::path::Path;
use std::time::Instant;

use plotters::coord::Shift;
use plotters::prelude::*;
use plotters::style::text_anchor::{HPos, Pos, VPos};
use serde::Serialize;

use crate::atomic::write_atomically;
use crate::error::{Error, Result};
use crate::fit::bounds::typical_range;
use crate::fit::demo::{demo_geometry, demo_truth, synthesize, DEMO_NOISE, DEMO_SCALE};
use crate::fit::{
    fit, free_parameters, param, EffectsChoice, Evaluator, FitData, FitOptions, Loss, ModelForward,
    Space,
};
use crate::model::{
    scattering, Angles, Effects, Lobes, Measurement, ModelConfig, Params, RootMode,
};
use crate::report::figures::{de, fmt_num, Figure, YScale, FONT};
use crate::report::{render, FigureInfo};

/// Error values below this are drawn at it on the log axes (the reference itself has error 0).
pub const ERROR_FLOOR: f64 = 1e-16;

/// Seed of every random choice in the ledger (angles, synthetic noise, fit starts).
pub const COST_SEED: u64 = 20_03;

/// Options of `hairfit cost`.
#[derive(Debug, Clone, Copy, Default)]
pub struct CostOptions {
    /// Fewer angles, shorter timings, fewer fit variants: under a minute on 2 cores.
    pub quick: bool,
}

/// One measured setting of one knob.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct CostRow {
    /// `model`, `jacobian` or `fit`.
    pub section: String,
    /// What was varied (e.g. `roots+effects`, `starts`).
    pub knob: String,
    /// The setting (e.g. `cubic R+TT`).
    pub setting: String,
    /// Seconds: per model evaluation (one direction pair, all channels), per Jacobian, per fit.
    pub time_s: f64,
    /// What the error measures (see [`CostLedger::metrics`]).
    pub error_max: f64,
    pub error_rms: f64,
    /// Where the largest error sits (angles and channel, or parameter name).
    pub worst_at: String,
    /// On the section's Pareto front of (time_s, error_rms).
    pub pareto: bool,
}

/// The ledger: rows plus what was measured and how.
#[derive(Debug, Clone, Serialize)]
pub struct CostLedger {
    pub hairfit_version: String,
    pub quick: bool,
    pub seed: u64,
    /// Rayon worker threads (the machine's cores unless limited).
    pub threads: usize,
    /// Error definition per section.
    pub metrics: serde_json::Value,
    pub rows: Vec<CostRow>,
    pub wall_time_s: f64,
}

/// SplitMix64: a tiny seeded generator, so the angle set is the same on every machine.
struct SplitMix64(u64);

impl SplitMix64 {
    fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [lo, hi).
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * (self.next_u64() >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A fixed, seeded set of directions: θ uniform in (−80°, 80°) (away from the degenerate ±90°),
/// φ uniform over the circle — every lobe, the glints and grazing θ_d occur.
pub fn representative_angles(n: usize, seed: u64) -> Vec<Angles> {
    let mut rng = SplitMix64(seed);
    (0..n)
        .map(|_| {
            Angles::from_degrees(
                rng.uniform(-80.0, 80.0),
                rng.uniform(-180.0, 180.0),
                rng.uniform(-80.0, 80.0),
                rng.uniform(-180.0, 180.0),
            )
        })
        .collect()
}

/// The effect sets of the ledger, cheapest first: R; R+TT; +TRT; +glints; +eccentricity.
pub fn effect_ladder() -> Vec<(&'static str, Effects)> {
    let lobes = |r, tt, trt| Lobes { r, tt, trt };
    let e = |l, glints, eccentricity| Effects {
        lobes: l,
        glints,
        eccentricity,
    };
    vec![
        ("R", e(lobes(true, false, false), false, false)),
        ("R+TT", e(lobes(true, true, false), false, false)),
        ("R+TT+TRT", e(lobes(true, true, true), false, false)),
        ("+glints", e(lobes(true, true, true), true, false)),
        ("+eccentricity", e(lobes(true, true, true), true, true)),
    ]
}

/// S for every angle (row-major angle × channel).
fn evaluate_all(p: &Params<f64>, config: &ModelConfig, angles: &[Angles]) -> Vec<f64> {
    let nc = p.sigma_a.len();
    let mut out = vec![0.0; angles.len() * nc];
    for (a, o) in angles.iter().zip(out.chunks_mut(nc)) {
        scattering(p, config, a, o);
    }
    out
}

/// Seconds per call of `f`: the fastest of five batches, each repeating `f` until `min_s / 5`
/// has elapsed. The minimum is the least disturbed by other work on a shared machine.
fn time_per_call(min_s: f64, mut f: impl FnMut()) -> f64 {
    let mut best = f64::INFINITY;
    for _ in 0..5 {
        let t0 = Instant::now();
        let mut calls = 0u64;
        loop {
            f();
            calls += 1;
            let t = t0.elapsed().as_secs_f64();
            if t >= min_s / 5.0 {
                best = best.min(t / calls as f64);
                break;
            }
        }
    }
    best
}

/// Relative error of `s` against `reference` with the denominator floored at 1e-3 × the median
/// reference value, so values in the far tails (underflowing lobes) do not dominate:
/// (max, rms, index of the max).
pub fn relative_error(s: &[f64], reference: &[f64]) -> (f64, f64, usize) {
    let mut sorted: Vec<f64> = reference
        .iter()
        .copied()
        .filter(|v| v.is_finite())
        .collect();
    sorted.sort_by(f64::total_cmp);
    let median = sorted.get(sorted.len() / 2).copied().unwrap_or(1.0);
    let floor = (1e-3 * median).max(f64::MIN_POSITIVE);
    let (mut max, mut sum, mut at) = (0.0f64, 0.0, 0usize);
    for (k, (&a, &b)) in s.iter().zip(reference).enumerate() {
        let e = (a - b).abs() / b.abs().max(floor);
        let e = if e.is_finite() { e } else { f64::INFINITY };
        sum += e * e;
        if e > max {
            max = e;
            at = k;
        }
    }
    (max, (sum / s.len().max(1) as f64).sqrt(), at)
}

/// Model section: every root mode × effect set against exact all-effects.
fn model_rows(quick: bool) -> Vec<CostRow> {
    let n = if quick { 2000 } else { 20_000 };
    let min_s = if quick { 0.05 } else { 0.5 };
    let angles = representative_angles(n, COST_SEED);
    let p = demo_truth();
    let nc = p.sigma_a.len();
    let reference = evaluate_all(
        &p,
        &ModelConfig {
            mode: RootMode::Exact,
            effects: Effects::default(),
        },
        &angles,
    );
    let mut rows = Vec::new();
    for mode in [RootMode::Cubic, RootMode::Exact] {
        for (name, effects) in effect_ladder() {
            let config = ModelConfig { mode, effects };
            let mut s = Vec::new();
            let per_set = time_per_call(min_s, || s = evaluate_all(&p, &config, &angles));
            let (max, rms, at) = relative_error(&s, &reference);
            let a = &angles[at / nc];
            rows.push(CostRow {
                section: "model".into(),
                knob: "roots+effects".into(),
                setting: format!("{mode} {name}"),
                time_s: per_set / n as f64,
                error_max: max,
                error_rms: rms,
                worst_at: format!(
                    "theta_i {:.1}, phi_i {:.1}, theta_r {:.1}, phi_r {:.1} deg, channel {}",
                    a.theta_i.to_degrees(),
                    a.phi_i.to_degrees(),
                    a.theta_r.to_degrees(),
                    a.phi_r.to_degrees(),
                    at % nc
                ),
                pareto: false,
            });
        }
    }
    rows
}

/// The seeded synthetic data of the fit section (the demo's geometry, truth, scale and noise).
fn synthetic_data() -> FitData {
    synthesize(
        &demo_truth(),
        &ModelConfig::default(),
        &demo_geometry(),
        &DEMO_SCALE,
        DEMO_NOISE,
        COST_SEED,
    )
}

/// Jacobian section: exact forward-mode AD against central finite differences in the solver's
/// parameters, at the truth, on the synthetic data; error per column relative to the AD column.
fn jacobian_rows(data: &FitData, quick: bool) -> Result<Vec<CostRow>> {
    let min_s = if quick { 0.1 } else { 1.0 };
    let truth = demo_truth();
    let nc = data.n_channels();
    let free = free_parameters(&Effects::default(), nc, false);
    let forward = ModelForward {
        config: ModelConfig::default(),
        measurement: Measurement::S,
    };
    let (ev, _) = Evaluator::new(
        &forward,
        data,
        Space::Log,
        Loss::L2,
        1.0,
        truth.clone(),
        free.clone(),
    )?;
    let x: Vec<f64> = free.iter().map(|&n| param(&truth, n)).collect();
    let u = ev.internal(&x);
    let n = u.len();
    let m = ev.n_residuals();
    let mut ad = Vec::new();
    let t_ad = time_per_call(min_s, || {
        ad = ev.eval_internal(&u, true).jacobian.unwrap_or_default();
    });
    let cols = ev.eval_internal(&u, true).n_cols;
    let central = || {
        let mut j = vec![0.0; m * n];
        for k in 0..n {
            // Step ~ cbrt(machine epsilon) × scale: balances truncation and rounding error.
            let h = 6e-6 * u[k].abs().max(1.0);
            let mut up = u.clone();
            let mut dn = u.clone();
            up[k] += h;
            dn[k] -= h;
            let rp = ev.eval_internal(&up, false).residual;
            let rm = ev.eval_internal(&dn, false).residual;
            for i in 0..m {
                j[i * n + k] = (rp[i] - rm[i]) / (2.0 * h);
            }
        }
        j
    };
    let mut fd = Vec::new();
    let t_fd = time_per_call(min_s, || fd = central());
    let mut col_err = Vec::with_capacity(n);
    for k in 0..n {
        let (mut num, mut den) = (0.0, 0.0);
        for i in 0..m {
            let a = ad.get(i * cols + k).copied().unwrap_or(f64::NAN);
            num += (fd[i * n + k] - a).powi(2);
            den += a * a;
        }
        col_err.push((num / den.max(f64::MIN_POSITIVE)).sqrt());
    }
    let (worst, max) =
        col_err.iter().enumerate().fold(
            (0, 0.0f64),
            |(w, mx), (k, &e)| if e > mx { (k, e) } else { (w, mx) },
        );
    let rms = (col_err.iter().map(|e| e * e).sum::<f64>() / n.max(1) as f64).sqrt();
    Ok(vec![
        CostRow {
            section: "jacobian".into(),
            knob: "jacobian".into(),
            setting: "AD (forward mode)".into(),
            time_s: t_ad,
            error_max: 0.0,
            error_rms: 0.0,
            worst_at: "reference".into(),
            pareto: false,
        },
        CostRow {
            section: "jacobian".into(),
            knob: "jacobian".into(),
            setting: "central differences".into(),
            time_s: t_fd,
            error_max: max,
            error_rms: rms,
            worst_at: free.get(worst).map_or("scale".into(), |p| p.json_name()),
            pareto: false,
        },
    ])
}

/// Every `stride`-th sample of `data`.
fn every_nth(data: &FitData, stride: usize) -> FitData {
    let idx: Vec<usize> = (0..data.len()).step_by(stride.max(1)).collect();
    data.subset(&idx)
}

/// Fit section: one fit per setting; error = |estimate − truth| / width of MODEL.md's typical
/// range, over the free shape parameters.
fn fit_rows(data: &FitData, quick: bool) -> Result<Vec<CostRow>> {
    let truth = demo_truth();
    let base = FitOptions {
        seed: COST_SEED,
        effects: EffectsChoice::All,
        starts: if quick { 4 } else { 16 },
        polish: if quick { 1 } else { 2 },
        ..FitOptions::default()
    };
    let mut settings: Vec<(&str, String, FitOptions, usize)> = Vec::new();
    let starts: &[usize] = if quick { &[1, 4] } else { &[1, 4, 16, 32] };
    for &s in starts {
        let o = FitOptions {
            starts: s,
            ..base.clone()
        };
        settings.push(("starts", format!("{s} starts"), o, 1));
    }
    for (name, global) in [
        ("Nelder-Mead", crate::fit::Global::NelderMead),
        ("particle swarm", crate::fit::Global::Pso),
    ] {
        settings.push((
            "global stage",
            format!("{name} global stage"),
            FitOptions {
                global,
                ..base.clone()
            },
            1,
        ));
    }
    let strides: &[usize] = if quick { &[4] } else { &[8, 4, 2] };
    for &k in strides {
        settings.push(("samples", format!("1/{k} of the samples"), base.clone(), k));
    }
    let subs: &[usize] = if quick { &[300] } else { &[300, 1000] };
    for &n in subs {
        settings.push((
            "multi-start subsample",
            format!("multi-start on {n} samples"),
            FitOptions {
                subsample: n,
                ..base.clone()
            },
            1,
        ));
    }
    let mut rows = Vec::new();
    for (knob, setting, opts, stride) in settings {
        let d = every_nth(data, stride);
        let t0 = Instant::now();
        let out = fit(&d, "synthetic", Default::default(), &opts)?;
        let wall = t0.elapsed().as_secs_f64();
        let free = free_parameters(&Effects::default(), d.n_channels(), false);
        let mut errs: Vec<(f64, String)> = free
            .iter()
            .map(|&p| {
                let (lo, hi) = typical_range(p);
                let e = (param(&out.params, p) - param(&truth, p)).abs() / (hi - lo);
                (if e.is_finite() { e } else { f64::INFINITY }, p.json_name())
            })
            .collect();
        errs.sort_by(|a, b| b.0.total_cmp(&a.0));
        let rms = (errs.iter().map(|e| e.0 * e.0).sum::<f64>() / errs.len().max(1) as f64).sqrt();
        rows.push(CostRow {
            section: "fit".into(),
            knob: knob.into(),
            setting: format!("{setting} (n={})", d.len()),
            time_s: wall,
            error_max: errs.first().map_or(0.0, |e| e.0),
            error_rms: rms,
            worst_at: errs.first().map_or(String::new(), |e| e.1.clone()),
            pareto: false,
        });
    }
    Ok(rows)
}

/// Mark each section's Pareto front of (time, rms error): no other row of the section is at
/// least as fast and as accurate and strictly better in one.
pub fn mark_pareto(rows: &mut [CostRow]) {
    let snapshot = rows.to_vec();
    for r in rows.iter_mut() {
        r.pareto = !snapshot.iter().any(|o| {
            o.section == r.section
                && o.time_s <= r.time_s
                && o.error_rms <= r.error_rms
                && (o.time_s < r.time_s || o.error_rms < r.error_rms)
        });
    }
}

/// Measure everything and write cost.csv, cost.json, cost.svg and cost.png into `out`.
pub fn run_cost(out: &Path, options: &CostOptions) -> Result<CostLedger> {
    let t0 = Instant::now();
    let quick = options.quick;
    let mut rows = model_rows(quick);
    let data = synthetic_data();
    rows.extend(jacobian_rows(&data, quick)?);
    rows.extend(fit_rows(&data, quick)?);
    mark_pareto(&mut rows);
    let ledger = CostLedger {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        quick,
        seed: COST_SEED,
        threads: rayon::current_num_threads(),
        metrics: serde_json::json!({
            "model": "relative error of S per channel against exact roots with every effect, denominator floored at 1e-3 x the median reference S; time per evaluation (one direction pair, all channels, one thread)",
            "jacobian": "per parameter column: ||J_fd - J_ad|| / ||J_ad|| (max and RMS over columns); time per full Jacobian of the synthetic data",
            "fit": "|estimate - truth| / width of MODEL.md's typical range, over the free shape parameters (max and RMS); wall time of the whole fit",
        }),
        rows,
        wall_time_s: t0.elapsed().as_secs_f64(),
    };
    write_ledger(out, &ledger)?;
    Ok(ledger)
}

/// The ledger as a table for the terminal.
pub fn summary_text(ledger: &CostLedger) -> String {
    let mut s = format!(
        "{:<9} {:<24} {:<44} {:>11} {:>10} {:>10}  pareto  worst at\n",
        "section", "knob", "setting", "time (s)", "max err", "rms err"
    );
    for r in &ledger.rows {
        s.push_str(&format!(
            "{:<9} {:<24} {:<44} {:>11.3e} {:>10.2e} {:>10.2e}  {:<6}  {}\n",
            r.section,
            r.knob,
            r.setting,
            r.time_s,
            r.error_max,
            r.error_rms,
            if r.pareto { "yes" } else { "" },
            r.worst_at
        ));
    }
    s.push_str(&format!(
        "{} threads, seed {}, {:.1} s in all\n",
        ledger.threads, ledger.seed, ledger.wall_time_s
    ));
    s
}

/// Write the ledger's files.
fn write_ledger(out: &Path, ledger: &CostLedger) -> Result<FigureInfo> {
    let csv_path = out.join("cost.csv");
    write_atomically(&csv_path, |w| {
        let mut writer = csv::Writer::from_writer(w);
        for r in &ledger.rows {
            writer
                .serialize(r)
                .map_err(|e| Error::Other(format!("{}: {e}", csv_path.display())))?;
        }
        writer.flush().map_err(|e| Error::io(&csv_path, e))
    })?;
    let json_path = out.join("cost.json");
    write_atomically(&json_path, |w| {
        let mut v = serde_json::to_value(ledger)
            .map_err(|e| Error::Other(format!("{}: {e}", json_path.display())))?;
        // Non-finite numbers become null (serde_json already does; kept explicit for readers).
        scrub_non_finite(&mut v);
        serde_json::to_writer_pretty(&mut *w, &v)
            .map_err(|e| Error::Other(format!("{}: {e}", json_path.display())))?;
        w.write_all(b"\n").map_err(|e| Error::io(&json_path, e))
    })?;
    render(
        out,
        &CostFigure {
            rows: ledger.rows.clone(),
            quick: ledger.quick,
        },
    )
}

fn scrub_non_finite(v: &mut serde_json::Value) {
    match v {
        serde_json::Value::Array(a) => a.iter_mut().for_each(scrub_non_finite),
        serde_json::Value::Object(o) => o.values_mut().for_each(scrub_non_finite),
        serde_json::Value::Number(n) if n.as_f64().is_some_and(|x| !x.is_finite()) => {
            *v = serde_json::Value::Null;
        }
        _ => {}
    }
}

/// Error against time per section, log–log, Pareto front joined and highlighted.
struct CostFigure {
    rows: Vec<CostRow>,
    quick: bool,
}

const SECTIONS: [(&str, &str, &str); 3] = [
    (
        "model",
        "Model: roots × effects",
        "time per evaluation (s, log)",
    ),
    (
        "jacobian",
        "Jacobian: AD vs central differences",
        "time per Jacobian (s, log)",
    ),
    (
        "fit",
        "Fit: stages, starts, samples",
        "fit wall time (s, log)",
    ),
];

impl Figure for CostFigure {
    fn stem(&self) -> &'static str {
        "cost"
    }
    fn title(&self) -> String {
        "Accuracy against time for each knob (Pareto front in red)".into()
    }
    fn size(&self) -> (u32, u32) {
        (1800, 900)
    }
    fn draw<DB: DrawingBackend>(&self, root: &DrawingArea<DB, Shift>) -> Result<()> {
        let (header, body) = root.split_vertically(70);
        let (w, _) = header.dim_in_pixel();
        let centre = Pos::new(HPos::Center, VPos::Top);
        header
            .draw(&Text::new(
                self.title(),
                (w as i32 / 2, 8),
                (FONT, 22).into_font().into_text_style(&header).pos(centre),
            ))
            .map_err(de)?;
        let sub = format!(
            "RMS error (log) against time (log); filled red: Pareto-optimal, grey: dominated; errors below {ERROR_FLOOR:e} drawn at it (the reference){}",
            if self.quick { "; --quick run" } else { "" }
        );
        header
            .draw(&Text::new(
                sub,
                (w as i32 / 2, 40),
                (FONT, 14).into_font().into_text_style(&header).pos(centre),
            ))
            .map_err(de)?;
        let areas = body.split_evenly((1, 3));
        for ((section, caption, x_desc), area) in SECTIONS.iter().zip(areas.iter()) {
            let rows: Vec<&CostRow> = self.rows.iter().filter(|r| r.section == *section).collect();
            draw_section(area, &rows, caption, x_desc)?;
        }
        Ok(())
    }
}

fn draw_section<DB: DrawingBackend>(
    area: &DrawingArea<DB, Shift>,
    rows: &[&CostRow],
    caption: &str,
    x_desc: &str,
) -> Result<()> {
    let lx = |r: &CostRow| r.time_s.max(1e-12).log10();
    let ly = |r: &CostRow| r.error_rms.max(ERROR_FLOOR).log10();
    let span = |v: Vec<f64>| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = v.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        if !lo.is_finite() {
            (-1.0, 1.0)
        } else {
            let pad = ((hi - lo) * 0.15).max(0.3);
            (lo - pad, hi + pad)
        }
    };
    let (x0, x1) = span(rows.iter().map(|r| lx(r)).collect());
    let (y0, y1) = span(rows.iter().map(|r| ly(r)).collect());
    let (plot, key) = area.split_vertically(600);
    let mut chart = ChartBuilder::on(&plot)
        .caption(caption, (FONT, 17))
        .margin(14)
        .x_label_area_size(44)
        .y_label_area_size(70)
        .build_cartesian_2d(x0..x1, y0..y1)
        .map_err(de)?;
    let x_fmt = |v: &f64| YScale::Log.label(*v, x1 - x0);
    let y_fmt = |v: &f64| YScale::Log.label(*v, y1 - y0);
    chart
        .configure_mesh()
        .x_desc(x_desc)
        .y_desc("RMS error (log)")
        .x_label_formatter(&x_fmt)
        .y_label_formatter(&y_fmt)
        .x_labels(YScale::Log.ticks(x1 - x0))
        .y_labels(YScale::Log.ticks(y1 - y0))
        .label_style((FONT, 13))
        .axis_desc_style((FONT, 14))
        .light_line_style(WHITE.mix(0.0))
        .draw()
        .map_err(de)?;
    let mut front: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.pareto)
        .map(|r| (lx(r), ly(r)))
        .collect();
    front.sort_by(|a, b| a.0.total_cmp(&b.0));
    chart
        .draw_series(LineSeries::new(front, RED.mix(0.6).stroke_width(2)))
        .map_err(de)?;
    // Points carry a number; the key below the plot names them (labels would overlap).
    let key_style = (FONT, 13).into_font().into_text_style(&key);
    for (k, r) in rows.iter().enumerate() {
        let p = (lx(r), ly(r));
        let colour = if r.pareto {
            RED.to_rgba()
        } else {
            RGBColor(120, 120, 120).to_rgba()
        };
        let marker = if r.pareto {
            Circle::new(p, 5, colour.filled())
        } else {
            Circle::new(p, 5, colour.stroke_width(2))
        };
        chart.draw_series(std::iter::once(marker)).map_err(de)?;
        chart
            .draw_series(std::iter::once(Text::new(
                format!("{}", k + 1),
                p,
                (FONT, 13)
                    .into_font()
                    .color(&colour)
                    .pos(Pos::new(HPos::Left, VPos::Bottom)),
            )))
            .map_err(de)?;
        let line = format!(
            "{}{}. {}: {} s, RMS error {}",
            if r.pareto { "★ " } else { "" },
            k + 1,
            r.setting,
            fmt_num(r.time_s),
            fmt_num(r.error_rms)
        );
        key.draw(&Text::new(line, (20, 4 + 18 * k as i32), key_style.clone()))
            .map_err(de)?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn row(section: &str, t: f64, e: f64) -> CostRow {
        CostRow {
            section: section.into(),
            knob: "k".into(),
            setting: "s".into(),
            time_s: t,
            error_max: e,
            error_rms: e,
            worst_at: String::new(),
            pareto: false,
        }
    }

    #[test]
    fn pareto_front_keeps_only_undominated_rows_per_section() {
        let mut rows = vec![
            row("a", 1.0, 1.0),
            row("a", 2.0, 0.5),
            row("a", 3.0, 0.6),   // dominated by (2, 0.5)
            row("a", 2.0, 0.5),   // tie: neither strictly better, both stay
            row("b", 10.0, 10.0), // alone in its section
        ];
        mark_pareto(&mut rows);
        let flags: Vec<bool> = rows.iter().map(|r| r.pareto).collect();
        assert_eq!(flags, [true, true, false, true, true]);
    }

    #[test]
    fn relative_error_floors_the_denominator_and_finds_the_worst() {
        let reference = [1.0, 1.0, 1.0, 1e-12];
        let s = [1.0, 1.1, 1.0, 2e-12];
        let (max, rms, at) = relative_error(&s, &reference);
        // The 1e-12 entry's denominator is floored at 1e-3 (× median 1), so its error is 1e-9.
        assert_eq!(at, 1);
        assert!((max - 0.1).abs() < 1e-12);
        assert!((rms - (0.01f64 / 4.0).sqrt()).abs() < 1e-9);
    }

    #[test]
    fn the_angle_set_is_seeded_and_avoids_the_axis() {
        let a = representative_angles(500, 7);
        assert_eq!(a, representative_angles(500, 7));
        assert!(a
            .iter()
            .all(|x| x.theta_i.abs() < 80f64.to_radians() && x.theta_r.abs() < 80f64.to_radians()));
    }
}

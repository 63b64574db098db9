//! Test support: the NIST StRD nonlinear-regression suite the LM solver is validated on —
//! parsing the `.dat` files, the 27 models with exact (forward-mode AD) Jacobians, and running
//! the solver (through [`super::lm::minimize`]) on all 54 problem–start pairs with the log
//! relative error (LRE) of the result. A sibling of `lm`: `support::nist` in the test
//! binaries, a crate-root module next to `lm` in `benches/lm.rs` (with `#[path]`).

// Each including crate uses a different part of this file.
#![allow(dead_code)]

use std::path::{Path, PathBuf};

use argmin::core::{Error as ArgminError, Jacobian, Operator};
use hairfit::lm::LmTermination;
use hairfit::{Error, Result};
use nalgebra::{DMatrix, DVector};
use num_dual::{Dual64, DualNum};

use super::lm::{minimize, LmOptions};

/// NIST certifies 11 significant digits, so no LRE above 11 is meaningful.
pub const LRE_CAP: f64 = 11.0;

/// The 27 StRD models, named after their data sets.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Model {
    /// `b1(1-exp(-b2 x))` (Misra1a, BoxBOD).
    Misra1a,
    /// `exp(-b1 x)/(b2+b3 x)` (Chwirut1, Chwirut2).
    Chwirut,
    /// Sum of three exponentials (Lanczos1–3).
    Lanczos,
    /// Exponential plus two Gaussians (Gauss1–3).
    Gauss,
    /// `b1 x^b2`.
    DanWood,
    /// `b1(1-(1+b2 x/2)^-2)`.
    Misra1b,
    /// Quadratic over quadratic.
    Kirby2,
    /// Cubic over cubic (Hahn1, Thurber).
    CubicRational,
    /// `log y = b1 - b2 x1 exp(-b3 x2)`.
    Nelson,
    /// `b1 + b2 exp(-x b4) + b3 exp(-x b5)`.
    Mgh17,
    /// `b1(1-(1+2 b2 x)^-1/2)`.
    Misra1c,
    /// `b1 b2 x/(1+b2 x)`.
    Misra1d,
    /// `b1 - b2 x - atan(b3/(x-b4))/π`.
    Roszman1,
    /// Constant plus three harmonic pairs.
    Enso,
    /// `b1(x²+x b2)/(x²+x b3+b4)`.
    Mgh09,
    /// `b1/(1+exp(b2-b3 x))`.
    Rat42,
    /// `b1 exp(b2/(x+b3))`.
    Mgh10,
    /// `(b1/b2) exp(-½((x-b3)/b2)²)`.
    Eckerle4,
    /// `b1/(1+exp(b2-b3 x))^(1/b4)`.
    Rat43,
    /// `b1 (b2+x)^(-1/b3)`.
    Bennett5,
}

impl Model {
    /// The model of the data set `name` (file stem), if it is one of the 27.
    pub fn from_name(name: &str) -> Option<Model> {
        Some(match name {
            "Misra1a" | "BoxBOD" => Model::Misra1a,
            "Chwirut1" | "Chwirut2" => Model::Chwirut,
            "Lanczos1" | "Lanczos2" | "Lanczos3" => Model::Lanczos,
            "Gauss1" | "Gauss2" | "Gauss3" => Model::Gauss,
            "DanWood" => Model::DanWood,
            "Misra1b" => Model::Misra1b,
            "Kirby2" => Model::Kirby2,
            "Hahn1" | "Thurber" => Model::CubicRational,
            "Nelson" => Model::Nelson,
            "MGH17" => Model::Mgh17,
            "Misra1c" => Model::Misra1c,
            "Misra1d" => Model::Misra1d,
            "Roszman1" => Model::Roszman1,
            "ENSO" => Model::Enso,
            "MGH09" => Model::Mgh09,
            "Rat42" => Model::Rat42,
            "MGH10" => Model::Mgh10,
            "Eckerle4" => Model::Eckerle4,
            "Rat43" => Model::Rat43,
            "Bennett5" => Model::Bennett5,
            _ => return None,
        })
    }

    /// The fitted response for an observed `y` (Nelson fits `log y`).
    pub fn response(self, y: f64) -> f64 {
        match self {
            Model::Nelson => y.ln(),
            _ => y,
        }
    }

    /// Model value `f(x; b)`, generic so that dual numbers give exact derivatives.
    pub fn eval<T: DualNum<f64> + Copy>(self, b: &[T], x: &[f64]) -> T {
        let t = x[0];
        let one = T::from(1.0);
        match self {
            Model::Misra1a => b[0] * (one - (b[1] * -t).exp()),
            Model::Chwirut => (b[0] * -t).exp() / (b[1] + b[2] * t),
            Model::Lanczos => {
                b[0] * (b[1] * -t).exp() + b[2] * (b[3] * -t).exp() + b[4] * (b[5] * -t).exp()
            }
            Model::Gauss => {
                let g1 = (-(b[3] - t).powi(2) / b[4].powi(2)).exp();
                let g2 = (-(b[6] - t).powi(2) / b[7].powi(2)).exp();
                b[0] * (b[1] * -t).exp() + b[2] * g1 + b[5] * g2
            }
            Model::DanWood => b[0] * (b[1] * t.ln()).exp(),
            Model::Misra1b => b[0] * (one - (one + b[1] * (t / 2.0)).powi(-2)),
            Model::Kirby2 => (b[0] + b[1] * t + b[2] * (t * t)) / (one + b[3] * t + b[4] * (t * t)),
            Model::CubicRational => {
                let (t2, t3) = (t * t, t * t * t);
                (b[0] + b[1] * t + b[2] * t2 + b[3] * t3) / (one + b[4] * t + b[5] * t2 + b[6] * t3)
            }
            Model::Nelson => b[0] - b[1] * x[0] * (b[2] * -x[1]).exp(),
            Model::Mgh17 => b[0] + b[1] * (b[3] * -t).exp() + b[2] * (b[4] * -t).exp(),
            Model::Misra1c => b[0] * (one - (one + b[1] * (2.0 * t)).powf(-0.5)),
            Model::Misra1d => b[0] * b[1] * t / (one + b[1] * t),
            Model::Roszman1 => b[0] - b[1] * t - (b[2] / (-b[3] + t)).atan() / std::f64::consts::PI,
            Model::Enso => {
                let w = 2.0 * std::f64::consts::PI * t;
                let a4 = b[3].recip() * w;
                let a7 = b[6].recip() * w;
                b[0] + b[1] * (w / 12.0).cos()
                    + b[2] * (w / 12.0).sin()
                    + b[4] * a4.cos()
                    + b[5] * a4.sin()
                    + b[7] * a7.cos()
                    + b[8] * a7.sin()
            }
            Model::Mgh09 => b[0] * (b[1] * t + t * t) / (b[2] * t + b[3] + t * t),
            Model::Rat42 => b[0] / (one + (b[1] - b[2] * t).exp()),
            Model::Mgh10 => b[0] * (b[1] / (b[2] + t)).exp(),
            Model::Eckerle4 => {
                let u = (-b[2] + t) / b[1];
                b[0] / b[1] * (u * u * -0.5).exp()
            }
            Model::Rat43 => b[0] / ((one + (b[1] - b[2] * t).exp()).ln() / b[3]).exp(),
            Model::Bennett5 => b[0] * (-(b[1] + t).ln() / b[2]).exp(),
        }
    }
}

/// One StRD data set with its certified results.
#[derive(Debug, Clone)]
pub struct NistProblem {
    /// Data set name (file stem), e.g. `MGH09`.
    pub name: String,
    /// NIST's difficulty: `Lower`, `Average` or `Higher`.
    pub difficulty: String,
    /// The model.
    pub model: Model,
    /// Start 1 and Start 2.
    pub starts: [Vec<f64>; 2],
    /// Certified parameter values.
    pub certified: Vec<f64>,
    /// Certified standard deviations of the parameters.
    pub certified_sd: Vec<f64>,
    /// Certified residual sum of squares.
    pub certified_ss: f64,
    /// Predictors, one row per observation.
    pub x: Vec<Vec<f64>>,
    /// Observed responses (raw, before [`Model::response`]).
    pub y: Vec<f64>,
}

/// Parse `s` as f64, or an input error at `file:line:column`.
fn parse_f64(s: &str, file: &Path, line: usize, column: usize) -> Result<f64> {
    s.parse::<f64>().map_err(|_| {
        Error::input(
            file,
            line as u64,
            column as u64,
            format!("expected a number, found `{s}`; is this an unmodified NIST StRD file?"),
        )
    })
}

/// Whitespace-separated tokens of `line` with their 1-based columns.
fn tokens(line: &str) -> Vec<(usize, &str)> {
    let mut out = Vec::new();
    let mut start = None;
    for (i, c) in line.char_indices() {
        match (c.is_whitespace(), start) {
            (false, None) => start = Some(i),
            (true, Some(s)) => {
                out.push((s + 1, &line[s..i]));
                start = None;
            }
            _ => {}
        }
    }
    if let Some(s) = start {
        out.push((s + 1, &line[s..]));
    }
    out
}

/// The `(first, last)` 1-based line range the header gives for `label`, e.g.
/// `Data              (lines 61 to 74)`.
fn header_range(lines: &[&str], label: &str, file: &Path) -> Result<(usize, usize)> {
    for (i, l) in lines.iter().enumerate().take(20) {
        let Some(pos) = l.find(label) else { continue };
        let rest = &l[pos + label.len()..];
        let Some(open) = rest.find("(lines") else {
            continue;
        };
        let inner = rest[open + 6..].trim_end().trim_end_matches(')');
        let nums: Vec<_> = inner.split("to").map(|s| s.trim()).collect();
        if nums.len() == 2 {
            let col = pos + label.len() + open + 7;
            let a = parse_f64(nums[0], file, i + 1, col)? as usize;
            let b = parse_f64(nums[1], file, i + 1, col)? as usize;
            if a >= 1 && b >= a && b <= lines.len() {
                return Ok((a, b));
            }
            return Err(Error::input(
                file,
                i as u64 + 1,
                col as u64,
                format!(
                    "line range {a} to {b} does not fit a file of {} lines",
                    lines.len()
                ),
            ));
        }
    }
    Err(Error::input(
        file,
        1,
        1,
        format!("header has no `{label} (lines A to B)` entry; is this a NIST StRD file?"),
    ))
}

impl NistProblem {
    /// Read and parse a StRD `.dat` file; the data set name is the file stem.
    pub fn load(path: &Path) -> Result<NistProblem> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let name = path
            .file_stem()
            .and_then(|s| s.to_str())
            .unwrap_or_default()
            .to_string();
        NistProblem::parse(&name, &text, path)
    }

    /// Parse the text of a StRD file named `name` (`file` is only used in error messages).
    pub fn parse(name: &str, text: &str, file: &Path) -> Result<NistProblem> {
        let model = Model::from_name(name).ok_or_else(|| {
            Error::input(
                file,
                1,
                1,
                format!("`{name}` is not one of the 27 NIST StRD nonlinear data sets"),
            )
        })?;
        let lines: Vec<&str> = text.lines().collect();
        let (s0, s1) = header_range(&lines, "Starting Values", file)?;
        let (_, c1) = header_range(&lines, "Certified Values", file)?;
        let (d0, d1) = header_range(&lines, "Data ", file)?;
        let difficulty = lines
            .iter()
            .find_map(|l| {
                l.trim()
                    .strip_suffix("Level of Difficulty")
                    .map(|d| d.trim().to_string())
            })
            .unwrap_or_else(|| "Unknown".into());

        let mut starts = [Vec::new(), Vec::new()];
        let mut certified = Vec::new();
        let mut certified_sd = Vec::new();
        for ln in s0..=s1 {
            let l = lines[ln - 1];
            let toks = tokens(l);
            let eq = toks.iter().position(|(_, t)| *t == "=").ok_or_else(|| {
                Error::input(file, ln as u64, 1, "expected `bN = start1 start2 value sd`")
            })?;
            let vals = &toks[eq + 1..];
            if vals.len() != 4 {
                return Err(Error::input(
                    file,
                    ln as u64,
                    toks.last().map_or(1, |t| t.0) as u64,
                    format!("expected 4 numbers after `=`, found {}", vals.len()),
                ));
            }
            let v: Vec<f64> = vals
                .iter()
                .map(|(c, s)| parse_f64(s, file, ln, *c))
                .collect::<Result<_>>()?;
            starts[0].push(v[0]);
            starts[1].push(v[1]);
            certified.push(v[2]);
            certified_sd.push(v[3]);
        }
        let (ss_line, ss_text) = (s1 + 1..=c1)
            .map(|ln| (ln, lines[ln - 1]))
            .find(|(_, l)| l.contains("Residual Sum of Squares:"))
            .ok_or_else(|| {
                Error::input(
                    file,
                    c1 as u64,
                    1,
                    "no `Residual Sum of Squares:` line in the certified values",
                )
            })?;
        let (col, tok) = *tokens(ss_text)
            .last()
            .expect("line contains the label, so it has tokens");
        let certified_ss = parse_f64(tok, file, ss_line, col)?;

        let n_x = if model == Model::Nelson { 2 } else { 1 };
        let mut x = Vec::new();
        let mut y = Vec::new();
        for ln in d0..=d1 {
            let toks = tokens(lines[ln - 1]);
            if toks.len() != n_x + 1 {
                return Err(Error::input(
                    file,
                    ln as u64,
                    1,
                    format!(
                        "expected {} numbers (y and predictors), found {}",
                        n_x + 1,
                        toks.len()
                    ),
                ));
            }
            let v: Vec<f64> = toks
                .iter()
                .map(|(c, s)| parse_f64(s, file, ln, *c))
                .collect::<Result<_>>()?;
            y.push(v[0]);
            x.push(v[1..].to_vec());
        }
        Ok(NistProblem {
            name: name.to_string(),
            difficulty,
            model,
            starts,
            certified,
            certified_sd,
            certified_ss,
            x,
            y,
        })
    }

    /// Residuals `f(x_i; b) - response(y_i)`.
    pub fn residuals(&self, b: &DVector<f64>) -> DVector<f64> {
        let bs = b.as_slice();
        DVector::from_iterator(
            self.y.len(),
            self.x
                .iter()
                .zip(&self.y)
                .map(|(x, &y)| self.model.eval(bs, x) - self.model.response(y)),
        )
    }

    /// Exact Jacobian `∂f(x_i; b)/∂b_j`, one forward-mode dual pass per parameter.
    pub fn jacobian(&self, b: &DVector<f64>) -> DMatrix<f64> {
        let n = b.len();
        let mut j = DMatrix::zeros(self.y.len(), n);
        let mut bd: Vec<Dual64> = b.iter().map(|&v| Dual64::from(v)).collect();
        for k in 0..n {
            bd[k] = Dual64::from(b[k]).derivative();
            for (i, x) in self.x.iter().enumerate() {
                j[(i, k)] = self.model.eval(&bd, x).eps;
            }
            bd[k] = Dual64::from(b[k]);
        }
        j
    }
}

/// A StRD problem as an argmin problem.
pub struct NistFit<'a>(pub &'a NistProblem);

impl Operator for NistFit<'_> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, b: &DVector<f64>) -> std::result::Result<DVector<f64>, ArgminError> {
        Ok(self.0.residuals(b))
    }
}

impl Jacobian for NistFit<'_> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, b: &DVector<f64>) -> std::result::Result<DMatrix<f64>, ArgminError> {
        Ok(self.0.jacobian(b))
    }
}

/// Log relative error `-log10(|x - c|/|c|)`, capped at [`LRE_CAP`] (and at 0 from below).
pub fn lre(x: f64, certified: f64) -> f64 {
    if !x.is_finite() {
        return 0.0;
    }
    let rel = if certified == 0.0 {
        x.abs()
    } else {
        ((x - certified) / certified).abs()
    };
    if rel == 0.0 {
        LRE_CAP
    } else {
        (-rel.log10()).clamp(0.0, LRE_CAP)
    }
}

/// The outcome of one problem–start pair.
#[derive(Debug, Clone)]
pub struct NistResult {
    /// Data set name.
    pub problem: String,
    /// NIST difficulty.
    pub difficulty: String,
    /// 1 or 2.
    pub start: usize,
    /// LRE per parameter.
    pub lre: Vec<f64>,
    /// Minimum LRE over parameters (correct significant digits of the worst parameter).
    pub lre_min: f64,
    /// Trial steps taken (argmin iterations, over all runs).
    pub iterations: u64,
    /// Why the solver stopped (`None`: iteration limit).
    pub termination: Option<LmTermination>,
    /// Certified residual sum of squares.
    pub certified_ss: f64,
    /// Our residual sum of squares.
    pub ss: f64,
    /// Fitted parameters.
    pub param: Vec<f64>,
}

/// Iteration budget per run; every StRD problem converges in far fewer trial steps.
const MAX_ITERS: u64 = 5000;

/// Fit `problem` from start `start` (1 or 2) with the LM solver at its default tolerances.
pub fn solve(problem: &NistProblem, start: usize) -> Result<NistResult> {
    let x0 = DVector::from_vec(problem.starts[start - 1].clone());
    let options = LmOptions {
        max_iters: MAX_ITERS,
        ..LmOptions::default()
    };
    let run = minimize(NistFit(problem), x0, options)
        .map_err(|e| Error::Other(format!("{} start {start}: {e}", problem.name)))?;
    let (param, iterations, termination) = (run.param, run.iterations, run.termination);
    let ss = 2.0 * run.cost;
    let lres: Vec<f64> = param
        .iter()
        .zip(&problem.certified)
        .map(|(&x, &c)| lre(x, c))
        .collect();
    Ok(NistResult {
        problem: problem.name.clone(),
        difficulty: problem.difficulty.clone(),
        start,
        lre_min: lres.iter().copied().fold(LRE_CAP, f64::min),
        lre: lres,
        iterations,
        termination,
        certified_ss: problem.certified_ss,
        ss,
        param: param.iter().copied().collect(),
    })
}

/// The 27 data sets in NIST's order of difficulty (lower, average, higher).
pub const PROBLEMS: [&str; 27] = [
    "Misra1a", "Chwirut2", "Chwirut1", "Lanczos3", "Gauss1", "Gauss2", "DanWood", "Misra1b",
    "Kirby2", "Hahn1", "Nelson", "MGH17", "Lanczos1", "Lanczos2", "Gauss3", "Misra1c", "Misra1d",
    "Roszman1", "ENSO", "MGH09", "Thurber", "BoxBOD", "Rat42", "MGH10", "Eckerle4", "Rat43",
    "Bennett5",
];

/// Directory holding the suite's copy of the StRD files.
pub fn data_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/nist")
}

/// Run all 54 problem–start pairs from the files in `dir`.
pub fn run_dir(dir: &Path) -> Result<Vec<NistResult>> {
    let mut out = Vec::with_capacity(54);
    for name in PROBLEMS {
        let p = NistProblem::load(&dir.join(format!("{name}.dat")))?;
        for start in [1, 2] {
            out.push(solve(&p, start)?);
        }
    }
    Ok(out)
}

/// Run all 54 problem–start pairs from [`data_dir`].
pub fn run_all() -> Result<Vec<NistResult>> {
    run_dir(&data_dir())
}

/// Markdown table of results: problem, difficulty, start, LRE min, iterations, RSS.
pub fn markdown_table(results: &[NistResult]) -> String {
    let mut s = String::from(
        "| Problem | Difficulty | Start | LRE min | Iterations | Certified RSS | Our RSS |\n\
         |---|---|---|---|---|---|---|\n",
    );
    for r in results {
        s.push_str(&format!(
            "| {} | {} | {} | {:.1} | {} | {:.10e} | {:.10e} |\n",
            r.problem, r.difficulty, r.start, r.lre_min, r.iterations, r.certified_ss, r.ss
        ));
    }
    s
}

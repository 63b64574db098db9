//! One parameter's profile: the re-fits with it pinned on each side of the optimum, how each
//! starts (on the linearised path, then extrapolated from the solved points), and the search
//! for the Δχ² crossings (bracket, then regula falsi, aimed by the profile's local shape).

use super::{End, Optimum, Profile, CHI2_68, CHI2_95};
use crate::error::Result;
use crate::files::{FitJson, ProfileMethod};
use crate::fit::bounds::Bound;
use crate::fit::problem::{Evaluator, FitParam, Forward};
use crate::fit::solve::{is_cancelled, run_lm};

/// On a side without a fit bound the search stops this many typical ranges from the optimum.
pub(super) const SEARCH_RANGES: f64 = 3.0;
/// Bracketing steps per side at most.
const MAX_BRACKET: usize = 10;
const MAX_REFINE: usize = 4; // Regula-falsi steps per crossing at most.
/// A crossing is accepted when `√Δχ²` is this close to its target (Δχ² within ~2% at 68%).
const SQRT_TOL: f64 = 0.01;
/// A side's 95% end is the local quadratic's, without a re-fit there, when the re-fit at the
/// linearised SE found `√Δχ²` this close to 1 (Δχ² within 0.5%): with `Δχ² = x²(1 + c·x + q·x²)`
/// in units of the SE, `√Δχ²` is off by `c/2` at 1 SE and `1.96·c/2` at the 95% point (1.96 SE)
/// for a cubic term, by `q/2` and `3.84·q/2` for a quartic one, so the 95% end is off by at most
/// 3.84 × 2.5e-3 < 1% — inside the [`SQRT_TOL`] a re-fitted crossing is accepted at. (The demos'
/// sides that miss it by a cubic term lie at 1e-3–2.5e-3.)
const EXTRAPOLATE_TOL: f64 = 2.5e-3;
/// A profile solve stops when a step gains less than this many χ² units (the polish's own
/// tolerance is 10⁻¹²·dof, far finer than a crossing needs).
const SOLVE_CHI2_TOL: f64 = 1e-3;
/// LM iterations per profile solve at most (warm-started solves need 3–15).
const SOLVE_MAX_ITERS: u64 = 100;

/// A solved point at signed distance `h` from the optimum.
struct Pt {
    h: f64,
    d: f64,
    u: Vec<f64>,
}

/// One parameter pinned: an evaluator without it, and its solves.
struct Pinned<'a, 'o, F: Forward> {
    opt: &'o Optimum<'a, F>,
    ev: Evaluator<'a, F>,
    p: F::Param,
    x0: f64,
    iterations: u64,
    solves: usize,
}

impl<F: Forward> Pinned<'_, '_, F> {
    /// Δχ² at `x0 + h` with the other parameters re-minimised from `u_start`.
    fn solve(&mut self, h: f64, u_start: &[f64]) -> Pt {
        self.p.set(&mut self.ev.base, self.x0 + h);
        let max_iters = self.opt.max_iters.min(SOLVE_MAX_ITERS);
        let (u, cost, iterations) = self.run(u_start, max_iters);
        self.iterations += iterations;
        self.solves += 1;
        let d = 2.0 * (cost - self.opt.cost) / self.opt.chi2_unit;
        Pt {
            h,
            d: if d.is_finite() { d } else { f64::INFINITY },
            u,
        }
    }

    /// The fit's LM runner ([`run_lm`]), stopping once the cost change or the Gauss–Newton
    /// predicted χ² gain (a warm start that close takes no step) is below [`SOLVE_CHI2_TOL`],
    /// without a final linearisation: `(u, cost, iterations)`, never worse than the start (the
    /// solver's best point and its cost: no extra passes for the start's and the end's cost).
    fn run(&self, u0: &[f64], max_iters: u64) -> (Vec<f64>, f64, u64) {
        let ftol =
            (SOLVE_CHI2_TOL / self.opt.dof.max(1) as f64).clamp(crate::fit::solve::FTOL, 1e-4);
        let solver = crate::lm::LevenbergMarquardt::new()
            .with_tolerances(ftol, crate::lm::DEFAULT_XTOL, 0.0)
            .and_then(|lm| lm.with_statistical_tolerance(self.opt.dof.max(1), SOLVE_CHI2_TOL))
            .unwrap_or_default()
            .with_lazy_final_linearization();
        let run = run_lm(&self.ev, u0, solver, max_iters, &self.opt.cancel, None);
        (run.u, run.cost, run.iterations)
    }

    /// Bracket both thresholds on one side out to `hmax`, from `pts` (the optimum and the side's
    /// first re-fit, if it had room for one); the points, ascending in |h|. `None` when
    /// cancelled.
    fn bracket(&mut self, hmax: f64, mut pts: Vec<Pt>, shape: Option<Shape>) -> Option<Vec<Pt>> {
        while (2..=MAX_BRACKET).contains(&pts.len()) {
            let last = &pts[pts.len() - 1];
            let (dir, h, d) = (last.h.signum(), last.h.abs(), last.d);
            if d >= CHI2_95 || near(d, CHI2_95) || h >= hmax || quadratic_end(&pts, hmax).is_some()
            {
                break;
            }
            // The first re-fits on both sides give the profile's local shape: aim at its 95%
            // crossing, which the crossing search then accepts as it stands when the shape
            // holds (one solve, not a bracket and a refinement). Without one, where the first
            // step (the linearised SE) found Δχ² ≈ 1, aim at the local quadratic's crossing,
            // h·√(3.84/d). Otherwise a parabola through the optimum reaches 1.3·3.84 at
            // h·√(5/d); grow by 1.5–4×.
            let aimed = match pts.len() {
                2 => shape.and_then(|s| s.crossing(CHI2_95, dir)).map(f64::abs),
                _ => None,
            };
            let grow = if pts.len() == 2 && near(d, CHI2_68) {
                (CHI2_95 / d).sqrt()
            } else {
                (1.3 * CHI2_95 / d.max(0.05)).sqrt().clamp(1.5, 4.0)
            };
            let h = aimed.unwrap_or(h * grow).min(hmax);
            if is_cancelled(&self.opt.cancel) {
                return None;
            }
            // The other parameters move nearly linearly with the pinned one near the optimum:
            // start where the last two points extrapolate to (the LM then settles in about one
            // iteration instead of two).
            let n = pts.len();
            let start = extrapolate(&pts[n - 2], &pts[n - 1], dir * h);
            let pt = self.solve(dir * h, &start);
            pts.push(pt);
        }
        Some(pts)
    }

    /// Where the side's profile crosses `target` (refining between bracketing points, which are
    /// added to `pts`), or where it ends open.
    /// `shape`: the profile's local shape, whose crossing is the first refinement's aim when it
    /// lies in the bracket (regula falsi after that).
    fn crossing(
        &mut self,
        pts: &mut Vec<Pt>,
        target: f64,
        bounded: bool,
        shape: Option<Shape>,
    ) -> Option<End> {
        let Some(k) = pts.iter().position(|p| p.d >= target || near(p.d, target)) else {
            let last = pts.last()?;
            return Some(End::Open {
                at: self.x0 + last.h,
                dchi2: last.d,
                bound: bounded,
            });
        };
        if near(pts[k].d, target) {
            return Some(End::Closed(self.x0 + pts[k].h));
        }
        let g = |d: f64| d.max(0.0).sqrt() - target.sqrt();
        let (mut a, mut b) = (k - 1, k);
        let mut aim = shape.and_then(|s| s.crossing(target, pts[b].h.signum()));
        for _ in 0..MAX_REFINE {
            let (pa, pb) = (&pts[a], &pts[b]);
            let (ga, gb) = (g(pa.d), g(pb.d));
            if gb.abs() < SQRT_TOL {
                return Some(End::Closed(self.x0 + pb.h));
            }
            if ga.abs() < SQRT_TOL && a > 0 {
                return Some(End::Closed(self.x0 + pa.h));
            }
            let (lo, hi) = (pa.h.min(pb.h), pa.h.max(pb.h));
            let mut h = match aim.take().filter(|&h| h > lo && h < hi) {
                Some(h) => h,
                None => pa.h + (pb.h - pa.h) * (-ga) / (gb - ga),
            };
            if !(h > lo && h < hi && h.is_finite()) {
                h = 0.5 * (pa.h + pb.h);
            }
            if is_cancelled(&self.opt.cancel) {
                return None;
            }
            let near = if (h - pa.h).abs() < (h - pb.h).abs() {
                pa.u.clone()
            } else {
                pb.u.clone()
            };
            let pt = self.solve(h, &near);
            let below = pt.d < target;
            pts.insert(b, pt);
            // The new point sits at index b; the old b moved to b + 1.
            if below {
                a = b;
                b += 1;
            }
        }
        let (pa, pb) = (&pts[a], &pts[b]);
        let (ga, gb) = (g(pa.d), g(pb.d));
        let t = if gb != ga { -ga / (gb - ga) } else { 0.5 };
        Some(End::Closed(
            self.x0 + pa.h + (pb.h - pa.h) * t.clamp(0.0, 1.0),
        ))
    }
}

/// The point on the line through `a` and `b` (solved points, in the solver's coordinates) at
/// pinned offset `h`.
fn extrapolate(a: &Pt, b: &Pt, h: f64) -> Vec<f64> {
    let t = if b.h != a.h {
        (h - b.h) / (b.h - a.h)
    } else {
        0.0
    };
    a.u.iter()
        .zip(&b.u)
        .map(|(ua, ub)| ub + (ub - ua) * t)
        .collect()
}

/// The profile near the optimum as `Δχ² = x²(1 + c·x + q·x²)` with `x = h/unit`, from the first
/// re-fits at `h = ±unit` (`d₋`, `d₊`): `c = (d₊ − d₋)/2` (the asymmetry), `q = (d₊ + d₋)/2 − 1`.
/// Kept only for a skewed profile, `|c| ≥` [`SQRT_TOL`]: the quadratic through a side's own
/// first point then aims its 95% re-fit off by about `0.94·|c|` in `√Δχ²` (`x²·c·(x − 1)` at
/// x = 1.96), beyond what the crossing accepts, while this shape follows the skew. Below it the
/// quadratic's aim lands, and the shape's even part `q` (of the order of the re-fits' own χ²
/// tolerance) would only add error.
#[derive(Debug, Clone, Copy)]
struct Shape {
    unit: f64,
    c: f64,
    q: f64,
}

impl Shape {
    /// From the two sides' first solved points, when they sit at `∓unit` with finite Δχ² and the
    /// profile is skewed.
    fn of(lower: &Pt, upper: &Pt) -> Option<Shape> {
        let unit = upper.h;
        let c = 0.5 * (upper.d - lower.d);
        let skewed = c.abs() >= SQRT_TOL;
        (skewed && unit > 0.0 && lower.h == -unit && lower.d.is_finite() && upper.d.is_finite())
            .then_some(Shape {
                unit,
                c,
                q: 0.5 * (upper.d + lower.d) - 1.0,
            })
    }

    /// The offset `h` on side `dir` where the shape reaches `target`, when the shape rises there
    /// and moves the crossing by at most 25% from the pure quadratic's (beyond that it is no
    /// longer a small correction, and the bracket finds the crossing instead).
    fn crossing(&self, target: f64, dir: f64) -> Option<f64> {
        let x0 = dir * target.sqrt();
        let mut x = x0;
        for _ in 0..30 {
            let f = x * x * (1.0 + self.c * x + self.q * x * x) - target;
            let slope = x * (2.0 + 3.0 * self.c * x + 4.0 * self.q * x * x);
            // Falling or flat (or NaN) here: no crossing this shape can aim at.
            if slope * dir <= 0.0 || slope.is_nan() {
                return None;
            }
            let dx = f / slope;
            x -= dx;
            if dx.abs() <= 1e-12 * x.abs() {
                break;
            }
        }
        let ratio = x / x0;
        (ratio.is_finite() && (0.75..=1.25).contains(&ratio)).then_some(x * self.unit)
    }
}

/// The side's 95% offset from the local quadratic, when its only solve (at the linearised SE)
/// found Δχ² within [`EXTRAPOLATE_TOL`] of 1 and the offset is inside the side's room `hmax`.
fn quadratic_end(pts: &[Pt], hmax: f64) -> Option<f64> {
    let [_, first] = pts else {
        return None;
    };
    let h95 = first.h.abs() * (CHI2_95 / first.d).sqrt();
    ((first.d.sqrt() - 1.0).abs() < EXTRAPOLATE_TOL && h95 <= hmax)
        .then_some(first.h.signum() * h95)
}

/// Whether a solved Δχ² is close enough to `target` to be its crossing: `√Δχ²` within
/// [`SQRT_TOL`] of `√target`.
fn near(d: f64, target: f64) -> bool {
    (d.max(0.0).sqrt() - target.sqrt()).abs() < SQRT_TOL
}

/// How a profile starts: its first step from the optimum (natural units, the linearised SE) and
/// the linearised profile path, `∂x_k/∂x_j = ρ_kj·σ_k/σ_j` for every free `k` (natural units; 1 at
/// `j`): where the other parameters' minimum moves as the pinned one does, to first order.
#[derive(Debug, Clone, Default)]
pub struct FirstStep {
    pub step: Option<f64>,
    pub slopes: Vec<f64>,
}

/// Profile free parameter `j` of `opt`, stepping first by `first.step` along `first.slopes`.
/// `None` when cancelled.
pub fn profile_parameter<F: Forward>(
    opt: &Optimum<'_, F>,
    j: usize,
    first: &FirstStep,
) -> Result<Option<Profile<F::Param>>> {
    let step = first.step;
    let p = opt.free[j];
    let free: Vec<F::Param> = opt.free.iter().copied().filter(|&q| q != p).collect();
    let (ev, _) = Evaluator::new(
        opt.forward,
        opt.data,
        opt.space,
        opt.loss,
        opt.loss_scale,
        opt.params.clone(),
        free,
    )?;
    let x0 = p.get(&opt.params);
    let mut u0 = opt.u.clone();
    u0.remove(j);
    let (a, b) = p.typical_range();
    let width = (b - a).abs().max(1e-12);
    let step = step
        .filter(|s| s.is_finite() && *s > 0.0)
        .unwrap_or(0.05 * width)
        .clamp(1e-6 * width, width);
    let mut pin = Pinned {
        opt,
        ev,
        p,
        x0,
        iterations: 0,
        solves: 0,
    };
    let far = SEARCH_RANGES * width;
    let (lo_room, lo_bounded, hi_room, hi_bounded) = match p.bound() {
        Bound::Free => (far, false, far, false),
        Bound::Lower(lo) => ((x0 - lo).max(0.0), true, far, false),
        Bound::Both(lo, hi) => ((x0 - lo).max(0.0), true, (hi - x0).max(0.0), true),
    };
    let mut ends = [[End::Closed(x0); 2]; 2];
    let mut methods = [ProfileMethod::Refits; 2];
    let mut points = Vec::new();
    let sides = [(-1.0, lo_room, lo_bounded), (1.0, hi_room, hi_bounded)];
    // Each side's first re-fit, at the linearised SE (or the side's room, if less), before either
    // side goes on: together they give the profile's local shape. Each starts on the linearised
    // path (the re-fit then has only the profile's curvature left to settle); without one, the
    // lower side's from the optimum and the upper side's from the lower side's solved point
    // mirrored through the optimum.
    let mut firsts: Vec<Option<Pt>> = Vec::with_capacity(2);
    let mut mirrored: Option<Vec<f64>> = None;
    for &(dir, room, _) in &sides {
        let h = step.min(room);
        if h <= 0.0 {
            firsts.push(None);
            continue;
        }
        if is_cancelled(&opt.cancel) {
            return Ok(None);
        }
        let start = path_start(opt, j, &first.slopes, dir * h)
            .or_else(|| mirrored.take())
            .unwrap_or_else(|| u0.clone());
        let pt = pin.solve(dir * h, &start);
        if pt.h == -step {
            mirrored = Some(u0.iter().zip(&pt.u).map(|(o, f)| 2.0 * o - f).collect());
        }
        firsts.push(Some(pt));
    }
    let shape = match (&firsts[0], &firsts[1]) {
        (Some(lower), Some(upper)) => Shape::of(lower, upper),
        _ => None,
    };
    for (side, (&(_, room, bounded), first)) in sides.iter().zip(firsts).enumerate() {
        let mut pts = vec![Pt {
            h: 0.0,
            d: 0.0,
            u: u0.clone(),
        }];
        pts.extend(first);
        let Some(mut pts) = pin.bracket(room, pts, shape) else {
            return Ok(None);
        };
        if let Some(h95) = quadratic_end(&pts, room) {
            ends[0][side] = End::Closed(x0 + pts[1].h);
            ends[1][side] = End::Closed(x0 + h95);
            methods[side] = ProfileMethod::Extrapolated;
        } else {
            for (t, target) in [CHI2_68, CHI2_95].into_iter().enumerate() {
                let Some(end) = pin.crossing(&mut pts, target, bounded, shape) else {
                    return Ok(None);
                };
                ends[t][side] = end;
            }
            // Two solves, no refinement inserted: the SE's solve at Δχ² ≈ 1 and the aimed 95%
            // point at ≈ 3.84 were taken as they stand.
            if pts.len() == 3 && near(pts[1].d, CHI2_68) && near(pts[2].d, CHI2_95) {
                methods[side] = ProfileMethod::Quadratic;
            }
        }
        points.extend(pts.iter().skip(side).map(|pt| (x0 + pt.h, pt.d)));
    }
    points.sort_by(|a, b| a.0.total_cmp(&b.0));
    Ok(Some(Profile {
        name: p,
        points,
        end_68: ends[0],
        end_95: ends[1],
        iterations: pin.iterations,
        solves: pin.solves,
        methods,
    }))
}

/// The solver coordinates of parameter `j`'s pinned evaluator (every free parameter but `j`) at
/// offset `h` along the linearised path `slopes`; the explicit log-scales as at the optimum.
/// `None` without a full set of slopes (the optimum is then the start).
fn path_start<F: Forward>(
    opt: &Optimum<'_, F>,
    j: usize,
    slopes: &[f64],
    h: f64,
) -> Option<Vec<f64>> {
    let nf = opt.free.len();
    if slopes.len() != nf || !slopes.iter().all(|s| s.is_finite()) {
        return None;
    }
    // Each coordinate on the branch of the optimum's own (the solver's points may sit on any
    // period of a bound's transform, and the next solves extrapolate through both).
    let mut u: Vec<f64> = (0..nf)
        .filter(|&k| k != j)
        .map(|k| {
            let p = opt.free[k];
            let b = p.bound();
            b.to_internal_near(b.clamp(p.get(&opt.params) + slopes[k] * h), opt.u[k])
        })
        .collect();
    u.extend_from_slice(&opt.u[nf..]);
    u.iter().all(|v| v.is_finite()).then_some(u)
}

/// Each free parameter's first step (its natural standard error) and linearised profile path,
/// from fit.json's standard errors and correlations (report units; the ratio `σ_k/σ_j` is taken
/// in natural units). A parameter without an error has no path.
pub fn first_steps<P: FitParam>(json: &FitJson, free: &[P]) -> Vec<FirstStep> {
    let se: Vec<Option<f64>> = free
        .iter()
        .map(|&p| {
            json.parameters
                .iter()
                .find(|e| e.name == p.json_name())
                .and_then(|e| e.std_error)
                .map(|se| se / p.report_factor())
        })
        .collect();
    let names = &json.correlation.names;
    let at: Vec<Option<usize>> = free
        .iter()
        .map(|&p| names.iter().position(|n| *n == p.json_name()))
        .collect();
    let rho = |a: usize, b: usize| -> Option<f64> {
        let (ia, ib) = (at[a]?, at[b]?);
        json.correlation.matrix.get(ia)?.get(ib).copied().flatten()
    };
    (0..free.len())
        .map(|j| {
            // A parameter without an error or a correlation stays where the optimum has it.
            let slopes = match se[j] {
                Some(sj) if sj > 0.0 => (0..free.len())
                    .map(|k| match (k == j, se[k], rho(k, j)) {
                        (true, ..) => 1.0,
                        (false, Some(sk), Some(r)) => r * sk / sj,
                        _ => 0.0,
                    })
                    .collect(),
                _ => Vec::new(),
            };
            FirstStep {
                step: se[j],
                slopes,
            }
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    fn pt(h: f64, d: f64) -> Pt {
        Pt {
            h,
            d,
            u: Vec::new(),
        }
    }

    /// On an exact cubic–quartic profile the shape from its two first points finds the true
    /// crossings (to the Newton iteration's 1e-12), where the quadratic through one side's
    /// point misses by ~0.94·c in √Δχ².
    #[test]
    fn a_skewed_profile_is_aimed_at_its_own_crossing() {
        let (c, q, unit) = (-0.12, 0.006, 0.5);
        let profile = |x: f64| x * x * (1.0 + c * x + q * x * x);
        let shape = Shape::of(&pt(-unit, profile(-1.0)), &pt(unit, profile(1.0))).unwrap();
        for (target, dir) in [(CHI2_95, -1.0), (CHI2_95, 1.0), (CHI2_68, -1.0)] {
            let h = shape.crossing(target, dir).unwrap();
            assert!(
                (profile(h / unit) - target).abs() < 1e-9,
                "{target} {dir}: {h}"
            );
        }
        let quadratic = (CHI2_95 / profile(-1.0)).sqrt();
        assert!((profile(-quadratic).sqrt() - CHI2_95.sqrt()).abs() > SQRT_TOL);
    }

    /// A profile whose asymmetry is below the crossing tolerance gets no shape (the quadratic's
    /// aim lands, and the shape's even part is the re-fits' noise), nor does one that bends
    /// over before its crossing.
    #[test]
    fn a_nearly_symmetric_or_turning_profile_has_no_aim() {
        assert!(Shape::of(&pt(-1.0, 1.004), &pt(1.0, 0.996)).is_none());
        assert!(Shape::of(&pt(-1.0, 1.004), &pt(0.5, 0.996)).is_none());
        let turning = Shape::of(&pt(-1.0, 1.6), &pt(1.0, 0.4)).unwrap();
        assert_eq!(turning.crossing(CHI2_95, 1.0), None);
    }
}

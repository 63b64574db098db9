//! The mapping fit: a renderer's variant of the Chiang model ([`crate::families::chiang::variant`]) fitted
//! by least squares in log S to the source fit's `S` over the measured directions plus a dense
//! sphere, with the project's Levenberg–Marquardt and exact AD Jacobians.
//!
//! Free variables are unconstrained transforms of the renderer's parameters, so every iterate is
//! a valid parameter set: `η = 1 + eˣ`, `σ_a = x²`, `β = 1/(1 + e⁻ˣ)` (0 < β < 1), `α = x`
//! (radians), `gain = eˣ`. Residuals are `ln(S_variant + f_c) − ln(S_source + f_c)` with a
//! per-channel floor `f_c` = [`FLOOR_FRACTION`] × the channel's largest source value, so
//! directions where both are negligibly dark do not dominate.

use argmin::core::{Jacobian, Operator};
use nalgebra::{DMatrix, DVector};
use num_dual::{DualDVec64, DualNum, DualSVec64};

use super::super::family::ChiangEvaluation;
use super::super::variant::{
    variant_jacobian, variant_jacobian_static, variant_scattering_batch, Formulation, Tilt,
    VariantParams,
};
use super::super::{ChiangEffects, ChiangModel, ChiangParams};
use crate::error::{Error, Result};
use crate::export::reference::{
    least_squares, log_errors, log_floored, max, rms, MappingTarget, FLOOR_FRACTION, MAX_ITERATIONS,
};
use crate::export::source::{SourceFit, SourceModel};
use crate::families::FamilyModel;
use crate::geometry::Angles;

/// A fitted mapping from the source fit to one renderer's parameters.
#[derive(Debug, Clone)]
pub struct Mapping {
    pub formulation: Formulation,
    /// The renderer's parameters (α in radians, in the renderer's sign convention).
    pub params: VariantParams<f64>,
    /// True when the renderer evaluates the source model itself (Chiang fit to pbrt-v4).
    pub exact: bool,
    pub n_measured: usize,
    pub n_sphere: usize,
    /// rms and max of `|ln(S_renderer + f) − ln(S_source + f)|` over all directions and channels.
    pub rms_log: f64,
    pub max_log: f64,
    /// The same rms over the measured directions only (None without curves.csv).
    pub rms_log_measured: Option<f64>,
    pub iterations: u64,
    pub starts: usize,
    /// A Chiang fit with a term switched off: the rms and max `|d ln S|` of the renderer at the
    /// fit's own parameters (every term on, the formula conversion's start point) against the
    /// fit's S — what exporting the parameters unchanged would cost. None otherwise.
    pub as_fitted: Option<(f64, f64)>,
}

impl Mapping {
    /// One line: how the renderer's parameters were obtained and how well they reproduce S.
    pub fn quality_text(&self) -> String {
        if self.exact {
            return format!(
                "exact: the renderer evaluates the fitted model itself (checked over {} measured \
                 + {} sphere directions: max |d ln S| {:.1e})",
                self.n_measured, self.n_sphere, self.max_log
            );
        }
        let measured = match self.rms_log_measured {
            Some(r) => format!(", measured directions only {r:.4}"),
            None => String::new(),
        };
        format!(
            "renderer model fitted over {} measured + {} sphere directions: rms |d ln S| {:.4} \
             (max {:.3}{measured}; floor {FLOOR_FRACTION:e} of each channel's peak), {} LM \
             iterations from {} starts",
            self.n_measured,
            self.n_sphere,
            self.rms_log,
            self.max_log,
            self.iterations,
            self.starts
        )
    }
}

/// Fit `formulation` to the source's S (or, for a Chiang fit exported to pbrt-v4, take it as is
/// and check that it is).
pub fn fit_mapping(source: &SourceFit, formulation: Formulation) -> Result<Mapping> {
    let MappingTarget {
        angles,
        target,
        floor,
        n_sphere,
    } = MappingTarget::new(source)?;
    let n = source.model.n_channels();
    let final_model = ChiangModel::default();
    let (params, exact, iterations, starts) = match (&source.model.model, formulation.tilt) {
        (FamilyModel::Chiang(ChiangEvaluation { params: p, model }), Tilt::Exit)
            if formulation == Formulation::PBRT_V4 && model.effects == ChiangEffects::default() =>
        {
            (
                VariantParams {
                    chiang: p.clone(),
                    gain: 1.0,
                },
                true,
                0,
                1,
            )
        }
        _ => {
            let problem = MappingProblem {
                angles: &angles,
                target_log: log_floored(&target, &floor, n),
                floor: floor.clone(),
                n,
                formulation,
                // The default (automatic) rule: S within 1e-7 at any β_n, as the errors use.
                model: ChiangModel::default(),
            };
            let starts = start_points(&source.model, &formulation);
            let mut best: Option<(f64, DVector<f64>)> = None;
            let mut iterations = 0;
            for x0 in &starts {
                let (cost, x, iters) = problem.solve(x0)?;
                iterations += iters;
                if best.as_ref().is_none_or(|(c, _)| cost < *c) {
                    best = Some((cost, x));
                }
            }
            let (_, x) = best.expect("at least one start");
            (
                build::<f64>(x.as_slice(), n, formulation.gain),
                false,
                iterations,
                starts.len(),
            )
        }
    };
    let errors_of = |p: &VariantParams<f64>| -> Vec<f64> {
        let mut fitted = vec![0.0; target.len()];
        variant_scattering_batch(p, &formulation, &final_model, &angles, &mut fitted);
        log_errors(&fitted, &target, &floor, n)
    };
    let errors = errors_of(&params);
    let as_fitted = match &source.model.model {
        FamilyModel::Chiang(c) if c.model.effects != ChiangEffects::default() => {
            let start = &start_points(&source.model, &formulation)[0];
            let e = errors_of(&build::<f64>(start, n, formulation.gain));
            Some((rms(&e), max(&e)))
        }
        _ => None,
    };
    let n_measured = source.measured.len();
    let mapping = Mapping {
        formulation,
        params,
        exact,
        n_measured,
        n_sphere,
        rms_log: rms(&errors),
        max_log: max(&errors),
        rms_log_measured: (n_measured > 0).then(|| rms(&errors[..n_measured * n])),
        iterations,
        starts,
        as_fitted,
    };
    if !(mapping.rms_log.is_finite() && mapping.max_log.is_finite()) {
        return Err(Error::Other(
            "the mapping fit ended with non-finite errors; the source fit may be degenerate".into(),
        ));
    }
    Ok(mapping)
}

/// The renderer's parameters from the free variables `[η, σ_a…, β_m, β_n, α, (gain)]`.
pub fn build<T: DualNum<f64>>(x: &[T], n: usize, gain: bool) -> VariantParams<T> {
    let logistic = |t: &T| ((-t.clone()).exp() + 1.0).recip();
    VariantParams {
        chiang: ChiangParams {
            eta: x[0].exp() + 1.0,
            sigma_a: x[1..=n].iter().map(|s| s.powi(2)).collect(),
            beta_m: logistic(&x[n + 1]),
            beta_n: logistic(&x[n + 2]),
            alpha: x[n + 3].clone(),
        },
        gain: if gain { x[n + 4].exp() } else { T::from(1.0) },
    }
}

/// The inverse of [`build`].
pub fn unbuild(p: &VariantParams<f64>, gain: bool) -> Vec<f64> {
    let logit = |b: f64| {
        let b = b.clamp(1e-6, 1.0 - 1e-6);
        (b / (1.0 - b)).ln()
    };
    let c = &p.chiang;
    let mut x = vec![(c.eta - 1.0).max(1e-6).ln()];
    // σ_a = x²: start off zero, where the derivative vanishes.
    x.extend(c.sigma_a.iter().map(|s| s.max(1e-4).sqrt()));
    x.extend([logit(c.beta_m), logit(c.beta_n), c.alpha]);
    if gain {
        x.push(p.gain.max(1e-12).ln());
    }
    x
}

/// Where the LM starts. A Chiang source: its own parameters, α mirrored for a θ_i-tilt renderer
/// (R sits at −α there). Another family with an R lobe: η and σ_a as fitted, β_m from R's width
/// (√v₀ ≈ 0.726β_m for small β), α from R's shift (the same sign rule), β_n at two widths.
fn start_points(model: &SourceModel, formulation: &Formulation) -> Vec<Vec<f64>> {
    let sign = match formulation.tilt {
        Tilt::Exit => 1.0,
        Tilt::Incidence => -1.0,
    };
    let gain = 1.0 / formulation.factor;
    let starts: Vec<VariantParams<f64>> = match &model.model {
        FamilyModel::Chiang(ChiangEvaluation { params: p, .. }) => vec![VariantParams {
            chiang: ChiangParams {
                alpha: sign * p.alpha,
                ..p.clone()
            },
            gain,
        }],
        _ => match model.specular_lobe() {
            Some(lobe) => [0.3, 0.7]
                .iter()
                .map(|&beta_n| VariantParams {
                    chiang: ChiangParams {
                        eta: lobe.eta,
                        sigma_a: lobe.sigma_a.clone(),
                        beta_m: (lobe.width / 0.726).clamp(0.02, 0.9),
                        beta_n,
                        alpha: sign * lobe.shift,
                    },
                    gain,
                })
                .collect(),
            // No R lobe to start from: the typical middle of pbrt's ranges, β_n at two widths.
            None => [0.3, 0.7]
                .iter()
                .map(|&beta_n| VariantParams {
                    chiang: ChiangParams {
                        beta_n,
                        ..crate::families::chiang::reference_params(model.n_channels())
                    },
                    gain,
                })
                .collect(),
        },
    };
    starts
        .iter()
        .map(|p| unbuild(p, formulation.gain))
        .collect()
}

/// The least-squares problem of one mapping: residuals in log S, exact Jacobian.
struct MappingProblem<'a> {
    angles: &'a [Angles],
    target_log: Vec<f64>,
    floor: Vec<f64>,
    n: usize,
    formulation: Formulation,
    model: ChiangModel,
}

impl MappingProblem<'_> {
    fn residuals(&self, x: &[f64]) -> Vec<f64> {
        let params = build::<f64>(x, self.n, self.formulation.gain);
        let mut s = vec![0.0; self.target_log.len()];
        variant_scattering_batch(&params, &self.formulation, &self.model, self.angles, &mut s);
        s.iter()
            .enumerate()
            .map(|(k, v)| (v + self.floor[k % self.n]).ln() - self.target_log[k])
            .collect()
    }

    /// Run LM from `x0`: (cost ½‖r‖², solution, iterations).
    fn solve(&self, x0: &[f64]) -> Result<(f64, DVector<f64>, u64)> {
        let (x, iterations) = least_squares(ProblemRef(self), x0, MAX_ITERATIONS)?;
        let r = self.residuals(x.as_slice());
        let cost = 0.5 * r.iter().map(|v| v * v).sum::<f64>();
        Ok((cost, x, iterations))
    }
}

/// argmin takes the problem by value; a reference keeps the directions borrowed.
struct ProblemRef<'a, 'b>(&'a MappingProblem<'b>);

impl Operator for ProblemRef<'_, '_> {
    type Param = DVector<f64>;
    type Output = DVector<f64>;
    fn apply(&self, x: &DVector<f64>) -> std::result::Result<DVector<f64>, argmin::core::Error> {
        // A non-finite residual is a failed trial step to the solver, not an error.
        Ok(DVector::from_vec(self.0.residuals(x.as_slice())))
    }
}

impl Jacobian for ProblemRef<'_, '_> {
    type Param = DVector<f64>;
    type Jacobian = DMatrix<f64>;
    fn jacobian(&self, x: &DVector<f64>) -> std::result::Result<DMatrix<f64>, argmin::core::Error> {
        let p = self.0;
        let gain = p.formulation.gain;
        let x = x.as_slice();
        let (values, jac) = match x.len() {
            5 => static_jacobian::<5>(p, x),
            6 => static_jacobian::<6>(p, x),
            7 => static_jacobian::<7>(p, x),
            8 => static_jacobian::<8>(p, x),
            _ => variant_jacobian(
                x,
                |d: &[DualDVec64]| build(d, p.n, gain),
                &p.formulation,
                &p.model,
                p.angles,
            ),
        };
        let m = DMatrix::from_fn(values.len(), x.len(), |k, j| {
            jac[k][j] / (values[k] + p.floor[k % p.n])
        });
        if m.iter().any(|v| !v.is_finite()) {
            return Err(argmin::core::Error::msg(
                "non-finite Jacobian in the mapping fit",
            ));
        }
        Ok(m)
    }
}

/// Values and Jacobian rows with stack duals for the common sizes (1 or 3 channels, with or
/// without a gain): the heap duals allocate per operation and are ~10× slower.
fn static_jacobian<const N: usize>(p: &MappingProblem<'_>, x: &[f64]) -> (Vec<f64>, Vec<Vec<f64>>) {
    let x: [f64; N] = x.try_into().expect("N matches the variable count");
    let gain = p.formulation.gain;
    let (values, jac) = variant_jacobian_static(
        &x,
        |d: &[DualSVec64<N>]| build(d, p.n, gain),
        &p.formulation,
        &p.model,
        p.angles,
    );
    (values, jac.into_iter().map(|r| r.to_vec()).collect())
}

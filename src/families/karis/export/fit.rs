//! The Unreal mapping fit: the engine's material inputs (Base Color per channel, Roughness,
//! Specular, Backlit, Scatter) and ONE shared gain (the light's intensity), fitted by least
//! squares in log S to the source fit's `S` over the measured directions plus the dense sphere
//! ([`crate::export::reference::MappingTarget`]). The engine's model is the Karis family with every
//! term on and the engine's fixed η and cuticle shift; the colour can only come from Base Color.
//!
//! Free variables are unconstrained: each input in `[lo, 1]` is `lo + (1 − lo) sin² x` (every
//! iterate is a value the engine accepts, and the ends are reachable: a Backlit of 1 or a
//! Scatter of 0 is written as such), the gain is `eˣ`. Exact Jacobians by forward-mode duals.

use nalgebra::{allocator::Allocator, Const, DefaultAllocator, Dim, Dyn, U1};
use num_dual::{Derivative, DualNum, DualVec64};

use super::super::{
    Karis, BACKLIT, BASE_COLOR, ENGINE_ETA, ENGINE_SHIFT, ETA, MIN_ROUGHNESS, ROUGHNESS, SCATTER,
    SCATTER_TERM, SHIFT, SPECULAR,
};
use crate::error::{Error, Result};
use crate::export::log_fit::{fit_log, LogErrors, LogFit, LogModel, LogTarget};
use crate::export::reference::{max, rms, MappingTarget};
use crate::export::source::{SourceFit, SourceModel};
use crate::families::table::{
    clear_terms, total, zero_terms, DynTable, Table, TableFamily, TableParams, TermSet,
};
use crate::families::{FamilyModel, TableModel};
use crate::geometry::Angles;

/// The smallest Base Color the fit reaches (the engine takes `ln C`).
pub const MIN_BASE_COLOR: f64 = 1e-4;

/// The engine's inputs for `n` channels (`base_color[c]`), and the light's gain.
#[derive(Debug, Clone, PartialEq)]
pub struct EngineInputs {
    pub base_color: Vec<f64>,
    pub roughness: f64,
    pub specular: f64,
    pub backlit: f64,
    pub scatter: f64,
    /// The factor on the engine's `S` (the light's intensity) that matches the source's.
    pub gain: f64,
}

impl EngineInputs {
    /// The Karis family's parameters of these inputs, η and the shift at the engine's values.
    pub fn table_params(&self) -> TableParams<f64> {
        engine_params(
            self.base_color.clone(),
            [self.roughness, self.specular, self.backlit, self.scatter],
        )
    }
}

/// Karis parameters from Base Color and `[roughness, specular, backlit, scatter]`.
fn engine_params<T: DualNum<f64>>(base_color: Vec<T>, shared: [T; 4]) -> TableParams<T> {
    let n_channels = base_color.len();
    let mut values = vec![Vec::new(); Karis::PARAMETERS.len()];
    values[BASE_COLOR] = base_color;
    for (k, v) in [ROUGHNESS, SPECULAR, BACKLIT, SCATTER]
        .into_iter()
        .zip(shared)
    {
        values[k] = vec![v];
    }
    values[ETA] = vec![T::from(ENGINE_ETA)];
    values[SHIFT] = vec![T::from(ENGINE_SHIFT)];
    TableParams { values, n_channels }
}

/// What the engine renders: every term.
pub fn engine_terms() -> TermSet {
    TermSet::all(Karis::TERMS.len())
}

/// The engine's `S` (times `gain`) at every direction, `out[k·n + c]`.
pub fn engine_scattering(inputs: &EngineInputs, on: TermSet, angles: &[Angles]) -> Vec<f64> {
    let p = inputs.table_params();
    let mut out = vec![0.0; angles.len() * p.n_channels];
    Table::<Karis>::NEW.eval_batch(&p, on, angles, &mut out);
    out.iter_mut().for_each(|v| *v *= inputs.gain);
    out
}

/// A fitted mapping from the source fit to the engine's inputs.
#[derive(Debug, Clone)]
pub struct EngineMapping {
    pub inputs: EngineInputs,
    /// `|ln(S_engine + f) − ln(S_source + f)|` over all directions and channels.
    pub errors: LogErrors,
    /// Directions: measured (curves.csv), then the dense sphere.
    pub directions: (usize, usize),
    /// LM iterations, and starts.
    pub work: (u64, usize),
    /// A Karis fit: the (rms, max) error of the engine at the fit's own parameters (gain 1) —
    /// what passing them on unchanged costs; 0 when the engine renders the fitted model itself.
    pub as_fitted: Option<(f64, f64)>,
    /// Scatter above 0: the (rms, max) error without the scatter term, which the engine's hair
    /// strands do not render.
    pub without_scatter: Option<(f64, f64)>,
}

impl EngineMapping {
    /// One line: how the inputs were obtained and how well they reproduce S.
    pub fn quality_text(&self) -> String {
        let e = &self.errors;
        let measured = match e.rms_measured {
            Some(r) => format!(", measured directions only {r:.4}"),
            None => String::new(),
        };
        format!(
            "engine inputs fitted over {} measured + {} sphere directions: rms |d ln S| {:.4} \
             (max {:.3}{measured}; floor {:e} of each channel's peak), {} LM iterations from {} \
             starts",
            self.directions.0,
            self.directions.1,
            e.rms,
            e.max,
            crate::export::reference::FLOOR_FRACTION,
            self.work.0,
            self.work.1
        )
    }
}

/// `lo + (1 − lo) sin² x`: a value in `[lo, 1]` from any `x`.
fn unit<T: DualNum<f64>>(x: &T, lo: f64) -> T {
    x.sin().powi(2) * (1.0 - lo) + lo
}

/// The inverse of [`unit`] (the `x` in `[0, π/2]`).
fn unit_inverse(v: f64, lo: f64) -> f64 {
    ((v - lo) / (1.0 - lo)).clamp(0.0, 1.0).sqrt().asin()
}

/// The Karis parameters and gain from the free variables
/// `[Base Color…, Roughness, Specular, Backlit, Scatter, ln gain]`.
fn build<T: DualNum<f64>>(x: &[T], n: usize) -> (TableParams<T>, T) {
    let colour = x[..n].iter().map(|v| unit(v, MIN_BASE_COLOR)).collect();
    let shared = [
        unit(&x[n], MIN_ROUGHNESS),
        unit(&x[n + 1], 0.0),
        unit(&x[n + 2], 0.0),
        unit(&x[n + 3], 0.0),
    ];
    (engine_params(colour, shared), x[n + 4].exp())
}

/// The inputs at the free variables `x`.
fn inputs_of(x: &[f64], n: usize) -> EngineInputs {
    let (p, gain) = build::<f64>(x, n);
    EngineInputs {
        base_color: p.values[BASE_COLOR].clone(),
        roughness: p.values[ROUGHNESS][0],
        specular: p.values[SPECULAR][0],
        backlit: p.values[BACKLIT][0],
        scatter: p.values[SCATTER][0],
        gain,
    }
}

/// The free variables of `inputs` (the inverse of [`build`]).
fn unbuild(inputs: &EngineInputs) -> Vec<f64> {
    let mut x: Vec<f64> = (inputs.base_color.iter())
        .map(|c| unit_inverse(*c, MIN_BASE_COLOR))
        .collect();
    x.push(unit_inverse(inputs.roughness, MIN_ROUGHNESS));
    x.extend([inputs.specular, inputs.backlit, inputs.scatter].map(|v| unit_inverse(v, 0.0)));
    x.push(inputs.gain.max(1e-300).ln());
    x
}

/// Where the LM starts: a Karis fit's own inputs (the engine renders that model, so this is
/// the answer when its η and shift are the engine's); for a fit with an R lobe, the
/// legacy colour of its σ_a (`C = e^{−4σ_a}`, docs/karis.md) and the Roughness whose lobe
/// width matches its β; then two generic starts. Values sit off the ends of `[0, 1]`, where
/// the transform's derivative vanishes, unless the source put them there.
fn start_inputs(model: &SourceModel) -> Vec<EngineInputs> {
    let n = model.n_channels();
    let generic = |colour: f64, roughness: f64| EngineInputs {
        base_color: vec![colour; n],
        roughness,
        specular: 0.5,
        backlit: 0.95,
        scatter: 0.02,
        gain: 1.0,
    };
    let legacy_colour = |sigma_a: &[f64]| -> Vec<f64> {
        let colour = sigma_a.iter().map(|s| (-4.0 * s).exp().clamp(0.01, 0.99));
        colour.collect()
    };
    let mut starts = match &model.model {
        FamilyModel::Table(TableModel { table, params, .. }) if table.name() == Karis::NAME => {
            let get = |k: usize| params.values[k][0];
            vec![EngineInputs {
                base_color: params.values[BASE_COLOR].clone(),
                roughness: get(ROUGHNESS),
                specular: get(SPECULAR),
                backlit: get(BACKLIT),
                scatter: get(SCATTER),
                gain: 1.0,
            }]
        }
        // Karis's θ_h width of R is ≈ r²/2.
        _ => (model.specular_lobe().into_iter())
            .map(|lobe| EngineInputs {
                base_color: legacy_colour(&lobe.sigma_a),
                roughness: (2.0 * lobe.width).sqrt().clamp(0.1, 1.0),
                ..generic(0.5, 0.5)
            })
            .collect(),
    };
    starts.extend([generic(0.3, 0.35), generic(0.6, 0.6)]);
    starts
}

/// Fit the engine's inputs to the source's `S`.
pub fn fit_engine(source: &SourceFit) -> Result<EngineMapping> {
    let t = MappingTarget::new(source)?;
    let angles = &t.angles;
    let n = source.model.n_channels();
    let target = LogTarget::new(&t.target, n);
    let model = UnrealModel { angles, n };
    let starts = start_inputs(&source.model);
    let gain = unbuild(&starts[0]).len() - 1;
    let x0: Vec<Vec<f64>> = (starts.iter())
        .map(|start| target.with_best_gain(&model, unbuild(start), gain))
        .collect();
    let LogFit { x, iterations, .. } = fit_log(&model, &target, &x0)?;
    let inputs = inputs_of(&x, n);
    let errors_of = |inputs: &EngineInputs, on: TermSet| {
        let e = target.errors(&engine_scattering(inputs, on, angles));
        (rms(&e), max(&e), e)
    };
    let n_measured = source.measured.len();
    let (_, _, all) = errors_of(&inputs, engine_terms());
    let errors = LogErrors::of(&all, n_measured * n);
    let as_fitted = match &source.model.model {
        FamilyModel::Table(TableModel { table, .. }) if table.name() == Karis::NAME => {
            let (r, m, _) = errors_of(&starts[0], engine_terms());
            Some((r, m))
        }
        _ => None,
    };
    let strands = TermSet(engine_terms().0 & !(1 << SCATTER_TERM));
    let without_scatter = (inputs.scatter > 0.0).then(|| {
        let (r, m, _) = errors_of(&inputs, strands);
        (r, m)
    });
    if !(errors.rms.is_finite() && errors.max.is_finite()) {
        return Err(Error::Other(
            "the Unreal mapping fit ended with non-finite errors; the source fit may be degenerate"
                .into(),
        ));
    }
    Ok(EngineMapping {
        inputs,
        errors,
        directions: (n_measured, t.n_sphere),
        work: (iterations, starts.len()),
        as_fitted,
        without_scatter,
    })
}

/// The engine's `S` as a function of the free variables, for [`fit_log`]; exact Jacobians by
/// forward-mode duals (on the stack for 1 and 3 channels).
struct UnrealModel<'a> {
    angles: &'a [Angles],
    n: usize,
}

impl UnrealModel<'_> {
    /// `S` (times the gain) and its derivatives in the `dim` free variables, row-major.
    fn dual_pass<D: Dim>(&self, dim: D, x: &[f64]) -> (Vec<f64>, Vec<f64>)
    where
        DefaultAllocator: Allocator<D>,
        DualVec64<D>: DualNum<f64>,
    {
        let seeded: Vec<DualVec64<D>> = (x.iter().enumerate())
            .map(|(j, &v)| DualVec64::new(v, Derivative::derivative_generic(dim, U1, j)))
            .collect();
        let (p, gain) = build(&seeded, self.n);
        let rows = self.angles.len() * self.n;
        let (mut values, mut jac) = (vec![0.0; rows], vec![0.0; rows * x.len()]);
        let mut terms = zero_terms::<DualVec64<D>>(self.n);
        for (i, a) in self.angles.iter().enumerate() {
            clear_terms(&mut terms);
            Karis::scatter(&p, a, engine_terms(), &mut terms);
            for (c, t) in terms.iter().enumerate() {
                let row = i * self.n + c;
                let s = total(t) * gain.clone();
                values[row] = s.re;
                let e = s.eps.unwrap_generic(dim, U1);
                jac[row * x.len()..(row + 1) * x.len()].copy_from_slice(e.as_slice());
            }
        }
        (values, jac)
    }
}

impl LogModel for UnrealModel<'_> {
    fn values(&self, x: &[f64]) -> Vec<f64> {
        engine_scattering(&inputs_of(x, self.n), engine_terms(), self.angles)
    }

    fn jacobian(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        // 5 shared variables besides Base Color.
        match x.len() {
            6 => self.dual_pass(Const::<6>, x),
            8 => self.dual_pass(Const::<8>, x),
            nx => self.dual_pass(Dyn(nx), x),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The transform reaches both ends and inverts.
    #[test]
    fn unit_transform_inverts_and_reaches_its_ends() {
        for v in [0.0, 1e-3, 0.37, 0.999, 1.0] {
            let x = unit_inverse(v, 0.0);
            assert!((unit(&x, 0.0) - v).abs() < 1e-12, "{v}");
        }
        let x = unit_inverse(0.5, MIN_ROUGHNESS);
        assert!((unit(&x, MIN_ROUGHNESS) - 0.5).abs() < 1e-12);
    }

    /// From a generic start (not the truth) the LM finds Karis inputs that generated the target:
    /// noise-free, so the error must fall to the solver's precision (1e-6 rms in ln S) and the
    /// inputs to 1e-4 of the truth (the ln S tolerance propagated through the weakest input).
    #[test]
    fn recovers_karis_inputs_from_a_generic_start() {
        let truth = EngineInputs {
            base_color: vec![0.2, 0.35, 0.6],
            roughness: 0.45,
            specular: 0.4,
            backlit: 0.8,
            scatter: 0.1,
            gain: 2.0,
        };
        let angles = crate::export::reference::dense_sphere();
        let target = engine_scattering(&truth, engine_terms(), &angles);
        let model = UnrealModel {
            angles: &angles,
            n: 3,
        };
        let target = LogTarget::new(&target, 3);
        let start = EngineInputs {
            base_color: vec![0.3; 3],
            roughness: 0.35,
            specular: 0.5,
            backlit: 0.95,
            scatter: 0.02,
            gain: 1.0,
        };
        let x0 = target.with_best_gain(&model, unbuild(&start), 3 + 4);
        let fit = fit_log(&model, &target, &[x0]).unwrap();
        let got = inputs_of(&fit.x, 3);
        let r = target.residuals(&model.values(&fit.x));
        assert!(rms(&r) < 1e-6, "{} {got:?}", rms(&r));
        let close = |a: f64, b: f64| (a - b).abs() < 1e-4 * b.max(1.0);
        assert!(got
            .base_color
            .iter()
            .zip(&truth.base_color)
            .all(|(a, b)| close(*a, *b)));
        for (a, b) in [
            (got.roughness, truth.roughness),
            (got.specular, truth.specular),
            (got.backlit, truth.backlit),
            (got.scatter, truth.scatter),
            (got.gain, truth.gain),
        ] {
            assert!(close(a, b), "{got:?}");
        }
    }
}

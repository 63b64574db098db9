//! Marschner's model as the fit sees it: its parameters as [`FitParam`]s and the model under one
//! configuration as a [`Forward`] ([`MarschnerForward`]), with exact gradients by forward-mode
//! AD ([`gradients`]).

use nalgebra::{allocator::Allocator, DefaultAllocator, Dim, U1};
use num_dual::{Derivative, DualNum, DualVec64};

use crate::families::marschner::jacobian::seeded;
use crate::families::marschner::{
    scattering_batch, scattering_by_lobe, scattering_by_lobe_lanes, scattering_lanes, ModelConfig,
    ModelNum, ParamName, Params,
};
use crate::fit::bounds::Bound;
use crate::fit::problem::{with_dual_dim, FitParam, Forward};
use crate::geometry::{Angles, Measurement};

impl FitParam for ParamName {
    type Set = Params<f64>;
    fn get(self, p: &Params<f64>) -> f64 {
        p.get(self)
    }
    fn set(self, p: &mut Params<f64>, value: f64) {
        p.set(self, value)
    }
    fn bound(self) -> Bound {
        fit_bound(self)
    }
    fn json_name(self) -> String {
        ParamName::json_name(&self)
    }
    fn report_factor(self) -> f64 {
        crate::families::marschner::parameters::report_factor(self)
    }
    fn typical_range(self) -> (f64, f64) {
        crate::families::marschner::parameters::typical_range(self)
    }
    fn check_domain(self, report_value: f64) -> std::result::Result<(), String> {
        self.fact().check(report_value)
    }
    fn channel(self) -> Option<usize> {
        match self {
            ParamName::SigmaA(c) => Some(c),
            _ => None,
        }
    }
}

/// The Marschner model of [`crate::families::marschner`] under one configuration, as the data measure it:
/// `S`, or `S · cos θ_i` for radiance ([`Measurement`]).
#[derive(Debug, Clone, Copy)]
pub struct MarschnerForward {
    pub config: ModelConfig,
    pub measurement: Measurement,
}

impl MarschnerForward {
    /// [`Forward::values`] in any number type: `f64`, or dual numbers whose derivative parts
    /// then carry exact gradients ([`gradients`]).
    pub fn values_in<T: ModelNum>(&self, p: &Params<T>, angles: &[Angles], out: &mut [T]) {
        let nc = p.sigma_a.len();
        scattering_batch(p, &self.config, angles, &mut out[..angles.len() * nc]);
        self.measurement
            .apply(angles, &mut out[..angles.len() * nc]);
    }
}

impl Forward for MarschnerForward {
    type Param = ParamName;

    /// In f64 the lanes run the model ([`scattering_lanes`]: several samples per vector in
    /// cubic mode, the scalar model in exact mode and for any lane off the common path): the
    /// fit's value passes (each LM trial step, the multi-start's) cost a third of the scalar
    /// model's. Their values agree with the gradient passes' to ~1e-13 relative (the lanes' own
    /// transcendental functions), far inside any fit's tolerance.
    fn values(&self, p: &Params<f64>, angles: &[Angles], out: &mut [f64]) {
        let rows = angles.len() * p.sigma_a.len();
        scattering_lanes(p, &self.config, angles, &mut out[..rows]);
        self.measurement.apply(angles, &mut out[..rows]);
    }

    fn gradients(
        &self,
        p: &Params<f64>,
        free: &[ParamName],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        gradients(self, p, free, angles, out, grad)
    }

    fn gradients_compressed(
        &self,
        p: &Params<f64>,
        shared: &[ParamName],
        local: &[Option<ParamName>],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        with_dual_dim!(shared.len() + 1, |dim| compressed_dim(
            self,
            dim,
            p,
            (shared, local),
            angles,
            (out, grad)
        ));
    }

    fn measurement(&self) -> Measurement {
        self.measurement
    }
    fn exact_values(&self, p: &Params<f64>, angles: &[Angles], out: &mut [f64]) -> bool {
        // Only the transmitted lobes' root maps differ between the modes.
        let lobes = self.config.effects.lobes;
        if self.config.mode == crate::families::marschner::RootMode::Exact
            || !(lobes.tt || lobes.trt)
        {
            return false;
        }
        let exact = MarschnerForward {
            config: ModelConfig {
                mode: crate::families::marschner::RootMode::Exact,
                ..self.config
            },
            measurement: self.measurement,
        };
        exact.values(p, angles, out);
        true
    }
    fn by_lobe(&self, p: &Params<f64>, angles: &Angles, out: &mut [[f64; 3]]) -> bool {
        scattering_by_lobe(p, &self.config, angles, out);
        self.measurement
            .apply(std::slice::from_ref(angles), out.as_flattened_mut());
        true
    }
    /// On the lanes, as the value passes ([`scattering_by_lobe_lanes`]).
    fn by_lobe_batch(&self, p: &Params<f64>, angles: &[Angles], out: &mut [[f64; 3]]) -> bool {
        scattering_by_lobe_lanes(p, &self.config, angles, out);
        self.measurement.apply(angles, out.as_flattened_mut());
        true
    }
}

/// Values of the Marschner `forward` into `out`, and `grad[(k * nc + c) * nf + j]` =
/// ∂value/∂`free[j]` (natural units), by forward-mode AD.
pub fn gradients(
    forward: &MarschnerForward,
    p: &Params<f64>,
    free: &[ParamName],
    angles: &[Angles],
    out: &mut [f64],
    grad: &mut [f64],
) {
    with_dual_dim!(free.len(), |dim| gradients_dim(
        forward,
        dim,
        p,
        free,
        angles,
        (out, grad)
    ));
}

/// [`gradients`] with `dim`-sized dual numbers; `(out, grad)` as there.
fn gradients_dim<D: Dim>(
    forward: &MarschnerForward,
    dim: D,
    p: &Params<f64>,
    free: &[ParamName],
    angles: &[Angles],
    (out, grad): (&mut [f64], &mut [f64]),
) where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    dual_pass(forward, dim, &seeded(p, free, dim), angles, out, grad)
}

/// [`Forward::gradients_compressed`] for the Marschner model: `shared[i]` seeded in dual slot
/// `i`, every free `σ_a[c]` in the last slot (channel `c` depends on `σ_a[c]` alone).
fn compressed_dim<D: Dim>(
    forward: &MarschnerForward,
    dim: D,
    p: &Params<f64>,
    (shared, local): (&[ParamName], &[Option<ParamName>]),
    angles: &[Angles],
    (out, grad): (&mut [f64], &mut [f64]),
) where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    let mut pd = seeded(p, shared, dim);
    for &name in local.iter().flatten() {
        let direction = Derivative::derivative_generic(dim, U1, shared.len());
        pd.set(name, DualVec64::new(p.get(name), direction));
    }
    dual_pass(forward, dim, &pd, angles, out, grad)
}

/// Values and the `dim` derivative parts of the seeded parameters `pd`, per sample and channel.
fn dual_pass<D: Dim>(
    forward: &MarschnerForward,
    dim: D,
    pd: &Params<DualVec64<D>>,
    angles: &[Angles],
    out: &mut [f64],
    grad: &mut [f64],
) where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    let nw = dim.value();
    let nc = pd.sigma_a.len();
    // The whole chunk at once, so the parameter-only factors are computed once.
    let mut o: Vec<DualVec64<D>> = vec![DualVec64::from_re(0.0); angles.len() * nc];
    forward.values_in(pd, angles, &mut o);
    for (r, v) in o.into_iter().enumerate() {
        out[r] = v.re;
        let e = v.eps.unwrap_generic(dim, U1);
        grad[r * nw..(r + 1) * nw].copy_from_slice(e.as_slice());
    }
}

/// The fit bounds of `name` in the parameter table (natural units, radians).
pub fn fit_bound(name: ParamName) -> Bound {
    match name.fact().fit_bounds() {
        (lo, Some(hi)) => Bound::Both(lo, hi),
        (lo, None) => Bound::Lower(lo),
    }
}

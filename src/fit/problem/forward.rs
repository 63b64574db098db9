//! The forward model as the fit sees it: the [`Forward`] trait (model values for a chunk of
//! samples, in any number type), its implementation by the Marschner model under one
//! configuration, and exact gradients of any [`Forward`] by forward-mode AD ([`gradients`]).

use nalgebra::{allocator::Allocator, Const, DefaultAllocator, Dim, Dyn, U1};
use num_dual::{DualNum, DualVec64};

use crate::model::jacobian::seeded;
use crate::model::{
    scattering, scattering_by_lobe, Angles, Measurement, ModelConfig, ParamName, Params,
};

/// The forward model seen by the fit: values and exact gradients for a chunk of samples.
pub trait Forward: Sync {
    /// `out[k * nc + c]` = model value of sample `k`, channel `c`, in any number type: `f64`, or
    /// dual numbers whose derivative parts then carry exact gradients ([`gradients`]).
    fn values<T: DualNum<f64>>(&self, p: &Params<T>, angles: &[Angles], out: &mut [T]);
    /// Per-lobe values `[R, TT, TRT]` per channel (for curves.csv); `None` when not available.
    fn by_lobe(&self, _p: &Params<f64>, _angles: &Angles, _out: &mut [[f64; 3]]) -> bool {
        false
    }
}

/// The Marschner model of [`crate::model`] under one configuration, as the data measure it:
/// `S`, or `S · cos θ_i` for radiance ([`Measurement`]).
#[derive(Debug, Clone, Copy)]
pub struct ModelForward {
    pub config: ModelConfig,
    pub measurement: Measurement,
}

impl Forward for ModelForward {
    fn values<T: DualNum<f64>>(&self, p: &Params<T>, angles: &[Angles], out: &mut [T]) {
        let nc = p.sigma_a.len();
        for (a, o) in angles.iter().zip(out.chunks_mut(nc)) {
            scattering(p, &self.config, a, o);
            // The factor depends on θ_i only, so values and derivatives scale alike.
            if self.measurement != Measurement::S {
                let f = self.measurement.factor(a);
                o.iter_mut().for_each(|v| *v = v.clone() * f);
            }
        }
    }

    fn by_lobe(&self, p: &Params<f64>, angles: &Angles, out: &mut [[f64; 3]]) -> bool {
        scattering_by_lobe(p, &self.config, angles, out);
        let f = self.measurement.factor(angles);
        out.iter_mut().flatten().for_each(|v| *v *= f);
        true
    }
}

/// Values of `forward` into `out`, and `grad[(k * nc + c) * nf + j]` = ∂value/∂`free[j]`
/// (natural units), by forward-mode AD.
pub fn gradients<F: Forward>(
    forward: &F,
    p: &Params<f64>,
    free: &[ParamName],
    angles: &[Angles],
    out: &mut [f64],
    grad: &mut [f64],
) {
    macro_rules! dispatch {
        ($($n:literal)*) => {
            match free.len() {
                $($n => gradients_dim(forward, Const::<$n>, p, free, angles, (out, grad)),)*
                nf => gradients_dim(forward, Dyn(nf), p, free, angles, (out, grad)),
            }
        };
    }
    // Static dual sizes avoid a heap allocation per arithmetic operation; every realistic
    // free-parameter count (≤ η + 3σ_a + 5 shape = 9, plus headroom) has one.
    dispatch!(1 2 3 4 5 6 7 8 9 10 11 12);
}

/// [`gradients`] with `dim`-sized dual numbers; `(out, grad)` as there.
fn gradients_dim<F: Forward, D: Dim>(
    forward: &F,
    dim: D,
    p: &Params<f64>,
    free: &[ParamName],
    angles: &[Angles],
    (out, grad): (&mut [f64], &mut [f64]),
) where
    DefaultAllocator: Allocator<D>,
    DualVec64<D>: DualNum<f64>,
{
    let nf = free.len();
    let nc = p.sigma_a.len();
    let pd = seeded(p, free, dim);
    let mut o: Vec<DualVec64<D>> = vec![DualVec64::from_re(0.0); nc];
    for (k, a) in angles.iter().enumerate() {
        forward.values(&pd, std::slice::from_ref(a), &mut o);
        for (c, v) in o.iter().enumerate() {
            out[k * nc + c] = v.re;
            let e = v.eps.clone().unwrap_generic(dim, U1);
            let row = &mut grad[(k * nc + c) * nf..(k * nc + c + 1) * nf];
            row.copy_from_slice(e.as_slice());
        }
    }
}

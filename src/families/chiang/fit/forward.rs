//! The Chiang model as the fit sees it: [`FitParam`] for [`ChiangParamName`] (bounds and
//! reporting facts from [`crate::families::chiang::PARAMETERS`]) and [`ChiangForward`], whose values and exact
//! Jacobians come from the batch evaluators, so a chunk pays the width integral once per exit
//! direction: with η fixed (the default) the plain-f64 [`fixed_eta`] path, with `--free eta`
//! stack duals for every realistic parameter count.

use crate::families::chiang::evaluator::scattering_by_lobe;
use crate::families::chiang::{
    batch_jacobian, batch_jacobian_static, fixed_eta, ChiangModel, ChiangParamName, ChiangParams,
};
use crate::fit::bounds::Bound;
use crate::fit::problem::{FitParam, Forward};
use crate::geometry::{Angles, Measurement};

impl ChiangParamName {
    /// Factor from the model's value to the file's (180/π for α, else 1).
    pub fn file_factor(self) -> f64 {
        if self == ChiangParamName::Alpha {
            180.0 / std::f64::consts::PI
        } else {
            1.0
        }
    }
}

impl FitParam for ChiangParamName {
    type Set = ChiangParams<f64>;
    fn get(self, p: &ChiangParams<f64>) -> f64 {
        ChiangParams::get(p, self)
    }
    fn set(self, p: &mut ChiangParams<f64>, value: f64) {
        ChiangParams::set(p, self, value)
    }
    fn bound(self) -> Bound {
        let f = self.fact();
        Bound::Both(
            f.fit_lo / self.file_factor(),
            f.fit_hi.unwrap_or(f64::INFINITY) / self.file_factor(),
        )
    }
    fn json_name(self) -> String {
        ChiangParamName::json_name(&self)
    }
    fn report_factor(self) -> f64 {
        self.file_factor()
    }
    fn typical_range(self) -> (f64, f64) {
        let (a, b) = self.fact().typical;
        (a / self.file_factor(), b / self.file_factor())
    }
    fn check_domain(self, report_value: f64) -> std::result::Result<(), String> {
        self.fact().check(report_value)
    }
    fn channel(self) -> Option<usize> {
        match self {
            ChiangParamName::SigmaA(c) => Some(c),
            _ => None,
        }
    }
}

/// The Chiang model under one configuration, as the data measure it: `S`, or `S · cos θ_i`
/// for radiance.
#[derive(Debug, Clone)]
pub struct ChiangForward {
    pub model: ChiangModel,
    pub measurement: Measurement,
}

impl Forward for ChiangForward {
    fn measurement(&self) -> Measurement {
        self.measurement
    }
    type Param = ChiangParamName;

    fn values(&self, p: &ChiangParams<f64>, angles: &[Angles], out: &mut [f64]) {
        // Plain f64 values: the fixed-η path is valid for any η when no derivative is asked.
        fixed_eta::batch(p, &self.model, angles, &[], out, None);
        let nc = p.sigma_a.len();
        self.measurement
            .apply(angles, &mut out[..angles.len() * nc]);
    }

    fn gradients(
        &self,
        p: &ChiangParams<f64>,
        free: &[ChiangParamName],
        angles: &[Angles],
        out: &mut [f64],
        grad: &mut [f64],
    ) {
        let nc = p.sigma_a.len();
        if !free.contains(&ChiangParamName::Eta) {
            fixed_eta::batch(p, &self.model, angles, free, out, Some(grad));
            self.apply_measurement(angles, nc, out, grad);
            return;
        }
        macro_rules! dispatch {
            ($($n:literal)*) => {
                match free.len() {
                    $($n => {
                        let which: &[ChiangParamName; $n] = free.try_into().expect("length checked");
                        let mut jac = vec![[0.0; $n]; out.len()];
                        batch_jacobian_static(p, &self.model, angles, which, out, &mut jac);
                        for (row, j) in grad.chunks_mut($n).zip(&jac) {
                            row.copy_from_slice(j);
                        }
                    })*
                    // Heap duals for parameter lists longer than the static dispatch covers.
                    _ => {
                        let (values, jac) = batch_jacobian(p, &self.model, angles, free);
                        out.copy_from_slice(&values);
                        for (row, j) in grad.chunks_mut(free.len()).zip(&jac) {
                            row.copy_from_slice(j);
                        }
                    }
                }
            };
        }
        // Stack duals: η + 3 σ_a + β_m, β_n, α = 7 for RGB; headroom for more channels.
        dispatch!(1 2 3 4 5 6 7 8 9 10);
        self.apply_measurement(angles, nc, out, grad);
    }

    /// With η fixed, values and derivatives come from one plain-f64 pass (the derivatives add
    /// about a fifth to its time) whose values are the value pass's to the bit.
    fn cheap_gradients(&self, free: &[ChiangParamName]) -> bool {
        !free.contains(&ChiangParamName::Eta)
    }

    fn by_lobe(&self, p: &ChiangParams<f64>, angles: &Angles, out: &mut [[f64; 3]]) -> bool {
        scattering_by_lobe(p, &self.model, angles, out);
        self.measurement
            .apply(std::slice::from_ref(angles), out.as_flattened_mut());
        true
    }
}

impl ChiangForward {
    /// Values and gradients of S scaled to what the data measure ([`Measurement::apply`]).
    fn apply_measurement(&self, angles: &[Angles], nc: usize, out: &mut [f64], grad: &mut [f64]) {
        self.measurement
            .apply(angles, &mut out[..angles.len() * nc]);
        self.measurement.apply(angles, grad);
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::chiang::{all_parameters, reference_params, ChiangEffects};

    /// Eight channels with η free is 12 parameters, past the stack-dual dispatch: the heap-dual
    /// branch must give the same derivatives as one-parameter stack duals column by column.
    /// Both are exact forward-mode AD of the same arithmetic, so they agree to rounding: 1e-12
    /// relative leaves room for a different summation order and nothing more.
    #[test]
    fn heap_duals_past_the_dispatch_match_stack_duals() {
        let nc = 8;
        let forward = ChiangForward {
            model: ChiangModel::new(ChiangEffects::default(), 64).unwrap(),
            measurement: Measurement::default(),
        };
        let p = reference_params(nc);
        let free = all_parameters(nc);
        assert!(free.len() > 10 && free.contains(&ChiangParamName::Eta));
        let angles: Vec<Angles> = (0..5)
            .map(|k| Angles {
                theta_i: 0.3 - 0.1 * k as f64,
                phi_i: 0.0,
                theta_r: -0.2 + 0.05 * k as f64,
                phi_r: 0.4 + 0.6 * k as f64,
            })
            .collect();
        let m = angles.len() * nc;
        let (mut out, mut grad) = (vec![0.0; m], vec![0.0; m * free.len()]);
        forward.gradients(&p, &free, &angles, &mut out, &mut grad);
        for (j, &param) in free.iter().enumerate() {
            // η free keeps the dual path; `param` first, so its column is column 0.
            let pair: Vec<ChiangParamName> = if param == ChiangParamName::Eta {
                vec![param]
            } else {
                vec![param, ChiangParamName::Eta]
            };
            let (mut o1, mut g2) = (vec![0.0; m], vec![0.0; m * pair.len()]);
            forward.gradients(&p, &pair, &angles, &mut o1, &mut g2);
            let g1: Vec<f64> = g2.chunks(pair.len()).map(|r| r[0]).collect();
            for i in 0..m {
                let (a, b) = (grad[i * free.len() + j], g1[i]);
                assert!(
                    (a - b).abs() <= 1e-12 * a.abs().max(b.abs()).max(1e-300),
                    "{param:?} row {i}: heap {a} vs stack {b}"
                );
                assert_eq!(out[i].to_bits(), o1[i].to_bits(), "value row {i}");
            }
        }
    }
}

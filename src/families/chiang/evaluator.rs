//! Evaluating `S`: per sample, or per batch with the width integral cached per exit direction.
//!
//! `Ñ_p` and `Ā₃` depend on (θ_r, φ) only and `S` is even in φ, so a batch keys its
//! [`AzimuthalTable`]s on (θ_r, |φ|): a rig with many incidences (and mirrored azimuths) per exit
//! direction pays the width integral once per distinct key; each sample then costs only its four
//! `M_p`.

use std::collections::HashMap;

use num_dual::DualNum;

use super::azimuthal::AzimuthalTable;
use super::longitudinal::{base_variance, longitudinal};
use super::{combine, ChiangEffects, ChiangModel, ChiangParams, WidthScratch};
use crate::geometry::angles::wrap;
use crate::geometry::Angles;

/// `M_p(θ_i, θ_r)` for p = 0..3, 0 where the term is off (and then not computed).
#[inline]
pub fn longitudinal_terms<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    effects: &ChiangEffects,
    theta_i: f64,
    theta_r: f64,
) -> [T; 4] {
    let v0 = base_variance(&params.beta_m);
    let on = [effects.r, effects.tt, effects.trt, effects.residual];
    std::array::from_fn(|p| {
        if on[p] {
            longitudinal(p, theta_i, theta_r, &params.alpha, &v0)
        } else {
            T::from(0.0)
        }
    })
}

/// `S` per channel for incidence `theta_i` from the table of its exit direction `theta_r`.
pub fn scattering_from_table<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    effects: &ChiangEffects,
    table: &AzimuthalTable<T>,
    theta_i: f64,
    theta_r: f64,
    out: &mut [T],
) {
    assert_eq!(out.len(), params.sigma_a.len(), "one output per channel");
    let m = longitudinal_terms(params, effects, theta_i, theta_r);
    let cos_i = theta_i.cos();
    for (c, o) in out.iter_mut().enumerate() {
        *o = combine(&m, &table.lobes[c], &table.residual[c], cos_i);
    }
}

/// The width integral of exit direction (`theta_r`, `phi`) over `model`'s width nodes (a
/// composite rule's written into `scratch`, reused across directions).
pub fn fill_table<T: DualNum<f64>>(
    table: &mut AzimuthalTable<T>,
    params: &ChiangParams<T>,
    model: &ChiangModel,
    theta_r: f64,
    phi: f64,
    scratch: &mut WidthScratch,
) {
    let (eta, beta_n) = (params.eta.re(), params.beta_n.re());
    let nodes = model.width_nodes_for(eta, beta_n, theta_r, phi, scratch);
    table.fill(params, &model.effects, nodes, theta_r, phi);
}

/// The width integral of one sample's exit direction (θ_r, |φ|: S is even in φ, and the
/// batches key their tables the same way).
fn sample_table<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    model: &ChiangModel,
    angles: &Angles,
) -> AzimuthalTable<T> {
    let mut table = AzimuthalTable::zeros(params.sigma_a.len());
    let phi = wrap(angles.phi_r - angles.phi_i).abs();
    let mut scratch = WidthScratch::default();
    fill_table(&mut table, params, model, angles.theta_r, phi, &mut scratch);
    table
}

/// `S` per channel for one sample, width integral included (no cache). Parameters and angles are
/// assumed valid ([`ChiangParams::validate`], [`Angles::validate`]).
pub fn scattering<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    model: &ChiangModel,
    angles: &Angles,
    out: &mut [T],
) {
    let table = sample_table(params, model, angles);
    scattering_from_table(
        params,
        &model.effects,
        &table,
        angles.theta_i,
        angles.theta_r,
        out,
    );
}

/// `S` for a batch: `out[k·n + c]` is sample k, channel c (`n` channels). One width integral per
/// distinct (θ_r, |φ|) in the batch, bit-exact keys (so results equal [`scattering`]'s).
pub fn scattering_batch<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    model: &ChiangModel,
    angles: &[Angles],
    out: &mut [T],
) {
    for_each_with_table(params, model, angles, out, |a, table, row| {
        scattering_from_table(params, &model.effects, table, a.theta_i, a.theta_r, row)
    });
}

/// Call `each(sample, table, row)` for every sample and its `row` of `out` (one value per
/// channel), with the azimuthal table of the sample's (θ_r, |φ|): one width integral per
/// distinct exit direction, bit-exact keys. What every batch evaluation of the family shares.
pub fn for_each_with_table<T: DualNum<f64>>(
    params: &ChiangParams<T>,
    model: &ChiangModel,
    angles: &[Angles],
    out: &mut [T],
    mut each: impl FnMut(&Angles, &AzimuthalTable<T>, &mut [T]),
) {
    let n = params.sigma_a.len();
    assert_eq!(
        out.len(),
        angles.len() * n,
        "one output per sample and channel"
    );
    let mut index: HashMap<(u64, u64), usize> = HashMap::new();
    let mut tables: Vec<AzimuthalTable<T>> = Vec::new();
    let mut scratch = WidthScratch::default();
    for (a, row) in angles.iter().zip(out.chunks_mut(n.max(1))) {
        let phi = wrap(a.phi_r - a.phi_i).abs();
        let key = (a.theta_r.to_bits(), phi.to_bits());
        let slot = *index.entry(key).or_insert_with(|| {
            let mut table = AzimuthalTable::zeros(n);
            fill_table(&mut table, params, model, a.theta_r, phi, &mut scratch);
            tables.push(table);
            tables.len() - 1
        });
        each(a, &tables[slot], row);
    }
}

/// Number of distinct exit directions (θ_r, |φ|) in `angles`: the width integrals a batch pays.
pub fn distinct_exit_directions(angles: &[Angles]) -> usize {
    let mut keys: Vec<(u64, u64)> = angles
        .iter()
        .map(|a| (a.theta_r.to_bits(), wrap(a.phi_r - a.phi_i).abs().to_bits()))
        .collect();
    keys.sort_unstable();
    keys.dedup();
    keys.len()
}

/// Chiang's `S` split into `[R, TT, TRT + residual]` per channel (one width integral).
pub fn scattering_by_lobe(
    params: &ChiangParams<f64>,
    model: &ChiangModel,
    angles: &Angles,
    out: &mut [[f64; 3]],
) {
    let table = sample_table(params, model, angles);
    let m = longitudinal_terms(params, &model.effects, angles.theta_i, angles.theta_r);
    let cos_i = angles.theta_i.cos();
    for (c, o) in out.iter_mut().enumerate() {
        let l = &table.lobes[c];
        o[0] = m[0] * l[0] / cos_i;
        o[1] = m[1] * l[1] / cos_i;
        o[2] = (m[2] * l[2] + m[3] * table.residual[c] * 0.5 * std::f64::consts::FRAC_1_PI) / cos_i;
    }
}

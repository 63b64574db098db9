//! Standard normal draws for the rough facets: Doornik's ZIGNOR (2005), the ziggurat of
//! Marsaglia and Tsang with 128 layers. Almost every draw is one `u64`, a compare and a
//! multiply; the layer index and the value come from disjoint bits of that `u64`. Written out
//! here (as `synth::random`'s distributions are) so a seed gives the same draws in every build.

use std::sync::OnceLock;

use rand_chacha::rand_core::RngCore;

use crate::synth::random::uniform_open0;

const LAYERS: usize = 128;
/// Start of the tail and the area of each layer for 128 layers.
const R: f64 = 3.442619855899;
const V: f64 = 9.91256303526217e-3;

struct Tables {
    /// Right edges of the layers, `x[LAYERS] = 0`.
    x: [f64; LAYERS + 1],
    /// `x[i+1] / x[i]`: below it a point lies inside the density for sure.
    ratio: [f64; LAYERS],
}

fn tables() -> &'static Tables {
    static T: OnceLock<Tables> = OnceLock::new();
    T.get_or_init(|| {
        let mut x = [0.0; LAYERS + 1];
        let mut f = (-0.5 * R * R).exp();
        x[0] = V / f;
        x[1] = R;
        for i in 2..LAYERS {
            x[i] = (-2.0 * (V / x[i - 1] + f).ln()).sqrt();
            f = (-0.5 * x[i] * x[i]).exp();
        }
        let mut ratio = [0.0; LAYERS];
        for i in 0..LAYERS {
            ratio[i] = x[i + 1] / x[i];
        }
        Tables { x, ratio }
    })
}

/// One standard normal draw.
#[inline]
pub fn normal(rng: &mut impl RngCore) -> f64 {
    let t = tables();
    loop {
        let bits = rng.next_u64();
        let u = ((bits >> 11) as f64 * (1.0 / (1u64 << 53) as f64)) * 2.0 - 1.0;
        if let Some(x) = attempt(t, (bits & 0x7f) as usize, u, rng) {
            return x;
        }
    }
}

/// A standard normal draw and an independent uniform in [0, 1) (25 bits), from one `u64` but
/// for the ziggurat's rare retries: bits 0–6 choose the layer, 32–63 the position in it (32
/// bits), 7–31 the uniform; no bit serves two draws, so they are independent.
#[inline(always)]
pub fn normal_and_uniform(rng: &mut impl RngCore) -> (f64, f64) {
    let bits = rng.next_u64();
    let v = ((bits >> 7) & ((1 << 25) - 1)) as f64 * (1.0 / (1u64 << 25) as f64);
    let u = (bits >> 32) as f64 * (1.0 / (1u64 << 31) as f64) - 1.0;
    match attempt(tables(), (bits & 0x7f) as usize, u, rng) {
        Some(x) => (x, v),
        None => (normal(rng), v),
    }
}

/// One try of the ziggurat at layer `i`, position `u` ∈ [−1, 1): the draw, or `None` when the
/// point fell outside the density (a fresh try follows).
#[inline]
fn attempt(t: &Tables, i: usize, u: f64, rng: &mut impl RngCore) -> Option<f64> {
    if u.abs() < t.ratio[i] {
        return Some(u * t.x[i]);
    }
    if i == 0 {
        return Some(tail(rng, u < 0.0));
    }
    let x = u * t.x[i];
    let f0 = (-0.5 * (t.x[i] * t.x[i] - x * x)).exp();
    let f1 = (-0.5 * (t.x[i + 1] * t.x[i + 1] - x * x)).exp();
    (f1 + crate::synth::random::uniform(rng) * (f0 - f1) < 1.0).then_some(x)
}

/// A draw from the normal's tail beyond R (Marsaglia 1964), negated when `negative`.
fn tail(rng: &mut impl RngCore, negative: bool) -> f64 {
    loop {
        let x = uniform_open0(rng).ln() / R;
        let y = uniform_open0(rng).ln();
        if -2.0 * y >= x * x {
            return if negative { x - R } else { R - x };
        }
    }
}

//! d'Eon's wrapped-Gaussian detector at every node of one order on f64 vectors: eight nodes at
//! once in one AVX-512 register, two AVX2 registers or two `wide::f64x4`, with the shared lanes'
//! exp (within 1 ulp of libm; the same bits on every CPU). One `exp` per node and order (more
//! for wide detectors, whose images count) was a quarter of a d'Eon fit in libm one node at a
//! time. Every pass that holds η — values and gradients alike — takes its detectors here, so a
//! gradient pass's values are still the value pass's bits.

use std::f64::consts::{PI, TAU};

use wide::f64x4;

use super::{IMAGES, NEGLIGIBLE_EXPONENT};
use crate::families::shared::lanes::functions::LaneFunctions;
use crate::families::shared::lanes::vector::{Lane, Pair};
#[cfg(target_arch = "x86_64")]
use crate::families::shared::lanes::{avx2, avx512};
use crate::geometry::angles;

/// A detector of width β: `h = 1/(2β²)`, `norm = 1/(β√(2π))`.
#[derive(Debug, Clone, Copy)]
pub(super) struct Detector {
    pub beta: f64,
    pub half_inv_variance: f64,
    pub norm: f64,
}

impl Detector {
    /// The detector of width `beta` (radians), its constants as [`super::WrappedGaussian::new`]
    /// forms them.
    pub(super) fn new(beta: f64) -> Detector {
        let g = super::WrappedGaussian::new(&beta);
        Detector {
            beta,
            half_inv_variance: g.half_inv_variance,
            norm: g.norm,
        }
    }
}

/// One order's nodes as the detector reads them: their exit azimuths `Φ_n` and weights.
#[derive(Clone, Copy)]
struct Nodes<'a> {
    det: Detector,
    phi: f64,
    exits: &'a [f64],
    weights: &'a [f64],
}

/// `value[n] = w_n·D(φ − Φ_n)` and `slope[n] = w_n·∂D/∂β` at every node `n`, where `exits`
/// holds the nodes' exit azimuths `Φ_n` of one order and `weights` their weights; `slope` is
/// left alone when `None`.
pub(super) fn weighted(
    det: Detector,
    phi: f64,
    exits: &[f64],
    weights: &[f64],
    value: &mut [f64],
    slope: Option<&mut [f64]>,
) {
    assert!(exits.len() == weights.len() && value.len() == exits.len());
    let nodes = Nodes {
        det,
        phi,
        exits,
        weights,
    };
    #[cfg(target_arch = "x86_64")]
    {
        if avx512::available() {
            // SAFETY: the CPU has AVX-512F and AVX-512DQ.
            return unsafe { weighted_avx512(nodes, value, slope) };
        }
        if avx2::available() {
            // SAFETY: the CPU has AVX2.
            return unsafe { weighted_avx2(nodes, value, slope) };
        }
    }
    kernel::<f64x4>(nodes, value, slope)
}

/// [`kernel`] compiled for AVX-512 (every helper is `#[inline(always)]`).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512dq")]
unsafe fn weighted_avx512(nodes: Nodes, value: &mut [f64], slope: Option<&mut [f64]>) {
    kernel::<avx512::F64x8>(nodes, value, slope)
}

/// [`kernel`] on two AVX2 registers, compiled for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn weighted_avx2(nodes: Nodes, value: &mut [f64], slope: Option<&mut [f64]>) {
    kernel::<Pair<avx2::F64x4>>(nodes, value, slope)
}

/// A rule whose length is not a multiple of the lanes ends in a vector padded with zeros,
/// whose lanes are dropped; each lane's result depends on its own node only. (No closures
/// here: a closure is a function of its own, compiled without the caller's target features.)
#[inline(always)]
fn kernel<V: Lane>(nodes: Nodes, value: &mut [f64], mut slope: Option<&mut [f64]>) {
    let Nodes {
        det,
        phi,
        exits,
        weights,
    } = nodes;
    let n = V::LANES;
    let full = exits.len() / n * n;
    for start in (0..full).step_by(n) {
        let (e, w) = (&exits[start..][..n], &weights[start..][..n]);
        let (e, w) = (V::new(array(e)), V::new(array(w)));
        some_nodes(det, phi, e, w, start, n, value, slope.as_deref_mut());
    }
    if full < exits.len() {
        let mut e = V::Array::default();
        let mut w = V::Array::default();
        let len = exits.len() - full;
        e.as_mut()[..len].copy_from_slice(&exits[full..]);
        w.as_mut()[..len].copy_from_slice(&weights[full..]);
        let (e, w) = (V::new(e), V::new(w));
        some_nodes(det, phi, e, w, full, len, value, slope);
    }
}

/// `V::Array` holding `v` (of `LANES` values).
#[inline(always)]
fn array<A: Default + AsMut<[f64]>>(v: &[f64]) -> A {
    let mut a = A::default();
    a.as_mut().copy_from_slice(v);
    a
}

/// The first `len` nodes from `start`, with exit azimuths `e` and weights `w`.
#[inline(always)]
#[allow(clippy::too_many_arguments)]
fn some_nodes<V: Lane>(
    det: Detector,
    phi: f64,
    e: V,
    w: V,
    start: usize,
    len: usize,
    value: &mut [f64],
    slope: Option<&mut [f64]>,
) {
    let (d, dd) = at(det, wrap(V::splat(phi) - e), slope.is_some());
    value[start..][..len].copy_from_slice(&(d * w).to_array().as_ref()[..len]);
    if let Some(slope) = slope {
        slope[start..][..len].copy_from_slice(&(dd * w).to_array().as_ref()[..len]);
    }
}

/// The scalar [`crate::geometry::angles::wrap`] lane by lane, to the bit: `|x| mod 2π` by exact
/// subtractions (Sterbenz's lemma, as the scalar's fmod is exact) up to `|x| < 8π` — the exit
/// azimuths of orders 0–3 less φ stay within 6π for η ≥ 1 — then its two roundings into
/// (−π, π]. Lanes beyond, infinite ones included, take the scalar function.
#[inline(always)]
fn wrap<V: Lane>(x: V) -> V {
    let a = x.abs();
    let far = a.cmp_ge(V::splat(4.0 * TAU));
    if far.move_mask() != 0 {
        let x = x.to_array();
        return V::from_fn(|l| angles::wrap(x.as_ref()[l]));
    }
    let a = a.cmp_ge(V::splat(2.0 * TAU)).blend(a - 2.0 * TAU, a);
    let a = a.cmp_ge(V::splat(TAU)).blend(a - TAU, a);
    let r = a.copysign(x);
    let y = r.cmp_lt(V::ZERO).blend(r + TAU, r);
    y.cmp_gt(V::splat(PI)).blend(y - TAU, y)
}

/// `D(x)` and (when `with_slope`, else 0) `∂D/∂β = (norm/β)·Σ_k g_k (2h·x_k² − 1)` at `x` in
/// [−π, π]: the central term and the images `x + 2πk` of `IMAGES` whose exponent is within
/// `NEGLIGIBLE_EXPONENT` of the central one (as [`super::WrappedGaussian::at`] keeps them).
#[inline(always)]
fn at<V: Lane>(det: Detector, x: V, with_slope: bool) -> (V, V) {
    let h = det.half_inv_variance;
    let x2 = x * x;
    let central = x2 * h;
    let mut sum = (-central).exp();
    let mut moment = sum * x2;
    // Image k of a lane is `x − 2πk·sign(x)`: k = 1 is the one across the nearer end of
    // [−π, π], k = −1 the one across the farther end, which only a wide detector sees
    // (4π²h ≥ 40 above the central exponent for β ≤ 40°). Both sides' lanes share a vector.
    let toward = V::splat(TAU).copysign(x);
    for k in IMAGES {
        let xk = x - toward * k;
        let xk2 = xk * xk;
        let exponent = xk2 * h;
        let near = (exponent - central).cmp_lt(V::splat(NEGLIGIBLE_EXPONENT));
        if near.move_mask() == 0 {
            continue;
        }
        let e = near.blend((-exponent).exp(), V::ZERO);
        sum = sum + e;
        moment = moment + e * xk2;
    }
    let slope = if with_slope {
        (moment * (2.0 * h) - sum) * (det.norm / det.beta)
    } else {
        V::ZERO
    };
    (sum * det.norm, slope)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::families::deon::WrappedGaussian;

    /// The lanes' wrap is the scalar one to the bit: at the edges of each branch (±π, ±2π, ±4π,
    /// ±8π and their neighbours), signed zeros, NaN, infinities and a sweep over ±30.
    #[test]
    fn lanes_wrap_as_the_scalar_does() {
        let mut xs = vec![0.0, -0.0, f64::NAN, f64::INFINITY, f64::NEG_INFINITY, 1e300];
        for edge in [PI, TAU, 2.0 * TAU, 4.0 * TAU] {
            for x in [edge, edge.next_up(), edge.next_down()] {
                xs.extend([x, -x]);
            }
        }
        xs.extend((-3000..=3000).map(|i| i as f64 * 0.01 + 1e-3));
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        let want: Vec<f64> = xs.iter().map(|&x| angles::wrap(x)).collect();
        let mut got = Vec::new();
        for chunk in xs.chunks(4) {
            let x = f64x4::from_fn(|l| chunk.get(l).copied().unwrap_or(0.0));
            got.extend(&wrap(x).to_array()[..chunk.len()]);
        }
        assert_eq!(bits(&got), bits(&want));
    }

    /// The kernels against the generic detector one node at a time in libm's exp, and against
    /// a central difference in β: every lane width, lengths that leave a partial vector, narrow
    /// and wide detectors (images off and on), arguments far outside [−π, π]. Tolerances: the
    /// lanes' exp is within 1 ulp of libm's, so D within a few ulp (1e-14 relative with the
    /// norm's and weight's roundings); the slope against a difference of step 1e-6·β, whose
    /// truncation is ~1e-12 relative and whose rounding ~1e-10 of `D/β`, to 1e-6 of the larger
    /// of the slope and `D/β`.
    #[test]
    fn kernels_match_the_generic_detector() {
        for beta_deg in [5.0, 15.0, 40.0, 75.0] {
            let beta: f64 = f64::to_radians(beta_deg);
            let det = Detector::new(beta);
            let reference = WrappedGaussian::new(&beta);
            for len in [1, 7, 8, 13, 48] {
                let exits: Vec<f64> = (0..len).map(|i| -9.0 + 1.37 * i as f64).collect();
                let weights: Vec<f64> = (0..len).map(|i| 0.01 + 0.003 * i as f64).collect();
                let phi = 0.7;
                let mut runs: Vec<(Vec<f64>, Vec<f64>)> = Vec::new();
                let mut run = |k: &dyn Fn(&mut [f64], &mut [f64])| {
                    let (mut v, mut s) = (vec![0.0; len], vec![0.0; len]);
                    k(&mut v, &mut s);
                    runs.push((v, s));
                };
                let nodes = Nodes {
                    det,
                    phi,
                    exits: &exits,
                    weights: &weights,
                };
                run(&|v, s| kernel::<f64x4>(nodes, v, Some(s)));
                #[cfg(target_arch = "x86_64")]
                {
                    if avx2::available() {
                        run(&|v, s| unsafe { weighted_avx2(nodes, v, Some(s)) });
                    }
                    if avx512::available() {
                        run(&|v, s| unsafe { weighted_avx512(nodes, v, Some(s)) });
                    }
                }
                for (v, s) in &runs {
                    assert_eq!(
                        v.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                        runs[0].0.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                        "every kernel gives the same bits"
                    );
                    assert_eq!(
                        s.iter().map(|x| x.to_bits()).collect::<Vec<_>>(),
                        runs[0].1.iter().map(|x| x.to_bits()).collect::<Vec<_>>()
                    );
                }
                let (v, s) = &runs[0];
                for i in 0..len {
                    let x = -exits[i] + phi;
                    let want = reference.at(&x) * weights[i];
                    assert!(
                        (v[i] - want).abs() <= 1e-14 * want.abs() + 1e-300,
                        "β {beta_deg}°, node {i}: {} vs {want}",
                        v[i]
                    );
                    let step = 1e-6 * beta;
                    let d = |b: f64| WrappedGaussian::new(&b).at(&x) * weights[i];
                    let diff = (d(beta + step) - d(beta - step)) / (2.0 * step);
                    assert!(
                        (s[i] - diff).abs() <= 1e-6 * diff.abs().max(want.abs() / beta),
                        "β {beta_deg}°, node {i}: slope {} vs difference {diff}",
                        s[i]
                    );
                }
                let mut alone = vec![0.0; len];
                weighted(det, phi, &exits, &weights, &mut alone, None);
                assert_eq!(alone, *v, "values without the slope are the same");
            }
        }
    }
}

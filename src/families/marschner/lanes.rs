//! `S` four or eight samples at a time, for plain f64 in cubic mode (what `hairfit eval` and the
//! fit's value passes run): each step of the scalar [`super::evaluate`] done on vectors
//! ([`vector::Lane`]). The vector is chosen at run time: eight lanes in one 512-bit register on
//! CPUs with AVX-512 ([`avx512`]), eight in two 256-bit registers on CPUs with AVX2 ([`avx2`],
//! [`vector::Pair`]), elsewhere four in `wide::f64x4`, which the default x86-64 target builds as
//! two SSE2 halves. All run the lanes' own exp, sin/cos, asin and acos ([`functions`]) and the
//! same IEEE operations, so they give the same bits. Per sample with every effect on (random
//! directions, callgrind): the scalar model takes 2,520 instructions, the four-lane AVX2 kernel
//! about 670 (the README has the times).
//!
//! The lanes take the common path only: at most one root per monotone piece of each map, a Newton
//! step from the closed-form cubic root that settles at once, and no TT fold. A lane off that
//! path is evaluated again by the scalar model, which stays the reference; elsewhere the two agree
//! to ~1e-13 relative (the lanes' and libm's transcendental functions differ in the last bits;
//! tests/families/marschner_lanes.rs states the tolerance and why).

use wide::f64x4;

use super::{evaluate_into, scattering_batch, Angles, ModelConfig, Params, Prepared, RootMode};

#[cfg(target_arch = "x86_64")]
use crate::families::shared::lanes::{avx2, avx512};
use crate::families::shared::lanes::{functions, vector};
mod cubic;
mod kernel;
mod steps;
use kernel::Lanes;
use vector::{Lane, Pair, MAX_LANES};

/// Which vector type runs the lanes (all give the same bits).
#[doc(hidden)]
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LaneKernel {
    /// `wide::f64x4` (two SSE2 halves in the default build), on any CPU.
    Wide,
    /// Eight lanes in two AVX registers where the CPU has AVX2, else `Wide`.
    Avx2,
    /// Eight lanes in one AVX-512 register where the CPU has AVX-512F and DQ, else `Avx2`.
    Avx512,
}

impl LaneKernel {
    /// The kernels this CPU runs as themselves (not by falling back), `Wide` first; the last is
    /// the one `scattering_lanes` picks.
    pub fn on_this_cpu() -> Vec<LaneKernel> {
        let mut kernels = vec![LaneKernel::Wide];
        #[cfg(target_arch = "x86_64")]
        {
            if avx2::available() {
                kernels.push(LaneKernel::Avx2);
            }
            if avx512::available() {
                kernels.push(LaneKernel::Avx512);
            }
        }
        kernels
    }
}

/// [`super::scattering_batch`] for f64: `out[k * nc + c]`. Cubic mode runs four or eight samples
/// per vector (each sample's value depends on that sample only, not on its neighbours or its
/// place in the batch); exact mode runs the scalar model.
pub fn scattering_lanes(
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    out: &mut [f64],
) {
    scattering_lanes_on(LaneKernel::Avx512, params, config, angles, out)
}

/// [`scattering_lanes`] on a chosen kernel (tests and benchmarks compare them).
#[doc(hidden)]
pub fn scattering_lanes_on(
    kernel: LaneKernel,
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    out: &mut [f64],
) {
    let nc = params.sigma_a.len();
    if config.mode != RootMode::Cubic || nc == 0 {
        return scattering_batch(params, config, angles, out);
    }
    assert_eq!(
        out.len(),
        angles.len() * nc,
        "one output per sample and channel"
    );
    let prepared = Prepared::new(params);
    let scalar = |a: &Angles, o: &mut [f64]| evaluate_into(params, &prepared, config, a, o);
    let lanes = Lanes {
        params,
        prepared: &prepared,
        config,
    };
    #[cfg(target_arch = "x86_64")]
    {
        if kernel == LaneKernel::Avx512 && avx512::available() {
            // SAFETY: the CPU has AVX-512F and AVX-512DQ.
            unsafe { groups_avx512(&lanes, angles, out, &scalar) };
            return;
        }
        if kernel != LaneKernel::Wide && avx2::available() {
            // SAFETY: the CPU has AVX2.
            unsafe { groups_avx2(&lanes, angles, out, &scalar) };
            return;
        }
    }
    groups::<f64x4>(&lanes, angles, out, &scalar);
}

/// [`super::scattering_by_lobe`] of every direction in `angles` (`out[k * nc + c]` =
/// `[R, TT, TRT]`), on the lanes: one [`scattering_lanes`] pass per enabled lobe with only that
/// lobe on. A lobe's terms do not depend on which other lobes are on, and the kernel sums them
/// per channel from zero as the scalar model's per-lobe sums do, so each pass gives that lobe's
/// values (to the lanes' ~1e-13 of the scalar model); three one-lobe passes cost about a third
/// of the scalar per-lobe model (curves.csv's lobe columns on large fits).
pub fn scattering_by_lobe_lanes(
    params: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    out: &mut [[f64; 3]],
) {
    let nc = params.sigma_a.len();
    assert_eq!(
        out.len(),
        angles.len() * nc,
        "one output per sample and channel"
    );
    let mut one = vec![0.0; out.len()];
    let lobes = config.effects.lobes;
    for (p, on) in [lobes.r, lobes.tt, lobes.trt].into_iter().enumerate() {
        if on {
            let mut alone = *config;
            alone.effects.lobes = super::Lobes {
                r: p == 0,
                tt: p == 1,
                trt: p == 2,
            };
            scattering_lanes(params, &alone, angles, &mut one);
        } else {
            one.fill(0.0);
        }
        for (o, v) in out.iter_mut().zip(&one) {
            o[p] = *v;
        }
    }
}

/// The groups on two [`avx2::F64x4`] side by side (eight samples: two independent chains of
/// work, 6% less time in eval than one register, measured on an Intel CPU run with AVX2 only),
/// compiled for AVX2 so that its intrinsics inline. Every helper of the kernel ([`kernel`],
/// [`cubic`], [`steps`]) is `#[inline(always)]` (and none is a closure) for that reason: a
/// helper left out of line has no AVX2 context, and each intrinsic in it becomes a call (eval
/// ran 3× slower).
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2")]
unsafe fn groups_avx2(
    lanes: &Lanes<'_>,
    angles: &[Angles],
    out: &mut [f64],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    groups::<Pair<avx2::F64x4>>(lanes, angles, out, scalar)
}

/// The groups on [`avx512::F64x8`], compiled for AVX-512 as `groups_avx2` is for AVX2.
#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,avx512f,avx512dq")]
unsafe fn groups_avx512(
    lanes: &Lanes<'_>,
    angles: &[Angles],
    out: &mut [f64],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    groups::<avx512::F64x8>(lanes, angles, out, scalar)
}

#[inline(always)]
fn groups<V: Lane>(
    lanes: &Lanes<'_>,
    angles: &[Angles],
    out: &mut [f64],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    let nc = lanes.params.sigma_a.len();
    let n = V::LANES;
    let mut sums = vec![V::ZERO; nc];
    let (groups, tail) = angles.split_at(angles.len() / n * n);
    for (group, o) in groups.chunks_exact(n).zip(out.chunks_mut(n * nc)) {
        one_group(lanes, group, n, o, &mut sums, scalar);
    }
    if let Some(last) = tail.last() {
        // A short last group repeats its last sample: a lane's value depends on its own sample
        // only, so every sample gets the same bits wherever it stands in the batch.
        let full: [Angles; MAX_LANES] = std::array::from_fn(|l| *tail.get(l).unwrap_or(last));
        let o = &mut out[groups.len() * nc..];
        one_group(lanes, &full[..n], tail.len(), o, &mut sums, scalar);
    }
}

/// The first `used` samples of `group` into `o` (`o[l * nc + c]`), the lanes off the fast path
/// by the scalar model.
#[inline(always)]
fn one_group<V: Lane>(
    lanes: &Lanes<'_>,
    group: &[Angles],
    used: usize,
    o: &mut [f64],
    sums: &mut [V],
    scalar: &dyn Fn(&Angles, &mut [f64]),
) {
    let nc = sums.len();
    let irregular = lanes.group(group, sums);
    for (c, s) in sums.iter().enumerate() {
        for (l, v) in s.to_array().as_ref().iter().take(used).enumerate() {
            o[l * nc + c] = *v;
        }
    }
    for (l, a) in group.iter().take(used).enumerate() {
        if irregular & (1 << l) != 0 {
            scalar(a, &mut o[l * nc..(l + 1) * nc]);
        }
    }
}

//! The tracer's only `unsafe` code: `Sampler::trace_batch`'s body compiled again for AVX2 and
//! for AVX-512 and chosen at run time (`is_x86_feature_detected!`), the baseline x86-64 build
//! otherwise. The body and its helpers are `#[inline]`/`#[inline(always)]`, so each copy is
//! compiled for its features: the lanes' loops get 4- or 8-wide registers and everything gets
//! the VEX encoding's three-operand instructions. The IEEE operations and their order are the
//! same in every copy (Rust never fuses a multiply and an add on its own, FMA or not), so every
//! kernel gives the same bits; `tests` checks it on the CPU it runs on.

/// Which compiled copy of the tracer's hot path runs.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Kernel {
    /// The release build's own target (SSE2 on x86-64).
    Baseline,
    /// AVX2, FMA, BMI1/2 (Haswell and later).
    Avx2,
    /// AVX2's set and AVX-512 F, DQ, VL, BW (Skylake-SP and later).
    Avx512,
}

impl Kernel {
    /// Every kernel, fastest last.
    pub const ALL: [Kernel; 3] = [Kernel::Baseline, Kernel::Avx2, Kernel::Avx512];

    /// Whether this CPU runs `self`.
    pub fn available(self) -> bool {
        match self {
            Kernel::Baseline => true,
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx2 => {
                std::arch::is_x86_feature_detected!("avx2")
                    && std::arch::is_x86_feature_detected!("fma")
                    && std::arch::is_x86_feature_detected!("bmi1")
                    && std::arch::is_x86_feature_detected!("bmi2")
            }
            #[cfg(target_arch = "x86_64")]
            Kernel::Avx512 => {
                Kernel::Avx2.available()
                    && std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512dq")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                    && std::arch::is_x86_feature_detected!("avx512bw")
            }
            #[cfg(not(target_arch = "x86_64"))]
            _ => false,
        }
    }

    /// The fastest kernel this CPU runs.
    pub fn best() -> Kernel {
        *Kernel::ALL.iter().rev().find(|k| k.available()).unwrap()
    }
}

/// The work a kernel compiles: the tracer's batch body for `NC` channels (0: any number). Its
/// `run` is `#[inline(always)]`, so each kernel below gets its own copy of it.
pub(super) trait Body {
    /// The number of channels (1 and 3 get copies of their own).
    fn channels(&self) -> usize;
    fn run<const NC: usize>(self);
}

/// `body` on `kernel`, or on the best this CPU runs if it does not run that.
pub(super) fn run<B: Body>(kernel: Kernel, body: B) {
    let kernel = if kernel.available() {
        kernel
    } else {
        Kernel::best()
    };
    // One channel (grey) and three (RGB) get their own copies, any other number the general one.
    match body.channels() {
        1 => on::<1, B>(kernel, body),
        3 => on::<3, B>(kernel, body),
        _ => on::<0, B>(kernel, body),
    }
}

/// `kernel`, which this CPU runs, for `NC` channels.
fn on<const NC: usize, B: Body>(kernel: Kernel, body: B) {
    match kernel {
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the caller checked that the CPU has every feature `avx512` is compiled for.
        Kernel::Avx512 => unsafe { avx512::<NC, B>(body) },
        #[cfg(target_arch = "x86_64")]
        // SAFETY: the caller checked that the CPU has every feature `avx2` is compiled for.
        Kernel::Avx2 => unsafe { avx2::<NC, B>(body) },
        _ => body.run::<NC>(),
    }
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2")]
unsafe fn avx2<const NC: usize, B: Body>(body: B) {
    body.run::<NC>()
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma,bmi1,bmi2,avx512f,avx512dq,avx512vl,avx512bw")]
unsafe fn avx512<const NC: usize, B: Body>(body: B) {
    body.run::<NC>()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trace::optics::V3;
    use crate::trace::sampler::{Balance, Sampler, Weights};
    use crate::trace::{batch_generator, optics::direction, Fiber};

    /// Every kernel this CPU runs gives the baseline's exits and balance, bit for bit, for a
    /// round rough fibre, a rough elliptical one averaged over rotations, and two channels.
    #[test]
    fn every_kernel_gives_the_same_bits() {
        let brown = Fiber::brown();
        let ellipse = Fiber {
            sigma_a: vec![0.2, 1.5],
            azimuthal_roughness: 4f64.to_radians(),
            eccentricity: 0.8,
            ..brown.clone()
        };
        for fiber in [brown, ellipse] {
            let s = Sampler::new(&fiber);
            let omega_i = direction(0.5, 0.0);
            let run = |k: Kernel| {
                let mut rng = batch_generator(3, 1, 2);
                let mut bal = Balance::default();
                let mut exits: Vec<(usize, [u64; 3], Vec<u64>)> = Vec::new();
                s.trace_batch_on(
                    k,
                    omega_i,
                    20_000,
                    &mut rng,
                    &mut bal,
                    &mut |p: usize, d: V3, w: &Weights| {
                        exits.push((p, d.map(f64::to_bits), w.map(f64::to_bits).to_vec()))
                    },
                );
                (exits, bal)
            };
            let base = run(Kernel::Baseline);
            for k in Kernel::ALL.into_iter().filter(|k| k.available()) {
                let got = run(k);
                assert!(got.0 == base.0, "{k:?}: exits differ");
                assert_eq!(got.1, base.1, "{k:?}: balance differs");
            }
        }
    }
}

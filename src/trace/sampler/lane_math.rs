//! The lanes' branch-free arithmetic: `exp` without libm, Fresnel from inside without a branch
//! on total internal reflection and from outside without one, so the sampler's loops over lanes
//! vectorise.

/// `e^x` for x ≤ 0 without branches or libm, so a loop of it vectorises: x = n·ln 2 + r,
/// |r| ≤ ln 2/2, `e^r` by its Taylor series to r¹³ (truncation 4e-18 relative), 2ⁿ built in
/// the exponent bits (as `families::marschner::lanes`' exp); below −708 it gives e^−708.
#[inline(always)]
pub(super) fn exp_lane(x: f64) -> f64 {
    // 2⁵² + 2⁵¹: adding it rounds to an integer and leaves it in the low bits.
    const INTEGER_BITS: f64 = 6_755_399_441_055_744.0;
    // ln 2 in two parts, the first of 32 bits, so n·LN2_HI is exact.
    const LN2_HI: f64 = 0.693_147_180_369_123_8;
    const LN2_LO: f64 = 1.908_214_929_270_587_7e-10;
    let x = if x < -708.0 { -708.0 } else { x };
    let t = x * std::f64::consts::LOG2_E + INTEGER_BITS;
    let n = t - INTEGER_BITS;
    let r = (x - n * LN2_HI) - n * LN2_LO;
    // 1/k!, k = 13 down to 0.
    const TAYLOR: [f64; 14] = {
        let (mut c, mut k, mut f) = ([0.0; 14], 0, 1.0);
        while k < 14 {
            c[13 - k] = 1.0 / f;
            k += 1;
            f *= k as f64;
        }
        c
    };
    let mut p = TAYLOR[0];
    for &c in &TAYLOR[1..] {
        p = p * r + c;
    }
    p * f64::from_bits((n + (INTEGER_BITS + 1023.0)).to_bits() << 52)
}

/// [`fresnel`](crate::trace::optics::fresnel) from inside a medium of index `eta` into air, without branches: the same
/// reflectance and refracted cosine (1 and 0 under total internal reflection).
#[inline]
pub(super) fn fresnel_lane(cos_i: f64, eta: f64) -> (f64, f64) {
    let sin2_t = eta * eta * (1.0 - cos_i * cos_i).max(0.0);
    let tir = sin2_t >= 1.0;
    let cos_t = (1.0 - sin2_t).max(0.0).sqrt();
    let rs = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let rp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let f = (rs * rs + rp * rp) / 2.0;
    if tir {
        (1.0, 0.0)
    } else {
        (f, cos_t)
    }
}

/// [`fresnel`](crate::trace::optics::fresnel)`(cos_i, 1, eta)`, from air into a medium of index
/// `eta` > 1, without a branch (there is no total internal reflection on this side): the same
/// expressions, so the same bits.
#[inline(always)]
pub(super) fn fresnel_in_lane(cos_i: f64, eta: f64) -> (f64, f64) {
    let e = 1.0 / eta;
    let sin2_t = e * e * (1.0 - cos_i * cos_i).max(0.0);
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    let rp = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    ((rs * rs + rp * rp) / 2.0, cos_t)
}

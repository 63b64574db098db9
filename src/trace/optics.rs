//! Vector optics at one interface: exact unpolarised Fresnel reflectance (total internal
//! reflection included), mirror reflection and Snell refraction of unit 3-D directions.

/// 3-D vector in the fibre frame `(u, v, w)`: `u` along the axis toward the tip.
pub type V3 = [f64; 3];

#[inline]
pub fn dot(a: V3, b: V3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

#[inline]
pub fn scale(a: V3, s: f64) -> V3 {
    [a[0] * s, a[1] * s, a[2] * s]
}

#[inline]
pub fn add(a: V3, b: V3) -> V3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}

pub fn normalize(a: V3) -> V3 {
    scale(a, 1.0 / dot(a, a).sqrt())
}

/// Unpolarised Fresnel reflectance for light arriving at cosine `cos_i` (> 0, against the
/// normal) from a medium of index `n1` into `n2`, and the refracted cosine (0 under total
/// internal reflection, where the reflectance is exactly 1).
#[inline]
pub fn fresnel(cos_i: f64, n1: f64, n2: f64) -> (f64, f64) {
    let e = n1 / n2;
    let sin2_t = e * e * (1.0 - cos_i * cos_i).max(0.0);
    if sin2_t >= 1.0 {
        return (1.0, 0.0);
    }
    let cos_t = (1.0 - sin2_t).sqrt();
    let rs = (n1 * cos_i - n2 * cos_t) / (n1 * cos_i + n2 * cos_t);
    let rp = (n2 * cos_i - n1 * cos_t) / (n2 * cos_i + n1 * cos_t);
    ((rs * rs + rp * rp) / 2.0, cos_t)
}

/// `d` mirrored at the plane with unit normal `n`.
#[inline]
pub fn reflect(d: V3, n: V3) -> V3 {
    add(d, scale(n, -2.0 * dot(d, n)))
}

/// `d` refracted through the plane with unit normal `n` facing the incoming side
/// (`dot(d, n) = −cos_i < 0`), index ratio `e = n1/n2`, refracted cosine `cos_t`; unit when
/// `d` and `n` are (Snell's law in vector form).
#[inline]
pub fn refract(d: V3, n: V3, e: f64, cos_i: f64, cos_t: f64) -> V3 {
    add(scale(d, e), scale(n, e * cos_i - cos_t))
}

/// Inclination θ and azimuth φ (radians) of a unit direction, docs/model.md's angles.
pub fn angles_of(d: V3) -> (f64, f64) {
    (d[0].clamp(-1.0, 1.0).asin(), d[2].atan2(d[1]))
}

/// The unit direction of inclination θ and azimuth φ (radians).
pub fn direction(theta: f64, phi: f64) -> V3 {
    let (st, ct) = theta.sin_cos();
    let (sp, cp) = phi.sin_cos();
    [st, ct * cp, ct * sp]
}

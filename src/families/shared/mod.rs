//! The mathematics more than one family uses, so that no family's folder imports another's:
//! - [`cylinder`]: a smooth dielectric cylinder's Fresnel, refraction, transmittance, `A_p`, `Φ_p`;
//! - [`longitudinal`]: d'Eon's lobe `M`, the per-lobe variances, the tilted exit inclination;
//! - [`bessel`]: the exponentially scaled `I₀` that `M` needs;
//! - [`logistic`]: the trimmed logistic of pbrt-v4's `N_p` and its roughness map;
//! - [`quadrature`]: cached Gauss–Legendre rules for the width integral over h;
//! - [`half_angle`]: the half angle of the real-time families' R Fresnel;
//! - `lanes`: f64 vectors (SSE2, AVX2, AVX-512) and their exp, sin/cos, asin for hot loops.

pub mod bessel;
pub mod cylinder;
pub mod half_angle;
pub(crate) mod lanes;
pub mod logistic;
pub mod longitudinal;
pub mod quadrature;

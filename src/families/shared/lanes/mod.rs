//! f64 vectors for the families' hot loops: one trait ([`vector::Lane`]) implemented by
//! `wide::f64x4` on any CPU, by one AVX2 register ([`avx2::F64x4`], run as a [`vector::Pair`])
//! and by one AVX-512 register ([`avx512::F64x8`]), with exp, sin/cos, asin and acos written once
//! over it ([`functions`]), so every kernel gives the same bits. A family's kernel is generic
//! over [`vector::Lane`] and compiled once per register type inside a
//! `#[target_feature]` function, chosen at run time (Marschner's lanes, Frostbite's node sums).

#[cfg(target_arch = "x86_64")]
pub(crate) mod avx2;
#[cfg(target_arch = "x86_64")]
pub(crate) mod avx512;
pub(crate) mod functions;
#[cfg(target_arch = "x86_64")]
mod register;
pub(crate) mod slices;
pub(crate) mod vector;

//! `hairfit trace`: a virtual goniometer. A Monte Carlo ray tracer of one infinitely long
//! dielectric fibre (round or elliptical, tilted cuticle, rough surface, absorbing cortex) under
//! a collimated beam, tallied at a rig's directions as hairfit's `S` — data that no model made.
//!
//! This module owns: the fibre file ([`fiber`]), the cross-section's geometry ([`section`]),
//! Fresnel and refraction ([`optics`]), the path sampler ([`sampler`]), the detector and its
//! tallies ([`tally`]) and the sidecar plus the dataset it becomes ([`output`]). docs/trace.md
//! states the physics and the estimator.
//!
//! Determinism: each incidence's rays are split into [`BATCHES`] fixed batches, each with its
//! own ChaCha8 generator keyed by the seed, the incidence and the batch; batches run in
//! parallel and are combined in order, so a seed gives the same bytes with any thread count.

pub mod fiber;
pub mod normal;
pub mod optics;
pub mod output;
pub mod sampler;
pub mod section;
pub mod tally;

use std::sync::atomic::{AtomicU64, Ordering};

use rand_chacha::rand_core::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rayon::prelude::*;

pub use self::fiber::{Fiber, FiberFile};
use self::optics::direction;
pub use self::sampler::{Balance, Sampler, MAX_CHANNELS, ORDERS};
use self::tally::{Collected, Detector, Tally};

/// Batches per incidence: the `sigma` column is their spread.
pub const BATCHES: usize = 32;

/// Generator description recorded in the sidecar.
pub const RNG_DESCRIPTION: &str = "ChaCha8 (rand_chacha 0.9), key = seed u64 LE, then \
    b\"trace\\0\\0\\0\", then the incidence's index u64 LE, zero-padded; stream = batch index";

/// The generator of one batch.
pub fn batch_generator(seed: u64, incidence: usize, batch: usize) -> ChaCha8Rng {
    let mut key = [0u8; 32];
    key[..8].copy_from_slice(&seed.to_le_bytes());
    key[8..16].copy_from_slice(b"trace\0\0\0");
    key[16..24].copy_from_slice(&(incidence as u64).to_le_bytes());
    let mut rng = ChaCha8Rng::from_seed(key);
    rng.set_stream(batch as u64);
    rng
}

/// How to trace: rays per incidence, seed, kernel radius (radians).
#[derive(Debug, Clone, Copy)]
pub struct TraceSetup {
    pub rays: u64,
    pub seed: u64,
    pub kernel: f64,
}

/// One incidence's result: per sampling point, order and channel, `S` and its batch spread.
#[derive(Debug, Clone)]
pub struct IncidenceResult {
    /// Indices into the caller's direction list.
    pub rows: Vec<usize>,
    /// `S` per (point, order, channel), `Collected`'s layout.
    pub s: Vec<f64>,
    /// Standard error of the total `S` per (point, channel), from the batches.
    pub sigma: Vec<f64>,
}

/// What [`run`] found.
#[derive(Debug, Clone)]
pub struct TraceResult {
    pub nc: usize,
    pub incidences: Vec<IncidenceResult>,
    pub balance: Balance,
    pub rays_total: u64,
}

/// Rays of batch `b` out of `rays` split over [`BATCHES`].
pub fn batch_rays(rays: u64, b: usize) -> u64 {
    let n = BATCHES as u64;
    rays / n + u64::from((b as u64) < rays % n)
}

/// Trace `setup.rays` rays per distinct incidence of `directions` (`[θ_i, φ_i, θ_r, φ_r]`,
/// radians) and estimate `S` at every direction. `progress` gets ray counts as they finish.
pub fn run(
    fiber: &Fiber,
    directions: &[[f64; 4]],
    setup: &TraceSetup,
    progress: &(dyn Fn(u64) + Sync),
) -> TraceResult {
    let sampler = Sampler::new(fiber);
    let nc = sampler.n_channels();
    // Distinct incidences in first-appearance order, by their bits.
    let mut groups: Vec<([f64; 2], Vec<usize>)> = Vec::new();
    let mut index = std::collections::HashMap::new();
    for (k, a) in directions.iter().enumerate() {
        let key = (a[0].to_bits(), a[1].to_bits());
        let g = *index.entry(key).or_insert_with(|| {
            groups.push(([a[0], a[1]], Vec::new()));
            groups.len() - 1
        });
        groups[g].1.push(k);
    }
    let detectors: Vec<Detector> = groups
        .iter()
        .map(|(_, rows)| {
            let dirs = rows
                .iter()
                .map(|&k| direction(directions[k][2], directions[k][3]))
                .collect();
            Detector::new(dirs, setup.kernel)
        })
        .collect();
    let jobs: Vec<(usize, usize)> = (0..groups.len())
        .flat_map(|g| (0..BATCHES).map(move |b| (g, b)))
        .collect();
    let done = AtomicU64::new(0);
    let outcomes: Vec<(Collected, Balance)> = jobs
        .par_iter()
        .map(|&(g, b)| {
            let det = &detectors[g];
            let omega_i = direction(groups[g].0[0], groups[g].0[1]);
            let mut rng = batch_generator(setup.seed, g, b);
            let mut col = Collected::new(det.len(), nc);
            let mut bal = Balance::default();
            let n = batch_rays(setup.rays, b);
            const TICK: u64 = 1 << 14;
            // Chunks of TICK rays (the lanes drain at each chunk's end), then the rest.
            let mut left = n;
            while left > 0 {
                let m = left.min(TICK);
                let mut tally = Tally {
                    detector: det,
                    collected: &mut col,
                };
                sampler.trace_batch(omega_i, m, &mut rng, &mut bal, &mut tally);
                left -= m;
                progress(done.fetch_add(m, Ordering::Relaxed) + m);
            }
            (col, bal)
        })
        .collect();

    let omega = 2.0 * std::f64::consts::PI * 2.0 * (setup.kernel / 2.0).sin().powi(2);
    let mut balance = Balance::default();
    let mut incidences = Vec::with_capacity(groups.len());
    for (g, (_, rows)) in groups.iter().enumerate() {
        let batches = &outcomes[g * BATCHES..(g + 1) * BATCHES];
        for (_, bal) in batches {
            balance.add(bal);
        }
        let np = rows.len();
        let mut s = vec![0.0; np * ORDERS * nc];
        let mut sigma = vec![0.0; np * nc];
        for (j, &k) in rows.iter().enumerate() {
            let cos_r = directions[k][2].cos();
            let norm = |n: u64| 1.0 / (n as f64 * omega * cos_r);
            for c in 0..nc {
                let mut total = 0.0;
                for p in 0..ORDERS {
                    let sum: f64 = batches.iter().map(|(col, _)| col.get(j, p, c)).sum();
                    s[(j * ORDERS + p) * nc + c] = sum * norm(setup.rays);
                    total += sum;
                }
                let mean = total * norm(setup.rays);
                let used: Vec<f64> = batches
                    .iter()
                    .enumerate()
                    .filter(|(b, _)| batch_rays(setup.rays, *b) > 0)
                    .map(|(b, (col, _))| {
                        let t: f64 = (0..ORDERS).map(|p| col.get(j, p, c)).sum();
                        t * norm(batch_rays(setup.rays, b))
                    })
                    .collect();
                let m = used.len() as f64;
                let var = if m > 1.0 {
                    used.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (m * (m - 1.0))
                } else {
                    0.0
                };
                // No spread (nothing reached this point): one full-weight ray's worth.
                sigma[j * nc + c] = var.sqrt().max(norm(setup.rays));
            }
        }
        incidences.push(IncidenceResult {
            rows: rows.clone(),
            s,
            sigma,
        });
    }
    TraceResult {
        nc,
        incidences,
        balance,
        rays_total: setup.rays * groups.len() as u64,
    }
}

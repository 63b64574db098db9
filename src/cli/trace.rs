//! `hairfit trace`: its options ([`TraceArgs`]) and the run that reads the fibre, traces it
//! through [`crate::trace`] at a rig's directions and writes the CSV and its sidecar.

use std::path::PathBuf;
use std::time::Instant;

use crate::error::{Error, Result};
use crate::json_file::ParameterFile;
use crate::synth::{channel_names, memory, random, Rig};
use crate::trace::output::{self, record_path, TraceRecord, ESTIMATOR};
use crate::trace::{FiberFile, TraceSetup, BATCHES, MAX_CHANNELS, RNG_DESCRIPTION};

/// Largest kernel radius `--kernel-deg` takes.
pub const MAX_KERNEL_DEG: f64 = 30.0;

/// Options of `hairfit trace`.
#[derive(Debug, Clone, clap::Args)]
pub struct TraceArgs {
    /// The fibre (JSON: eta, sigma_a, cuticle_tilt_deg, roughness_deg, azimuthal_roughness_deg,
    /// eccentricity, rotation_deg, max_segments; docs/trace.md).
    #[arg(long)]
    pub fiber: PathBuf,
    /// Sample geometry, as `hairfit synth` takes it (e.g. `azimuthal:incidences=15,30,45`).
    #[arg(long)]
    pub rig: String,
    /// Rays per distinct incidence of the rig (at least 32: the batches the sigma comes from).
    #[arg(long)]
    pub rays: u64,
    /// Seed of every random draw (same seed, same bytes, any thread count).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// Radius of the cap around each rig direction that collects the exits, in degrees.
    #[arg(long, default_value_t = 2.0)]
    pub kernel_deg: f64,
    /// Output CSV (`FILE.csv`); the sidecar goes to `FILE.trace.json`. Both written atomically.
    #[arg(long)]
    pub output: PathBuf,
}

/// What `hairfit trace` wrote.
#[derive(Debug, Clone)]
pub struct TraceSummary {
    pub csv: PathBuf,
    pub sidecar: PathBuf,
    pub record: TraceRecord,
    pub seconds: f64,
}

/// Run `hairfit trace`; `command_line` is recorded in the sidecar.
pub fn run(args: &TraceArgs, command_line: Option<String>) -> Result<TraceSummary> {
    crate::atomic::require_csv_pair(&args.output, "trace", "its sidecar FILE.trace.json")?;
    let inputs = [("--fiber", args.fiber.as_path())];
    crate::atomic::refuse_replacing_inputs("--output", &args.output, &inputs)?;
    crate::atomic::refuse_replacing_inputs(
        "--output's sidecar",
        &record_path(&args.output),
        &inputs,
    )?;
    if args.rays < BATCHES as u64 {
        return Err(Error::Other(format!(
            "--rays {}: give at least {BATCHES} rays per incidence (the sigma column is the \
             spread of {BATCHES} batches)",
            args.rays
        )));
    }
    if !(args.kernel_deg.is_finite() && args.kernel_deg > 0.0 && args.kernel_deg <= MAX_KERNEL_DEG)
    {
        return Err(Error::Other(format!(
            "--kernel-deg {}: give a cap radius in (0, {MAX_KERNEL_DEG}] degrees",
            args.kernel_deg
        )));
    }
    let rig = Rig::parse(&args.rig)?;
    let file = FiberFile::load(&args.fiber)?;
    let nc = file.sigma_a_values().len();
    if nc > MAX_CHANNELS {
        return Err(Error::Other(format!(
            "{}: sigma_a has {nc} channels; trace takes at most {MAX_CHANNELS}",
            args.fiber.display()
        )));
    }
    rig.check_memory(nc, &args.rig, memory::machine_default())?;
    let directions_deg = rig.angles(&mut random::generator(args.seed, random::Stream::Angles));
    let directions = output::radians(&directions_deg);
    let setup = TraceSetup {
        rays: args.rays,
        seed: args.seed,
        kernel: args.kernel_deg.to_radians(),
    };
    let n_incidences = {
        let mut seen: Vec<(u64, u64)> = directions
            .iter()
            .map(|a| (a[0].to_bits(), a[1].to_bits()))
            .collect();
        seen.sort_unstable();
        seen.dedup();
        seen.len() as u64
    };
    let total = n_incidences.checked_mul(args.rays).ok_or_else(|| {
        Error::Other(format!(
            "--rays {} × {n_incidences} incidences overflows: use fewer rays",
            args.rays
        ))
    })?;
    let bar = indicatif::ProgressBar::new(total);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "tracing {bar:40} {human_pos}/{human_len} rays, {per_sec}, eta {eta}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let start = Instant::now();
    let result = crate::trace::run(&file.fiber(), &directions, &setup, &|n| bar.set_position(n));
    bar.finish_and_clear();
    let seconds = start.elapsed().as_secs_f64();
    let channels = channel_names(nc);
    let (ds, extra) = output::dataset(&result, &directions);
    if let Some(v) = ds
        .radiance
        .iter()
        .chain(ds.sigma.iter().flatten())
        .find(|v| !v.is_finite())
    {
        return Err(Error::Other(format!(
            "the tracer produced {v} for {}: please report this fibre",
            args.fiber.display()
        )));
    }
    let record = TraceRecord {
        hairfit_version: env!("CARGO_PKG_VERSION").into(),
        fiber: file,
        channels: channels.clone(),
        rig: rig.to_string(),
        rays_per_incidence: args.rays,
        incidences: result.incidences.len(),
        batches: BATCHES,
        seed: args.seed,
        rng: RNG_DESCRIPTION.into(),
        kernel_deg: args.kernel_deg,
        estimator: ESTIMATOR.into(),
        measurement: "s".into(),
        n_samples: ds.len(),
        energy: TraceRecord::energy(&result, &channels),
        grazing_rays: result.balance.grazing,
        mirrored_directions: result.balance.mirrored,
        normal_fallbacks: result.balance.fallbacks,
        command_line,
    };
    output::write(&ds, &extra, &record, &args.output)?;
    Ok(TraceSummary {
        csv: args.output.clone(),
        sidecar: record_path(&args.output),
        record,
        seconds,
    })
}

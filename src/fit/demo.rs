//! `hairfit demo`: a realistic 3-channel dataset from the project's synthesizer (2% relative
//! noise, a goniometer-style scan), fitted from the default start design, written to `fits/demo/`.
//! [`synthesize`] is a small in-memory twin used by the fit tests and benchmark.

use std::path::Path;
use std::sync::atomic::AtomicBool;
use std::sync::Arc;

use super::args::FitArgs;
use super::design::SplitMix64;
use super::problem::FitData;
use super::{fit, output};
use crate::error::Result;
use crate::model::{scattering, Angles, ModelConfig, Params};

/// The demo's true parameters (mid-range MODEL.md values, brown-ish hair).
pub fn demo_truth() -> Params<f64> {
    Params {
        eta: 1.55,
        sigma_a: vec![0.25, 0.45, 0.8],
        alpha_r: (-7f64).to_radians(),
        beta_r: 7.5f64.to_radians(),
        k_g: 2.0,
        w_c: 15f64.to_radians(),
        eccentricity: 0.9,
        delta_eta_prime: 0.3,
        delta_h_m: 0.5,
    }
}

/// Per-channel exposure of the demo camera.
pub const DEMO_SCALE: [f64; 3] = [2.0, 1.5, 1.0];

/// Relative noise of the demo data.
pub const DEMO_NOISE: f64 = 0.02;

/// Goniometer scan: θ_i ∈ {−30,−15,0,15,30}°, θ_r from −60° to 60° by 10°, φ_r all round by 10°,
/// two source azimuths (0° and 60°) alternating so φ_h is spread.
pub fn demo_geometry() -> Vec<Angles> {
    let mut v = Vec::new();
    for (k, ti) in [-30.0, -15.0, 0.0, 15.0, 30.0].into_iter().enumerate() {
        for tr in (-6..=6).map(|j| j as f64 * 10.0) {
            for pr in (-17..=18).map(|j| j as f64 * 10.0) {
                let pi = if (k + v.len()) % 2 == 0 { 0.0 } else { 60.0 };
                v.push(Angles::from_degrees(ti, pi, tr, pr));
            }
        }
    }
    v
}

/// Synthesize `scale_c · S · (1 + noise·N(0,1))` with sigma = noise·scale·S (true), seeded.
pub fn synthesize(
    truth: &Params<f64>,
    config: &ModelConfig,
    angles: &[Angles],
    scale: &[f64],
    noise: f64,
    seed: u64,
) -> FitData {
    let nc = truth.sigma_a.len();
    let mut rng = SplitMix64::new(seed);
    let mut values = Vec::with_capacity(angles.len() * nc);
    let mut sigma = Vec::with_capacity(angles.len() * nc);
    let mut s = vec![0.0; nc];
    for a in angles {
        scattering(truth, config, a, &mut s);
        for c in 0..nc {
            let clean = scale[c] * s[c];
            values.push(clean * (1.0 + noise * rng.normal()));
            sigma.push(if noise > 0.0 { noise * clean } else { 1.0 });
        }
    }
    let channels = match nc {
        3 => vec!["r".into(), "g".into(), "b".into()],
        _ => (0..nc).map(|c| format!("c{c}")).collect(),
    };
    FitData {
        channels,
        angles: angles.to_vec(),
        values,
        sigma: (noise > 0.0).then_some(sigma),
        weight: None,
        line: (2..angles.len() as u64 + 2).collect(),
    }
}

/// The demo geometry as `[θ_i, φ_i, θ_r, φ_r]` in degrees (for the synthesizer).
pub fn demo_directions() -> Vec<[f64; 4]> {
    demo_geometry()
        .iter()
        .map(|a| {
            [a.theta_i, a.phi_i, a.theta_r, a.phi_r].map(|x| (x.to_degrees() * 1e9).round() / 1e9)
        })
        .collect()
}

/// `hairfit demo --out DIR`: synthesize with the project's synthesizer (`crate::synth`), write
/// `data.csv` and `truth.json`, fit from the default start design, write, summarise.
pub fn demo_command(args: &FitArgs, out: &Path, cancel: Option<Arc<AtomicBool>>) -> Result<String> {
    let opts = args.options(cancel)?;
    let truth = demo_truth();
    let config = ModelConfig {
        mode: opts.mode,
        ..ModelConfig::default()
    };
    let noise = crate::synth::Noise::parse(&format!("relative:{DEMO_NOISE}"))?;
    let (dataset, truth_record) = crate::synth::synthesize_directions(
        &truth,
        &config,
        &demo_directions(),
        "hairfit demo: 5 incidences x 13 exit inclinations x 36 azimuths",
        &noise,
        &DEMO_SCALE,
        opts.seed,
    )?;
    std::fs::create_dir_all(out).map_err(|e| crate::Error::io(out, e))?;
    let data_path = out.join("data.csv");
    crate::data::write_csv(&dataset, &data_path)?;
    let truth_path = out.join("truth.json");
    crate::atomic::write_atomically(&truth_path, |w| {
        serde_json::to_writer_pretty(&mut *w, &truth_record)
            .map_err(|e| crate::Error::Other(format!("{}: {e}", truth_path.display())))
    })?;
    let report = serde_json::json!({
        "file": data_path.display().to_string(),
        "format": "synthetic",
        "rows_read": dataset.len(),
        "accepted": dataset.len(),
        "notes": [format!("hairfit demo: crate::synth, noise {noise}, seed {}", opts.seed)],
    });
    let data = super::fit_data(&dataset);
    let outcome = fit(&data, &data_path.display().to_string(), report, &opts)?;
    output::write_outputs(out, &outcome)?;
    let mut s = output::summary(&outcome, Some(out));
    s += &output::write_report_line(out);
    s += &format!(
        "truth: sigma_a {:?}, alpha_r_deg -7, beta_r_deg 7.5, k_g 2, w_c_deg 15, eccentricity 0.9, scale {:?} (see {})\n",
        truth.sigma_a,
        DEMO_SCALE,
        truth_path.display()
    );
    Ok(s)
}

//! `hairfit demo`: a realistic 3-channel dataset from the project's synthesizer (2% relative
//! noise over a camera's noise floor, a goniometer-style scan), fitted from the default start
//! design, written to `--out`. Each family's true parameters are its own
//! ([`ModelFamily::demo_truth`]).

use std::path::Path;

use crate::error::Result;
use crate::families::effects::ModelConfig;
use crate::families::{FamilyModel, FamilyParams, ModelFamily, ModelSetup};
use crate::files::LoadReport;
use crate::fit::problem::FitData;
use crate::fit::registry::fit_family;
use crate::fit::{FitOptions, FitOutcome};
use crate::geometry::Angles;
use crate::report::publish::PublishedFit;

/// Per-channel exposure of the demo camera.
pub const DEMO_SCALE: [f64; crate::families::DEMO_CHANNELS] = [2.0, 1.5, 1.0];

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

/// The demo geometry as `[θ_i, φ_i, θ_r, φ_r]` in degrees (for the synthesizer).
pub fn demo_directions() -> Vec<[f64; 4]> {
    demo_geometry()
        .iter()
        .map(|a| {
            [a.theta_i, a.phi_i, a.theta_r, a.phi_r].map(|x| (x.to_degrees() * 1e9).round() / 1e9)
        })
        .collect()
}

/// `hairfit demo --out DIR`: synthesize with the project's synthesizer (`crate::synth`) and the
/// model family `opts.family`, write `data.csv` and `truth.json`, fit the same family from the
/// default start design, and publish them with the fit's files as one set (`force` as
/// `hairfit fit --force`).
pub fn demo_command(opts: &FitOptions, out: &Path, force: bool) -> Result<PublishedFit> {
    // A bad --fix is an error about the option, before anything touches the output directory.
    crate::fit::registry::family_fit(opts.family).check_fixes(&opts.fix, DEMO_SCALE.len())?;
    crate::report::publish::publish_fit(out, "hairfit demo", force, &[], |staging| {
        demo_into(opts, out, staging)
    })
}

/// The demo's dataset and its truth for `opts` (family, terms, measurement, seed), in memory.
pub fn demo_synthesis(opts: &FitOptions) -> Result<(crate::data::Dataset, crate::files::Truth)> {
    let setup = ModelSetup {
        config: ModelConfig {
            mode: opts.model.config.mode,
            ..ModelConfig::default()
        },
        ..opts.model.clone()
    };
    let file = ModelFamily::demo_truth(opts.family);
    let model = FamilyModel::new(&file, &setup);
    let source = crate::synth::Source {
        model: &model,
        file: &file,
        records: setup.records(opts.family),
    };
    let how = crate::synth::Acquisition {
        directions: &demo_directions(),
        label: "hairfit demo: 5 incidences x 13 exit inclinations x 36 azimuths",
        noise: &demo_noise(),
        scale: &DEMO_SCALE,
        measurement: opts.measurement,
        seed: opts.seed,
    };
    crate::synth::synthesize_model(&source, &how)
}

/// The demo's data as the fit sees them ([`demo_synthesis`]).
pub fn demo_data(opts: &FitOptions) -> Result<FitData> {
    Ok(crate::fit::fit_data(&demo_synthesis(opts)?.0))
}

/// The demo camera's noise floor (additive, σ in the data's units): about 1/10⁴ of the brightest
/// demo values (~3), a 13–14-bit sensor's read noise, so dark directions read as noise around
/// zero as on a real rig (data/README.md) instead of values down to 1e-26.
pub const DEMO_FLOOR: f64 = 3e-4;

fn demo_noise() -> crate::synth::Noise {
    crate::synth::Noise::parse(&format!("relative:{DEMO_NOISE}+floor:{DEMO_FLOOR}"))
        .expect("the demo noise parses")
}

/// The demo's data, truth and fit, written into `staging` (published later as `out`).
fn demo_into(opts: &FitOptions, out: &Path, staging: &Path) -> Result<FitOutcome<FamilyParams>> {
    let (dataset, truth_record) = demo_synthesis(opts)?;
    // Files go to the staging directory; the fit records where they will be.
    let data_path = out.join("data.csv");
    crate::data::write_csv(&dataset, &staging.join("data.csv"))?;
    truth_record.save(&staging.join("truth.json"))?;
    let report = LoadReport {
        file: data_path.display().to_string(),
        format: "synthetic".into(),
        rows_read: dataset.len() as u64,
        accepted: dataset.len() as u64,
        notes: vec![format!(
            "hairfit demo: crate::synth, noise {}, seed {}",
            demo_noise(),
            opts.seed
        )],
        ..LoadReport::default()
    };
    let data = crate::fit::fit_data(&dataset);
    fit_family(&data, &data_path.display().to_string(), report, opts)
}

/// The demo's truth (of `family`), for the end of its summary.
pub fn truth_line(out: &Path, family: ModelFamily) -> String {
    let params = serde_json::to_value(ModelFamily::demo_truth(family)).unwrap_or_default();
    let mut items = Vec::new();
    if let Some(map) = params.as_object() {
        for (key, value) in map.iter().filter(|(k, _)| *k != "model") {
            items.push(format!("{key} {value}"));
        }
    }
    format!(
        "truth: {}, scale {:?} (see {})\n",
        items.join(", "),
        DEMO_SCALE,
        out.join("truth.json").display()
    )
}

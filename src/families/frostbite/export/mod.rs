//! `hairfit export fits/NAME --to unity`: Unity HDRP's Hair material (Material Type Physical)
//! — Base Color, Smoothness, Radial Smoothness, Cuticle Angle, with the IOR HDRP fixes at 1.55 —
//! fitted to the fit's `S` through the frostbite family, which evaluates HDRP's physical hair
//! ([`crate::families::frostbite`]), times one shared gain (the light's intensity: the colour
//! must come from Base Color). Written as a JSON file with the inputs, the HDRP conventions they
//! follow, the mapping's error and the source fit, and a C# editor script beside it
//! ([`script`]) that sets them on a material.

use std::path::{Path, PathBuf};

use serde_json::{json, Value};

mod script;

use super::{
    absorption_denominator, Frostbite, BASE_COLOR, BASE_COLOR_MIN, CUTICLE_ANGLE, ETA,
    RADIAL_SMOOTHNESS, RADIAL_SMOOTHNESS_MAX, SMOOTHNESS, SMOOTHNESS_MAX,
};
use crate::error::{Error, Result};
use crate::export::log_fit::{fit_log, LogErrors, LogFit, LogModel, LogTarget};
use crate::export::reference::{max as largest, MappingTarget};
use crate::export::source::{SourceFit, SourceModel};
use crate::export::{warning_lines, ExportTarget, FamilyTargets};
use crate::families::table::fit::{TableForward, TableParam};
use crate::families::table::{TableFamily, TableParams, TermSet};
use crate::families::{FamilyModel, TableModel};
use crate::fit::problem::Forward;
use crate::geometry::{Angles, Measurement};
use script::{csharp_identifier, script};

/// The HDRP behaviour the inputs are fitted to (docs/frostbite.md, "Which HDRP").
pub const HDRP_CONVENTIONS: &str = "Unity HDRP Hair Master Stack, Material Type Physical, the \
     non-cinematic raster path of Runtime/Material/Hair/Hair.hlsl as on the Unity-Technologies/\
     Graphics master branch (Unity 6 / HDRP 17 line or later; the release was not pinned); IOR \
     fixed at 1.55";

/// HDRP's IOR (not an input).
pub const HDRP_IOR: f64 = 1.55;

/// What `--to unity` produced.
#[derive(Debug, Clone)]
pub struct UnityExport {
    /// The JSON file's text.
    pub json: String,
    /// The C# editor script's text.
    pub script: String,
    /// One line for stderr: what was fitted and how well.
    pub summary: String,
    pub warnings: Vec<String>,
}

/// The fitted inputs, HDRP's units (Base Color linear, Cuticle Angle in degrees).
#[derive(Debug, Clone, PartialEq)]
pub struct UnityInputs {
    pub base_color: Vec<f64>,
    pub smoothness: f64,
    pub radial_smoothness: f64,
    pub cuticle_angle_deg: f64,
    /// The shared factor on S: the light's intensity relative to the source fit's.
    pub gain: f64,
}

impl UnityInputs {
    /// The frostbite family's parameters (model units) at HDRP's IOR.
    pub fn params(&self) -> TableParams<f64> {
        let mut values = vec![Vec::new(); Frostbite::PARAMETERS.len()];
        values[BASE_COLOR] = self.base_color.clone();
        values[SMOOTHNESS] = vec![self.smoothness];
        values[RADIAL_SMOOTHNESS] = vec![self.radial_smoothness];
        values[CUTICLE_ANGLE] = vec![self.cuticle_angle_deg.to_radians()];
        values[ETA] = vec![HDRP_IOR];
        TableParams {
            values,
            n_channels: self.base_color.len(),
        }
    }

    /// The inputs read from a frostbite fit's parameters (its η is dropped: HDRP fixes it).
    fn from_params(p: &TableParams<f64>) -> UnityInputs {
        UnityInputs {
            base_color: p.values[BASE_COLOR].clone(),
            smoothness: p.values[SMOOTHNESS][0],
            radial_smoothness: p.values[RADIAL_SMOOTHNESS][0],
            cuticle_angle_deg: p.values[CUTICLE_ANGLE][0].to_degrees(),
            gain: 1.0,
        }
    }
}

/// `1/(1 + e^{−x})`.
fn logistic(x: f64) -> f64 {
    1.0 / (1.0 + (-x).exp())
}

/// The inverse of [`logistic`], kept off its ends.
fn logit(y: f64) -> f64 {
    let y = y.clamp(1e-9, 1.0 - 1e-9);
    (y / (1.0 - y)).ln()
}

/// Free variables ↔ inputs: every iterate is a valid material. `C = C_min + (1 − C_min)σ(x)`,
/// `s_L = 0.99σ(x)`, `s_N = 0.9σ(x)` (the table's range), Cuticle Angle = x radians,
/// gain = eˣ; `x = [C…, s_L, s_N, a, ln g]`.
fn inputs_of(x: &[f64], n: usize) -> UnityInputs {
    UnityInputs {
        base_color: x[..n]
            .iter()
            .map(|&v| BASE_COLOR_MIN + (1.0 - BASE_COLOR_MIN) * logistic(v))
            .collect(),
        smoothness: SMOOTHNESS_MAX * logistic(x[n]),
        radial_smoothness: RADIAL_SMOOTHNESS_MAX * logistic(x[n + 1]),
        cuticle_angle_deg: x[n + 2].to_degrees(),
        gain: x[n + 3].exp(),
    }
}

/// The inverse of [`inputs_of`].
fn variables_of(u: &UnityInputs) -> Vec<f64> {
    let mut x: Vec<f64> = u
        .base_color
        .iter()
        .map(|&c| logit((c - BASE_COLOR_MIN) / (1.0 - BASE_COLOR_MIN)))
        .collect();
    x.extend([
        logit(u.smoothness / SMOOTHNESS_MAX),
        logit(u.radial_smoothness / RADIAL_SMOOTHNESS_MAX),
        u.cuticle_angle_deg.to_radians(),
        u.gain.max(1e-300).ln(),
    ]);
    x
}

/// `dinput/dx` for every variable but the gain (the chain rule from [`inputs_of`]).
fn input_slopes(x: &[f64], n: usize) -> Vec<f64> {
    let slope = |v: f64, span: f64| {
        let s = logistic(v);
        span * s * (1.0 - s)
    };
    let mut d: Vec<f64> = x[..n]
        .iter()
        .map(|&v| slope(v, 1.0 - BASE_COLOR_MIN))
        .collect();
    d.extend([
        slope(x[n], SMOOTHNESS_MAX),
        slope(x[n + 1], RADIAL_SMOOTHNESS_MAX),
        1.0,
    ]);
    d
}

/// HDRP's physical hair (the frostbite family, all three lobes, η = 1.55) times the gain, at
/// fixed directions.
struct UnityModel<'a> {
    angles: &'a [Angles],
    n: usize,
    forward: TableForward<Frostbite>,
}

impl<'a> UnityModel<'a> {
    fn new(angles: &'a [Angles], n: usize) -> UnityModel<'a> {
        UnityModel {
            angles,
            n,
            forward: TableForward::new(TermSet::all(Frostbite::TERMS.len()), Measurement::S),
        }
    }

    /// The frostbite parameters the variables stand for (model units) and the gain.
    fn params(&self, x: &[f64]) -> (TableParams<f64>, f64) {
        let u = inputs_of(x, self.n);
        (u.params(), u.gain)
    }
}

impl LogModel for UnityModel<'_> {
    fn values(&self, x: &[f64]) -> Vec<f64> {
        let (p, gain) = self.params(x);
        let mut out = vec![0.0; self.angles.len() * self.n];
        self.forward.values(&p, self.angles, &mut out);
        out.iter_mut().for_each(|v| *v *= gain);
        out
    }

    fn jacobian(&self, x: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let (p, gain) = self.params(x);
        let n = self.n;
        let mut free: Vec<TableParam<Frostbite>> = (0..n)
            .map(|c| TableParam::new((BASE_COLOR, Some(c))))
            .collect();
        free.extend(
            [SMOOTHNESS, RADIAL_SMOOTHNESS, CUTICLE_ANGLE].map(|k| TableParam::new((k, None))),
        );
        let rows = self.angles.len() * n;
        let nf = free.len();
        let mut s = vec![0.0; rows];
        let mut grad = vec![0.0; rows * nf];
        self.forward
            .gradients(&p, &free, self.angles, &mut s, &mut grad);
        let slopes = input_slopes(x, n);
        let nx = x.len();
        let mut jac = vec![0.0; rows * nx];
        for r in 0..rows {
            for j in 0..nf {
                jac[r * nx + j] = gain * grad[r * nf + j] * slopes[j];
            }
            jac[r * nx + nf] = gain * s[r];
        }
        s.iter_mut().for_each(|v| *v *= gain);
        (s, jac)
    }
}

/// Base Color for absorption σ_a at azimuthal roughness β_N: HDRP's inverse of Chiang eq. 9,
/// `C = exp(−√σ_a D(β_N))`, kept inside the Base Color range.
fn base_color_for(sigma_a: f64, beta_n: f64) -> f64 {
    (-(sigma_a.max(0.0).sqrt()) * absorption_denominator(&beta_n))
        .exp()
        .clamp(2.0 * BASE_COLOR_MIN, 0.999)
}

/// Where the LM starts: a frostbite fit's own inputs; from a fit with an R lobe, the
/// inputs it suggests (R's θ_h width → 1 − Smoothness, R's centre → −Cuticle Angle,
/// σ_a → Base Color) at two Radial Smoothness values; from any other family a small grid.
fn starting_inputs(model: &SourceModel, n: usize) -> Vec<UnityInputs> {
    let at_radial = |sigma: &[f64], width: f64, centre: f64| {
        [0.7, 0.4]
            .map(|radial: f64| UnityInputs {
                base_color: sigma
                    .iter()
                    .map(|&s| base_color_for(s, 1.0 - radial))
                    .collect(),
                smoothness: (1.0 - width).clamp(0.3, 0.98),
                radial_smoothness: radial,
                cuticle_angle_deg: -centre.to_degrees(),
                gain: 1.0,
            })
            .to_vec()
    };
    match &model.model {
        FamilyModel::Table(TableModel { table, params, .. }) if table.name() == Frostbite::NAME => {
            vec![UnityInputs::from_params(params)]
        }
        _ => match model.specular_lobe() {
            Some(lobe) => at_radial(&lobe.sigma_a, lobe.width, lobe.shift),
            None => [(0.8, 0.5), (0.92, 0.8)]
                .map(|(smoothness, radial_smoothness)| UnityInputs {
                    base_color: vec![0.5; n],
                    smoothness,
                    radial_smoothness,
                    cuticle_angle_deg: 3.0,
                    gain: 1.0,
                })
                .to_vec(),
        },
    }
}

/// The mapping's result: the inputs and how well they reproduce the source's S.
#[derive(Debug, Clone)]
pub struct UnityMapping {
    pub inputs: UnityInputs,
    /// `gain · S` against the source.
    pub errors: LogErrors,
    /// What HDRP renders with its clamp, `gain · min(S, 1)`, against the source.
    pub clamped: LogErrors,
    /// Directions: measured (curves.csv), then the dense sphere.
    pub directions: (usize, usize),
    /// LM iterations, and starts.
    pub work: (u64, usize),
    /// The largest S (without the gain) at the fitted inputs over every direction and channel,
    /// and how many direction-channel values exceed 1 (HDRP clamps S at 1).
    pub max_s: f64,
    pub above_one: usize,
}

/// Fit HDRP's inputs and one gain to the source's S over its measured directions and the dense
/// sphere.
pub fn fit_unity(source: &SourceFit) -> Result<UnityMapping> {
    let mapped = MappingTarget::new(source)?;
    let n = source.model.n_channels();
    let target = LogTarget::new(&mapped.target, n);
    let model = UnityModel::new(&mapped.angles, n);
    // Each start's gain is the geometric mean ratio of the source's S to the engine's there.
    let starts: Vec<Vec<f64>> = starting_inputs(&source.model, n)
        .into_iter()
        .map(|u| target.with_best_gain(&model, variables_of(&u), n + 3))
        .collect();
    let LogFit {
        x,
        iterations,
        starts,
        ..
    } = fit_log(&model, &target, &starts)?;
    let values = model.values(&x);
    let inputs = inputs_of(&x, n);
    let measured_rows = source.measured.len() * n;
    let unscaled: Vec<f64> = values.iter().map(|v| v / inputs.gain).collect();
    let clamped: Vec<f64> = unscaled.iter().map(|v| v.min(1.0) * inputs.gain).collect();
    Ok(UnityMapping {
        errors: LogErrors::of(&target.errors(&values), measured_rows),
        clamped: LogErrors::of(&target.errors(&clamped), measured_rows),
        directions: (source.measured.len(), mapped.n_sphere),
        work: (iterations, starts),
        max_s: largest(&unscaled),
        above_one: unscaled.iter().filter(|&&v| v > 1.0).count(),
        inputs,
    })
}

/// What the inputs cannot carry of the source fit, and where HDRP departs from the family.
fn warnings(source: &SourceFit, m: &UnityMapping) -> Vec<String> {
    let mut out = Vec::new();
    if let FamilyModel::Table(TableModel {
        table,
        params,
        terms,
    }) = &source.model.model
    {
        if table.name() == Frostbite::NAME {
            if *terms != TermSet::all(Frostbite::TERMS.len()) {
                out.push(format!(
                    "the fit ran with terms {} only, but HDRP always renders R, TT and TRT: the \
                     inputs were refitted to the fit's S",
                    terms.names(Frostbite::TERMS).join("+")
                ));
            }
            if params.values[ETA][0] != HDRP_IOR {
                out.push(format!(
                    "the fit freed eta ({:.4}); HDRP fixes the IOR at 1.55, so the inputs were \
                     refitted at 1.55",
                    params.values[ETA][0]
                ));
            }
        }
    }
    if m.above_one > 0 {
        out.push(format!(
            "at these inputs S exceeds 1 at {} of {} direction-channel values (largest {:.3}); \
             HDRP clamps S at 1 per channel (saturate), which costs rms |d ln S| {:.4} (max \
             {:.3}) instead of {:.4}",
            m.above_one,
            (m.directions.0 + m.directions.1) * m.inputs.base_color.len(),
            m.max_s,
            m.clamped.rms,
            m.clamped.max,
            m.errors.rms
        ));
    }
    let u = &m.inputs;
    for (name, value, limit) in [
        ("Smoothness", u.smoothness, SMOOTHNESS_MAX),
        (
            "Radial Smoothness",
            u.radial_smoothness,
            RADIAL_SMOOTHNESS_MAX,
        ),
    ] {
        if value > limit - 1e-3 {
            out.push(format!(
                "{name} came out at its upper limit {limit}: the fit's S wants narrower lobes \
                 than HDRP (or hairfit's azimuthal table) allows"
            ));
        }
    }
    out
}

/// `--to unity`: the frostbite family is HDRP's physical hair.
impl FamilyTargets for Frostbite {
    fn targets() -> &'static [&'static dyn ExportTarget] {
        &[&Unity]
    }
}

/// Unity HDRP's hair, Material Type Physical: a JSON file of its inputs and a C# editor script
/// beside it.
pub struct Unity;

impl ExportTarget for Unity {
    fn name(&self) -> &'static str {
        "unity"
    }

    fn aliases(&self) -> &'static [&'static str] {
        &["hdrp"]
    }

    fn program(&self) -> &'static str {
        "Unity HDRP"
    }

    fn extension(&self) -> &'static str {
        "json"
    }

    fn file_name(&self) -> &'static str {
        "hair.json"
    }

    fn file_kind(&self) -> &'static str {
        "a Unity HDRP hair material (JSON; its C# editor script goes beside it)"
    }

    fn companion(&self, output: &Path) -> Option<PathBuf> {
        Some(output.with_extension("cs"))
    }

    /// Two files cannot go to stdout: `--output` names the JSON.
    fn check_output(&self, output: Option<&Path>) -> Result<()> {
        unity_output(output).map(|_| ())
    }

    fn run(&self, dir: &Path, output: Option<&Path>) -> Result<(String, Option<String>)> {
        unity_command(dir, output).map(|summary| (summary, None))
    }
}

/// `--to unity`'s `--output`: required (two files cannot go to stdout), and the JSON's name,
/// not the script's.
fn unity_output(output: Option<&Path>) -> Result<&Path> {
    let json = output.ok_or_else(|| {
        Error::Other(
            "--to unity writes two files, NAME.json and the C# editor script NAME.cs beside it: \
             pass --output NAME.json"
                .into(),
        )
    })?;
    if json
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("cs"))
    {
        return Err(Error::Other(format!(
            "--output {}: --to unity's --output names the JSON file; the C# script is written \
             beside it with .cs: pass --output {}",
            json.display(),
            json.with_extension("json").display()
        )));
    }
    Ok(json)
}

/// `--to unity`: the JSON and the C# script beside it.
fn unity_command(dir: &Path, output: Option<&Path>) -> Result<String> {
    let json = unity_output(output)?;
    let script = json.with_extension("cs");
    let script_name = script
        .file_name()
        .map(|n| n.to_string_lossy().into_owned())
        .unwrap_or_default();
    let result = export_unity(dir, &script_name)?;
    // Both or neither: a pair from two different fits would load without complaint.
    crate::atomic::write_together(&[
        (json, result.json.as_bytes()),
        (&script, result.script.as_bytes()),
    ])?;
    Ok(format!(
        "{}{}; wrote {} and {}",
        warning_lines(&result.warnings),
        result.summary,
        json.display(),
        script.display()
    ))
}

/// Export the fit in `dir` for Unity; `script_file` is the name the C# script will have (its
/// class is named after the material).
pub fn export_unity(dir: &Path, script_file: &str) -> Result<UnityExport> {
    let source = SourceFit::load(dir)?;
    let channels = source.rgb_order()?;
    let mapping = fit_unity(&source)?;
    let warnings = warnings(&source, &mapping);
    let name = crate::export::text::material_name(&source);
    let json = json_text(&source, &mapping, &channels, &warnings, script_file);
    let script = script(&csharp_identifier(&name), &source, &mapping, &warnings);
    let summary = format!(
        "export to unity: HDRP Hair (Physical) inputs from the {} fit in {}: {}",
        source.model.name(),
        dir.display(),
        quality_text(&mapping)
    );
    Ok(UnityExport {
        json,
        script,
        summary,
        warnings,
    })
}

/// One line: how well the inputs reproduce the source's S.
pub fn quality_text(m: &UnityMapping) -> String {
    let e = &m.errors;
    let measured = e
        .rms_measured
        .map(|r| format!(", measured directions only {r:.4}"))
        .unwrap_or_default();
    format!(
        "fitted over {} measured + {} sphere directions: rms |d ln S| {:.4} (max {:.3}{measured}), \
         light gain {:.4}, {} LM iterations from {} starts",
        m.directions.0, m.directions.1, e.rms, e.max, m.inputs.gain, m.work.0, m.work.1
    )
}

/// sRGB encoding of a linear value (IEC 61966-2-1), for the Inspector's display of Base Color.
pub fn srgb_encode(linear: f64) -> f64 {
    if linear <= 0.003_130_8 {
        12.92 * linear
    } else {
        1.055 * linear.powf(1.0 / 2.4) - 0.055
    }
}

/// Base Color as RGB (one channel repeated as grey).
pub fn rgb(c: &[f64]) -> [f64; 3] {
    match c {
        [g] => [*g; 3],
        [r, g, b] => [*r, *g, *b],
        other => panic!("rgb needs 1 or 3 channels, got {}", other.len()),
    }
}

fn json_text(
    source: &SourceFit,
    m: &UnityMapping,
    channels: &[String],
    warnings: &[String],
    script_file: &str,
) -> String {
    let u = &m.inputs;
    let linear = rgb(&u.base_color);
    let value: Value = json!({
        "hairfit_export": "unity",
        "written_by": format!("hairfit {}", env!("CARGO_PKG_VERSION")),
        "engine": "Unity HDRP",
        "conventions": HDRP_CONVENTIONS,
        "material": {
            "base_color_linear": linear,
            "base_color_srgb": linear.map(srgb_encode),
            "smoothness": u.smoothness,
            "radial_smoothness": u.radial_smoothness,
            "cuticle_angle_deg": u.cuticle_angle_deg,
        },
        "held": { "ior": HDRP_IOR },
        "light_gain": u.gain,
        "mapping": {
            "rms_abs_d_ln_s": m.errors.rms,
            "max_abs_d_ln_s": m.errors.max,
            "rms_abs_d_ln_s_measured": m.errors.rms_measured,
            "measured_directions": m.directions.0,
            "sphere_directions": m.directions.1,
            "floor_fraction": crate::export::reference::FLOOR_FRACTION,
            "lm_iterations": m.work.0,
            "starts": m.work.1,
            "max_s": m.max_s,
            "rms_abs_d_ln_s_with_hdrp_clamp": m.clamped.rms,
            "max_abs_d_ln_s_with_hdrp_clamp": m.clamped.max,
        },
        "source_fit": {
            "dir": source.dir.display().to_string(),
            "model": source.model.name(),
            "fitted_by": source.fitted_by,
            "quality": source.quality,
            "channels_as_rgb": channels,
            "measured_directions_from": source.measured_from,
            "held": source.held,
        },
        "not_modelled": [
            "HDRP's non-cinematic path adds Zinke et al.'s local multiple scattering to R+TT+TRT \
             and clamps S at 1 per channel; hairfit fits the single-fibre lobes only",
            "HDRP reads the azimuthal lobes from its own 64^3 half-float table (20 samples \
             across the fibre); hairfit integrates them accurately (docs/frostbite.md)",
        ],
        "warnings": warnings,
        "script": script_file,
    });
    let mut text = serde_json::to_string_pretty(&value).expect("JSON values serialise");
    text.push('\n');
    text
}

//! The two files of an Unreal export: a JSON file of the fitted material inputs (named as the
//! parent material's parameters), the engine version whose conventions they follow, the
//! mapping's quality and the source fit; and an Unreal Editor Python script that creates a
//! material instance of a parent hair material with those inputs (docs/export.md, "Unreal").

use serde_json::{json, Value};

use super::super::{ENGINE_ETA, ENGINE_SHIFT};
use super::fit::EngineMapping;
use super::{ENGINE_VERSION, MODEL_NAME, PARAMETERS};
use crate::export::reference::FLOOR_FRACTION;
use crate::export::source::SourceFit;
use crate::export::text::{material_name, rgb};

/// Where a parent material lives unless the script is told otherwise.
pub const DEFAULT_PARENT: &str = "/Game/Hairfit/M_HairfitHair";

/// The folder the instance is created in.
pub const PACKAGE_PATH: &str = "/Game/Hairfit";

/// How the engine evaluates what the inputs were fitted to.
pub const CONVENTIONS: &str = "HairBsdf.ush HairShading for one punctual light on an unshadowed \
fibre: separable R, legacy TT absorption (r.HairStrands.Components.TTModel 0, the default), eta \
1.55 and cuticle shift 0.035 rad hard-coded, tangent root to tip; the value is f = S cos(theta_i) \
with no N.L";

fn error_pair(pair: Option<(f64, f64)>) -> Value {
    pair.map_or(
        Value::Null,
        |(rms, max)| json!({"rms_log": rms, "max_log": max}),
    )
}

/// The JSON file: parameters under the parent material's names, with everything a reader needs
/// to judge them.
pub fn json(
    source: &SourceFit,
    m: &EngineMapping,
    channels: &[String],
    warnings: &[String],
) -> String {
    let i = &m.inputs;
    let params_path = source.dir.join("params.json");
    let source_params = crate::json_file::read_text(&params_path)
        .ok()
        .and_then(|t| serde_json::from_str::<Value>(&t).ok())
        .unwrap_or(Value::Null);
    let value = json!({
        "hairfit_export": "unreal",
        "written_by": format!("hairfit {}", env!("CARGO_PKG_VERSION")),
        "engine": {
            "name": "Unreal Engine",
            "versions": ENGINE_VERSION,
            "model": MODEL_NAME,
            "shading_model": "Hair (MSM_Hair)",
            "conventions": CONVENTIONS,
            "colour_space": "linear",
        },
        "material_instance": format!("MI_{}", material_name(source)),
        "parameters": {
            "BaseColor": rgb(&i.base_color),
            "Roughness": i.roughness,
            "Specular": i.specular,
            "Backlit": i.backlit,
            "Scatter": i.scatter,
        },
        "parameter_pins": PARAMETERS
            .iter()
            .map(|(name, pin, kind)| json!({"name": name, "pin": pin, "kind": kind}))
            .collect::<Vec<_>>(),
        "light_gain": i.gain,
        "held": { "eta": ENGINE_ETA, "shift_rad": ENGINE_SHIFT },
        "mapping": {
            "rms_log": m.errors.rms,
            "max_log": m.errors.max,
            "rms_log_measured": m.errors.rms_measured,
            "n_measured": m.directions.0,
            "n_sphere": m.directions.1,
            "floor_fraction": FLOOR_FRACTION,
            "iterations": m.work.0,
            "starts": m.work.1,
            "as_fitted": error_pair(m.as_fitted),
            "without_scatter": error_pair(m.without_scatter),
        },
        "source": {
            "dir": source.dir.display().to_string(),
            "model": source.model.name(),
            "fitted_by": source.fitted_by,
            "quality": source.quality,
            "channels": channels,
            "measured_from": source.measured_from,
            "held": source.held,
            "params": source_params,
        },
        "warnings": warnings,
    });
    let mut text = serde_json::to_string_pretty(&value).expect("a JSON value serialises");
    text.push('\n');
    text
}

/// A float as Python reads it back to the same f64.
fn py(x: f64) -> String {
    format!("{x:?}")
}

/// The Unreal Editor script: load the parent, create (or update) the instance, set every
/// parameter, read each back, save.
pub fn script(source: &SourceFit, m: &EngineMapping, warnings: &[String]) -> String {
    let i = &m.inputs;
    let [r, g, b] = rgb(&i.base_color);
    let mut header: Vec<String> = warnings.iter().map(|w| format!("WARNING: {w}")).collect();
    header.extend([
        format!("hairfit export: {MODEL_NAME}, {ENGINE_VERSION} conventions"),
        format!(
            "source fit: {} ({} model{})",
            source.dir.display(),
            source.model.name(),
            (source.fitted_by.as_ref())
                .map(|v| format!(", fitted by hairfit {v}"))
                .unwrap_or_default()
        ),
        format!("written by hairfit {}", env!("CARGO_PKG_VERSION")),
        format!("fit quality: {}", source.quality),
        format!("mapping: {}", m.quality_text()),
        format!(
            "light gain {}: the engine's S times this is the fit's S (set it as the light's \
             intensity, or ignore it when only the look matters)",
            py(i.gain)
        ),
    ]);
    let header: String = header.iter().map(|l| format!("# {l}\n")).collect();
    let name = format!("MI_{}", material_name(source));
    format!(
        r#"{header}"""Create the material instance {name} of a hair material with hairfit's fitted inputs.

Run it in the Unreal Editor with the Python Editor Script Plugin enabled, e.g. in the Output
Log's Python console:  py "path/to/this.py"  (or  py "path/to/this.py" /Game/Path/M_Parent).
The parent material uses the Hair shading model and exposes a Vector Parameter BaseColor and
Scalar Parameters Roughness, Specular, Backlit and Scatter, each wired to the pin of that name
(hairfit's docs/export.md, "Unreal Engine"). An instance of the same name is updated.
"""
import sys

import unreal

PARENT_MATERIAL = "{DEFAULT_PARENT}"
PACKAGE_PATH = "{PACKAGE_PATH}"
INSTANCE_NAME = "{name}"
# Linear RGB, as the Base Color pin takes it.
VECTORS = {{"BaseColor": ({r}, {g}, {b})}}
SCALARS = {{
    "Roughness": {roughness},
    "Specular": {specular},
    "Backlit": {backlit},
    "Scatter": {scatter},
}}


def names(found):
    return set(str(n) for n in found)


def create_instance(parent_path=PARENT_MATERIAL, package_path=PACKAGE_PATH, name=INSTANCE_NAME):
    assets = unreal.EditorAssetLibrary
    lib = unreal.MaterialEditingLibrary
    parent = assets.load_asset(parent_path)
    if parent is None:
        raise RuntimeError("no material at %s: create the parent hair material first" % parent_path)
    missing = sorted(set(SCALARS) - names(lib.get_scalar_parameter_names(parent)))
    missing += sorted(set(VECTORS) - names(lib.get_vector_parameter_names(parent)))
    if missing:
        raise RuntimeError("%s lacks the parameters %s" % (parent_path, ", ".join(missing)))
    path = package_path + "/" + name
    if assets.does_asset_exist(path):
        instance = assets.load_asset(path)
    else:
        tools = unreal.AssetToolsHelpers.get_asset_tools()
        instance = tools.create_asset(
            name,
            package_path,
            unreal.MaterialInstanceConstant,
            unreal.MaterialInstanceConstantFactoryNew(),
        )
    if instance is None:
        raise RuntimeError("could not create the material instance %s" % path)
    lib.set_material_instance_parent(instance, parent)
    for key, value in SCALARS.items():
        lib.set_material_instance_scalar_parameter_value(instance, key, value)
    for key, (red, green, blue) in VECTORS.items():
        colour = unreal.LinearColor(red, green, blue, 1.0)
        lib.set_material_instance_vector_parameter_value(instance, key, colour)
    lib.update_material_instance(instance)
    # The setters' return values are reported unreliable in some 5.x versions: read back instead.
    for key, value in SCALARS.items():
        got = lib.get_material_instance_scalar_parameter_value(instance, key)
        if abs(got - value) > 1e-6 * max(1.0, abs(value)):
            raise RuntimeError("%s reads back %r, not %r" % (key, got, value))
    for key, rgb in VECTORS.items():
        got = lib.get_material_instance_vector_parameter_value(instance, key)
        if any(abs(a - b) > 1e-6 for a, b in zip((got.r, got.g, got.b), rgb)):
            raise RuntimeError("%s reads back %r, not %r" % (key, got, rgb))
    assets.save_asset(path)
    unreal.log("hairfit: wrote %s (parent %s)" % (path, parent_path))
    return instance


create_instance(*getattr(sys, "argv", [])[1:2])
"#,
        r = py(r),
        g = py(g),
        b = py(b),
        roughness = py(i.roughness),
        specular = py(i.specular),
        backlit = py(i.backlit),
        scatter = py(i.scatter),
    )
}

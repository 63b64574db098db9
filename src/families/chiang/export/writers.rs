//! The three files `hairfit export` writes, each opening with the same header (source fit,
//! hairfit version, the fit's quality, the mapping's error) in the format's comment syntax:
//! a pbrt-v4 `MakeNamedMaterial` block, a Blender Python script, a MaterialX document.

use super::mapping::Mapping;
use super::Renderer;
use crate::export::source::SourceFit;
use crate::export::text::{num, rgb};
use crate::families::FamilyModel;

/// The header's lines (no comment markers).
pub fn header_lines(
    source: &SourceFit,
    renderer: Renderer,
    mapping: &Mapping,
    channels: &[String],
    warnings: &[String],
) -> Vec<String> {
    let mut lines: Vec<String> = warnings.iter().map(|w| format!("WARNING: {w}")).collect();
    lines.extend([
        format!("hairfit export: {}", renderer.model_name()),
        format!(
            "source fit: {} ({} model{})",
            source.dir.display(),
            source.model.name(),
            source
                .fitted_by
                .as_ref()
                .map(|v| format!(", fitted by hairfit {v}"))
                .unwrap_or_default()
        ),
        format!("written by hairfit {}", env!("CARGO_PKG_VERSION")),
        format!("fit quality: {}", source.quality),
        format!("mapping: {}", mapping.quality_text()),
        format!("measured directions: {}", source.measured_from),
    ]);
    if matches!(source.model.model, FamilyModel::Chiang(_)) && !source.held.is_empty() {
        lines.push(format!(
            "held by the fit, not fitted from the data: {}",
            source.held.join(", ")
        ));
    }
    lines.push(if channels.len() == 1 {
        format!("colour: one channel ({}) written as grey RGB", channels[0])
    } else {
        format!(
            "colour: channels {} written as R, G, B",
            channels.join(", ")
        )
    });
    let note = match renderer {
        Renderer::Pbrt => {
            "alpha is pbrt's alpha in degrees: the R peak sits at theta_h = +alpha along the \
             curve's dpdu (root to tip for strands stored root first); pbrt-v4 clamps beta to \
             [0.01, 1]"
        }
        Renderer::Blender => {
            "Cycles tilts theta_i (R at -Offset), so Offset was fitted, not negated; Offset is \
             in radians in bpy; colour is given as Absorption Coefficient (per fibre radius), so \
             Blender's melanin constants do not enter; Coat 0 keeps the R roughness at Roughness"
        }
        Renderer::Materialx => {
            "chiang_hair_bsdf tilts theta_i and divides f by pi: cuticle_angle = alpha/pi + 0.5 \
             was fitted, and the grey tints carry the fitted gain (about pi); roughness pairs \
             come from chiang_hair_roughness (scale_TT 0.5, scale_TRT 2 as in pbrt)"
        }
    };
    lines.push(note.into());
    lines
}

fn commented(header: &[String], marker: &str) -> String {
    header
        .iter()
        .map(|l| format!("{marker} {l}\n"))
        .collect::<String>()
}

/// pbrt-v4: `MakeNamedMaterial "name" "string type" [ "hair" ]` with the hair parameters.
pub fn pbrt(name: &str, header: &[String], mapping: &Mapping) -> String {
    let p = &mapping.params.chiang;
    let [r, g, b] = rgb(&p.sigma_a);
    format!(
        "{}MakeNamedMaterial \"{name}\"\n    \"string type\" [ \"hair\" ]\n    \
         \"rgb sigma_a\" [ {} {} {} ]\n    \"float eta\" [ {} ]\n    \
         \"float beta_m\" [ {} ]\n    \"float beta_n\" [ {} ]\n    \"float alpha\" [ {} ]\n",
        commented(header, "#"),
        num(r),
        num(g),
        num(b),
        num(p.eta),
        num(p.beta_m),
        num(p.beta_n),
        num(p.alpha.to_degrees()),
    )
}

/// Blender (bpy, 4.x/5.x): a script that creates the material with a Principled Hair BSDF,
/// model Chiang, parametrisation Absorption Coefficient, wired to the material output. (Random
/// Color is unavailable in that parametrisation; Random Roughness 0 keeps β as fitted.)
pub fn blender(name: &str, header: &[String], mapping: &Mapping) -> String {
    let p = &mapping.params.chiang;
    let [r, g, b] = rgb(&p.sigma_a);
    let inputs = [
        (
            "Absorption Coefficient",
            format!("({}, {}, {})", num(r), num(g), num(b)),
        ),
        ("Roughness", num(p.beta_m)),
        ("Radial Roughness", num(p.beta_n)),
        ("Coat", "0.0".into()),
        ("IOR", num(p.eta)),
        ("Offset", num(p.alpha)),
        ("Random Roughness", "0.0".into()),
    ];
    let inputs: String = inputs
        .iter()
        .map(|(k, v)| format!("    \"{k}\": {v},\n"))
        .collect();
    format!(
        r#"{header}"""Create the material "{name}": Principled Hair BSDF (Chiang) with hairfit's fitted inputs.

Run inside Blender (Scripting tab, or `blender --background --python THIS.py`) or with the bpy module.
"""
import bpy

MATERIAL_NAME = "{name}"
# Input name -> value; Offset in radians (bpy angle sockets are radians).
INPUTS = {{
{inputs}}}


def create_material(name=MATERIAL_NAME):
    mat = bpy.data.materials.get(name) or bpy.data.materials.new(name)
    if mat.node_tree is None:
        mat.use_nodes = True
    tree = mat.node_tree
    tree.nodes.clear()
    hair = tree.nodes.new("ShaderNodeBsdfHairPrincipled")
    hair.model = "CHIANG"
    hair.parametrization = "ABSORPTION"
    for key, value in INPUTS.items():
        hair.inputs[key].default_value = value
    out = tree.nodes.new("ShaderNodeOutputMaterial")
    out.location = (300, 0)
    tree.links.new(hair.outputs["BSDF"], out.inputs["Surface"])
    return mat


material = create_material()
"#,
        header = commented(header, "#"),
    )
}

/// MaterialX 1.39: `chiang_hair_roughness` → `chiang_hair_bsdf` → `surface` → `surfacematerial`.
pub fn materialx(name: &str, header: &[String], mapping: &Mapping) -> String {
    let p = &mapping.params.chiang;
    let [r, g, b] = rgb(&p.sigma_a);
    let gain = num(mapping.params.gain);
    let tint = format!("{gain}, {gain}, {gain}");
    let cuticle = p.alpha / std::f64::consts::PI + 0.5;
    // "--" may not appear inside an XML comment.
    let comment: String = header
        .iter()
        .map(|l| format!("  {}\n", l.replace("--", "- -")))
        .collect();
    format!(
        r#"<?xml version="1.0"?>
<!--
{comment}-->
<materialx version="1.39">
  <chiang_hair_roughness name="{name}_roughness" type="multioutput">
    <input name="longitudinal" type="float" value="{bm}" />
    <input name="azimuthal" type="float" value="{bn}" />
    <input name="scale_TT" type="float" value="0.5" />
    <input name="scale_TRT" type="float" value="2.0" />
  </chiang_hair_roughness>
  <chiang_hair_bsdf name="{name}_bsdf" type="BSDF">
    <input name="tint_R" type="color3" value="{tint}" />
    <input name="tint_TT" type="color3" value="{tint}" />
    <input name="tint_TRT" type="color3" value="{tint}" />
    <input name="ior" type="float" value="{eta}" />
    <input name="roughness_R" type="vector2" nodename="{name}_roughness" output="roughness_R" />
    <input name="roughness_TT" type="vector2" nodename="{name}_roughness" output="roughness_TT" />
    <input name="roughness_TRT" type="vector2" nodename="{name}_roughness" output="roughness_TRT" />
    <input name="cuticle_angle" type="float" value="{cuticle}" />
    <input name="absorption_coefficient" type="vector3" value="{r}, {g}, {b}" />
  </chiang_hair_bsdf>
  <surface name="{name}_surface" type="surfaceshader">
    <input name="bsdf" type="BSDF" nodename="{name}_bsdf" />
  </surface>
  <surfacematerial name="{name}" type="material">
    <input name="surfaceshader" type="surfaceshader" nodename="{name}_surface" />
  </surfacematerial>
</materialx>
"#,
        bm = num(p.beta_m),
        bn = num(p.beta_n),
        eta = num(p.eta),
        cuticle = num(cuticle),
        r = num(r),
        g = num(g),
        b = num(b),
    )
}

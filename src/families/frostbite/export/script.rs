//! The C# editor script `--to unity` writes beside its JSON: a static class with the fitted
//! inputs and two menu items (Tools ▸ hairfit) that set them on a named material or on the
//! selected one with `Material.SetColor`/`SetFloat`, then `HDMaterial.ValidateMaterial` as
//! HDRP asks of scripted changes. The Hair Master Stack's inputs are Shader Graph blocks, not
//! material properties: a script can only reach the Blackboard properties a graph exposes, under
//! the reference names its author chose, so those names sit in one place at the script's top
//! for the user to match (docs/export.md, "Unity").

use super::{quality_text, rgb, UnityMapping, HDRP_CONVENTIONS};
use crate::export::source::SourceFit;
use crate::export::text::num;

/// A C# identifier from a material name: other characters become `_`, a leading digit gets one.
pub fn csharp_identifier(name: &str) -> String {
    let mut id: String = name
        .chars()
        .map(|c| if c.is_ascii_alphanumeric() { c } else { '_' })
        .collect();
    if !id.starts_with(|c: char| c.is_ascii_alphabetic() || c == '_') {
        id.insert(0, '_');
    }
    id
}

/// A C# `float` literal.
fn float(x: f64) -> String {
    format!("{}f", num(x))
}

/// Lines as `//` comments.
fn comment_lines(lines: &[String]) -> String {
    lines.iter().map(|l| format!("// {l}\n")).collect()
}

/// The script: class `class`, the inputs of `m`, a header naming the source and the warnings.
pub fn script(class: &str, source: &SourceFit, m: &UnityMapping, warnings: &[String]) -> String {
    let u = &m.inputs;
    let [r, g, b] = rgb(&u.base_color);
    let mut header = vec![
        format!(
            "hairfit {}: Unity HDRP hair inputs fitted to {}",
            env!("CARGO_PKG_VERSION"),
            source.dir.display()
        ),
        format!("({} model; {})", source.model.name(), source.quality),
        format!("conventions: {HDRP_CONVENTIONS}"),
        format!("mapping: {}", quality_text(m)),
        "Put this file in an Editor folder. Set the light's intensity to the light gain times \
         the source's to match the fit's brightness."
            .to_string(),
    ];
    header.extend(source.held.iter().map(|h| format!("held by the fit: {h}")));
    header.extend(warnings.iter().map(|w| format!("WARNING: {w}")));
    format!(
        r#"{header}#if UNITY_EDITOR
using UnityEditor;
using UnityEngine;
using UnityEngine.Rendering.HighDefinition;

public static class {class}
{{
    // The material the first menu item sets (a path under Assets/).
    const string MaterialPath = "Assets/{class}.mat";

    // Reference names of the Blackboard properties your Hair Shader Graph (Material Type:
    // Physical) exposes and connects to the Base Color, Smoothness, Radial Smoothness and Cuticle
    // Angle blocks. HDRP defines no material property names for these blocks: rename to match.
    const string BaseColorProperty = "_BaseColor";
    const string SmoothnessProperty = "_Smoothness";
    const string RadialSmoothnessProperty = "_RadialSmoothness";
    const string CuticleAngleProperty = "_CuticleAngle";

    // The fitted inputs. Base Color is linear RGB as the shader must see it.
    static readonly Color BaseColorLinear = new Color({r}, {g}, {b}, 1f);
    const float Smoothness = {smoothness};
    const float RadialSmoothness = {radial};
    const float CuticleAngleDegrees = {cuticle};
    // The light intensity factor (S_unity x gain = the fit's S); not a material input.
    public const float LightGain = {gain};

    [MenuItem("Tools/hairfit/Apply {class} to its material")]
    static void ApplyToNamedMaterial()
    {{
        var material = AssetDatabase.LoadAssetAtPath<Material>(MaterialPath);
        if (material == null)
        {{
            Debug.LogError("hairfit: no material at " + MaterialPath + " (edit MaterialPath)");
            return;
        }}
        Apply(material);
    }}

    [MenuItem("Tools/hairfit/Apply {class} to the selected material")]
    static void ApplyToSelection()
    {{
        var material = Selection.activeObject as Material;
        if (material == null)
        {{
            Debug.LogError("hairfit: select a material first");
            return;
        }}
        Apply(material);
    }}

    public static bool Apply(Material material)
    {{
        foreach (var name in new[] {{ BaseColorProperty, SmoothnessProperty, RadialSmoothnessProperty, CuticleAngleProperty }})
        {{
            if (!material.HasProperty(name))
            {{
                Debug.LogError("hairfit: " + material.name + " has no property " + name +
                    ": expose it on the Hair Shader Graph's Blackboard or rename it at the top of this script");
                return false;
            }}
        }}
        Undo.RecordObject(material, "hairfit inputs");
        // SetColor takes a colour as the Inspector shows it (sRGB) and linearises it in a
        // Linear project: hand it the sRGB encoding so that the shader gets the linear value.
        var color = QualitySettings.activeColorSpace == ColorSpace.Linear ? BaseColorLinear.gamma : BaseColorLinear;
        material.SetColor(BaseColorProperty, color);
        material.SetFloat(SmoothnessProperty, Smoothness);
        material.SetFloat(RadialSmoothnessProperty, RadialSmoothness);
        material.SetFloat(CuticleAngleProperty, CuticleAngleDegrees);
        // HDRP does not validate a material changed from a script on its own.
        HDMaterial.ValidateMaterial(material);
        EditorUtility.SetDirty(material);
        AssetDatabase.SaveAssets();
        Debug.Log("hairfit: set the inputs of " + material.name);
        return true;
    }}
}}
#endif
"#,
        header = comment_lines(&header),
        r = float(r),
        g = float(g),
        b = float(b),
        smoothness = float(u.smoothness),
        radial = float(u.radial_smoothness),
        cuticle = float(u.cuticle_angle_deg),
        gain = float(u.gain),
    )
}

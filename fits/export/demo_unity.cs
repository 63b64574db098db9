// hairfit 0.1.0: Unity HDRP hair inputs fitted to fits/demo
// (Marschner model; status converged, verdict good, residual rms 1.0050, reduced chi2 1.012, log space)
// conventions: Unity HDRP Hair Master Stack, Material Type Physical, the non-cinematic raster path of Runtime/Material/Hair/Hair.hlsl as on the Unity-Technologies/Graphics master branch (Unity 6 / HDRP 17 line or later; the release was not pinned); IOR fixed at 1.55
// mapping: fitted over 2340 measured + 1573 sphere directions: rms |d ln S| 0.4663 (max 2.475, measured directions only 0.3683), light gain 1.7349, 60 LM iterations from 2 starts
// Put this file in an Editor folder. Set the light's intensity to the light gain times the source's to match the fit's brightness.
// held by the fit: eta = 1.55 (not varied by default)
// held by the fit: delta_eta_prime = 0.3 (not varied by default)
// held by the fit: delta_h_m = 0.5 (not varied by default)
// WARNING: at these inputs S exceeds 1 at 27 of 11739 direction-channel values (largest 1.443); HDRP clamps S at 1 per channel (saturate), which costs rms |d ln S| 0.4664 (max 2.475) instead of 0.4663
#if UNITY_EDITOR
using UnityEditor;
using UnityEngine;
using UnityEngine.Rendering.HighDefinition;

public static class hairfit_demo
{
    // The material the first menu item sets (a path under Assets/).
    const string MaterialPath = "Assets/hairfit_demo.mat";

    // Reference names of the Blackboard properties your Hair Shader Graph (Material Type:
    // Physical) exposes and connects to the Base Color, Smoothness, Radial Smoothness and Cuticle
    // Angle blocks. HDRP defines no material property names for these blocks: rename to match.
    const string BaseColorProperty = "_BaseColor";
    const string SmoothnessProperty = "_Smoothness";
    const string RadialSmoothnessProperty = "_RadialSmoothness";
    const string CuticleAngleProperty = "_CuticleAngle";

    // The fitted inputs. Base Color is linear RGB as the shader must see it.
    static readonly Color BaseColorLinear = new Color(0.021595f, 0.009306f, 0.002952f, 1f);
    const float Smoothness = 0.865757f;
    const float RadialSmoothness = 0.694785f;
    const float CuticleAngleDegrees = 6.91298f;
    // The light intensity factor (S_unity x gain = the fit's S); not a material input.
    public const float LightGain = 1.734855f;

    [MenuItem("Tools/hairfit/Apply hairfit_demo to its material")]
    static void ApplyToNamedMaterial()
    {
        var material = AssetDatabase.LoadAssetAtPath<Material>(MaterialPath);
        if (material == null)
        {
            Debug.LogError("hairfit: no material at " + MaterialPath + " (edit MaterialPath)");
            return;
        }
        Apply(material);
    }

    [MenuItem("Tools/hairfit/Apply hairfit_demo to the selected material")]
    static void ApplyToSelection()
    {
        var material = Selection.activeObject as Material;
        if (material == null)
        {
            Debug.LogError("hairfit: select a material first");
            return;
        }
        Apply(material);
    }

    public static bool Apply(Material material)
    {
        foreach (var name in new[] { BaseColorProperty, SmoothnessProperty, RadialSmoothnessProperty, CuticleAngleProperty })
        {
            if (!material.HasProperty(name))
            {
                Debug.LogError("hairfit: " + material.name + " has no property " + name +
                    ": expose it on the Hair Shader Graph's Blackboard or rename it at the top of this script");
                return false;
            }
        }
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
    }
}
#endif

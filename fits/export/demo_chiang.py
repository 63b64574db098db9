# hairfit export: Blender Cycles Principled Hair BSDF, model Chiang (tilt on theta_i)
# source fit: fits/demo_chiang (Chiang model, fitted by hairfit 0.1.0)
# written by hairfit 0.1.0
# fit quality: status converged, residual rms 1980.9896, reduced chi2 3929357.580, log space
# mapping: renderer model fitted over 2340 measured + 1573 sphere directions: rms |d ln S| 0.1168 (max 0.846, measured directions only 0.0426; floor 1e-3 of each channel's peak), 13 LM iterations from 1 starts
# measured directions: fits/demo_chiang/curves.csv (2340 samples)
# held by the fit, not fitted from the data: eta = 1.55 (not varied by default), beta_n = 0.05000000000001487 (at a bound of the fit's range)
# colour: channels r, g, b written as R, G, B
# Cycles tilts theta_i (R at -Offset), so Offset was fitted, not negated; Offset is in radians in bpy; colour is given as Absorption Coefficient (per fibre radius), so Blender's melanin constants do not enter; Coat 0 keeps the R roughness at Roughness
"""Create the material "hairfit_demo_chiang": Principled Hair BSDF (Chiang) with hairfit's fitted inputs.

Run inside Blender (Scripting tab, or `blender --background --python THIS.py`) or with the bpy module.
"""
import bpy

MATERIAL_NAME = "hairfit_demo_chiang"
# Input name -> value; Offset in radians (bpy angle sockets are radians).
INPUTS = {
    "Absorption Coefficient": (1.348271, 1.416924, 1.567525),
    "Roughness": 0.250132,
    "Radial Roughness": 0.049219,
    "Coat": 0.0,
    "IOR": 1.548003,
    "Offset": 0.085359,
    "Random Roughness": 0.0,
}


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

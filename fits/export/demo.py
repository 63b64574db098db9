# hairfit export: Blender Cycles Principled Hair BSDF, model Chiang (tilt on theta_i)
# source fit: fits/demo (Marschner model, fitted by hairfit 0.1.0)
# written by hairfit 0.1.0
# fit quality: status converged, verdict good, residual rms 1.0050, reduced chi2 1.012, log space
# mapping: renderer model fitted over 2340 measured + 1573 sphere directions: rms |d ln S| 0.3946 (max 3.460, measured directions only 0.3739; floor 1e-3 of each channel's peak), 69 LM iterations from 2 starts
# measured directions: fits/demo/curves.csv (2340 samples)
# colour: channels r, g, b written as R, G, B
# Cycles tilts theta_i (R at -Offset), so Offset was fitted, not negated; Offset is in radians in bpy; colour is given as Absorption Coefficient (per fibre radius), so Blender's melanin constants do not enter; Coat 0 keeps the R roughness at Roughness
"""Create the material "hairfit_demo": Principled Hair BSDF (Chiang) with hairfit's fitted inputs.

Run inside Blender (Scripting tab, or `blender --background --python THIS.py`) or with the bpy module.
"""
import bpy

MATERIAL_NAME = "hairfit_demo"
# Input name -> value; Offset in radians (bpy angle sockets are radians).
INPUTS = {
    "Absorption Coefficient": (0.145779, 0.310946, 0.594125),
    "Roughness": 0.277372,
    "Radial Roughness": 0.346559,
    "Coat": 0.0,
    "IOR": 1.699358,
    "Offset": 0.116203,
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

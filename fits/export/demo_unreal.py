# WARNING: Scatter 0.0034 is applied to hair cards and meshes only: hair strands ignore it and would miss the fit's S by rms |d ln S| 0.6312 (max 5.111)
# hairfit export: Unreal Engine 5 Hair shading model (Karis 2016), Unreal Engine 5.0-5.3 conventions
# source fit: fits/demo (Marschner model, fitted by hairfit 0.1.0)
# written by hairfit 0.1.0
# fit quality: status converged, verdict good, residual rms 1.0050, reduced chi2 1.012, log space
# mapping: engine inputs fitted over 2340 measured + 1573 sphere directions: rms |d ln S| 0.6291 (max 5.080, measured directions only 0.5787; floor 1e-3 of each channel's peak), 180 LM iterations from 3 starts
# light gain 3.37366760449125: the engine's S times this is the fit's S (set it as the light's intensity, or ignore it when only the look matters)
"""Create the material instance MI_hairfit_demo of a hair material with hairfit's fitted inputs.

Run it in the Unreal Editor with the Python Editor Script Plugin enabled, e.g. in the Output
Log's Python console:  py "path/to/this.py"  (or  py "path/to/this.py" /Game/Path/M_Parent).
The parent material uses the Hair shading model and exposes a Vector Parameter BaseColor and
Scalar Parameters Roughness, Specular, Backlit and Scatter, each wired to the pin of that name
(hairfit's docs/export.md, "Unreal Engine"). An instance of the same name is updated.
"""
import sys

import unreal

PARENT_MATERIAL = "/Game/Hairfit/M_HairfitHair"
PACKAGE_PATH = "/Game/Hairfit"
INSTANCE_NAME = "MI_hairfit_demo"
# Linear RGB, as the Base Color pin takes it.
VECTORS = {"BaseColor": (0.115215036355809, 0.05377591066978483, 0.016829654988400423)}
SCALARS = {
    "Roughness": 0.5328348921972592,
    "Specular": 0.3448859855125226,
    "Backlit": 0.9999989502517731,
    "Scatter": 0.003438651522411545,
}


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

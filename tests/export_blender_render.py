"""Run a `hairfit export --to blender` script with Blender's bpy module, check the material it
creates (model, parametrisation, every input value, the link to the output), then render a small
wisp of hair curves with Cycles on the CPU to a PNG.

usage: python3 tests/export_blender_render.py EXPORTED.py OUT.png
Needs `bpy` (scripts/install-test-tools.sh --with-bpy). Exits non-zero on any mismatch.
"""
import math
import runpy
import sys

import bpy

script, out_png = sys.argv[1], sys.argv[2]

bpy.ops.wm.read_factory_settings(use_empty=True)
ns = runpy.run_path(script)
name, expected = ns["MATERIAL_NAME"], ns["INPUTS"]

mat = bpy.data.materials[name]
nodes = mat.node_tree.nodes
hair = next(n for n in nodes if n.bl_idname == "ShaderNodeBsdfHairPrincipled")
assert hair.model == "CHIANG", hair.model
assert hair.parametrization == "ABSORPTION", hair.parametrization
for key, want in expected.items():
    got = hair.inputs[key].default_value
    got = tuple(got) if hasattr(got, "__len__") else (got,)
    want = tuple(want) if isinstance(want, tuple) else (want,)
    assert len(got) == len(want), (key, got, want)
    for g, w in zip(got, want):
        # Blender stores float32: 1e-6 relative is a few ulps.
        assert abs(g - w) <= 1e-6 * max(1.0, abs(w)), (key, g, w)
    print(f"input {key}: {got}")
output = next(n for n in nodes if n.bl_idname == "ShaderNodeOutputMaterial")
assert output.inputs["Surface"].links[0].from_node == hair

# A wisp of 40 gently curved strands along x (root at -x), 2 mm thick, as a hair Curves object.
curves = bpy.data.hair_curves.new("wisp")
n_strands, n_points = 40, 16
curves.add_curves([n_points] * n_strands)
for s in range(n_strands):
    y = (s - n_strands / 2) * 0.012
    for k in range(n_points):
        t = k / (n_points - 1)
        p = curves.points[s * n_points + k]
        p.position = (-0.6 + 1.2 * t, y + 0.03 * math.sin(3 * t + s), 0.15 * math.sin(math.pi * t))
        p.radius = 0.002
curves.materials.append(mat)
wisp = bpy.data.objects.new("wisp", curves)
scene = bpy.context.scene
scene.collection.objects.link(wisp)

sun = bpy.data.objects.new("sun", bpy.data.lights.new("sun", "SUN"))
sun.data.energy = 6.0
sun.rotation_euler = (math.radians(40), math.radians(-30), 0)
scene.collection.objects.link(sun)
world = bpy.data.worlds.new("world")
world.color = (0.05, 0.05, 0.06)
scene.world = world

cam = bpy.data.objects.new("cam", bpy.data.cameras.new("cam"))
cam.location = (0.0, -1.6, 0.6)
cam.rotation_euler = (math.radians(75), 0, 0)
scene.collection.objects.link(cam)
scene.camera = cam

scene.render.engine = "CYCLES"
scene.cycles.device = "CPU"
scene.cycles.samples = 32
scene.render.resolution_x = 320
scene.render.resolution_y = 200
scene.render.image_settings.file_format = "PNG"
scene.render.filepath = out_png
bpy.ops.render.render(write_still=True)
print(f"rendered {out_png}")

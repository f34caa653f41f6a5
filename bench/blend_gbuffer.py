"""Runs inside Blender for bench/sweep.py: export a .blend's current frame through
the add-on (the same export and G-buffer a render uses) and write the trace's
inputs, the triangles and a render of the frame to an .npz.
  blender -b file.blend --python bench/blend_gbuffer.py -- out.npz [WxH]
The add-on is imported from this checkout; the core from GLINT_CORE_PATH."""
import os
import sys
import tempfile

import bpy
import numpy as np

args = sys.argv[sys.argv.index("--") + 1:]
out = args[0]
root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(root, "addon"))

from glint import gather, measure, native  # noqa: E402

core = native.load()
if core is None:
    sys.exit(f"blend_gbuffer: {native.error()}")
scene = bpy.context.scene
if len(args) > 1:
    w, h = (int(v) for v in args[1].lower().split("x"))
    scene.render.resolution_x, scene.render.resolution_y = w, h
    scene.render.resolution_percentage = 100
try:
    arrays = measure.frame_arrays(bpy.context.evaluated_depsgraph_get(), core, "cpu")
except gather.SkipFrame as exc:
    print(f"blend_gbuffer: SKIP {exc}")
    sys.exit(3)

# The frame as the engine renders it, for the reflection colour: a short render
# (few samples: this is the colour reflections pick up, not a beauty frame).
if scene.render.engine == "CYCLES":
    scene.cycles.samples, scene.cycles.use_denoising = 16, False
elif scene.render.engine == "BLENDER_EEVEE":
    scene.eevee.taa_render_samples = 8
    scene.eevee.use_ssr = False
scene.render.use_compositing = False
scene.render.image_settings.file_format = "OPEN_EXR"
scene.render.image_settings.color_depth = "32"
scene.render.filepath = os.path.join(tempfile.mkdtemp(prefix="glint-color-"), "color.exr")
bpy.ops.render.render(write_still=True)
layers, _ = core.read_exr(scene.render.filepath)
arrays["color"] = layers.get("") if "" in layers else next(iter(layers.values()))
np.savez(out, **arrays)
print(f"blend_gbuffer: wrote {out}")

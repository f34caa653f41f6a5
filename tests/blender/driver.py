"""Runs inside Blender for tests/blender: apply a JSON config, dump what the
tests check. Usage: blender -b file.blend --python driver.py [-f N | -a] -- config.json

config keys: size [w, h], percentage, out (folder), eevee_samples, cycles_samples,
engine, glint {setting: value} (applied in order, 'enabled' last), python (code
run after the settings), dump (bool: write dump_<frame>.npz at render_post),
mirror_objects [names] (their vertices mirrored in z = 0, through world_to_camera_view),
exr ('OPEN_EXR' | 'OPEN_EXR_MULTILAYER' | 'PNG').
"""
import json
import os
import sys

import bpy
import numpy as np
from bpy_extras.object_utils import world_to_camera_view

cfg = json.load(open(sys.argv[sys.argv.index("--") + 1]))
scene = bpy.context.scene
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scene_config  # noqa: E402  (beside this file)

scene_config.apply(scene, cfg)
r = scene.render
if cfg.get("exr") == "OPEN_EXR_MULTILAYER":
    from glint.host import nodes as host_nodes  # 5.0+ asks for the media type first
    host_nodes.set_multilayer_exr(r.image_settings)
else:
    r.image_settings.file_format = cfg.get("exr", "OPEN_EXR")
if r.image_settings.file_format.startswith("OPEN_EXR"):
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
r.filepath = os.path.join(cfg["out"], "frame_")
exec(cfg.get("python", ""))


def _dump(scene, *args):
    import glint.state as st  # the add-on under test
    data = {}
    with st.STATE.lock:
        arrays = dict(st.STATE.arrays)
    if arrays.get("frame") == scene.frame_current:
        data.update({k: np.asarray(v) for k, v in arrays.items()})
    last = st.STATE.last
    if last is not None:
        data["status"] = np.array(last.status)
        data["message"] = np.array(last.message)
        data["backend"] = np.array(last.backend)
        data["report_frame"] = np.array(last.frame)
        data["timings"] = np.array(json.dumps(last.timings_ms))
    cam = scene.camera
    data["frame"] = np.array(scene.frame_current)
    # Independent of the add-on: Blender's own world -> camera-frame mapping of
    # points the tests name (the mirror images of object centres, etc.).
    from mathutils import Vector
    for name, points in cfg.get("wtcv_points", {}).items():
        data["wtcv_" + name] = np.array([tuple(world_to_camera_view(scene, cam, Vector(p))) for p in points])
    for name in cfg.get("mirror_objects", []):
        ob = bpy.data.objects[name]
        pts = [ob.matrix_world @ v.co for v in ob.data.vertices]
        data["mirror_" + name] = np.array([tuple(world_to_camera_view(scene, cam, Vector((q.x, q.y, -q.z))))
                                           for q in pts])
        data["real_" + name] = np.array([tuple(world_to_camera_view(scene, cam, q)) for q in pts])
    np.savez(os.path.join(cfg["out"], f"dump_{scene.frame_current:04d}.npz"), **data)


if cfg.get("dump"):
    bpy.app.handlers.render_post.append(_dump)

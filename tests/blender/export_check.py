"""Runs inside Blender for test_export.py: export the scene with the add-on's own
gather functions and write, beside it, Blender's independent numbers for the same
vertices (world positions, world_to_camera_view). Usage:
  blender -b file.blend --python export_check.py -- out.npz '<python to run first>'
"""
import sys

import bpy
import numpy as np
from bpy_extras.object_utils import world_to_camera_view

args = sys.argv[sys.argv.index("--") + 1:]
out = args[0]
exec(args[1] if len(args) > 1 else "")

import glint.gather as gather  # noqa: E402  (the add-on under test)

scene = bpy.context.scene
depsgraph = bpy.context.evaluated_depsgraph_get()
exp = gather.export_scene(depsgraph)
world, wtcv, owner = [], [], []
for ob in scene.objects:
    if ob.type != "MESH" or ob.hide_render:
        continue
    ev = ob.evaluated_get(depsgraph)
    me = ev.to_mesh()
    for v in me.vertices:
        p = ob.matrix_world @ v.co
        world.append(tuple(p))
        wtcv.append(tuple(world_to_camera_view(scene, scene.camera, p)))
        owner.append(ob.name)
    ev.to_mesh_clear()
np.savez(out, positions=exp.triangles.positions, projection=exp.camera.projection, view=exp.camera.view,
         width=exp.camera.width, height=exp.camera.height, kind=exp.camera.kind, world=np.array(world),
         wtcv=np.array(wtcv), owner=np.array(owner), culled=exp.culled, objects=exp.objects, materials=exp.materials,
         material_index=exp.triangles.material_index)

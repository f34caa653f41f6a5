"""The exported camera and geometry against Blender's own, independent numbers:
``world_to_camera_view`` (camera frame from ``Camera.view_frame``, not from
``calc_matrix_camera``) and Cycles' depth pass."""
import json
import os

import numpy as np
import pytest

from glint_blender_helpers import HERE, load_dump, read_exr

pytestmark = pytest.mark.blender

CHECK = os.path.join(HERE, "export_check.py")

VARIANTS = {
    "perspective": ("mirror_floor", ""),
    "orthographic": ("ortho_camera", ""),
    "shift_fit_aspect": ("mirror_floor", """
import bpy
s = bpy.context.scene
c = s.camera.data
c.shift_x, c.shift_y = 0.15, -0.1
c.sensor_fit = 'VERTICAL'
c.lens = 28
s.render.resolution_x, s.render.resolution_y = 200, 100
s.render.pixel_aspect_x = 2.0
s.render.resolution_percentage = 50
"""),
    "ortho_shift_fit": ("ortho_camera", """
import bpy
s = bpy.context.scene
c = s.camera.data
c.shift_x = -0.2
c.sensor_fit = 'VERTICAL'
s.render.resolution_x, s.render.resolution_y = 90, 160
s.render.pixel_aspect_y = 1.5
"""),
}


def run_check(blender, samples, tmp_path, name, scene, code):
    """Run export_check.py on sample ``scene`` after ``code``; its numbers by name."""
    out = str(tmp_path / f"{name}.npz")
    blender.run([samples[scene], "--addons", "glint", "--python", CHECK, "--", out, code])
    return dict(np.load(out))


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_projection_and_positions_match_world_to_camera_view(blender, samples, tmp_path, variant):
    d = run_check(blender, samples, tmp_path, variant, *VARIANTS[variant])
    P, V = d["projection"], d["view"]
    corners = d["positions"].reshape(-1, 3).astype(np.float64)
    # Every exported corner is a world vertex of the scene, carried by the view matrix.
    world_of_corner = (corners - V[:3, 3]) @ np.linalg.inv(V[:3, :3]).T
    dist = np.linalg.norm(world_of_corner[:, None, :] - d["world"][None, :, :], axis=-1)
    nearest = dist.argmin(axis=1)
    assert dist.min(axis=1).max() < 1e-4
    # Objects with a vertex in the frame must be exported whole (culling only
    # drops objects wholly outside the view).
    w = d["wtcv"]
    in_frame = (w[:, 0] >= 0) & (w[:, 0] <= 1) & (w[:, 1] >= 0) & (w[:, 1] <= 1) & (w[:, 2] > 0)
    visible_objects = set(d["owner"][in_frame])
    must = np.isin(d["owner"], list(visible_objects))
    assert len(visible_objects) >= 2
    missing = set(np.flatnonzero(must)) - set(np.unique(nearest))
    assert not missing, f"vertices of {sorted(set(d['owner'][list(missing)]))} were not exported"
    # Projected by the exported matrix, each corner lands where Blender's
    # world_to_camera_view puts the same vertex, at the same depth.
    clip = np.c_[corners, np.ones(len(corners))] @ P.T
    uv = clip[:, :2] / clip[:, 3:4] * 0.5 + 0.5
    want = d["wtcv"][nearest]
    assert np.abs(uv - want[:, :2]).max() < 1e-5
    assert np.abs(-corners[:, 2] - want[:, 2]).max() < 1e-4
    assert str(d["kind"]) == ("orthographic" if variant.startswith("ortho") else "perspective")
    if variant == "shift_fit_aspect":
        assert (int(d["width"]), int(d["height"])) == (100, 50)


def test_hidden_and_out_of_view_objects_are_not_exported(blender, samples, tmp_path):
    code = """
import bpy
s = bpy.context.scene
me = bpy.data.meshes.new('extra')
me.from_pydata([(0, 0, 0), (1, 0, 0), (0, 1, 0)], [], [(0, 1, 2)])
mat = bpy.data.materials['Mirror']
me.materials.append(mat)
behind = bpy.data.objects.new('Behind', me); behind.location = (0, -20, 2); s.collection.objects.link(behind)
hidden = bpy.data.objects.new('Hidden', me); hidden.location = (0, 0, 3); hidden.hide_render = True
s.collection.objects.link(hidden)
bpy.data.objects['Green Cube'].hide_render = True
"""
    d = run_check(blender, samples, tmp_path, "extra", "mirror_floor", code)
    assert int(d["culled"]) == 1  # the triangle behind the camera
    # floor 2 + sphere + cone triangles, no cube (hidden), no 'Hidden', no 'Behind'
    corners = d["positions"].reshape(-1, 3)
    V = d["view"]
    world = (corners - V[:3, 3]) @ np.linalg.inv(V[:3, :3]).T
    assert not np.any(np.all(np.isclose(world, (0, 0, 3)), axis=1))
    assert not np.any(np.isclose(world[:, 1], -20))
    cube_centre = np.array([-2.3, 1.0, 0.55])
    assert np.linalg.norm(world - cube_centre, axis=1).min() > 0.5


def test_gbuffer_depth_matches_cycles_z_pass(blender, samples, session_dir):
    out = os.path.join(session_dir, "cycles_z")
    code = """
import bpy
s = bpy.context.scene
s.view_layers[0].use_pass_z = True
s.cycles.filter_width = 0.01
s.cycles.pixel_filter_type = 'BOX'
"""
    # Glint leaves Cycles frames alone (it has true reflections), so its G-buffer
    # comes from a Workbench render of the same frame, camera and objects.
    blender.render(samples["mirror_floor"], out, {"engine": "CYCLES", "cycles_samples": 1,
                                                  "exr": "OPEN_EXR_MULTILAYER", "python": code,
                                                  "glint": {"enabled": False}})
    blender.render(samples["mirror_floor"], out + "_gbuffer", {"engine": "BLENDER_WORKBENCH", "dump": True,
                                                               "glint": {"backend": "CPU"}})
    layers = read_exr(os.path.join(out, "frame_0001.exr"), layer=None)
    depth_layer = next(k for k in layers if k.endswith("Depth"))
    z = layers[depth_layer]
    depth = z[..., 0] if np.any(z[..., 0] != 0) else z[..., 3]
    dump = load_dump(out + "_gbuffer")
    pos = dump["position"]
    seen = pos[..., 3] > 0.5
    sky = depth > 1e5
    assert np.array_equal(seen, ~sky) or (seen != ~sky).sum() < 0.01 * seen.size
    both = seen & ~sky
    err = np.abs(-pos[..., 2] - depth)[both]
    rel = err / depth[both]
    # Silhouette pixels can see different surfaces at the centre and at the
    # sample position; the interior agrees to float precision.
    print(f"\nG-buffer depth vs Cycles Z: {both.sum()} pixels, median rel {np.median(rel):.2e}, "
          f"98th pct {np.percentile(rel, 98):.2e}, depth layer {depth_layer}")
    assert np.median(rel) < 1e-5, np.median(rel)
    assert np.percentile(rel, 98) < 1e-3, np.percentile(rel, 98)


INSTANCES = r"""
import bpy
s = bpy.context.scene
for ob in list(s.objects):
    if ob.type == 'MESH':
        bpy.data.objects.remove(ob)
mirror = bpy.data.materials['Mirror']
def cube(name, size):
    h = size / 2
    me = bpy.data.meshes.new(name)
    v = [(x * h, y * h, z * h) for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)]
    f = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    me.from_pydata(v, [], f)
    me.materials.append(mirror)
    return bpy.data.objects.new(name, me)
# a collection (not in the scene) instanced twice: 2 x 12 triangles
src = bpy.data.collections.new('Src')
src.objects.link(cube('Src Cube', 0.4))
for i, x in enumerate((-1.0, 1.0)):
    e = bpy.data.objects.new(f'Instance {i}', None)
    e.instance_type = 'COLLECTION'
    e.instance_collection = src
    e.location = (x, 0.0, 0.5)
    s.collection.objects.link(e)
# hair particles instancing a cube on a 2-triangle emitter: 2 + 5 x 12
me = bpy.data.meshes.new('Emitter')
me.from_pydata([(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)], [], [(0, 1, 2, 3)])
me.materials.append(mirror)
emitter = bpy.data.objects.new('Emitter', me)
s.collection.objects.link(emitter)
ps = emitter.modifiers.new('Hair', 'PARTICLE_SYSTEM').particle_system.settings
ps.type = 'HAIR'
ps.count = 5
ps.render_type = 'OBJECT'
ps.instance_object = src.objects['Src Cube']
ps.particle_size = 1.0
# a subdivided cube: render levels 2 -> 6 x 16 quads = 192 triangles (viewport level 1 would give 96)
sub = cube('Subdivided', 0.6)
sub.location = (0.0, 1.0, 0.8)
mod = sub.modifiers.new('Subsurf', 'SUBSURF')
mod.levels, mod.render_levels = 1, 2
s.collection.objects.link(sub)
# hidden from render, and far behind the camera: neither is sent
hidden = cube('Hidden', 0.5); hidden.hide_render = True; s.collection.objects.link(hidden)
behind = cube('Behind', 0.5); behind.location = (0, -30, 1); s.collection.objects.link(behind)
"""


def test_instances_particles_and_render_modifiers_are_exported(blender, samples, tmp_path):
    out = str(tmp_path / "instances")
    log = blender.render(samples["mirror_floor"], out, {"engine": "BLENDER_WORKBENCH", "python": INSTANCES,
                                                        "glint": {"backend": "CPU"}})
    line = next(l for l in log.splitlines() if l.startswith("Glint: frame 1:"))
    assert "reflections composited" in line, line
    # objects: 2 collection instances + emitter + 5 particles + the subdivided cube
    assert f"{2 * 12 + 2 + 5 * 12 + 192} triangles from 9 objects, 1 culled" in line, line


MATERIALS = r"""
import bpy, json
import glint.gather as gather
out = {}
def principled(name, **inputs):
    m = bpy.data.materials.new(name); m.use_nodes = True
    p = m.node_tree.nodes['Principled BSDF']
    for k, v in inputs.items():
        if k == 'Specular' and k not in p.inputs:  # 4.0+: the same F0 through Specular IOR Level
            k = 'Specular IOR Level'
        p.inputs[k].default_value = v
    return m
out['default'] = principled('Default')
out['gold'] = principled('Gold', **{'Base Color': (1.0, 0.77, 0.34, 1.0), 'Metallic': 1.0, 'Roughness': 0.0})
out['matte'] = principled('Matte', Specular=0.0)
h = principled('Hard', Roughness=1.0); h['hardness'] = 511; out['hardness'] = h
d = bpy.data.materials.new('Diffuse'); d.use_nodes = True
nt = d.node_tree; nt.nodes.remove(nt.nodes['Principled BSDF'])
df = nt.nodes.new('ShaderNodeBsdfDiffuse')
gl = nt.nodes.new('ShaderNodeBsdfGlossy')
mix = nt.nodes.new('ShaderNodeMixShader')
gl.inputs['Roughness'].default_value = 0.0
gl.inputs['Color'].default_value = (1.0, 1.0, 1.0, 1.0)
mix.inputs['Fac'].default_value = 0.25
nt.links.new(df.outputs[0], mix.inputs[1]); nt.links.new(gl.outputs[0], mix.inputs[2])
nt.links.new(mix.outputs[0], nt.nodes['Material Output'].inputs['Surface'])
out['mix'] = d
from glint.host import data as host_data
v = bpy.data.materials.new('Viewport'); v.metallic = 1.0; v.roughness = 0.0
if not host_data._nodes_always_on(v):  # 5.0+: every material is node-based, there is no viewport-only one
    v.use_nodes = False
    v.diffuse_color = (0.2, 0.4, 0.6, 1.0); out['viewport'] = v
res = {k: list(gather.material_info(m)[0].row()) for k, m in out.items()}
print('MATS' + json.dumps(res))
"""


def test_material_mapping_inside_blender(blender):
    log = blender.run(["--addons", "glint", "--python-expr", MATERIALS])
    res = json.loads(next(l[4:] for l in log.splitlines() if l.startswith("MATS")))
    approx = lambda row: pytest.approx(row, abs=1e-6)  # noqa: E731
    assert res["default"] == approx([0.04, 0.04, 0.04, 7.5])  # Specular 0.5, Roughness 0.5 -> hardness 30
    assert res["gold"] == approx([1.0, 0.77, 0.34, 127.75])
    assert res["matte"][:3] == [0.0, 0.0, 0.0]
    assert res["hardness"] == approx([0.04, 0.04, 0.04, 127.75])
    assert res["mix"] == approx([0.25, 0.25, 0.25, 127.75])  # a quarter of a white mirror
    if "viewport" in res:  # Blenders that still have materials without nodes
        assert res["viewport"] == approx([0.2, 0.4, 0.6, 127.75])

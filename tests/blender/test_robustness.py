"""What must not break a render: a panoramic camera, a core error, an OpenGL
context that cannot be made; and the compositor set-up coming and going cleanly."""
import json
import os

import numpy as np
import pytest

from glint_blender_helpers import PANELS, load_dump, read_exr

pytestmark = pytest.mark.blender


def test_panoramic_camera_is_reported_and_skipped(blender, samples, tmp_path):
    out = str(tmp_path / "pano")
    code = "import bpy; c = bpy.context.scene.camera.data; c.type = 'PANO'; c.cycles.panorama_type = 'EQUIRECTANGULAR'"
    log = blender.render(samples["mirror_floor"], out, {"engine": "BLENDER_WORKBENCH", "python": code})
    assert "is panoramic" in log and "Glint: frame 1: nothing to reflect" in log
    assert os.path.isfile(os.path.join(out, "frame_0001.exr"))


# One frame of Glint run directly, no render: what Glint reports for a frame of
# the loaded sample (Workbench's settings). The tests below need a Blender that
# cannot make an EGL context, or frames Blender's own renderer cannot allocate:
# with no render they do not depend on the engine (Cycles frames Glint leaves alone).
FRAME_RUN = """
import bpy, json
from glint import frame
s = bpy.context.scene
s.render.engine = 'BLENDER_WORKBENCH'
{setup}
r = frame.run(bpy.context.evaluated_depsgraph_get(), s)
print('FRAME ' + json.dumps(dict(status=r.status, message=r.message, backend=r.backend)))
"""


def run_frame(blender, blend, setup):
    log = blender.run([blend, "--addons", "glint", "--python-expr", FRAME_RUN.format(setup=setup)])
    return json.loads(next(line[6:] for line in log.splitlines() if line.startswith("FRAME ")))


def test_core_error_is_reported(blender, samples):
    # Wider than the core accepts (32768 pixels a side): rasterize raises ValueError.
    res = run_frame(blender, samples["mirror_floor"], "s.render.resolution_x, s.render.resolution_y = 33000, 2\n"
                    "s.render.resolution_percentage = 100\ns.glint.backend = 'CPU'")
    assert res["status"] == "error" and res["message"].startswith("ValueError: width"), res


def test_a_frame_over_the_memory_limit_renders_without_reflections(blender, samples, tmp_path):
    out = str(tmp_path / "memory")
    saved = blender.env
    # 0.2 MiB: the sample's triangles alone need more, so the core refuses before
    # allocating at every size the add-on tries (test_frame_faults.py: the sizes).
    blender.env = {**saved, "GLINT_MEMORY_LIMIT_MB": "0.2"}
    try:
        log = blender.render(samples["mirror_floor"], out, {"engine": "BLENDER_WORKBENCH",
                                                            "glint": {"backend": "CPU"}})
    finally:
        blender.env = saved
    assert "rendered WITHOUT reflections: over Glint's memory limit" in log, log[-2000:]
    assert "GLINT_MEMORY_LIMIT_MB" in log
    assert os.path.isfile(os.path.join(out, "frame_0001.exr"))


@pytest.fixture()
def no_egl(blender):
    """An environment where no EGL driver can be found (glvnd finds no vendor)."""
    env = dict(blender.env)
    env["__EGL_VENDOR_LIBRARY_FILENAMES"] = "/nonexistent/egl_vendor.json"
    env["__EGL_VENDOR_LIBRARY_DIRS"] = "/nonexistent"
    saved = blender.env
    blender.env = env
    yield blender
    blender.env = saved


def test_gl_that_cannot_run_is_reported(no_egl, samples):
    res = run_frame(no_egl, samples["mirror_floor"], "s.glint.backend = 'GL'")
    assert res["status"] == "error" and res["message"].startswith("backend unavailable"), res


def test_auto_falls_back_to_the_cpu(no_egl, samples):
    # 1920x1080 is past Auto's CPU-only sizes (docs/addon.md): it asks for GL first.
    res = run_frame(no_egl, samples["mirror_floor"], "s.glint.backend = 'AUTO'\n"
                    "s.render.resolution_x, s.render.resolution_y = 1920, 1080")
    assert res["status"] == "ok" and res["backend"] == "cpu", res


SETUP_CHECK = r"""
import bpy, json
from glint.logic import compositing as cg
from glint.host import nodes as hn  # this Blender's compositor (its tree, node and socket names)
s = bpy.context.scene
res = {}
def links(tree):
    return sorted(f"{l.from_node.name}:{l.from_socket.name}->{l.to_node.name}:{l.to_socket.name}" for l in tree.links)
def nodes_on():
    return not hn.tree_switch_is_off(s)
# A scene without compositing nodes: Glint switches them on and off again.
if nodes_on(): hn.release_tree(s)
s.glint.enabled = True
res['plain_on'] = {'use_nodes': nodes_on(), 'links': links(hn.scene_tree(s))}
s.glint.enabled = False
res['plain_off'] = {'use_nodes': nodes_on(), 'group': cg.GROUP_NAME in bpy.data.node_groups,
                    'images': [n for n in cg.ALL_IMAGES if n in bpy.data.images]}
# A user tree: Render Layers -> Glare -> Composite, and a Viewer on the render.
t = hn.scene_tree(s, create=True)
rl = t.nodes['Render Layers']; comp_in = hn.frame_outputs(t)[0]
glare = t.nodes.new('CompositorNodeGlare'); glare.name = 'User Glare'
viewer = t.nodes.new('CompositorNodeViewer'); viewer.name = 'User Viewer'
for l in list(t.links): t.links.remove(l)
t.links.new(rl.outputs['Image'], glare.inputs['Image'])
t.links.new(glare.outputs['Image'], comp_in)
t.links.new(rl.outputs['Image'], viewer.inputs['Image'])
# The names this Blender gives what the assertions mention.
res['names'] = {'frame': f"{comp_in.node.name}:{comp_in.name}", 'frame_node': comp_in.node.name}
res['user_before'] = links(t)
s.glint.enabled = True
s.glint.write_layers_exr = True
res['user_on'] = links(t)
res['exr_node'] = cg.EXR_NODE_NAME in t.nodes
s.glint.debug_view = 'REFLECTION'
g = bpy.data.node_groups[cg.GROUP_NAME]
res['passes'] = [s.view_layers[0].use_pass_glossy_direct, s.view_layers[0].use_pass_glossy_color]
res['switch'] = [hn.switch_is_on(g.nodes['show_reflection']), hn.switch_is_on(g.nodes['show_debug'])]
res['names']['rgb'] = t.nodes[cg.WORLD_COLOUR_NODE].outputs[0].name
# The second bounce: Auto runs it from two sharp reflectors on (the factory cube,
# made one here: its default material's Roughness 0.5 does not count)
cube_mat = s.objects['Cube'].material_slots[0].material
cube_mat.node_tree.nodes['Principled BSDF'].inputs['Roughness'].default_value = 0.1
from glint import compositor as glint_compositor
bounce, muted = [], []
def record():  # the bounce's Switch, and the mute of what only it reads
    bounce.append(hn.switch_is_on(g.nodes['use_bounce'])); muted.append(g.nodes['bounce_map_uv'].mute)
record()
plane = bpy.data.objects.new('Second Reflector', bpy.data.meshes.new('Second Reflector'))
plane.data.materials.append(s.objects['Cube'].material_slots[0].material)
s.collection.objects.link(plane)
glint_compositor.ensure(s)
record()
s.glint.second_bounce = 'OFF'
record()
plane.hide_render = True
s.glint.second_bounce = 'ON'
record()
s.glint.second_bounce = 'AUTO'
record()
bpy.data.objects.remove(plane)
res['bounce'] = bounce
res['bounce_muted'] = muted
s.glint.preset = 'HIGH'
res['preset'] = [s.glint.march, s.glint.resolution, s.glint.steps]
from glint import native as glint_native
res['core_high'] = glint_native.load().presets()['high']
s.glint.steps = 7
res['preset_after_edit'] = s.glint.preset
s.glint.enabled = True  # again: nothing may be duplicated
res['nodes_on'] = sorted(n.name for n in t.nodes)
# A world that is not one colour: S from Eevee's passes, which Glint turns on
w = s.world.node_tree
w.links.new(w.nodes.new('ShaderNodeTexGradient').outputs['Color'], w.nodes['Background'].inputs['Color'])
s.glint.enabled = True
# The passes' outputs are listed once the passes are on (4.x lists no others).
res['names'].update(dir=hn.pass_output(rl, 'glossy_direct').name, col=hn.pass_output(rl, 'glossy_color').name)
res['textured_on'] = {'links': links(t), 'nodes': sorted(n.name for n in t.nodes),
                      'passes': [s.view_layers[0].use_pass_glossy_direct, s.view_layers[0].use_pass_glossy_color]}
s.glint.enabled = False
res['user_off'] = links(t)
res['nodes_off'] = sorted(n.name for n in t.nodes)
res['use_nodes_off'] = nodes_on()
res['group_off'] = cg.GROUP_NAME in bpy.data.node_groups
res['passes_off'] = [s.view_layers[0].use_pass_glossy_direct, s.view_layers[0].use_pass_glossy_color]
print('SETUP' + json.dumps(res))
"""


def test_compositor_setup_keeps_user_nodes_and_is_removed_cleanly(blender):
    log = blender.run(["--addons", "glint", "--python-expr", SETUP_CHECK])
    res = json.loads(next(line[5:] for line in log.splitlines() if line.startswith("SETUP")))
    names = res["names"]  # Composite:Image, GlossDir... on 3.4 and 4.x; Group Output:Image, Glossy Direct... on 5.x
    frame, frame_node = names["frame"], names["frame_node"]
    assert res["plain_on"]["use_nodes"] is True
    # The factory scene's world is one colour: S = that colour (an RGB node) x the weight image
    world = [f"Glint World Colour:{names['rgb']}->Glint:Specular Light",
             "Glint World Weight:Image->Glint:Specular Color"]
    passes = sorted([f"Render Layers:{names['col']}->Glint:Specular Color",
                     f"Render Layers:{names['dir']}->Glint:Specular Light"])
    assert res["plain_on"]["links"] == sorted([f"Glint:Image->{frame}", "Render Layers:Image->Glint:Image"]
                                              + world)
    assert res["plain_off"] == {"use_nodes": False, "group": False, "images": []}
    assert res["user_on"] == sorted(["Render Layers:Image->Glint:Image", "Glint:Image->User Glare:Image",
                                     f"User Glare:Image->{frame}", "Glint:Image->User Viewer:Image"] +
                                    world + ["Glint:Engine Specular->Glint EXR:EngineSpecular"] +
                                    [f"Glint:{name}->Glint EXR:{name}" for name in
                                     ("Image", "Base", "Reflection", "Position", "Normal", "Specular", "UV",
                                      "Visibility")])
    assert res["exr_node"] is True
    # Eevee's Specular Light and Color passes: not needed under a uniform world; on
    # under a textured one (in place of the world nodes), off again after
    assert res["passes"] == [False, False]
    assert res["textured_on"]["passes"] == [True, True] and res["passes_off"] == [False, False]
    assert sorted(set(res["textured_on"]["links"]) - set(res["user_on"])) == passes
    assert sorted(set(res["user_on"]) - set(res["textured_on"]["links"])) == world
    assert res["textured_on"]["nodes"] == sorted([frame_node, "Render Layers", "User Glare", "User Viewer",
                                                  "Glint", "Glint EXR"])
    assert res["switch"] == [True, False]
    # Auto with one reflector, Auto with two, Off, On with the second hidden, Auto so
    assert res["bounce"] == [False, True, False, True, False]
    # What only the bounce reads is muted while it is off: 5.x computes a Switch's dropped side.
    assert res["bounce_muted"] == [not on for on in res["bounce"]]
    high = res["core_high"]  # the add-on's presets are the core's
    assert res["preset"] == [high["march"].upper(), pytest.approx(high["resolution"]), high["steps"]]
    assert res["preset_after_edit"] == "CUSTOM"
    assert res["nodes_on"] == sorted([frame_node, "Render Layers", "User Glare", "User Viewer", "Glint",
                                      "Glint EXR", "Glint World Colour", "Glint World Weight"])
    assert res["user_off"] == res["user_before"]
    assert res["nodes_off"] == sorted([frame_node, "Render Layers", "User Glare", "User Viewer"])
    assert res["use_nodes_off"] is True and res["group_off"] is False


NAME_CLASH = r"""
import bpy, json
from glint import compositor
from glint.logic import compositing as cg
# A user's own shader node group that happens to be called "Glint" (node groups of
# every kind share one name space).
user = bpy.data.node_groups.new(cg.GROUP_NAME, 'ShaderNodeTree')
user.use_fake_user = True
user.nodes.new('ShaderNodeMath')
s = bpy.context.scene
s.glint.enabled = True
res = {}
def compositor_groups():  # the scene's own tree is a compositor node group too on 5.x: not counted
    scene_tree = getattr(s, 'compositing_node_group', None)
    return sorted(g.name for g in bpy.data.node_groups if g.bl_idname == 'CompositorNodeTree' and g != scene_tree)
res['on'] = compositor_groups()
try:  # what render_init does on F12's render thread: nothing may be missing now
    compositor.ensure(s, allow_changes=False)
    res['render_thread'] = 'ok'
except compositor.SetupIncomplete as exc:
    res['render_thread'] = str(exc)
compositor.ensure(s)
res['again'] = compositor_groups()
s.glint.enabled = False
res['off'] = compositor_groups()
res['user_group'] = [user.name, user.bl_idname, len(user.nodes)]
print('CLASH' + json.dumps(res))
"""


def test_a_users_node_group_named_glint_is_left_alone(blender):
    log = blender.run(["--addons", "glint", "--python-expr", NAME_CLASH])
    res = json.loads(next(line[5:] for line in log.splitlines() if line.startswith("CLASH")))
    assert res["render_thread"] == "ok"
    assert len(res["on"]) == 1 and res["again"] == res["on"]  # one Glint group, not one more per ensure
    assert res["off"] == []
    assert res["user_group"] == ["Glint", "ShaderNodeTree", 1]


@pytest.mark.parametrize("view", ["VISIBILITY", "REFLECTION"])
def test_debug_view_renders_the_layer(blender, samples, mirror_off, tmp_path, view):
    out = str(tmp_path / view)
    blender.render(samples["mirror_floor"], out, {"dump": True, "glint": {"debug_view": view, "backend": "CPU",
                                                                          "write_layers_exr": True}})
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    dump = load_dump(out)
    if view == "VISIBILITY":
        assert np.allclose(img[..., 0], dump["uv"][..., 2]) and np.allclose(img[..., 1], dump["uv"][..., 2])
    else:
        layers = read_exr(os.path.join(out, "frame_glint_0001.exr"), layer=None)
        assert np.array_equal(img, layers["Reflection"])
        hit = dump["uv"][..., 2] > 0
        assert img[hit, 3].mean() > 0.3 and np.all(img[~hit & (img[..., 3] == 0), :3] == 0)


def test_cancelling_the_export_renders_the_frame_without_reflections(blender, samples, mirror_off, tmp_path):
    out = str(tmp_path / "cancel")
    # What GLINT_OT_cancel does, at the moment the render evaluates the frame.
    code = """
import bpy, glint.state as st
def stop(scene, *args):
    st.STATE.cancel.set()
bpy.app.handlers.frame_change_pre.append(stop)
"""
    log = blender.render(samples["mirror_floor"], out, {"python": code})
    assert "Glint: frame 1: rendered WITHOUT reflections: Glint export cancelled at" in log
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    base = read_exr(os.path.join(mirror_off[0], "frame_0001.exr"))
    assert np.abs(img - base).max() <= 1e-6


def test_add_on_disables_and_enables_again(blender):
    log = blender.run(["--python-expr", """
import addon_utils, bpy
for _ in range(2):
    addon_utils.enable('glint', default_set=True, handle_error=None)
    assert hasattr(bpy.types.Scene, 'glint') and hasattr(bpy.types, 'GLINT_PT_render')
    assert any(h.__name__ == 'on_frame_change_post' for h in bpy.app.handlers.frame_change_post)
    bpy.context.scene.glint.enabled = True
    bpy.context.scene.glint.enabled = False
    addon_utils.disable('glint', default_set=True, handle_error=None)
    assert not hasattr(bpy.types.Scene, 'glint')
    assert not any(h.__name__.startswith('on_') and h.__module__.startswith('glint')
                   for h in bpy.app.handlers.frame_change_post)
print('CYCLE OK')
"""])
    assert "CYCLE OK" in log and "Traceback" not in log, log[-2000:]


def test_panels_draw_every_setting(blender):
    log = blender.run(["--addons", "glint", "--python-expr", PANELS])
    line = next(l for l in log.splitlines() if l.startswith("PANELS"))
    for name in ("enabled", "preset", "max_distance", "resolution", "steps", "thickness", "march",
                 "backend", "view_layer", "debug_view", "write_layers_exr", "glint.compute_layers"):
        assert f"'{name}'" in line, (name, line)

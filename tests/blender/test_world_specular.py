"""The specular a found reflection replaces (S): under a uniform world it is the
world's colour x the split-sum weight and Eevee's Specular passes stay off (they
double Eevee's render time); a world that is not uniform keeps the passes."""
import os

import numpy as np
import pytest

from glint_blender_helpers import core, load_dump, read_exr

pytestmark = pytest.mark.blender

# The mirror_floor sample's world: a Background node, colour (0.05, 0.06, 0.08), strength 1.
WORLD = np.array([0.05, 0.06, 0.08])
STRENGTH = 1.5

# Print the pass flags as the render left them; a Glint that owned the passes
# (an earlier version, or an earlier render under a sky) turned them on.
REPORT = """
import bpy
vl = bpy.context.scene.view_layers[0]
def _flags(scene, *a):
    print('PASSES', vl.use_pass_glossy_direct, vl.use_pass_glossy_color, flush=True)
bpy.app.handlers.render_post.append(_flags)
"""
OWNED = """
vl.use_pass_glossy_direct = vl.use_pass_glossy_color = True
bpy.context.scene.glint.owns_specular_passes = True
"""
STRONGER = f"""
bpy.context.scene.world.node_tree.nodes['Background'].inputs['Strength'].default_value = {STRENGTH}
"""
GRADIENT = """
wt = bpy.context.scene.world.node_tree
g = wt.nodes.new('ShaderNodeTexGradient')
wt.links.new(g.outputs['Color'], wt.nodes['Background'].inputs['Color'])
"""


def render(blender, samples, session_dir, name, python):
    out = os.path.join(session_dir, name)
    log = blender.render(samples["mirror_floor"], out, {
        "engine": "BLENDER_EEVEE", "glint": {"write_layers_exr": True, "backend": "CPU", "enabled": True},
        "dump": True, "python": python})
    flags = next(line.split()[1:] for line in log.splitlines() if line.startswith("PASSES"))
    return out, log, flags


def test_uniform_world_needs_no_passes(blender, samples, session_dir):
    out, log, flags = render(blender, samples, session_dir, "world_uniform", REPORT + OWNED + STRONGER)
    assert flags == ["False", "False"], "the Specular passes Glint owned were not turned off"
    assert "comes from the world colour" in log
    assert "Glint: frame 1: reflections composited" in log
    layers = read_exr(os.path.join(out, "frame_glint_0001.exr"), layer=None)
    dump = load_dump(out)
    refl = dump["uv"][..., 2] > 0
    assert refl.sum() > 50
    # S = world colour x strength x W, W the core's split-sum weight of the pixel
    w = core().specular_weight(dump["position"], dump["normal"], dump["specular"],
                               dump["projection"].astype(np.float32))[..., :3].astype(np.float64)
    expected = WORLD * STRENGTH * w
    got = layers["EngineSpecular"][..., :3]
    assert expected[refl].max() > 0.01
    assert np.abs(got[refl] - expected[refl]).max() < 1e-4
    # and the reflection reached the frame: it differs from the render where hits are, nowhere else
    changed = np.abs(layers["Image"][..., :3] - layers["Base"][..., :3]).max(axis=-1) > 0.02
    assert (changed & refl).sum() > 50
    assert not (changed & ~refl).any()


def test_a_world_with_a_texture_keeps_the_passes(blender, samples, session_dir):
    out, log, flags = render(blender, samples, session_dir, "world_gradient", REPORT + GRADIENT)
    assert flags == ["True", "True"]
    assert "comes from the Eevee passes" in log
    assert "Glint: frame 1: reflections composited" in log
    layers = read_exr(os.path.join(out, "frame_glint_0001.exr"), layer=None)
    refl = load_dump(out)["uv"][..., 2] > 0
    assert layers["EngineSpecular"][..., :3][refl].max() > 0, "the passes did not reach the group"


def test_eevee_ssr_keeps_the_passes_under_a_uniform_world(blender, samples, session_dir):
    # Eevee's own reflections (Legacy's SSR, Next's ray tracing) replace the
    # world's specular in the frame: only the passes hold it
    out, log, flags = render(blender, samples, session_dir, "world_ssr",
                             REPORT + "from glint.host import engines\n"
                             "engines.set_eevee_traces_reflections(bpy.context.scene, True)\n")
    assert flags == ["True", "True"]
    assert "comes from the Eevee passes" in log
    assert "Glint: frame 1: reflections composited" in log

"""Ticking Glint is enough: files saved with the compositor off (Use Nodes off,
Post Processing > Compositing off, no Composite node) get their reflections when
Glint is enabled and the file rendered, and the log and the panel say what Glint
turned on. The files are made here, from the mirror_floor sample, by blender -b."""
import os

import numpy as np
import pytest

from glint_blender_helpers import PANELS, read_exr

pytestmark = pytest.mark.blender

# Run in Blender on the sample (Glint enabled by make_samples.py): switch Glint
# off (which takes its nodes out), then break the compositor as an old file has it.
VARIANTS = {
    "nodes_off": "s.glint.enabled = False; hn.release_tree(s)",
    "compositing_off": "s.glint.enabled = False; hn.scene_tree(s, create=True); s.render.use_compositing = False",
    "no_composite_node": (
        "s.glint.enabled = False; t = hn.scene_tree(s, create=True)\n"
        "for n in {x.node for x in hn.frame_outputs(t)}: t.nodes.remove(n)\n"
        "rl = next(n for n in t.nodes if n.bl_idname == 'CompositorNodeRLayers')\n"
        "v = t.nodes.get('Viewer') or t.nodes.new('CompositorNodeViewer')\n"
        "t.links.new(rl.outputs['Image'], v.inputs['Image'])"),
    # Saved with Glint on, then compositing switched off by hand (load_post and render_init repair it).
    "enabled_everything_off": "hn.release_tree(s); s.render.use_compositing = False",
}

# hn: this Blender's compositor tree (Use Nodes and scene.node_tree before 5.0,
# the compositing node group since), so the old files are made the same on each.
SAVE = """
import bpy
from glint.host import nodes as hn
s = bpy.context.scene
{code}
t = hn.scene_tree(s)
print('SAVED', not hn.tree_switch_is_off(s), s.render.use_compositing, s.glint.enabled,
      sorted(n.bl_idname for n in t.nodes) if t else None)
bpy.ops.wm.save_as_mainfile(filepath={path!r})
"""

CONFIG = {"glint": {"backend": "CPU", "enabled": True}}


@pytest.fixture(scope="module")
def old_files(blender, samples, session_dir):
    out = os.path.join(session_dir, "old_files")
    os.makedirs(out, exist_ok=True)
    paths = {}
    for name, code in VARIANTS.items():
        path = os.path.join(out, name + ".blend")
        log = blender.run([samples["mirror_floor"], "--addons", "glint", "--python-expr",
                           SAVE.format(code=code, path=path)])
        assert "SAVED" in log and os.path.isfile(path), log[-2000:]
        paths[name] = path
    return paths


@pytest.fixture(scope="module")
def reference(blender, samples, session_dir):
    out = os.path.join(session_dir, "old_files_reference")
    log = blender.render(samples["mirror_floor"], out, CONFIG)
    assert "Glint: frame 1: reflections composited" in log
    return read_exr(os.path.join(out, "frame_0001.exr"))


@pytest.mark.parametrize("variant", sorted(VARIANTS))
def test_enabling_glint_in_an_old_file_gives_reflections(variant, old_files, reference, mirror_off,
                                                         blender, tmp_path):
    out = str(tmp_path / "out")
    log = blender.render(old_files[variant], out, CONFIG)
    assert "Glint: frame 1: reflections composited" in log, log[-3000:]
    assert "turned on" in log, log[-3000:]
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    off = read_exr(os.path.join(mirror_off[0], "frame_0001.exr"))
    # The reflections are there: the frame is the sample's with Glint, not the plain one.
    with_glint = np.abs(reference[..., :3] - off[..., :3]).mean()
    assert with_glint > 1e-3
    assert np.abs(img[..., :3] - reference[..., :3]).mean() < 0.05 * with_glint


def test_the_panel_says_what_was_turned_on_and_off_restores_it(old_files, blender):
    code = ("import bpy\nfrom glint.host import nodes as hn\ns = bpy.context.scene\ns.glint.enabled = True\n" +
            PANELS + "\ns.glint.enabled = False\n"
            "print('AFTER', not hn.tree_switch_is_off(s), s.render.use_compositing)\n")
    log = blender.run([old_files["compositing_off"], "--addons", "glint", "--python-expr", code])
    assert "Post Processing > Compositing" in next(l for l in log.splitlines() if l.startswith("Glint: scene"))
    labels = next(l for l in log.splitlines() if l.startswith("LABELS"))
    # The file's world is one colour: S comes from it, Eevee's Specular passes stay off
    assert "'Glint turned on Post Processing > Compositing for its reflections'" in labels, labels
    assert "Replaced specular from the world colour" in labels, labels
    # Switching Glint off again gives the file its own settings back.
    assert "AFTER True False" in log, log[-2000:]


def test_compositing_switched_off_after_enabling_is_turned_on_at_render_init(samples, reference, blender, tmp_path):
    """Compositing unticked by hand after Glint was enabled (no update runs then):
    render_init turns it on for this very render."""
    out = str(tmp_path / "out")
    log = blender.render(samples["mirror_floor"], out, dict(
        CONFIG, python="bpy.context.scene.render.use_compositing = False"))
    assert "turned on Output Properties > Post Processing > Compositing" in log, log[-3000:]
    assert "Glint: frame 1: reflections composited" in log
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    assert np.abs(img[..., :3] - reference[..., :3]).mean() < 1e-3


def test_a_group_saved_by_an_older_glint_is_rebuilt_and_the_frame_is_not_black(
        samples, reference, blender, tmp_path):
    """A file saved by an older Glint carries an older node group: rebuilding it must
    keep the links the scene's tree makes to it (cutting them left the Composite node
    with nothing, and the frame black)."""
    path = str(tmp_path / "older_group.blend")
    code = ("from glint import compositor\n"
            "g = compositor.find_group()\n"
            "g[compositor.LAYOUT_KEY] = 'older'\n"
            "g.nodes.remove(g.nodes['combined'])\n")
    log = blender.run([samples["mirror_floor"], "--addons", "glint", "--python-expr",
                       code + SAVE.format(code="", path=path)])
    assert "SAVED" in log, log[-2000:]
    out = str(tmp_path / "out")
    log = blender.render(path, out, CONFIG)
    assert "Glint: frame 1: reflections composited" in log, log[-3000:]
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    assert np.abs(img[..., :3] - reference[..., :3]).mean() < 1e-3

"""Model only what the scene needs: an object on screen that no reflected ray can
meet is not exported (the log says so), and leaving it out changes no traced
value: the trace equals the one with every object exported, bit for bit."""
import re

import numpy as np
import pytest

from glint_blender_helpers import load_dump

pytestmark = pytest.mark.blender

# The mirror floor shrunk to a 1.6 m tile under the red sphere, rays 1 m long,
# and a white cube far up on the right: on screen, far from any ray.
SCENE = """
import bpy
s = bpy.context.scene
floor = bpy.data.objects['Mirror Floor']
floor.scale = (0.1, 0.1, 1.0)
bpy.ops.mesh.primitive_cube_add(size=0.6, location=(3.2, 6.0, 1.9))
bpy.context.object.name = 'Far Cube'
"""
KEEP_ALL = """
import glint.gather as G
G.reach_culling = lambda cam, boxes, reflective, max_distance: [False] * len(boxes)
"""


@pytest.mark.parametrize("march", ["HIZ", "SEED"])
def test_objects_out_of_reach_are_not_exported_and_change_nothing(march, blender, samples, tmp_path):
    runs = {}
    for name, extra in (("culled", ""), ("all", KEEP_ALL)):
        out = str(tmp_path / name)
        log = blender.render(samples["mirror_floor"], out, {
            "glint": {"preset": "CUSTOM", "march": march, "max_distance": 1.0, "backend": "CPU",
                      "enabled": True},
            "dump": True, "python": SCENE + extra, "wtcv_points": {"far": [[3.2, 6.0, 1.9]]}})
        line = next(l for l in log.splitlines() if l.startswith("Glint: frame 1: reflections composited"))
        runs[name] = (line, load_dump(out))
    far = runs["culled"][1]["wtcv_far"][0]
    assert 0 < far[0] < 1 and 0 < far[1] < 1 and far[2] > 0  # the cube is on screen
    count = re.compile(r"and (\d+) out of the reflections' reach not exported")
    assert count.search(runs["all"][0]).group(1) == "0"
    assert int(count.search(runs["culled"][0]).group(1)) >= 1, runs["culled"][0]
    culled, full = runs["culled"][1], runs["all"][1]
    assert np.array_equal(culled["uv"], full["uv"])
    refl = full["uv"][..., 2] > 0
    if march == "SEED":
        # The tile reflects the sphere's underside (40 pixels at 160x90), which the
        # camera does not see: the seed reports the front in front of it (its
        # thickness test), the hiz march nothing, since it reports visible hits only
        # (with the sphere's own normals, which trace(specular=) now keeps).
        assert refl.sum() > 20
    # The G-buffer differs only where the left-out objects were seen.
    differs = np.any(culled["position"] != full["position"], axis=-1)
    assert differs.any() and not (differs & refl).any()

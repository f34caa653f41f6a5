"""Measure This Scene under ``blender -b``, and the Exact preset in a render."""
import json
import os

import numpy as np
import pytest

from glint_blender_helpers import load_dump

pytestmark = pytest.mark.blender

MEASURE = """
import bpy, json, sys
scene = bpy.context.scene
scene.render.resolution_x, scene.render.resolution_y, scene.render.resolution_percentage = 160, 90, 100
scene.glint.preset = {preset!r}
assert bpy.ops.glint.measure(repeat=1, save_path={png!r}) == {{'FINISHED'}}
from glint.state import STATE
print('MEASURED ' + json.dumps({{k: v for k, v in STATE.measurement.items() if k != 'trace_kwargs'}}))
"""


def measured(log):
    line = next(l for l in log.splitlines() if l.startswith("MEASURED "))
    return json.loads(line[len("MEASURED "):])


def test_measure_reports_the_preset_against_exact(blender, samples, tmp_path):
    png = str(tmp_path / "disagree.png")
    log = blender.run([samples["mirror_floor"], "--addons", "glint", "--python-expr",
                       MEASURE.format(preset="BALANCED", png=png)])
    m = measured(log)
    assert m["preset"] == "Balanced" and (m["width"], m["height"]) == (160, 90)
    assert m["exact_visible"] > 100, "the mirror floor reflects its objects"
    assert 0.5 < m["recall"] <= 1.0 and 0.5 < m["precision"] <= 1.0
    assert m["ms"] > 0 and m["exact_ms"] > 0 and m["triangles"] > 100
    assert "Glint: measured Balanced: precision" in log
    assert os.path.getsize(png) > 100


def test_exact_scores_one_against_itself(blender, samples, tmp_path):
    log = blender.run([samples["mirror_floor"], "--addons", "glint", "--python-expr",
                       MEASURE.format(preset="EXACT", png="")])
    m = measured(log)
    assert m["precision"] == 1.0 and m["recall"] == 1.0 and m["false_reflections"] == 0


def test_measure_without_reflective_materials_says_so(blender, samples, tmp_path):
    code = ("import bpy\nbpy.ops.glint.measure(repeat=1)\n")
    log = blender.run([samples["no_reflection"], "--addons", "glint", "--python-expr", code], check=False)
    assert "nothing to measure" in log


def test_exact_preset_renders_reflections(blender, samples, tmp_path):
    out = str(tmp_path / "exact")
    log = blender.render(samples["mirror_floor"], out, {"engine": "BLENDER_WORKBENCH", "dump": True,
                                                        "glint": {"preset": "EXACT", "backend": "CPU"}})
    assert "WITHOUT" not in log, log[-2000:]
    dump = load_dump(out)
    assert str(dump["status"]) == "ok", dump["message"]
    vis = dump["uv"][..., 2]
    assert (vis > 0).sum() > 100
    # Whole hits, but on the reflection's outlines the share of five rays (antialias 4).
    fifths = vis * 5
    assert np.allclose(fifths, np.round(fifths), atol=1e-4), "the exact march reports hits in fifths only"
    assert ((vis > 0) & (vis < 1)).sum() > 0, "the exact preset antialiases its outlines"
    assert ((vis > 0) & (vis < 1)).sum() < 0.2 * (vis > 0).sum()

"""A render cropped to a render region (Output > Format > Render Region with Crop to
Render Region) gets its reflections: the region is Glint's screen
(logic/projection.window_projection). Against the whole frame rendered with the same
settings: the plain cropped frame is the whole frame's pixels there (so the window is
the one Blender crops, rows counted from the bottom), and Glint changes the cropped
frame as it changes those pixels of the whole frame, but where a ray leaves the region
(it then fades out, as at a frame's edge)."""
import os
import sys

import numpy as np
import pytest

from glint_blender_helpers import read_exr

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "addon"))
from glint_addon_helpers import load_logic  # noqa: E402

pytestmark = pytest.mark.blender

projection = load_logic("projection")

SIZE = (320, 180)
# x 0.2-0.85, y 0.05-0.9: the objects and their mirror images, less the frame's sides
BORDER = (0.2, 0.85, 0.05, 0.9)
CROP = ("r = scene.render\nr.use_border = True\nr.use_crop_to_border = True\n"
        "r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = {}\n").format(BORDER)


def test_a_cropped_render_region_composites_the_whole_frames_reflections_there(blender, samples, session_dir):
    frames = {}
    for crop in (False, True):
        for on in (False, True):
            out = os.path.join(session_dir, f"render-region-{crop}-{on}")
            config = {"size": list(SIZE), "engine": "BLENDER_WORKBENCH", "python": CROP if crop else "",
                      "glint": {"backend": "CPU", "enabled": on}}
            log = blender.render(samples["mirror_floor"], out, config)
            if on:
                assert "reflections composited" in log, log[-2000:]
            frames[crop, on] = read_exr(os.path.join(out, "frame_0001.exr"))[..., :3]
    win = projection.render_window(*SIZE, 100, BORDER)
    assert frames[True, False].shape[:2] == (win.height, win.width)
    rows, cols = slice(win.y0, win.y0 + win.height), slice(win.x0, win.x0 + win.width)
    # The plain cropped frame is the whole frame's window (read_exr: row 0 at the bottom).
    plain = np.abs(frames[True, False] - frames[False, False][rows, cols]).max()
    assert plain < 1e-3, plain
    whole = (frames[False, True] - frames[False, False])[rows, cols]
    cropped = frames[True, True] - frames[True, False]
    changed = np.abs(whole).max(axis=-1) > 0.02
    assert changed.sum() > 300, changed.sum()
    agree = np.abs(cropped - whole).max(axis=-1) < 0.02
    share = (agree & changed).sum() / changed.sum()
    assert share > 0.9, share

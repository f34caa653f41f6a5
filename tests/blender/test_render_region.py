"""A render region (Output > Format > Render Region), against the whole frame rendered
with the same settings. Cropped to it (Crop to Render Region), the region is Glint's
screen (logic/projection.window_projection): the plain cropped frame is the whole
frame's pixels there (so the window is the one Blender crops, rows counted from the
bottom), and Glint changes it as it changes those pixels of the whole frame, but where
a ray leaves the region (it then fades out, as at a frame's edge). Not cropped, the
frame outside the region stays black, and inside it Glint's change is the whole
frame's but where a ray meets the black outside."""
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


def region(crop):
    return ("r = scene.render\nr.use_border = True\nr.use_crop_to_border = {}\n"
            "r.border_min_x, r.border_max_x, r.border_min_y, r.border_max_y = {}\n").format(crop, BORDER)


def renders(blender, samples, session_dir, crop):
    """The plain frame and Glint's change to it; crop None: no render region."""
    frames = {}
    for on in (False, True):
        out = os.path.join(session_dir, f"render-region-{crop}-{on}")
        config = {"size": list(SIZE), "engine": "BLENDER_WORKBENCH", "python": "" if crop is None else region(crop),
                  "glint": {"backend": "CPU", "enabled": on}}
        log = blender.render(samples["mirror_floor"], out, config)
        if on:
            assert "reflections composited" in log, log[-2000:]
        frames[on] = read_exr(os.path.join(out, "frame_0001.exr"))
    return frames[False], frames[True] - frames[False]


@pytest.fixture(scope="module")
def whole(blender, samples, session_dir):
    return renders(blender, samples, session_dir, None)


@pytest.mark.parametrize("crop", [True, False], ids=["cropped", "not_cropped"])
def test_a_render_region_composites_the_whole_frames_reflections_there(blender, samples, session_dir, whole, crop):
    plain, change = renders(blender, samples, session_dir, crop)
    whole_plain, whole_change = whole
    win = projection.render_window(*SIZE, 100, BORDER, crop)
    rows, cols = slice(win.y0, win.y0 + win.height), slice(win.x0, win.x0 + win.width)
    if crop:
        assert plain.shape[:2] == (win.height, win.width)
    else:
        # nothing rendered outside the region, and Glint leaves it so
        assert plain.shape[:2] == whole_plain.shape[:2]
        outside = np.ones(plain.shape[:2], bool)
        outside[rows, cols] = False
        assert not plain[outside].any() and not change[outside].any()
        plain, change = plain[rows, cols], change[rows, cols]
    # read_exr: row 0 at the bottom, as Blender's window
    assert np.abs(plain - whole_plain[rows, cols]).max() < 1e-3
    want = whole_change[rows, cols][..., :3]
    changed = np.abs(want).max(axis=-1) > 0.02
    assert changed.sum() > 300, changed.sum()
    agree = np.abs(change[..., :3] - want).max(axis=-1) < 0.02
    share = (agree & changed).sum() / changed.sum()
    print(f"render region, crop {crop}: {share:.4f} of {changed.sum()} changed pixels agree")
    assert share > 0.9, share

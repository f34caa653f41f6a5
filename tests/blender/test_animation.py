"""``-a`` on the animated scene: each frame is exported with its own camera, the
frames differ, and a frame rendered alone (a farm's split range) is the same."""
import math
import os

import numpy as np
import pytest

from glint_blender_helpers import SIZE, load_dump, read_exr

pytestmark = pytest.mark.blender

FRAMES = (1, 2, 3, 4)


def expected_camera(frame):
    """The camera make_samples.py keys at ``frame``, built here from its formula."""
    a = math.radians(-25.0 + 50.0 * (frame - 1) / 3.0)
    loc = np.array([7.0 * math.sin(a), -7.0 * math.cos(a), 2.2])
    d = np.array([0.0, 0.0, 0.5]) - loc
    d /= np.linalg.norm(d)
    z = -d
    x = np.cross([0.0, 0.0, 1.0], z)
    x /= np.linalg.norm(x)
    y = np.cross(z, x)
    m = np.eye(4)
    m[:3, 0], m[:3, 1], m[:3, 2], m[:3, 3] = x, y, z, loc
    return m


@pytest.fixture(scope="module")
def animation(blender, samples, session_dir):
    out = os.path.join(session_dir, "anim")
    log = blender.render(samples["animated_camera"], out, {"dump": True, "glint": {"backend": "CPU"}},
                         frames=("-a",))
    return out, log


def test_every_frame_gets_its_own_camera(animation):
    out, log = animation
    for f in FRAMES:
        assert f"Glint: frame {f}: reflections composited" in log
        dump = load_dump(out, f)
        assert int(dump["frame"]) == f
        view_expected = np.linalg.inv(expected_camera(f))
        assert np.abs(dump["view"] - view_expected).max() < 1e-4, f


def test_frames_differ_and_each_reflects_the_sphere_where_its_camera_says(animation):
    out, _ = animation
    images = [read_exr(os.path.join(out, f"frame_{f:04d}.exr")) for f in FRAMES]
    for i in range(len(images)):
        for j in range(i + 1, len(images)):
            assert np.abs(images[i] - images[j]).mean() > 0.005, (i, j)
    w, h = SIZE
    for f, img in zip(FRAMES, images):
        dump = load_dump(out, f)
        view = np.linalg.inv(expected_camera(f))
        clip = dump["projection"] @ view @ np.array([0.0, 0.0, -1.0, 1.0])  # the sphere centre's mirror image
        u, v = clip[:2] / clip[3] * 0.5 + 0.5
        px, py = int(u * w), int(v * h)
        patch = img[py - 1:py + 2, px - 1:px + 2, :3].mean(axis=(0, 1))
        assert patch[0] > 2.0 * patch[1] and patch[0] > 2.0 * patch[2], (f, patch)


def test_a_frame_rendered_alone_matches_the_same_frame_of_the_sequence(animation, blender, samples, session_dir):
    out = os.path.join(session_dir, "anim_split")
    log = blender.render(samples["animated_camera"], out, {"glint": {"backend": "CPU"}},
                         frames=("-s", "3", "-e", "3", "-a"))
    assert "Glint: frame 3: reflections composited" in log
    alone = read_exr(os.path.join(out, "frame_0003.exr"))
    in_sequence = read_exr(os.path.join(animation[0], "frame_0003.exr"))
    assert np.abs(alone - in_sequence).max() <= 1e-6


def test_the_exact_march_keeps_its_bvh_while_the_camera_moves(blender, samples, tmp_path):
    """The Exact preset traces against one ExactScene kept in world space: built on
    the first frame, and only refit or reused on the next ones, where the camera
    moved and nothing else did (docs/addon.md, the exact march in the add-on)."""
    out = str(tmp_path / "exact")
    log = blender.render(samples["animated_camera"], out, {"glint": {"backend": "CPU", "preset": "EXACT"}},
                         frames=("-s", "1", "-e", "3", "-a"))
    lines = [line for line in log.splitlines() if line.startswith("Glint: frame ")]
    assert len(lines) == 3 and all("reflections composited" in line for line in lines), log[-3000:]
    assert "exact march's BVH built" in lines[0], lines[0]
    for line in lines[1:]:
        assert "exact march's BVH refit" in line or "exact march's BVH reused" in line, line

"""A frame loses nothing: over the memory limit it is traced at reduced resolution,
and only when the floor fails too it renders without reflections, saying why."""
import os

import numpy as np
import pytest

from glint_blender_helpers import load_dump, read_exr

pytestmark = pytest.mark.blender


def _frame(out):
    return read_exr(os.path.join(out, "frame_0001.exr"))


def _render_with_env(blender, blend, out, config, **env):
    saved = blender.env
    blender.env = {**saved, **env}
    try:
        return blender.render(blend, out, config)
    finally:
        blender.env = saved


@pytest.fixture(scope="module")
def full_size(blender, samples, tmp_path_factory):
    """mirror_floor with reflections traced at full size (no limit), on the CPU."""
    out = str(tmp_path_factory.mktemp("full"))
    log = blender.render(samples["mirror_floor"], out, {"dump": True, "glint": {"backend": "CPU"}})
    assert "reflections composited" in log and "reduced resolution" not in log, log[-2000:]
    return out


def test_over_the_memory_limit_the_frame_is_traced_at_half_size(blender, samples, mirror_off, full_size,
                                                               tmp_path):
    out = str(tmp_path / "half")
    # 1 MiB: the 160x90 G-buffer and trace need about 1.9 MiB, 80x45 about a quarter.
    log = _render_with_env(blender, samples["mirror_floor"], out, {"dump": True, "glint": {"backend": "CPU"}},
                           GLINT_MEMORY_LIMIT_MB="1")
    assert "reflections traced at reduced resolution 80x45 (1/2 of 160x90)" in log, log[-3000:]
    assert "Glint: frame 1: reflections composited" in log and "memory limit of 1.0 MiB" in log
    dump, full = load_dump(out), load_dump(full_size)
    assert str(dump["status"]) == "ok"
    uv = dump["uv"]
    assert uv.shape == full["uv"].shape == (90, 160, 4)
    # Nearest-neighbour from 80x45: every 2x2 block of the frame is one traced pixel.
    blocks = uv.reshape(45, 2, 80, 2, 4)
    assert np.array_equal(blocks, np.broadcast_to(blocks[:, :1, :, :1], blocks.shape))
    # The half-size trace finds the full-size one's reflections: hits agree on most
    # pixels, and where both hit, the uvs are within the reduced pixels' size.
    hit, hit_full = uv[..., 2] > 0, full["uv"][..., 2] > 0
    assert hit_full.sum() > 500 and (hit == hit_full).mean() > 0.95
    both = hit & hit_full
    duv = np.abs(uv[both, :2] - full["uv"][both, :2])
    assert np.median(duv[:, 0]) < 2.0 / 160 and np.median(duv[:, 1]) < 2.0 / 90
    # And the picture has the reflections: far from the frame without them, near the full-size one.
    img, base, ref = _frame(out), _frame(mirror_off[0]), _frame(full_size)
    changed = np.abs(ref - base)[..., :3].max(axis=-1) > 0.02
    assert changed.sum() > 200
    err_reduced = np.abs(img - ref)[changed][:, :3].mean()
    err_none = np.abs(base - ref)[changed][:, :3].mean()
    assert err_reduced < 0.5 * err_none, (err_reduced, err_none)


def test_when_not_even_the_floor_fits_the_frame_renders_without_reflections(blender, samples, tmp_path):
    out = str(tmp_path / "floor")
    # 0.2 MiB: the 1038 triangles' set-up alone is more, at any size.
    log = _render_with_env(blender, samples["mirror_floor"], out, {"engine": "CYCLES", "cycles_samples": 1,
                                                                   "glint": {"backend": "CPU"}},
                           GLINT_MEMORY_LIMIT_MB="0.2")
    assert "trying 1/4: 40x23" in log and "trying 1/8: 20x12" in log, log[-3000:]
    assert "rendered WITHOUT reflections: over Glint's memory limit (also at 20x12" in log, log[-3000:]
    assert os.path.isfile(os.path.join(out, "frame_0001.exr"))

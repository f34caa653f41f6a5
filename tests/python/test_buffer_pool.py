"""The core's buffer pool (glint_core.buffer_pool): large buffers freed by one call
are handed to the next of the same size instead of being faulted in again, what
was in them never shows through, and the pool obeys its limit and its release."""
from __future__ import annotations

import numpy as np
import pytest

import glint_core

W, H = 640, 480  # 4.7 MiB per RGBA image: pooled (kPoolMinBytes is 1 MiB)


@pytest.fixture(autouse=True)
def pool():
    before = glint_core.buffer_pool()
    glint_core.release_buffers()
    glint_core.buffer_pool(limit_mb=256, max_idle_s=60)
    yield
    glint_core.release_buffers()
    glint_core.buffer_pool(limit_mb=before["limit_mb"], max_idle_s=before["max_idle_s"])


def corner_triangle():
    """One triangle over the lower-left corner, seen through an orthographic view of
    one unit per pixel: it covers exactly the pixels with x + y + 1 < 40."""
    pos = np.array([[[-W / 2, -H / 2, -5], [-W / 2 + 40, -H / 2, -5], [-W / 2, -H / 2 + 40, -5]]], np.float32)
    nrm = np.broadcast_to(np.array([0, 0, 1], np.float32), pos.shape).copy()
    proj = np.zeros((4, 4), np.float32)
    proj[0, 0], proj[1, 1], proj[2, 2], proj[2, 3], proj[3, 3] = 2 / W, 2 / H, -2 / 99.9, -100.1 / 99.9, 1
    mats = np.array([[0.5, 0.5, 0.5, 64.0]], np.float32)
    return pos, nrm, np.zeros(1, np.int32), mats, proj


def test_a_second_frame_takes_no_new_memory():
    args = corner_triangle()
    del glint_core.rasterize(*args, W, H, back_layer=True)["position"]  # the rest goes with the dict
    first = glint_core.buffer_pool()
    assert first["held_mb"] >= 4 * 4.6, first  # the four G-buffers came back to the pool
    glint_core.rasterize(*args, W, H, back_layer=True)
    second = glint_core.buffer_pool()
    assert second["allocated"] == first["allocated"], second
    assert second["reused"] >= first["reused"] + 4, second


def test_what_a_reused_buffer_held_never_shows():
    # Fill the pool with buffers full of non-zero values (the trace's outputs of
    # a garbage G-buffer), then rasterize: uncovered pixels must be exactly zero.
    noise = np.random.default_rng(1).uniform(1, 2, (H, W, 4)).astype(np.float32)
    proj = corner_triangle()[4]
    for _ in range(3):
        glint_core.trace(noise, noise, proj)
    assert glint_core.buffer_pool()["held_mb"] > 0
    out = glint_core.rasterize(*corner_triangle(), W, H, back_layer=True)
    y, x = np.mgrid[0:H, 0:W]
    covered = x + y + 1 < 40
    np.testing.assert_array_equal(out["position"][..., 3] == 1, covered)
    for name in ("position", "normal", "specular", "back_position"):
        assert not out[name][~covered].any(), name


def test_the_limit_and_release_hold():
    args = corner_triangle()
    glint_core.buffer_pool(limit_mb=0)
    glint_core.rasterize(*args, W, H)
    assert glint_core.buffer_pool()["held_mb"] == 0
    glint_core.buffer_pool(limit_mb=8)  # one 6 MiB block (4.7 MiB rounded to 2 MiB) fits, two do not
    glint_core.rasterize(*args, W, H)
    assert glint_core.buffer_pool()["held_mb"] == 6
    assert glint_core.release_buffers() == 6
    assert glint_core.buffer_pool()["held_mb"] == 0


@pytest.mark.parametrize("kwargs,name", [({"limit_mb": -1}, "limit_mb"), ({"limit_mb": float("nan")}, "limit_mb"),
                                         ({"max_idle_s": -1.0}, "max_idle_s"),
                                         ({"max_idle_s": float("inf")}, "max_idle_s")])
def test_bad_settings_name_the_argument(kwargs, name):
    with pytest.raises(ValueError, match=name):
        glint_core.buffer_pool(**kwargs)

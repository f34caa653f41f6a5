"""A frame loses nothing: over the memory limit it is traced at reduced resolution;
a lost GL context, a core error or a cancel in the middle of the frame leave it
rendered without reflections, and the log says why. Faults are injected from
outside the add-on and the core (glint_faults.py, fault_egl.c)."""
import os
import subprocess

import numpy as np
import pytest

from glint_blender_helpers import HERE, core, load_dump, read_exr

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


def test_at_reduced_resolution_debug_views_and_layers_are_frame_sized(blender, samples, tmp_path):
    out = str(tmp_path / "half_layers")
    log = _render_with_env(blender, samples["mirror_floor"], out,
                           {"dump": True, "glint": {"backend": "CPU", "debug_view": "NORMAL",
                                                    "write_layers_exr": True}},
                           GLINT_MEMORY_LIMIT_MB="1")
    assert "reflections traced at reduced resolution 80x45" in log, log[-3000:]
    dump = load_dump(out)
    layers = read_exr(os.path.join(out, "frame_glint_0001.exr"), layer=None)
    for name in ("Position", "Normal", "Specular", "UV"):
        assert layers[name].shape == (90, 160, 4), name
    # The normal debug view is the stretched G-buffer: 2x2 blocks, n * 0.5 + 0.5 where seen.
    img = _frame(out)
    n = dump["normal"]
    assert n.shape == (90, 160, 4)
    seen = dump["position"][..., 3] > 0.5
    assert np.allclose(img[seen, :3], n[seen, :3] * 0.5 + 0.5, atol=1e-6)
    blocks = n.reshape(45, 2, 80, 2, 4)
    assert np.array_equal(blocks, np.broadcast_to(blocks[:, :1, :, :1], blocks.shape))


def test_when_not_even_the_floor_fits_the_frame_renders_without_reflections(blender, samples, tmp_path):
    out = str(tmp_path / "floor")
    # 0.2 MiB: the 1038 triangles' set-up alone is more, at any size.
    log = _render_with_env(blender, samples["mirror_floor"], out, {"engine": "BLENDER_WORKBENCH",
                                                                   "glint": {"backend": "CPU"}},
                           GLINT_MEMORY_LIMIT_MB="0.2")
    assert "trying 1/4: 40x23" in log and "trying 1/8: 20x12" in log, log[-3000:]
    assert "rendered WITHOUT reflections: over Glint's memory limit (also at 20x12" in log, log[-3000:]
    assert os.path.isfile(os.path.join(out, "frame_0001.exr"))


@pytest.fixture(scope="module")
def egl_shim(tmp_path_factory):
    """fault_egl.c built into a stand-in EGL library (the system's libEGL behind it)."""
    try:
        core().backend_name("gl")
    except core().BackendUnavailable as exc:
        pytest.skip(f"no OpenGL here: {exc}")
    path = str(tmp_path_factory.mktemp("egl") / "fault_egl.so")
    proc = subprocess.run(["cc", "-shared", "-fPIC", "-O1", "-o", path, os.path.join(HERE, "fault_egl.c"),
                           "-l:libEGL.so.1"], stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    if proc.returncode != 0:
        pytest.skip(f"cannot build the EGL shim: {proc.stdout[-1000:]}")
    return path


def _assert_rendered_without_reflections(log, out, mirror_off, why):
    assert f"Glint: frame 1: rendered WITHOUT reflections: {why}" in log, log[-3000:]
    assert "reflections composited" not in log
    img, base = _frame(out), _frame(mirror_off[0])
    assert img.shape == base.shape
    assert np.abs(img - base).max() <= 1e-6  # the frame without reflections, untouched


def test_a_gl_context_lost_mid_frame(blender, samples, mirror_off, egl_shim, tmp_path):
    out = str(tmp_path / "gl_lost")
    code = f"import glint_faults; glint_faults.lose_gl_context_after_rasterize({egl_shim!r})"
    log = _render_with_env(blender, samples["mirror_floor"], out,
                           {"python": code, "dump": True, "glint": {"backend": "GL"}},
                           GLINT_EGL_LIBRARY=egl_shim)
    # The G-buffer came from GL; the trace's read-back found the context gone.
    _assert_rendered_without_reflections(log, out, mirror_off, "RuntimeError: glint GL: GL_CONTEXT_LOST in ")
    assert str(load_dump(out)["backend"]) == "gl"


def test_a_core_error_mid_frame(blender, samples, mirror_off, tmp_path):
    out = str(tmp_path / "core_error")
    code = "import glint_faults; glint_faults.core_error_in_trace()"
    log = blender.render(samples["mirror_floor"], out, {"python": code, "glint": {"backend": "CPU"}})
    _assert_rendered_without_reflections(log, out, mirror_off,
                                         "RuntimeError: glint: injected core failure in trace")


@pytest.mark.parametrize("when, code, why", [
    # The export looks once per exported object (4 here): the second look is after the first.
    ("export", "glint_faults.cancel_after_checks(2)", "Glint export cancelled at 2/4"),
    # All 4 objects exported, the G-buffer drawn and traced: the look after the trace stops it.
    ("trace", "glint_faults.cancel_during_trace()", "Glint export cancelled at 4/4"),
])
def test_a_cancel_mid_frame(blender, samples, mirror_off, tmp_path, when, code, why):
    out = str(tmp_path / f"cancel_{when}")
    log = blender.render(samples["mirror_floor"], out, {"python": "import glint_faults; " + code,
                                                        "glint": {"backend": "CPU"}})
    _assert_rendered_without_reflections(log, out, mirror_off, why)

"""backend="gl" against backend="cpu" for the physically based look
(specular_weight, cone_blur, the weighted reflection, the replacing combine,
and the whole default pipeline), on identical inputs, as test_gl_parity.py does
for the seed's stages: all channels within 1e-4 on >= 99.9% of pixels, and the
largest difference printed (pytest -s)."""
from __future__ import annotations

import numpy as np
import pytest

import analytic as A

pytestmark = pytest.mark.gl
SHARE = 0.999


def agree(label, cpu, gl_out, tol=1e-4):
    d = np.abs(cpu.astype(np.float64) - gl_out).max(axis=-1)
    share = float((d <= tol).mean())
    print(f"{label}: {share * 100:.3f}% of pixels within {tol:g}, max |diff| {d.max():.3g}")
    assert share >= SHARE, label


def scene(kind, alpha):
    floor = A.Material(color=(0.4, 0.4, 0.4), specular=(0.05, 0.04, 0.03), alpha=alpha)
    sphere = A.Material(color=(0.9, 0.1, 0.1), specular=(0.9, 0.6, 0.2), alpha=0.7)
    return A.render(A.mirror_floor_scene(kind, floor=floor, sphere_material=sphere), 96, 64)


@pytest.mark.parametrize("kind", ["persp", "ortho"])
def test_stages_agree(gl, kind):
    gb = scene(kind, 0.4)
    args = (gb["position"], gb["normal"], gb["specular"], gb["projection"])
    w_cpu = gl.specular_weight(*args, backend="cpu")
    agree(f"{kind} specular_weight", w_cpu, gl.specular_weight(*args, backend="gl"))
    out = gl.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"], gb["projection"],
                      resolution=1.0)
    rc, uv, spec = out["reflection_color"], out["uv"], gb["specular"]
    cone = gl.cone_blur(rc, uv, spec, backend="cpu")
    agree(f"{kind} cone_blur", cone, gl.cone_blur(rc, uv, spec, backend="gl"))
    mirror = dict(position=gb["position"], projection=gb["projection"])  # the flat mirror's bound
    agree(f"{kind} cone_blur, bounded", gl.cone_blur(rc, uv, spec, **mirror, backend="cpu"),
          gl.cone_blur(rc, uv, spec, **mirror, backend="gl"))
    r = gl.reflection(cone, None, spec, weight=w_cpu, backend="cpu")
    agree(f"{kind} reflection", r, gl.reflection(cone, None, spec, weight=w_cpu, backend="gl"))
    sb = (gb["color"][..., :3] * 0.2).astype(np.float32)
    c_cpu = gl.combine(gb["color"], r, specular_base=sb, coverage=cone, backend="cpu")
    agree(f"{kind} combine (specular_base)", c_cpu,
          gl.combine(gb["color"], r, specular_base=sb, coverage=cone, backend="gl"))


def test_cone_blur_agrees_with_per_pixel_levels(gl):
    """Neighbouring pixels reading different mip levels, odd level sizes."""
    rng = np.random.default_rng(7)
    h, w = 61, 93
    col = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    uv = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    uv[..., 2] = 1.0
    spec = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    agree("cone_blur random levels", gl.cone_blur(col, uv, spec, backend="cpu"),
          gl.cone_blur(col, uv, spec, backend="gl"))
    # Random positions in front of a perspective camera: the flat mirror's bound
    # binds on some pixels and not on others, and a few texels are unseen.
    pos = np.ones((h, w, 4), np.float32)
    pos[..., :2] = rng.uniform(-3, 3, (h, w, 2))
    pos[..., 2] = rng.uniform(-40, -1, (h, w))
    pos[..., 3] = rng.uniform(0, 1, (h, w)) > 0.05
    proj = A.projection_matrix("persp", w, h)
    bounded = gl.cone_blur(col, uv, spec, position=pos, projection=proj, backend="cpu")
    assert not np.array_equal(bounded, gl.cone_blur(col, uv, spec, backend="cpu"))
    agree("cone_blur random levels, bounded", bounded,
          gl.cone_blur(col, uv, spec, position=pos, projection=proj, backend="gl"))


@pytest.mark.parametrize("alpha", [1.0, 0.3])
def test_default_pipeline_agrees(gl, alpha):
    gb = scene("persp", alpha)
    sb = (gb["color"][..., :3] * 0.1).astype(np.float32)
    outs = {be: gl.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"],
                            gb["projection"], specular_base=sb, backend=be) for be in ("cpu", "gl")}
    assert outs["cpu"]["stats"]["skipped"] == outs["gl"]["stats"]["skipped"]
    for layer in gl.LAYERS:
        agree(f"pipeline alpha {alpha} {layer}", outs["cpu"][layer], outs["gl"][layer])


def test_seed_look_agrees(gl):
    gb = scene("persp", 0.4)
    outs = {be: gl.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"],
                            gb["projection"], weighting="seed", blur="box", combine="seed",
                            backend=be) for be in ("cpu", "gl")}
    for layer in gl.LAYERS:
        agree(f"seed look {layer}", outs["cpu"][layer], outs["gl"][layer])

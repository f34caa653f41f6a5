"""Extreme parameters and degenerate data: never a hang, never NaN/Inf out.

Every case runs both marches and the whole pipeline under a wall-clock guard
(a generous 60 s: a hang, not a timing). Outputs must be finite, visibility
in [0, 1] and the uv buffer's two visibility channels equal.
"""
import math
import threading

import numpy as np
import pytest

import analytic as A
import glint_core
from glint_tables import SCREEN_MARCHES

HANG_SECONDS = 60.0
BASE = dict(max_distance=15.0, resolution=0.3, steps=10, thickness=0.5)


def guarded(fn, *args, **kwargs):
    """Run fn in a worker thread (the core releases the GIL) and fail as a
    hang if it has not returned within HANG_SECONDS."""
    box = {}

    def work():
        try:
            box["value"] = fn(*args, **kwargs)
        except BaseException as exc:  # re-raised in the test's thread
            box["error"] = exc

    t = threading.Thread(target=work, daemon=True)
    t.start()
    t.join(HANG_SECONDS)
    if t.is_alive():
        pytest.fail(f"hang: {getattr(fn, '__name__', fn)} did not return within {HANG_SECONDS} s")
    if "error" in box:
        raise box["error"]
    return box["value"]


def check_uv(uv, shape):
    assert uv.shape == shape[:2] + (4,) and uv.dtype == np.float32
    assert np.isfinite(uv).all(), "NaN/Inf in the uv buffer"
    assert (uv[..., 2] >= 0).all() and (uv[..., 2] <= 1).all(), "visibility outside [0, 1]"
    np.testing.assert_array_equal(uv[..., 2], uv[..., 3])


def check_pipeline(out, gb):
    shape = gb["position"].shape
    for name in glint_core.LAYERS:
        layer = out[name]
        assert layer.shape == shape[:2] + (4,) and layer.dtype == np.float32, name
        assert np.isfinite(layer).all(), f"NaN/Inf in layer {name}"
    check_uv(out["uv"], shape)
    rc = out["reflection_color"]
    assert (rc[..., 3] >= 0).all() and (rc[..., 3] <= 1).all()
    assert set(out["stats"]["skipped"]) <= set(glint_core.STAGES)


# The marches as the extremes run them: each screen march with one ray a pixel,
# and hiz with antialiased outlines too, as the presets that most users render
# with trace (docs/hiz.md, *Antialiased outlines*).
MARCH_RUNS = [dict(march=m) for m in SCREEN_MARCHES] + [dict(march="hiz", antialias=4)]


def run_all(gb, **params):
    """Every march run and the pipeline on one G-buffer, each under the guard."""
    kw = dict(BASE, **params)
    for run in MARCH_RUNS:
        uv = guarded(glint_core.trace, gb["position"], gb["normal"], gb["projection"],
                     **run, **kw)
        check_uv(uv, gb["position"].shape)
        # Unseen pixels report exactly nothing.
        unseen = ~(gb["position"][..., 3] > 0)
        assert np.all(uv[unseen] == 0)
    out = guarded(glint_core.pipeline, gb["position"], gb["normal"], gb["specular"], gb["color"],
                  gb["projection"], **kw)
    check_pipeline(out, gb)
    return out


_scene_cache = {}


@pytest.mark.parametrize("kind", ["persp", "ortho"])
def test_the_extremes_reach_the_antialiased_outlines(kind):
    """MARCH_RUNS' antialiased hiz is only a test of that code if the scenes the
    extremes start from have outline pixels: there it must change some pixels."""
    gb = scene(kind)
    args = (gb["position"], gb["normal"], gb["projection"])
    one = glint_core.trace(*args, march="hiz", **BASE)
    aa = glint_core.trace(*args, march="hiz", antialias=4, **BASE)
    changed = (one != aa).any(axis=-1).sum()
    assert changed >= 50, changed


def scene(kind="persp", w=64, h=48, **cam):
    key = (kind, w, h, tuple(sorted(cam.items())))
    if key not in _scene_cache:
        sc = A.mirror_floor_scene(kind)
        for k, v in cam.items():
            setattr(sc.camera, k, v)
        _scene_cache[key] = A.render(sc, w, h)
    return {k: (v.copy() if isinstance(v, np.ndarray) else v) for k, v in _scene_cache[key].items()}


PARAM_CASES = {
    "resolution_0": dict(resolution=0.0),
    "resolution_1": dict(resolution=1.0),
    "steps_0": dict(steps=0),
    "steps_1000": dict(steps=1000),
    "thickness_0": dict(thickness=0.0),
    "thickness_1e6": dict(thickness=1e6),
    "max_distance_0": dict(max_distance=0.0),
    "max_distance_1e6": dict(max_distance=1e6),
    "all_huge": dict(max_distance=1e6, resolution=1.0, steps=1000, thickness=1e6),
}


@pytest.mark.parametrize("kind", ["persp", "ortho"])
@pytest.mark.parametrize("case", list(PARAM_CASES))
def test_parameter_extremes(case, kind):
    run_all(scene(kind), **PARAM_CASES[case])


def test_zero_parameters_find_nothing():
    """resolution 0 (no first pass), steps 0 (no bisection), thickness 0 (no
    depth fits) and max_distance 0 (no ray): the seed reports no hit at all."""
    gb = scene()
    for params in (dict(resolution=0.0), dict(steps=0), dict(thickness=0.0), dict(max_distance=0.0)):
        uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], **dict(BASE, **params))
        assert np.all(uv[..., 2] == 0), params
    uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], march="linear",
                          **dict(BASE, steps=0))
    assert np.all(uv == 0)


def test_huge_max_distance_costs_only_the_screen():
    """max_distance 1e6 on a 64 x 64 image: first-pass sample counts in the
    millions per pixel if the march walked them all; it must still return
    (the guard is the only timing here)."""
    gb = scene(w=64, h=64)
    for res in (0.3, 1.0):
        uv = guarded(glint_core.trace, gb["position"], gb["normal"], gb["projection"],
                     max_distance=1e6, resolution=res, steps=1000)
        check_uv(uv, gb["position"].shape)
        assert (uv[..., 2] > 0).sum() > 100  # it still finds reflections


def test_near_1e_4_far_1e7():
    gb = scene(near=1e-4, far=1e7)
    assert np.isfinite(gb["projection"]).all()
    out = run_all(gb)
    assert (out["uv"][..., 2] > 0).sum() > 100
    run_all(gb, max_distance=1e6, resolution=1.0)


def _wall(w, h, kind="persp", vd=5.0):
    """A wall facing the camera at view distance vd, exactly: every pixel's
    view position is built from the projection, normals (0, 0, 1)."""
    proj = A.projection_matrix(kind, w, h, fov=math.radians(60), ortho_scale=8.0)
    nx, ny = A.pixel_ndc(w, h)
    pos = np.zeros((h, w, 4))
    if kind == "persp":
        pos[..., 0] = (nx - proj[0, 2]) / proj[0, 0] * vd
        pos[..., 1] = (ny - proj[1, 2]) / proj[1, 1] * vd
    else:
        pos[..., 0] = (nx - proj[0, 3]) / proj[0, 0]
        pos[..., 1] = (ny - proj[1, 3]) / proj[1, 1]
    pos[..., 2] = -vd
    pos[..., 3] = 1.0
    nrm = np.zeros((h, w, 3))
    nrm[..., 2] = 1.0
    spec = np.zeros((h, w, 4), np.float32)
    spec[...] = (1.0, 1.0, 1.0, 1.0)
    color = np.ones((h, w, 4), np.float32)
    color[..., 0] = np.linspace(0, 1, w)[None, :]
    return dict(position=pos.astype(np.float32), normal=nrm.astype(np.float32), specular=spec,
                color=color, projection=proj)


def _aim(gb, rows, cols, direction):
    """Set the normals of the given pixels so their mirror ray is exactly
    ``direction`` (reflect(u, n) = r for n = normalize(r - u))."""
    p = gb["position"][rows, cols, :3].astype(np.float64)
    if gb["projection"][3, 3] == 1.0:  # orthographic: every view ray runs along -z
        u = np.broadcast_to(np.array([0.0, 0.0, -1.0]), p.shape)
    else:
        u = p / np.linalg.norm(p, axis=-1, keepdims=True)
    r = np.asarray(direction, float)
    r = r / np.linalg.norm(r)
    n = r - u
    gb["normal"][rows, cols] = (n / np.linalg.norm(n, axis=-1, keepdims=True)).astype(np.float32)


@pytest.mark.parametrize("kind", ["persp", "ortho"])
@pytest.mark.parametrize("axis", ["x", "y"])
def test_rays_parallel_to_image_axes(axis, kind):
    """Rays along the image axes (delta x or delta y exactly 0: the seed's
    mix() of both divisions would give NaN) find the step they run into.

    A 33 x 33 wall at distance 5; the centre row's (or column's) pixels get
    rays along +x (or +y) in view space, which stay on that row (column): its
    view y (x) is exactly 0. They lean slightly towards the camera, so they
    stay in front of their own half of the wall; the other half (x > 0, or
    y > 0) is moved 0.2 closer, so each ray passes behind it right after the
    middle.
    """
    w = h = 33
    gb = _wall(w, h, kind)
    c = 16
    if axis == "x":
        assert np.all(gb["position"][c, :, 1] == 0)
        near_half = (slice(None), slice(c + 1, None))
        rows, cols = np.full(c, c), np.arange(c)
        direction = (1.0, 0.0, 0.02)
    else:
        assert np.all(gb["position"][:, c, 0] == 0)
        near_half = (slice(c + 1, None), slice(None))
        rows, cols = np.arange(c), np.full(c, c)
        direction = (0.0, 1.0, 0.02)
    pos = gb["position"]
    if kind == "persp":  # keep the closer half on the same pixel rays
        pos[near_half][..., :3] *= 4.8 / 5.0
    else:
        pos[near_half][..., 2] = -4.8
    _aim(gb, rows, cols, direction)
    for res in (0.3, 1.0):
        uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], resolution=res,
                              max_distance=15.0, thickness=0.5)
        check_uv(uv, pos.shape)
        hit = uv[rows, cols]
        assert (hit[:, 2] > 0).all(), f"resolution {res}: some axis-parallel rays found nothing"
        along, across = (0, 1) if axis == "x" else (1, 0)
        size = (w, h)[along]
        # The first texel of the closer half, c + 1, within a pixel.
        assert np.all(np.abs(hit[:, along] * size - (c + 1)) <= 1.0), hit[:, along] * size
        np.testing.assert_allclose(hit[:, across], 0.5, atol=1e-6)
    run_all(gb)


@pytest.mark.parametrize("kind", ["persp", "ortho"])
def test_rays_straight_back_at_the_camera(kind):
    """Mirror rays pointing back along the incoming ray (normal = -direction):
    through the eye, cut at the near plane; the fade-out makes them invisible."""
    gb = _wall(24, 16, kind)
    p = gb["position"][..., :3].astype(np.float64)
    gb["normal"][...] = (-p / np.linalg.norm(p, axis=-1, keepdims=True)).astype(np.float32)
    out = run_all(gb)
    assert np.all(out["uv"][..., 2] <= 1e-5)
    run_all(gb, max_distance=1e6, resolution=1.0, steps=1000)


@pytest.mark.parametrize("height", [1e-3, 1e-6])
def test_grazing_rays_along_a_floor(height):
    """A camera just above a mirror floor looking at the horizon: every mirror
    ray skims the floor."""
    sc = A.Scene([A.Plane((0, 0, 0), (0, 0, 1), A.MIRROR),
                  A.Sphere((0, 6, 0.5), 0.5, A.RED)],
                 A.Camera(eye=(0, 0, height), target=(0, 10, height), near=height / 10, far=1e4))
    gb = A.render(sc, 64, 48)
    assert (gb["object"] == 0).sum() > 500
    run_all(gb)
    run_all(gb, resolution=1.0, steps=1000, max_distance=1e6)


def test_normals_perpendicular_to_the_view_ray():
    """n . u = 0: the mirror ray continues along the view ray, away from the
    camera, and projects onto a single point."""
    gb = _wall(24, 16)
    p = gb["position"][..., :3].astype(np.float64)
    u = p / np.linalg.norm(p, axis=-1, keepdims=True)
    n = np.cross(u, [0.0, 1.0, 0.0])
    gb["normal"][...] = (n / np.linalg.norm(n, axis=-1, keepdims=True)).astype(np.float32)
    run_all(gb)


BAD_VALUES = [np.nan, np.inf, -np.inf]


def _poisoned():
    gb = scene()
    rng = np.random.default_rng(7)
    h, w = gb["position"].shape[:2]
    picks = rng.choice(h * w, size=(5, 40), replace=False)
    for k, idx in enumerate(picks[:3]):  # NaN / +Inf / -Inf in position xyz
        gb["position"].reshape(-1, 4)[idx, k % 3] = BAD_VALUES[k]
    gb["position"].reshape(-1, 4)[picks[3], 3] = np.nan  # and in w
    bad_normal = picks[4]
    gb["normal"].reshape(-1, 3)[bad_normal[:10]] = np.nan
    gb["normal"].reshape(-1, 3)[bad_normal[10:20], 1] = np.inf
    gb["normal"].reshape(-1, 3)[bad_normal[20:]] = 0.0
    gb["specular"].reshape(-1, 4)[picks[0][:10]] = np.nan
    return gb, picks


def test_non_finite_and_zero_values_in_the_buffers():
    gb, picks = _poisoned()
    out = run_all(gb)
    for run in MARCH_RUNS:
        uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], **run)
        # Those pixels themselves read as nothing seen / no normal: (0, 0, 0, 0).
        for idx in picks:
            assert np.all(uv.reshape(-1, 4)[idx] == 0), run
    assert (out["uv"][..., 2] > 0).sum() > 100  # the rest still reflects


@pytest.mark.parametrize("h, w", [(1, 1), (1, 4096), (4096, 1), (2, 3)])
def test_tiny_and_thin_images(h, w):
    gb = scene(w=w, h=h)
    run_all(gb)
    run_all(gb, resolution=1.0, steps=1000, max_distance=1e6)


def test_single_pixel_exact_values():
    """A lone seen pixel has nothing to hit: both marches report zero visibility;
    a lone unseen pixel reports (0, 0, 0, 0)."""
    pos = np.array([[[0.0, 0.0, -3.0, 1.0]]], np.float32)
    nrm = np.array([[[0.0, 0.6, 0.8]]], np.float32)
    proj = A.projection_matrix("persp", 1, 1)
    for run in MARCH_RUNS:
        uv = glint_core.trace(pos, nrm, proj, resolution=1.0, **run)
        assert uv[0, 0, 2] == 0
        pos[0, 0, 3] = 0.0
        assert np.all(glint_core.trace(pos, nrm, proj, **run) == 0)
        pos[0, 0, 3] = 1.0

"""glint_core.trace (float32 C++) against reference_seed.py (float64 Python loops).

Both implement the same text (the seed chapter + the fixes of docs/conventions.md, the book's
linear march), so they must agree pixel for pixel: uv within 1e-3 and
visibility within 1e-3 on >= 99% of the pixels of every scene and parameter
set (see ``agreement`` for uv far off screen).

Where a discrete decision of a pixel (which texel a probe falls in, a depth
against 0 or the thickness, int(delta)) sat closer to its threshold than
float32 resolves, the reference also computes the outcome with that decision
taken the other way (reference_seed.py, "Rounding alternatives"); the core
agrees with the reference on a pixel when it matches the nominal outcome or
one of those. The seed's bisection converges onto texel edges by design (with
resolution 1 its first probe lies exactly on one), so this is common.

Seed rays that reach the near plane and are shortened there (fix 2 of docs/conventions.md) get
their own share and their own test: their end point sits on the plane, where
float32 rounding decides which side it lands on. The plain share (nominal
outcome only) is printed too.
"""
import numpy as np
import pytest

import analytic as A
import glint_core
import reference_seed as R


def _scaled(scene_fn, factor):
    """The same camera with clip coordinates scaled: an invertible projection
    that is neither of the two standard forms (the core's general path)."""
    def make(w, h):
        sc = scene_fn()
        gb = A.render(sc, w, h)
        gb["projection"] = gb["projection"] * factor
        return gb
    return make


def _plain(scene_fn):
    return lambda w, h: A.render(scene_fn(), w, h)


SCENES = {
    "persp": _plain(lambda: A.mirror_floor_scene("persp")),
    "persp_shift": _plain(lambda: A.mirror_floor_scene("persp", shift=(0.2, 0.1))),
    "ortho": _plain(lambda: A.mirror_floor_scene("ortho")),
    "persp_general": _scaled(lambda: A.mirror_floor_scene("persp"), 2.5),
}

SEED_PARAMS = {
    "default": dict(max_distance=15.0, resolution=0.3, steps=10, thickness=0.5),
    "fine_thin": dict(max_distance=10.0, resolution=0.7, steps=12, thickness=0.3),
    "coarse_thick": dict(max_distance=8.0, resolution=0.15, steps=5, thickness=1.5),
    # Resolution 1: the first bisection probe lies exactly on a texel edge.
    "pixel_steps": dict(max_distance=15.0, resolution=1.0, steps=8, thickness=0.5),
}

LINEAR_PARAMS = {
    "ten_steps": dict(max_distance=15.0, steps=10, thickness=0.5),
    "book": dict(max_distance=15.0, steps=100, thickness=1.0),
    "short": dict(max_distance=8.0, steps=37, thickness=0.3),
}

SIZE = (64, 48)
SMALL = (48, 36)  # for resolution 1, whose first pass visits every pixel

SEED_CASES = [(scene, params) for scene in SCENES for params in SEED_PARAMS
              if params != "pixel_steps" or scene in ("persp", "ortho")]

_gbufs = {}


def gbuf(scene, size=SIZE):
    if (scene, size) not in _gbufs:
        _gbufs[scene, size] = SCENES[scene](*size)
    return _gbufs[scene, size]


def near_cut(gb, max_distance):
    """Seen pixels whose seed ray the near plane shortens (float64 geometry of
    the float32 buffers, as the reference computes it)."""
    p = gb["position"][..., :3].astype(np.float64).reshape(-1, 3)
    n = gb["normal"][..., :3].astype(np.float64).reshape(-1, 3)
    with np.errstate(invalid="ignore", divide="ignore"):
        u = p / np.linalg.norm(p, axis=1, keepdims=True)
        n = n / np.linalg.norm(n, axis=1, keepdims=True)
        pivot = u - 2.0 * np.einsum("ij,ij->i", u, n)[:, None] * n
        pivot /= np.linalg.norm(pivot, axis=1, keepdims=True)
    length = A.near_plane_length(gb["projection"], p, pivot, max_distance)
    return ((length < R._f32(max_distance)) & (gb["position"][..., 3].ravel() > 0)).reshape(
        gb["position"].shape[:2])


def agreement(core, ref):
    """uv within 1e-3 and visibility within 1e-3, per pixel.

    A uv far outside [0, 1] (the last probe of a miss, many image widths
    away) is compared relative to its size: it comes from an end point on the
    near plane, where w is small and every rounding of the end is magnified."""
    uv_tol = 1e-3 * np.maximum(1.0, np.abs(ref[..., :2]))
    return ((np.abs(core[..., :2] - ref[..., :2]) <= uv_tol).all(axis=-1)
            & (np.abs(core[..., 2:] - ref[..., 2:]).max(axis=-1) <= 1e-3))


def run_both(gb, march, params):
    """(core, reference, plain agreement, agreement allowing rounding alternatives,
    pixels with an ambiguous decision)."""
    ref, alt, n_amb = R.trace(gb["position"], gb["normal"], gb["projection"], march=march,
                              alternatives=True, **params)
    core = glint_core.trace(gb["position"], gb["normal"], gb["projection"], march=march, **params)
    plain = agreement(core, ref)
    agree = plain.copy()
    for i in range(alt.shape[2]):
        agree |= agreement(core, alt[:, :, i])
    return core, ref, plain, agree, n_amb > 0


def _report(label, plain, agree, ambiguous, cut, ref):
    near = f", near-cut rays {agree[cut].mean():.2%} of {cut.sum()}" if cut.any() else ""
    print(f"\n{label}: agreement {agree.mean():.2%} ({(ref[..., 2] > 0).sum()} reference hits"
          f"{near}); plain agreement {plain.mean():.2%}, "
          f"{ambiguous.mean():.2%} of pixels took a decision at the rounding limit")


def _save(artifacts, core, ref, agree):
    artifacts.add("core", core[..., :3], 0, 1)
    artifacts.add("reference", ref[..., :3], 0, 1)
    artifacts.add("disagree", ~agree)


@pytest.mark.parametrize("scene, params", SEED_CASES)
def test_seed_agrees_with_reference(scene, params, artifacts):
    gb = gbuf(scene, SMALL if params == "pixel_steps" else SIZE)
    p = SEED_PARAMS[params]
    core, ref, plain, agree, ambiguous = run_both(gb, "seed", p)
    cut = near_cut(gb, p["max_distance"])
    _report(f"seed {scene}/{params}", plain, agree, ambiguous, cut, ref)
    _save(artifacts, core, ref, agree)
    seen = gb["position"][..., 3] > 0
    assert (ref[..., 2] > 0).sum() >= 100, "too few hits to compare"
    assert agree.mean() >= 0.99
    # Unseen pixels are (0, 0, 0, 0) in both, exactly.
    assert np.all(core[~seen] == 0) and np.all(ref[~seen] == 0)


@pytest.mark.parametrize("params", list(LINEAR_PARAMS))
@pytest.mark.parametrize("scene", ["persp", "ortho", "persp_general"])
def test_linear_agrees_with_reference(scene, params, artifacts):
    gb = gbuf(scene)
    core, ref, plain, agree, ambiguous = run_both(gb, "linear", LINEAR_PARAMS[params])
    _report(f"linear {scene}/{params}", plain, agree, ambiguous, np.zeros_like(ambiguous), ref)
    _save(artifacts, core, ref, agree)
    assert (ref[..., 2] > 0).sum() >= 100
    assert agree.mean() >= 0.99


@pytest.mark.parametrize("scene", ["persp", "persp_shift"])
def test_near_cut_rays_agree(scene, artifacts):
    """Rays heading back towards the camera, cut at the near plane: the core
    must march the whole cut ray as the reference does (an earlier core
    halved it whenever the float end point rounded to behind the plane)."""
    gb = gbuf(scene)
    p = SEED_PARAMS["default"]
    core, ref, plain, agree, ambiguous = run_both(gb, "seed", p)
    cut = near_cut(gb, p["max_distance"])
    print(f"\nseed {scene}/default near-cut rays: {cut.sum()}, agree {agree[cut].mean():.2%}")
    _save(artifacts, core, ref, agree)
    assert cut.sum() >= 100
    assert agree[cut].mean() >= 0.99


def _hand_buffers():
    """An 8 x 1 orthographic strip, 1 px per unit: pixel 0 is a mirror at
    view distance 5 whose ray runs right and slightly towards the camera;
    texels 1-4 lie behind the ray (distance 5.3), texels 5-7 in front of it
    (4.6), so the first hit is texel 5."""
    proj = A.projection_matrix("ortho", 8, 1, ortho_scale=8.0, near=0.1, far=100.0)
    x = -4.0 + (np.arange(8) + 0.5)
    vd = np.array([5.0, 5.3, 5.3, 5.3, 5.3, 4.6, 4.6, 4.6])
    pos = np.zeros((1, 8, 4), np.float32)
    pos[0, :, 0], pos[0, :, 2], pos[0, :, 3] = x, -vd, 1.0
    nrm = np.zeros((1, 8, 3), np.float32)
    nrm[0, :, 2] = 1.0
    p0 = pos[0, 0, :3].astype(np.float64)
    u = np.array([0.0, 0.0, -1.0])  # an orthographic camera's view ray, the same for every pixel
    r = np.array([1.0, 0.0, 0.05]) / np.linalg.norm([1.0, 0.0, 0.05])
    n = (r - u) / np.linalg.norm(r - u)  # reflect(u, n) == r
    nrm[0, 0] = n
    return pos, nrm, proj, p0, u, r


def test_hand_computed_seed_pixel():
    pos, nrm, proj, p0, u, r = _hand_buffers()
    # Seed, resolution 0.5, max_distance 15: the ray spans 15 px (x grows 1 px
    # per unit, r.x ~ 0.99875), so delta = 7.49, probes every 2 px from 0.5:
    # 2.5, 4.5 (behind nothing: miss), 6.5 (texel 6, 4.6 < ray): first hit.
    # One bisection step probes halfway between 4.5 and 6.5, i.e. 5.5: texel
    # 5, a hit, and the last probe.
    end_x = p0[0] + 4.0 + r[0] * 15.0 + 0.0  # frag x of the end (1 px per unit)
    frac = (5.5 - 0.5) / (end_x - 0.5)
    ray_vd = 5.0 - r[2] * 15.0 * frac  # orthographic: linear in screen
    depth = ray_vd - 4.6
    p5 = pos[0, 5, :3].astype(np.float64)
    vis = ((1.0 - max(np.dot(-u, r), 0.0)) * (1.0 - depth / 0.5)
           * (1.0 - np.linalg.norm(p5 - p0) / 15.0))
    expect = np.array([5.5 / 8.0, 0.5, vis, vis])
    kw = dict(max_distance=15.0, resolution=0.5, steps=1, thickness=0.5)
    ref = R.trace_seed(pos, nrm, proj, **kw)[0, 0]
    core = glint_core.trace(pos, nrm, proj, march="seed", **kw)[0, 0]
    print(f"\nhand {expect}\nref  {ref}\ncore {core}")
    assert 0.0 < vis < 1.0
    np.testing.assert_allclose(ref, expect, atol=1e-6)
    np.testing.assert_allclose(core, expect, atol=1e-5)


def test_hand_computed_linear_pixel():
    pos, nrm, proj, p0, u, r = _hand_buffers()
    # Linear, 15 steps of 1 unit: samples at x frag 0.5 + r.x * d; d = 1..4 land
    # on texels 1-4 (5.3 > ray: miss), d = 5 on texel 5 (4.6 <= ray <= 5.1):
    # hit. The step back restarts at 4 * (1 / 11) units (the book's quirk),
    # and every later sample stays over texels 0-1, in front of both.
    d = 5.0
    frag_x = 0.5 + r[0] * d
    vis = 1.0 - max(np.dot(r, -u), 0.0)
    expect = np.array([frag_x / 8.0, 0.5, vis, vis])
    kw = dict(max_distance=15.0, steps=15, thickness=0.5)
    ref = R.trace_linear(pos, nrm, proj, **kw)[0, 0]
    core = glint_core.trace(pos, nrm, proj, march="linear", **kw)[0, 0]
    print(f"\nhand {expect}\nref  {ref}\ncore {core}")
    np.testing.assert_allclose(ref, expect, atol=1e-6)
    np.testing.assert_allclose(core, expect, atol=1e-5)

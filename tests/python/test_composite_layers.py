"""composite_layers(): the add-on's per-frame images in one call, held to the
separate calls it stands for (trace, specular_weight, cone_lod) and to a float32
reference of the uv continuation written here."""
import numpy as np
import pytest

import analytic as A
import glint_core


def continued_reference(uv, rings):
    """Plain loops: each ring of misses next to known pixels takes the mean uv of
    its known 3x3 neighbours, summed in float32 in the order dy, dx = -1..1."""
    out = uv.astype(np.float32).copy()
    h, w = out.shape[:2]
    known = out[..., 2] > 0
    for _ in range(rings):
        before = known.copy()
        for y in range(h):
            for x in range(w):
                if before[y, x]:
                    continue
                acc, n = np.zeros(2, np.float32), np.float32(0)
                for dy in (-1, 0, 1):
                    for dx in (-1, 0, 1):
                        yy, xx = y + dy, x + dx
                        if 0 <= yy < h and 0 <= xx < w and before[yy, xx]:
                            acc += out[yy, xx, :2]
                            n += np.float32(1)
                if n:
                    out[y, x, :2] = acc / n
                    known[y, x] = True
    return out


def test_misses_take_their_neighbours_uv_and_stay_misses():
    uv = np.zeros((3, 5, 4), np.float32)
    uv[1, 1] = (0.2, 0.4, 1.0, 1.0)
    uv[1, 2] = (0.4, 0.6, 0.5, 0.5)
    out = glint_core.continue_missing_uv(uv, rings=1)
    assert np.array_equal(out[..., 2:], uv[..., 2:])  # visibility and alpha untouched
    assert np.array_equal(out[1, 1], uv[1, 1])  # hits untouched
    assert np.allclose(out[1, 0, :2], (0.2, 0.4))  # one hit neighbour
    assert np.allclose(out[0, 1, :2], (0.3, 0.5))  # two hit neighbours: their mean
    assert np.allclose(out[1, 3, :2], (0.4, 0.6))
    assert np.array_equal(out[1, 4, :2], (0, 0))  # two rings away: not with one ring
    assert np.allclose(glint_core.continue_missing_uv(uv, rings=2)[1, 4, :2], (0.4, 0.6))
    assert np.array_equal(glint_core.continue_missing_uv(np.zeros((2, 2, 4), np.float32)), np.zeros((2, 2, 4)))


@pytest.mark.parametrize("rings", [0, 1, 2, 3])
def test_continuation_matches_the_reference_bit_for_bit(rings):
    rng = np.random.default_rng(rings)
    uv = rng.uniform(0, 1, (23, 31, 4)).astype(np.float32)
    uv[..., 2] *= rng.uniform(size=(23, 31)) > 0.85  # sparse hits, wide gaps
    uv[uv[..., 2] == 0, :2] = 0
    assert np.array_equal(glint_core.continue_missing_uv(uv, rings=rings), continued_reference(uv, rings))


def test_negative_rings_are_refused():
    with pytest.raises(ValueError, match="rings"):
        glint_core.continue_missing_uv(np.zeros((2, 2, 4), np.float32), rings=-1)


@pytest.fixture(scope="module")
def rough_floor():
    gb = A.render(A.mirror_floor_scene(), 160, 120)
    spec = gb["specular"].copy()
    spec[..., 3] = np.where(spec[..., :3].mean(-1) > 0, 0.6, spec[..., 3])  # rough enough for a blur
    return gb, spec


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_layers_are_the_separate_calls_in_one(rough_floor, backend, request):
    if backend == "gl":
        request.getfixturevalue("gl")
    gb, spec = rough_floor
    proj = gb["projection"].astype(np.float32)
    kw = dict(glint_core.presets()["balanced"], backend=backend)
    layers = glint_core.composite_layers(gb["position"], gb["normal"], spec, proj, **kw)
    uv = glint_core.trace(gb["position"], gb["normal"], proj, specular=spec, **kw)
    want_uv = continued_reference(uv, 2)
    want_uv[..., 3] = 1
    assert np.array_equal(layers["uv"], want_uv)
    weight = glint_core.specular_weight(gb["position"], gb["normal"], spec, proj, backend=backend)
    assert np.array_equal(layers["weight"][..., :3], weight[..., :3])
    lod = glint_core.cone_lod(uv, spec)
    assert np.array_equal(layers["weight"][..., 3], lod)
    seen = gb["position"][..., 3] > 0
    assert layers["reflective_pixels"] == int((seen & (spec[..., :3].mean(-1) > 0)).sum()) > 0
    assert layers["any_rough"] == bool((lod > 0).any()) is True


def test_a_mirror_frame_is_not_rough_and_an_unreflective_one_is_not_traced():
    gb = A.render(A.mirror_floor_scene(), 64, 48)
    proj = gb["projection"].astype(np.float32)
    mirror = gb["specular"].copy()
    mirror[..., 3] = 1.0
    layers = glint_core.composite_layers(gb["position"], gb["normal"], mirror, proj, march="hiz")
    assert layers["reflective_pixels"] > 0 and not layers["any_rough"]
    assert (layers["uv"][..., 2] > 0).any()
    none = glint_core.composite_layers(gb["position"], gb["normal"], np.zeros_like(mirror), proj, march="hiz")
    assert none["reflective_pixels"] == 0 and not none["any_rough"]
    assert not none["uv"].any() and not none["weight"].any()


def test_the_specular_buffer_is_required():
    gb = A.render(A.mirror_floor_scene(), 16, 12)
    with pytest.raises(ValueError, match="specular"):
        glint_core.composite_layers(gb["position"], gb["normal"], None, gb["projection"])

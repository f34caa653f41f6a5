"""The add-on's texel rules (logic/texels.py: seen, specular amount, reflective)
against values worked out here by hand, and against glint_core, which counts a
pixel as reflective when it is seen and its specular reflects
(``composite_layers``' ``reflective_pixels``, glint/material.h). The material
side (SpecularSpec.reflective, which the material table and the scene scan
ask) goes through the core's rasterizer first, as a material does in a frame."""
import itertools
import math

import numpy as np
import pytest

from glint_addon_helpers import load_logic

texels = load_logic("texels")
materials = load_logic("materials")

INF, NAN = math.inf, math.nan
TINY = 2.0 ** -149  # float32's smallest positive value (a denormal)

# (x, y, z, w) -> seen: w > 0 and all four channels finite (docs/conventions.md).
POSITIONS = [
    ((0.0, 0.0, -1.0, 1.0), True),
    ((0.0, 0.0, -1.0, 0.0), False),
    ((0.0, 0.0, -1.0, 0.25), True),  # below the add-on's old 0.5, above the core's 0
    ((0.0, 0.0, -1.0, 0.5), True),
    ((0.0, 0.0, -1.0, TINY), True),
    ((0.0, 0.0, -1.0, -1.0), False),
    ((NAN, 0.0, -1.0, 1.0), False),
    ((0.0, INF, -1.0, 1.0), False),
    ((0.0, 0.0, -INF, 1.0), False),
    ((0.0, 0.0, -1.0, NAN), False),
    ((0.0, 0.0, -1.0, INF), False),
    ((3e38, 3e38, -1.0, 1.0), True),  # finite channels whose float32 sum overflows
    ((-3e38, -3e38, -3e38, 1.0), True),
]

# (r, g, b, shininess alpha) -> reflective: float32 (r + g + b) / 3 positive and finite.
SPECULARS = [
    ((0.3, 0.6, 0.9, 0.25), True),
    ((0.0, 0.0, 0.0, 1.0), False),
    ((0.0, 0.0, 1e-6, 0.0), True),  # the shininess plays no part
    ((1.0, -1.0, 0.0, 1.0), False),  # mean 0
    ((-0.5, 1.0, 0.0, 1.0), True),  # mean 1/6
    ((NAN, 1.0, 1.0, 1.0), False),
    ((INF, 1.0, 1.0, 1.0), False),
    ((-INF, 1.0, 1.0, 1.0), False),
    ((TINY, 0.0, 0.0, 1.0), False),  # a third of the smallest float32 rounds to 0
    ((TINY, TINY, TINY, 1.0), True),  # 3 x TINY / 3 = TINY, exactly
    ((3e38, 3e38, 0.0, 1.0), False),  # the float32 sum overflows to inf
]


def test_seen_by_hand():
    p = np.array([p for p, _ in POSITIONS], np.float32)
    assert texels.texel_seen(p).tolist() == [want for _, want in POSITIONS]
    # one texel at a time (a 0-d answer) and as a frame agree
    assert [bool(texels.texel_seen(np.float32(q))) for q in p] == [want for _, want in POSITIONS]


def test_reflective_by_hand():
    s = np.array([s for s, _ in SPECULARS], np.float32)
    assert texels.is_reflective(s).tolist() == [want for _, want in SPECULARS]
    assert [bool(texels.is_reflective(q)) for q in s] == [want for _, want in SPECULARS]
    assert texels.specular_amount(np.array([0.25, 0.5, 0.75, 0.0], np.float32)) == 0.5
    assert texels.specular_amount(np.array([[1.0, 2.0, 6.0]], np.float32)).tolist() == [3.0]


def test_the_mask_is_seen_and_reflective():
    pairs = list(itertools.product(POSITIONS, SPECULARS))
    p = np.array([[p for (p, _), _ in pairs]], np.float32)
    s = np.array([[s for _, (s, _) in pairs]], np.float32)
    want = [seen and refl for (_, seen), (_, refl) in pairs]
    assert texels.reflective_mask(p, s)[0].tolist() == want


def _projection(w, h):
    """A 60-degree perspective (OpenGL's, as Blender's camera gives it), near 0.1, far 100."""
    f = 1.0 / math.tan(math.radians(30.0))
    n, fa = 0.1, 100.0
    return np.array([[f * h / w, 0, 0, 0], [0, f, 0, 0],
                     [0, 0, (fa + n) / (n - fa), 2 * fa * n / (n - fa)], [0, 0, -1, 0]], np.float32)


def _core_reflective_pixels(core, position, specular):
    normal = np.zeros_like(position)
    normal[..., 2] = normal[..., 3] = 1.0
    h, w = position.shape[:2]
    out = core.composite_layers(position, normal, specular, _projection(w, h), backend="cpu", threads=1)
    return int(out["reflective_pixels"])


def test_the_core_counts_the_same_texels(core):
    # Every pair on its own 1x1 frame: the core's answer per texel, beside
    # the hand-worked one and the add-on's.
    for (p, seen), (s, refl) in itertools.product(POSITIONS, SPECULARS):
        position = np.array([[p]], np.float32)
        specular = np.array([[s]], np.float32)
        want = seen and refl
        assert _core_reflective_pixels(core, position, specular) == int(want), (p, s)
        assert bool(texels.reflective_mask(position, specular)[0, 0]) == want, (p, s)


def test_the_core_counts_a_frame_as_the_addon_does(core):
    rng = np.random.default_rng(24)
    h, w = 48, 64
    position = rng.uniform(-5, 5, (h, w, 4)).astype(np.float32)
    position[..., 2] = -np.abs(position[..., 2]) - 0.1
    position[..., 3] = rng.choice([0.0, 0.25, 1.0], (h, w))
    specular = rng.uniform(-0.2, 1.0, (h, w, 4)).astype(np.float32)
    specular[rng.uniform(size=(h, w)) < 0.3, :3] = 0.0
    position[rng.uniform(size=(h, w)) < 0.05, 0] = np.nan
    specular[rng.uniform(size=(h, w)) < 0.05, 1] = np.inf
    mask = texels.reflective_mask(position, specular)
    assert 0 < mask.sum() < h * w
    assert _core_reflective_pixels(core, position, specular) == int(mask.sum())


# SpecularSpec colour -> reflective, worked out on the float32 the G-buffer holds.
MATERIALS = [
    ((0.04, 0.04, 0.04), True),
    ((0.0, 0.0, 0.0), False),
    ((1e-46, 0.0, 0.0), False),  # positive as a double, 0 as a float32
    ((1e-40, 0.0, 0.0), True),  # a float32 denormal, and so is a third of it
    ((-0.5, 1.0, 0.0), True),
    ((1.0, -1.0, 0.0), False),
]


@pytest.mark.parametrize("colour, want", MATERIALS)
def test_a_material_reflects_where_the_core_traces_its_pixels(core, colour, want):
    spec = materials.SpecularSpec(colour, 64.0)
    assert spec.reflective is want
    w = h = 8
    # Two triangles over the whole frame at z = -2.
    quad = np.array([[[-5, -5, -2], [5, -5, -2], [5, 5, -2]], [[-5, -5, -2], [5, 5, -2], [-5, 5, -2]]], np.float32)
    normals = np.zeros_like(quad)
    normals[..., 2] = 1.0
    rows = np.array([materials.NO_SPECULAR.row(), spec.row()], np.float32)
    gbuf = core.rasterize(quad, normals, np.ones(2, np.int32), rows, _projection(w, h), w, h, backend="cpu")
    assert np.all(gbuf["position"][..., 3] == 1.0)
    assert np.array_equal(gbuf["specular"][..., :3], np.broadcast_to(np.float32(colour), (h, w, 3)))
    assert _core_reflective_pixels(core, gbuf["position"], gbuf["specular"]) == (w * h if want else 0)
    assert materials.NO_SPECULAR.reflective is False

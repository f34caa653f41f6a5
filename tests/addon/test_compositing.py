"""The compositor group, run on numpy arrays, against the core's combine formula
written out here, and (when the build is there) against glint_core's own stages."""
import numpy as np
import pytest

from glint_addon_helpers import load_logic

cg = load_logic("compositing")

INPUTS = {"CompositorNodeMath": 3, "CompositorNodeMixRGB": 3, "CompositorNodeSeparateColor": 1,
          "CompositorNodeCombineColor": 4, "CompositorNodeMapUV": 2, "CompositorNodeBlur": 2,
          "CompositorNodeSwitch": 2, "CompositorNodeImage": 0}
OUTPUTS = {"CompositorNodeSeparateColor": 4, "CompositorNodeImage": 2}


def test_links_name_real_nodes_and_sockets():
    targets = set()
    for src, so, dst, di in cg.GROUP_LINKS:
        if src == cg.GROUP_IN:
            assert so < len(cg.GROUP_INPUTS)
        else:
            kind = cg.GROUP_NODES[src][0]
            assert so < OUTPUTS.get(kind, 1), (src, so)
        if dst == cg.GROUP_OUT:
            assert di < len(cg.GROUP_OUTPUTS)
        else:
            assert di < INPUTS[cg.GROUP_NODES[dst][0]], (dst, di)
        assert (dst, di) not in targets, f"input {dst}[{di}] linked twice"
        targets.add((dst, di))
    assert {(cg.GROUP_OUT, i) for i in range(len(cg.GROUP_OUTPUTS))} <= targets


# -- an independent reference of the core's combine ---------------------------

def bilinear_clamp(img, u, v):
    h, w = img.shape[:2]
    x = u * w - 0.5
    y = v * h - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    ax = (x - x0)[..., None]
    ay = (y - y0)[..., None]
    xi0 = np.clip(x0, 0, w - 1).astype(int)
    xi1 = np.clip(x0 + 1, 0, w - 1).astype(int)
    yi0 = np.clip(y0, 0, h - 1).astype(int)
    yi1 = np.clip(y0 + 1, 0, h - 1).astype(int)
    bottom = img[yi0, xi0] * (1 - ax) + img[yi0, xi1] * ax
    top = img[yi1, xi0] * (1 - ax) + img[yi1, xi1] * ax
    return bottom * (1 - ay) + top * ay


def box_clamp(img, size):
    if size == 0:
        return img.copy()
    h, w = img.shape[:2]
    out = np.zeros_like(img, dtype=np.float64)
    for dy in range(-size, size + 1):
        for dx in range(-size, size + 1):
            ys = np.clip(np.arange(h) + dy, 0, h - 1)
            xs = np.clip(np.arange(w) + dx, 0, w - 1)
            out += img[ys][:, xs]
    return (out / (2 * size + 1) ** 2).astype(np.float32)


def reference_combine(base, uv, spec, seen, size):
    vis = np.where(seen, uv[..., 2], 0.0)
    c = bilinear_clamp(base, uv[..., 0], uv[..., 1])
    C = np.concatenate([c[..., :3] * vis[..., None], vis[..., None]], axis=-1)
    C[vis <= 0] = 0
    B = box_clamp(C.astype(np.float32), size)
    amount = spec[..., :3].mean(-1)
    amount = np.where(seen & (amount > 0), amount, 0.0)
    r = 1 - np.clip(spec[..., 3], 0, 1)
    refl = (C * (1 - r[..., None]) + B * r[..., None]) * amount[..., None]
    a = np.clip(refl[..., 3], 0, 1)
    out = base.copy()
    out[..., :3] = base[..., :3] * (1 - a[..., None]) + refl[..., :3]
    return out, refl


def scene(h=12, w=16, seed=3):
    rng = np.random.default_rng(seed)
    base = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    base[..., 3] = 1
    position = np.zeros((h, w, 4), np.float32)
    position[..., 3] = (rng.uniform(size=(h, w)) > 0.2).astype(np.float32)
    spec = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    spec[rng.uniform(size=(h, w)) < 0.3, :3] = 0  # some non-reflective pixels
    uv = np.zeros((h, w, 4), np.float32)
    uv[..., :2] = rng.uniform(0, 1, (h, w, 2))
    uv[..., 2] = rng.uniform(0, 1, (h, w)) * (rng.uniform(size=(h, w)) > 0.3)
    uv[..., 3] = uv[..., 2]
    seen = position[..., 3] > 0.5
    spec[~seen] = 0  # as the rasterizer leaves pixels no triangle covers
    mask = cg.reflective_mask(position, spec)
    uv[~mask] = 0  # the trace reports nothing where it does not march
    return base, position, spec, uv, seen


def np_map_uv(image, uv_rgba):
    """Map UV modelled as a bilinear clamp-to-edge lookup premultiplied by the third channel."""
    vis = uv_rgba[..., 2:3]
    c = bilinear_clamp(image, uv_rgba[..., 0], uv_rgba[..., 1]) * vis
    return np.where(vis > 0, c, 0).astype(np.float32)


@pytest.mark.parametrize("size", [0, 1, 3])
def test_group_computes_the_core_combine(size):
    base, position, spec, uv, seen = scene()
    images = {cg.IMAGE_UV: cg.uv_image(uv), cg.IMAGE_MASK: spec,
              cg.IMAGE_DEBUG: np.zeros_like(base), cg.IMAGE_POSITION: position,
              cg.IMAGE_NORMAL: np.zeros_like(base), cg.IMAGE_SPECULAR: spec}
    out = cg.evaluate_group(base, images, np_map_uv, box_clamp, size)
    want, refl = reference_combine(base, uv, spec, seen, size)
    assert np.allclose(out["Image"], want, atol=1e-5)
    assert np.allclose(out["Reflection"][..., :3], refl[..., :3], atol=1e-5)
    assert np.allclose(out["Reflection"][..., 3], np.clip(refl[..., 3], 0, 1), atol=1e-5)
    assert np.array_equal(out["Base"], base)
    assert np.array_equal(out["Visibility"], uv[..., 2])


def test_nothing_reflective_leaves_the_base_bit_exact():
    base, position, spec, uv, seen = scene()
    spec[..., :3] = 0
    uv[:] = 0
    images = {cg.IMAGE_UV: cg.uv_image(uv), cg.IMAGE_MASK: spec,
              cg.IMAGE_DEBUG: base, cg.IMAGE_POSITION: position, cg.IMAGE_NORMAL: base, cg.IMAGE_SPECULAR: spec}
    out = cg.evaluate_group(base, images, np_map_uv, box_clamp, 2)
    assert np.array_equal(out["Image"], base)


def test_debug_switches():
    base, position, spec, uv, seen = scene()
    dbg = np.full_like(base, 0.25)
    images = {cg.IMAGE_UV: cg.uv_image(uv), cg.IMAGE_MASK: spec, cg.IMAGE_DEBUG: dbg,
              cg.IMAGE_POSITION: position, cg.IMAGE_NORMAL: base, cg.IMAGE_SPECULAR: spec}
    refl = cg.evaluate_group(base, images, np_map_uv, box_clamp, 1, debug_view="REFLECTION")
    assert np.array_equal(refl["Image"], refl["Reflection"])
    for view in cg.GBUFFER_DEBUG_VIEWS:
        assert np.array_equal(cg.evaluate_group(base, images, np_map_uv, box_clamp, 1, view)["Image"], dbg)
    assert cg.switch_states("NONE") == {"show_reflection": False, "show_debug": False}


def test_group_matches_glint_core_stages(core):
    base, position, spec, uv, seen = scene(20, 24, seed=7)
    size = 2
    color = core.reflection_color(uv, base)
    blurred = core.box_blur(color, size=size)
    masked_spec = np.where(cg.reflective_mask(position, spec)[..., None], spec, 0).astype(np.float32)
    refl = core.reflection(color, blurred, masked_spec)
    want = core.combine(base, refl)
    images = {cg.IMAGE_UV: cg.uv_image(uv), cg.IMAGE_MASK: spec,
              cg.IMAGE_DEBUG: base, cg.IMAGE_POSITION: position, cg.IMAGE_NORMAL: base, cg.IMAGE_SPECULAR: spec}
    out = cg.evaluate_group(base, images, lambda img, uvi: core.reflection_color(np.ascontiguousarray(uvi), img),
                            lambda img, s: core.box_blur(np.ascontiguousarray(img), size=s), size)
    assert np.allclose(out["Image"], want, atol=1e-6)


def test_mask_and_uv_images():
    position = np.zeros((1, 4, 4), np.float32)
    position[0, :, 3] = (1, 1, 0, 1)
    position[0, 3, 0] = np.nan
    spec = np.array([[[0.3, 0.6, 0.9, 0.25], [0, 0, 0, 1], [1, 1, 1, 1], [1, 1, 1, 1]]], np.float32)
    assert np.array_equal(cg.reflective_mask(position, spec)[0], (True, False, False, False))
    n = np.ones((1, 4, 4), np.float32)
    assert np.array_equal(cg.trace_normals(n, position, spec)[0, :, 0], (1, 0, 0, 0))
    uv = np.full((1, 4, 4), 0.5, np.float32)
    assert np.array_equal(cg.uv_image(uv)[0, 0], (0.5, 0.5, 0.5, 1.0))


def test_misses_get_their_neighbours_uv_and_stay_misses():
    uv = np.zeros((3, 5, 4), np.float32)
    uv[1, 1] = (0.2, 0.4, 1.0, 1.0)
    uv[1, 2] = (0.4, 0.6, 0.5, 0.5)
    out = cg.fill_missing_uv(uv, passes=1)
    assert np.array_equal(out[..., 2], uv[..., 2])  # visibility untouched
    assert np.array_equal(out[1, 1], uv[1, 1])  # hits untouched
    assert np.allclose(out[1, 0, :2], (0.2, 0.4))  # one hit neighbour
    assert np.allclose(out[0, 1, :2], (0.3, 0.5))  # two hit neighbours: their mean
    assert np.allclose(out[1, 3, :2], (0.4, 0.6))
    assert np.array_equal(out[1, 4, :2], (0, 0))  # two rings away: not with one pass
    assert np.allclose(cg.fill_missing_uv(uv, passes=2)[1, 4, :2], (0.4, 0.6))
    assert np.array_equal(cg.fill_missing_uv(np.zeros((2, 2, 4), np.float32)), np.zeros((2, 2, 4)))


def test_debug_images():
    position = np.zeros((1, 2, 4), np.float32)
    position[0, 0] = (1, 2, -3, 1)
    normal = np.zeros((1, 2, 4), np.float32)
    normal[0, 0, :3] = (0, 0, 1)
    spec = np.zeros((1, 2, 4), np.float32)
    spec[0, 0] = (0.5, 0.25, 0.125, 1)
    uv = np.zeros((1, 2, 4), np.float32)
    uv[0, 0] = (0.3, 0.7, 0.5, 0.5)
    assert np.array_equal(cg.debug_image("POSITION", position, normal, spec, uv)[0, 0], (1, 2, -3, 1))
    assert np.array_equal(cg.debug_image("NORMAL", position, normal, spec, uv)[0, 0], (0.5, 0.5, 1, 1))
    assert np.array_equal(cg.debug_image("NORMAL", position, normal, spec, uv)[0, 1], (0, 0, 0, 1))
    assert np.array_equal(cg.debug_image("SPECULAR", position, normal, spec, uv)[0, 0], (0.5, 0.25, 0.125, 1))
    assert np.allclose(cg.debug_image("UV", position, normal, spec, uv)[0, 0], (0.3, 0.7, 0, 1))
    assert np.array_equal(cg.debug_image("VISIBILITY", position, normal, spec, uv)[0, 0], (0.5, 0.5, 0.5, 1))
    with pytest.raises(ValueError):
        cg.debug_image("REFLECTION", position, normal, spec, uv)

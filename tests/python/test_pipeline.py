"""The pipeline's stages against formulas written out here in numpy, the
pipeline against its stages chained, its skipping rules, and one end-to-end
fact checked against the exact mirror geometry."""
import numpy as np
import pytest

import analytic as A
import glint_core

# The stages a default run (weighting "physical", blur "cone") reports.
STAGES = ["trace", "reflection_color", "specular_weight", "cone_blur", "reflection", "combine"]
# The seed's reflection and blur; test_look.py covers the physical ones.
SEED_LOOK = dict(weighting="seed", blur="box")


# --- formulas --------------------------------------------------------------------------


def bilinear(img, x, y):
    """img sampled at texel coordinates (x, y) (integer = texel centre),
    linear between texels, clamped to the edge: GL_LINEAR + CLAMP_TO_EDGE."""
    h, w = img.shape[:2]
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


def reflection_color_formula(uv, color):
    """The seed's reflection-colour pass: colour at the reflected uv, mixed
    from black by visibility; alpha = visibility."""
    color = color.astype(np.float64)
    h, w = color.shape[:2]
    vis = np.clip(uv[..., 2].astype(np.float64), 0, 1)
    c = bilinear(color, uv[..., 0] * w - 0.5, uv[..., 1] * h - 0.5)
    out = np.zeros(uv.shape[:2] + (4,))
    out[..., :3] = c[..., :3] * vis[..., None]
    out[..., 3] = vis
    return out


def box_blur_formula(img, size, separation):
    """(2 size + 1)^2 taps `separation` texels apart around every texel, each
    read with bilinear + clamp-to-edge, averaged; all four channels."""
    img = img.astype(np.float64)
    h, w = img.shape[:2]
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float64)
    acc = np.zeros_like(img)
    for j in range(-size, size + 1):
        for i in range(-size, size + 1):
            acc += bilinear(img, xx + i * separation, yy + j * separation)
    return acc / (2 * size + 1) ** 2


def reflection_formula(color, blurred, specular):
    """mix(colour, blurred, roughness) * specular amount; amount = mean of the
    specular rgb (0 output where it is not > 0); roughness = 1 - shininess,
    shininess clamped to [0, 1]."""
    spec = specular.astype(np.float64)
    amount = spec[..., :3].sum(axis=2) / 3.0
    rough = 1.0 - np.clip(spec[..., 3], 0, 1)
    out = (color * (1 - rough[..., None]) + blurred * rough[..., None]) * amount[..., None]
    return np.where((amount > 0)[..., None], out, 0.0)


def combine_formula(base, refl, mode):
    a = np.clip(refl[..., 3:4].astype(np.float64), 0, 1)
    out = base.astype(np.float64).copy()
    if mode == "over":  # premultiplied reflection over the base
        out[..., :3] = base[..., :3] * (1 - a) + refl[..., :3]
    else:  # the demo's mix(base, reflection, alpha)
        out[..., :3] = base[..., :3] * (1 - a) + refl[..., :3] * a
    return out


# --- stage tests -------------------------------------------------------------------------


def rng_images(seed, h=20, w=24):
    rng = np.random.default_rng(seed)
    color = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    return rng, color


def test_reflection_color_matches_formula():
    rng, color = rng_images(1)
    h, w = color.shape[:2]
    uv = np.zeros((h, w, 4), np.float32)
    uv[..., 0] = rng.uniform(-0.3, 1.3, (h, w))  # outside [0, 1]: clamp to edge
    uv[..., 1] = rng.uniform(-0.3, 1.3, (h, w))
    vis = rng.uniform(-0.2, 1.2, (h, w))
    vis[rng.uniform(size=(h, w)) < 0.2] = 0.0
    uv[..., 2] = uv[..., 3] = vis
    # a few exact texel centres and edges
    uv[0, :5, 0] = (np.arange(5) + 0.5) / w
    uv[1, :5, 0] = np.arange(5) / w
    got = glint_core.reflection_color(uv, color)
    np.testing.assert_allclose(got, reflection_color_formula(uv, color), atol=2e-6)
    assert np.all(got[vis <= 0] == 0)


def test_reflection_color_three_channel_colour():
    rng, color = rng_images(2)
    h, w = color.shape[:2]
    uv = np.zeros((h, w, 4), np.float32)
    uv[..., :2] = rng.uniform(0, 1, (h, w, 2))
    uv[..., 2:] = 1.0
    got = glint_core.reflection_color(uv, color[..., :3].copy())
    want = reflection_color_formula(uv, np.concatenate([color[..., :3], np.ones((h, w, 1))], 2))
    np.testing.assert_allclose(got, want, atol=2e-6)


@pytest.mark.parametrize("size, separation", [(8, 1.0), (2, 1.0), (3, 1.5), (1, 2.0), (0, 1.0),
                                              (4, 7.25)])
def test_box_blur_matches_brute_force(size, separation):
    _, img = rng_images(3, h=19, w=23)
    img[5, 7] = (9.0, -3.0, 4.0, 2.0)  # a spike shows any off-by-one in the window
    got = glint_core.box_blur(img, size=size, separation=separation)
    np.testing.assert_allclose(got, box_blur_formula(img, size, separation), atol=1e-5)


def test_box_blur_default_is_the_17x17_box():
    _, img = rng_images(4, h=21, w=18)
    got = glint_core.box_blur(img)
    h, w = img.shape[:2]
    # Direct: clamp the integer window indices to the image.
    want = np.zeros((h, w, 4))
    for y in range(h):
        for x in range(w):
            ys = np.clip(np.arange(y - 8, y + 9), 0, h - 1)
            xs = np.clip(np.arange(x - 8, x + 9), 0, w - 1)
            want[y, x] = img[np.ix_(ys, xs)].astype(np.float64).sum(axis=(0, 1)) / 289.0
    np.testing.assert_allclose(got, want, atol=1e-5)


def test_reflection_matches_formula():
    rng, color = rng_images(5)
    h, w = color.shape[:2]
    blurred = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    spec = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    spec[::3, ::2, :3] = 0.0  # no specular: no reflection
    spec[1::4, :, 3] = rng.uniform(-1.0, 2.0, (len(range(1, h, 4)), w))  # out-of-range shininess
    spec[2, :4, :3] = (-0.5, 0.2, 0.1)  # negative amount
    got = glint_core.reflection(color, blurred, spec)
    want = reflection_formula(color.astype(np.float64), blurred.astype(np.float64), spec)
    np.testing.assert_allclose(got, want, atol=2e-6)
    assert np.all(got[spec[..., :3].sum(axis=2) <= 0] == 0)


@pytest.mark.parametrize("mode", ["over", "seed"])
def test_combine_matches_formula(mode):
    rng, base = rng_images(6)
    h, w = base.shape[:2]
    refl = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    refl[0, :3, 3] = (-0.5, 0.0, 1.5)  # alpha outside [0, 1] is clamped
    got = glint_core.combine(base, refl, mode=mode)
    np.testing.assert_allclose(got, combine_formula(base, refl, mode), atol=2e-6)
    np.testing.assert_array_equal(got[..., 3], base[..., 3])


def test_combine_over_shows_a_full_mirror_exactly():
    """Specular 1, shininess 1, visibility 1: 'over' shows exactly the reflected colour."""
    _, base = rng_images(7)
    refl = np.zeros_like(base)
    refl[..., :3] = (0.9, 0.1, 0.1)
    refl[..., 3] = 1.0
    got = glint_core.combine(base, refl, mode="over")
    np.testing.assert_allclose(got[..., :3], np.broadcast_to([0.9, 0.1, 0.1], got[..., :3].shape),
                               atol=1e-7)


def test_shininess_mapping():
    assert glint_core.shininess_from_hardness(511) == pytest.approx(127.75)
    assert glint_core.shininess_from_hardness(1) == pytest.approx(0.25)
    assert glint_core.shininess_to_alpha(127.75) == pytest.approx(1.0)
    assert glint_core.shininess_to_alpha(127.75 / 2) == pytest.approx(0.5)
    # past 127.75 the gloss range: hardness 4000 is alpha 4000 / 511, not capped at 1
    assert glint_core.shininess_to_alpha(1000.0) == pytest.approx(1000.0 / 127.75)
    assert glint_core.shininess_to_alpha(float("inf")) == 1.0  # a mirror
    assert glint_core.shininess_to_alpha(-3.0) == 0.0
    assert glint_core.shininess_to_alpha(float("nan")) == 0.0
    assert glint_core.MAX_SHININESS == pytest.approx(127.75)


# --- the pipeline ------------------------------------------------------------------------

W, H = 64, 48


def red_sphere_scene(kind, floor_alpha=1.0, wall=False):
    floor = A.Material(color=(0.4, 0.4, 0.4), specular=(1.0, 1.0, 1.0), alpha=floor_alpha)
    return A.mirror_floor_scene(kind, box=False, wall=wall, floor=floor,
                                sphere_material=A.Material(color=(0.9, 0.1, 0.1)))


def run_pipeline(gb, **kw):
    return glint_core.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"],
                               gb["projection"], **kw)


@pytest.mark.parametrize("kind", ["persp", "ortho"])
def test_pipeline_is_its_stages_chained(kind):
    sc = A.mirror_floor_scene(kind, floor=A.Material(color=(0.4, 0.4, 0.4),
                                                     specular=(0.8, 0.7, 0.9), alpha=0.6))
    gb = A.render(sc, W, H)
    kw = dict(max_distance=12.0, resolution=0.5, steps=8, thickness=0.7)
    out = run_pipeline(gb, blur_size=3, blur_separation=1.5, **SEED_LOOK, **kw)
    seen = gb["position"][..., 3] > 0
    spec = gb["specular"]
    reflective = seen & (spec[..., :3].sum(axis=2) > 0)
    rough = reflective & (spec[..., 3] < 1)
    assert out["stats"]["reflective_pixels"] == reflective.sum()
    assert out["stats"]["rough_pixels"] == rough.sum()
    assert out["stats"]["skipped"] == ["specular_weight"]

    uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], **kw)
    np.testing.assert_array_equal(out["uv"], np.where(reflective[..., None], uv, 0))
    rc = glint_core.reflection_color(out["uv"], gb["color"])
    np.testing.assert_allclose(out["reflection_color"], rc, atol=1e-7)
    blurred = glint_core.box_blur(rc, size=3, separation=1.5)
    # The blur runs over the bounding box of the rough reflective pixels only.
    ys, xs = np.nonzero(rough)
    box = (slice(ys.min(), ys.max() + 1), slice(xs.min(), xs.max() + 1))
    np.testing.assert_allclose(out["reflection_blur"][box], blurred[box], atol=1e-6)
    refl = glint_core.reflection(rc, blurred, spec)
    np.testing.assert_allclose(out["reflection"], refl, atol=1e-6)
    np.testing.assert_allclose(out["combined"], glint_core.combine(gb["color"], refl), atol=1e-6)
    # And the chain against the formulas, not only against the stage functions.
    np.testing.assert_allclose(out["combined"],
                               combine_formula(gb["color"], reflection_formula(
                                   reflection_color_formula(out["uv"], gb["color"]),
                                   box_blur_formula(rc, 3, 1.5), spec), "over"), atol=1e-5)


def test_glints_look_reads_the_colour_inside_outlines():
    """weighting="physical" reads the frame at read_inside_outlines() of the trace's
    uv; the uv layer stays the trace's own, and the seed's look reads at it."""
    sc = A.mirror_floor_scene("persp", floor=A.Material(color=(0.4, 0.4, 0.4), specular=(0.8, 0.7, 0.9)))
    gb = A.render(sc, W, H)
    kw = dict(glint_core.presets()["balanced"], blocked="occluder")
    out = run_pipeline(gb, **kw)
    read = glint_core.read_inside_outlines(out["uv"], gb["position"], thickness=kw["thickness"])
    moved = (read[..., :2] != out["uv"][..., :2]).any(axis=-1)
    assert moved.sum() > 5
    uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], specular=gb["specular"], **kw)
    np.testing.assert_array_equal(out["uv"], uv)
    np.testing.assert_allclose(out["reflection_color"], glint_core.reflection_color(read, gb["color"]), atol=1e-7)
    assert np.abs(out["reflection_color"] - glint_core.reflection_color(uv, gb["color"])).max(axis=-1)[moved].max() > 0
    seed = run_pipeline(gb, **kw, **SEED_LOOK)
    np.testing.assert_allclose(seed["reflection_color"], glint_core.reflection_color(uv, gb["color"]), atol=1e-7)


def test_no_reflective_pixel_returns_the_base_unchanged():
    sc = A.mirror_floor_scene("persp", floor=A.Material(color=(0.4, 0.4, 0.4)))
    gb = A.render(sc, W, H)
    # Specular on unseen (sky) pixels does not count: nothing seen reflects.
    gb["specular"][gb["object"] < 0] = (1.0, 1.0, 1.0, 1.0)
    assert gb["specular"][gb["object"] >= 0, :3].max() == 0
    for color in (gb["color"], gb["color"][..., :3].copy()):
        out = glint_core.pipeline(gb["position"], gb["normal"], gb["specular"], color,
                                  gb["projection"])
        want = color if color.shape[2] == 4 else np.concatenate(
            [color, np.ones(color.shape[:2] + (1,), np.float32)], axis=2)
        assert out["combined"].tobytes() == want.tobytes(), "base not returned bit-identical"
        assert sorted(out["stats"]["skipped"]) == sorted(STAGES)
        assert out["stats"]["reflective_pixels"] == 0
        for name in ("uv", "reflection_color", "reflection_blur", "specular_weight", "reflection"):
            assert np.all(out[name] == 0)


def test_mirror_only_scene_skips_the_blur():
    gb = A.render(red_sphere_scene("persp", floor_alpha=1.0), W, H)
    assert run_pipeline(gb)["stats"]["skipped"] == ["cone_blur"]
    out = run_pipeline(gb, **SEED_LOOK)
    assert out["stats"]["skipped"] == ["specular_weight", "box_blur"]
    assert out["stats"]["rough_pixels"] == 0 and out["stats"]["reflective_pixels"] > 0
    # With no rough pixel the reflection is the unblurred colour times the amount.
    np.testing.assert_allclose(out["reflection"], reflection_formula(
        out["reflection_color"].astype(np.float64), np.zeros((H, W, 4)), gb["specular"]),
        atol=1e-6)


def test_blur_size_zero_skips_the_blur():
    gb = A.render(red_sphere_scene("persp", floor_alpha=0.3), W, H)
    assert "box_blur" not in run_pipeline(gb, blur="box")["stats"]["skipped"]
    out = run_pipeline(gb, blur="box", blur_size=0)
    assert out["stats"]["skipped"] == ["box_blur"]
    np.testing.assert_array_equal(out["reflection_blur"], out["reflection_color"])


@pytest.mark.parametrize("kind", ["persp", "ortho"])
def test_red_sphere_turns_the_mirror_floor_under_it_red(kind, artifacts):
    """Floor pixels whose exact mirror ray hits the red sphere (an analytic
    fact) come out reddish; floor pixels whose ray goes to the empty sky keep
    their base colour."""
    sc = red_sphere_scene(kind)
    W, H = 96, 64
    gb = A.render(sc, W, H)
    mh = A.mirror_hits(sc, gb, 15.0)
    out = run_pipeline(gb, resolution=1.0)
    comb = out["combined"]
    artifacts.add("combined", comb[..., :3], 0, 1)
    artifacts.add("base", gb["color"][..., :3], 0, 1)
    floor = gb["object"] == 0
    sphere = 1
    # Keep clear of the sphere's silhouette in the image (1 texel).
    uvx = np.nan_to_num(mh["uv"], nan=-1.0)
    px = np.floor(np.clip(uvx[..., 0], -1, 2) * W).astype(int)
    py = np.floor(np.clip(uvx[..., 1], -1, 2) * H).astype(int)
    inner = np.ones((H, W), bool)
    for dy in range(-1, 2):
        for dx in range(-1, 2):
            x, y = np.clip(px + dx, 0, W - 1), np.clip(py + dy, 0, H - 1)
            inner &= gb["object"][y, x] == sphere
    on_sphere = floor & (mh["object"] == sphere) & mh["visible"] & mh["front"] & inner
    reddish = (comb[..., 0] > comb[..., 1] + 0.15) & (comb[..., 0] > comb[..., 2] + 0.15)
    print(f"\n{kind}: {on_sphere.sum()} floor pixels mirror the sphere, "
          f"reddish {reddish[on_sphere].mean():.2%}")
    assert on_sphere.sum() >= 40
    assert reddish[on_sphere].mean() >= 0.9
    # Rays to the empty sky leave the base untouched (within float rounding).
    clear, _ = A.path_state(gb, mh["pivot"], 15.0, 0.5)
    sky = floor & ~mh["hit"] & clear
    assert sky.sum() >= 100
    np.testing.assert_allclose(comb[sky], gb["color"][sky], atol=1e-6)

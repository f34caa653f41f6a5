"""The compositor group, run on numpy arrays, against the composite's formula
written out here (docs/addon.md), and (when the build is there) against
glint_core's own stages."""
import math

import numpy as np
import pytest

from compositing_reference import bilinear_clamp, bilinear_zero, blurred_at_lod, gauss_clamp
from compositing_reference import map_uv as np_map_uv
import group_model as gm
from glint_addon_helpers import load_logic

cg = load_logic("compositing")
gi = load_logic("group_images")
texels = load_logic("texels")

# The abstract kinds' inputs and outputs as the description numbers them
# (host/nodes.py maps them onto each Blender's sockets).
INPUTS = {"math": 3, "mix": 3, "separate": 1, "combine": 4, "map_uv": 2, "blur": 1, "soften": 1,
          "switch": 2, "image": 0, "translate": 3, "frame_scale": 1, "keep": 1}
OUTPUTS = {"separate": 4, "image": 2}
# float32 against the float64 formula, plus the first level's lift through the
# 3x3 filter (compositing.SOFTEN_LIFT): D rounded to that float's spacing,
# twice (on and off).
ATOL = 1e-5 + 2 * float(np.spacing(np.float32(cg.SOFTEN_LIFT)))


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


def test_blur_levels_hold_half_their_energy_in_the_cone_footprint():
    """A 2D Gaussian holds half its energy within r = sigma sqrt(2 ln 2): each
    level's sigma puts that r at LEVEL_FOOTPRINT_SHARE (0.5) of half its lod's
    footprint 2^lod."""
    assert cg.LEVEL_FOOTPRINT_SHARE == 0.5
    for lod, sigma in cg.BLUR_LEVELS:
        j = cg.BLUR_LEVELS.index((lod, sigma)) + 1
        kind, props, defaults = cg.GROUP_NODES[f"blur_{j}"]
        if j == 1:  # the 3x3 binomial filter, whose variance per axis is its sigma^2, at lod 2
            taps = np.array([-1.0, 0.0, 1.0])
            kernel = np.array(cg.SOFTEN_TAPS)
            assert kind == "soften" and kernel.sum() == 1.0
            assert float((kernel * taps * taps).sum()) == pytest.approx(sigma * sigma)
            rule = 2.0 ** lod / 4 / math.sqrt(2 * math.log(2))  # the sigma the rule asks at its lod
            assert lod == 2.0 and sigma == pytest.approx(0.83 * rule, abs=0.01)
            continue
        r = 2.0 ** lod / 4
        assert 1 - math.exp(-r * r / (2 * sigma * sigma)) == pytest.approx(0.5, abs=1e-9)
        on_canvas = sigma / cg.COARSE if j > cg.FULL_LEVELS else sigma  # the wide levels blur coarse texels
        assert kind == "blur" and props["sigma"] == pytest.approx(on_canvas)


def test_the_soften_level_is_the_3x3_binomial_kernel():
    """The numpy model of Blender's Soften against the kernel written out: an
    impulse spreads to (1 2 1; 2 4 2; 1 2 1) / 16, the edge texel repeated."""
    img = np.zeros((5, 6, 4), np.float32)
    img[2, 3] = 16.0
    out = gm._softened(img)
    want = np.zeros((5, 6), np.float32)
    want[1:4, 2:5] = [[1, 2, 1], [2, 4, 2], [1, 2, 1]]
    assert np.array_equal(out[..., 0], want) and np.array_equal(out[..., 3], want)
    corner = np.zeros((3, 3, 4), np.float32)
    corner[0, 0] = 16.0  # clamped: the corner texel weighs (1 + 2) / 4 along each axis
    assert gm._softened(corner)[0, 0, 0] == pytest.approx(9.0)


# -- an independent reference of the composite (sampling and blur: compositing_reference.py)

def reference_composite(base, uv, weight, lod, light, colour, bounce=False, hidden=None, past_edge="zero",
                        at_most_frame=False):
    """out = max(base + R, 0), R = D at the pixel's lod between Gaussian levels of
    D, D = C W - rep S, or with ``at_most_frame`` (the world's path) C W -
    min(rep S, base): written from the formula, not from the node list. With
    ``bounce``, C is sampled from the frame with its first bounce, base + D.
    ``hidden`` (albedo, vis): those pixels (vis 0 in ``uv``) show albedo x the
    frame at the pixel, times their vis, and replace that share of S.
    ``past_edge``: how the coarse levels are read back (blurred_at_lod)."""
    vis = uv[..., 2:3]
    rep = vis if hidden is None else vis + hidden[..., 3:4]
    own = 0.0 if hidden is None else hidden[..., :3] * hidden[..., 3:4] * base[..., :3]
    # what is taken out: the engine's specular where a hit replaces it (at most the frame)
    taken_out = rep * (light[..., :3] * colour[..., :3])
    if at_most_frame:
        taken_out = np.minimum(taken_out, base[..., :3])
    C = np.where(vis > 0, bilinear_clamp(base, uv[..., 0], uv[..., 1]) * vis, 0.0)
    D = (C[..., :3] + own) * weight[..., :3] - taken_out
    if bounce:
        first = base.copy()
        first[..., :3] += D
        C = np.where(vis > 0, bilinear_clamp(first, uv[..., 0], uv[..., 1]) * vis, 0.0)
        D = (C[..., :3] + own) * weight[..., :3] - taken_out
    R = blurred_at_lod(D, lod, past_edge=past_edge)
    out = base.copy()
    out[..., :3] = np.maximum(out[..., :3] + R, 0.0)  # no pixel below 0
    return out, R


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
    seen = position[..., 3] > 0  # positions here are finite: seen is w > 0
    spec[~seen] = 0  # as the rasterizer leaves pixels no triangle covers
    mask = texels.reflective_mask(position, spec)
    uv[~mask] = 0  # the trace reports nothing where it does not march
    weight = np.zeros((h, w, 4), np.float32)
    weight[mask, :3] = rng.uniform(0.02, 0.9, (int(mask.sum()), 3))
    lod = np.where(mask, rng.uniform(0, 9.5, (h, w)), 0).astype(np.float32)
    light = rng.uniform(0, 2, (h, w, 4)).astype(np.float32)
    colour = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    return base, position, spec, uv, seen, weight, lod, light, colour


def uv_image(uv, hidden=None):
    """The uv image as glint_core.composite_layers makes it, short of the continued uv of
    misses (which only Blender's Map UV filter reads): (u, v, vis, rep), rep = vis, or the
    hidden image's vis where a ray came into a hidden side (vis 0 there)."""
    out = uv.copy()
    out[..., 3] = out[..., 2] if hidden is None else out[..., 2] + hidden[..., 3]
    return out


def images_of(base, position, spec, uv, weight, lod, debug=None, hidden=None):
    w = weight.copy()
    w[..., 3] = lod
    h, wd = base.shape[:2]
    return {cg.IMAGE_UV: uv_image(uv, hidden), cg.IMAGE_WEIGHT: w,
            cg.IMAGE_HIDDEN: np.zeros_like(base) if hidden is None else hidden,
            cg.IMAGE_DEBUG: np.zeros_like(base) if debug is None else debug, cg.IMAGE_POSITION: position,
            cg.IMAGE_NORMAL: np.zeros_like(base), cg.IMAGE_SPECULAR: spec,
            **gi.coarse_images(lod, (0, 0, wd, h), wd, h)}


@pytest.mark.parametrize("engine_passes", [True, False])
def test_group_computes_the_composite(engine_passes):
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    kw = dict(specular_light=light, specular_color=colour) if engine_passes else {}
    out = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod), np_map_uv, gauss_clamp, **kw)
    if not engine_passes:  # an unlinked input is black: nothing replaced, the reflection added
        light = colour = np.zeros_like(base)
    want, R = reference_composite(base, uv, weight, lod, light, colour)
    assert np.allclose(out["Image"][..., :3], want[..., :3], atol=ATOL)
    assert np.array_equal(out["Image"][..., 3], base[..., 3])
    assert np.allclose(out["Reflection"][..., :3], R, atol=ATOL)
    assert np.array_equal(out["Base"], base)
    assert np.array_equal(out["Visibility"], uv[..., 2])
    assert np.allclose(out["Engine Specular"][..., :3], light[..., :3] * colour[..., :3], atol=1e-6)


def with_hidden_sides(uv, seed=5):
    """A share of the hits turned into hidden sides: vis 0 in the uv, (albedo, vis) in the hidden image."""
    rng = np.random.default_rng(seed)
    uv = uv.copy()
    pick = (uv[..., 2] > 0) & (rng.uniform(size=uv.shape[:2]) < 0.4)
    hidden = np.zeros_like(uv)
    hidden[pick, :3] = rng.uniform(0, 1, (int(pick.sum()), 3))
    hidden[pick, 3] = uv[pick, 2]
    uv[pick, 2] = 0
    return uv, hidden


@pytest.mark.parametrize("world", [False, True])
@pytest.mark.parametrize("bounce", [False, True])
@pytest.mark.parametrize("whole_frame", [False, True])
def test_hidden_sides_show_their_albedo_lit_by_the_frame_at_the_pixel(world, bounce, whole_frame):
    """``whole_frame``: a host whose group works on the whole frame."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    uv, hidden = with_hidden_sides(uv)
    assert (hidden[..., 3] > 0).sum() > 10
    images = images_of(base, position, spec, uv, weight, lod, hidden=hidden)
    if world:  # S = the world colour x W (the world's path)
        colour = weight.copy()
        kw = dict(specular_light=light[0, 0], specular_color=weight, world_specular=True)
        light = np.broadcast_to(light[0, 0], base.shape)
    else:
        kw = dict(specular_light=light, specular_color=colour)
    kw["whole_frame"] = whole_frame
    out = gm.evaluate_group(base, images, np_map_uv, gauss_clamp, use_bounce=bounce, use_hidden=True, **kw)
    edge = "clamp" if whole_frame else "zero"  # the fine image's Map UV, or the Scale
    want, _ = reference_composite(base, uv, weight, lod, light, colour, bounce=bounce, hidden=hidden,
                                  past_edge=edge, at_most_frame=world)
    assert np.allclose(out["Image"][..., :3], want[..., :3], atol=ATOL)
    # switched off, the hidden image is not read: the pixels only lose S
    off = gm.evaluate_group(base, images, np_map_uv, gauss_clamp, use_bounce=bounce, **kw)
    hidden_off = hidden.copy()
    hidden_off[..., :3] = 0
    want_off, _ = reference_composite(base, uv, weight, lod, light, colour, bounce=bounce, hidden=hidden_off,
                                      past_edge=edge, at_most_frame=world)
    assert np.allclose(off["Image"][..., :3], want_off[..., :3], atol=ATOL)


def test_a_cleared_uv_image_passes_the_frame_through_whatever_the_hidden_image_holds():
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    uv, hidden = with_hidden_sides(uv)
    images = images_of(base, position, spec, np.zeros_like(uv), weight, lod, hidden=hidden)
    images[cg.IMAGE_UV] = np.zeros_like(uv)  # clear_images(only_pass_through=True)
    out = gm.evaluate_group(base, images, np_map_uv, gauss_clamp, specular_light=light, specular_color=colour,
                            use_hidden=True)
    assert np.array_equal(out["Image"], base)


@pytest.mark.parametrize("engine_passes", [True, False])
def test_second_bounce_samples_the_frame_with_its_first(engine_passes):
    base, position, spec, uv, seen, weight, lod, light, colour = scene(seed=11)
    kw = dict(specular_light=light, specular_color=colour) if engine_passes else {}
    out = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod), np_map_uv, gauss_clamp,
                            use_bounce=True, **kw)
    if not engine_passes:
        light = colour = np.zeros_like(base)
    want, R = reference_composite(base, uv, weight, lod, light, colour, bounce=True)
    one, _ = reference_composite(base, uv, weight, lod, light, colour)
    assert np.abs(want - one).max() > 0.05  # the second bounce is there to be found
    assert np.allclose(out["Image"][..., :3], want[..., :3], atol=ATOL)
    assert np.allclose(out["Reflection"][..., :3], R, atol=ATOL)
    assert np.array_equal(out["Image"][..., 3], base[..., 3])


def test_only_sharp_or_metallic_reflectors_count_for_autos_second_bounce():
    mats = load_logic("materials")

    def counts(**inputs):  # a Principled BSDF with Blender 3.x's input names
        spec = mats.principled_specular(dict({"Specular": 0.5, "Roughness": 0.5, "Metallic": 0.0}, **inputs))
        return cg.counts_for_second_bounce(spec.reflective, spec.alpha, spec.amount)
    # Blender's default material: F0 = 0.08 x 0.5 = 0.04, Roughness 0.5 (hardness ~33 < 511)
    assert not counts()
    assert counts(Roughness=0.1)  # below ~0.25: the gloss range, alpha above 1
    assert counts(Metallic=1.0, **{"Base Color": (0.9, 0.9, 0.9, 1.0)})  # amount 0.9
    assert not counts(Specular=0.0, Roughness=0.1)  # not reflective at all
    assert not cg.counts_for_second_bounce(True, 0.5, 0.49)
    assert cg.counts_for_second_bounce(True, 0.5, 0.5)


def test_second_bounce_runs_where_reflectors_can_meet():
    assert not cg.use_second_bounce("AUTO", 0)
    assert not cg.use_second_bounce("AUTO", 1)
    assert cg.use_second_bounce("AUTO", 2)
    assert cg.use_second_bounce("ON", 1)
    assert not cg.use_second_bounce("OFF", 5)
    with pytest.raises(ValueError, match="second bounce"):
        cg.use_second_bounce("TWICE", 2)
    calls = []
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    images = images_of(base, position, spec, uv, weight, lod)
    gm.evaluate_group(base, images, lambda i, u: calls.append(1) or np_map_uv(i, u), gauss_clamp, use_blur=False)
    assert len(calls) == 1  # switched off, the second Map UV does not run (nor the coarse levels' two)


@pytest.mark.parametrize("bounce", [False, True])
def test_the_world_path_is_the_passes_path_with_s_the_world_colour_times_w(bounce):
    """Under a uniform world the group's inputs are the world colour and W: its
    short path must give what the passes' path gives for those inputs, but that
    it takes out at most the frame (that S is a model; the passes' is what the
    frame holds)."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene(seed=5)
    world = np.broadcast_to(np.array((0.3, 0.35, 0.45, 1.0), np.float32), base.shape)
    w_image = images_of(base, position, spec, uv, weight, lod)[cg.IMAGE_WEIGHT]
    kw = dict(specular_light=world, specular_color=w_image, use_bounce=bounce)
    short = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod), np_map_uv,
                              gauss_clamp, world_specular=True, **kw)
    full = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod), np_map_uv, gauss_clamp, **kw)
    want, _ = reference_composite(base, uv, weight, lod, world, w_image, bounce=bounce, at_most_frame=True)
    whole, _ = reference_composite(base, uv, weight, lod, world, w_image, bounce=bounce)
    assert np.allclose(short["Image"][..., :3], want[..., :3], atol=ATOL)
    assert np.allclose(full["Image"][..., :3], whole[..., :3], atol=ATOL)
    assert np.abs(short["Image"] - base).max() > 0.05
    assert np.abs(want - whole).max() > 0.05  # the frame bounds what leaves somewhere


@pytest.mark.parametrize("world", [False, True])
def test_replaces_the_engine_specular_where_a_mirror_hit_is_found(world):
    """vis 1, lod 0: the pixel's engine specular S leaves, the reflection C W comes in;
    under a uniform world, whose S is a model, at most the frame leaves."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    lod[:] = 0
    images = images_of(base, position, spec, uv, weight, lod)
    if world:
        light, colour = np.broadcast_to(light[0, 0], base.shape), images[cg.IMAGE_WEIGHT]
        kw = dict(specular_light=light[0, 0], specular_color=colour, world_specular=True)
    else:
        kw = dict(specular_light=light, specular_color=colour)
    out = gm.evaluate_group(base, images, np_map_uv, gauss_clamp, **kw)["Image"]
    hit = uv[..., 2] > 0
    C = np_map_uv(base, uv_image(uv))
    S = uv[..., 2:3] * light[..., :3] * colour[..., :3]
    if world:  # the core's combine with a specular base (glint_core.combine)
        want = np.maximum(base[..., :3] - S, 0.0) + C[..., :3] * weight[..., :3]
    else:
        want = np.maximum(base[..., :3] - S + C[..., :3] * weight[..., :3], 0.0)
    assert np.allclose(out[hit, :3], want[hit], atol=ATOL)
    assert np.array_equal(out[~hit], base[~hit])
    # the engine's specular exceeds the frame on some hits: under a uniform world
    # those show the reflection alone, never less
    short = hit[..., None] & (S > base[..., :3])
    assert short.sum() > 10
    if world:
        assert np.allclose(out[..., :3][short], (C[..., :3] * weight[..., :3])[short], atol=ATOL)
    assert out[..., :3].min() >= 0.0


@pytest.mark.parametrize("world", [False, True])
def test_no_pixel_goes_below_0_where_the_engine_specular_exceeds_the_frame(world):
    """S up to twice the frame's white, on blurred pixels: the bound before the blur
    and the floor after it leave every channel at 0 or above."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene(seed=17)
    base[..., :3] *= 0.2  # a dark frame, which the engine's specular exceeds on most hits
    kw = dict(specular_light=light, specular_color=colour)
    if world:
        kw = dict(specular_light=light[0, 0], specular_color=weight, world_specular=True)
    out = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod), np_map_uv, gauss_clamp,
                            **kw)
    assert (out["Reflection"][..., :3] < -0.05).any()  # the frame does darken
    assert out["Image"][..., :3].min() >= 0.0


def test_without_rough_surfaces_the_levels_are_switched_off():
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    lod[:] = 0  # every pixel sharp: the levels would pick D anyway
    calls = []
    images = images_of(base, position, spec, uv, weight, lod)
    on = gm.evaluate_group(base, images, np_map_uv, lambda i, s: calls.append(s) or gauss_clamp(i, s))
    off = gm.evaluate_group(base, images, np_map_uv, lambda i, s: calls.append(s) or gauss_clamp(i, s),
                            use_blur=False)
    assert len(calls) == len(cg.BLUR_LEVELS) - 1  # only the first evaluation blurred (level 1 is the 3x3 filter)
    assert np.allclose(on["Image"], off["Image"], atol=1e-6)


def test_nan_engine_specular_where_nothing_reflects_stays_out_of_the_frame():
    """Eevee divides its light passes by their colour: 0 / 0 where a pixel has no
    specular colour. Those pixels have no hit (vis 0) and must stay the engine's."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    lod[:] = 0
    miss = uv[..., 2] == 0
    light[miss] = np.nan
    colour[miss] = 0
    out = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod), np_map_uv, gauss_clamp,
                            specular_light=light, specular_color=colour)
    assert np.isfinite(out["Image"]).all()
    assert np.array_equal(out["Image"][miss], base[miss])


def test_nothing_reflective_leaves_the_base_bit_exact():
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    spec[..., :3] = 0
    uv[:] = 0
    weight[:] = 0
    out = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod * 0), np_map_uv, gauss_clamp,
                            specular_light=light, specular_color=colour)
    assert np.array_equal(out["Image"], base)


def test_debug_switches():
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    dbg = np.full_like(base, 0.25)
    images = images_of(base, position, spec, uv, weight, lod, debug=dbg)
    refl = gm.evaluate_group(base, images, np_map_uv, gauss_clamp, debug_view="REFLECTION")
    assert np.array_equal(refl["Image"], refl["Reflection"])
    for view in cg.GBUFFER_DEBUG_VIEWS:
        assert np.array_equal(gm.evaluate_group(base, images, np_map_uv, gauss_clamp,
                                                debug_view=view)["Image"], dbg)
    assert cg.switch_states("NONE", False) == {"show_reflection": False, "show_debug": False, "use_blur": False,
                                               "use_bounce": False, "use_passes": True, "use_hidden": False,
                                               "lift_in_1": True, "lift_out_1": True,
                                               "coarse_by_scale": True, "d_buffered": True}
    assert not any(cg.switch_states("NONE", soften_filters=False)[name] for name in ("lift_in_1", "lift_out_1"))


def test_the_muted_nodes_are_exactly_those_no_output_reads(monkeypatch):
    """The model reads a node only when an output needs it through the sides its
    Switches pass: every such node must stay unmuted, and every other is muted.
    Over every combination of the switches' inputs."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene(h=6, w=8)
    images = images_of(base, position, spec, uv, weight, lod)
    read = set()
    node_output = gm._node_output

    def recording(node, *args, **kwargs):
        read.add(node)
        return node_output(node, *args, **kwargs)

    monkeypatch.setattr(gm, "_node_output", recording)
    switches = {name for name, (kind, _, _) in cg.GROUP_NODES.items() if kind == "switch"}
    flags = ("use_blur", "use_bounce", "world_specular", "use_hidden", "soften_filters", "whole_frame")
    for view in [v for v, _, _ in cg.DEBUG_VIEWS]:
        for bits in range(1 << len(flags)):
            kw = {name: bool(bits >> i & 1) for i, name in enumerate(flags)}
            read.clear()
            gm.evaluate_group(base, images, np_map_uv, gauss_clamp, debug_view=view, **kw)
            dead = cg.dead_nodes(cg.switch_states(view, *(kw[name] for name in flags)))
            assert read - switches == set(cg.GROUP_NODES) - switches - dead, (view, kw)
            assert "map_uv" not in dead and not dead & {"uv_image", "weight_image"}, (view, kw)
    states = cg.switch_states("NONE", True, False, whole_frame=True)
    assert {"bounce_map_uv", "hidden_light", "box_back_x", "coarse_to_frame", "d_kept"} <= cg.dead_nodes(states)


def test_group_matches_glint_core_for_a_mirror(core):
    """Where nothing is rough the group and glint_core's stages compute the same
    thing: the core's reflection colour x its weight, replacing S by visibility."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene(20, 24, seed=7)
    lod[:] = 0
    S = light * colour
    color = core.reflection_color(uv, base)
    refl = core.reflection(color, None, spec, weight=weight)
    want = core.combine(base, refl, specular_base=S, coverage=color)
    out = gm.evaluate_group(base, images_of(base, position, spec, uv, weight, lod),
                            lambda img, uvi: core.reflection_color(np.ascontiguousarray(uvi), img), gauss_clamp,
                            specular_light=light, specular_color=colour, use_blur=False)
    # the core clamps base - S coverage at 0; the random S here often exceeds the base
    ok = (base[..., :3] - S[..., :3] * color[..., 3:4] >= 0).all(axis=-1)
    assert ok.sum() > 50
    assert np.allclose(out["Image"][ok, :3], want[ok, :3], atol=ATOL)


def test_debug_images():
    position = np.zeros((1, 2, 4), np.float32)
    position[0, 0] = (1, 2, -3, 1)
    normal = np.zeros((1, 2, 4), np.float32)
    normal[0, 0, :3] = (0, 0, 1)
    spec = np.zeros((1, 2, 4), np.float32)
    spec[0, 0] = (0.5, 0.25, 0.125, 1)
    uv = np.zeros((1, 2, 4), np.float32)
    uv[0, 0] = (0.3, 0.7, 0.5, 0.5)
    assert np.array_equal(gi.debug_image("POSITION", position, normal, spec, uv)[0, 0], (1, 2, -3, 1))
    assert np.array_equal(gi.debug_image("NORMAL", position, normal, spec, uv)[0, 0], (0.5, 0.5, 1, 1))
    assert np.array_equal(gi.debug_image("NORMAL", position, normal, spec, uv)[0, 1], (0, 0, 0, 1))
    assert np.array_equal(gi.debug_image("SPECULAR", position, normal, spec, uv)[0, 0], (0.5, 0.25, 0.125, 1))
    assert np.allclose(gi.debug_image("UV", position, normal, spec, uv)[0, 0], (0.3, 0.7, 0, 1))
    assert np.array_equal(gi.debug_image("VISIBILITY", position, normal, spec, uv)[0, 0], (0.5, 0.5, 0.5, 1))
    with pytest.raises(ValueError):
        gi.debug_image("REFLECTION", position, normal, spec, uv)


# -- the region: only the part of the frame that can change is composited ------

def test_image_region_is_the_box_of_hits_and_blurred_pixels_grown_by_the_pad():
    vis = np.zeros((60, 80), np.float32)
    lod = np.zeros((60, 80), np.float32)
    assert gi.image_region(vis, lod) == (0, 0, 1, 1)  # nothing to do: one pixel, vis 0
    vis[25, 27] = 0.5
    vis[29, 32] = 1.0
    p = gi.REGION_PAD
    assert p >= 2 * cg.COARSE  # the coarse levels' clear border (test_a_region_composites_...)
    # rows 25-p..30+p are 5 + 2p, odd in a frame 60 high: one more row, so
    # that the region centred on the frame sits on whole pixels
    assert gi.image_region(vis, lod) == (27 - p, 25 - p, 33 + p, 30 + p + 1)
    lod[35, 40] = 0.25  # a rough pixel takes blurred D from hits around it
    assert gi.image_region(vis, lod) == (27 - p, 25 - p, 41 + p, 36 + p + 1)
    lod[35, 40] = 0.0
    vis[59, 79] = 1.0  # at the frame's far corner an odd count grows towards the origin
    assert gi.image_region(vis, lod) == (27 - p - 1, 25 - p - 1, 80, 60)
    vis[59, 79] = 0.0
    vis[0, 0] = lod[59, 79] = 1.0  # the pad stops at the frame
    assert gi.image_region(vis, lod) == (0, 0, 80, 60)


@pytest.mark.parametrize("region,size", [((3, 2, 23, 12), (64, 36)), ((40, 20, 61, 31), (64, 36)),
                                         ((0, 0, 64, 7), (64, 36)), ((63, 35, 64, 36), (64, 36)),
                                         ((0, 0, 64, 36), (64, 36)), ((5, 4, 10, 9), (11, 9))])
def test_the_offset_puts_the_region_back_where_it_was_cut(region, size):
    """The placements measured in Blender 3.4 (both execution models): a bw x bh
    image translated by (x0 + bw/2 - W/2, y0 + bh/2 - H/2) covers exactly
    columns x0..x0+bw-1 and rows y0..y0+bh-1."""
    w, h = size
    rng = np.random.default_rng(1)
    frame = rng.uniform(size=(h, w, 4)).astype(np.float32)
    imgs = gi.region_images(frame, frame, region)
    x0, y0, x1, y1 = region
    dx, dy = imgs[cg.IMAGE_OFFSET][0, 0, :2]
    placed = gm._translated(imgs[cg.IMAGE_UV], float(dx), float(dy), (h, w))
    want = np.zeros_like(frame)
    want[y0:y1, x0:x1] = frame[y0:y1, x0:x1]
    assert np.array_equal(placed, want)


def confined_scene(seed):
    """scene() with every hit and every rough pixel inside rows 17..25, columns 19..32
    of a 48 x 64 frame: with the pad, the region is a quarter of it, and its
    blocks of the coarse levels do not start on the frame's."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene(h=48, w=64, seed=seed)
    inside = np.zeros(base.shape[:2], bool)
    inside[17:26, 19:33] = True
    uv[~inside] = 0
    lod[~inside] = 0
    return base, position, spec, uv, seen, weight, lod, light, colour


@pytest.mark.parametrize("world,bounce,blur,hidden", [(True, False, False, True), (True, True, True, False),
                                                      (False, False, True, True), (False, True, False, False)])
def test_a_region_composites_what_the_whole_frame_does(world, bounce, blur, hidden):
    """Cut to the region and placed back by the offset, the images give the frame
    the group gives from frame-sized ones, bit for bit (with the blur, to the
    float rounding of what its levels spread to the region's edge); a frame-sized input that
    met the region untranslated would raise. With hidden sides, the frame they are
    lit by is read under the region, not at the frame's centre."""
    base, position, spec, uv, seen, weight, lod, light, colour = confined_scene(seed=7)
    hid = None
    if hidden:  # hidden sides in the hits' lower left only: a box off the region's centre
        uv, hid = with_hidden_sides(uv)
        ys, xs = np.nonzero(hid[..., 3] > 0)
        away = (xs > np.median(xs)) | (ys > np.median(ys))
        uv[ys[away], xs[away], 2] = hid[ys[away], xs[away], 3]
        hid[ys[away], xs[away]] = 0
        assert (hid[..., 3] > 0).sum() > 3
    full = images_of(base, position, spec, uv, weight, lod, hidden=hid)
    region = gi.image_region(full[cg.IMAGE_UV][..., 3], lod)
    h, w = base.shape[:2]
    p = gi.REGION_PAD
    # rows 17..25 grown by the pad are 9 + 2p, odd in a frame 48 high: one row more
    assert region == (19 - p, 17 - p, 33 + p, 26 + p + 1)
    assert region[0] % cg.COARSE and region[1] % cg.COARSE  # blocks on the frame's grid, not the region's
    boxed, offset = gi.hidden_images(hid, region, w, h)
    if hidden:  # the box is smaller than the region and not centred on it
        box = gi.hidden_box(hid[..., 3] > 0, region)
        assert (box[2] - box[0]) * (box[3] - box[1]) < (region[2] - region[0]) * (region[3] - region[1])
        assert offset != (0.0, 0.0)
    cut = dict(full, **gi.region_images(full[cg.IMAGE_UV], full[cg.IMAGE_WEIGHT], region, offset), **boxed)
    if world:  # the world path's inputs: a colour (an RGB node, no size) and the weight image
        kw = dict(specular_light=np.array((0.3, 0.35, 0.45, 1.0), np.float32), world_specular=True)
    else:
        kw = dict(specular_light=light, specular_color=colour)
    kw.update(use_bounce=bounce, use_blur=blur, use_hidden=hidden)
    want = gm.evaluate_group(base, full, np_map_uv, gauss_clamp, **kw)
    got = gm.evaluate_group(base, cut, np_map_uv, gauss_clamp, **kw)
    assert np.abs(want["Image"] - base).max() > 0.05
    if blur:  # the blur's clamp at the region's edge of what it spread there: 6e-8 at most here
        assert np.abs(got["Image"] - want["Image"]).max() <= 1e-6
    else:
        assert np.array_equal(got["Image"], want["Image"])


def test_region_meeting_the_frame_untranslated_is_caught():
    with pytest.raises(ValueError, match="different sizes"):
        gm._canvas([np.zeros((4, 5, 4)), np.zeros((6, 5))], (6, 5))
    with pytest.raises(ValueError, match="does not land"):
        gm._translated(np.zeros((3, 3, 4)), 0.25, 0.0, (8, 8))


def test_the_hidden_box_bounds_the_hidden_sides_with_the_regions_parity():
    seen = np.zeros((20, 30), bool)
    seen[5:8, 10:13] = True  # 3x3
    region = (2, 1, 28, 19)  # 26 x 18: even, even
    box = gi.hidden_box(seen, region)
    assert box[0] <= 10 and box[1] <= 5 and box[2] >= 13 and box[3] >= 8
    assert (box[2] - box[0]) % 2 == 0 and (box[3] - box[1]) % 2 == 0
    images, offset = gi.hidden_images(np.dstack([np.ones((20, 30, 3)), seen]).astype(np.float32), region, 30, 20)
    bw, bh = box[2] - box[0], box[3] - box[1]
    assert set(images) == {cg.IMAGE_HIDDEN} and images[cg.IMAGE_HIDDEN].shape == (bh, bw, 4)
    assert offset == (box[0] + bw / 2 - 15, box[1] + bh / 2 - 10)
    assert np.array_equal(images[cg.IMAGE_HIDDEN][..., 3], seen[box[1]:box[3], box[0]:box[2]])
    none, _ = gi.hidden_images(None, region, 30, 20)
    assert none[cg.IMAGE_HIDDEN].shape[:2] == (2, 2) and not none[cg.IMAGE_HIDDEN].any()
    whole, at = gi.hidden_images(None, region, 30, 20, placeable=False)
    assert whole[cg.IMAGE_HIDDEN].shape[:2] == (18, 26) and at == (0.0, 0.0)


def test_a_host_without_the_filter_runs_the_first_level_as_a_gaussian_of_its_sigma():
    """Where the first level is a Gaussian (host/nodes.soften_is_a_filter
    false) the lift's mixes pass D through and ``blur`` gets SOFTEN_SIGMA: with
    a ``blur`` that is the 3x3 kernel at that sigma, both hosts' groups agree."""
    base, position, spec, uv, seen, weight, lod, light, colour = scene()
    images = images_of(base, position, spec, uv, weight, lod)
    sigmas = []

    def blur(img, sigma):
        sigmas.append(sigma)
        return gm._softened(np.asarray(img, np.float32)) if sigma == cg.SOFTEN_SIGMA else gauss_clamp(img, sigma)

    kw = dict(specular_light=light, specular_color=colour)
    filt = gm.evaluate_group(base, images, np_map_uv, gauss_clamp, **kw)
    gauss = gm.evaluate_group(base, images, np_map_uv, blur, soften_filters=False, **kw)
    assert sigmas.count(cg.SOFTEN_SIGMA) == 1 and len(sigmas) == len(cg.BLUR_LEVELS)
    assert np.abs(filt["Reflection"]).max() > 0.01
    assert np.allclose(filt["Image"], gauss["Image"], atol=ATOL)


@pytest.mark.parametrize("wh", [(64, 48), (66, 50), (68, 52), (1920, 1080), (1918, 1078), (7, 3), (1, 1)])
def test_the_grid_shift_places_a_domain_scale_s_read_on_the_texels_frame_scale_reads(wh):
    """On 5.x the Scale and the Translate after it transform the canvas's
    domain, which the Mix samples once at u = (x + 0.5 - W / 2 - t) / s + cw / 2
    - 0.5 - c: a canvas centred on the frame, s = W / cw, c = -0.5 where cw and
    W differ in parity (Blender's realize_on_domain, read in its source). With
    coarse_grid_shift as t that is frame_scale's texel x cw / W at every pixel
    (checked in Blender 5.2 to 2e-6 at 64x48, 66x50 and 68x52)."""
    w, h = wh
    for size, n, t in zip((w, h), gi.coarse_size(w, h), gi.coarse_grid_shift(w, h)):
        c = -0.5 if n % 2 != size % 2 else 0.0
        x = np.arange(size, dtype=np.float64)
        u = (x + 0.5 - size / 2 - t) / (size / n) + n / 2 - 0.5 - c
        assert np.allclose(u, x * n / size, rtol=0, atol=1e-9)


@pytest.mark.parametrize("wh", [(64, 48), (66, 50), (1920, 1080), (1918, 1078), (7, 3), (1, 1)])
def test_the_scale_offset_places_4_3_s_read_on_the_texels_frame_scale_reads(wh):
    """4.2-4.3's Scale to the render size reads u = (x + 0.5 - ox W) cw / W - 0.5
    and v = (y + 0.5 - oy W) ch / H - 0.5 with offsets (ox, oy), both fractions
    of the frame's width (fitted in Blender 4.3 on random canvases, 64x48 from
    16x6 and 16x12, 66x50, 480x270 and 1920x1080). coarse_scale_offset's
    offsets make that frame_scale's texel x cw / W, y ch / H."""
    w, h = wh
    cw, ch = gi.coarse_size(w, h)
    ox, oy = gi.coarse_scale_offset(w, h)
    x, y = np.arange(w, dtype=np.float64), np.arange(h, dtype=np.float64)
    assert np.allclose((x + 0.5 - ox * w) * cw / w - 0.5, x * cw / w, rtol=0, atol=1e-9)
    assert np.allclose((y + 0.5 - oy * w) * ch / h - 0.5, y * ch / h, rtol=0, atol=1e-9)


@pytest.mark.parametrize("hw", [(1, 1), (7, 9), (50, 66), (270, 480), (1080, 1920)])
def test_the_cores_bin_means_are_the_rules_bit_for_bit(core, hw):
    """The coarse texels' mean lod: glint_core.positive_bin_means (the add-on's
    frames) against positive_bin_means, the rule in numpy, on lods with zeros,
    negatives and a NaN, on whole frames and on a region cut from a 4-channel
    image (a strided view, as the add-on hands it)."""
    h, w = hw
    rng = np.random.default_rng(11)
    weight = rng.uniform(-1, 9, (h, w, 4)).astype(np.float32)
    weight[rng.uniform(size=(h, w)) < 0.3, 3] = 0.0
    weight[h // 2, w // 2, 3] = np.nan
    cw, ch = gi.coarse_size(w, h)
    regions = [(0, 0, w, h)] + ([(3, 2, w - 5, h - 1)] if w > 8 and h > 3 else [])
    for x0, y0, x1, y1 in regions:
        lod = weight[y0:y1, x0:x1, 3]
        tx, ty = gi._nearest_texels(x0, x1, w, cw), gi._nearest_texels(y0, y1, h, ch)
        want = gi.positive_bin_means(lod, ty, tx, (ch, cw))
        got = core.positive_bin_means(lod, ty, tx, (ch, cw))
        assert got.dtype == np.float32 and np.array_equal(got, want, equal_nan=True), (hw, x0, y0)
    if h > 1:  # bins that decrease
        with pytest.raises(ValueError, match="row_bins"):
            core.positive_bin_means(weight[..., 3], np.arange(h)[::-1].copy(), np.zeros(w), (h, 1))
    with pytest.raises(ValueError, match="col_bins"):
        core.positive_bin_means(weight[..., 3], np.zeros(h), np.full(w, 2), (1, 2))


@pytest.mark.parametrize("hw", [(12, 16), (50, 66), (1, 1)])
def test_the_coarse_canvas_comes_back_as_blenders_scale_reads_it(hw):
    """frame_scale's model against the read written out (3.4's Scale to the
    render size: texel x n / W at pixel x, 0 past the canvas; checked on Blender
    3.4 at 64x36 and 66x50 to 1e-6), on frames whose size is not whole texels,
    and the coarse canvas's texels on the frame's grid whatever the region."""
    h, w = hw
    cw, ch = gi.coarse_size(w, h)
    img = np.random.default_rng(4).uniform(-1, 1, (ch, cw, 4)).astype(np.float32)
    x = (np.arange(w) * (cw / w))[None, :] * np.ones((h, 1))
    y = (np.arange(h) * (ch / h))[:, None] * np.ones((1, w))
    assert np.allclose(gm._scaled_to_frame(img, (h, w)), bilinear_zero(img, x, y), atol=1e-6)
    lod = np.random.default_rng(5).uniform(-1, 9, (h, w)).astype(np.float32)
    whole = gi.coarse_images(lod, (0, 0, w, h), w, h)
    if w > 4:
        region = (3, 2, w - 5, h - 1)
        cut = np.zeros_like(lod)
        cut[2:h - 1, 3:w - 5] = lod[2:h - 1, 3:w - 5]
        part = gi.coarse_images(lod[2:h - 1, 3:w - 5], region, w, h, fine=False)
        assert cg.IMAGE_FINE not in part
        same = gi.coarse_images(cut, (0, 0, w, h), w, h)[cg.IMAGE_COARSE]
        assert np.allclose(part[cg.IMAGE_COARSE][..., 3], same[..., 3])
    fine = whole[cg.IMAGE_FINE]  # the Map UV read-back: the same points as the Scale's
    assert np.allclose(fine[..., 0] * cw - 0.5, x) and np.allclose(fine[..., 1] * ch - 0.5, y)

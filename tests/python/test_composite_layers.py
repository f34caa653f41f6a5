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


def continued_lod_reference(weight, uv, spec, pos):
    """continue_lod's rule with the true (Euclidean) distance, by brute force:
    ({pixel: lod} of the misses whose answer is certain, the set of misses the
    chamfer distance may settle either way: near a tie between hits of
    different lods, or past the reach by at most its 8% slack)."""
    hit = uv[..., 2] > 0
    hits, lods = np.argwhere(hit), weight[..., 3][hit]
    sure, either = {}, set()
    reflective = (pos[..., 3] > 0) & (spec[..., :3].mean(-1) > 0)
    for y, x in np.argwhere(~hit & reflective):
        d = np.hypot(hits[:, 0] - y, hits[:, 1] - x)
        k = int(np.argmin(d))
        rivals = d[lods != lods[k]]
        if rivals.size and rivals.min() - d[k] < 1.5:
            either.add((y, x))
            continue
        radius = 2.0 ** (lods[k] - 1) if lods[k] > 0 else -1.0
        if d[k] <= radius:
            sure[(y, x)] = lods[k]
        elif d[k] <= radius * 1.0824:
            either.add((y, x))
        else:
            sure[(y, x)] = 0.0
    return sure, either


def test_misses_take_the_nearest_blurred_hits_lod():
    """Two blocks of hits (lod 3: reach 4 px; lod 4.5: reach 11 px) on a
    reflective frame with a column that does not reflect and an unseen pixel:
    misses within reach take the nearest block's lod, those beyond keep 0, and
    hits, non-reflective and unseen pixels keep theirs."""
    h, w = 40, 64
    pos = np.zeros((h, w, 4), np.float32)
    pos[..., 2], pos[..., 3] = -5.0, 1.0
    pos[20, 30, 3] = 0.0  # unseen
    spec = np.zeros((h, w, 4), np.float32)
    spec[..., :3], spec[..., 3] = 0.04, 0.5
    spec[:, 50, :3] = 0.0  # does not reflect
    uv = np.zeros((h, w, 4), np.float32)
    weight = np.zeros((h, w, 4), np.float32)
    weight[..., :3] = 0.1
    uv[8:16, 6:14, 2] = 1.0
    weight[8:16, 6:14, 3] = 3.0
    uv[22:30, 36:44, 2] = 1.0
    weight[22:30, 36:44, 3] = 4.5
    weight[25, 40, 3] = 0.0  # one sharp hit inside the block stays sharp
    got = glint_core.continue_lod(weight, uv, spec, pos)
    assert np.array_equal(got[..., :3], weight[..., :3])
    hit = uv[..., 2] > 0
    assert np.array_equal(got[..., 3][hit], weight[..., 3][hit])
    assert got[20, 30, 3] == 0.0 and not got[:, 50, 3].any()
    sure, either = continued_lod_reference(weight, uv, spec, pos)
    continued = [p for p, lod in sure.items() if lod > 0]
    assert len(continued) > 300 and len(either) < len(continued) / 2
    for (y, x), lod in sure.items():
        assert got[y, x, 3] == lod, (y, x, got[y, x, 3], lod)
    assert got[16 + 3, 10, 3] == 3.0 and got[16 + 6, 10, 3] == 0.0  # reach 4 below block 1
    assert got[26, 44 + 10, 3] == 4.5 and got[26, 44 + 13, 3] == 0.0


def test_nothing_to_continue_without_a_blurred_hit():
    h, w = 12, 16
    pos = np.zeros((h, w, 4), np.float32)
    pos[..., 3] = 1.0
    spec = np.full((h, w, 4), 0.5, np.float32)
    uv = np.zeros((h, w, 4), np.float32)
    uv[4:6, 4:6, 2] = 1.0
    weight = np.zeros((h, w, 4), np.float32)  # a mirror's hits: lod 0
    assert np.array_equal(glint_core.continue_lod(weight, uv, spec, pos), weight)
    assert np.array_equal(glint_core.continue_lod(weight, np.zeros_like(uv), spec, pos), weight)
    with pytest.raises(ValueError, match="uv"):
        glint_core.continue_lod(weight, uv[:5], spec, pos)
    huge = weight.copy()
    huge[4, 4, 3] = np.inf  # reaches the whole frame, without overflowing
    assert glint_core.continue_lod(huge, uv, spec, pos)[0, 0, 3] == np.inf


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
    # The colour is read inside outlines, then the misses are continued.
    want_uv = continued_reference(glint_core.read_inside_outlines(uv, gb["position"], thickness=kw["thickness"]), 2)
    want_uv[..., 3] = want_uv[..., 2]  # no hidden side: the share replaced is vis
    assert np.array_equal(layers["uv"], want_uv)
    weight = glint_core.specular_weight(gb["position"], gb["normal"], spec, proj, backend=backend)
    assert np.array_equal(layers["weight"][..., :3], weight[..., :3])
    lod = glint_core.cone_lod(uv, spec, position=gb["position"], projection=proj)
    hits_lod = np.concatenate([weight[..., :3], lod[..., None]], axis=-1)
    assert np.array_equal(layers["weight"][..., 3], glint_core.continue_lod(hits_lod, uv, spec, gb["position"])[..., 3])
    assert (layers["weight"][..., 3] > lod).any()
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


def hidden_reference(uv, back_albedo):
    """docs/hiz.md, *Blocked rays*: an occluder entered by its hidden side
    (hit channel ENTERED_HIDDEN) whose texel has a back surface shows that
    surface's albedo, with its visibility in alpha; everything else is 0."""
    entered_hidden = glint_core.schema()["constants"]["ENTERED_HIDDEN"]
    h, w = uv.shape[:2]
    out = np.zeros((h, w, 4), np.float32)
    for y in range(h):
        for x in range(w):
            u, v, vis, hit = uv[y, x]
            if not vis > 0 or hit != entered_hidden:
                continue
            i, j = int(np.floor(u * np.float32(w))), int(np.floor(v * np.float32(h)))  # in float32, as the core
            if 0 <= i < w and 0 <= j < h and back_albedo[j, i, 3] > 0:
                out[y, x, :3] = back_albedo[j, i, :3]
                out[y, x, 3] = vis
    return out


def test_hidden_sides_take_the_back_surfaces_albedo():
    h, w = 6, 8
    uv = np.zeros((h, w, 4), np.float32)
    albedo = np.zeros((h, w, 4), np.float32)
    albedo[2, 3] = (0.5, 0.25, 0.125, 1.0)                 # a closed object's far side
    centre = ((3 + 0.5) / w, (2 + 0.5) / h)
    uv[0, 0] = (*centre, 0.8, -1.0)                       # entered by the hidden side
    uv[0, 1] = (*centre, 0.8, 0.0)                        # an occluder found a texel late
    uv[0, 2] = (*centre, 0.8, 0.8)                        # a hit
    uv[0, 3] = ((1 + 0.5) / w, (1 + 0.5) / h, 1.0, -1.0)  # entered, but no back surface there
    got, count = glint_core.hidden_sides(uv, albedo)
    assert count == 1
    assert np.allclose(got[0, 0], (0.5, 0.25, 0.125, 0.8)) and not got.reshape(-1, 4)[1:].any()
    assert np.array_equal(got, hidden_reference(uv, albedo))
    with pytest.raises(ValueError, match="back_albedo"):
        glint_core.hidden_sides(uv, albedo[:5])


def settle_reference(uv, hidden, back_albedo):
    """docs/hiz.md, *Uncertain shares inside a reflection*, pixel by pixel:
    a hit under its screen-edge fade whose eight neighbours all report
    something, within REUSE_PIXELS of its hit unless it is a hidden side
    entered, gives the rest of the fade to the hidden side when a neighbour
    entered one (and its hit's texel has a back surface), else to itself.
    Decided on the uv as given."""
    const = glint_core.schema()["constants"]
    entered, reach, edge_fade = const["ENTERED_HIDDEN"], const["REUSE_PIXELS"], const["EDGE_FADE"]
    h, w = uv.shape[:2]
    uv_out, hid_out = uv.copy(), hidden.copy()
    f32 = np.float32
    for y in range(1, h - 1):
        for x in range(1, w - 1):
            u, v, vis, hit = uv[y, x]
            if not hit > 0:
                continue
            # the fade toward the edge the pixel's ray heads for (glint/schema.h)
            du, dv = u - (f32(x) + f32(0.5)) / f32(w), v - (f32(y) + f32(0.5)) / f32(h)
            mu, mv = (f32(1) - u if du > 0 else u), (f32(1) - v if dv > 0 else v)
            if du == 0 and dv == 0:
                edge = min(min(u, f32(1) - u), min(v, f32(1) - v))
            else:
                edge = mu if mu * abs(dv) <= mv * abs(du) else mv
            fade = f32(min(max(edge / f32(edge_fade), f32(0)), f32(1)))
            if not vis < fade * f32(0.999):
                continue
            near = [uv[y + dy, x + dx] for dy in (-1, 0, 1) for dx in (-1, 0, 1) if dy or dx]
            if not all(q[2] > 0 and (q[3] == entered
                                     or ((q[0] - u) * f32(w)) ** 2 + ((q[1] - v) * f32(h)) ** 2 <= f32(reach) ** 2)
                       for q in near):
                continue
            i, j = int(np.floor(u * f32(w))), int(np.floor(v * f32(h)))
            # the hit's back surface, else that of the first entered neighbour
            # (rows up, then along) whose texel has one
            backs = [(i, j)] + [(int(np.floor(q[0] * f32(w))), int(np.floor(q[1] * f32(h))))
                                for q in near if q[3] == entered]
            backs = [(bi, bj) for bi, bj in backs if 0 <= bi < w and 0 <= bj < h and back_albedo[bj, bi, 3] > 0]
            if any(q[3] == entered for q in near) and backs:
                bi, bj = backs[0]
                share = fade - vis
                hid_out[y, x, :3] = back_albedo[bj, bi, :3] * (share / fade)
                hid_out[y, x, 3] = share
            else:
                uv_out[y, x, 2] = uv_out[y, x, 3] = fade
    return uv_out, hid_out


def test_uncertain_shares_go_to_the_hidden_side_or_the_hit():
    """A hit the march was unsure of (vis under its fade), inside its reflection:
    beside a hidden side it shares with it, elsewhere it is sure; on the
    reflection's outline, or beside another object's hit, it stays."""
    h, w = 7, 9
    albedo = np.zeros((h, w, 4), np.float32)
    albedo[:, :] = (0.6, 0.3, 0.2, 1.0)
    centre = np.array([(4 + 0.5) / w, (3 + 0.5) / h], np.float32)

    def block(vis=0.6, tag=None):
        uv = np.zeros((h, w, 4), np.float32)
        uv[2:5, 3:6, :2] = centre
        uv[2:5, 3:6, 2:] = 1.0
        uv[3, 4, 2:] = vis
        if tag is not None:
            uv[2, 3, 3] = tag
        return uv

    zeros = np.zeros((h, w, 4), np.float32)
    entered = glint_core.schema()["constants"]["ENTERED_HIDDEN"]
    uv, hid, count = glint_core.settle_uncertain_shares(block(tag=entered), zeros, albedo)
    assert count == 1 and np.isclose(uv[3, 4, 2], 0.6) and np.allclose(hid[3, 4], (0.24, 0.12, 0.08, 0.4))
    uv, hid, count = glint_core.settle_uncertain_shares(block(), zeros, albedo)
    assert count == 0 and uv[3, 4, 2] == uv[3, 4, 3] == 1.0 and not hid.any()
    # A hidden side's report is the texel its ray entered, texels behind the
    # rim: it counts at any distance (an antialiased line between the two sides).
    far_entered = block(tag=entered)
    far_entered[2, 3, 1] += 5.0 / h
    uv, hid, count = glint_core.settle_uncertain_shares(far_entered, zeros, albedo)
    assert count == 1 and np.allclose(hid[3, 4], (0.24, 0.12, 0.08, 0.4))
    for case in ("miss", "far", "edge"):
        before = block(tag=entered)
        if case == "miss":
            before[4, 5] = 0.0
        elif case == "far":
            before[4, 5, 0] += 4.0 / w
        else:  # near the screen's edge: as sure as the fade lets it be
            before[2:5, 3:6, 1] = np.float32(0.5 / h)
            before[3, 4, 2:] = np.float32(0.5 / h) / np.float32(0.075)
        uv, hid, count = glint_core.settle_uncertain_shares(before, zeros, albedo)
        assert count == 0 and np.array_equal(uv, before) and not hid.any(), case
    # A rim texel the back layer does not cover: the albedo of the texel the
    # hidden side's ray entered.
    rim = block(tag=entered)
    rim[2, 3, :2] = ((6 + 0.5) / w, (1 + 0.5) / h)
    bare = albedo.copy()
    bare[3, 4] = 0.0
    bare[1, 6] = (0.2, 0.4, 0.6, 1.0)
    uv, hid, count = glint_core.settle_uncertain_shares(rim, zeros, bare)
    assert count == 1 and np.allclose(hid[3, 4], (0.08, 0.16, 0.24, 0.4))
    want_uv, want_hid = settle_reference(rim, zeros, bare)
    uv, hid, _ = glint_core.settle_uncertain_shares(rim, zeros, bare)
    assert np.array_equal(uv, want_uv) and np.array_equal(hid, want_hid)
    for case in (block(tag=entered), block(), far_entered):
        want_uv, want_hid = settle_reference(case, zeros, albedo)
        uv, hid, _ = glint_core.settle_uncertain_shares(case, zeros, albedo)
        assert np.array_equal(uv, want_uv) and np.array_equal(hid, want_hid)


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_layers_show_hidden_sides_in_place_of_the_occluder(backend, request):
    """With the back layer's albedo, the pixels whose rays came in by an object's
    hidden side leave the uv's visibility (vis 0, uv kept) for the hidden image;
    the rest of the layers are what they are without it."""
    if backend == "gl":
        request.getfixturevalue("gl")
    sc = A.mirror_floor_scene()
    gb = A.render(sc, 160, 120)
    back = A.back_layer(sc, gb)
    albedo = np.zeros_like(back)
    rng = np.random.default_rng(1)
    albedo[back[..., 3] > 0] = np.concatenate([rng.uniform(0.1, 0.9, ((back[..., 3] > 0).sum(), 3)),
                                              np.ones(((back[..., 3] > 0).sum(), 1))], axis=1)
    proj = gb["projection"].astype(np.float32)
    kw = dict(glint_core.presets()["balanced"], backend=backend, back_position=back, blocked="occluder")
    plain = glint_core.composite_layers(gb["position"], gb["normal"], gb["specular"], proj, **kw)
    layers = glint_core.composite_layers(gb["position"], gb["normal"], gb["specular"], proj, **kw,
                                         back_albedo=albedo)
    uv = glint_core.trace(gb["position"], gb["normal"], proj, specular=gb["specular"], **kw)
    settled, want = settle_reference(uv, hidden_reference(uv, albedo), albedo)
    entered = (uv[..., 3] == glint_core.schema()["constants"]["ENTERED_HIDDEN"]) & (want[..., 3] > 0)
    shared = (want[..., 3] > 0) & ~entered
    changed = ~entered & ~shared & (settled[..., 2] != uv[..., 2])
    assert layers["hidden_pixels"] == entered.sum() + shared.sum() and entered.sum() > 50
    assert np.array_equal(layers["hidden"], want)
    assert np.array_equal(layers["uv"][entered, 2], np.zeros(entered.sum(), np.float32))
    assert np.array_equal(layers["uv"][entered, 3], want[entered, 3])  # what they replace
    # A hit sharing with a hidden side keeps its vis; it replaces both shares.
    assert np.array_equal(layers["uv"][shared, 2], uv[shared, 2])
    assert np.array_equal(layers["uv"][shared, 3], uv[shared, 2] + want[shared, 3])
    assert np.array_equal(layers["uv"][changed, 2], settled[changed, 2])
    rest = ~entered & ~shared & ~changed
    assert np.array_equal(layers["uv"][rest], plain["uv"][rest])
    assert np.array_equal(layers["uv"][entered | shared, :2], plain["uv"][entered | shared, :2])
    assert np.array_equal(layers["weight"], plain["weight"])
    assert "hidden" not in plain


def inside_reference(uv, position, back, thickness):
    """read_inside_outlines() written from its description (glint/composite.h), one
    pixel at a time in float64."""
    h, w = position.shape[:2]
    out = uv.copy()
    seen = (position[..., 3] > 0) & np.isfinite(position).all(axis=-1)
    for y, x in zip(*np.nonzero(uv[..., 2] > 0)):
        # The texel of the uv as the core finds it: the float32 product, floored.
        i = int(np.floor(np.float32(uv[y, x, 0]) * np.float32(w)))
        j = int(np.floor(np.float32(uv[y, x, 1]) * np.float32(h)))
        if not (0 <= i < w and 0 <= j < h) or not seen[j, i]:
            continue
        def thick(ai, aj):
            d = -float(position[aj, ai, 2])
            if back is not None and back[aj, ai, 3] > 0 and -back[aj, ai, 2] > d:
                return -float(back[aj, ai, 2]) - d
            return thickness

        d = -float(position[j, i, 2])
        t = thick(i, j)

        def inside_frame(qi, qj):
            return 0 <= qi < w and 0 <= qj < h

        def outside(qi, qj):
            return inside_frame(qi, qj) and (not seen[qj, qi] or -position[qj, qi, 2] > d + t)

        si = int(outside(i - 1, j)) - int(outside(i + 1, j))
        sj = int(outside(i, j - 1)) - int(outside(i, j + 1))
        if (si, sj) == (0, 0):
            # Not on an outline, but within half a texel of one along an axis
            # (the texel beside outside, or on a line whose next texel is):
            # to its own texel's centre on that axis.
            def rim(ai, aj, bi, bj):
                if not inside_frame(ai, aj):
                    return False
                if outside(ai, aj):
                    return True
                if not inside_frame(bi, bj):
                    return False
                return not seen[bj, bi] or -position[bj, bi, 2] > -float(position[aj, ai, 2]) + thick(ai, aj)

            fx = np.float32(uv[y, x, 0]) * np.float32(w) - np.float32(i)
            fy = np.float32(uv[y, x, 1]) * np.float32(h) - np.float32(j)
            ex, ey = (-1 if fx < 0.5 else 1), (-1 if fy < 0.5 else 1)
            if rim(i + ex, j, i + 2 * ex, j):
                out[y, x, 0] = (i + 0.5) / w
            if rim(i, j + ey, i, j + 2 * ey):
                out[y, x, 1] = (j + 0.5) / h
            continue
        qi, qj = i + si, j + sj
        if (si, sj) == (0, 0) or not (0 <= qi < w and 0 <= qj < h) or not seen[qj, qi] or outside(qi, qj):
            continue
        out[y, x, :2] = ((qi + 0.5) / w, (qj + 0.5) / h)
    return out


@pytest.mark.parametrize("back", [False, True])
def test_the_colour_is_read_inside_outlines(back):
    """A hit or occluder on an object's outline texel is read one texel inside the
    object, where the frame is the object alone; every other report keeps its uv."""
    sc = A.mirror_floor_scene()
    gb = A.render(sc, 160, 120)
    back_layer = A.back_layer(sc, gb) if back else None
    uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], back_position=back_layer,
                          blocked="occluder", **glint_core.presets()["balanced"])
    got = glint_core.read_inside_outlines(uv, gb["position"], back_position=back_layer, thickness=0.5)
    want = inside_reference(uv, gb["position"], back_layer, 0.5)
    moved = (got != uv).any(axis=-1)
    assert moved.sum() > 20, "the scene's reflections should meet outlines"
    assert np.allclose(got, want, atol=1e-7) and np.array_equal(got[..., 2:], uv[..., 2:])
    # A moved read lands on the object: the texel it reads is no farther than the
    # outline texel's own depth plus its thickness.
    h, w = uv.shape[:2]
    i = (got[moved, 0] * np.float32(w)).astype(int)
    j = (got[moved, 1] * np.float32(h)).astype(int)
    i0, j0 = (uv[moved, 0] * np.float32(w)).astype(int), (uv[moved, 1] * np.float32(h)).astype(int)
    assert (gb["position"][j, i, 3] > 0).all()
    assert (np.abs(i - i0) <= 1).all() and (np.abs(j - j0) <= 1).all()
    d0 = -gb["position"][j0, i0, 2]
    t0 = np.full_like(d0, 0.5)
    if back:
        b = back_layer[j0, i0]
        t0 = np.where((b[:, 3] > 0) & (-b[:, 2] > d0), -b[:, 2] - d0, 0.5)
    assert (-gb["position"][j, i, 2] <= d0 + t0 + 1e-4).all()


def test_read_inside_outlines_refuses_bad_input():
    gb = A.render(A.mirror_floor_scene(), 16, 12)
    uv = np.zeros((12, 16, 4), np.float32)
    with pytest.raises(ValueError, match="uv"):
        glint_core.read_inside_outlines(uv[:5], gb["position"])
    with pytest.raises(ValueError, match="thickness"):
        glint_core.read_inside_outlines(uv, gb["position"], thickness=float("nan"))


def test_a_hits_own_specular_is_taken_along_the_ray():
    """world_specular: the colour a hit samples holds its surface's specular as the
    camera sees it, W(hit) x colour at the camera's N.V there. Along the ray the
    surface shows W'(hit) x colour, W' the split-sum weight at N.V = -ray . normal(hit);
    `replaced` grows by vis x (W - W') so that a compositor subtracting replaced x colour
    reflects the hit as the ray sees it (docs/look-core.md, *The hit's own specular*),
    but for the share the hit's own reflection (its vis) replaces.
    A corridor of glossy dielectric walls at grazing angles, computed here in numpy from
    env_brdf() and specular_weight(): the hits on the walls differ from the camera's
    view by 0.05 and more."""
    import math
    glossy = A.Material(color=(0.5, 0.5, 0.5), specular=(0.04, 0.04, 0.04), alpha=0.9)
    sc = A.Scene([A.Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), glossy),
                  A.Box((-2.2, -2.0, 0.0), (-1.8, 40.0, 3.0), glossy),
                  A.Box((1.8, -2.0, 0.0), (2.2, 40.0, 3.0), glossy)],
                 A.Camera(eye=(0.0, -1.5, 0.45), target=(0.0, 30.0, 0.25), fov=math.radians(60.0), near=0.05,
                          far=200.0))
    gb = A.render(sc, 96, 64)
    args = (gb["position"], gb["normal"], gb["specular"], gb["projection"])
    kw = dict(glint_core.presets()["balanced"], resolution=1.0, antialias=0)
    plain = glint_core.composite_layers(*args, **kw)
    along = glint_core.composite_layers(*args, **kw, world_specular=True)
    uv = plain["uv"]
    assert np.array_equal(along["uv"][..., :3], uv[..., :3]) and np.array_equal(along["weight"], plain["weight"])
    h, w = uv.shape[:2]
    vis = uv[..., 2]
    i = np.clip(np.floor(uv[..., 0] * w).astype(int), 0, w - 1)
    j = np.clip(np.floor(uv[..., 1] * h).astype(int), 0, h - 1)
    cam = glint_core.specular_weight(gb["position"], gb["normal"], gb["specular"], gb["projection"])[..., :3]
    p = gb["position"][..., :3].astype(float)
    n = gb["normal"][..., :3].astype(float)
    d = p / np.maximum(np.linalg.norm(p, axis=-1, keepdims=True), 1e-30)
    n = n / np.maximum(np.linalg.norm(n, axis=-1, keepdims=True), 1e-30)
    ray = d - 2.0 * (d * n).sum(-1, keepdims=True) * n
    want = uv[..., 3].astype(float).copy()
    k_all = np.zeros((h, w))
    for y, x in zip(*np.nonzero(vis > 0)):
        s = gb["specular"][j[y, x], i[y, x]]
        if not s[:3].mean() > 0:
            continue
        nh = n[j[y, x], i[y, x]]
        nv = min(max(-float(ray[y, x] @ nh), 0.0), 1.0)
        a, b = glint_core.env_brdf(nv, glint_core.ggx_alpha(float(s[3])))
        own = min(max(float(uv[j[y, x], i[y, x], 2]), 0.0), 1.0)  # the hit's own reflection keeps its weight
        k = (cam[j[y, x], i[y, x]].mean() - float(np.mean(s[:3] * a + b))) * (1.0 - own)
        k_all[y, x] = k
        want[y, x] += vis[y, x] * k
    assert (np.abs(k_all) > 0.05).sum() > 100, "the walls' hits should see their specular otherwise"
    assert np.allclose(along["uv"][..., 3], want, atol=2e-4)
    assert np.array_equal(plain["uv"][..., 3], uv[..., 2])  # without it: replaced is vis

"""The physically based look (docs/look-core.md) on the CPU backend: the split-sum
weight against a float64 integral written here, the cone blur against formulas,
replacing the engine's specular, the stage chain and its skips, and the seed's
pipeline kept bit for bit.

data/seed_pipeline_before_weighting.npz holds the G-buffers and every layer of
glint_core.pipeline(..., march="seed", combine=<seed|over>, blur_size=3,
blur_separation=1.5) as commit c4c64de (before weighting and cone blur
existed) computed them, on two 48x32 analytic scenes (mirror_floor_scene,
floor specular (0.8, 0.7, 0.9), alpha 0.6, perspective and orthographic).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

import analytic as A
import glint_core
from glint_tables import addon_schema

SCHEMA = addon_schema()

DATA = Path(__file__).resolve().parent / "data"
SEED_LOOK = dict(weighting="seed", blur="box")


# --- the float64 reference of the split-sum integrals ----------------------------------


def smith_lambda(c, a2):
    c = np.asarray(c, float)
    return 0.5 * (-1.0 + np.sqrt(1.0 + a2 * (1.0 - c * c) / (c * c)))


def fresnel_rim(c):
    """Fh of docs/look-core.md: a dielectric's reflectance at cosine c (the mean
    of the s and p Fresnel equations, through Snell's law) rescaled to 0 head on
    and 1 at grazing, for the index schema FRESNEL_SHAPE_IOR."""
    n = SCHEMA.FRESNEL_SHAPE_IOR
    c = np.clip(np.asarray(c, float), 0.0, 1.0)
    cos_t = np.sqrt(1.0 - (1.0 - c * c) / (n * n))
    rs = (c - n * cos_t) / (c + n * cos_t)
    rp = (n * c - cos_t) / (n * c + cos_t)
    f0 = ((n - 1) / (n + 1)) ** 2
    return (0.5 * (rs * rs + rp * rp) - f0) / (1.0 - f0)


def env_brdf_reference(nov, alpha, nu=2048, nphi=256):
    """A = int (1 - Fh) f cos dl, B = int Fh f cos dl for GGX + height-correlated
    Smith, Fh = fresnel_rim(V.H), over half-vectors in the variables where D (N.H) is
    uniform (u = CDF of the polar angle, phi), u = 1 - (1 - s)^3 against the
    1 / N.H growth near u = 1; phi over the full circle."""
    a2 = alpha * alpha
    s = (np.arange(nu) + 0.5) / nu
    u = 1.0 - (1.0 - s) ** 3
    jac = 3.0 * (1.0 - s) ** 2
    phi = 2.0 * np.pi * (np.arange(nphi) + 0.5) / nphi
    ct = np.sqrt((1.0 - u) / (1.0 + (a2 - 1.0) * u))[:, None]
    st = np.sqrt(1.0 - ct * ct)
    hx = st * np.cos(phi)[None, :]
    vx, vz = math.sqrt(1.0 - nov * nov), nov
    voh = vx * hx + vz * ct
    lz = 2.0 * voh * ct - vz
    ok = (lz > 0) & (voh > 0)
    g2 = 1.0 / (1.0 + smith_lambda(nov, a2) + smith_lambda(np.where(ok, lz, 1.0), a2))
    gv = np.where(ok, g2 * voh / (ct * nov), 0.0) * jac[:, None]
    fc = fresnel_rim(voh)
    return ((1.0 - fc) * gv).mean(), (fc * gv).mean()


def env_brdf_brute(nov, alpha, nt=2000, nphi=400):
    """The same integrals the textbook way, over light directions on the
    hemisphere: f = D G2 F / (4 N.L N.V), D = a^2 / (pi ((N.H)^2 (a^2 - 1) + 1)^2)."""
    a2 = alpha * alpha
    th = (np.arange(nt) + 0.5) / nt * (np.pi / 2)
    ph = (np.arange(nphi) + 0.5) / nphi * 2 * np.pi
    t, p = np.meshgrid(th, ph, indexing="ij")
    lx, ly, lz = np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)
    vx, vz = math.sqrt(1 - nov * nov), nov
    hx, hy, hz = lx + vx, ly, lz + vz
    n = np.sqrt(hx * hx + hy * hy + hz * hz)
    hx, hz = hx / n, hz / n
    voh = vx * hx + vz * hz
    d = a2 / (np.pi * (hz * hz * (a2 - 1) + 1) ** 2)
    g2 = 1 / (1 + smith_lambda(nov, a2) + smith_lambda(lz, a2))
    f = d * g2 / (4 * lz * nov) * lz * np.sin(t) * (np.pi / 2 / nt) * (2 * np.pi / nphi)
    fc = fresnel_rim(voh)
    return ((1 - fc) * f).sum(), (fc * f).sum()


def ggx_alpha(shininess_alpha):
    """docs/addon.md: hardness = 2 / alpha^2 - 2 = 511 * shininess alpha, past 511
    in the gloss range; inverted, with shininess alpha 1 (the book's 511) read as a
    mirror."""
    if shininess_alpha == 1 or not math.isfinite(shininess_alpha):
        return 0.0
    return math.sqrt(2.0 / (511.0 * max(shininess_alpha, 0.0) + 2.0))


@pytest.mark.parametrize("nov, alpha", [(0.5, 0.5), (0.2, 0.7), (0.9, 0.3)])
def test_reference_agrees_with_the_hemisphere_integral(nov, alpha):
    a, b = env_brdf_reference(nov, alpha)
    ba, bb = env_brdf_brute(nov, alpha)
    assert abs(a - ba) < 2e-4 and abs(b - bb) < 2e-4, (a, ba, b, bb)


def test_reference_of_a_mirror_is_the_fresnel_equations():
    """A mirror reflects F0 + (1 - F0) Fh(N.V); at IOR 1.5 a dielectric (F0 0.04)
    reflects 0.0892 at 60 degrees and 0.3877 at 80 (Fresnel's equations by hand),
    where Schlick's approximation gives 0.0700 and 0.4099."""
    for nov in (0.05, 0.3, 1.0):
        a, b = env_brdf_reference(nov, 0.0, nu=2048, nphi=8)
        fc = fresnel_rim(nov)
        assert a == pytest.approx(1 - fc, abs=1e-6) and b == pytest.approx(fc, abs=1e-6)
    assert SCHEMA.FRESNEL_SHAPE_IOR == 1.5
    for deg, f in ((60, 0.0892), (80, 0.3877), (0, 0.04), (90, 1.0)):
        a, b = env_brdf_reference(math.cos(math.radians(deg)) or 1e-12, 0.0, nu=64, nphi=8)
        assert 0.04 * a + b == pytest.approx(f, abs=2e-4), deg


def ortho_weight(nov, shininess_alpha, f0=(1.0, 0.0, 0.5)):
    """specular_weight of pixels seen by an orthographic camera (view rays -Z)
    whose normals make N.V = nov: one row, one pixel per value."""
    nov = np.asarray(nov, np.float64)
    n = len(nov)
    pos = np.zeros((1, n, 4), np.float32)
    pos[..., 2] = -5.0
    pos[..., 3] = 1.0
    nrm = np.zeros((1, n, 4), np.float32)
    nrm[0, :, 0] = np.sqrt(1 - nov ** 2)
    nrm[0, :, 2] = nov
    spec = np.zeros((1, n, 4), np.float32)
    spec[..., :3] = f0
    spec[..., 3] = shininess_alpha
    proj = A.projection_matrix("ortho", n, 1)
    return glint_core.specular_weight(pos, nrm, spec, proj)


def karis_mobile_fit(nov, roughness):
    """Karis' analytic approximation of A and B ("Physically Based Shading on
    Mobile", 2014), the alternative to a table; roughness = sqrt(alpha)."""
    r = roughness * np.array([-1, -0.0275, -0.572, 0.022]) + np.array([1, 0.0425, 1.04, -0.04])
    a004 = min(r[0] * r[0], 2 ** (-9.28 * nov)) * r[0] + r[1]
    return -1.04 * a004 + r[2], 1.04 * a004 + r[3]


def test_specular_weight_against_the_integral():
    """F0 = (1, 0, 0.5) gives A + B, B and A / 2 + B in one image: the table's
    A and B against the float64 integral, on and between the nodes. Karis'
    mobile fit is measured beside it, for the choice of a table."""
    novs = np.linspace(0.0, 1.0, 41)
    worst = worst_fit = 0.0
    for sa in (39.1, 2.44, 1.001, 1.0, 0.999, 0.9, 0.5, 0.2, 0.05, 0.01, 0.0):
        alpha = ggx_alpha(sa)
        assert glint_core.ggx_alpha(sa) == pytest.approx(alpha, rel=1e-6)
        w = ortho_weight(novs, sa)[0].astype(np.float64)
        got_b = w[:, 1]
        got_a = w[:, 0] - w[:, 1]
        assert np.allclose(w[:, 2], got_a / 2 + got_b, atol=1e-6)
        assert np.allclose(w[:, 3], w[:, :3].mean(axis=1), atol=1e-6)
        for i, nov in enumerate(novs):
            ra, rb = env_brdf_reference(max(float(nov), 1e-4), alpha, nu=512, nphi=128)
            worst = max(worst, abs(got_a[i] - ra), abs(got_b[i] - rb))
            fa, fb = karis_mobile_fit(float(nov), math.sqrt(alpha))
            worst_fit = max(worst_fit, abs(fa - ra), abs(fb - rb))
    print(f"\nmax |error| of A and B against the float64 integral: table {worst:.4f}, "
          f"Karis' mobile fit {worst_fit:.3f}")
    assert worst < 0.01
    assert worst_fit > 10 * worst


def test_weight_uses_the_real_view_ray():
    """Perspective: V = -normalize(position). A floor seen at grazing angles
    reflects far more than at normal incidence (Fresnel)."""
    w, h = 8, 6
    proj = A.projection_matrix("persp", w, h)
    pos = np.zeros((h, w, 4), np.float32)
    rng = np.random.default_rng(3)
    pos[..., :3] = rng.uniform(-1, 1, (h, w, 3))
    pos[..., 2] = rng.uniform(-8, -1, (h, w))
    pos[..., 3] = 1
    nrm = np.zeros_like(pos)
    nrm[..., :3] = rng.normal(size=(h, w, 3))
    nrm[..., 2] = np.abs(nrm[..., 2]) + 0.5
    spec = np.zeros_like(pos)
    spec[..., :3] = (0.04, 0.5, 1.0)
    spec[..., 3] = 0.4
    got = glint_core.specular_weight(pos, nrm, spec, proj).astype(np.float64)
    p = pos[..., :3].astype(np.float64)
    n = nrm[..., :3] / np.linalg.norm(nrm[..., :3], axis=2, keepdims=True)
    nov = np.clip(-(p * n).sum(axis=2) / np.linalg.norm(p, axis=2), 0, 1)
    alpha = ggx_alpha(0.4)
    for y in range(h):
        for x in range(w):
            a, b = env_brdf_reference(max(nov[y, x], 1e-4), alpha, nu=512, nphi=128)
            np.testing.assert_allclose(got[y, x, :3], spec[y, x, :3] * a + b, atol=0.01)


def test_grazing_floor_reflects_more_than_f0():
    w = ortho_weight([1.0, 0.5, 0.1], 1.0, f0=(0.04, 0.04, 0.04))[0]
    assert w[0, 0] == pytest.approx(0.04, abs=2e-3)  # head on: F0
    assert w[2, 0] > 4 * 0.04  # grazing: Fresnel


def test_weight_is_zero_where_nothing_reflects():
    w = ortho_weight([0.5, 0.5], 0.5, f0=(0.0, 0.0, 0.0))
    assert np.all(w == 0)


# --- the cone blur -----------------------------------------------------------------------


def cone_inputs(h, w, offset_px, shininess_alpha):
    uv = np.zeros((h, w, 4), np.float32)
    yy, xx = np.mgrid[0:h, 0:w]
    uv[..., 0] = (xx + 0.5 + offset_px) / w
    uv[..., 1] = (yy + 0.5) / h
    uv[..., 2:] = 1.0
    spec = np.zeros((h, w, 4), np.float32)
    spec[..., :3] = 0.5
    spec[..., 3] = shininess_alpha
    return uv, spec


def footprint_offset(lod, shininess_alpha):
    """The ray length (pixels) whose footprint 2 L tan is 2^lod."""
    a = ggx_alpha(shininess_alpha)
    tan = 2 * a / (1 - a * a)
    return 2.0 ** lod / (2 * tan)


def test_cone_tan_formula():
    for a in (0.0, 0.1, 0.5, 0.9):
        assert glint_core.cone_tan(a) == pytest.approx(min(2 * a / (1 - a * a), 16.0), rel=1e-6)
    assert glint_core.cone_tan(1.0) == 16.0


def test_constant_image_stays_constant():
    h, w = 24, 40
    col = np.empty((h, w, 4), np.float32)
    col[:] = (0.3, 0.6, 0.9, 1.0)
    for off in (0.0, 3.0, 17.0, 200.0):
        uv, spec = cone_inputs(h, w, off, 0.3)
        np.testing.assert_allclose(glint_core.cone_blur(col, uv, spec), col, atol=1e-6)


@pytest.mark.parametrize("lod, want", [(1.0, 0.5), (2.0, 0.5), (3.5, 0.5), (0.5, None)])
def test_checkerboard_gives_its_mean(lod, want):
    """One-texel checkerboard, 64x32: every level from 1 up is exactly 0.5, so a
    footprint of 2^lod texels gives the mean; lod 0.5 is halfway between the
    texel itself and the mean."""
    h, w = 32, 64
    yy, xx = np.mgrid[0:h, 0:w]
    c = ((xx + yy) % 2).astype(np.float32)
    col = np.stack([c, 1 - c, c, np.ones_like(c)], axis=2)
    uv, spec = cone_inputs(h, w, footprint_offset(lod, 0.3), 0.3)
    got = glint_core.cone_blur(col, uv, spec)
    expect = np.full_like(col, 0.5) if want is not None else 0.5 * col + 0.25
    expect[..., 3] = 1.0
    np.testing.assert_allclose(got, expect, atol=1e-5)


def test_contact_and_smooth_pixels_keep_their_colour():
    h, w = 20, 30
    rng = np.random.default_rng(4)
    col = rng.uniform(0, 1, (h, w, 4)).astype(np.float32)
    uv, spec = cone_inputs(h, w, 0.0, 0.1)  # the hit is the pixel itself: ray length 0
    assert glint_core.cone_blur(col, uv, spec).tobytes() == col.tobytes()
    uv, spec = cone_inputs(h, w, 25.0, 1.0)  # shininess 1: a mirror
    assert glint_core.cone_blur(col, uv, spec).tobytes() == col.tobytes()


def flat_mirror_frame(kind, hit_depth, w=40, h=24, depth=5.0):
    """A w x h frame whose left half lies on the plane z = -depth in front of a
    `kind` camera and reflects, each pixel's hit half the frame to its right, on the
    plane z = -hit_depth that the right half shows."""
    offset_px = w // 2
    proj = A.projection_matrix(kind, w, h)
    inv = np.linalg.inv(proj)
    yy, xx = np.mgrid[0:h, 0:w]

    def on_plane(px, py, z):
        ndc = np.stack([(px + 0.5) / w * 2 - 1, (py + 0.5) / h * 2 - 1], -1)
        near = np.concatenate([ndc, -np.ones(ndc.shape[:-1] + (1,)), np.ones(ndc.shape[:-1] + (1,))], -1) @ inv.T
        far = np.concatenate([ndc, np.ones(ndc.shape[:-1] + (1,)), np.ones(ndc.shape[:-1] + (1,))], -1) @ inv.T
        a, b = near[..., :3] / near[..., 3:], far[..., :3] / far[..., 3:]
        return a + (b - a) * ((-z - a[..., 2]) / (b[..., 2] - a[..., 2]))[..., None]

    pos = np.ones((h, w, 4))
    left = xx < offset_px
    pos[..., :3] = np.where(left[..., None], on_plane(xx, yy, depth), on_plane(xx, yy, hit_depth))
    uv, spec = cone_inputs(h, w, offset_px, 0.3)
    uv[~left, 2] = 0.0
    return pos.astype(np.float32), proj, uv, spec


def flat_mirror_lod(pos, proj, uv, spec, kind):
    """The bound by hand, in float64: the hit's 3D distance t, the pixel's camera ray
    carried on by t, and the pixels a view unit spans there (h/2 |P11| / clip w)."""
    h, w = uv.shape[:2]
    a = ggx_alpha(0.3)
    tan = 2 * a / (1 - a * a)
    yy, xx = np.mgrid[0:h, 0:w]
    hx = np.clip(np.floor(uv[..., 0] * w).astype(int), 0, w - 1)
    hy = np.clip(np.floor(uv[..., 1] * h).astype(int), 0, h - 1)
    p = pos[..., :3].astype(np.float64)
    q = p[hy, hx]
    t = np.linalg.norm(q - p, axis=-1)
    d = p / np.linalg.norm(p, axis=-1, keepdims=True) if kind == "persp" else np.array([0.0, 0.0, -1.0])
    v = p + t[..., None] * d
    clip_w = v @ proj[3, :3] + proj[3, 3]
    flat = 2 * t * tan * (h / 2 * abs(proj[1, 1])) / clip_w
    screen = 2 * np.hypot(uv[..., 0] * w - (xx + 0.5), uv[..., 1] * h - (yy + 0.5)) * tan
    fp = np.minimum(flat, screen)
    return np.where((uv[..., 2] > 0) & (fp > 1), np.log2(np.maximum(fp, 1)), 0.0)


@pytest.mark.parametrize("kind, hit_depth, binds", [("persp", 5.0, True), ("persp", 60.0, False),
                                                   ("ortho", 5.0, False), ("ortho", 2.0, False)])
def test_cone_lod_is_no_wider_than_a_flat_mirrors(kind, hit_depth, binds):
    """With the positions and the projection, the footprint is at most a flat mirror's
    (docs/look-core.md, *No wider than a flat mirror*): a perspective mirror whose hits
    lie beside it on its own plane shows them smaller than their screen distance, one
    whose hits are far behind does not. Under an orthographic camera a view unit spans
    the same pixels everywhere and a segment's screen length is at most its 3D length,
    so the bound never binds."""
    pos, proj, uv, spec = flat_mirror_frame(kind, hit_depth)
    plain = glint_core.cone_lod(uv, spec)
    got = glint_core.cone_lod(uv, spec, position=pos, projection=proj)
    np.testing.assert_allclose(got, flat_mirror_lod(pos, proj, uv, spec, kind), atol=1e-4)
    hits = uv[..., 2] > 0
    assert (got <= plain + 1e-6).all()
    assert (got[hits] < plain[hits] - 0.05).all() if binds else np.allclose(got, plain, atol=1e-4)
    # The cone blur reads the same rule: narrower where it binds, the same elsewhere.
    col = np.random.default_rng(3).uniform(0, 1, uv.shape).astype(np.float32)
    bounded = glint_core.cone_blur(col, uv, spec, position=pos, projection=proj)
    unbounded = glint_core.cone_blur(col, uv, spec)
    assert (not np.allclose(bounded, unbounded, atol=1e-6)) is binds
    # A hit off the image (any uv cone_lod() is given) has no texel to bound by.
    off = uv.copy()
    off[..., 0] = np.where(hits, 1e30, off[..., 0])
    np.testing.assert_array_equal(glint_core.cone_lod(off, spec, position=pos, projection=proj),
                                  glint_core.cone_lod(off, spec))
    with pytest.raises(ValueError, match="position"):
        glint_core.cone_lod(uv, spec, position=pos)
    with pytest.raises(ValueError, match="position"):
        glint_core.cone_lod(uv, spec, position=pos[:, :-1], projection=proj)


@pytest.mark.parametrize("shininess_alpha", [0.3, 2.44])  # the book's range, the gloss range
@pytest.mark.parametrize("lod", [0.25, 1.0, 3.5, 6.0])
def test_cone_lod_is_log2_of_the_footprint(lod, shininess_alpha):
    """cone_lod, the map the add-on's compositor blends its blur levels by, is
    log2(2 L tan) for a ray of L pixels; 0 for a mirror, a miss, a non-reflective
    pixel, or a footprint within one pixel."""
    h, w = 20, 30
    uv, spec = cone_inputs(h, w, footprint_offset(lod, shininess_alpha), shininess_alpha)
    got = glint_core.cone_lod(uv, spec)
    assert got.shape == (h, w) and got.dtype == np.float32
    want = max(lod, 0.0) if 2.0 ** lod > 1.0 else 0.0
    np.testing.assert_allclose(got, want, atol=1e-4)
    uv_miss = uv.copy()
    uv_miss[..., 2] = 0.0
    assert not glint_core.cone_lod(uv_miss, spec).any()
    mirror = spec.copy()
    mirror[..., 3] = 1.0
    assert not glint_core.cone_lod(uv, mirror).any()
    dull = spec.copy()
    dull[..., :3] = 0.0
    assert not glint_core.cone_lod(uv, dull).any()
    with pytest.raises(ValueError, match="specular"):
        glint_core.cone_lod(uv, spec[:, :-1])


def test_blur_grows_with_the_ray_length():
    """Far reflections spread: the deviation from the checkerboard mean falls as
    the ray gets longer."""
    h, w = 32, 64
    yy, xx = np.mgrid[0:h, 0:w]
    c = ((xx + yy) % 2).astype(np.float32)
    col = np.stack([c, c, c, np.ones_like(c)], axis=2)
    dev = []
    for off in (0.5, 2.0, 3.0, 4.0, 8.0):
        uv, spec = cone_inputs(h, w, off, 0.3)
        dev.append(np.abs(glint_core.cone_blur(col, uv, spec)[..., 0] - 0.5).mean())
    # Sharp up to a one-texel footprint (2 L tan <= 1), then blurring in.
    assert dev[0] == dev[1] == 0.5 and dev[1] > dev[2] > dev[3] >= dev[4], dev


# --- replace, do not add -----------------------------------------------------------------


def test_combine_replaces_the_engine_specular():
    rng = np.random.default_rng(5)
    h, w = 10, 12
    base = rng.uniform(0.2, 1, (h, w, 4)).astype(np.float32)
    spec_base = (base[..., :3] * rng.uniform(0, 0.5, (h, w, 1))).astype(np.float32)
    refl = rng.uniform(0, 0.3, (h, w, 4)).astype(np.float32)
    cov = np.zeros((h, w, 4), np.float32)
    cov[..., 3] = rng.uniform(-0.2, 1.2, (h, w))
    got = glint_core.combine(base, refl, specular_base=spec_base, coverage=cov)
    c = np.clip(cov[..., 3:4].astype(np.float64), 0, 1)
    want = np.maximum(base[..., :3] - spec_base * c, 0) + refl[..., :3]
    np.testing.assert_allclose(got[..., :3], want, atol=1e-6)
    np.testing.assert_array_equal(got[..., 3], base[..., 3])
    with pytest.raises(ValueError, match="specular_base"):
        glint_core.combine(base, refl, mode="seed", specular_base=spec_base, coverage=cov)
    with pytest.raises(ValueError, match="coverage"):
        glint_core.combine(base, refl, specular_base=spec_base)


W, H = 64, 48


def floor_scene(kind="persp", alpha=0.5, f0=0.04):
    floor = A.Material(color=(0.4, 0.4, 0.4), specular=(f0, f0, f0), alpha=alpha)
    return A.render(A.mirror_floor_scene(kind, floor=floor), W, H)


def run(gb, **kw):
    return glint_core.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"],
                               gb["projection"], **kw)


@pytest.mark.parametrize("kind", ["persp", "ortho"])
def test_pipeline_is_the_physical_stages_chained(kind):
    gb = floor_scene(kind)
    rng = np.random.default_rng(6)
    spec_base = (gb["color"][..., :3] * rng.uniform(0, 0.3, (H, W, 1))).astype(np.float32)
    kw = dict(resolution=0.5, steps=8)
    out = run(gb, specular_base=spec_base, **kw)
    assert out["stats"]["skipped"] == []
    weight = glint_core.specular_weight(gb["position"], gb["normal"], gb["specular"], gb["projection"])
    np.testing.assert_array_equal(out["specular_weight"], weight)
    cone = glint_core.cone_blur(out["reflection_color"], out["uv"], gb["specular"])
    np.testing.assert_array_equal(out["reflection_blur"], cone)
    refl = glint_core.reflection(cone, None, gb["specular"], weight=weight)
    np.testing.assert_array_equal(out["reflection"], refl)
    # The formula: blurred colour x weight; the engine's specular out where covered.
    refl_f = np.where(gb["specular"][..., :1] > 0, cone.astype(np.float64) * weight, 0)
    np.testing.assert_allclose(out["reflection"], refl_f, atol=1e-7)
    want = np.maximum(gb["color"][..., :3] - spec_base * np.clip(cone[..., 3:4], 0, 1), 0) + refl_f[..., :3]
    np.testing.assert_allclose(out["combined"][..., :3], want, atol=1e-6)
    # Where the trace found nothing, the frame is the engine's.
    miss = out["uv"][..., 2] <= 0
    assert miss.sum() > 100
    still = miss & (cone[..., 3] == 0)
    np.testing.assert_array_equal(out["combined"][still], gb["color"][still])


def test_over_without_specular_base_weighs_the_base_by_weight_times_visibility():
    gb = floor_scene(alpha=1.0)
    out = run(gb)
    r = out["reflection"].astype(np.float64)
    c = out["reflection_color"].astype(np.float64)
    w = out["specular_weight"].astype(np.float64)
    np.testing.assert_allclose(r[..., 3], c[..., 3] * w[..., 3], atol=1e-7)
    want = gb["color"][..., :3] * (1 - np.clip(r[..., 3:4], 0, 1)) + r[..., :3]
    np.testing.assert_allclose(out["combined"][..., :3], want, atol=1e-6)


def test_skips_what_the_scene_does_not_need():
    gb = floor_scene(alpha=1.0)
    assert run(gb)["stats"]["skipped"] == ["cone_blur"]  # nothing rough
    assert run(gb, **SEED_LOOK)["stats"]["skipped"] == ["specular_weight", "box_blur"]
    # The gloss range (alpha above 1) has a lobe for the cone, none for the book's box.
    gb["specular"][..., 3] = np.where(gb["specular"][..., 3] > 0, 2.44, 0.0)
    assert run(gb)["stats"]["skipped"] == []
    assert run(gb, **SEED_LOOK)["stats"]["skipped"] == ["specular_weight", "box_blur"]
    gb["specular"][...] = 0  # nothing reflective: nothing runs
    out = run(gb)
    assert set(out["stats"]["skipped"]) == {"trace", "reflection_color", "specular_weight",
                                            "cone_blur", "reflection", "combine"}
    assert set(out["stats"]["skipped"]) <= set(glint_core.STAGES)


def test_bad_options_name_their_keyword():
    gb = floor_scene()
    with pytest.raises(ValueError, match="weighting"):
        run(gb, weighting="pbr")
    with pytest.raises(ValueError, match="blur"):
        run(gb, blur="gauss")
    with pytest.raises(ValueError, match="specular_base"):
        run(gb, specular_base=np.zeros((3, 3, 3), np.float32))
    with pytest.raises(ValueError, match="specular_base"):
        run(gb, combine="seed", specular_base=np.zeros((H, W, 3), np.float32))


# --- the seed, exactly -------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["persp", "ortho"])
@pytest.mark.parametrize("combine", ["seed", "over"])
def test_seed_look_is_bit_for_bit_the_pipeline_before_it(kind, combine):
    """A regression guard, not a check of correctness: the outputs in the .npz were
    recorded from this same code before the physical look was added, so this only
    says that weighting="seed", blur="box" still gives exactly what it gave then.
    That the seed look is right is test_pipeline.py's (formulas written out there)."""
    f = np.load(DATA / "seed_pipeline_before_weighting.npz")
    g = {k: f[f"{kind}_{k}"] for k in ("position", "normal", "specular", "color", "projection")}
    out = glint_core.pipeline(g["position"], g["normal"], g["specular"], g["color"], g["projection"],
                              march="seed", combine=combine, blur_size=3, blur_separation=1.5,
                              **SEED_LOOK)
    for layer in ("uv", "reflection_color", "reflection_blur", "reflection", "combined"):
        assert out[layer].tobytes() == f[f"{kind}_{combine}_{layer}"].tobytes(), layer


# --- glint-exr ---------------------------------------------------------------------------


def test_glint_exr_takes_the_look_options(tmp_path):
    import os
    import subprocess

    build = Path(os.environ.get("GLINT_BUILD_DIR", Path(__file__).resolve().parents[2] / "build"))
    tool = build / "bin" / "glint-exr"
    if not tool.is_file():
        pytest.skip(f"glint-exr not built: {tool}")
    gb = floor_scene(alpha=0.5)
    rng = np.random.default_rng(8)
    layers = {k: gb[k] for k in ("position", "normal", "specular", "color")}
    layers["specular_base"] = np.concatenate(
        [gb["color"][..., :3] * rng.uniform(0, 0.3, (H, W, 1)), np.ones((H, W, 1))], axis=2).astype(np.float32)
    src = tmp_path / "in.exr"
    glint_core.write_exr(src, layers, projection=gb["projection"])

    def cli(*args):
        return subprocess.run([str(tool), *map(str, args)], capture_output=True, text=True, timeout=120)

    for flags, kw in (([], {}), (["--weighting", "seed", "--blur", "box", "--combine", "seed"],
                                 dict(weighting="seed", blur="box", combine="seed"))):
        dst = tmp_path / "out.exr"
        proc = cli(*flags, src, dst)
        assert proc.returncode == 0, proc.stderr
        out, header = glint_core.read_exr(dst)
        want = run(gb, **kw, **({} if kw else dict(specular_base=layers["specular_base"][..., :3].copy())))
        for name in glint_core.LAYERS:
            np.testing.assert_allclose(out[name], want[name], atol=1e-6, err_msg=name)
        look = kw or dict(weighting="physical", blur="cone")
        for k, v in look.items():
            assert f"{k}={v}" in header["options"]
    proc = cli("--weighting", "pbr", src, tmp_path / "x.exr")
    assert proc.returncode != 0 and "--weighting" in proc.stderr and "physical" in proc.stderr

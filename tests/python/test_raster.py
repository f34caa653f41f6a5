"""glint_core.rasterize against NumPy ray casts of the same analytic geometry.

Run: GLINT_BUILD_DIR=/work/main/build /usr/bin/python3 -m pytest tests/python/test_raster.py
"""
import math
import os
import sys

import numpy as np
import pytest

BUILD_DIR = os.environ.get("GLINT_BUILD_DIR", "/work/main/build")
sys.path.insert(0, os.path.join(BUILD_DIR, "python"))

import glint_core  # noqa: E402
import analytic as A  # noqa: E402


def perspective(fov_y, aspect, near, far):
    f = 1.0 / math.tan(fov_y / 2)
    return np.array([[f / aspect, 0, 0, 0],
                     [0, f, 0, 0],
                     [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)],
                     [0, 0, -1, 0]], dtype=np.float64)


def pixel_rays(proj, w, h):
    """Unnormalised view rays (z = -1) through every pixel centre, [H, W, 3], row 0 at the bottom."""
    u = (np.arange(w) + 0.5) / w * 2 - 1
    v = (np.arange(h) + 0.5) / h * 2 - 1
    d = np.empty((h, w, 3))
    d[..., 0] = (u[None, :] + proj[0, 2]) / proj[0, 0]
    d[..., 1] = (v[:, None] + proj[1, 2]) / proj[1, 1]
    d[..., 2] = -1.0
    return d


MATERIALS = np.array([[0.25, 0.5, 0.75, 63.875], [1.0, 1.0, 1.0, 127.75]], np.float32)


def soup(*triangles, normal=(0, 0, 1)):
    pos = np.array(triangles, np.float32).reshape(-1, 3, 3)
    nrm = np.broadcast_to(np.array(normal, np.float32), pos.shape).copy()
    return pos, nrm, np.zeros(len(pos), np.int32)


def quad(x0, y0, x1, y1, z, reversed_=False):
    a, b, c, d = (x0, y0, z), (x1, y0, z), (x1, y1, z), (x0, y1, z)
    if reversed_:
        return soup((a, c, b), (a, d, c), normal=(0, 0, -1))
    return soup((a, b, c), (a, c, d))


def square_perspective():
    p = perspective(math.pi / 2, 1.0, 0.1, 100.0)
    p[0, 0] = p[1, 1] = 1.0  # x_ndc = x / -z exactly
    return p


def pixel_ortho(w, h):
    """One view unit per pixel: screen x = x + w / 2."""
    p = np.zeros((4, 4))
    p[0, 0], p[1, 1] = 2.0 / w, 2.0 / h
    p[2, 2], p[2, 3] = -2.0 / 99.9, -100.1 / 99.9
    p[3, 3] = 1.0
    return p


def test_returns_three_float32_buffers_of_the_image_size():
    pos, nrm, mat = quad(-0.5, -0.5, 0.5, 0.5, -2.0)
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, square_perspective(), 64, 48)
    assert set(out) == {"position", "normal", "specular"}
    for img in out.values():
        assert img.shape == (48, 64, 4) and img.dtype == np.float32


def test_unit_quad_covers_the_hand_counted_rectangle():
    # At z = -2 the 90-degree view spans [-2, 2]: 16 pixels per unit on 64 x 64,
    # so the unit quad covers columns and rows 24..39 (edges between centres).
    pos, nrm, mat = quad(-0.5, -0.5, 0.5, 0.5, -2.0)
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, square_perspective(), 64, 64)
    seen = out["position"][..., 3] == 1
    expected = np.zeros((64, 64), bool)
    expected[24:40, 24:40] = True
    np.testing.assert_array_equal(seen, expected)
    assert np.all(out["position"][~seen] == 0) and np.all(out["normal"][~seen] == 0)
    assert np.all(out["specular"][~seen] == 0)


def test_ties_follow_the_top_left_rule():
    # Edges exactly on pixel centres 24.5 and 40.5: the left column and row 24
    # are in, the right column and row 40 out: the top-left rule in row-index
    # order (the smaller row index is "top"), as llvmpipe draws into an FBO.
    w = h = 64
    for reversed_ in (False, True):
        pos, nrm, mat = quad(24.5 - 32, 24.5 - 32, 40.5 - 32, 40.5 - 32, -2.0, reversed_)
        out = glint_core.rasterize(pos, nrm, mat, MATERIALS, pixel_ortho(w, h), w, h)
        expected = np.zeros((h, w), bool)
        expected[24:40, 24:40] = True
        np.testing.assert_array_equal(out["position"][..., 3] == 1, expected)


def test_positions_match_a_numpy_ray_cast_of_the_plane():
    w, h = 80, 60
    proj = perspective(0.8, w / h, 0.1, 100.0)
    m = np.array([0.3, -0.4, math.sqrt(0.75)])  # plane dot(m, p) = dot(m, (0, 0, -3))
    corners = []
    for x, y in [(-4, -4), (4, -4), (4, 4), (-4, 4)]:
        corners.append((x, y, -3.0 - (m[0] * x + m[1] * y) / m[2]))
    a, b, c, d = corners
    pos, nrm, mat = soup((a, b, c), (a, c, d), normal=m)
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h)
    rays = pixel_rays(proj, w, h)
    t = (-3.0 * m[2]) / (rays @ m)
    expected = rays * t[..., None]
    assert np.all(out["position"][..., 3] == 1)
    np.testing.assert_allclose(out["position"][..., :3], expected, rtol=0, atol=1e-5 * np.abs(expected).max())
    rel = np.abs(out["position"][..., :3] - expected).max(axis=-1) / np.abs(expected[..., 2])
    assert rel.max() < 1e-5
    np.testing.assert_allclose(out["normal"][..., :3], np.broadcast_to(m, (h, w, 3)), atol=1e-6)
    np.testing.assert_array_equal(out["normal"][..., 3], 1.0)
    np.testing.assert_array_equal(out["specular"][..., :3], np.broadcast_to(MATERIALS[0, :3], (h, w, 3)))
    np.testing.assert_allclose(out["specular"][..., 3], 0.5, rtol=1e-6)


def test_near_plane_clipping_matches_a_numpy_ray_cast():
    # A floor triangle y = -1 reaching from behind the camera (z = +5) to z = -20.
    w, h, near, far = 96, 64, 0.5, 50.0
    proj = perspective(1.2, w / h, near, far)
    a, b, c = np.array([-30, -1, 5.0]), np.array([30, -1, 5.0]), np.array([0, -1, -20.0])
    pos, nrm, mat = soup((a, b, c), normal=(0, 1, 0))
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h)
    rays = pixel_rays(proj, w, h)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = -1.0 / rays[..., 1]
    p = rays * t[..., None]
    # Barycentrics in the xz plane.
    e1, e2, q = (b - a)[[0, 2]], (c - a)[[0, 2]], p[..., [0, 2]] - a[[0, 2]]
    det = e1[0] * e2[1] - e1[1] * e2[0]
    l1 = (q[..., 0] * e2[1] - q[..., 1] * e2[0]) / det
    l2 = (e1[0] * q[..., 1] - e1[1] * q[..., 0]) / det
    l0 = 1 - l1 - l2
    dist = -p[..., 2]
    hit = (rays[..., 1] < 0) & (l0 >= 0) & (l1 >= 0) & (l2 >= 0) & (dist >= near) & (dist <= far)
    margin = np.minimum(np.minimum(np.abs(l0), np.abs(l1)), np.minimum(np.abs(l2), np.abs(dist - near)))
    clear = (rays[..., 1] >= 0) | (margin > 1e-3)
    seen = out["position"][..., 3] == 1
    np.testing.assert_array_equal(seen[clear], hit[clear])
    assert hit.sum() > w * h // 4
    both = seen & hit
    np.testing.assert_allclose(out["position"][both][:, :3], p[both], atol=1e-5 * np.abs(p[both]).max())


def test_triangle_behind_the_camera_draws_nothing():
    pos, nrm, mat = soup(((-1, -1, 2), (1, -1, 2), (0, 1, 2)))
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, square_perspective(), 32, 32)
    assert not out["position"].any() and not out["normal"].any() and not out["specular"].any()


def test_back_faces_have_their_normals_flipped_toward_the_eye():
    proj = square_perspective()
    front = glint_core.rasterize(*quad(-0.5, -0.5, 0.5, 0.5, -2.0), MATERIALS, proj, 64, 64)
    back = glint_core.rasterize(*quad(-0.5, -0.5, 0.5, 0.5, -2.0, True), MATERIALS, proj, 64, 64)
    np.testing.assert_array_equal(front["position"], back["position"])
    np.testing.assert_array_equal(back["normal"][32, 32], [0, 0, 1, 1])
    # A ceiling y = 1 wound counter-clockwise from above (normals up) seen from below.
    pos, nrm, mat = soup(((-5, 1, -1), (5, 1, -1), (0, 1, -20)), normal=(0, 1, 0))
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, 64, 64)
    assert out["position"][50, 32, 3] == 1
    np.testing.assert_allclose(out["normal"][50, 32, :3], [0, -1, 0], atol=1e-6)


def test_nearer_surface_wins_whatever_the_order():
    near = quad(-0.5, -0.5, 0.5, 0.5, -2.0)
    far = quad(-2, -2, 2, 2, -3.0)
    for first, second in ((near, far), (far, near)):
        pos = np.concatenate([first[0], second[0]])
        nrm = np.concatenate([first[1], second[1]])
        mat = np.array([0, 0, 1, 1], np.int32)
        out = glint_core.rasterize(pos, nrm, mat, MATERIALS, square_perspective(), 64, 64)
        assert out["position"][32, 32, 2] == pytest.approx(-2.0)
        assert out["position"][20, 20, 2] == pytest.approx(-3.0)


def test_non_finite_corners_skip_only_that_triangle():
    pos, nrm, mat = quad(-0.5, -0.5, 0.5, 0.5, -2.0)
    pos[0, 1, 0] = np.nan
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, square_perspective(), 64, 64)
    assert (out["position"][..., 3] == 1).sum() == 16 * 15 // 2  # centres strictly above the diagonal
    assert np.isfinite(out["position"]).all() and np.isfinite(out["normal"]).all()


def test_empty_mesh_gives_empty_buffers():
    out = glint_core.rasterize(np.zeros((0, 3, 3), np.float32), np.zeros((0, 3, 3), np.float32),
                               np.zeros(0, np.int32), np.zeros((0, 4), np.float32),
                               square_perspective(), 8, 4)
    assert out["position"].shape == (4, 8, 4) and not out["position"].any()


def tilted_map(angle, toward):
    """A constant normal map: the surface normal tilted by `angle` toward tangent-space `toward`."""
    n = np.array([0.0, 0.0, math.cos(angle)])
    n[toward] = math.sin(angle)
    img = np.empty((4, 4, 3), np.float32)
    img[...] = n * 0.5 + 0.5
    return img


@pytest.mark.parametrize("sign", [1.0, -1.0])
def test_normal_maps_rotate_the_normal_in_tangent_space(sign):
    pos, nrm, mat = quad(-0.5, -0.5, 0.5, 0.5, -2.0)
    uvs = (pos[..., :2] + 0.5).astype(np.float32)
    tangents = np.zeros((2, 3, 4), np.float32)
    tangents[..., 0] = 1.0  # T = +x, so B = sign * cross(N, T) = sign * (0, 1, 0)
    tangents[..., 3] = sign
    proj = square_perspective()
    kw = dict(uvs=uvs, tangents=tangents, material_normal_map=np.array([0, -1], np.int32))
    flat = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, 64, 64,
                                normal_maps=[tilted_map(0.0, 0)], **kw)
    np.testing.assert_allclose(flat["normal"][24:40, 24:40, :3], np.broadcast_to([0, 0, 1], (16, 16, 3)),
                               atol=1e-6)
    angle = math.radians(25)
    along_t = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, 64, 64,
                                   normal_maps=[tilted_map(angle, 0)], **kw)["normal"][24:40, 24:40, :3]
    np.testing.assert_allclose(along_t, np.broadcast_to([math.sin(angle), 0, math.cos(angle)], along_t.shape),
                               atol=1e-5)
    along_b = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, 64, 64,
                                   normal_maps=[tilted_map(angle, 1)], **kw)["normal"][24:40, 24:40, :3]
    np.testing.assert_allclose(along_b, np.broadcast_to([0, sign * math.sin(angle), math.cos(angle)],
                                                        along_b.shape), atol=1e-5)
    # A material without a map ignores uvs and tangents.
    plain = glint_core.rasterize(pos, nrm, np.ones(2, np.int32), MATERIALS, proj, 64, 64,
                                 normal_maps=[tilted_map(angle, 0)], **kw)
    np.testing.assert_allclose(plain["normal"][24:40, 24:40, 2], 1.0, atol=1e-6)


def test_normal_map_uv_origin_is_the_bottom_left_texel():
    # Quad on screen [24.5, 40.5]^2 with uv (0, 0) at its bottom-left: pixel
    # (col 28, row 28) samples uv (0.25, 0.25), the centre of texel row 0 col 0.
    w = h = 64
    pos, nrm, mat = quad(24.5 - 32, 24.5 - 32, 40.5 - 32, 40.5 - 32, -2.0)
    uvs = ((pos[..., :2] + 32 - 24.5) / 16).astype(np.float32)
    tangents = np.zeros((2, 3, 4), np.float32)
    tangents[..., 0] = 1.0
    tangents[..., 3] = 1.0
    img = np.empty((2, 2, 4), np.float32)
    img[...] = [0.5, 0.5, 1.0, 1.0]
    tilt = math.radians(30)
    img[0, 0, :3] = np.array([math.sin(tilt), 0, math.cos(tilt)]) * 0.5 + 0.5  # image row 0 = bottom
    out = glint_core.rasterize(pos, nrm, mat, MATERIALS, pixel_ortho(w, h), w, h, uvs=uvs, tangents=tangents,
                               material_normal_map=np.array([0, -1], np.int32), normal_maps=(img,))
    np.testing.assert_allclose(out["normal"][28, 28, :3], [math.sin(tilt), 0, math.cos(tilt)], atol=1e-5)
    np.testing.assert_allclose(out["normal"][36, 28, :3], [0, 0, 1], atol=1e-6)
    np.testing.assert_allclose(out["normal"][28, 36, :3], [0, 0, 1], atol=1e-6)


def _args():
    pos, nrm, mat = quad(-0.5, -0.5, 0.5, 0.5, -2.0)
    return dict(positions=pos, normals=nrm, material_index=mat, materials=MATERIALS,
                projection=square_perspective(), width=16, height=16)


def _with(**changes):
    kw = _args()
    kw.update(changes)
    return kw


BAD = [
    ("positions", _with(positions=np.zeros((2, 3, 3), np.float64))),
    ("positions", _with(positions=np.zeros((2, 3), np.float32))),
    ("positions", _with(positions=[[0, 0, 0]])),
    ("normals", _with(normals=np.zeros((3, 3, 3), np.float32))),
    ("material_index", _with(material_index=np.zeros(3, np.int32))),
    ("material_index", _with(material_index=np.array([0, 2], np.int32))),
    ("material_index", _with(material_index=np.array([0, -1], np.int32))),
    ("material_index", _with(material_index=np.zeros(2, np.float32))),
    ("materials", _with(materials=np.zeros((2, 3), np.float32))),
    ("materials", _with(materials=np.array([[1, 1, 1, np.nan]], np.float32))),
    ("materials", _with(materials=np.zeros((0, 4), np.float32))),
    ("material_normal_map", _with(material_normal_map=np.array([0, -1], np.int32))),
    ("material_normal_map", _with(material_normal_map=np.array([-1], np.int32))),
    ("uvs", _with(material_normal_map=np.array([0, -1], np.int32), normal_maps=[np.zeros((2, 2, 3), np.float32)],
                  tangents=np.zeros((2, 3, 4), np.float32))),
    ("uvs", _with(uvs=np.zeros((3, 3, 2), np.float32))),
    ("tangents", _with(material_normal_map=np.array([0, -1], np.int32), normal_maps=[np.zeros((2, 2, 3), np.float32)],
                       uvs=np.zeros((2, 3, 2), np.float32))),
    ("tangents", _with(tangents=np.zeros((2, 3, 3), np.float32))),
    ("normal_maps", _with(normal_maps=np.zeros((2, 2, 3), np.float32))),
    ("normal_maps[0]", _with(normal_maps=[np.zeros((2, 2, 2), np.float32)])),
    ("width", _with(width=0)),
    ("height", _with(height=40000)),
    ("projection", _with(projection=np.zeros((4, 4)))),
    ("backend", _with(backend="vulkan")),
    ("material_albedo", _with(material_albedo=np.zeros((2, 3), np.float32))),  # without back_layer
    ("material_albedo", _with(back_layer=True, material_albedo=np.zeros((3, 3), np.float32))),
    ("material_albedo", _with(back_layer=True, material_albedo=np.zeros((2, 4), np.float32))),
    ("material_albedo", _with(back_layer=True, material_albedo=np.zeros(6, np.float32))),
    ("material_albedo", _with(back_layer=True, material_albedo=np.zeros((2, 3), np.int32))),
    ("material_albedo", _with(back_layer=True, material_albedo=[[0.5, 0.5, 0.5]] * 2)),
    ("material_albedo", _with(back_layer=True, material_albedo=np.array([[0, 0, 0], [0, np.nan, 0]]))),
    ("material_albedo", _with(back_layer=True, material_albedo=np.array([[0, 0, np.inf], [0, 0, 0]]))),
    ("material_albedo", _with(back_layer=True, material_albedo=np.array([[0, 0, 0], [-0.1, 0, 0]]))),
]


@pytest.mark.parametrize("argument,kwargs", BAD, ids=[f"{a}-{i}" for i, (a, _) in enumerate(BAD)])
def test_bad_input_raises_value_error_naming_the_argument(argument, kwargs):
    with pytest.raises(ValueError) as err:
        glint_core.rasterize(**kwargs)
    assert str(err.value).startswith(argument + ":"), str(err.value)


def test_material_albedo_messages_say_what_was_wrong():
    with pytest.raises(ValueError) as err:
        glint_core.rasterize(**_with(material_albedo=np.zeros((2, 3))))
    assert str(err.value) == "material_albedo: needs back_layer=True"
    for bad, words in ((np.zeros((3, 3)), ["expected shape", "M = 2"]),
                       (np.array([[0, 0, 0], [-0.1, 0, 0]]), ["expected finite values >= 0", "row 1"]),
                       (np.array([[0, 0, 0], [0, np.nan, 0]]), ["expected finite values >= 0", "row 1"])):
        with pytest.raises(ValueError) as err:
            glint_core.rasterize(**_with(back_layer=True, material_albedo=bad))
        for word in words:
            assert word in str(err.value), str(err.value)


def test_empty_materials_are_fine_without_triangles():
    kw = _with(material_index=np.zeros(0, np.int32), positions=np.zeros((0, 3, 3), np.float32),
               normals=np.zeros((0, 3, 3), np.float32), materials=np.zeros((0, 4), np.float32))
    assert not glint_core.rasterize(**kw)["position"].any()


def test_int64_material_indices_are_accepted():
    kw = _with(material_index=np.array([0, 1], np.int64))
    out = glint_core.rasterize(**kw)
    assert (out["position"][..., 3] == 1).any()


@pytest.mark.gl
def test_gl_backend_agrees_with_the_cpu_reference():
    try:
        glint_core.backend_name("gl")
    except (glint_core.BackendUnavailable, ValueError) as e:
        pytest.skip(f"no GL backend: {e}")
    w, h = 96, 64
    proj = perspective(1.0, w / h, 0.1, 100.0)
    rng = np.random.default_rng(2)
    centres = np.stack([rng.uniform(-3, 3, 200), rng.uniform(-2, 2, 200), rng.uniform(-9, -3, 200)], -1)
    pos = (centres[:, None, :] + rng.uniform(-0.7, 0.7, (200, 3, 3))).astype(np.float32)
    nrm = np.broadcast_to(np.float32([0, 0, 1]), pos.shape).copy()
    mat = (np.arange(200) % 2).astype(np.int32)
    cpu = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h, backend="cpu")
    gl = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h, backend="gl")
    same = (cpu["position"][..., 3] == gl["position"][..., 3])
    assert same.mean() > 0.97  # edge pixels may differ with the GPU's own snapping
    both = (cpu["position"][..., 3] == 1) & (gl["position"][..., 3] == 1)
    close = np.abs(cpu["position"][both] - gl["position"][both]).max(axis=-1) < 1e-3
    assert close.mean() > 0.95  # the rest: a different triangle won a near depth tie at an edge


def _gl_or_skip():
    try:
        glint_core.backend_name("gl")
    except glint_core.BackendUnavailable as exc:
        pytest.skip(f"no GL here: {exc}")


def closed_box(lo, hi):
    """The 12 triangles of an axis-aligned box, each wound counter-clockwise seen
    from outside, float32 (12, 3, 3)."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    corners = np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])
    quads = [(0, 1, 3, 2), (4, 6, 7, 5), (0, 4, 5, 1), (2, 3, 7, 6), (0, 2, 6, 4), (1, 5, 7, 3)]
    tris = []
    centre = corners.mean(axis=0)
    for q in quads:
        for t in ((q[0], q[1], q[2]), (q[0], q[2], q[3])):
            a, b, c = corners[list(t)]
            tris.append(t if np.cross(b - a, c - a) @ (a - centre) > 0 else (t[0], t[2], t[1]))
    return corners[np.array(tris)].astype(np.float32)


def slab(lo, hi, d):
    """Entry and exit distances of rays from the eye (the origin) along d [..., 3]
    through the box lo..hi; entry < exit where they hit it."""
    with np.errstate(divide="ignore", invalid="ignore"):
        a, b = np.asarray(lo) / d, np.asarray(hi) / d
    return np.max(np.minimum(a, b), axis=-1), np.min(np.maximum(a, b), axis=-1)


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_back_layer_is_the_far_side_of_a_closed_box(backend):
    """back_layer=True: behind every pixel that sees the box, its exit point
    along the pixel's view ray (slab method, computed here); nothing elsewhere."""
    if backend == "gl":
        _gl_or_skip()
    w, h = 64, 48
    proj = A.projection_matrix("persp", w, h)
    lo, hi = np.array([-1.0, -1.0, -6.0]), np.array([1.0, 1.0, -4.0])
    pos = closed_box(lo, hi)
    g = glint_core.rasterize(pos, np.zeros_like(pos), np.zeros(len(pos), np.int32),
                             np.zeros((1, 4), np.float32), proj, w, h, back_layer=True, backend=backend)
    seen = g["position"][..., 3] > 0
    back = g["back_position"][..., 3] > 0
    assert seen.sum() > 500 and np.array_equal(seen, back)
    nx, ny = A.pixel_ndc(w, h)
    _, d = A.unproject_rays(proj, nx, ny)
    d = d.reshape(h, w, 3)
    with np.errstate(divide="ignore"):
        t_far = np.min(np.maximum(lo / d, hi / d), axis=-1)  # rays start at the eye (origin)
    expect = d * t_far[..., None]
    err = np.abs(g["back_position"][..., :3] - expect)[back].max()
    assert err < 1e-4 * 6.0, err
    # Without the flag there is no such layer.
    assert "back_position" not in glint_core.rasterize(pos, np.zeros_like(pos), np.zeros(len(pos), np.int32),
                                                       np.zeros((1, 4), np.float32), proj, w, h,
                                                       backend=backend)


# Two boxes of two materials, the far (larger) one first in the arrays, and an
# open front-facing wall behind both, which is a front surface with nothing
# behind it.
ALBEDO = np.array([[0.8, 0.1, 0.2], [0.1, 0.6, 0.3]])  # per row of MATERIALS
BOXES = [((-1.6, -1.2, -9.0), (1.4, 1.3, -6.0), 1),   # lo, hi, material
         ((-0.7, -0.4, -4.5), (0.3, 0.6, -3.5), 0)]


def two_boxes_and_a_wall():
    wall, wall_n, _ = quad(-30.0, -30.0, 30.0, 30.0, -20.0)
    pos = np.concatenate([closed_box(lo, hi) for lo, hi, _ in BOXES] + [wall])
    mat = np.concatenate([np.full(12, m, np.int32) for _, _, m in BOXES] + [np.ones(2, np.int32)])
    nrm = np.zeros_like(pos)  # the face normals: not what this is about
    return pos, nrm, mat


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_back_albedo_is_the_material_of_the_surface_back_position_shows(backend):
    """material_albedo: back_albedo is (albedo of the back-layer triangle's
    material, 1) where back_position is set, all zeros elsewhere. Which box's far
    side a pixel shows is decided here independently: the box its ray enters
    first (slab method), whose exit back_position must be."""
    if backend == "gl":
        _gl_or_skip()
    w, h = 64, 48
    proj = A.projection_matrix("persp", w, h)
    pos, nrm, mat = two_boxes_and_a_wall()
    g = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h, back_layer=True,
                             material_albedo=ALBEDO, backend=backend)
    assert g["back_albedo"].shape == (h, w, 4) and g["back_albedo"].dtype == np.float32
    nx, ny = A.pixel_ndc(w, h)
    _, d = A.unproject_rays(proj, nx, ny)
    d = d.reshape(h, w, 3)
    entry, exit_ = np.stack([slab(lo, hi, d) for lo, hi, _ in BOXES], axis=1)  # [2 boxes, H, W] each
    inside = exit_ - entry  # > 0 where the ray goes through the box
    hit = inside > 0
    first = np.argmin(np.where(hit, entry, np.inf), axis=0)  # the box seen
    # Pixels whose centre is not within a hair of some box's outline.
    clear = np.all(np.abs(inside) > 1e-3 * np.abs(exit_), axis=0)
    back = g["back_position"][..., 3] > 0
    np.testing.assert_array_equal(back[clear], hit.any(axis=0)[clear])
    assert np.all(g["position"][..., 3] > 0)  # the wall is behind everything else
    # Where there is a back surface, it is the exit of the box seen, and its
    # albedo that box's material's (copied, so exact), with alpha 1.
    sel = back & clear
    t_exit = np.take_along_axis(exit_, first[None], axis=0)[0]
    np.testing.assert_allclose(g["back_position"][sel][:, :3], (d * t_exit[..., None])[sel], atol=1e-4 * 9)
    material = np.array([m for _, _, m in BOXES])[first]
    expected = ALBEDO.astype(np.float32)[material]
    np.testing.assert_array_equal(g["back_albedo"][sel][:, :3], expected[sel])
    np.testing.assert_array_equal(g["back_albedo"][..., 3], g["back_position"][..., 3])
    assert not g["back_albedo"][~back].any()
    for k in (0, 1):  # both materials really are shown, and so is the bare wall
        assert (sel & (material == BOXES[k][2])).sum() > 30, k
    assert (~back).sum() > 500
    # back_position is as it was without the albedo, which is only in the dict when asked for.
    plain = glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h, back_layer=True, backend=backend)
    assert "back_albedo" not in plain
    np.testing.assert_array_equal(plain["back_position"], g["back_position"])


@pytest.mark.gl
def test_back_albedo_is_the_same_on_cpu_and_gl():
    """The albedo is copied, not computed: both backends give the same bits
    (llvmpipe also gives the same coverage, so the whole image)."""
    _gl_or_skip()
    w, h = 96, 64
    pos, nrm, mat = two_boxes_and_a_wall()
    for proj in (A.projection_matrix("persp", w, h), A.projection_matrix("ortho", w, h)):
        out = [glint_core.rasterize(pos, nrm, mat, MATERIALS, proj, w, h, back_layer=True,
                                    material_albedo=ALBEDO.astype(np.float32), backend=b)
               for b in ("cpu", "gl")]
        both = (out[0]["back_position"][..., 3] > 0) & (out[1]["back_position"][..., 3] > 0)
        assert both.sum() > 500
        np.testing.assert_array_equal(out[0]["back_albedo"][both], out[1]["back_albedo"][both])
        np.testing.assert_array_equal(out[0]["back_albedo"], out[1]["back_albedo"])

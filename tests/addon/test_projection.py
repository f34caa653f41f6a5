"""Camera maths against matrices written out by hand."""
import math

import numpy as np
import pytest

from glint_addon_helpers import load_logic

p = load_logic("projection")
fr = load_logic("frustum")


def gl_perspective(fov_x, aspect, near, far):
    """OpenGL's perspective matrix, as Blender's calc_matrix_camera builds it (sensor fit horizontal)."""
    fx = 1.0 / math.tan(fov_x / 2)
    fy = fx * aspect
    return np.array([[fx, 0, 0, 0], [0, fy, 0, 0],
                     [0, 0, -(far + near) / (far - near), -2 * far * near / (far - near)], [0, 0, -1, 0]])


def gl_ortho(half_w, half_h, near, far):
    return np.array([[1 / half_w, 0, 0, 0], [0, 1 / half_h, 0, 0],
                     [0, 0, -2 / (far - near), -(far + near) / (far - near)], [0, 0, 0, 1]])


@pytest.mark.parametrize("rx,ry,pct,expected", [(1920, 1080, 100, (1920, 1080)), (1920, 1080, 50, (960, 540)),
                                                (333, 333, 33, (109, 109)), (320, 180, 25, (80, 45))])
def test_render_size_uses_integer_percentage(rx, ry, pct, expected):
    assert p.render_size(rx, ry, pct) == expected


def test_render_size_zero_is_an_error():
    with pytest.raises(p.ProjectionError):
        p.render_size(1, 1, 1)


def test_render_window_is_the_whole_frame_unless_cropped():
    assert p.render_window(320, 180, 50) == p.RenderWindow(160, 90, 0, 0, 160, 90)


def test_render_window_truncates_the_region_as_blender():
    """Blender 3.4 rendered 333x187 at 77% cropped to x 0.1234-0.6789, y 0.2222-0.7777
    as 142x80 (bpy, a PNG read back); the sides are float32 products truncated."""
    win = p.render_window(333, 187, 77, (0.1234, 0.6789, 0.2222, 0.7777))
    assert (win.full_width, win.full_height) == (256, 143)
    assert (win.x0, win.y0, win.width, win.height) == (31, 31, 142, 80)
    # bpy reads a border of 0.7 back as float32's 0.69999999: times 10 that truncates
    # to 6 in float64, and is 7 in float32, as Blender multiplies
    stored = float(np.float32(0.7))
    assert int(stored * 10) == 6
    assert p.render_window(10, 10, 100, (0.0, stored, 0.0, 1.0)).width == 7


def test_a_render_region_hands_the_compositor_its_own_size_only_when_cropped():
    region = (0.25, 0.75, 0.5, 1.0)
    assert p.render_window(100, 40, 100, region).image_size == (100, 40)
    assert p.render_window(100, 40, 100, region, crop=True).image_size == (50, 20)


@pytest.mark.parametrize("size", [(100, 40), (50, 20), (33, 13)])
def test_zero_outside_keeps_the_pixels_whose_centres_lie_in_the_window(size):
    """At the frame's size and at reduced ones (the add-on's memory fallback), a
    pixel stays where its centre, in the frame's pixels, lies in the window."""
    win = p.render_window(100, 40, 100, (0.25, 0.75, 0.5, 1.0))  # columns 25..74, rows 20..39
    w, h = size
    img = np.ones((h, w, 4), np.float32)
    out = p.zero_outside(img, win)
    cx = (np.arange(w) + 0.5) * 100 / w
    cy = (np.arange(h) + 0.5) * 40 / h
    want = ((cy >= 20) & (cy < 40))[:, None] & ((cx >= 25) & (cx < 75))[None, :]
    assert np.array_equal(out[..., 0] == 1, want)
    assert img.all()  # a copy


def test_a_render_region_under_a_pixel_is_an_error():
    with pytest.raises(p.ProjectionError, match="render region of 0x"):
        p.render_window(100, 100, 100, (0.5, 0.505, 0.0, 1.0))


@pytest.mark.parametrize("make", [lambda: gl_perspective(1.1, 16 / 9, 0.1, 100), lambda: gl_ortho(4, 2.25, 0.1, 100)])
def test_window_projection_puts_a_point_on_the_same_pixel(make):
    """Through the narrowed projection a point lands on the window's pixel that is
    the whole frame's pixel minus the window's corner, also with a lens shift."""
    full = make()
    full[0, 2] += 0.3  # shift, as calc_matrix_camera writes it (a perspective's; an ortho's is in [0, 3])
    full[1, 3] += -0.2
    win = p.RenderWindow(400, 225, 37, 101, 150, 61)
    narrow = p.window_projection(full, win)
    rng = np.random.default_rng(3)
    pts = np.stack([rng.uniform(-3, 3, 50), rng.uniform(-2, 2, 50), rng.uniform(-20, -1, 50)], axis=-1)
    def pixels(proj, w, h):
        clip = np.c_[pts, np.ones(len(pts))] @ np.asarray(proj).T
        ndc = clip[:, :2] / clip[:, 3:4]
        return (ndc + 1.0) * 0.5 * np.array([w, h])
    want = pixels(full, 400, 225) - np.array([37, 101])
    assert np.allclose(pixels(narrow, 150, 61), want, atol=1e-9)
    assert np.array_equal(narrow[2:], full[2:])  # depth and w untouched
    whole = p.window_projection(full, p.RenderWindow(400, 225, 0, 0, 400, 225))
    assert np.allclose(whole, full, atol=1e-15)


def test_view_matrix_ignores_camera_scale():
    cam = np.eye(4)
    cam[:3, :3] = np.diag([2.0, 3.0, 0.5])
    cam[:3, 3] = (1.0, 2.0, 3.0)
    v = p.view_matrix(cam)
    assert np.allclose(p.transform_points(v, [1.0, 2.0, 3.0]), 0.0)
    # one unit along world -Z is one unit along view -Z, scale notwithstanding
    assert np.allclose(p.transform_points(v, [1.0, 2.0, 2.0]), (0.0, 0.0, -1.0))


def test_view_matrix_of_rotated_camera():
    # camera at (0, -5, 0) looking along +Y (rotated 90 degrees about X)
    c, s = math.cos(math.pi / 2), math.sin(math.pi / 2)
    cam = np.array([[1, 0, 0, 0], [0, c, -s, -5.0], [0, s, c, 0], [0, 0, 0, 1]])
    v = p.view_matrix(cam)
    assert np.allclose(p.transform_points(v, [0.0, 0.0, 0.0]), (0.0, 0.0, -5.0))
    assert np.allclose(p.transform_points(v, [0.0, -5.0, 1.0]), (0.0, 1.0, 0.0))


def test_classify():
    assert p.classify_projection(gl_perspective(1.0, 16 / 9, 0.1, 100)) == p.PERSPECTIVE
    assert p.classify_projection(gl_ortho(4, 2.25, 0.1, 100)) == p.ORTHOGRAPHIC
    with pytest.raises(p.ProjectionError, match="singular"):
        p.classify_projection(np.zeros((4, 4)))
    bad = gl_perspective(1.0, 1.0, 0.1, 100)
    bad[0, 0] = np.nan
    with pytest.raises(p.ProjectionError, match="non-finite"):
        p.classify_projection(bad)
    with pytest.raises(p.ProjectionError, match="4x4"):
        p.classify_projection(np.eye(3))
    odd = gl_perspective(1.0, 1.0, 0.1, 100)
    odd[3] = (0.1, 0, -1, 0)
    with pytest.raises(p.ProjectionError, match="last row"):
        p.classify_projection(odd)


def test_project_perspective_by_hand():
    proj = gl_perspective(math.radians(90), 16 / 9, 0.1, 100)  # fx = 1
    uv, w = p.project(proj, [[0.0, 0.0, -3.0], [1.0, 0.0, -2.0], [0.0, 0.5, -4.0]])
    assert np.allclose(uv[0], (0.5, 0.5)) and w[0] == pytest.approx(3.0)
    assert np.allclose(uv[1], (0.5 + 0.5 * 1.0 / 2.0, 0.5))
    assert np.allclose(uv[2], (0.5, 0.5 + 0.5 * (16 / 9) * 0.5 / 4.0))


def test_project_ortho_by_hand():
    proj = gl_ortho(4.0, 2.25, 0.1, 100)
    uv, w = p.project(proj, [[2.0, -1.125, -50.0]])
    assert np.allclose(uv[0], (0.75, 0.25)) and w[0] == 1.0
    assert np.array_equal(p.pixel_of_uv(uv, 160, 90)[0], (120, 22))


def test_normals_use_inverse_transpose():
    m = np.diag([2.0, 1.0, 1.0, 1.0])
    n = p.transform_normals(m, [[1.0, 1.0, 0.0]])
    expected = np.array([0.5, 1.0, 0.0]) / math.hypot(0.5, 1.0)
    assert np.allclose(n[0], expected)
    # a flattened object keeps a normal along the collapsed axis
    flat = np.diag([1.0, 1.0, 0.0, 1.0])
    assert np.allclose(p.transform_normals(flat, [[0.0, 0.0, 1.0]])[0], (0.0, 0.0, 1.0))


class TestFrustum:
    proj = gl_perspective(math.radians(90), 1.0, 0.1, 100.0)
    unit_box = np.array([[x, y, z] for x in (-0.5, 0.5) for y in (-0.5, 0.5) for z in (-0.5, 0.5)])

    def at(self, x, y, z):
        m = np.eye(4)
        m[:3, 3] = (x, y, z)
        return self.proj @ m

    def test_in_front_is_kept(self):
        assert not fr.outside_frustum(self.at(0, 0, -5), self.unit_box)

    def test_behind_the_camera_is_culled(self):
        assert fr.outside_frustum(self.at(0, 0, 5), self.unit_box)

    def test_far_to_the_side_is_culled(self):
        assert fr.outside_frustum(self.at(20, 0, -5), self.unit_box)  # 90 degree fov: |x| <= 5 at z=-5
        assert not fr.outside_frustum(self.at(5.2, 0, -5), self.unit_box)  # straddles the edge

    def test_straddling_the_near_plane_is_kept(self):
        assert not fr.outside_frustum(self.at(0, 0, 0), self.unit_box)

    def test_beyond_far_is_culled(self):
        assert fr.outside_frustum(self.at(0, 0, -200), self.unit_box)

    def test_non_finite_is_kept(self):
        m = self.at(0, 0, 5)
        m[0, 0] = np.inf
        assert not fr.outside_frustum(m, self.unit_box)

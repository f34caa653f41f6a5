"""Which on-screen objects a reflected ray can meet: rectangles against projections
worked out by hand, and rays sampled at random against the reach rectangle."""
import math

import numpy as np
import pytest

from glint_addon_helpers import load_logic

fr = load_logic("frustum")

# 90 degree square perspective: x_ndc = x / -z, y_ndc = y / -z.
PROJ = np.array([[1.0, 0, 0, 0], [0, 1.0, 0, 0], [0, 0, -1.0202, -0.20202], [0, 0, -1.0, 0]])


def corners(lo, hi):
    return np.array([[x, y, z] for x in (lo[0], hi[0]) for y in (lo[1], hi[1]) for z in (lo[2], hi[2])])


def test_screen_rect_of_a_box_in_front():
    rect = fr.screen_rect(PROJ, corners((1, -1, -5), (2, 1, -4)))
    # x: 1/5 .. 2/4, y: -1/4 .. 1/4 (the nearer face bounds it)
    assert rect == pytest.approx((0.2, -0.25, 0.5, 0.25))
    assert fr.screen_rect(PROJ, corners((1, -1, -5), (2, 1, -4)), margin=0.1) == pytest.approx(
        (0.1, -0.35, 0.6, 0.35))


def test_screen_rect_is_clamped_and_whole_screen_behind_the_eye():
    assert fr.screen_rect(PROJ, corners((-50, -1, -5), (2, 1, -4))) == pytest.approx((-1, -0.25, 0.5, 0.25))
    assert fr.screen_rect(PROJ, corners((-1, -1, -5), (1, 1, 3))) == fr.FULL_SCREEN  # crosses z = 0
    m = PROJ.copy()
    m[0, 0] = np.nan
    assert fr.screen_rect(m, corners((1, -1, -5), (2, 1, -4))) == fr.FULL_SCREEN


def test_grown_box():
    c = fr.grown_box_corners(corners((0, 1, -6), (2, 1, -4)), 0.5)
    assert c.min(axis=0) == pytest.approx((-0.5, 0.5, -6.5)) and c.max(axis=0) == pytest.approx((2.5, 1.5, -3.5))
    with pytest.raises(ValueError, match="reach"):
        fr.grown_box_corners(c, -1.0)


def test_transform_points():
    m = np.eye(4)
    m[:3, :3] = [[0, -1, 0], [1, 0, 0], [0, 0, 1]]  # 90 degrees about z
    m[:3, 3] = (1, 2, 3)
    assert fr.transform_points(m, [[1, 0, 0]])[0] == pytest.approx([1, 3, 3])


def test_out_of_reach_keeps_reflectors_and_what_rays_can_cross():
    floor = fr.screen_rect(PROJ, corners((-1, -1.1, -6), (0, -1, -4)))  # lower left
    reach = [fr.screen_rect(PROJ, fr.grown_box_corners(corners((-1, -1.1, -6), (0, -1, -4)), 0.5))]
    far_right = fr.screen_rect(PROJ, corners((3, 2, -5), (4, 3, -4)))  # upper right, beyond 0.5 of the floor
    on_floor = fr.screen_rect(PROJ, corners((-0.5, -1, -5), (-0.3, -0.5, -4.8)))
    assert fr.out_of_reach([floor, far_right, on_floor], [True, False, False], reach) == [False, True, False]
    # Without any reflector every non-reflective object could go (the caller skips the frame anyway).
    assert fr.out_of_reach([far_right], [False], []) == [True]


def test_every_sampled_ray_stays_inside_the_reach_rectangle():
    """Rays of length <= max_distance from points of a reflective box, projected:
    all land in the rectangle (an independent check of the growing and projecting)."""
    rng = np.random.default_rng(7)
    lo, hi, reach = np.array([-1.0, -1.2, -12.0]), np.array([0.5, -1.0, -8.0]), 1.0
    rect = fr.screen_rect(PROJ, fr.grown_box_corners(corners(lo, hi), reach))
    start = lo + (hi - lo) * rng.random((20000, 3))
    d = rng.normal(size=(20000, 3))
    d /= np.linalg.norm(d, axis=1)[:, None]
    end = start + d * reach * rng.random((20000, 1))
    ndc = end[:, :2] / -end[:, 2:3]
    inside = (ndc >= np.array(rect[:2]) - 1e-12) & (ndc <= np.array(rect[2:]) + 1e-12)
    on_screen = np.all(np.abs(ndc) <= 1, axis=1)
    assert np.all(inside[on_screen])
    # and the rectangle is not the whole screen, so the test says something
    assert rect != fr.FULL_SCREEN and (rect[2] - rect[0]) < 1.5

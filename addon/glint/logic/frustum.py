"""Which objects can be seen at all: bounding boxes against the view frustum.

Screen-space reflections only reflect what is on screen, so an object whose
bounding box lies wholly outside the frustum adds nothing and is not exported.
The test runs in homogeneous clip space (no division), so boxes that straddle
or lie behind the camera are handled exactly.
"""
from __future__ import annotations

import numpy as np

# Clip-space half-spaces of OpenGL's frustum: a point is inside when every one
# of these is >= 0 (x + w, w - x, y + w, w - y, z + w, w - z).
_PLANES = np.array(
    [
        [1.0, 0.0, 0.0, 1.0],
        [-1.0, 0.0, 0.0, 1.0],
        [0.0, 1.0, 0.0, 1.0],
        [0.0, -1.0, 0.0, 1.0],
        [0.0, 0.0, 1.0, 1.0],
        [0.0, 0.0, -1.0, 1.0],
    ]
)


def box_corners(bound_box) -> np.ndarray:
    """Blender's ``Object.bound_box`` (8 corners) as an [8, 3] array."""
    c = np.asarray(bound_box, dtype=np.float64).reshape(-1, 3)
    if c.shape[0] == 0:
        raise ValueError("bound_box: expected corners, got none")
    return c


def outside_frustum(clip_from_local, corners) -> bool:
    """True when every corner lies outside one and the same frustum plane.

    ``clip_from_local`` = projection @ view @ object-to-world. Conservative: a box
    that is outside but not wholly beyond a single plane is kept (exported for
    nothing, never wrongly dropped).
    """
    m = np.asarray(clip_from_local, dtype=np.float64)
    c = np.asarray(corners, dtype=np.float64)
    if not np.all(np.isfinite(m)) or not np.all(np.isfinite(c)):
        return False  # cannot tell: keep it
    hom = np.concatenate([c, np.ones((c.shape[0], 1))], axis=1)
    clip = hom @ m.T  # [8, 4]
    dist = clip @ _PLANES.T  # [8, 6]
    return bool(np.any(np.all(dist < 0.0, axis=0)))


# ----------------------------------------------------------------------------
# Reach: which on-screen objects a reflected ray can meet
#
# A screen-space march only visits pixels along the screen projection of its
# ray, and a ray is at most ``max_distance`` long (every march's rule). So every
# pixel any ray visits lies in the projection of a reflective surface's box grown
# by max_distance, and the reflective pixels themselves lie in the projection of
# the reflective surfaces. An object whose screen rectangle meets none of those
# projected rectangles owns no pixel that a ray reads or that reflects: leaving
# it out of the G-buffer changes no traced value. Rectangles are conservative
# (a box's corners' projection bounds its projection; a box reaching behind the
# camera covers the whole screen), so nothing that matters is ever left out.

FULL_SCREEN = (-1.0, -1.0, 1.0, 1.0)
# Clip w below which a corner is taken as at or behind the eye: its projection
# is unbounded, so the rectangle is the whole screen.
_MIN_W = 1e-6


def screen_rect(clip_from_local, corners, margin: float = 0.0):
    """The NDC rectangle (x0, y0, x1, y1) bounding the projection of the box
    with these corners, grown by ``margin`` (NDC units) and clamped to the screen."""
    m = np.asarray(clip_from_local, dtype=np.float64)
    c = np.asarray(corners, dtype=np.float64).reshape(-1, 3)
    if not np.all(np.isfinite(m)) or not np.all(np.isfinite(c)):
        return FULL_SCREEN  # cannot tell: everything
    clip = np.concatenate([c, np.ones((c.shape[0], 1))], axis=1) @ m.T
    w = clip[:, 3]
    if np.any(w < _MIN_W):
        return FULL_SCREEN
    x, y = clip[:, 0] / w, clip[:, 1] / w
    return (max(float(x.min()) - margin, -1.0), max(float(y.min()) - margin, -1.0),
            min(float(x.max()) + margin, 1.0), min(float(y.max()) + margin, 1.0))


def transform_points(matrix, points) -> np.ndarray:
    """Points [N, 3] through an affine 4x4 matrix (object -> view)."""
    m = np.asarray(matrix, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64).reshape(-1, 3)
    return p @ m[:3, :3].T + m[:3, 3]


def grown_box_corners(view_corners, reach: float) -> np.ndarray:
    """The 8 corners of the axis-aligned box around ``view_corners`` grown by ``reach``
    on every side (it holds every point within ``reach`` of the corners' box)."""
    if not (reach >= 0.0):
        raise ValueError(f"reach: expected a distance >= 0, got {reach}")
    c = np.asarray(view_corners, dtype=np.float64).reshape(-1, 3)
    lo, hi = c.min(axis=0) - reach, c.max(axis=0) + reach
    return np.array([[(lo, hi)[i][0], (lo, hi)[j][1], (lo, hi)[k][2]]
                     for i in (0, 1) for j in (0, 1) for k in (0, 1)])


def rects_overlap(a, b) -> bool:
    """Closed rectangles meet (touching counts: kept rather than dropped)."""
    return a[0] <= b[2] and b[0] <= a[2] and a[1] <= b[3] and b[1] <= a[3]


def out_of_reach(object_rects, reflective, reach_rects):
    """For each object (its screen rectangle, whether it reflects): True when it can
    be left out: it does not reflect and meets none of ``reach_rects`` (the
    reflective surfaces' boxes grown by max_distance, projected)."""
    return [not refl and not any(rects_overlap(r, q) for q in reach_rects)
            for r, refl in zip(object_rects, reflective)]

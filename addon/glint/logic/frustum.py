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

"""The exact march's scene kept from one frame to the next.

Building Embree's BVH over a large scene costs several times the trace itself
(docs/marches.md, "Keeping the BVH"), and in an animation the geometry mostly
stays put while the camera moves. The export is in view space, where a camera
move changes every vertex, so the corners are carried back into world space
(``logic.geometry.world_vertices``) and one ``glint_core.ExactScene`` is kept
there: the same vertices bit for bit reuse the BVH, moved ones refit it (the
corners are unshared, so the same triangle count is the same topology), another
count rebuilds it. A camera move alone changes the world corners only by the
round trip's float32 rounding, which a refit absorbs. The scene is dropped as
soon as a frame does not use the exact march, so its memory is not held for
nothing.
"""
import threading

import numpy as np

from .logic import geometry

_lock = threading.Lock()  # a final render and the Measure operator may both trace
_scene = None


def seen_from_camera(core, triangles: geometry.Triangles, view_to_world):
    """``(mesh, update)``: what ``trace(mesh=...)`` takes for this frame, and
    ``{'bvh': 'built' | 'refit' | 'reused', 'ms': float}``."""
    global _scene
    vertices = geometry.world_vertices(triangles, view_to_world)
    with _lock:
        if _scene is not None and _scene.triangle_count * 3 == vertices.shape[0]:
            update = _scene.update(vertices)
        else:
            _scene = None  # its memory goes before the new one is built
            _scene = core.ExactScene(vertices, geometry.corner_triangles(vertices.shape[0]))
            update = _scene.last_update
        return _scene.seen_from(np.asarray(view_to_world, dtype=np.float64)), dict(update)


def release() -> None:
    """Drop the kept scene (a frame that does not use the exact march)."""
    global _scene
    with _lock:
        _scene = None

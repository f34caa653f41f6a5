"""Camera maths on numpy arrays: render size and window, view matrix, projection checks.

The projection itself comes from Blender (``Object.calc_matrix_camera``); this
module only checks it, builds the view transform the way Blender's renderers do
(camera scale removed) and projects points, so tests can compare against
Blender's independent ``world_to_camera_view``.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Optional, Tuple

import numpy as np

PERSPECTIVE = "perspective"
ORTHOGRAPHIC = "orthographic"


class ProjectionError(ValueError):
    """A projection Glint cannot use (the message says why)."""


def render_size(resolution_x: int, resolution_y: int, percentage: int) -> Tuple[int, int]:
    """The rendered image size: Blender's ``resolution * percentage / 100`` in integers."""
    w = int(resolution_x) * int(percentage) // 100
    h = int(resolution_y) * int(percentage) // 100
    if w < 1 or h < 1:
        raise ProjectionError(f"render size {w}x{h}: expected at least 1x1 pixels")
    return w, h


@dataclass(frozen=True)
class RenderWindow:
    """The pixels a render produces, inside its whole frame: columns [x0, x0 +
    width) and rows [y0, y0 + height) of a full_width x full_height frame (row 0 at
    the bottom), and whether the render's image is cropped to them. The whole frame
    when there is no render region."""
    full_width: int
    full_height: int
    x0: int
    y0: int
    width: int
    height: int
    cropped: bool = False

    @property
    def image_size(self) -> Tuple[int, int]:
        """The size of the image the render hands the compositor: the window's when
        cropped to it, else the whole frame's (black outside the window)."""
        return (self.width, self.height) if self.cropped else (self.full_width, self.full_height)


def render_window(resolution_x: int, resolution_y: int, percentage: int,
                  region: Optional[Tuple[float, float, float, float]] = None, crop: bool = False) -> RenderWindow:
    """The window a render produces. ``region``: the render region (border_min_x,
    border_max_x, border_min_y, border_max_y, fractions of the frame) when one is
    set, else None; ``crop``: the image is cropped to it (*Crop to Render
    Region*). Blender takes each side as the float32 product of the fraction and
    the frame's size, truncated (RE_InitState's disprect), and refuses a window
    under one pixel."""
    w, h = render_size(resolution_x, resolution_y, percentage)
    if region is None:
        return RenderWindow(w, h, 0, 0, w, h)
    min_x, max_x, min_y, max_y = (np.float32(v) for v in region)
    x0, x1 = int(min_x * np.float32(w)), int(max_x * np.float32(w))
    y0, y1 = int(min_y * np.float32(h)), int(max_y * np.float32(h))
    if x1 - x0 < 1 or y1 - y0 < 1:
        raise ProjectionError(f"render region of {x1 - x0}x{y1 - y0} pixels: expected at least 1x1")
    return RenderWindow(w, h, x0, y0, x1 - x0, y1 - y0, bool(crop))


def zero_outside(image: np.ndarray, window: RenderWindow) -> np.ndarray:
    """``image`` (the whole frame at its size or a reduced one, [h, w, ...]) with
    the pixels whose centres fall outside ``window`` set to 0, a copy."""
    out = np.array(image, copy=True)
    h, w = out.shape[:2]
    # pixel x's centre (x + 0.5) / w of the frame lies in [x0, x0 + width) / full_width
    cols = (2 * np.arange(w) + 1) * window.full_width
    rows = (2 * np.arange(h) + 1) * window.full_height
    keep_x = (cols >= 2 * window.x0 * w) & (cols < 2 * (window.x0 + window.width) * w)
    keep_y = (rows >= 2 * window.y0 * h) & (rows < 2 * (window.y0 + window.height) * h)
    out[~(keep_y[:, None] & keep_x[None, :])] = 0
    return out


def window_projection(projection, window: RenderWindow) -> np.ndarray:
    """The whole frame's projection narrowed to ``window``: its clip space maps the
    window's pixels to [-1, 1], so the window is a screen of its own (an off-axis
    projection, as a camera's shift makes). A pixel centre of the window and the
    same pixel of the whole frame see the same point."""
    m = np.array(projection, dtype=np.float64).reshape(4, 4).copy()
    fw, fh = float(window.full_width), float(window.full_height)
    # whole-frame NDC x = a x' + b, x' the window's NDC (the same for y)
    ax, bx = window.width / fw, (2.0 * window.x0 + window.width) / fw - 1.0
    ay, by = window.height / fh, (2.0 * window.y0 + window.height) / fh - 1.0
    m[0] = (m[0] - bx * m[3]) / ax
    m[1] = (m[1] - by * m[3]) / ay
    return m


def normalized_camera_matrix(matrix_world) -> np.ndarray:
    """The camera's world matrix with scale removed (unit axes), as renderers use it.

    Blender's renderers ignore camera scale: a camera object scaled by 2 renders
    the same image. The view matrix is the inverse of this.
    """
    m = np.array(matrix_world, dtype=np.float64).reshape(4, 4).copy()
    for c in range(3):
        n = np.linalg.norm(m[:3, c])
        if not np.isfinite(n) or n == 0.0:
            raise ProjectionError("camera matrix: an axis has zero or non-finite length")
        m[:3, c] /= n
    return m


def view_matrix(camera_matrix_world) -> np.ndarray:
    """World -> view (Blender camera space: -Z forward, +Y up)."""
    return np.linalg.inv(normalized_camera_matrix(camera_matrix_world))


def classify_projection(projection) -> str:
    """'perspective' or 'orthographic'; raises ProjectionError for anything unusable."""
    p = np.asarray(projection, dtype=np.float64)
    if p.shape != (4, 4):
        raise ProjectionError(f"projection: expected a 4x4 matrix, got shape {p.shape}")
    if not np.all(np.isfinite(p)):
        raise ProjectionError("projection: contains non-finite values")
    if abs(np.linalg.det(p)) < 1e-300:
        raise ProjectionError("projection: singular matrix")
    last = p[3]
    if np.allclose(last, (0.0, 0.0, -1.0, 0.0)):
        return PERSPECTIVE
    if np.allclose(last, (0.0, 0.0, 0.0, 1.0)):
        return ORTHOGRAPHIC
    raise ProjectionError(f"projection: last row {tuple(last)} is neither perspective nor orthographic")


def transform_points(matrix, points) -> np.ndarray:
    """Apply a 4x4 affine matrix to [..., 3] points."""
    m = np.asarray(matrix, dtype=np.float64)
    p = np.asarray(points, dtype=np.float64)
    return p @ m[:3, :3].T + m[:3, 3]


def normal_matrix(matrix) -> np.ndarray:
    """The 3x3 that carries normals through ``matrix``: the inverse transpose."""
    m3 = np.asarray(matrix, dtype=np.float64)[:3, :3]
    det = np.linalg.det(m3)
    if not np.isfinite(det) or abs(det) < 1e-300:
        # A flattened object (scale 0 on an axis) has no inverse: its normals
        # still point along the collapsed axis, which the cofactor matrix keeps.
        cof = np.empty((3, 3))
        for i in range(3):
            for j in range(3):
                minor = np.delete(np.delete(m3, i, 0), j, 1)
                cof[i, j] = (-1) ** (i + j) * np.linalg.det(minor)
        return cof
    return np.linalg.inv(m3).T


def transform_normals(matrix, normals) -> np.ndarray:
    """Normals through ``matrix`` (inverse transpose), renormalised; zero stays zero."""
    n = np.asarray(normals, dtype=np.float64) @ normal_matrix(matrix).T
    length = np.linalg.norm(n, axis=-1, keepdims=True)
    return np.divide(n, length, out=np.zeros_like(n), where=length > 0)


def project(projection, view_points) -> Tuple[np.ndarray, np.ndarray]:
    """View-space points -> (uv in [0, 1] across the image, clip w)."""
    p = np.asarray(projection, dtype=np.float64)
    v = np.asarray(view_points, dtype=np.float64)
    clip = v @ p[:3, :3].T + p[:3, 3]
    w = v @ p[3, :3] + p[3, 3]
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = clip[..., :2] / w[..., None] * 0.5 + 0.5
    return uv, w


def pixel_of_uv(uv, width: int, height: int) -> np.ndarray:
    """(col, row) of the pixel whose square contains uv (row 0 at the bottom)."""
    uv = np.asarray(uv, dtype=np.float64)
    return np.stack([np.floor(uv[..., 0] * width), np.floor(uv[..., 1] * height)], axis=-1).astype(np.int64)

"""Tracing a frame at a lower resolution when the core refuses it for memory.

The core works out from a request's sizes what it will allocate and refuses one
over its memory limit before allocating anything (``MemoryLimitExceeded``, with
``needed_bytes`` and ``limit_bytes``). Nearly all of that memory is per pixel:
the G-buffer, the trace's scratch and its output. So a refused frame is
rasterized and traced again at 1/2, 1/4 or 1/8 of its width and height (the
floor: 1/64 of its pixels), and the result is stretched back to the frame's size. The projection
does not depend on the pixel count, and the trace's reflected (u, v) are
normalized to the frame, so they stay valid at any size.

Stretching is by nearest neighbour, for every layer stretched (the uv, the
mask, and the G-buffer when a debug view or the layers EXR shows it). Bilinear weights would
invent uvs the trace never found: between a hit and a miss (whose uv is 0, 0)
they point toward the frame's corner, and between a reflected sphere and the
wall behind it they point at neither. Nearest keeps every uv one the trace
returned and every edge where it was, only coarser; the node group's blur
softens the blocks. No ``bpy`` here.
"""
from __future__ import annotations

import math
from typing import Optional, Tuple

import numpy as np

# The floor: the largest factor the width and the height are divided by.
MAX_FACTOR = 8

MIB = 1024.0 * 1024.0


def reduced_size(width: int, height: int, factor: int) -> Tuple[int, int]:
    """The trace size at ``factor`` (1, 2, 4, ...): each side divided, rounded up,
    so that the reduced pixels still cover the whole frame."""
    if factor < 1 or int(factor) != factor:
        raise ValueError(f"factor: expected a whole number >= 1, got {factor!r}")
    if width < 1 or height < 1:
        raise ValueError(f"width, height: expected at least 1 pixel, got {width}x{height}")
    f = int(factor)
    return -(-int(width) // f), -(-int(height) // f)


def next_factor(factor: int, needed_bytes: float = 0.0, limit_bytes: float = 0.0,
                max_factor: int = MAX_FACTOR) -> Optional[int]:
    """The factor to try after a refusal at ``factor``, or None when even the
    floor cannot fit.

    Memory goes with the pixel count, 1/f^2 of the frame's at factor f: the next
    factor is the smallest power of two that brings ``needed_bytes`` under
    ``limit_bytes`` by that rule, and at least twice ``factor`` (a refusal with
    unknown sizes halves). What does not shrink with the pixels (the triangles,
    the exact march's mesh) only makes a later try fail too, and halving goes on.
    """
    step = 2
    if needed_bytes > 0 and limit_bytes > 0 and needed_bytes > limit_bytes:
        step = max(2, 2 ** math.ceil(math.log2(math.sqrt(needed_bytes / limit_bytes))))
    nxt = int(factor) * step
    if nxt > max_factor:
        return None
    return nxt


def upsample_nearest(image: np.ndarray, width: int, height: int) -> np.ndarray:
    """``image`` ([h, w] or [h, w, C]) stretched to ``height`` x ``width``: each
    output pixel takes the input pixel under its centre. Pixel x of ``width``
    has its centre at (x + 0.5) / width of the frame, which falls in input
    column floor((x + 0.5) * w / width), computed exactly in integers."""
    img = np.asarray(image)
    h, w = img.shape[:2]
    if width < 1 or height < 1:
        raise ValueError(f"width, height: expected at least 1 pixel, got {width}x{height}")
    if (w, h) == (width, height):
        return img
    cols = ((2 * np.arange(width, dtype=np.int64) + 1) * w) // (2 * width)
    rows = ((2 * np.arange(height, dtype=np.int64) + 1) * h) // (2 * height)
    # np.take along one axis at a time: a tenth of the time of fancy indexing
    # (36 ms against 350 ms for 960x540 RGBA to 3840x2160 here).
    return np.take(np.take(img, rows, axis=0), cols, axis=1)


def mib(n: float) -> str:
    return f"{n / MIB:.1f} MiB"


def describe(width: int, height: int, factor: int, needed_bytes: float, limit_bytes: float) -> str:
    """The report of a frame traced at ``factor``: the size used and why."""
    w, h = reduced_size(width, height, factor)
    why = "the core refused the full size for memory"
    if needed_bytes > 0 and limit_bytes > 0:
        why = (f"{width}x{height} needs {mib(needed_bytes)}, over Glint's memory limit of "
               f"{mib(limit_bytes)}")
    return (f"reflections traced at reduced resolution {w}x{h} (1/{factor} of {width}x{height}): "
            f"{why}; raise the limit (GLINT_MEMORY_LIMIT_MB) for full resolution")


def retrying(width: int, height: int, refused: int, factor: int) -> str:
    """The log line of one retry: the size refused and the one tried next."""
    where = "full size" if refused == 1 else "{}x{} (1/{})".format(*reduced_size(width, height, refused), refused)
    w, h = reduced_size(width, height, factor)
    return f"over the memory limit at {where}; trying 1/{factor}: {w}x{h}"


def gave_up(width: int, height: int, factor: int, max_factor: int = MAX_FACTOR) -> str:
    """Why a frame refused at ``factor`` gets no reflections: the last size tried
    failed, or by the sizes even the floor would not fit."""
    if factor > 1:
        w, h = reduced_size(width, height, factor)
        return f"also at {w}x{h}, 1/{factor} of {width}x{height}, the smallest size tried"
    w, h = reduced_size(width, height, max_factor)
    return f"not even at {w}x{h}, 1/{max_factor} of {width}x{height}, would it fit"

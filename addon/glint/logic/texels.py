"""What the core reads from one G-buffer texel: whether it is seen, its specular
amount, and whether it reflects. No bpy, no glint_core.

These are ``glint/material.h``'s rules (``texel_seen``, ``specular_amount``,
``is_reflective``; docs/conventions.md), written once for the add-on: the frame's
masks (``compositing.py``, ``frame.py``), the material table (``gather.py``) and
the scene scan (``compositor.py``) all ask here. A copy of a rule elsewhere
drifts (the add-on once called a texel seen at ``w > 0.5`` where the core says
``w > 0``); tests/addon/test_texels.py checks these against glint_core.

Each takes an array of any shape ``[..., 4]`` (``[..., 3]`` for a colour): a
whole frame, or one material's row. The arithmetic is float32 in the core's
order, because the core decides on the float32 buffers the rasterizer writes:
a material's colour, kept in double precision by the add-on, is rounded to
float32 before it is asked about, as it is on its way into the G-buffer.
"""
from __future__ import annotations

import numpy as np


def specular_amount(specular) -> np.ndarray:
    """The core's specular amount: the mean of r, g and b, summed in that order
    (glint::specular_amount). Non-finite where a channel is."""
    s = np.asarray(specular, dtype=np.float32)
    # One pass per channel over strided views, no reduction along the last
    # axis: this runs on every pixel of a frame. A sum past float32's range
    # is inf, as in the core, which then calls the texel not reflective.
    with np.errstate(over="ignore"):
        amount = s[..., 0] + s[..., 1]
        amount += s[..., 2]
    amount /= np.float32(3.0)
    return amount


def is_reflective(specular) -> np.ndarray:
    """Whether the core traces a texel (or a material's pixels) with this
    specular: a positive, finite specular amount (glint::is_reflective)."""
    amount = specular_amount(specular)
    return (amount > 0) & np.isfinite(amount)


def texel_seen(position) -> np.ndarray:
    """Whether a position texel shows a surface: w > 0 and all four channels
    finite (glint::texel_seen). The rasterizer writes w = 1 where a triangle
    covers the pixel and 0 elsewhere."""
    p = np.asarray(position, dtype=np.float32)
    seen = p[..., 3] > 0
    # A sum of the four channels is finite when each is, and NaN or inf
    # propagate: one pass for the common frame. A non-finite sum also comes
    # from finite channels past ~8e37 that overflow, so then each channel is
    # asked, and the rule stays the core's exactly.
    with np.errstate(over="ignore"):
        total = p[..., 0] + p[..., 1]
        total += p[..., 2]
        total += p[..., 3]
    finite = np.isfinite(total)
    if not np.all(finite):
        finite = np.isfinite(p).all(axis=-1)
    seen &= finite
    return seen


def reflective_mask(position, specular) -> np.ndarray:
    """The texels the core traces, and counts as ``reflective_pixels``: seen,
    with a reflective specular."""
    mask = texel_seen(position)
    mask &= is_reflective(specular)
    return mask

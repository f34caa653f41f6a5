"""The images Glint hands the compositor, cut to what the group needs: the
region outside which the frame passes through (:func:`image_region`), the
offset that places it (:func:`region_offset`), the hidden sides' box
(:func:`hidden_images`), the coarse canvas of the wide blur levels
(:func:`coarse_images`) and the debug views (:func:`debug_image`).
logic/compositing.py describes the group that reads them and why each exists.
Pure numpy: no ``bpy``."""
from __future__ import annotations

import functools
from typing import Dict, Optional, Tuple

import numpy as np

from . import texels
from .compositing import (COARSE, GBUFFER_DEBUG_VIEWS, IMAGE_COARSE, IMAGE_FINE, IMAGE_HIDDEN, IMAGE_OFFSET,
                          IMAGE_UV, IMAGE_WEIGHT)


# Pixels kept around the region's hits: Map UV estimates each pixel's uv
# derivatives from its neighbours' uv (bilinear reads one pixel away), and a hit
# at the region's edge must see the same neighbours as in the whole frame (with
# 0 the frame's border hits change, tests/blender/test_region.py fails; 1 is
# enough there). The coarse levels need more: the region's outermost coarse
# texel must hold no D2, as the whole frame's texels beyond it hold none, and
# the filter that reads D2 for a texel reaches about a block around its centre.
# Two blocks of pad leave the outermost texel's block and its neighbour's half clear.
REGION_PAD = 2 * COARSE


def image_region(replaced: np.ndarray, lod: np.ndarray, pad: int = REGION_PAD) -> Tuple[int, int, int, int]:
    """(x0, y0, x1, y1), the pixel rows and columns [y0, y1) x [x0, x1) outside
    which the group leaves the frame as it is: the bounding box of the pixels
    whose reflection replaces something (the UV image's rep > 0: a hit or a
    hidden side; D = 0 elsewhere) and of the pixels that take a blurred D
    (lod > 0), grown by ``pad`` and cut to the frame. No such pixel: one pixel,
    whose rep 0 changes nothing."""
    h, w = np.shape(replaced)[:2]
    touched = np.asarray(replaced) > 0
    touched |= np.asarray(lod) > 0
    rows = np.flatnonzero(touched.any(axis=1))
    if rows.size == 0:
        return 0, 0, 1, 1
    cols = np.flatnonzero(touched[rows[0]:rows[-1] + 1].any(axis=0))
    x0, x1 = _same_parity(max(0, int(cols[0]) - pad), min(w, int(cols[-1]) + 1 + pad), w)
    y0, y1 = _same_parity(max(0, int(rows[0]) - pad), min(h, int(rows[-1]) + 1 + pad), h)
    return x0, y0, x1, y1


def _same_parity(lo: int, hi: int, size: int) -> Tuple[int, int]:
    """[lo, hi) grown by a pixel where its length and the frame's differ in
    parity: a canvas centred on the frame then sits on whole pixels, and the
    Translate that puts it back moves it by whole pixels, which every
    compositor does exactly (a half-pixel shift is rounded one way by 3.4 and
    interpolated by 4.2 and later)."""
    if (hi - lo) % 2 != size % 2:
        if hi < size:
            hi += 1
        else:
            lo -= 1
    return lo, hi


def region_offset(region: Tuple[int, int, int, int], width: int, height: int) -> Tuple[float, float]:
    """The Translate that puts a region-sized canvas, which Blender centres on
    the frame, at its place: (x0 + bw/2 - W/2, y0 + bh/2 - H/2) pixels, whole
    pixels for a region from :func:`image_region` (checked with Blender 3.4,
    Tiled and Full Frame, 4.3 and 5.2)."""
    x0, y0, x1, y1 = region
    return x0 + (x1 - x0) / 2.0 - width / 2.0, y0 + (y1 - y0) / 2.0 - height / 2.0


def hidden_box(seen: np.ndarray, region: Tuple[int, int, int, int]) -> Tuple[int, int, int, int]:
    """(x0, y0, x1, y1) in the frame: the bounding box of the hidden sides
    (``seen``, frame-sized) inside ``region``, its width and height of the
    region's parity so that the Translate into the region moves it by whole
    pixels (:func:`_same_parity`); none: a box of one or two pixels."""
    rx0, ry0, rx1, ry1 = region
    inside = np.asarray(seen)[ry0:ry1, rx0:rx1]
    rows = np.flatnonzero(inside.any(axis=1))
    if rows.size == 0:
        x0, x1, y0, y1 = 0, 1, 0, 1
    else:
        cols = np.flatnonzero(inside[rows[0]:rows[-1] + 1].any(axis=0))
        x0, x1, y0, y1 = int(cols[0]), int(cols[-1]) + 1, int(rows[0]), int(rows[-1]) + 1
    x0, x1 = _same_parity(x0, x1, rx1 - rx0)
    y0, y1 = _same_parity(y0, y1, ry1 - ry0)
    return rx0 + x0, ry0 + y0, rx0 + x1, ry0 + y1


def hidden_images(hidden: Optional[np.ndarray], region: Tuple[int, int, int, int], width: int, height: int,
                  placeable: bool = True) -> Tuple[Dict[str, np.ndarray], Tuple[float, float]]:
    """The hidden sides' image on their box (:func:`hidden_box`) and the
    Translate that puts the box in the region: :data:`IMAGE_HIDDEN` (albedo,
    vis) as ``composite_layers`` gives it (None: a frame without hidden sides,
    all 0). The group reads the frame's light under the box through a
    Translate by the box's offset (``hidden_light``), so the box needs no uv.
    Not ``placeable`` (a compositor that takes a Translate's offset as one
    value, host/nodes.compositor_places_regions): the box is the region, which
    is the frame."""
    if placeable:
        seen = np.zeros((height, width), bool) if hidden is None else np.asarray(hidden)[..., 3] > 0
        x0, y0, x1, y1 = hidden_box(seen, region)
    else:
        x0, y0, x1, y1 = region
    albedo = np.zeros((y1 - y0, x1 - x0, 4), np.float32) if hidden is None else hidden[y0:y1, x0:x1]
    rx0, ry0, rx1, ry1 = region
    offset = (x0 + (x1 - x0) / 2.0 - (rx0 + rx1) / 2.0, y0 + (y1 - y0) / 2.0 - (ry0 + ry1) / 2.0)
    return {IMAGE_HIDDEN: albedo}, offset


def region_images(uv: np.ndarray, weight: np.ndarray, region: Tuple[int, int, int, int],
                  hidden_offset: Tuple[float, float] = (0.0, 0.0), fine: bool = True,
                  bin_means=None) -> Dict[str, np.ndarray]:
    """The uv and weight images cut to ``region`` (views, not copies), the 1x1
    offset image that places them (:data:`IMAGE_OFFSET`: dx, dy and the hidden
    box's offset in the region, :func:`hidden_images`) and the coarse levels'
    images (:func:`coarse_images`; ``fine``: the group reads the coarse canvas
    back through the fine image, where the host's Scale cannot do it:
    host/nodes.coarse_read_back_by_scale)."""
    x0, y0, x1, y1 = region
    h, w = np.shape(uv)[:2]
    dx, dy = region_offset(region, w, h)
    images = {IMAGE_UV: uv[y0:y1, x0:x1], IMAGE_WEIGHT: weight[y0:y1, x0:x1],
              IMAGE_OFFSET: np.array([[[dx, dy, hidden_offset[0], hidden_offset[1]]]], np.float32)}
    images.update(coarse_images(weight[y0:y1, x0:x1, 3], region, w, h, fine, bin_means))
    return images


def coarse_size(width: int, height: int) -> Tuple[int, int]:
    """The coarse canvas's texels across and up: one per COARSE pixels of the
    frame and one more, so that texel i sits at pixel i x width / across, where
    ``frame_scale`` reads it (Blender's Scale to the render size reads texel
    x x across / width at pixel x; past the last texel it blends with 0)."""
    return width // COARSE + 1, height // COARSE + 1


def coarse_grid_shift(width: int, height: int) -> Tuple[float, float]:
    """The move of ``coarse_grid``, the Translate after the coarse read-back's
    Scale, on a compositor whose Scale is placed by its domain
    (host/nodes.scale_reads_by_domain, 5.x), so that
    frame pixel x reads the coarse canvas at texel x cw / W, as ``frame_scale``
    reads it on 3.x-4.1 and in this model.

    There a Scale and the Translate after it only transform the canvas's
    domain, and the Mix that meets the frame samples it once, bilinearly, at
    u = (x + 0.5 - t) cw / W - 0.5 - c, where c is -0.5 when cw and W differ
    in parity and 0 otherwise (Blender keeps a canvas centred on the frame's
    centre; the half-texel c puts an odd canvas's centre texel there). Solved
    for u = x cw / W: t = 0.5 - (0.5 + c) W / cw, per axis. docs/frame-cost.md,
    *On 5.2: the Scale read-back placed*."""
    def axis(size: int, n: int) -> float:
        c = -0.5 if (n ^ size) & 1 else 0.0
        return 0.5 - (0.5 + c) * size / n
    cw, ch = coarse_size(width, height)
    return axis(int(width), cw), axis(int(height), ch)


def coarse_scale_offset(width: int, height: int) -> Tuple[float, float]:
    """The offsets of ``coarse_to_frame`` (the Scale node's X and Y offset,
    both as fractions of the frame's width) on 4.2-4.3's compositor
    (host/nodes.scale_offset_places_read), so that frame pixel x reads the
    coarse canvas at texel x cw / W, as ``frame_scale`` reads it.

    Measured there (docs/frame-cost.md, *On 4.3: what a node costs, and how its
    Scale reads*): with offsets (ox, oy) pixel (x, y) reads the texel
    coordinates u = (x + 0.5 - ox W) cw / W - 0.5 and v = (y + 0.5 - oy W)
    ch / H - 0.5, in one bilinear read. Solved for u = x cw / W and
    v = y ch / H."""
    cw, ch = coarse_size(width, height)
    w, h = float(width), float(height)
    return 0.5 / w - 0.5 / cw, (0.5 - 0.5 * h / ch) / w


def _nearest_texels(lo: int, hi: int, size: int, n: int) -> np.ndarray:
    """For the pixels [lo, hi) of a frame axis of ``size`` pixels, the coarse
    texel (of ``n``) each one's read lies nearest."""
    return np.minimum(np.floor(np.arange(lo, hi) * (n / size) + 0.5).astype(np.int64), n - 1)


def _texel_sums(values: np.ndarray, texel: np.ndarray, n: int, axis: int) -> np.ndarray:
    """``values`` summed along ``axis`` over the runs of pixels of one texel
    (``texel`` does not decrease), placed at those texels of ``n``."""
    starts = np.flatnonzero(np.r_[True, texel[1:] != texel[:-1]])
    sums = np.add.reduceat(values, starts, axis=axis)
    shape = list(values.shape)
    shape[axis] = n
    out = np.zeros(shape, sums.dtype)
    index = [slice(None)] * values.ndim
    index[axis] = texel[starts]
    out[tuple(index)] = sums
    return out


def positive_bin_means(values: np.ndarray, row_bins: np.ndarray, col_bins: np.ndarray,
                       shape: Tuple[int, int]) -> np.ndarray:
    """Per bin of ``values`` (rows and columns binned by ``row_bins`` and
    ``col_bins``, which never decrease), the mean of its positive values, 0
    where it has none: float32 ``shape``. The rule; the core's
    ``positive_bin_means`` gives the same bits several times faster (a 1080p
    region's sums were 36 ms of numpy a frame), and :func:`coarse_images`
    takes it in this one's place."""
    values = np.asarray(values, np.float32)
    total = _texel_sums(_texel_sums(np.maximum(values, 0.0), row_bins, shape[0], 0), col_bins, shape[1], 1)
    count = _texel_sums(_texel_sums((values > 0).astype(np.int32), row_bins, shape[0], 0), col_bins, shape[1], 1)
    return np.where(count > 0, total / np.maximum(count, 1), 0.0).astype(np.float32)


def coarse_images(lod: np.ndarray, region: Tuple[int, int, int, int], width: int, height: int,
                  fine: bool = True, bin_means=None) -> Dict[str, np.ndarray]:
    """The coarse canvas's images for a region of a ``width`` x ``height``
    frame whose pixels have ``lod``. The canvas covers the frame
    (:func:`coarse_size`), texel (i, j) at the frame's pixel (i W / cw, j H / ch):

    * :data:`IMAGE_COARSE`: (u, v) of that point in the region's uv (where Map
      UV reads D2; its filter, sized by the texels' spacing, averages the
      pixels around it), 1 (Map UV's vis), and the mean lod of the blurred
      pixels (lod > 0) nearest the texel, 0 where there are none, which mixes
      the levels there;
    * with ``fine``, :data:`IMAGE_FINE`, region-sized: (u, v) on the coarse
      canvas of the point each pixel reads, the texel coordinates x cw / W and
      y ch / H, 1, 1: the Map UV read-back, for a compositor whose Scale does
      not read where ``frame_scale`` does (4.4-4.5, untested). Without: the compositor
      reads the canvas back through ``frame_scale``.

    ``bin_means``: the core's ``positive_bin_means``, which gives the same bits;
    None: :func:`positive_bin_means`."""
    x0, y0, x1, y1 = region
    bw, bh = x1 - x0, y1 - y0
    cw, ch = coarse_size(width, height)
    coarse = np.ones((ch, cw, 4), np.float32)
    coarse[..., 0] = ((np.arange(cw) * (width / cw) + 0.5 - x0) / bw)[None, :]
    coarse[..., 1] = ((np.arange(ch) * (height / ch) + 0.5 - y0) / bh)[:, None]
    tx, ty = _nearest_texels(x0, x1, width, cw), _nearest_texels(y0, y1, height, ch)
    coarse[..., 3] = (bin_means or positive_bin_means)(np.asarray(lod, np.float32), ty, tx, (ch, cw))
    images = {IMAGE_COARSE: coarse}
    if fine:
        images[IMAGE_FINE] = _fine_image(tuple(int(v) for v in region), int(width), int(height))
    return images


@functools.lru_cache(maxsize=1)
def _fine_image(region: Tuple[int, int, int, int], width: int, height: int) -> np.ndarray:
    """:data:`IMAGE_FINE` of a region: it depends on the region and the frame's
    size alone, and at 1080p making it (28 MB of fresh pages) was a fifth of the
    images stage, in every frame, although the add-on writes it only when the
    region moves.
    Read-only: the cache hands the same array to every caller."""
    x0, y0, x1, y1 = region
    cw, ch = coarse_size(width, height)
    fine = np.ones((y1 - y0, x1 - x0, 4), np.float32)
    # Map UV reads the texel whose centre is at uv x size - 0.5
    fine[..., 0] = ((np.arange(x0, x1) * (cw / width) + 0.5) / cw)[None, :]
    fine[..., 1] = ((np.arange(y0, y1) * (ch / height) + 0.5) / ch)[:, None]
    fine.flags.writeable = False
    return fine


def debug_image(view: str, position, normal, specular, uv) -> np.ndarray:
    """The RGBA picture of a G-buffer layer for the debug view (alpha 1)."""
    h, w = np.asarray(position).shape[:2]
    out = np.zeros((h, w, 4), np.float32)
    seen = texels.texel_seen(position)
    if view == "POSITION":
        out[..., :3] = np.asarray(position)[..., :3]
    elif view == "NORMAL":
        out[..., :3] = np.where(seen[..., None], np.asarray(normal)[..., :3] * 0.5 + 0.5, 0.0)
    elif view == "SPECULAR":
        out[..., :3] = np.asarray(specular)[..., :3]
    elif view == "UV":
        vis = np.asarray(uv)[..., 2:3] > 0
        out[..., :2] = np.where(vis, np.asarray(uv)[..., :2], 0.0)
    elif view == "VISIBILITY":
        out[..., :3] = np.asarray(uv)[..., 2:3]
    else:
        raise ValueError(f"debug view: expected one of {GBUFFER_DEBUG_VIEWS}, got {view!r}")
    out[..., 3] = 1.0
    return np.nan_to_num(out, nan=0.0, posinf=0.0, neginf=0.0)

"""The add-on's compositor group (logic/compositing.py's GROUP_NODES and
GROUP_LINKS) run on numpy arrays, as Blender runs it: each operation sized by
its inputs, a region meeting the frame untranslated an error. The tests hold
the wiring to the composite's formula with it (test_compositing.py); it is
test code, so it lives here and not in the add-on."""
from __future__ import annotations

from typing import Callable, Dict, Optional, Tuple

import numpy as np

from glint_addon_helpers import load_logic

cg = load_logic("compositing")
GROUP_IN, GROUP_OUT, GROUP_NODES, GROUP_LINKS, GROUP_OUTPUTS = (
    cg.GROUP_IN, cg.GROUP_OUT, cg.GROUP_NODES, cg.GROUP_LINKS, cg.GROUP_OUTPUTS)
IMAGE_HIDDEN, IMAGE_OFFSET, IMAGE_UV = cg.IMAGE_HIDDEN, cg.IMAGE_OFFSET, cg.IMAGE_UV
SOFTEN_TAPS = cg.SOFTEN_TAPS
switch_states = cg.switch_states



def _blend(props, fac, c1, c2):
    """Blender's compositor Mix node; like Blender's, it keeps the first input's alpha."""
    fac = np.asarray(fac, dtype=np.float32)
    if fac.ndim == c1.ndim - 1:
        fac = fac[..., None]
    mode = props["blend"]
    out = np.array(c1, dtype=np.float32, copy=True)
    if mode == "MIX":
        out[..., :3] = (1.0 - fac) * c1[..., :3] + fac * c2[..., :3]
    elif mode == "MULTIPLY":
        out[..., :3] = c1[..., :3] * ((1.0 - fac) + fac * c2[..., :3])
    elif mode == "ADD":
        out[..., :3] = c1[..., :3] + fac * c2[..., :3]
    elif mode == "SUBTRACT":
        out[..., :3] = c1[..., :3] - fac * c2[..., :3]
    elif mode in ("LIGHTEN", "DARKEN"):  # 4.x-5.x's rule; 3.4's, max(c1, fac * c2), is the same at factor 1
        pick = np.maximum if mode == "LIGHTEN" else np.minimum
        out[..., :3] = (1.0 - fac) * c1[..., :3] + fac * pick(c1[..., :3], c2[..., :3])
    else:
        raise ValueError(f"blend {mode!r} is not modelled")
    return out.astype(np.float32)


def _as_colour(v, shape):
    """A socket value as RGBA: a float v becomes (v, v, v, 1), as Blender converts it."""
    v = np.asarray(v, dtype=np.float32)
    if v.shape == tuple(shape):
        return v
    if v.shape == (4,):  # an unlinked colour socket's default
        return np.broadcast_to(v, tuple(shape)).astype(np.float32)
    out = np.ones(shape, np.float32)
    out[..., :3] = np.broadcast_to(v, tuple(shape[:-1]))[..., None]
    return out


_MATH = {"ADD": lambda a, b, c: a + b, "SUBTRACT": lambda a, b, c: a - b, "MULTIPLY": lambda a, b, c: a * b,
         "DIVIDE": lambda a, b, c: a / b, "MULTIPLY_ADD": lambda a, b, c: a * b + c,
         "MAXIMUM": lambda a, b, c: np.where(a > b, a, b)}  # Blender's: a NaN a gives b


def _canvas(values, frame_hw):
    """The (h, w) an operation works on: that of its array inputs, which must
    agree (the group never lets the region meet the frame untranslated), else
    the frame's when all are constants."""
    sizes = {tuple(np.shape(v)[:2]) for v in values if v is not None and np.ndim(v) >= 2}
    if len(sizes) > 1:
        raise ValueError(f"inputs of different sizes meet: {sorted(sizes)} (translate the region first)")
    return sizes.pop() if sizes else frame_hw


def _softened(img: np.ndarray) -> np.ndarray:
    """Blender's Filter node, Soften, at factor 1: the 3x3 kernel
    SOFTEN_TAPS along each axis on every channel, the edge texels repeated
    past the canvas."""
    h, w = img.shape[:2]
    k = [np.float32(c) for c in SOFTEN_TAPS]
    rows = sum(k[i] * img[np.clip(np.arange(h) + i - 1, 0, h - 1)] for i in range(3))
    return sum(k[i] * rows[:, np.clip(np.arange(w) + i - 1, 0, w - 1)] for i in range(3)).astype(np.float32)


def _scaled_to_frame(img: np.ndarray, frame_hw) -> np.ndarray:
    """Blender's Scale to the render size, stretched (``frame_scale``, as 3.4
    does it): pixel (x, y) of the frame is the bilinear read of ``img`` at
    texel coordinates (x n / W, y m / H), texel centres on whole numbers,
    0 past the canvas."""
    h, w = frame_hw
    m, n = img.shape[:2]
    padded = np.zeros((m + 1, n + 1) + img.shape[2:], np.float32)
    padded[:m, :n] = img

    def taps(count, size):
        pos = np.arange(count) * (size / count)
        first = np.floor(pos).astype(np.int64)
        return first, (pos - first).astype(np.float32)

    x, fx = taps(w, n)
    y, fy = taps(h, m)
    rows = padded[y] * (1.0 - fy)[:, None, None] + padded[y + 1] * fy[:, None, None]
    return (rows[:, x] * (1.0 - fx)[None, :, None] + rows[:, x + 1] * fx[None, :, None]).astype(np.float32)


def _region_origin(region_hw, dx: float, dy: float, frame_hw) -> Tuple[int, int]:
    """The frame's column and row where a region-sized canvas, centred on the
    frame and translated by (dx, dy) pixels, starts; raises unless it lands on
    whole pixels inside the frame."""
    h, w = frame_hw
    bh, bw = region_hw
    x0, y0 = dx + (w - bw) / 2.0, dy + (h - bh) / 2.0
    if x0 != int(x0) or y0 != int(y0) or not (0 <= x0 <= w - bw and 0 <= y0 <= h - bh):
        raise ValueError(f"a {bw}x{bh} region translated by ({dx}, {dy}) does not land on the frame's pixels")
    return int(x0), int(y0)


def _translated(value, dx: float, dy: float, frame_hw) -> np.ndarray:
    """Blender's Translate of a region-sized canvas, centred on the frame, by
    (dx, dy) pixels: the region's pixels in a frame of zeros (or a box's in a
    region's, ``frame_hw`` then the region's size)."""
    value = np.asarray(value, dtype=np.float32)
    bh, bw = value.shape[:2]
    x0, y0 = _region_origin((bh, bw), dx, dy, frame_hw)
    out = np.zeros(tuple(frame_hw) + value.shape[2:], np.float32)
    out[y0:y0 + bh, x0:x0 + bw] = value
    return out


def _region_of(value, dx: float, dy: float, region_hw, frame_hw) -> np.ndarray:
    """A frame-sized canvas moved by minus the region's offset (dx, dy), as a
    region-sized operation reads it (Blender centres the larger canvas on the
    smaller): the frame's pixels under the region."""
    value = np.asarray(value, dtype=np.float32)
    if value.shape[:2] != tuple(frame_hw):
        value = _as_colour(value, tuple(frame_hw) + (4,))
    bh, bw = region_hw
    x0, y0 = _region_origin(region_hw, dx, dy, frame_hw)
    return value[y0:y0 + bh, x0:x0 + bw]


def evaluate_group(base: np.ndarray, images: Dict[str, np.ndarray],
                   map_uv: Callable[[np.ndarray, np.ndarray], np.ndarray],
                   blur: Callable[[np.ndarray, float], np.ndarray],
                   specular_light: Optional[np.ndarray] = None, specular_color: Optional[np.ndarray] = None,
                   debug_view: str = "NONE", use_blur: bool = True,
                   use_bounce: bool = False, world_specular: bool = False,
                   use_hidden: bool = False, soften_filters: bool = True,
                   whole_frame: bool = False, scale_read_back: Optional[bool] = None) -> Dict[str, np.ndarray]:
    """Run :data:`GROUP_NODES` / :data:`GROUP_LINKS` on arrays.

    ``soften_filters``: the host runs the first level as the 3x3 filter
    (host/nodes.soften_is_a_filter), else as ``blur`` at SOFTEN_SIGMA, the
    lift's Switches off. ``whole_frame``: the host's group works on the whole
    frame (``images`` frame-sized), and a hidden side's light is the frame.
    ``scale_read_back``: as :func:`switch_states` takes it.

    ``map_uv(image, uv_rgba)`` and ``blur(image, sigma)`` stand in for Blender's
    Map UV and Fast Gaussian (e.g. a bilinear lookup and an exact Gaussian, to
    check the wiring; Blender's own filters differ slightly). The engine's
    passes default to black, as an unlinked group input is. ``images`` as the
    add-on fills them: :data:`REGION_IMAGES` cut to a region and
    ``IMAGE_OFFSET`` placing it (:func:`region_images`), or frame-sized with a
    zero offset (the default when ``IMAGE_OFFSET`` is missing). Operations work
    on the size of their inputs, as Blender's do, and inputs of two sizes
    meeting raise. Returns the group's outputs by name.
    """
    base = np.asarray(base, dtype=np.float32)
    frame_hw = base.shape[:2]
    images = dict(images)
    images.setdefault(IMAGE_OFFSET, np.array([[[0.0, 0.0, 0.0, 0.0]]], np.float32))
    black = np.array((0.0, 0.0, 0.0, 1.0), np.float32)
    group_in = [base, black if specular_light is None else np.asarray(specular_light, np.float32),
                black if specular_color is None else np.asarray(specular_color, np.float32)]
    incoming: Dict[Tuple[str, int], Tuple[str, int]] = {}
    for src, so, dst, di in GROUP_LINKS:
        incoming[(dst, di)] = (src, so)
    cache: Dict[Tuple[str, int], np.ndarray] = {}
    switches = switch_states(debug_view, use_blur, use_bounce, world_specular, use_hidden, soften_filters,
                             whole_frame, scale_read_back)

    def inp(node, index):
        link = incoming.get((node, index))
        if link is None:
            return GROUP_NODES[node][2].get(index)
        return out(*link)

    def out(node, index):
        key = (node, index)
        if key not in cache:
            if node == GROUP_IN:
                cache[key] = group_in[index]
            elif GROUP_NODES[node][0] == "switch":  # the other side is never read: muted (dead_nodes)
                cache[key] = inp(node, 1 if switches[node] else 0)
            else:
                cache[key] = _node_output(node, index, lambda i: inp(node, i), frame_hw, images, map_uv, blur,
                                          soften_filters)
        return cache[key]

    return {name: inp(GROUP_OUT, i) for i, (name, _) in enumerate(GROUP_OUTPUTS)}


def _node_output(node: str, index: int, inp: Callable[[int], object], frame_hw, images: Dict[str, np.ndarray],
                 map_uv, blur, soften_filters: bool = True) -> np.ndarray:
    """Output ``index`` of one of :data:`GROUP_NODES` (not a switch), given its
    inputs by number (``inp``), on the canvas Blender would give it."""
    kind, props, _ = GROUP_NODES[node]
    n_in = {"math": 3, "mix": 3, "combine": 4}.get(kind)
    hw = _canvas([inp(i) for i in range(n_in)], frame_hw) if n_in else None
    if kind == "image":
        value = np.asarray(images[props["image"]], dtype=np.float32)
        return value[..., 3] if index == 1 else value
    if kind == "translate":
        dx, dy = (float(np.asarray(inp(i), np.float32).flat[0]) for i in (1, 2))
        if props["onto"] == "region":
            return _translated(inp(0), dx, dy, np.shape(images[IMAGE_UV])[:2])
        if props["onto"] == "box":
            return _region_of(inp(0), -dx, -dy, np.shape(images[IMAGE_HIDDEN])[:2], frame_hw)
        if props["onto"] == "grid":  # frame_scale already reads where the host's Scale and this move do
            return inp(0)
        if props["sign"] < 0:
            return _region_of(inp(0), -dx, -dy, np.shape(images[IMAGE_UV])[:2], frame_hw)
        return _translated(inp(0), dx, dy, frame_hw)
    if kind == "combine":
        return np.stack([np.broadcast_to(np.asarray(inp(i), np.float32), hw) for i in range(4)], axis=-1)
    if kind == "map_uv":
        return map_uv(inp(0), inp(1))
    if kind == "frame_scale":
        return _scaled_to_frame(np.asarray(inp(0), np.float32), frame_hw)
    if kind == "keep":
        return inp(0)
    if kind == "blur":
        return blur(inp(0), props["sigma"])
    if kind == "soften":
        if not soften_filters:
            return blur(inp(0), props["sigma"])
        return np.maximum(_softened(np.asarray(inp(0), np.float32)), 0.0)  # Blender clamps at 0
    if kind == "separate":
        src = inp(0)
        return _as_colour(src, tuple(_canvas([src], frame_hw)) + (4,))[..., index]
    if kind == "math":
        a, b, c = (np.asarray(inp(i) if inp(i) is not None else 0.0, np.float32) for i in range(3))
        value = _MATH[props["operation"]](a, b, c)
        if props["clamp"]:
            value = np.clip(value, 0.0, 1.0)
        return np.broadcast_to(value, hw).astype(np.float32)
    if kind == "mix":
        fac = np.asarray(inp(0), np.float32)
        shape = tuple(hw) + (4,)
        return _blend(props, fac, _as_colour(inp(1), shape), _as_colour(inp(2), shape))
    raise ValueError(kind)

"""The compositing maths: the images Glint hands the compositor, and the node
group that turns them into the core's combine, described as data.

The core's combine (``native/src/cpu/cpu_backend.cpp``) is premultiplied "over":

    C    = (colour at uv * vis, vis)                    reflection colour
    B    = box_blur(C)                                  (2 size + 1)^2, all 4 channels
    refl = (C * (1 - r) + B * r) * amount               r = 1 - clamp(spec.a, 0, 1)
    out  = base.rgb * (1 - clamp(refl.a, 0, 1)) + refl.rgb,  alpha = base alpha

where amount = mean(spec.rgb). Before the render Glint knows the G-buffer and
the reflected uv, not the colour: it hands the compositor two images

    UV image   = (u, v, vis, 1)        Map UV's UV input: it samples at (u, v)
                                       and premultiplies by the third channel
    mask image = the specular buffer   (r, g, b, shininess / 127.75) as the
                                       rasterizer made it (zero where nothing is
                                       seen); the nodes take amount and r from it

and :data:`GROUP_NODES` / :data:`GROUP_LINKS` compute ``out`` with Blender's
own nodes (Map UV, a Flat blur, Mix and Math), in the core's order of
operations. :func:`evaluate_group` runs the same description on numpy arrays,
so tests can check the wiring against the formula without Blender.
"""
from __future__ import annotations

from typing import Callable, Dict, List, Tuple

import numpy as np

# Image data-blocks the group reads (filled by the add-on before compositing).
IMAGE_UV = "Glint UV"
IMAGE_MASK = "Glint Mask"
IMAGE_DEBUG = "Glint Debug"
IMAGE_POSITION = "Glint Position"
IMAGE_NORMAL = "Glint Normal"
IMAGE_SPECULAR = "Glint Specular"
ALL_IMAGES = (IMAGE_UV, IMAGE_MASK, IMAGE_DEBUG, IMAGE_POSITION, IMAGE_NORMAL, IMAGE_SPECULAR)

GROUP_NAME = "Glint"
GROUP_NODE_NAME = "Glint"  # the group node in the scene's compositor tree
EXR_NODE_NAME = "Glint EXR"

GROUP_INPUTS = (("Image", "NodeSocketColor"),)
GROUP_OUTPUTS = (
    ("Image", "NodeSocketColor"),  # composited (or the debug view)
    ("Reflection", "NodeSocketColor"),  # premultiplied reflection
    ("Base", "NodeSocketColor"),
    ("UV", "NodeSocketColor"),
    ("Visibility", "NodeSocketFloat"),
    ("Position", "NodeSocketColor"),
    ("Normal", "NodeSocketColor"),
    ("Specular", "NodeSocketColor"),
)

# Debug views: enum value -> (label, description). REFLECTION is computed in the
# compositor; the others are G-buffer layers shown through IMAGE_DEBUG.
DEBUG_VIEWS = (
    ("NONE", "None", "The composited frame"),
    ("POSITION", "Position", "View-space position (x, y, z)"),
    ("NORMAL", "Normal", "View-space normal, shown as n * 0.5 + 0.5"),
    ("SPECULAR", "Specular", "Specular colour (rgb) of the specular buffer"),
    ("UV", "Reflected UV", "The reflected uv (u, v, 0) where a reflection was found"),
    ("VISIBILITY", "Visibility", "The reflection's visibility as grey"),
    ("REFLECTION", "Reflection", "The premultiplied reflection before it is combined"),
)
GBUFFER_DEBUG_VIEWS = ("POSITION", "NORMAL", "SPECULAR", "UV", "VISIBILITY")

# Node description: name -> (bl_idname, properties, {input index: default value}).
# Inputs are addressed by index: Math nodes have two inputs both named "Value".
GROUP_NODES: Dict[str, Tuple[str, Dict[str, object], Dict[int, object]]] = {
    "uv_image": ("CompositorNodeImage", {"image": IMAGE_UV}, {}),
    "mask_image": ("CompositorNodeImage", {"image": IMAGE_MASK}, {}),
    "debug_image": ("CompositorNodeImage", {"image": IMAGE_DEBUG}, {}),
    "position_image": ("CompositorNodeImage", {"image": IMAGE_POSITION}, {}),
    "normal_image": ("CompositorNodeImage", {"image": IMAGE_NORMAL}, {}),
    "specular_image": ("CompositorNodeImage", {"image": IMAGE_SPECULAR}, {}),
    # alpha = 0: no fading by uv derivatives, so Map UV only premultiplies by vis.
    "map_uv": ("CompositorNodeMapUV", {"alpha": 0}, {}),
    # Flat = Blender's box filter: 2 size + 1 equal taps per axis.
    "blur": ("CompositorNodeBlur", {"filter_type": "FLAT", "use_relative": False, "use_bokeh": False,
                                    "use_gamma_correction": False, "use_extended_bounds": False,
                                    "use_variable_size": False, "size_x": 8, "size_y": 8}, {1: 1.0}),
    "sep_color": ("CompositorNodeSeparateColor", {"mode": "RGB"}, {}),
    "sep_blur": ("CompositorNodeSeparateColor", {"mode": "RGB"}, {}),
    "sep_mask": ("CompositorNodeSeparateColor", {"mode": "RGB"}, {}),
    "sep_uv": ("CompositorNodeSeparateColor", {"mode": "RGB"}, {}),
    # amount = mean(spec.rgb), r = 1 - clamp(spec.a, 0, 1): the mask image is the
    # rasterizer's specular buffer itself, handed over without a copy.
    "amount_rg": ("CompositorNodeMath", {"operation": "ADD", "use_clamp": False}, {}),
    "amount_rgb": ("CompositorNodeMath", {"operation": "ADD", "use_clamp": False}, {}),
    "amount": ("CompositorNodeMath", {"operation": "DIVIDE", "use_clamp": False}, {1: 3.0}),
    # 1 - a clamped to [0, 1] is 1 - clamp(a, 0, 1) for every a.
    "rough": ("CompositorNodeMath", {"operation": "SUBTRACT", "use_clamp": True}, {0: 1.0}),
    "mix_rough": ("CompositorNodeMixRGB", {"blend_type": "MIX", "use_alpha": False, "use_clamp": False}, {}),
    "refl_rgb": ("CompositorNodeMixRGB", {"blend_type": "MULTIPLY", "use_alpha": False, "use_clamp": False},
                 {0: 1.0}),
    "one_minus_rough": ("CompositorNodeMath", {"operation": "SUBTRACT", "use_clamp": False}, {0: 1.0}),
    "c_alpha": ("CompositorNodeMath", {"operation": "MULTIPLY", "use_clamp": False}, {}),
    "b_alpha": ("CompositorNodeMath", {"operation": "MULTIPLY", "use_clamp": False}, {}),
    "mixed_alpha": ("CompositorNodeMath", {"operation": "ADD", "use_clamp": False}, {}),
    "refl_alpha": ("CompositorNodeMath", {"operation": "MULTIPLY", "use_clamp": True}, {}),
    "one_minus_alpha": ("CompositorNodeMath", {"operation": "SUBTRACT", "use_clamp": False}, {0: 1.0}),
    "base_scaled": ("CompositorNodeMixRGB", {"blend_type": "MULTIPLY", "use_alpha": False, "use_clamp": False},
                    {0: 1.0}),
    "combined": ("CompositorNodeMixRGB", {"blend_type": "ADD", "use_alpha": False, "use_clamp": False},
                 {0: 1.0}),
    "sep_refl": ("CompositorNodeSeparateColor", {"mode": "RGB"}, {}),
    "refl_rgba": ("CompositorNodeCombineColor", {"mode": "RGB"}, {}),
    "show_reflection": ("CompositorNodeSwitch", {"check": False}, {}),
    "show_debug": ("CompositorNodeSwitch", {"check": False}, {}),
}

GROUP_IN = "__input__"
GROUP_OUT = "__output__"

# (from node, output index, to node, input index); the group's input and output
# are GROUP_IN / GROUP_OUT with socket indices into GROUP_INPUTS / GROUP_OUTPUTS.
GROUP_LINKS: List[Tuple[str, int, str, int]] = [
    (GROUP_IN, 0, "map_uv", 0),
    ("uv_image", 0, "map_uv", 1),
    ("map_uv", 0, "blur", 0),
    ("map_uv", 0, "sep_color", 0),
    ("blur", 0, "sep_blur", 0),
    ("mask_image", 0, "sep_mask", 0),
    ("uv_image", 0, "sep_uv", 0),
    ("sep_mask", 0, "amount_rg", 0),
    ("sep_mask", 1, "amount_rg", 1),
    ("amount_rg", 0, "amount_rgb", 0),
    ("sep_mask", 2, "amount_rgb", 1),
    ("amount_rgb", 0, "amount", 0),
    ("sep_mask", 3, "rough", 1),
    # rgb: mix(C, B, r) * amount
    ("rough", 0, "mix_rough", 0),
    ("map_uv", 0, "mix_rough", 1),
    ("blur", 0, "mix_rough", 2),
    ("mix_rough", 0, "refl_rgb", 1),
    ("amount", 0, "refl_rgb", 2),
    # alpha: (C.a (1 - r) + B.a r) * amount, clamped to [0, 1]
    ("rough", 0, "one_minus_rough", 1),
    ("sep_color", 3, "c_alpha", 0),
    ("one_minus_rough", 0, "c_alpha", 1),
    ("sep_blur", 3, "b_alpha", 0),
    ("rough", 0, "b_alpha", 1),
    ("c_alpha", 0, "mixed_alpha", 0),
    ("b_alpha", 0, "mixed_alpha", 1),
    ("mixed_alpha", 0, "refl_alpha", 0),
    ("amount", 0, "refl_alpha", 1),
    # over: base * (1 - a) + refl.rgb
    ("refl_alpha", 0, "one_minus_alpha", 1),
    (GROUP_IN, 0, "base_scaled", 1),
    ("one_minus_alpha", 0, "base_scaled", 2),
    ("base_scaled", 0, "combined", 1),
    ("refl_rgb", 0, "combined", 2),
    # the reflection as premultiplied rgba, for the debug view and the EXR
    ("refl_rgb", 0, "sep_refl", 0),
    ("sep_refl", 0, "refl_rgba", 0),
    ("sep_refl", 1, "refl_rgba", 1),
    ("sep_refl", 2, "refl_rgba", 2),
    ("refl_alpha", 0, "refl_rgba", 3),
    # output switches: composited / reflection / G-buffer debug image
    ("combined", 0, "show_reflection", 0),
    ("refl_rgba", 0, "show_reflection", 1),
    ("show_reflection", 0, "show_debug", 0),
    ("debug_image", 0, "show_debug", 1),
    ("show_debug", 0, GROUP_OUT, 0),
    ("refl_rgba", 0, GROUP_OUT, 1),
    (GROUP_IN, 0, GROUP_OUT, 2),
    ("uv_image", 0, GROUP_OUT, 3),
    ("sep_uv", 2, GROUP_OUT, 4),
    ("position_image", 0, GROUP_OUT, 5),
    ("normal_image", 0, GROUP_OUT, 6),
    ("specular_image", 0, GROUP_OUT, 7),
]

# Layers of the multilayer EXR written beside the output: slot name -> group output.
EXR_LAYERS = (
    ("Image", "Image"),
    ("Base", "Base"),
    ("Reflection", "Reflection"),
    ("Position", "Position"),
    ("Normal", "Normal"),
    ("Specular", "Specular"),
    ("UV", "UV"),
    ("Visibility", "Visibility"),
)


def switch_states(debug_view: str) -> Dict[str, bool]:
    """The two Switch nodes' ``check`` for a debug view."""
    return {"show_reflection": debug_view == "REFLECTION", "show_debug": debug_view in GBUFFER_DEBUG_VIEWS}


# ----------------------------------------------------------------------------
# Images handed to the compositor


# These run on every pixel of every frame (2 M at 1920x1080): one pass per
# channel over strided views, no reductions along the last axis, no temporaries
# of the whole [h, w, 4] array that are not handed on.


def specular_amount(specular: np.ndarray) -> np.ndarray:
    """The core's specular amount: mean of rgb; non-finite counts as zero."""
    s = np.asarray(specular, dtype=np.float32)
    amount = s[..., 0] + s[..., 1]
    amount += s[..., 2]
    amount /= np.float32(3.0)
    amount[~np.isfinite(amount)] = 0.0
    return amount


def reflective_mask(position: np.ndarray, specular: np.ndarray) -> np.ndarray:
    """Pixels the core would trace: seen (w = 1, finite) with a positive specular amount."""
    p = np.asarray(position, dtype=np.float32)
    # A sum of the four channels is finite exactly when each is (NaN and inf
    # propagate), short of an overflow past 3e38, which no position reaches.
    total = p[..., 0] + p[..., 1]
    total += p[..., 2]
    total += p[..., 3]
    seen = p[..., 3] > 0.5
    seen &= np.isfinite(total)
    seen &= specular_amount(specular) > 0
    return seen


def trace_normals(normal: np.ndarray, position: np.ndarray, specular: np.ndarray,
                  refl: np.ndarray = None) -> np.ndarray:
    """Normals with non-reflective pixels zeroed: the core reports (0, 0, 0, 0)
    there without marching, as its pipeline does for pixels it does not trace."""
    if refl is None:
        refl = reflective_mask(position, specular)
    n = np.asarray(normal, dtype=np.float32)
    out = np.zeros(n.shape, np.float32)
    np.copyto(out, n, where=refl[..., None])
    return out


def _dilate3(mask: np.ndarray) -> np.ndarray:
    """Pixels with a True pixel in their 3x3 neighbourhood, separably."""
    rows = mask.copy()
    rows[1:] |= mask[:-1]
    rows[:-1] |= mask[1:]
    out = rows.copy()
    out[:, 1:] |= rows[:, :-1]
    out[:, :-1] |= rows[:, 1:]
    return out


def fill_missing_uv(uv: np.ndarray, passes: int = 2) -> np.ndarray:
    """Give pixels with no reflection (vis = 0) the mean (u, v) of their hit neighbours.

    Map UV estimates each pixel's uv derivatives from its neighbours and filters
    (EWA) over that footprint. A miss reports uv (0, 0): beside a hit it makes a
    huge derivative and the hit's colour is averaged over a large part of the
    frame. Misses stay misses (vis 0: Map UV returns zero there); only their uv
    is made continuous. ``passes`` rings of misses around each hit are filled,
    each ring from the pixels known before it (the hits, then the earlier rings).
    Only the ring's pixels are gathered: a frame's rings are a small share of it.
    """
    out = np.array(uv, dtype=np.float32, copy=True)
    known = out[..., 2] > 0
    h, w = known.shape
    for _ in range(passes):
        ys, xs = np.nonzero(_dilate3(known) & ~known)
        if ys.size == 0:
            break
        acc = np.zeros((ys.size, 2), np.float32)
        cnt = np.zeros(ys.size, np.float32)
        for dy in (-1, 0, 1):
            yy = ys + dy
            for dx in (-1, 0, 1):
                xx = xs + dx
                inside = (yy >= 0) & (yy < h) & (xx >= 0) & (xx < w)
                yc, xc = np.clip(yy, 0, h - 1), np.clip(xx, 0, w - 1)
                k = known[yc, xc] & inside
                acc += np.where(k[:, None], out[yc, xc, :2], np.float32(0.0))
                cnt += k
        out[ys, xs, :2] = acc / cnt[:, None]
        known[ys, xs] = True
    return out


def uv_image(uv: np.ndarray) -> np.ndarray:
    """The trace's (u, v, vis, vis) as Map UV's input (u, v, vis, 1), misses' uv filled."""
    out = fill_missing_uv(uv)
    out[..., 3] = 1.0
    return out


def debug_image(view: str, position, normal, specular, uv) -> np.ndarray:
    """The RGBA picture of a G-buffer layer for the debug view (alpha 1)."""
    h, w = np.asarray(position).shape[:2]
    out = np.zeros((h, w, 4), np.float32)
    seen = np.asarray(position)[..., 3] > 0.5
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


# ----------------------------------------------------------------------------
# The group on numpy arrays


def _blend(props, fac, c1, c2):
    """Blender's compositor Mix node; like Blender's, it keeps the first input's alpha."""
    fac = np.asarray(fac, dtype=np.float32)
    if fac.ndim == c1.ndim - 1:
        fac = fac[..., None]
    mode = props["blend_type"]
    out = np.array(c1, dtype=np.float32, copy=True)
    if mode == "MIX":
        out[..., :3] = (1.0 - fac) * c1[..., :3] + fac * c2[..., :3]
    elif mode == "MULTIPLY":
        out[..., :3] = c1[..., :3] * ((1.0 - fac) + fac * c2[..., :3])
    elif mode == "ADD":
        out[..., :3] = c1[..., :3] + fac * c2[..., :3]
    else:
        raise ValueError(f"blend_type {mode!r} is not modelled")
    return out.astype(np.float32)


def _as_colour(v, shape):
    """A socket value as RGBA: a float v becomes (v, v, v, 1), as Blender converts it."""
    v = np.asarray(v, dtype=np.float32)
    if v.shape == tuple(shape):
        return v
    out = np.ones(shape, np.float32)
    out[..., :3] = np.broadcast_to(v, tuple(shape[:-1]))[..., None]
    return out


def evaluate_group(base: np.ndarray, images: Dict[str, np.ndarray],
                   map_uv: Callable[[np.ndarray, np.ndarray], np.ndarray],
                   blur: Callable[[np.ndarray, int], np.ndarray], blur_size: int,
                   debug_view: str = "NONE") -> Dict[str, np.ndarray]:
    """Run :data:`GROUP_NODES` / :data:`GROUP_LINKS` on arrays.

    ``map_uv(image, uv_rgba)`` and ``blur(image, size)`` stand in for Blender's
    Map UV and Blur nodes (e.g. bilinear lookup and a clamp-to-edge box, the
    core's, to check the wiring; Blender's own filters differ slightly).
    Returns the group's outputs by name.
    """
    base = np.asarray(base, dtype=np.float32)
    shape = base.shape
    incoming: Dict[Tuple[str, int], Tuple[str, int]] = {}
    for src, so, dst, di in GROUP_LINKS:
        incoming[(dst, di)] = (src, so)
    cache: Dict[Tuple[str, int], np.ndarray] = {}
    switches = switch_states(debug_view)

    def inp(node, index):
        link = incoming.get((node, index))
        if link is None:
            return GROUP_NODES[node][2].get(index)
        return out(*link)

    def out(node, index):
        key = (node, index)
        if key in cache:
            return cache[key]
        if node == GROUP_IN:
            value = base
        else:
            kind, props, _ = GROUP_NODES[node]
            if kind == "CompositorNodeImage":
                value = np.asarray(images[props["image"]], dtype=np.float32)
                if index == 1:
                    value = value[..., 3]
            elif kind == "CompositorNodeMapUV":
                value = map_uv(inp(node, 0), inp(node, 1))
            elif kind == "CompositorNodeBlur":
                value = blur(inp(node, 0), blur_size)
            elif kind == "CompositorNodeSeparateColor":
                value = _as_colour(inp(node, 0), shape)[..., index]
            elif kind == "CompositorNodeCombineColor":
                value = np.stack([np.broadcast_to(np.asarray(inp(node, i), np.float32), shape[:-1])
                                  for i in range(4)], axis=-1)
            elif kind == "CompositorNodeMath":
                a = np.asarray(inp(node, 0), np.float32)
                b = np.asarray(inp(node, 1), np.float32)
                op = props["operation"]
                value = {"ADD": lambda: a + b, "SUBTRACT": lambda: a - b, "MULTIPLY": lambda: a * b,
                         "DIVIDE": lambda: a / b}[op]()
                if props["use_clamp"]:
                    value = np.clip(value, 0.0, 1.0)
                value = np.broadcast_to(value, shape[:-1]).astype(np.float32)
            elif kind == "CompositorNodeMixRGB":
                fac = np.asarray(inp(node, 0), np.float32)
                value = _blend(props, fac, _as_colour(inp(node, 1), shape), _as_colour(inp(node, 2), shape))
            elif kind == "CompositorNodeSwitch":
                value = inp(node, 1 if switches[node] else 0)
            else:
                raise ValueError(kind)
        cache[key] = value
        return value

    return {name: inp(GROUP_OUT, i) for i, (name, _) in enumerate(GROUP_OUTPUTS)}

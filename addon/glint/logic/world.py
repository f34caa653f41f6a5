"""Where the engine's specular S (what a found reflection replaces) comes from.

Eevee's world probe of a uniform world is that colour in every direction, so
its specular at a pixel is the colour times the pixel's split-sum weight W,
which Glint already computes (the weight image): S needs no render pass. Eevee's
Specular Light and Color passes double its render time (docs/addon.md), so they
are turned on only for a world that is not uniform (a texture, a sky, anything
linked), where W alone does not know what the probe sees.

The bpy side describes the world with plain values (:func:`describe` in
``compositor.py``); :func:`specular_source` decides.
"""
from __future__ import annotations

from typing import Optional, Sequence, Tuple

SOURCE_WORLD = "world colour"
SOURCE_PASSES = "Eevee passes"

# A world description:
#   None                                   no world: Eevee's world is black
#   {"use_nodes": False, "color": (r, g, b)}
#   {"use_nodes": True, "surface": None}   the output's Surface unlinked: black
#   {"use_nodes": True, "surface": {"kind": <bl_idname of the node feeding Surface>,
#                                   "color": (r, g, b[, a]) or None if linked,
#                                   "strength": float or None if linked}}


def _rgb(value, name: str) -> Tuple[float, float, float]:
    try:
        rgb = tuple(float(c) for c in value)[:3]
    except TypeError:
        raise ValueError(f"{name}: expected a colour (r, g, b), got {value!r}") from None
    if len(rgb) != 3:
        raise ValueError(f"{name}: expected a colour (r, g, b), got {value!r}")
    return rgb


def specular_source(world: Optional[dict], engine_ssr: bool = False
                    ) -> Tuple[str, Optional[Tuple[float, float, float]]]:
    """(SOURCE_WORLD, (r, g, b)) when the world is one colour, the radiance
    every direction sees; (SOURCE_PASSES, None) when S must come from the passes:
    a world that is not uniform, or Eevee's own SSR on (``engine_ssr``), whose
    reflections are in the frame in place of the world's and only the passes hold."""
    if engine_ssr:
        return SOURCE_PASSES, None
    if world is None:
        return SOURCE_WORLD, (0.0, 0.0, 0.0)
    if not isinstance(world, dict) or "use_nodes" not in world:
        raise ValueError(f"world: expected None or a dict with 'use_nodes', got {world!r}")
    if not world["use_nodes"]:
        return SOURCE_WORLD, _rgb(world.get("color"), "world['color']")
    surface = world.get("surface")
    if surface is None:
        return SOURCE_WORLD, (0.0, 0.0, 0.0)
    if surface.get("kind") != "ShaderNodeBackground":
        return SOURCE_PASSES, None
    colour, strength = surface.get("color"), surface.get("strength")
    if colour is None or strength is None:  # linked: a texture, a sky, a gradient
        return SOURCE_PASSES, None
    s = float(strength)
    r, g, b = _rgb(colour, "surface['color']")
    return SOURCE_WORLD, (r * s, g * s, b * s)



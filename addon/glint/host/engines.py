"""Render engines as the running Blender names them, and Eevee's own reflections.

Blender 3.4 calls Eevee ``BLENDER_EEVEE`` (Legacy, with screen-space
reflections behind ``scene.eevee.use_ssr``); 4.2 to 4.5 call its successor
``BLENDER_EEVEE_NEXT`` (ray tracing behind ``scene.eevee.use_raytracing``,
light probes and the world otherwise); 5.0 gave Eevee Next the old id back.
Which one this Blender has is read from the engine enum and the Eevee
settings, never from the version number.
"""
from __future__ import annotations

from typing import Tuple

import bpy

# Every id an Eevee has had; the first one this Blender offers is its Eevee.
EEVEE_IDS = ("BLENDER_EEVEE_NEXT", "BLENDER_EEVEE")
WORKBENCH = "BLENDER_WORKBENCH"
CYCLES = "CYCLES"


def engine_ids() -> Tuple[str, ...]:
    """The render engines this Blender offers (add-on engines included)."""
    prop = bpy.types.RenderSettings.bl_rna.properties["engine"]
    return tuple(item.identifier for item in prop.enum_items)


def eevee_id() -> str:
    """The id of this Blender's Eevee, for scripts that set a scene's engine."""
    have = engine_ids()
    return next((e for e in EEVEE_IDS if e in have), EEVEE_IDS[-1])


def is_eevee(engine: str) -> bool:
    return engine in EEVEE_IDS


def eevee_is_legacy(scene) -> bool:
    """Eevee Legacy (3.x-4.1) has screen-space reflections; Eevee Next has not."""
    return hasattr(scene.eevee, "use_ssr")


def eevee_traces_reflections(scene) -> bool:
    """Whether Eevee puts reflections of its own into the frame (Legacy SSR,
    Next's ray tracing): then they, not the world's probe, are the specular a
    Glint hit replaces, and only Eevee's passes hold it."""
    ee = scene.eevee
    if hasattr(ee, "use_ssr"):
        return bool(ee.use_ssr)
    return bool(getattr(ee, "use_raytracing", False))


def set_eevee_traces_reflections(scene, on: bool) -> None:
    """Switch Eevee's own reflections (SSR or ray tracing), for benchmarks and tests."""
    ee = scene.eevee
    if hasattr(ee, "use_ssr"):
        ee.use_ssr = on
    else:
        ee.use_raytracing = on


def eevee_reflections_name(scene) -> str:
    return "Screen Space Reflections" if eevee_is_legacy(scene) else "Ray Tracing"


def set_eevee_traces_reflections_for_comparison(scene, on: bool) -> None:
    """Eevee's own reflections as the benchmarks compare them: Legacy's SSR at
    full resolution (its half-resolution trace is visibly coarser); Next's ray
    tracing at its defaults, which is what its users get."""
    set_eevee_traces_reflections(scene, on)
    if hasattr(scene.eevee, "use_ssr_halfres"):
        scene.eevee.use_ssr_halfres = False


def set_eevee_ambient_occlusion(scene, distance: float) -> None:
    """Eevee's occlusion of the world light over ``distance`` (Legacy's GTAO;
    Next always occludes, by horizon scan, whose reach is this distance)."""
    ee = scene.eevee
    if hasattr(ee, "use_gtao"):
        ee.use_gtao = True
    if hasattr(ee, "gtao_distance"):
        ee.gtao_distance = distance
    elif hasattr(ee, "fast_gi_distance"):
        ee.fast_gi_distance = distance


def own_reflections_note(scene):
    """The panel's and log's sentence when Eevee traces reflections of its own
    under Glint, else None. Glint then takes Eevee's specular from its passes
    and replaces it, traced reflections included, wherever Glint finds a hit;
    where Glint finds none Eevee's own reflection stays."""
    if not is_eevee(scene.render.engine) or not eevee_traces_reflections(scene):
        return None
    return (f"Eevee's {eevee_reflections_name(scene)} is on: Glint replaces it where it finds a "
            "reflection and keeps it elsewhere; turning it off saves its render time")

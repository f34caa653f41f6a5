"""The pipeline's parameters: limits, quality presets, and the keyword set the core takes.

Defaults and limits are the core's (``schema.py``, generated from
``native/include/glint/schema.h``), so that the panel never offers a value the
core rejects; only the panel's soft range and tooltip are chosen here. The
presets (the core's) only touch the parameters that trade quality for time,
never the scene-scale ones (max distance, thickness).
"""
from __future__ import annotations

import glob
import sys
from typing import Callable, Dict, List, Mapping, Tuple, TypeVar

from . import schema

# The panel's own part of each parameter: (soft_min, soft_max, tooltip).
_PANEL = {
    "max_distance": (0.1, 100.0, "Longest reflected ray, in scene units (the seed's maxDistance)"),
    "resolution": (0.0, 1.0, "Share of the on-screen pixels the coarse pass visits (the seed's resolution)"),
    "steps": (0, 64, "Iteration budget; what it counts for each march is in the March tooltip"),
    "antialias": (0, 4, "Extra rays inside a pixel on a reflection's outline, so that its edges are as "
                        "smooth as the frame's (Hi-Z march); 0 traces one ray per pixel"),
    "thickness": (0.01, 10.0, "How deep surfaces are behind their front, in scene units (per march: March tooltip)"),
}
# name: (default, min, max, soft_min, soft_max, description)
PARAMETERS = {
    name: (schema.OPTIONS[name]["default"], schema.OPTIONS[name]["min"], schema.OPTIONS[name]["max"]) + panel
    for name, panel in _PANEL.items()
}

BACKENDS = (
    ("AUTO", "Auto", "The CPU where it is faster (no GPU, or a frame up to 960x540 and 100k "
                     "triangles), else OpenGL when a context can be made"),
    ("GL", "OpenGL", "Headless OpenGL (EGL); reports an error if it cannot run"),
    ("CPU", "CPU", "The CPU reference backend"),
)

# The marches and presets are the core's (glint_core.march_details(), presets()):
# the functions below turn those tables into Blender enum items and settings,
# and take them as arguments so that they are tested without the module.
CUSTOM = "CUSTOM"
DEFAULT_PRESET = schema.DEFAULT_PRESET.upper()  # its values are whatever the core says
# What a preset sets; max_distance and thickness describe the scene, not the quality.
QUALITY_KEYS = ("march", "resolution", "steps", "antialias")
MISSING = "glint_core is not loaded, so its marches and presets cannot be listed"


DEFAULT_MARCH = schema.OPTIONS["march"]["default"].upper()  # the core's trace default


def march_items(details: Mapping[str, Mapping], current: str = DEFAULT_MARCH) -> List[Tuple[str, str, str, int]]:
    """Enum items (identifier, label, tooltip, number) for the core's marches.
    Tooltips say what each option means for that march. Without the core, only
    the stored value is listed, so a file keeps its choice."""
    items = []
    for k, (name, d) in enumerate(details.items()):
        opts = "; ".join(f"{opt.replace('_', ' ')}: {meaning}" for opt, meaning in d["options"].items())
        extra = " Needs the scene's triangles." if d.get("needs_mesh") else ""
        extra += "" if d.get("gl", True) else " Runs on the CPU."
        items.append((name.upper(), name.title(), f"{d['description']}.{extra} {opts}", k))
    return items or [(current, current.title(), MISSING, 0)]


def preset_items(presets: Mapping[str, Mapping], descriptions: Mapping[str, str],
                 current: str = DEFAULT_PRESET) -> List[Tuple[str, str, str, int]]:
    """Enum items for the core's presets, then Custom (the raw parameters)."""
    items = []
    for k, (name, kw) in enumerate(presets.items()):
        values = ", ".join(f"{key} {kw.get(key, PARAMETERS.get(key, ('',))[0])}" for key in QUALITY_KEYS)
        items.append((name.upper(), name.title(), f"{descriptions.get(name, '')} ({values})", k))
    if not items and current != CUSTOM:
        items.append((current, current.title(), MISSING, 0))
    items.append((CUSTOM, "Custom", "The raw parameters below as set", len(items)))
    return items


def preset_values(presets: Mapping[str, Mapping], name: str) -> Dict[str, object]:
    """The quality parameters of preset ``name`` (enum spelling), march upper-case."""
    for key, kw in presets.items():
        if key.upper() == name:
            return {"march": str(kw["march"]).upper(), "resolution": float(kw["resolution"]),
                    "steps": int(kw["steps"]), "antialias": int(kw.get("antialias", PARAMETERS["antialias"][0]))}
    raise ValueError(f"preset: expected one of {[k.upper() for k in presets]}, got {name!r}")


def matching_preset(values: Mapping[str, object], presets: Mapping[str, Mapping]) -> str:
    """The preset the values equal (floats within 1e-6), or CUSTOM."""
    for key in presets:
        want = preset_values(presets, key.upper())
        if all(abs(float(values.get(k, -1)) - v) <= 1e-6 if isinstance(v, float) else values.get(k) == v
               for k, v in want.items()):
            return key.upper()
    return CUSTOM


def trace_kwargs(values: Mapping[str, object], presets: Mapping[str, Mapping] = None) -> Dict[str, object]:
    """Keyword arguments for ``glint_core.trace`` from the settings (enum names upper-case).
    A named preset takes its quality parameters from the core's table as it is now,
    so a scene saved with "Balanced" follows what the core measures as balanced."""
    merged = dict(values)
    preset = str(values.get("preset", CUSTOM))
    if presets and preset != CUSTOM and any(k.upper() == preset for k in presets):
        merged.update(preset_values(presets, preset))
    out = {}
    for key in ("max_distance", "resolution", "thickness"):
        out[key] = float(merged[key])
    out["steps"] = int(merged["steps"])
    out["antialias"] = int(merged.get("antialias", PARAMETERS["antialias"][0]))
    out["march"] = str(merged["march"]).lower()
    for key in ("max_distance", "resolution", "steps", "antialias", "thickness"):
        default, lo, hi = PARAMETERS[key][:3]
        v = out[key]
        if not (lo <= v <= hi):
            raise ValueError(f"{key}: expected a value in [{lo}, {hi}], got {v}")
    return out


def look_kwargs(values: Mapping[str, object]) -> Dict[str, str]:
    """What ``glint_core.composite_layers`` takes beyond the trace's quality: what a
    ray that passes behind an object shows. With ``fill_hidden`` (the default) it shows
    the object in front, as Eevee's SSR does, or the side it came into
    (:func:`shows_hidden_sides`), instead of the engine's reflection of the world
    (docs/addon.md, "Hidden reflections"). Not for measuring accuracy: an occluder is
    not the hit."""
    return {"blocked": "occluder" if values.get("fill_hidden", True) else "miss"}


def shows_hidden_sides(values: Mapping[str, object]) -> bool:
    """Whether a ray that comes into an object by its hidden side shows that side
    in its material's colour (the compositor's hidden images; docs/addon.md,
    *Hidden sides*): ``hidden_sides`` with ``fill_hidden`` (both on by default)."""
    return bool(values.get("fill_hidden", True)) and bool(values.get("hidden_sides", True))


def backend_name(enum_value: str) -> str:
    """Panel enum -> the core's backend name."""
    names = {"AUTO": "auto", "GL": "gl", "CPU": "cpu"}
    if enum_value not in names:
        raise ValueError(f"backend: expected AUTO, GL or CPU, got {enum_value!r}")
    return names[enum_value]


# Auto's rule (docs/addon.md, "Which backend Auto picks"). Measured with
# bench/frame_bench.py and bench/backend_sweep.py side by side, on 2 cores with Mesa's
# llvmpipe as the only GL: the CPU rasterized and traced faster at every size
# and triangle count tried (320x240 to 3840x2160, 144 to 400k triangles), and
# GL's first use in a process costs ~0.2 s more (its context). Without a GPU,
# GL is llvmpipe on the same cores, so Auto takes the CPU. With one, the CPU is
# kept up to 960x540 and 100k triangles, where its whole cost (~0.2 s measured)
# is about GL's fixed cost; beyond, GL, whose throughput a GPU multiplies.
AUTO_CPU_MAX_PIXELS = 960 * 540
AUTO_CPU_MAX_TRIANGLES = 100_000
GPU_DEVICE_PATTERNS = ("/dev/dri/renderD*", "/dev/nvidia[0-9]*")


def has_gpu_device(patterns=GPU_DEVICE_PATTERNS, platform: str = None) -> bool:
    """Whether a GPU could back an EGL context: on Linux a DRM render node or an
    NVIDIA device; elsewhere assumed (no cheap way to tell)."""
    platform = sys.platform if platform is None else platform
    if not platform.startswith("linux"):
        return True
    return any(glob.glob(p) for p in patterns)


def auto_backend(pixels: int, triangles: int, gpu: bool = None) -> str:
    """'cpu' or 'auto' (GL if a context can be made) for a frame of ``pixels``
    and ``triangles``; ``gpu``: :func:`has_gpu_device` (looked up when None)."""
    if pixels < 0 or triangles < 0:
        raise ValueError(f"pixels, triangles: expected counts >= 0, got {pixels}, {triangles}")
    if gpu is None:
        gpu = has_gpu_device()
    if not gpu:
        return "cpu"
    if pixels <= AUTO_CPU_MAX_PIXELS and triangles <= AUTO_CPU_MAX_TRIANGLES:
        return "cpu"
    return "auto"


T = TypeVar("T")


def with_cpu_fallback(call: Callable[[str], T], backend: str, requested: str,
                      log: Callable[[str], None]) -> Tuple[T, str]:
    """``(call(backend), backend)``. When the user asked for Auto and OpenGL fails
    (no context, a lost context, a GL error mid-frame: the core raises
    RuntimeError or its subclass BackendUnavailable for those), run ``call`` again
    on the CPU, with a line for the log. Bad input (ValueError), memory refusals
    (MemoryError) and anything the user pinned to a backend are raised as they are."""
    try:
        return call(backend), backend
    except RuntimeError as exc:
        if requested != "auto" or backend != "gl":
            raise
        log(f"OpenGL backend failed ({type(exc).__name__}: {exc}); using the CPU backend")
        return call("cpu"), "cpu"

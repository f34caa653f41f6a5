"""The pipeline's parameters: limits, quality presets, and the keyword set the core takes.

The limits mirror ``native/include/glint/options.h`` so that the panel never
offers a value the core rejects; the presets only touch the parameters that
trade quality for time, never the scene-scale ones (max distance, thickness).
"""
from __future__ import annotations

from typing import Dict, Mapping

# name: (default, min, max, soft_min, soft_max, description)
PARAMETERS = {
    "max_distance": (15.0, 1e-4, 1e6, 0.1, 100.0,
                     "Longest reflected ray, in scene units (the seed's maxDistance)"),
    "resolution": (0.3, 0.0, 1.0, 0.0, 1.0,
                   "Share of the on-screen pixels the coarse pass visits (the seed's resolution)"),
    "steps": (10, 0, 1000, 0, 64,
              "Bisection iterations of the second pass (the seed's steps)"),
    "thickness": (0.5, 1e-5, 1e6, 0.01, 10.0,
                  "How far behind a surface a ray still counts as a hit, in scene units"),
    "blur_size": (8, 0, 128, 0, 32,
                  "Half-width of the box blur for rough surfaces: a (2 size + 1)^2 box, 0 = none"),
}

MARCH_MODES = (
    ("SEED", "Seed (two-pass)", "The chapter's coarse pass plus bisection"),
    ("LINEAR", "Linear", "The book's older single march in view-space steps"),
)

BACKENDS = (
    ("AUTO", "Auto", "OpenGL when a context can be made, else the CPU"),
    ("GL", "OpenGL", "Headless OpenGL (EGL); reports an error if it cannot run"),
    ("CPU", "CPU", "The CPU reference backend"),
)

# Values are the preset's parameters; anything not listed is left as it is.
PRESETS: Dict[str, Dict[str, object]] = {
    "LOW": {"resolution": 0.15, "steps": 5, "blur_size": 4, "march": "SEED"},
    "MEDIUM": {"resolution": 0.3, "steps": 10, "blur_size": 8, "march": "SEED"},  # the seed's
    "HIGH": {"resolution": 0.6, "steps": 20, "blur_size": 8, "march": "SEED"},
}
PRESET_ITEMS = (
    ("LOW", "Low", "Coarse march, small blur: fastest"),
    ("MEDIUM", "Medium", "The seed chapter's defaults"),
    ("HIGH", "High", "Twice the coarse samples and bisection steps"),
    ("CUSTOM", "Custom", "The raw parameters below as set"),
)

PRESET_KEYS = ("resolution", "steps", "blur_size", "march")


def preset_values(name: str) -> Dict[str, object]:
    if name not in PRESETS:
        raise ValueError(f"preset: expected one of {sorted(PRESETS)}, got {name!r}")
    return dict(PRESETS[name])


def matching_preset(values: Mapping[str, object]) -> str:
    """The preset the values equal (floats within 1e-6), or 'CUSTOM'."""
    for name, preset in PRESETS.items():
        same = True
        for key, want in preset.items():
            got = values.get(key)
            if isinstance(want, float):
                same = got is not None and abs(float(got) - want) <= 1e-6
            else:
                same = got == want
            if not same:
                break
        if same:
            return name
    return "CUSTOM"


def trace_kwargs(values: Mapping[str, object]) -> Dict[str, object]:
    """Keyword arguments for ``glint_core.trace`` from the settings (enum names upper-case)."""
    out = {}
    for key in ("max_distance", "resolution", "thickness"):
        out[key] = float(values[key])
    out["steps"] = int(values["steps"])
    out["march"] = str(values["march"]).lower()
    for key in ("max_distance", "resolution", "steps", "thickness"):
        default, lo, hi = PARAMETERS[key][:3]
        v = out[key]
        if not (lo <= v <= hi):
            raise ValueError(f"{key}: expected a value in [{lo}, {hi}], got {v}")
    return out


def backend_name(enum_value: str) -> str:
    """Panel enum -> the core's backend name."""
    names = {"AUTO": "auto", "GL": "gl", "CPU": "cpu"}
    if enum_value not in names:
        raise ValueError(f"backend: expected AUTO, GL or CPU, got {enum_value!r}")
    return names[enum_value]

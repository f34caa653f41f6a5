"""Measure this scene: the frame's preset against march="exact", from the same
export and G-buffer the render uses. Called by GLINT_OT_measure (and so by a
script under ``blender -b``) and by bench/blend_gbuffer.py."""
from __future__ import annotations

import statistics
import time

import numpy as np

from . import compositor, gather
from .frame import rasterize, settings_dict
from .logic import geometry, measurement, settings as settings_logic


def frame_arrays(depsgraph, core, backend: str = "cpu") -> dict:
    """The trace's inputs for the evaluated frame: G-buffer (with the back layer),
    projection and the scene's triangles in view space."""
    exp = gather.export_scene(depsgraph)
    if not exp.any_reflective:
        raise gather.SkipFrame("no reflective material in view")
    gbuf = rasterize(core, exp, backend, back_layer=True)
    vertices, triangles = geometry.trace_mesh(exp.triangles)
    cam = exp.camera
    return {
        "position": gbuf["position"], "specular": gbuf["specular"], "back_position": gbuf["back_position"],
        "normal": gbuf["normal"],
        "projection": cam.projection, "vertices": vertices, "triangles": triangles,
    }


def _timed(call, repeat: int):
    out = call()  # warm-up: programs, threads, first-touch pages
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = call()
        times.append((time.perf_counter() - t0) * 1e3)
    return out, statistics.median(times)


def measure(core, arrays: dict, kwargs: dict, backend: str, preset: str, repeat: int = 3) -> dict:
    """Trace with ``kwargs`` and with the exact march; the figures of glint_core.compare.
    The time is the setting's as it is; the figures are scored ray by ray, each pixel's own
    ray against its exact one, so both traces are taken with one ray per pixel
    (``antialias`` 0): an antialiased outline pixel reports the share of its rays that hit,
    which no single exact ray scores."""
    details = core.march_details()[kwargs["march"]]
    kw = dict(kwargs)
    if details["uses_back_position"]:
        kw["back_position"] = arrays["back_position"]
    if details["needs_mesh"]:
        kw["mesh"] = (arrays["vertices"], arrays["triangles"])
    p, n, proj = arrays["position"], arrays["normal"], arrays["projection"].astype(np.float32)
    spec = arrays["specular"]
    uv, ms = _timed(lambda: core.trace(p, n, proj, specular=spec, backend=backend, **kw), repeat)
    if kw.get("antialias", 0):
        uv = core.trace(p, n, proj, specular=spec, backend=backend, **dict(kw, antialias=0))
    exact, exact_ms = _timed(lambda: core.trace(p, n, proj, march="exact", max_distance=kwargs["max_distance"],
                                                mesh=(arrays["vertices"], arrays["triangles"]), specular=spec,
                                                antialias=0),
                             repeat)
    figures = core.compare(uv, exact, specular=arrays["specular"])
    h, w = p.shape[:2]
    return dict(figures, ms=ms, exact_ms=exact_ms, preset=preset, width=w, height=h, backend=backend,
                triangles=int(arrays["triangles"].shape[0]), trace_kwargs=kwargs)


def measure_scene(depsgraph, scene, core, repeat: int = 3) -> dict:
    """The scene's own preset and backend, measured on its current frame; the
    disagreement image goes to the image named measurement.IMAGE_DISAGREEMENT."""
    values = settings_dict(scene.glint)
    backend = core.backend_name(settings_logic.backend_name(values["backend"]))
    kwargs = settings_logic.trace_kwargs(values, core.presets())
    arrays = frame_arrays(depsgraph, core, backend)
    result = measure(core, arrays, kwargs, backend, values["preset"].title(), repeat)
    compositor.fill_images({measurement.IMAGE_DISAGREEMENT: result["disagreement"]})
    return result

"""One frame of Glint: export -> rasterize -> trace -> images for the compositor.

Called from the render's ``frame_change_post`` handler with the render's own
evaluated depsgraph (never ``bpy.context``). Returns a :class:`state.FrameReport`;
raises nothing for expected failures (missing module, GL, core errors): those
become a report and the frame renders without reflections.
"""
from __future__ import annotations

import numpy as np

from . import compositor, gather, native
from .host import nodes as host_nodes
from .logic import compositing, geometry, reduced, settings as settings_logic
from .logic.progress import Cancelled, Progress, Timings
from .state import STATE, FrameReport, log


def settings_dict(glint) -> dict:
    """The scene's Glint settings as plain values."""
    return {
        "max_distance": glint.max_distance, "resolution": glint.resolution, "steps": glint.steps,
        "thickness": glint.thickness, "march": glint.march_name, "preset": glint.preset_name,
        "backend": glint.backend, "debug_view": glint.debug_view, "write_layers_exr": glint.write_layers_exr,
        "fill_hidden": glint.fill_hidden,
    }


def rasterize(core, exp: gather.SceneExport, backend: str, back_layer: bool = False, size=None):
    """The G-buffer of an export (with its normal maps, if any) on ``backend``; with
    ``back_layer``, also the surface behind each pixel (the march's true thickness).
    ``size`` (w, h): fewer pixels over the same view (the projection does not
    depend on the pixel count); default the camera's."""
    t = exp.triangles
    kwargs = {"back_layer": True} if back_layer else {}
    if t.uvs is not None and exp.normal_maps:
        kwargs.update(uvs=t.uvs, tangents=t.tangents, material_normal_map=exp.material_normal_map,
                      normal_maps=exp.normal_maps)
    cam = exp.camera
    return core.rasterize(t.positions, t.normals, t.material_index, exp.materials,
                          cam.projection.astype(np.float32), *(size or (cam.width, cam.height)),
                          backend=backend, **kwargs)


def mesh_kwargs(core, exp: gather.SceneExport, march: str) -> dict:
    """``{"mesh": ...}`` for a march that traces the scene's triangles, else ``{}``."""
    if core.march_details()[march]["needs_mesh"]:
        return {"mesh": geometry.trace_mesh(exp.triangles)}
    return {}


def resolve_backend(core, requested: str) -> str:
    """The backend a setting names ('auto' -> 'gl' or 'cpu'); 'auto' falls back to
    the CPU when no GL context can be made, 'gl' raises BackendUnavailable."""
    try:
        return core.backend_name(requested)
    except core.BackendUnavailable as exc:
        if requested != "auto":
            raise
        log(f"OpenGL backend unavailable ({exc}); using the CPU backend")
        return "cpu"


def run(depsgraph, scene, should_stop=None, progress_report=None) -> FrameReport:
    """Export, rasterize and trace the frame; fill the compositor's images."""
    glint = scene.glint
    values = settings_dict(glint)
    report = FrameReport(frame=depsgraph.scene_eval.frame_current)
    timings = Timings()
    core = native.load()
    if core is None:
        report.status, report.message = "error", native.error()
        return report
    if scene.render.engine in compositing.TRUE_REFLECTION_ENGINES:
        report.status, report.message = "skipped", compositing.TRUE_REFLECTION_NOTE
        return report
    progress = Progress(0, report=progress_report, should_stop=should_stop, label="Glint export")
    memory_refused = getattr(core, "MemoryLimitExceeded", ())
    tried = 1  # the last resolution factor the core refused for memory
    try:
        with timings.measure("export"):
            exp = gather.export_scene(depsgraph, progress, max_distance=values["max_distance"])
        cam = exp.camera
        report.width, report.height = cam.width, cam.height
        report.objects, report.culled = exp.objects, exp.culled
        report.message = exp.skipped_text()
        report.triangles = exp.triangles.count
        if not exp.any_reflective:
            report.status, report.message = "skipped", "no reflective material in view: no mesh exported, no trace"
            report.timings_ms = timings.ms
            return report
        requested = settings_logic.backend_name(values["backend"])
        with timings.measure("rasterize"):
            # Auto takes the CPU where it measured faster, without even making
            # a GL context (the first costs ~0.2 s per process): docs/addon.md.
            choice = settings_logic.auto_backend(cam.width * cam.height, report.triangles) \
                if requested == "auto" else requested
            backend = resolve_backend(core, choice)
            kwargs = settings_logic.trace_kwargs(values, core.presets())
            back_layer = core.march_details()[kwargs["march"]]["uses_back_position"]

        def attempt(size):
            """(position, normal, specular, layers) at ``size`` (None: the frame's),
            layers as ``core.composite_layers`` returns them; None when no pixel reflects."""
            kw = dict(kwargs, **settings_logic.look_kwargs(values))
            with timings.measure("rasterize"):
                gbuf, used = settings_logic.with_cpu_fallback(
                    lambda b: rasterize(core, exp, b, back_layer, size), backend, requested, log)
            progress.check()
            position, normal, specular = gbuf["position"], gbuf["normal"], gbuf["specular"]
            report.backend = used
            if back_layer:
                kw["back_position"] = gbuf["back_position"]
            kw.update(mesh_kwargs(core, exp, kw["march"]))
            if used == "gl" and not core.march_details()[kw["march"]]["gl"]:
                log(f"march '{kw['march']}' has no OpenGL form: it traces on the CPU")
            proj32 = cam.projection.astype(np.float32)
            with timings.measure("trace"):
                # One call for all the composite needs that does not depend on the
                # frame's colour (the uv image, each pixel's weight and blur level):
                # the G-buffer crosses into the core once. Pixels that do not
                # reflect are not traced; the normals of what they show stay, for
                # the rays that hit them.
                layers, used = settings_logic.with_cpu_fallback(
                    lambda b: core.composite_layers(position, normal, specular, proj32, backend=b, **kw),
                    used, requested, log)
            report.backend = used
            report.reflective_pixels = int(layers["reflective_pixels"])
            if report.reflective_pixels == 0:
                return None
            return position, normal, specular, layers

        # A refusal for memory (rasterize, trace, the exact march's mesh) retries
        # with fewer pixels down to a floor before the frame goes without: logic/reduced.py.
        factor = 1
        while True:
            try:
                traced = attempt(None if factor == 1 else reduced.reduced_size(cam.width, cam.height, factor))
                break
            except memory_refused as exc:
                tried = factor
                needed, limit = getattr(exc, "needed_bytes", 0), getattr(exc, "limit_bytes", 0)
                if factor == 1:
                    first_refusal = (needed, limit)
                factor = reduced.next_factor(factor, needed, limit)
                if factor is None:
                    raise
                log(f"frame {report.frame}: {reduced.retrying(cam.width, cam.height, tried, factor)}")
        if traced is None:
            report.status, report.message = "skipped", "no reflective pixel on screen: no trace"
            report.timings_ms = timings.ms
            return report
        position, normal, specular, layers = traced
        uv, weight = layers["uv"], layers["weight"]
        if not layers["any_rough"]:
            report.message = "; ".join(filter(None, [report.message, "no rough reflection: blur not needed"]))
        if STATE.second_bounce is False:
            report.message = "; ".join(filter(None, [report.message, "second bounce not run"]))
        if factor > 1:
            with timings.measure("upsample"):
                lod = weight[..., 3]
                lod[lod > 0] += np.float32(np.log2(factor))  # the footprint in frame pixels is `factor` times larger
                # The compositor reads the uv and the weight at the frame's size; the
                # G-buffer only for a debug view or the layers EXR (else it stays
                # reduced: fewer frame-size images when memory is short).
                refl = compositing.reflective_mask(position, specular)
                stretched = [uv, weight]
                if values["debug_view"] in compositing.GBUFFER_DEBUG_VIEWS or values["write_layers_exr"]:
                    stretched += [position, normal, specular]
                stretched = [reduced.upsample_nearest(a, cam.width, cam.height) for a in stretched]
                uv, weight = stretched[:2]
                if len(stretched) == 5:
                    position, normal, specular = stretched[2:]
                report.reflective_pixels = int(np.count_nonzero(reduced.upsample_nearest(refl, cam.width,
                                                                                        cam.height)))
            note = reduced.describe(cam.width, cam.height, factor, *first_refusal)
            report.message = "; ".join(m for m in (report.message, note) if m)
            log(f"frame {report.frame}: {note}")
        progress.check()
        with timings.measure("images"):
            view = values["debug_view"]
            # The group composites only the region that can change; a debug
            # view or the layers EXR shows the uv and vis of the whole frame,
            # and so does a compositor that cannot place a region (host/nodes).
            if view != "NONE" or values["write_layers_exr"] or not host_nodes.compositor_places_regions():
                region = (0, 0, cam.width, cam.height)
            else:
                region = compositing.image_region(uv[..., 2], weight[..., 3])
            images = compositing.region_images(uv, weight, region)
            report.region = region
            if view in compositing.GBUFFER_DEBUG_VIEWS:
                images[compositing.IMAGE_DEBUG] = compositing.debug_image(view, position, normal, specular, uv)
            if values["write_layers_exr"]:
                images[compositing.IMAGE_POSITION] = position
                n4 = np.array(normal, dtype=np.float32, copy=True)
                n4[..., 3] = 1.0
                images[compositing.IMAGE_NORMAL] = n4
                images[compositing.IMAGE_SPECULAR] = specular
            compositor.fill_images(images)
        with STATE.lock:
            STATE.arrays = {"position": position, "normal": normal, "specular": specular, "uv": uv,
                            "projection": cam.projection, "view": cam.view, "frame": report.frame}
        report.status = "ok"
    except Cancelled as exc:
        report.status, report.message = "cancelled", str(exc)
    except gather.SkipFrame as exc:
        report.status, report.message = "skipped", str(exc)
    except core.BackendUnavailable as exc:
        report.status, report.message = "error", f"backend unavailable: {exc}"
    except memory_refused as exc:
        # Refused from its sizes before anything was allocated, at full size and
        # down to the floor: the render goes on without reflections, and the
        # message says how much and how to raise the limit.
        report.status = "error"
        report.message = f"over Glint's memory limit ({reduced.gave_up(cam.width, cam.height, tried)}): {exc}"
    except (ValueError, RuntimeError, MemoryError) as exc:
        report.status, report.message = "error", f"{type(exc).__name__}: {exc}"
    report.timings_ms = timings.ms
    return report

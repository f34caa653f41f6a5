"""One frame of Glint: export -> rasterize -> trace -> images for the compositor.

Called from the render's ``frame_change_post`` handler with the render's own
evaluated depsgraph (never ``bpy.context``). Returns a :class:`state.FrameReport`;
raises nothing for expected failures (missing module, GL, core errors): those
become a report and the frame renders without reflections.

:func:`run` takes the frame through four steps, each reading and writing one
:class:`FrameState` (one per render, so nothing of a frame lives in module
globals): :func:`export` (the scene's triangles), :func:`plan` (backend and
trace options), :func:`compute` (G-buffer and composite layers, retried at
fewer pixels when the core refuses the memory) and :func:`publish` (the
compositor's images).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Optional, Tuple

import numpy as np

from . import compositor, exact_cache, gather, native
from .host import nodes as host_nodes
from .logic import compositing, geometry, group_images, projection, reduced, settings as settings_logic, texels
from .logic import world as world_logic
from .logic.progress import Cancelled, Progress, Timings
from .state import STATE, FrameReport, log


def settings_dict(glint) -> dict:
    """The scene's Glint settings as plain values."""
    return {
        "max_distance": glint.max_distance, "resolution": glint.resolution, "steps": glint.steps,
        "antialias": glint.antialias, "thickness": glint.thickness, "march": glint.march_name, "preset": glint.preset_name,
        "backend": glint.backend, "debug_view": glint.debug_view, "write_layers_exr": glint.write_layers_exr,
        "fill_hidden": glint.fill_hidden, "hidden_sides": glint.hidden_sides,
    }


def rasterize(core, exp: gather.SceneExport, backend: str, back_layer: bool = False, size=None,
              back_albedo: bool = False):
    """The G-buffer of an export (with its normal maps, if any) on ``backend``; with
    ``back_layer``, also the surface behind each pixel (the march's true thickness),
    and with ``back_albedo`` its material's albedo (what a hidden side shows).
    ``size`` (w, h): fewer pixels over the same view (the projection does not
    depend on the pixel count); default the camera's."""
    t = exp.triangles
    kwargs = {"back_layer": True} if back_layer else {}
    if back_layer and back_albedo and exp.material_albedo is not None:
        kwargs["material_albedo"] = exp.material_albedo
    if t.uvs is not None and exp.normal_maps:
        kwargs.update(uvs=t.uvs, tangents=t.tangents, material_normal_map=exp.material_normal_map,
                      normal_maps=exp.normal_maps)
    cam = exp.camera
    return core.rasterize(t.positions, t.normals, t.material_index, exp.materials,
                          cam.projection.astype(np.float32), *(size or (cam.width, cam.height)),
                          backend=backend, **kwargs)


def mesh_kwargs(core, exp: gather.SceneExport, march: str, note=None) -> dict:
    """``{"mesh": ...}`` for a march that traces the scene's triangles, else ``{}``.
    The BVH is kept between frames where the core can (``exact_cache``); ``note``
    receives what happened to it, for the frame's log line."""
    if not core.march_details()[march]["needs_mesh"]:
        exact_cache.release()
        return {}
    if not hasattr(core, "ExactScene"):  # a core from before the kept BVH
        return {"mesh": geometry.trace_mesh(exp.triangles)}
    mesh, update = exact_cache.seen_from_camera(core, exp.triangles, np.linalg.inv(exp.camera.view))
    if note is not None:
        note(f"exact march's BVH {update['bvh']} in {update['ms']:.0f} ms")
    return {"mesh": mesh}


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


@dataclass
class FrameState:
    """One frame on its way through the steps below: what each step leaves for
    the next. The render thread makes one per render (:func:`run`), so two
    renders never share a frame's state and nothing of it outlives the call."""

    core: object
    values: dict  # settings_dict() of the scene
    report: FrameReport
    timings: Timings
    progress: Progress
    exp: Optional[gather.SceneExport] = None
    requested: str = ""  # the backend the settings name ('auto', 'gl', 'cpu')
    backend: str = ""  # the one plan() chose for the first try
    kwargs: dict = field(default_factory=dict)  # the trace's, from the settings and the core's presets
    back_layer: bool = False
    factor: int = 1  # the frame traced at 1/factor of its width and height
    tried: int = 1  # the last resolution factor the core refused for memory
    first_refusal: Tuple[int, int] = (0, 0)  # (needed, limit) bytes of the full-size refusal
    # The G-buffer and the composite's layers, as compute() left them; publish()
    # stretches them back to the frame's size when the frame was reduced.
    position: Optional[np.ndarray] = None
    normal: Optional[np.ndarray] = None
    specular: Optional[np.ndarray] = None
    layers: Optional[dict] = None

    @property
    def camera(self) -> gather.CameraInfo:
        return self.exp.camera

    @property
    def memory_refused(self):
        """The core's refusal for memory (nothing to catch from a core without it)."""
        return getattr(self.core, "MemoryLimitExceeded", ())

    def note(self, message: str) -> None:
        """Add a clause to the report's message."""
        self.report.message = "; ".join(filter(None, [self.report.message, message]))

    def skip(self, message: str) -> bool:
        """Mark the frame skipped, ``message`` saying why; False, for the step to return."""
        self.report.status, self.report.message = "skipped", message
        return False


def run(depsgraph, scene, should_stop=None, progress_report=None) -> FrameReport:
    """Export, rasterize and trace the frame; fill the compositor's images."""
    values = settings_dict(scene.glint)
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
    frame = FrameState(core, values, report, timings, progress)
    memory_refused = frame.memory_refused
    try:
        # export and compute return False when the frame goes without
        # reflections for a reason the report gives (a skip, not an error).
        if export(frame, depsgraph):
            plan(frame)
            if compute(frame):
                publish(frame)
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
        cam = frame.camera
        report.status = "error"
        report.message = f"over Glint's memory limit ({reduced.gave_up(cam.width, cam.height, frame.tried)}): {exc}"
    except (ValueError, RuntimeError, MemoryError) as exc:
        report.status, report.message = "error", f"{type(exc).__name__}: {exc}"
    report.timings_ms = timings.ms
    return report


def export(frame: FrameState, depsgraph) -> bool:
    """The scene's view-space triangles and materials (gather.py). False when no
    reflective material is in view: then no mesh was fetched and nothing is traced."""
    report = frame.report
    with frame.timings.measure("export"):
        exp = gather.export_scene(depsgraph, frame.progress, max_distance=frame.values["max_distance"])
    frame.exp = exp
    report.width, report.height = exp.camera.width, exp.camera.height
    report.objects, report.culled = exp.objects, exp.culled
    report.message = exp.skipped_text()
    report.triangles = exp.triangles.count
    if not exp.any_reflective:
        return frame.skip("no reflective material in view: no mesh exported, no trace")
    return True


def plan(frame: FrameState) -> None:
    """The backend, the trace's options and whether the march wants the back-face
    layer. Timed as rasterize: choosing GL makes its context."""
    core, cam = frame.core, frame.camera
    frame.requested = requested = settings_logic.backend_name(frame.values["backend"])
    with frame.timings.measure("rasterize"):
        # Auto takes the CPU where it measured faster, without even making
        # a GL context (the first costs ~0.2 s per process): docs/addon.md.
        choice = settings_logic.auto_backend(cam.width * cam.height, frame.report.triangles) \
            if requested == "auto" else requested
        frame.backend = resolve_backend(core, choice)
        frame.kwargs = settings_logic.trace_kwargs(frame.values, core.presets())
        frame.back_layer = core.march_details()[frame.kwargs["march"]]["uses_back_position"]


def compute(frame: FrameState) -> bool:
    """Rasterize and trace the frame, at full size or, when the core refuses it
    for memory, at fewer pixels (logic/reduced.py). False when no pixel reflects."""
    cam, report = frame.camera, frame.report
    memory_refused = frame.memory_refused
    # A refusal for memory (rasterize, trace, the exact march's mesh) retries
    # with fewer pixels down to a floor before the frame goes without.
    while True:
        size = None if frame.factor == 1 else reduced.reduced_size(cam.width, cam.height, frame.factor)
        try:
            traced = _rasterize_and_trace(frame, size)
            break
        except memory_refused as exc:
            frame.tried = factor = frame.factor
            needed, limit = getattr(exc, "needed_bytes", 0), getattr(exc, "limit_bytes", 0)
            if factor == 1:
                frame.first_refusal = (needed, limit)
            frame.factor = reduced.next_factor(factor, needed, limit)
            if frame.factor is None:
                raise
            log(f"frame {report.frame}: {reduced.retrying(cam.width, cam.height, factor, frame.factor)}")
    if not traced:
        return frame.skip("no reflective pixel on screen: no trace")
    return True


def _rasterize_and_trace(frame: FrameState, size) -> bool:
    """The G-buffer at ``size`` (None: the frame's) and the composite's layers
    (``core.composite_layers``), into ``frame``; False when no pixel reflects."""
    core, exp, report = frame.core, frame.exp, frame.report
    kw = dict(frame.kwargs, **settings_logic.look_kwargs(frame.values))
    # The hidden sides' colours need the back layer's albedo (blocked="occluder" only).
    albedo = settings_logic.shows_hidden_sides(frame.values)
    with frame.timings.measure("rasterize"):
        gbuf, used = settings_logic.with_cpu_fallback(
            lambda b: rasterize(core, exp, b, frame.back_layer, size, albedo), frame.backend, frame.requested, log)
    frame.progress.check()
    position, normal, specular = gbuf["position"], gbuf["normal"], gbuf["specular"]
    if exp.camera.rendered is not None:
        # Outside a render region the engine renders nothing: no reflection
        # to add there, so no ray to trace (on 5.x the compositor would
        # composite one over the black).
        specular = projection.zero_outside(specular, exp.camera.rendered)
    report.backend = used
    if frame.back_layer:
        kw["back_position"] = gbuf["back_position"]
    if "back_albedo" in gbuf:
        kw["back_albedo"] = gbuf["back_albedo"]
    kw.update(mesh_kwargs(core, exp, kw["march"], frame.note))
    # Under a uniform world the engine's specular is W x the world colour at
    # every texel, so the core can take a hit's own specular along the ray
    # instead of as the camera sees it (docs/look-core.md, *The hit's own specular*).
    kw["world_specular"] = STATE.specular_source == world_logic.SOURCE_WORLD
    if used == "gl" and not core.march_details()[kw["march"]]["gl"]:
        log(f"march '{kw['march']}' has no OpenGL form: it traces on the CPU")
    proj32 = exp.camera.projection.astype(np.float32)
    with frame.timings.measure("trace"):
        # One call for all the composite needs that does not depend on the
        # frame's colour (the uv image, each pixel's weight and blur level):
        # the G-buffer crosses into the core once. Pixels that do not
        # reflect are not traced; the normals of what they show stay, for
        # the rays that hit them.
        layers, used = settings_logic.with_cpu_fallback(
            lambda b: core.composite_layers(position, normal, specular, proj32, backend=b, **kw),
            used, frame.requested, log)
    report.backend = used
    report.reflective_pixels = int(layers["reflective_pixels"])
    if report.reflective_pixels == 0:
        return False
    frame.position, frame.normal, frame.specular, frame.layers = position, normal, specular, layers
    return True


def publish(frame: FrameState) -> None:
    """Hand the frame's layers on: the compositor's images, and the arrays the
    debug operators and tests read (``STATE.arrays``)."""
    report, cam = frame.report, frame.camera
    uv, weight, hidden = frame.layers["uv"], frame.layers["weight"], frame.layers.get("hidden")
    if hidden is not None and frame.layers.get("hidden_pixels"):
        frame.note(f"{int(frame.layers['hidden_pixels'])} pixels show a hidden side")
    if not frame.layers["any_rough"]:
        frame.note("no rough reflection: blur not needed")
    if STATE.second_bounce is False:
        frame.note("second bounce not run")
    position, normal, specular = frame.position, frame.normal, frame.specular
    if frame.factor > 1:
        with frame.timings.measure("upsample"):
            uv, weight, hidden, position, normal, specular = _upsample(frame, uv, weight, hidden)
        note = reduced.describe(cam.width, cam.height, frame.factor, *frame.first_refusal)
        frame.note(note)
        log(f"frame {report.frame}: {note}")
    frame.progress.check()
    with frame.timings.measure("images"):
        _fill_images(frame, uv, weight, hidden, position, normal, specular)
    with STATE.lock:
        STATE.arrays = {"position": position, "normal": normal, "specular": specular, "uv": uv,
                        "weight": weight, "hidden": hidden, "projection": cam.projection, "view": cam.view,
                        "frame": report.frame}
    report.status = "ok"


def _upsample(frame: FrameState, uv, weight, hidden):
    """A reduced frame's layers at the frame's size: (uv, weight, hidden,
    position, normal, specular), hidden None when there is none. The compositor
    reads the uv, the weight and the hidden sides at the frame's size; the
    G-buffer only for a debug view or the layers EXR (else it stays reduced:
    fewer frame-size images when memory is short)."""
    cam, values = frame.camera, frame.values
    position, normal, specular = frame.position, frame.normal, frame.specular
    lod = weight[..., 3]
    lod[lod > 0] += np.float32(np.log2(frame.factor))  # the footprint in frame pixels is `factor` times larger
    refl = texels.reflective_mask(position, specular)
    stretched = [uv, weight]
    if values["debug_view"] in compositing.GBUFFER_DEBUG_VIEWS or values["write_layers_exr"]:
        stretched += [position, normal, specular]
    if hidden is not None:
        stretched.append(hidden)
    stretched = [reduced.upsample_nearest(a, cam.width, cam.height) for a in stretched]
    uv, weight = stretched[:2]
    if hidden is not None:
        hidden = stretched.pop()
    if len(stretched) == 5:
        position, normal, specular = stretched[2:]
    frame.report.reflective_pixels = int(np.count_nonzero(reduced.upsample_nearest(refl, cam.width, cam.height)))
    return uv, weight, hidden, position, normal, specular


def _fill_images(frame: FrameState, uv, weight, hidden, position, normal, specular) -> None:
    """The compositor's images: the uv, weight and hidden sides of the region
    that can change, and the debug view's or the layers EXR's G-buffer images."""
    cam, view = frame.camera, frame.values["debug_view"]
    # The group composites only the region that can change; a debug
    # view or the layers EXR shows the uv and vis of the whole frame,
    # and so does a compositor that cannot place a region (host/nodes).
    placeable = host_nodes.compositor_places_regions()
    if view != "NONE" or frame.values["write_layers_exr"] or not placeable:
        region = (0, 0, cam.width, cam.height)
    else:
        # A hit's replaced share can fall to 0 or below (the hit's own specular
        # taken along the ray): its vis still marks it.
        region = group_images.image_region(np.maximum(uv[..., 2], uv[..., 3]), weight[..., 3])
    keys = {compositing.IMAGE_FINE: (region, cam.width, cam.height)}
    offset = (0.0, 0.0)
    hidden_imgs = {}
    if settings_logic.shows_hidden_sides(frame.values):
        # The group reads them (its switch is on): on the box of this frame's
        # hidden sides, a pixel or two when there are none.
        if not frame.layers.get("hidden_pixels"):
            hidden = None
        hidden_imgs, offset = group_images.hidden_images(hidden, region, cam.width, cam.height, placeable)
        if hidden is None:
            # all zeros, and the same while the region keeps its size: written once
            # (on a compositor that cannot place them they are frame-sized)
            keys.update((name, ("none", region, placeable)) for name in hidden_imgs)
    # where the host's Scale brings the coarse canvas back, the fine image is
    # not read (compositing.switch_states)
    # The core's bin means where it has them (a core from before: None, the rule in numpy).
    bin_means = getattr(frame.core, "positive_bin_means", None)
    images = group_images.region_images(uv, weight, region, offset,
                                        fine=not host_nodes.coarse_read_back_by_scale(), bin_means=bin_means)
    images.update(hidden_imgs)
    frame.report.region = region
    if view in compositing.GBUFFER_DEBUG_VIEWS:
        images[compositing.IMAGE_DEBUG] = group_images.debug_image(view, position, normal, specular, uv)
    if frame.values["write_layers_exr"]:
        images[compositing.IMAGE_POSITION] = position
        n4 = np.array(normal, dtype=np.float32, copy=True)
        n4[..., 3] = 1.0
        images[compositing.IMAGE_NORMAL] = n4
        images[compositing.IMAGE_SPECULAR] = specular
    compositor.fill_images(images, keys=keys)

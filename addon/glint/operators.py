"""Operators: compute the layers for the current frame (with progress and Esc
to cancel), cancel a running export, retry loading the native module, and
rebuild the compositor set-up."""
from __future__ import annotations

import threading

import bpy
import numpy as np

from . import compositor, gather, measure, native
from .frame import mesh_kwargs, rasterize, settings_dict
from .logic import compositing, group_images, measurement, settings as settings_logic
from .logic.progress import Cancelled, Progress, Timings
from .state import STATE, log


class GLINT_OT_retry_native(bpy.types.Operator):
    """Look for Glint's native module again"""

    bl_idname = "glint.retry_native"
    bl_label = "Retry Loading the Native Module"

    def execute(self, context):
        native.reset()
        core = native.load(retry=True)
        if core is None:
            self.report({"ERROR"}, f"Glint: {native.error()}")
            return {"CANCELLED"}
        self.report({"INFO"}, f"Glint: native module loaded from {native.origin()}")
        return {"FINISHED"}


class GLINT_OT_cancel(bpy.types.Operator):
    """Stop Glint's work for the render under way (its frames render without reflections)"""

    bl_idname = "glint.cancel"
    bl_label = "Cancel Glint"

    def execute(self, context):
        STATE.cancel.set()
        self.report({"INFO"}, "Glint: cancelling")
        return {"FINISHED"}


class GLINT_OT_report(bpy.types.Operator):
    """Show a Glint message in the status bar and the Info log (used after renders)"""

    bl_idname = "glint.report"
    bl_label = "Glint Report"
    bl_options = {"INTERNAL"}

    message: bpy.props.StringProperty(options={"SKIP_SAVE"})
    level: bpy.props.EnumProperty(items=(("ERROR", "Error", ""), ("WARNING", "Warning", ""), ("INFO", "Info", "")),
                                  default="ERROR", options={"SKIP_SAVE"})

    _timer = None

    def invoke(self, context, event):
        # Reports of an operator called from Python stay with the caller; a modal
        # operator's go to the window manager: the status bar and the Info log.
        wm = context.window_manager
        self._timer = wm.event_timer_add(0.01, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def modal(self, context, event):
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        context.window_manager.event_timer_remove(self._timer)
        self.report({self.level}, self.message)
        return {"FINISHED"}

    def execute(self, context):
        self.report({self.level}, self.message)
        return {"FINISHED"}


class GLINT_OT_setup_compositor(bpy.types.Operator):
    """Put Glint's node group back into this scene's compositor"""

    bl_idname = "glint.setup_compositor"
    bl_label = "Set Up Compositor"

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.glint.enabled

    def execute(self, context):
        warning = compositor.ensure(context.scene)
        if warning:
            self.report({"WARNING"}, f"Glint: {warning}")
        return {"FINISHED"}


class GLINT_OT_compute_layers(bpy.types.Operator):
    """Compute Glint's layers (position, normal, specular, reflected uv, visibility)
    for the current frame and the viewport's evaluated scene, and show the debug
    view's layer in an Image Editor. Esc cancels"""

    bl_idname = "glint.compute_layers"
    bl_label = "Compute Layers"

    _timer = None
    _thread = None
    _result = None
    _cancel = None

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.camera is not None

    def invoke(self, context, event):
        core = native.load()
        if core is None:
            self.report({"ERROR"}, f"Glint: {native.error()}")
            return {"CANCELLED"}
        scene = context.scene
        depsgraph = context.evaluated_depsgraph_get()  # not a final render: the viewport's scene
        wm = context.window_manager
        self._cancel = threading.Event()
        wm.progress_begin(0, 100)

        def report(fraction, message):
            wm.progress_update(int(fraction * 50))

        timings = Timings()
        try:
            with timings.measure("export"):
                exp = gather.export_scene(depsgraph, Progress(0, report=report, should_stop=self._cancel.is_set,
                                                              interval=0.1))
        except (gather.SkipFrame, Cancelled, ValueError) as exc:
            wm.progress_end()
            self.report({"WARNING"}, f"Glint: {exc}")
            return {"CANCELLED"}
        values = settings_dict(scene.glint)
        backend = settings_logic.backend_name(values["backend"])
        kwargs = settings_logic.trace_kwargs(values, core.presets())
        kwargs.update(mesh_kwargs(core, exp, kwargs["march"]))
        self._result = {"timings": timings}

        def work():
            # Native stages only: they release the GIL, Blender's UI stays live.
            try:
                with timings.measure("rasterize"):
                    g = rasterize(core, exp, backend)
                if self._cancel.is_set():
                    return
                proj = exp.camera.projection
                with timings.measure("trace"):
                    uv = core.trace(g["position"], g["normal"], proj.astype(np.float32), specular=g["specular"],
                                    backend=backend, **kwargs)
                self._result.update(g, uv=uv, projection=proj)
            except Exception as exc:  # reported by the modal loop
                self._result["error"] = f"{type(exc).__name__}: {exc}"

        self._thread = threading.Thread(target=work, name="glint-layers", daemon=True)
        self._thread.start()
        self._timer = wm.event_timer_add(0.05, window=context.window)
        wm.modal_handler_add(self)
        return {"RUNNING_MODAL"}

    def _finish(self, context):
        wm = context.window_manager
        if self._timer is not None:
            wm.event_timer_remove(self._timer)
            self._timer = None
        wm.progress_end()

    def modal(self, context, event):
        if event.type == "ESC":
            self._cancel.set()
            self._finish(context)
            self.report({"INFO"}, "Glint: cancelled")
            return {"CANCELLED"}
        if event.type != "TIMER":
            return {"PASS_THROUGH"}
        if self._thread.is_alive():
            context.window_manager.progress_update(75)
            return {"PASS_THROUGH"}
        self._finish(context)
        r = self._result
        if "error" in r:
            self.report({"ERROR"}, f"Glint: {r['error']}")
            return {"CANCELLED"}
        if "uv" not in r:
            return {"CANCELLED"}
        view = context.scene.glint.debug_view
        if view not in compositing.GBUFFER_DEBUG_VIEWS:
            view = "VISIBILITY"
        img = group_images.debug_image(view, r["position"], r["normal"], r["specular"], r["uv"])
        compositor.fill_images({compositing.IMAGE_DEBUG: img})
        with STATE.lock:
            STATE.arrays = {k: r[k] for k in ("position", "normal", "specular", "uv", "projection")}
        for area in context.screen.areas:
            if area.type == "IMAGE_EDITOR":
                area.spaces.active.image = bpy.data.images[compositing.IMAGE_DEBUG]
                break
        self.report({"INFO"}, f"Glint: layers computed ({r['timings'].summary()}); "
                              f"'{compositing.IMAGE_DEBUG}' shows {view.lower()}")
        return {"FINISHED"}


class GLINT_OT_measure(bpy.types.Operator):
    """Measure this scene: trace the current frame with Glint's preset and with the
    exact march, and report precision, recall, pixel error and time (the image
    'Glint Disagreement' shows where they differ: red false, green right, blue
    missed, yellow misplaced)"""

    bl_idname = "glint.measure"
    bl_label = "Measure This Scene"

    repeat: bpy.props.IntProperty(name="Repeat", default=3, min=1, max=50,
                                  description="Timed runs of each trace (the median is reported)")
    save_path: bpy.props.StringProperty(name="Save Image", default="", subtype="FILE_PATH",
                                        description="Also write the disagreement image here (PNG)")

    @classmethod
    def poll(cls, context):
        return context.scene is not None and context.scene.camera is not None

    def execute(self, context):
        core = native.load()
        if core is None:
            self.report({"ERROR"}, f"Glint: {native.error()}")
            return {"CANCELLED"}
        try:
            result = measure.measure_scene(context.evaluated_depsgraph_get(), context.scene, core, self.repeat)
        except gather.SkipFrame as exc:
            self.report({"WARNING"}, f"Glint: nothing to measure ({exc})")
            return {"CANCELLED"}
        except (ValueError, RuntimeError, MemoryError) as exc:
            self.report({"ERROR"}, f"Glint: {type(exc).__name__}: {exc}")
            return {"CANCELLED"}
        with STATE.lock:
            STATE.measurement = {k: v for k, v in result.items() if k != "disagreement"}
        line = measurement.summary(result)
        log(f"measured {line}")
        if self.save_path:
            img = bpy.data.images[measurement.IMAGE_DISAGREEMENT]
            img.filepath_raw = bpy.path.abspath(self.save_path)
            img.file_format = "PNG"
            img.save()
        self.report({"INFO"}, f"Glint: {line}")
        return {"FINISHED"}


CLASSES = (GLINT_OT_retry_native, GLINT_OT_cancel, GLINT_OT_report, GLINT_OT_setup_compositor,
           GLINT_OT_compute_layers, GLINT_OT_measure)

register, unregister = bpy.utils.register_classes_factory(CLASSES)

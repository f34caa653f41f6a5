"""Render Properties > Glint: the switch, quality, backend, debug views, status."""
from __future__ import annotations

import time

import bpy

from . import compositor, native
from .host import engines
from .logic import measurement
from .state import STATE


class GLINT_PT_render(bpy.types.Panel):
    bl_label = "Glint"
    bl_idname = "GLINT_PT_render"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}

    def draw_header(self, context):
        self.layout.prop(context.scene.glint, "enabled", text="")

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        glint = context.scene.glint
        layout.active = glint.enabled
        core = native.load()
        if core is None:
            box = layout.box()
            box.alert = True
            box.label(text="Native module missing: no reflections", icon="ERROR")
            box.operator("glint.retry_native", icon="FILE_REFRESH")
        else:
            # Which of the search order's places won, and what it is (docs/addon.md).
            col = layout.column(align=True)
            col.label(text=f"Core {native.version()} from {native.source()}", icon="LINKED")
            col.label(text=native.origin() or "?")
        if STATE.writes_stuck:
            box = layout.box()
            box.alert = True
            box.label(text="Blender refuses add-ons' writes since a render", icon="ERROR")
            box.label(text="(a Blender 3.x/4.x fault): restart Blender to clear it")
        layout.prop(glint, "preset")
        if glint.enabled:
            notice = compositor.turned_on_notice(context.scene)
            if notice:
                layout.label(text=f"{notice} for its reflections", icon="INFO")
            if STATE.specular_source:
                layout.label(text=f"Replaced specular from the {STATE.specular_source}", icon="WORLD")
            own = engines.own_reflections_note(context.scene)
            if own:
                layout.label(text=own, icon="INFO")
            if not context.scene.render.use_compositing:
                layout.label(text="Compositing is off: Glint turns it on when rendering", icon="INFO")
        last = STATE.last
        if last is not None:
            icon = {"ok": "CHECKMARK", "skipped": "INFO"}.get(last.status, "ERROR")
            text = f"Frame {last.frame}: {last.status}"
            if last.backend:
                text += f" ({last.backend})"
            layout.label(text=text, icon=icon)
            if last.message:
                layout.label(text=last.message)
            if last.timings_ms:
                layout.label(text=", ".join(f"{k} {v:.0f} ms" for k, v in last.timings_ms.items()))
        if STATE.busy and STATE.progress:
            layout.label(text=STATE.progress, icon="TIME")
        if STATE.busy or STATE.rendering:
            layout.operator("glint.cancel", icon="CANCEL")
        STATE.panel_drawn_at = time.monotonic()
        if STATE.rendering:
            STATE.panel_drawn.set()


class _GlintSubPanel:
    """Where every Glint sub-panel sits: under the Glint panel, closed at first."""
    bl_parent_id = "GLINT_PT_render"
    bl_space_type = "PROPERTIES"
    bl_region_type = "WINDOW"
    bl_context = "render"
    bl_options = {"DEFAULT_CLOSED"}


class GLINT_PT_parameters(_GlintSubPanel, bpy.types.Panel):
    bl_label = "Parameters"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        glint = context.scene.glint
        layout.active = glint.enabled
        col = layout.column(align=True)
        col.prop(glint, "max_distance")
        col.prop(glint, "thickness")
        col = layout.column(align=True)
        col.prop(glint, "resolution")
        col.prop(glint, "steps")
        col.prop(glint, "antialias")
        layout.prop(glint, "march")
        layout.prop(glint, "fill_hidden")
        row = layout.row()
        row.active = glint.fill_hidden
        row.prop(glint, "hidden_sides")
        layout.prop(glint, "second_bounce")


class GLINT_PT_backend(_GlintSubPanel, bpy.types.Panel):
    bl_label = "Backend"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        glint = context.scene.glint
        layout.prop(glint, "backend")
        used = STATE.last.backend if STATE.last is not None and STATE.last.backend else "not rendered yet"
        layout.label(text=f"Last used: {used}")
        layout.prop_search(glint, "view_layer", context.scene, "view_layers")


class GLINT_PT_debug(_GlintSubPanel, bpy.types.Panel):
    bl_label = "Debug"

    def draw(self, context):
        layout = self.layout
        layout.use_property_split = True
        glint = context.scene.glint
        layout.prop(glint, "debug_view")
        layout.prop(glint, "write_layers_exr")
        row = layout.row()
        row.operator("glint.compute_layers", icon="RENDERLAYERS")
        row.operator("glint.setup_compositor", icon="NODETREE")


class GLINT_PT_accuracy(_GlintSubPanel, bpy.types.Panel):
    bl_label = "Accuracy"

    def draw(self, context):
        layout = self.layout
        layout.operator("glint.measure", icon="DRIVER_DISTANCE")
        if STATE.measurement:
            box = layout.box()
            for line in measurement.panel_lines(STATE.measurement):
                box.label(text=line)
            box.label(text=f"Image: {measurement.IMAGE_DISAGREEMENT}", icon="IMAGE_DATA")


CLASSES = (GLINT_PT_render, GLINT_PT_parameters, GLINT_PT_backend, GLINT_PT_debug, GLINT_PT_accuracy)

register, unregister = bpy.utils.register_classes_factory(CLASSES)

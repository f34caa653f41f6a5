"""Add-on preferences: where the native module came from, or why it is missing."""
from __future__ import annotations

import textwrap

import bpy

from . import native


class GLINT_AddonPreferences(bpy.types.AddonPreferences):
    bl_idname = __package__

    def draw(self, context):
        layout = self.layout
        core = native.load()
        if core is None:
            box = layout.box()
            box.alert = True
            box.label(text="Glint's native module is missing: renders get no reflections.", icon="ERROR")
            # Paths stay whole: a line may run long rather than split one.
            for line in textwrap.wrap(native.error() or "", 90, break_long_words=False, break_on_hyphens=False):
                box.label(text=line)
        else:
            layout.label(text=f"Native module {getattr(core, '__version__', '?')} loaded from:", icon="CHECKMARK")
            layout.label(text=native.origin() or "?")
            try:
                gl = "compiled in" if core.gl_compiled_in() else "not compiled in"
            except AttributeError:
                gl = "unknown"
            layout.label(text=f"OpenGL backend: {gl}")
        layout.operator("glint.retry_native", icon="FILE_REFRESH")


CLASSES = (GLINT_AddonPreferences,)

register, unregister = bpy.utils.register_classes_factory(CLASSES)

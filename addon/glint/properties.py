"""Every setting lives in the .blend: ``scene.glint`` (a PropertyGroup).

A render farm runs ``blender -b scene.blend -f N`` with nothing else, so all a
frame needs is here; nothing is read from preferences at render time.
"""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from .logic import compositing as cg
from .logic import settings as sl

_guard = {"busy": False}


def _on_enabled(self, context):
    from . import compositor
    scene = self.id_data
    if self.enabled:
        warning = compositor.ensure(scene)
        if warning:
            from .state import log
            log(warning)
    else:
        compositor.remove(scene)


def _on_preset(self, context):
    if self.preset == "CUSTOM" or _guard["busy"]:
        return
    _guard["busy"] = True
    try:
        for key, value in sl.preset_values(self.preset).items():
            setattr(self, key, value)
    finally:
        _guard["busy"] = False
    _on_compositor_setting(self, context)


def _on_raw(self, context):
    if _guard["busy"]:
        return
    values = {k: getattr(self, k) for k in sl.PRESET_KEYS}
    match = sl.matching_preset(values)
    if match != self.preset:
        _guard["busy"] = True
        try:
            self.preset = match
        finally:
            _guard["busy"] = False
    _on_compositor_setting(self, context)


def _on_compositor_setting(self, context):
    if not self.enabled:
        return
    from . import compositor
    compositor.ensure(self.id_data)


def _param(name, kind, update=_on_raw):
    default, lo, hi, soft_lo, soft_hi, desc = sl.PARAMETERS[name]
    if kind is int:
        return IntProperty(name=name.replace("_", " ").title(), description=desc, default=default,
                           min=lo, max=hi, soft_min=soft_lo, soft_max=soft_hi, update=update)
    return FloatProperty(name=name.replace("_", " ").title(), description=desc, default=default,
                         min=lo, max=hi, soft_min=soft_lo, soft_max=soft_hi, update=update,
                         precision=3, unit="LENGTH" if name in ("max_distance", "thickness") else "NONE")


class GLINT_SceneSettings(bpy.types.PropertyGroup):
    enabled: BoolProperty(
        name="Glint", default=False, update=_on_enabled,
        description="Composite screen-space reflections into every rendered frame")
    preset: EnumProperty(name="Quality", items=sl.PRESET_ITEMS, default="MEDIUM", update=_on_preset,
                         description="Quality preset: sets resolution, steps, blur size and march")
    max_distance: _param("max_distance", float, update=_on_compositor_setting)
    resolution: _param("resolution", float)
    steps: _param("steps", int)
    thickness: _param("thickness", float, update=_on_compositor_setting)
    blur_size: _param("blur_size", int)
    march: EnumProperty(name="March", items=sl.MARCH_MODES, default="SEED", update=_on_raw,
                        description="How rays are marched in screen space")
    backend: EnumProperty(name="Backend", items=sl.BACKENDS, default="AUTO",
                          description="Where the G-buffer and the trace run")
    debug_view: EnumProperty(name="Debug View", items=cg.DEBUG_VIEWS, default="NONE",
                             update=_on_compositor_setting,
                             description="Render an intermediate layer instead of the composited frame")
    write_layers_exr: BoolProperty(
        name="Write Layers EXR", default=False, update=_on_compositor_setting,
        description="Also write every layer (base, reflection, position, normal, specular, uv, "
                    "visibility) to a multilayer EXR beside the output, <output>glint_<frame>.exr")
    view_layer: StringProperty(name="View Layer", default="", update=_on_compositor_setting,
                               description="View layer to reflect (empty: the first one rendered)")
    owns_use_nodes: BoolProperty(default=False, options={"HIDDEN"},
                                 description="Glint switched the compositor on and will switch it off")


CLASSES = (GLINT_SceneSettings,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.glint = bpy.props.PointerProperty(type=GLINT_SceneSettings)


def unregister():
    del bpy.types.Scene.glint
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

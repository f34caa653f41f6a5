"""Every setting lives in the .blend: ``scene.glint`` (a PropertyGroup).

A render farm runs ``blender -b scene.blend -f N`` with nothing else, so all a
frame needs is here; nothing is read from preferences at render time.
"""
from __future__ import annotations

import bpy
from bpy.props import BoolProperty, EnumProperty, FloatProperty, IntProperty, StringProperty

from . import native
from .logic import compositing as cg
from .logic import settings as sl

_guard = {"busy": False}


def _on_enabled(self, context):
    from . import compositor
    scene = self.id_data
    if self.enabled:
        turned_on = compositor.ensure(scene)
        if turned_on:
            from .state import log
            log(f"scene {scene.name!r}: {turned_on}")
    else:
        compositor.remove(scene)


def _core_tables():
    """(march details, presets, preset descriptions) from the core, or empty
    tables when it cannot be loaded (the panel then says why)."""
    core = native.load()
    if core is None:
        return {}, {}, {}
    return core.march_details(), core.presets(), core.preset_descriptions()


# Blender keeps only pointers into the strings of dynamic enum items: the
# lists must outlive the call that returned them.
_items = {"march": [], "preset": []}


def _march_items(self, context):
    _items["march"] = sl.march_items(_core_tables()[0], current=self.march_name)
    return _items["march"]


def _preset_items(self, context):
    _, presets, descriptions = _core_tables()
    _items["preset"] = sl.preset_items(presets, descriptions, current=self.preset_name)
    return _items["preset"]


def _number_of(items, identifier):
    for item in items:
        if item[0] == identifier:
            return item[3]
    return 0


def _stored_by_name(items_fn, attr):
    """get/set for an enum whose choice is kept by name in the string property
    ``attr`` (its number is only the position in the items of the moment)."""
    def get(self):
        return _number_of(items_fn(self, None), getattr(self, attr))

    def set_(self, number):
        for item in items_fn(self, None):
            if item[3] == number:
                setattr(self, attr, item[0])
    return get, set_


_get_march, _set_march = _stored_by_name(_march_items, "march_name")
_get_preset, _set_preset = _stored_by_name(_preset_items, "preset_name")


def _on_preset(self, context):
    if self.preset_name == sl.CUSTOM or _guard["busy"]:
        return
    presets = _core_tables()[1]
    if not presets:
        return
    _guard["busy"] = True
    try:
        for key, value in sl.preset_values(presets, self.preset_name).items():
            setattr(self, key, value)
    finally:
        _guard["busy"] = False
    _on_compositor_setting(self, context)


def _on_raw(self, context):
    if _guard["busy"]:
        return
    presets = _core_tables()[1]
    values = {k: getattr(self, k) for k in sl.QUALITY_KEYS}
    match = sl.matching_preset(values, presets) if presets else self.preset_name
    if match != self.preset_name:
        self.preset_name = match
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
    # Stored by name: the enums below list whatever the core's tables hold.
    preset_name: StringProperty(default=sl.DEFAULT_PRESET, options={"HIDDEN"})
    # The core's trace default. Rendering follows preset_name unless it is
    # Custom; a default of the default preset's march would change what files
    # saved with Custom and an untouched March render.
    march_name: StringProperty(default=sl.DEFAULT_MARCH, options={"HIDDEN"})
    preset: EnumProperty(name="Quality", items=_preset_items, get=_get_preset, set=_set_preset,
                         update=_on_preset,
                         description="Quality preset, measured in docs/marches.md: sets the march, "
                                     "resolution, steps and antialias; rendering follows the core's preset")
    max_distance: _param("max_distance", float, update=_on_compositor_setting)
    resolution: _param("resolution", float)
    steps: _param("steps", int)
    antialias: _param("antialias", int)
    thickness: _param("thickness", float, update=_on_compositor_setting)
    march: EnumProperty(name="March", items=_march_items, get=_get_march, set=_set_march,
                        update=_on_raw, description="How rays are marched in screen space")
    fill_hidden: BoolProperty(
        name="Fill Hidden Reflections", default=True,
        description="Where a reflected ray passes behind an object, so that what it reflects is hidden "
                    "from the camera, show the object in front (as Eevee's SSR does) instead of the "
                    "world. Hi-Z march only")
    hidden_sides: BoolProperty(
        name="Hidden Sides in Their Colour", default=True, update=_on_compositor_setting,
        description="With Fill Hidden Reflections: where a reflected ray meets a side of an object the "
                    "camera does not see (a floating object's underside), show it in its material's "
                    "colour, lit by the surface that reflects it, instead of the object's lit front. "
                    "Costs the compositor a few nodes (about 0.1-0.15 s per 1920x1080 frame on Blender "
                    "3.4 and 5.2's CPU compositors)")
    second_bounce: EnumProperty(
        name="Second Bounce", items=cg.SECOND_BOUNCE, default="AUTO", update=_on_compositor_setting,
        description="Mirrors that reflect mirrors show those mirrors' reflections too (one more "
                    "bounce, one more Map UV in the compositor)")
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
    owns_specular_passes: BoolProperty(default=False, options={"HIDDEN"},
                                       description="Glint switched Eevee's Specular Light and Color "
                                                   "passes on and will switch them off")
    owns_use_compositing: BoolProperty(default=False, options={"HIDDEN"},
                                       description="Glint switched Post Processing > Compositing on "
                                                   "and will switch it off")


CLASSES = (GLINT_SceneSettings,)


def register():
    for cls in CLASSES:
        bpy.utils.register_class(cls)
    bpy.types.Scene.glint = bpy.props.PointerProperty(type=GLINT_SceneSettings)


def unregister():
    del bpy.types.Scene.glint
    for cls in reversed(CLASSES):
        bpy.utils.unregister_class(cls)

"""Glint: screen-space reflections composited into Blender's renders.

Tick "Glint" in Render Properties and render: Eevee, Cycles and Workbench
frames get the reflections of the "3D Game Shaders For Beginners" SSR chapter,
under F12 and under ``blender -b scene.blend -f N`` / ``-a`` alike. See
docs/addon.md in the repository.
"""

bl_info = {
    "name": "Glint",
    "author": "Glint contributors",
    "version": (0, 1, 0),
    "blender": (3, 4, 0),
    "location": "Properties > Render > Glint",
    "description": "Screen-space reflections composited into every rendered frame",
    "doc_url": "https://github.com/glint-ssr/glint/blob/main/docs/addon.md",
    "category": "Render",
}

# Reload support (F3 > Reload Scripts): submodules first, in dependency order,
# as BlendLuxCore does. Every module of the package is listed
# (tests/addon/test_reload_order.py).
RELOAD_ORDER = (
    "logic", "logic.schema", "logic.texels", "logic.materials", "logic.projection", "logic.frustum", "logic.settings",
    "logic.progress", "logic.geometry", "logic.reduced", "logic.world", "logic.measurement", "logic.compositing",
    "logic.group_images", "host", "host.engines", "host.nodes", "host.data", "host.writes", "native", "state",
    "gather", "compositor", "exact_cache", "frame", "measure", "properties", "preferences", "operators",
    "ui", "handlers")
if "bpy" in locals():
    import importlib

    for _name in RELOAD_ORDER:
        importlib.reload(importlib.import_module(f"{__name__}.{_name}"))

import bpy  # noqa: E402,F401  (its presence in locals() marks a reload)

from . import handlers, operators, preferences, properties, ui  # noqa: E402

# Registration order: data (properties) before what uses it (operators, UI),
# handlers last so that nothing runs before the settings exist.
_MODULES = (properties, preferences, operators, ui, handlers)


def register():
    for mod in _MODULES:
        mod.register()


def unregister():
    for mod in reversed(_MODULES):
        mod.unregister()

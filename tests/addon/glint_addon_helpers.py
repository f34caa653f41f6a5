"""Helpers for tests/addon: import the add-on's bpy-free modules without Blender.

``addon/glint/__init__.py`` imports bpy, so the logic package is loaded under
its own name (``glint_logic``) straight from its folder, and ``native.py`` as a
standalone module.
"""
import importlib.util
import os
import sys

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
ADDON = os.path.join(ROOT, "addon", "glint")


def _load_logic():
    if "glint_logic" in sys.modules:
        return sys.modules["glint_logic"]
    path = os.path.join(ADDON, "logic", "__init__.py")
    spec = importlib.util.spec_from_file_location("glint_logic", path,
                                                  submodule_search_locations=[os.path.dirname(path)])
    mod = importlib.util.module_from_spec(spec)
    sys.modules["glint_logic"] = mod
    spec.loader.exec_module(mod)
    return mod


def load_logic(name):
    _load_logic()
    return importlib.import_module(f"glint_logic.{name}")


def load_standalone(filename, modname):
    spec = importlib.util.spec_from_file_location(modname, os.path.join(ADDON, filename))
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod


def build_python_dir():
    """The glint_core build to test against, if any (GLINT_BUILD_DIR, default build/)."""
    build = os.environ.get("GLINT_BUILD_DIR", os.path.join(ROOT, "build"))
    d = os.path.join(build, "python")
    return d if os.path.isdir(d) else None


def core_module():
    import pytest  # here, not at the top: bench/look_compare.py runs group_model.py inside Blender
    d = build_python_dir()
    if d is None:
        pytest.skip("no glint_core build (set GLINT_BUILD_DIR)")
    sys.path.insert(0, d)
    try:
        import glint_core
    except ImportError as exc:
        pytest.skip(f"glint_core not importable from {d}: {exc}")
    return glint_core

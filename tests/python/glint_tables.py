"""The core's own tables as the tests iterate them, so that a new march or
preset is tested without editing any test."""
import importlib.util
from pathlib import Path

import glint_core

DETAILS = glint_core.march_details()
# Marches that work from the G-buffer alone (the exact march also needs the mesh).
SCREEN_MARCHES = [name for name, d in DETAILS.items() if not d["needs_mesh"]]
MESH_MARCHES = [name for name, d in DETAILS.items() if d["needs_mesh"]]


def addon_schema():
    """addon/glint/logic/schema.py, the schema's Python copy (values as written
    in native/include/glint/schema.h, where glint_core.schema() gives float32's)."""
    path = Path(__file__).resolve().parents[2] / "addon" / "glint" / "logic" / "schema.py"
    spec = importlib.util.spec_from_file_location("glint_addon_schema", path)
    mod = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(mod)
    return mod

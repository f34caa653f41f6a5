"""The core's own tables as the tests iterate them, so that a new march or
preset is tested without editing any test."""
import glint_core

DETAILS = glint_core.march_details()
# Marches that work from the G-buffer alone (the exact march also needs the mesh).
SCREEN_MARCHES = [name for name, d in DETAILS.items() if not d["needs_mesh"]]
MESH_MARCHES = [name for name, d in DETAILS.items() if d["needs_mesh"]]

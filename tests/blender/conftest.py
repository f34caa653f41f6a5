"""tests/blender: drive ``blender -b`` in subprocesses. Helpers and fixtures live in
glint_blender_helpers.py (pytest runs in importlib mode: the folder goes on sys.path)."""
import os
import sys

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

from glint_blender_helpers import (  # noqa: E402,F401  (fixtures, found by name)
    blender, blender_ok, mirror_off, samples, session_dir)

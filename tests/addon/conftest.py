"""tests/addon: plain pytest, no Blender. Helpers live in glint_addon_helpers.py
(pytest runs in importlib mode, so the folder is put on sys.path here)."""
import os
import sys

import pytest

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))

import glint_addon_helpers  # noqa: E402


@pytest.fixture(scope="session")
def core():
    return glint_addon_helpers.core_module()

"""The core found like any Python module: a glint_core that Blender's Python can
import (here: in the user scripts' ``modules`` folder, which Blender puts on
sys.path) is used when nothing else is set, and the log and the panel say so."""
import os
import shutil

import pytest

from glint_blender_helpers import CORE_DIR, PANELS, ROOT, Blender

pytestmark = pytest.mark.blender


def test_core_on_sys_path_is_found_and_named(samples, tmp_path):
    b = Blender(str(tmp_path / "home"), core_path=False)  # no GLINT_CORE_PATH
    # The add-on is a symlink into the checkout: hide the checkout's build by
    # linking a copy of the add-on instead, so sys.path is the only place left.
    link = os.path.join(b.scripts, "addons", "glint")
    os.remove(link)
    shutil.copytree(os.path.join(ROOT, "addon", "glint"), link,
        ignore=shutil.ignore_patterns("__pycache__", "native"))
    modules = os.path.join(b.scripts, "addons", "modules")
    os.makedirs(modules)
    for name in os.listdir(CORE_DIR):
        if name.startswith("glint_core") or name.startswith("libglint"):
            os.symlink(os.path.join(CORE_DIR, name), os.path.join(modules, name))
    log = b.render(samples["mirror_floor"], str(tmp_path / "out"), {"glint": {"backend": "CPU"}})
    assert "Glint: frame 1: reflections composited" in log, log[-3000:]
    line = next(l for l in log.splitlines() if l.startswith("Glint: using glint_core"))
    assert " from sys.path (" in line and modules in line, line
    log = b.run(["--addons", "glint", "--python-expr", PANELS])
    labels = next(l for l in log.splitlines() if l.startswith("LABELS"))
    assert "from sys.path" in labels and modules in labels, labels

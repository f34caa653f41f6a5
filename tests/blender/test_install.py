"""Installing: the release zip through Blender's own installer, the one-line
install from a checkout, and an add-on without its native module."""
import os
import shutil
import subprocess
import zipfile

import numpy as np
import pytest

from glint_blender_helpers import BLENDER as BLENDER_EXE, BUILD, PANELS, ROOT, Blender, read_exr

pytestmark = pytest.mark.blender


def test_package_installs_the_way_this_blender_installs_and_renders_reflections(session_dir, samples, tmp_path):
    """The package build_addon_zip.sh makes for this Blender: an extension on
    4.2 and later (installed with Blender's own ``extension install-file``), the
    legacy add-on zip before (Preferences > Add-ons > Install)."""
    zip_path = str(tmp_path / "glint.zip")
    subprocess.run(["bash", os.path.join(ROOT, "scripts", "build_addon_zip.sh"), BUILD, zip_path], check=True)
    with zipfile.ZipFile(zip_path) as z:
        names = z.namelist()
    extension = "blender_manifest.toml" in names
    b = Blender(str(tmp_path / "home"), core_path=False, link_addon=False)
    b.env["BLENDER_USER_EXTENSIONS"] = os.path.join(b.root, "extensions")
    if extension:
        assert any(n.startswith("native/glint_core") for n in names), names
        proc = subprocess.run([BLENDER_EXE, "--command", "extension", "install-file", "-r", "user_default", "-e",
                               zip_path], env=b.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              timeout=300)
        assert proc.returncode == 0, proc.stdout
        installed = os.path.join(b.root, "extensions", "user_default", "glint")
    else:
        log = b.run(["--python-expr", f"""
import bpy
bpy.ops.preferences.addon_install(filepath={zip_path!r})
bpy.ops.preferences.addon_enable(module='glint')
bpy.context.preferences.is_dirty = True
bpy.ops.wm.save_userpref()
print('ENABLED', 'glint' in bpy.context.preferences.addons)
"""], factory=False)
        assert "ENABLED True" in log
        installed = os.path.join(b.scripts, "addons", "glint")
    assert os.path.isdir(os.path.join(installed, "native")) and not os.path.islink(installed), installed
    # No GLINT_CORE_PATH, no --addons: the saved preferences load the add-on and
    # the module comes from the package's native/ folder.
    log = b.render(samples["mirror_floor"], str(tmp_path / "out"), {"glint": {"backend": "CPU"}},
                   addons=False, factory=False)
    assert "Glint: frame 1: reflections composited" in log, log[-3000:]


def test_install_script_links_and_enables(samples, tmp_path):
    b = Blender(str(tmp_path / "home"), link_addon=False)
    proc = subprocess.run(["bash", os.path.join(ROOT, "scripts", "install_addon.sh")], env=b.env,
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True, timeout=300)
    assert proc.returncode == 0, proc.stdout
    link = os.path.join(b.scripts, "addons", "glint")
    assert os.path.islink(link) and os.path.realpath(link) == os.path.join(ROOT, "addon", "glint")
    assert os.path.isfile(os.path.join(b.config, "userpref.blend")), proc.stdout
    log = b.render(samples["mirror_floor"], str(tmp_path / "out"), {"glint": {"backend": "CPU"}},
                   addons=False, factory=False)
    assert "Glint: frame 1: reflections composited" in log, log[-3000:]


def test_missing_native_module_renders_without_reflections(samples, mirror_off, tmp_path):
    b = Blender(str(tmp_path / "home"), core_path=False, link_addon=False)
    # A plain copy (not a symlink into the checkout) with no native/ folder.
    shutil.copytree(os.path.join(ROOT, "addon", "glint"), os.path.join(b.scripts, "addons", "glint"),
                    ignore=shutil.ignore_patterns("__pycache__", "native"))
    out = str(tmp_path / "out")
    log = b.render(samples["mirror_floor"], out)
    assert "Glint: reflections are off for this render: the native module glint_core was not found" in log
    assert "Glint: frame 1: rendered WITHOUT reflections" in log
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    base = read_exr(os.path.join(mirror_off[0], "frame_0001.exr"))
    assert np.abs(img - base).max() <= 1e-6
    # The preferences and the panel say so.
    log = b.run(["--addons", "glint", "--python-expr", PANELS])
    labels = next(l for l in log.splitlines() if l.startswith("LABELS"))
    assert "Glint's native module is missing: renders get no reflections." in labels
    assert "Native module missing: no reflections" in labels


def test_a_farm_node_without_the_add_on_renders_the_plain_frame(samples, mirror_off, tmp_path):
    """The .blend keeps Glint's group; with no add-on to fill its images it must pass
    the render through untouched (its images are black: no reflective pixel)."""
    b = Blender(str(tmp_path / "home"), core_path=False, link_addon=False)
    out = str(tmp_path / "out")
    log = b.render(samples["mirror_floor"], out, addons=False)
    assert "Glint:" not in log
    img = read_exr(os.path.join(out, "frame_0001.exr"))
    base = read_exr(os.path.join(mirror_off[0], "frame_0001.exr"))
    assert np.abs(img - base).max() <= 1e-6

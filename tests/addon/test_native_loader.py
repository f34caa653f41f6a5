"""The lazy loader's search order and its failure message (no Blender needed)."""
import ast
import os
import sys

import pytest

from glint_addon_helpers import ADDON, build_python_dir, load_standalone


@pytest.fixture()
def native():
    mod = load_standalone("native.py", "glint_native_under_test")
    saved = sys.modules.pop("glint_core", None)
    mod.reset()
    yield mod
    mod.reset()
    if saved is not None:
        sys.modules["glint_core"] = saved


def test_search_order_bundled_then_env_then_checkout(native, tmp_path):
    checkout = tmp_path / "checkout"
    (checkout / "addon" / "glint").mkdir(parents=True)
    addons = tmp_path / "user" / "addons"
    addons.mkdir(parents=True)
    link = addons / "glint"
    link.symlink_to(checkout / "addon" / "glint")
    dirs = native.candidate_dirs(str(link), {"GLINT_CORE_PATH": f"/a{os.pathsep}/b"})
    assert [label for label, _ in dirs] == ["add-on native/ folder", "GLINT_CORE_PATH", "GLINT_CORE_PATH",
                                             "checkout build"]
    assert dirs[0][1] == os.path.join(str(link), "native")
    assert [d for _, d in dirs[1:3]] == ["/a", "/b"]
    assert dirs[3][1] == str(checkout / "build" / "python")


def test_installed_copy_has_no_checkout(native, tmp_path):
    pkg = tmp_path / "addons" / "glint"
    pkg.mkdir(parents=True)
    assert native.checkout_of(str(pkg)) is None
    assert [label for label, _ in native.candidate_dirs(str(pkg), {})] == ["add-on native/ folder"]


def test_missing_module_is_a_clear_error_not_an_exception(native, tmp_path):
    pkg = tmp_path / "glint"
    pkg.mkdir()
    empty = tmp_path / "empty"
    empty.mkdir()
    assert native.load(str(pkg), {"GLINT_CORE_PATH": str(empty)}) is None
    msg = native.error()
    assert "glint_core was not found" in msg
    assert str(empty) in msg and "GLINT_CORE_PATH" in msg and "native" in msg
    # cached: a second call does not search again
    assert native.load(str(pkg), {"GLINT_CORE_PATH": str(empty)}) is None


def test_broken_module_file_is_reported(native, tmp_path):
    pkg = tmp_path / "glint"
    (pkg / "native").mkdir(parents=True)
    (pkg / "native" / "glint_core.cpython-311-x86_64-linux-gnu.so").write_bytes(b"not an ELF file")
    assert native.load(str(pkg), {}) is None
    assert "import failed" in native.error()


def test_finds_the_build_through_glint_core_path(native, tmp_path):
    d = build_python_dir()
    if d is None:
        pytest.skip("no build")
    pkg = tmp_path / "glint"
    pkg.mkdir()
    core = native.load(str(pkg), {"GLINT_CORE_PATH": d})
    assert core is not None, native.error()
    assert native.origin().startswith(d)
    assert all(hasattr(core, name) for name in native.REQUIRED)


def _imports(path):
    tree = ast.parse(open(path).read())
    names = set()
    for node in ast.walk(tree):
        if isinstance(node, ast.Import):
            names.update(a.name.split(".")[0] for a in node.names)
        elif isinstance(node, ast.ImportFrom) and node.module and node.level == 0:
            names.add(node.module.split(".")[0])
    return names


def test_package_imports_nothing_native_at_import_time():
    # The add-on must register without glint_core: only native.py loads it, by name, lazily.
    for root, _, files in os.walk(ADDON):
        for f in files:
            if f.endswith(".py"):
                assert "glint_core" not in _imports(os.path.join(root, f)), f


def test_logic_modules_import_neither_bpy_nor_glint_core():
    logic = os.path.join(ADDON, "logic")
    for f in os.listdir(logic):
        if f.endswith(".py"):
            assert not {"bpy", "glint_core", "mathutils"} & _imports(os.path.join(logic, f)), f

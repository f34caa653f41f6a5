"""The lazy loader's search order and its failure message (no Blender needed)."""
import ast
import os
import sys

import pytest

from glint_addon_helpers import ADDON, build_python_dir, load_standalone


@pytest.fixture()
def native(monkeypatch):
    mod = load_standalone("native.py", "glint_native_under_test")
    saved = sys.modules.pop("glint_core", None)
    # Other tests put the build on sys.path: here sys.path holds no glint_core
    # unless a test puts one there.
    monkeypatch.setattr(sys, "path", [p for p in sys.path if not _holds_core(p)])
    mod.reset()
    yield mod
    mod.reset()
    sys.modules.pop("glint_core", None)
    if saved is not None:
        sys.modules["glint_core"] = saved


def _holds_core(directory):
    try:
        return any(n.startswith("glint_core") for n in os.listdir(directory or "."))
    except OSError:
        return False


FAKE_CORE = """
__version__ = {version!r}
def trace(*a, **k): pass
def rasterize(*a, **k): pass
def backend_name(*a, **k): return "cpu"
"""


def _fake_core(directory, version="9.8.7"):
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "glint_core.py").write_text(FAKE_CORE.format(version=version))
    return str(directory)


def test_search_order_env_then_bundled_then_checkout(native, tmp_path):
    checkout = tmp_path / "checkout"
    (checkout / "addon" / "glint").mkdir(parents=True)
    addons = tmp_path / "user" / "addons"
    addons.mkdir(parents=True)
    link = addons / "glint"
    link.symlink_to(checkout / "addon" / "glint")
    dirs = native.candidate_dirs(str(link), {"GLINT_CORE_PATH": f"/a{os.pathsep}/b"})
    assert [label for label, _ in dirs] == ["GLINT_CORE_PATH", "GLINT_CORE_PATH", "add-on native/ folder",
                                             "checkout build"]
    assert [d for _, d in dirs[0:2]] == ["/a", "/b"]
    assert dirs[2][1] == os.path.join(str(link), "native")
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
    assert "sys.path: not importable from sys.path" in msg
    # cached: a second call does not search again
    assert native.load(str(pkg), {"GLINT_CORE_PATH": str(empty)}) is None


def test_importable_module_on_sys_path_is_used(native, tmp_path, monkeypatch):
    pkg = tmp_path / "glint"
    pkg.mkdir()
    site = _fake_core(tmp_path / "site-packages")
    monkeypatch.syspath_prepend(site)
    core = native.load(str(pkg), {})
    assert core is not None, native.error()
    assert native.source() == "sys.path"
    assert native.origin() == os.path.join(site, "glint_core.py")
    assert native.version() == "9.8.7"
    assert native.describe() == f"glint_core 9.8.7 from sys.path ({os.path.join(site, 'glint_core.py')})"


def test_glint_core_path_wins_over_sys_path(native, tmp_path, monkeypatch):
    # GLINT_CORE_PATH takes only folders holding a compiled module; sys.path has a fake one.
    d = build_python_dir()
    if d is None:
        pytest.skip("no build")
    pkg = tmp_path / "glint"
    pkg.mkdir()
    monkeypatch.syspath_prepend(_fake_core(tmp_path / "site-packages"))
    core = native.load(str(pkg), {"GLINT_CORE_PATH": d})
    assert core is not None, native.error()
    assert native.source() == "GLINT_CORE_PATH" and native.origin().startswith(d)
    assert native.version() != "9.8.7"


def test_already_imported_module_is_reused(native, tmp_path, monkeypatch):
    monkeypatch.syspath_prepend(_fake_core(tmp_path / "elsewhere", version="1.2.3"))
    import glint_core  # noqa: F401  (as another add-on would have)
    monkeypatch.setattr(sys, "path", [p for p in sys.path if "elsewhere" not in p])
    pkg = tmp_path / "glint"
    pkg.mkdir()
    assert native.load(str(pkg), {}) is sys.modules["glint_core"]
    assert native.source() == "already imported" and native.version() == "1.2.3"


def test_version_without_dunder_version_is_unknown_not_an_error(native, tmp_path, monkeypatch):
    site = tmp_path / "site"
    site.mkdir()
    (site / "glint_core.py").write_text(FAKE_CORE.format(version="x").replace("__version__ = 'x'", ""))
    monkeypatch.syspath_prepend(str(site))
    assert native.load(str(tmp_path), {}) is not None
    assert native.version() == "unknown"


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
    assert native.source() == "GLINT_CORE_PATH" and native.version() == core.__version__
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

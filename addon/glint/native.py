"""Finding and importing the native module ``glint_core``, lazily.

Nothing imports ``glint_core`` at registration: the add-on registers (panel,
settings, handlers) even when the module is missing, and every render that
needs it asks :func:`load`, which remembers both success and the reason for a
failure. Search order, the most deliberate choice first and Python's general
path last (the first one that imports and has :data:`REQUIRED` wins):

  (0) a ``glint_core`` this Python has already imported (another add-on or a
      script did; a second copy of an extension module cannot be loaded anyway);
  (1) the directories in the environment variable ``GLINT_CORE_PATH``
      (``os.pathsep``-separated): set on purpose, so it overrides the rest;
  (2) ``native/`` inside this package (the release zip bundles
      ``glint_core*.so`` and ``libglint.so`` there: built with this add-on);
  (3) when this package is a symlink into a checkout (``scripts/install_addon.sh``),
      ``<checkout>/build/python``, the README's build directory;
  (4) ``sys.path``: a ``glint_core`` importable like any module (an installed
      package, Blender's ``scripts/modules``, a folder a test or script added).

No ``bpy`` here: tests import this module with plain Python.
"""
from __future__ import annotations

import importlib
import importlib.util
import os
import sys
from typing import List, Optional, Tuple

MODULE_NAME = "glint_core"
PACKAGE_DIR = os.path.dirname(os.path.abspath(__file__))
# What the add-on calls; a module without them is too old for this add-on.
REQUIRED = ("trace", "rasterize", "backend_name")

_module = None
_error: Optional[str] = None
_origin: Optional[str] = None
_source: Optional[str] = None  # the label of the place it came from
_tried: List[Tuple[str, str, str]] = []


def checkout_of(package_dir: str) -> Optional[str]:
    """The checkout a symlinked package lives in (``<checkout>/addon/glint``), else None."""
    real = os.path.realpath(package_dir)
    if real == os.path.normpath(os.path.abspath(package_dir)):
        return None  # not a symlink: an installed copy has no checkout
    checkout = os.path.dirname(os.path.dirname(real))
    if os.path.basename(os.path.dirname(real)) != "addon":
        return None
    return checkout


SYS_PATH = "sys.path"
ALREADY_IMPORTED = "already imported"


def candidate_dirs(package_dir: str = PACKAGE_DIR, environ=None) -> List[Tuple[str, str]]:
    """(label, directory) in search order, steps (1)-(3); directories may not exist.
    Step (4), ``sys.path``, is Python's own search and comes after these."""
    environ = os.environ if environ is None else environ
    dirs = []
    for part in environ.get("GLINT_CORE_PATH", "").split(os.pathsep):
        if part.strip():
            dirs.append(("GLINT_CORE_PATH", os.path.abspath(os.path.expanduser(part.strip()))))
    dirs.append(("add-on native/ folder", os.path.join(package_dir, "native")))
    checkout = checkout_of(package_dir)
    if checkout is not None:
        dirs.append(("checkout build", os.path.join(checkout, "build", "python")))
    return dirs


def _has_module_file(directory: str) -> bool:
    try:
        names = os.listdir(directory)
    except OSError:
        return False
    return any(n.startswith(MODULE_NAME) and (n.endswith(".so") or n.endswith(".pyd")) for n in names)


def _import_from(directory: str):
    sys.path.insert(0, directory)
    try:
        return importlib.import_module(MODULE_NAME)
    finally:
        try:
            sys.path.remove(directory)
        except ValueError:
            pass


def _import_from_sys_path():
    """Step (4): Python's own search, or None when nothing on ``sys.path`` has it."""
    try:
        spec = importlib.util.find_spec(MODULE_NAME)
    except (ImportError, ValueError) as exc:
        _tried.append((SYS_PATH, "", f"lookup failed: {exc}"))
        return None
    if spec is None:
        _tried.append((SYS_PATH, "", "not importable from sys.path"))
        return None
    try:
        return importlib.import_module(MODULE_NAME)
    except ImportError as exc:
        sys.modules.pop(MODULE_NAME, None)
        _tried.append((SYS_PATH, spec.origin or "", f"import failed: {exc}"))
        return None


def load(package_dir: str = PACKAGE_DIR, environ=None, retry: bool = False):
    """The ``glint_core`` module, or None (then :func:`error` says why). Cached."""
    global _module, _error, _origin, _source, _tried
    if _module is not None:
        return _module
    if _error is not None and not retry:
        return None
    _tried = []
    already = sys.modules.get(MODULE_NAME)
    found = None
    if already is not None:
        found, _source = already, ALREADY_IMPORTED
        _origin = getattr(already, "__file__", None) or ALREADY_IMPORTED
    else:
        for label, directory in candidate_dirs(package_dir, environ):
            if not _has_module_file(directory):
                _tried.append((label, directory, "no glint_core module there"))
                continue
            try:
                found = _import_from(directory)
                _origin, _source = getattr(found, "__file__", directory), label
                break
            except ImportError as exc:  # e.g. libglint.so missing or a different Python
                sys.modules.pop(MODULE_NAME, None)
                _tried.append((label, directory, f"import failed: {exc}"))
        if found is None:
            found = _import_from_sys_path()
            if found is not None:
                _origin, _source = getattr(found, "__file__", None) or SYS_PATH, SYS_PATH
    if found is None:
        where = "; ".join(f"{label} {d}: {why}" if d else f"{label}: {why}" for label, d, why in _tried)
        _error = (f"the native module {MODULE_NAME} was not found ({where}). Build it "
                  f"(scripts/setup.sh), install the release zip, set GLINT_CORE_PATH, or "
                  f"install {MODULE_NAME} where Blender's Python imports it.")
        return None
    missing = [name for name in REQUIRED if not hasattr(found, name)]
    if missing:
        _error = (f"the native module at {_origin} is too old for this add-on "
                  f"(missing {', '.join(missing)}); rebuild it")
        return None
    _module, _error = found, None
    return _module


def error() -> Optional[str]:
    """Why :func:`load` failed, or None."""
    return _error


def origin() -> Optional[str]:
    """The file the loaded module came from."""
    return _origin


def source() -> Optional[str]:
    """Which step of the search order found it ("GLINT_CORE_PATH", "sys.path", ...)."""
    return _source


def version(module=None) -> str:
    """The module's version: ``__version__`` (the bindings set it), else the
    installed distribution's metadata, else "unknown"."""
    module = _module if module is None else module
    v = getattr(module, "__version__", None)
    if v:
        return str(v)
    try:
        from importlib import metadata
        return metadata.version(MODULE_NAME)
    except Exception:  # no metadata: a bare .so on a path
        return "unknown"


def describe() -> Optional[str]:
    """'glint_core 0.1.0 from GLINT_CORE_PATH (/path/glint_core....so)', or None."""
    if _module is None:
        return None
    return f"{MODULE_NAME} {version()} from {_source} ({_origin})"


def release_buffers(idle_only: bool = True) -> float:
    """Give the core's pooled buffers back to the system (with ``idle_only``,
    those unused for the pool's idle time); MiB freed. Never loads the core."""
    if _module is None:
        return 0.0
    return float(_module.release_buffers(idle_only=idle_only))


def reset() -> None:
    """Forget the cached result (tests; the preferences' Retry button)."""
    global _module, _error, _origin, _source, _tried
    _module, _error, _origin, _source, _tried = None, None, None, None, []

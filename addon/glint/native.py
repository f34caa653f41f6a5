"""Finding and importing the native module ``glint_core``, lazily.

Nothing imports ``glint_core`` at registration: the add-on registers (panel,
settings, handlers) even when the module is missing, and every render that
needs it asks :func:`load`, which remembers both success and the reason for a
failure. Search order:

  (a) ``native/`` inside this package (the release zip bundles
      ``glint_core*.so`` and ``libglint.so`` there);
  (b) the directories in the environment variable ``GLINT_CORE_PATH``
      (``os.pathsep``-separated);
  (c) when this package is a symlink into a checkout (``scripts/install_addon.sh``),
      ``<checkout>/build/python``, the README's build directory.

No ``bpy`` here: tests import this module with plain Python.
"""
from __future__ import annotations

import importlib
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


def candidate_dirs(package_dir: str = PACKAGE_DIR, environ=None) -> List[Tuple[str, str]]:
    """(label, directory) in search order; directories may not exist."""
    environ = os.environ if environ is None else environ
    dirs = [("add-on native/ folder", os.path.join(package_dir, "native"))]
    for part in environ.get("GLINT_CORE_PATH", "").split(os.pathsep):
        if part.strip():
            dirs.append(("GLINT_CORE_PATH", os.path.abspath(os.path.expanduser(part.strip()))))
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


def load(package_dir: str = PACKAGE_DIR, environ=None, retry: bool = False):
    """The ``glint_core`` module, or None (then :func:`error` says why). Cached."""
    global _module, _error, _origin, _tried
    if _module is not None:
        return _module
    if _error is not None and not retry:
        return None
    _tried = []
    already = sys.modules.get(MODULE_NAME)
    found = None
    if already is not None:
        found, _origin = already, getattr(already, "__file__", "already imported")
    else:
        for label, directory in candidate_dirs(package_dir, environ):
            if not _has_module_file(directory):
                _tried.append((label, directory, "no glint_core module there"))
                continue
            try:
                found = _import_from(directory)
                _origin = getattr(found, "__file__", directory)
                break
            except ImportError as exc:  # e.g. libglint.so missing or a different Python
                sys.modules.pop(MODULE_NAME, None)
                _tried.append((label, directory, f"import failed: {exc}"))
    if found is None:
        where = "; ".join(f"{label} {d}: {why}" for label, d, why in _tried) or "nowhere to look"
        _error = (f"the native module {MODULE_NAME} was not found ({where}). Build it "
                  f"(scripts/setup.sh), install the release zip, or set GLINT_CORE_PATH.")
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
    return _origin


def reset() -> None:
    """Forget the cached result (tests; the preferences' Retry button)."""
    global _module, _error, _origin, _tried
    _module, _error, _origin, _tried = None, None, None, []

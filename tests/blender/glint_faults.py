"""Fault injection for tests/blender, imported by a test's ``python`` config inside
Blender (driver.py puts this folder on sys.path). Nothing here is in the add-on
or the core: each fault is put in place from outside, by replacing what the
add-on calls, so the shipped code pays nothing for it. docs/hardening.md.

- ``lose_gl_context_after_rasterize(shim)``: the G-buffer is drawn on the GL
  backend, then the context is lost (fault_egl.c, loaded by the core through
  GLINT_EGL_LIBRARY) and the trace's read-back fails inside the core.
- ``core_error_in_trace()``: the core's trace (the add-on calls it as
  ``composite_layers``) raises RuntimeError, as a ``glint::Error`` reaches Python.
- ``cancel_after_checks(n)``: the render's cancel flag reads as set from its n-th
  look on (the export asks once per object): a cancel in the middle of the export.
- ``cancel_during_trace()``: the user cancels while the trace runs.
"""
import ctypes
import threading

import glint.frame
import glint.native
from glint.state import STATE


def _after_rasterize(fn):
    real = glint.frame.rasterize

    def rasterize(*args, **kwargs):
        out = real(*args, **kwargs)
        fn()
        return out

    glint.frame.rasterize = rasterize


def lose_gl_context_after_rasterize(shim_path):
    lib = ctypes.CDLL(shim_path)  # the same copy the core dlopen()ed by this path
    _after_rasterize(lib.glint_fault_lose_context)


class _Core:
    """The loaded glint_core with some functions replaced."""

    def __init__(self, real, **replaced):
        self._real = real
        self.__dict__.update(replaced)

    def __getattr__(self, name):
        return getattr(self._real, name)


def _replace_core(**replaced):
    real = glint.native.load()
    assert real is not None, glint.native.error()
    glint.native._module = _Core(real, **{k: v(getattr(real, k)) for k, v in replaced.items()})


def core_error_in_trace():
    def make(real_trace):
        def trace(*args, **kwargs):
            raise RuntimeError("glint: injected core failure in trace")
        return trace
    _replace_core(composite_layers=make)


def cancel_during_trace():
    def make(real_trace):
        def trace(*args, **kwargs):
            out = real_trace(*args, **kwargs)
            STATE.cancel.set()  # what GLINT_OT_cancel does, while the trace ran
            return out
        return trace
    _replace_core(composite_layers=make)


class _TripAfter(threading.Event):
    """An Event that reads as set from its n-th ``is_set`` on."""

    def __init__(self, n):
        super().__init__()
        self.n, self.looks = n, 0

    def is_set(self):
        self.looks += 1
        return self.looks >= self.n or super().is_set()


def cancel_after_checks(n):
    STATE.cancel = _TripAfter(n)

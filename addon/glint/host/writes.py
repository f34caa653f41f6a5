"""Main-thread work that writes to Blender data, even where Blender has left
Python's writes refused.

Blender refuses Python's writes to ID data, and calls of operators, while a
read-only Python callback runs (a panel's ``draw``, a Python render engine's
method such as Cycles'). It does so with one process-wide flag that each
callback saves, sets and restores. When callbacks on the render thread and on
the main thread overlap (the GIL changes hands between them), they can restore
out of order and leave the flag set for the rest of the session: from then on
every write from a timer or a handler fails with "Writing to ID classes in this
context is not allowed" or "can't modify blend data in this state".

Two things still work in that state: a property of the window manager may be
written (Blender exempts it), and a property's update callback runs with
writes allowed. :func:`run` goes through both. It is for the main thread with
no render thread running: what Glint does after a render, on loading a file
and in a script's blocking render, which handlers.py tries directly first. On
the render thread the update would post window notifiers from the wrong
thread, so what Glint writes there is kept to calls Blender does not refuse
(``pixels.foreach_set``, ``scale``) and to values written when they differ.
See docs/addon.md, *Writes Blender refuses*.
"""
from __future__ import annotations

import threading
import time
from typing import Callable, Dict, TypeVar

import bpy

T = TypeVar("T")

_PROP = "glint_write_through"
_call: Dict[str, object] = {}


def refused(exc: BaseException) -> bool:
    """Whether ``exc`` is Blender refusing a write or an operator for the flag,
    rather than a fault of the write itself."""
    text = str(exc)
    return ((isinstance(exc, AttributeError) and "in this context is not allowed" in text)
            or (isinstance(exc, RuntimeError) and "modify blend data in this state" in text))


# How long the render thread tries a refused write again: a panel's draw on
# the main thread lasts milliseconds; refused for longer, the flag is stuck.
WAIT_SECONDS = 2.0


def retrying(fn: Callable[[], T]) -> T:
    """``fn()``, tried again every 20 ms for up to WAIT_SECONDS while Blender
    refuses it, off the main thread: there, up to 4.x, a Python panel drawn on
    the main thread refuses it for that moment. On the main thread a refusal
    means the flag is stuck, and it is raised at once."""
    if threading.current_thread() is threading.main_thread():
        return fn()
    deadline = time.monotonic() + WAIT_SECONDS
    while True:
        try:
            return fn()
        except (AttributeError, RuntimeError) as exc:
            if not refused(exc) or time.monotonic() > deadline:
                raise
            time.sleep(0.02)


def _through(self, context) -> None:
    try:
        _call["value"] = _call["fn"]()
    except BaseException as exc:  # handed to run(), out of Blender's reach
        _call["error"] = exc


def run(fn: Callable[[], T]) -> T:
    """``fn()`` with writes and operators allowed; its exceptions reach the caller."""
    if threading.current_thread() is not threading.main_thread():
        raise RuntimeError("glint.host.writes.run is for the main thread")
    wm = bpy.data.window_managers[0] if bpy.data.window_managers else None
    if wm is None or not hasattr(wm, _PROP):  # no window manager: nothing draws, nothing refuses
        return fn()
    _call.clear()
    _call["fn"] = fn
    try:
        setattr(wm, _PROP, not getattr(wm, _PROP))
        if "error" in _call:
            raise _call["error"]
        if "value" not in _call:
            raise RuntimeError("the window manager's update callback did not run")
        return _call["value"]
    finally:
        _call.clear()


def register() -> None:
    setattr(bpy.types.WindowManager, _PROP, bpy.props.BoolProperty(
        name="Glint write-through", description="Toggled to run Glint's after-render work (internal)",
        update=_through, options={"HIDDEN", "SKIP_SAVE"}))


def unregister() -> None:
    if hasattr(bpy.types.WindowManager, _PROP):
        delattr(bpy.types.WindowManager, _PROP)

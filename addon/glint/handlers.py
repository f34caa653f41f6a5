"""Render-time hooks: where Glint runs during F12, ``-f``, ``-a`` and frame ranges.

Order of events for every rendered frame (all engines; checked with Blender 3.4):

  render_init (once per job) -> render_pre (per frame) ->
  frame_change_post(scene, depsgraph)  with the render's own RENDER depsgraph,
                                       evaluated at the frame, per view layer
  -> engine renders -> compositor -> file written -> render_post

Glint exports from that depsgraph (render visibility, render modifiers, the
frame's animation), never from ``bpy.context``. ``render_pre`` mutes the group
so that a frame Glint cannot handle composites unchanged; a successful frame
unmutes it. Motion blur re-evaluates sub-frames: only the first evaluation at
the frame itself is used.
"""
from __future__ import annotations

import bpy
from bpy.app.handlers import persistent

from . import compositor, frame, native
from .state import STATE, log

_job = {"scene": None, "target": None, "done": False, "ui_notice": None}


def _enabled(scene) -> bool:
    glint = getattr(scene, "glint", None)
    return bool(glint is not None and glint.enabled)


def _progress_printer(fraction: float, message: str) -> None:
    log(f"export {fraction * 100.0:.0f}% ({message})")


@persistent
def on_render_init(scene, *args):
    _job.update(scene=None, target=None, done=False)
    if not _enabled(scene):
        return
    _job["scene"] = scene.name
    STATE.cancel.clear()
    if native.load() is None:
        log(f"reflections are off for this render: {native.error()}")
    try:
        warning = compositor.ensure(scene)
    except Exception as exc:  # never let a node-tree problem stop the render
        log(f"could not set up the compositor ({type(exc).__name__}: {exc}); no reflections")
        _job["scene"] = None
        return
    if warning:
        log(warning)


@persistent
def on_render_pre(scene, *args):
    if _job["scene"] != scene.name or not _enabled(scene):
        return
    _job["target"] = (scene.frame_current, round(scene.frame_subframe, 6))
    _job["done"] = False
    compositor.set_active(scene, False)


@persistent
def on_frame_change_post(scene, depsgraph=None, *args):
    if depsgraph is None or depsgraph.mode != "RENDER" or _job["done"]:
        return
    if _job["scene"] != scene.name or _job["target"] is None or not _enabled(scene):
        return
    ev = depsgraph.scene_eval
    if (ev.frame_current, round(ev.frame_subframe, 6)) != _job["target"]:
        return  # a motion-blur sub-frame
    if depsgraph.view_layer.name != compositor.target_view_layer(scene).name:
        return
    _job["done"] = True
    STATE.busy = True
    try:
        report = frame.run(depsgraph, scene, should_stop=STATE.cancel.is_set, progress_report=_progress_printer)
    except Exception as exc:  # an add-on bug must not take the render down
        import traceback
        traceback.print_exc()
        from .state import FrameReport
        report = FrameReport(frame=ev.frame_current, status="error", message=f"{type(exc).__name__}: {exc}")
    finally:
        STATE.busy = False
    STATE.last = report
    t = ", ".join(f"{k} {v:.1f} ms" for k, v in report.timings_ms.items())
    if report.status == "ok":
        compositor.set_active(scene, True)
        log(f"frame {report.frame}: reflections composited ({report.width}x{report.height}, "
            f"{report.triangles} triangles from {report.objects} objects, {report.culled} culled, "
            f"{report.reflective_pixels} reflective pixels, backend {report.backend}; {t})")
    elif report.status == "skipped":
        log(f"frame {report.frame}: nothing to reflect: {report.message} ({t or 'no work'})")
    else:
        log(f"frame {report.frame}: rendered WITHOUT reflections: {report.message}")
        _notify_ui(report.message)


def _notify_ui(message: str) -> None:
    """In the UI, show the error once the render is over (from the main thread)."""
    if bpy.app.background or _job.get("ui_notice") == message:
        return
    _job["ui_notice"] = message

    def popup():
        wm = bpy.context.window_manager
        if wm is None:
            return None

        def draw(menu, _context):
            menu.layout.label(text=message, icon="ERROR")

        wm.popup_menu(draw, title="Glint: rendered without reflections", icon="ERROR")
        return None

    try:
        bpy.app.timers.register(popup, first_interval=0.1)
    except Exception:
        pass


@persistent
def on_render_end(scene, *args):
    if _job["scene"] == scene.name:
        _job.update(scene=None, target=None, done=False, ui_notice=None)


@persistent
def on_load_post(*args):
    # Files made elsewhere (or saved before the group changed) get their
    # compositor set up on load; update callbacks do not run on load.
    for scene in bpy.data.scenes:
        if _enabled(scene):
            try:
                compositor.ensure(scene)
            except Exception as exc:
                log(f"could not set up the compositor of scene {scene.name!r}: {exc}")


HANDLERS = (
    ("render_init", on_render_init),
    ("render_pre", on_render_pre),
    ("frame_change_post", on_frame_change_post),
    ("render_complete", on_render_end),
    ("render_cancel", on_render_end),
    ("load_post", on_load_post),
)


def register():
    for name, fn in HANDLERS:
        lst = getattr(bpy.app.handlers, name)
        if fn not in lst:
            lst.append(fn)


def unregister():
    for name, fn in HANDLERS:
        lst = getattr(bpy.app.handlers, name)
        while fn in lst:
            lst.remove(fn)

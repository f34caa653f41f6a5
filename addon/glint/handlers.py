"""Render-time hooks: where Glint runs during F12, ``-f``, ``-a`` and frame ranges.

Order of events for every rendered frame (all engines; checked with Blender 3.4):

  render_init (once per job) -> render_pre (per frame) ->
  frame_change_post(scene, depsgraph)  with the render's own RENDER depsgraph,
                                       evaluated at the frame, per view layer
  -> engine renders -> compositor -> file written -> render_post

Under ``-b`` all of them run on the main thread; under F12 in the UI all of them
run on the render job's thread while the UI stays live (checked under Xvfb).

Glint exports from that depsgraph (render visibility, render modifiers, the
frame's animation), never from ``bpy.context``. Under F12 the compositor works on
a copy of the node tree taken before ``frame_change_post``: muting or unmuting
Glint's node there never reaches it. So the node stays unmuted; ``render_pre``
zeroes Glint's images, which makes the group pass the frame through unchanged,
and a successful frame fills them. Images are not copied for the render: the
compositor reads what was written.
From the render thread Glint writes only those images and, when they changed,
a few node values (blur size, debug switches, the EXR folder); a compositor
set-up that needs new nodes or links is repaired on the main thread and the
frame renders without reflections, with a report. Motion blur re-evaluates
sub-frames: only the first evaluation at the frame itself is used.
"""
from __future__ import annotations

import queue
import threading
import time
import traceback
from dataclasses import dataclass
from typing import Optional, Tuple

import bpy
from bpy.app.handlers import persistent

from . import compositor, frame, host, native
from .host import engines, writes
from .state import STATE, FrameReport, log


@dataclass
class RenderJob:
    """What one render (an F12, a ``-f``, a whole ``-a``) carries from handler to
    handler: made at ``render_init`` for a scene with Glint on, dropped when the
    render completes or is cancelled. Nothing of it outlives its render."""
    scene: str
    # (frame, subframe) that render_pre announced: the one evaluation traced
    target: Optional[Tuple[int, float]] = None
    done: bool = False  # that frame was traced (motion blur evaluates it again)
    skip: Optional[str] = None  # why this render gets no reflections at all
    ui_notice: Optional[str] = None  # the last report queued, so -a shows it once


# The render in progress; handlers get only the scene, so they find it here.
_render: Optional[RenderJob] = None


def _job_of(scene) -> Optional[RenderJob]:
    """The running render's job when it is ``scene``'s and Glint is still on."""
    job = _render
    return job if job is not None and job.scene == scene.name and _enabled(scene) else None

# The core already named in the log (once per session, and again if it changes).
_announced = {"core": None, "host": False}

# How often the main thread looks for queued work (reports, redraws, repairs).
TICK_SECONDS = 0.2
# How often it hands the core's idle pooled buffers back (glint_core.buffer_pool):
# between renders nothing else in the core runs to notice they went idle.
TRIM_SECONDS = 10.0
# Where the window draws nothing during the export (host.draws_during_export),
# render_pre waits up to this long for the panel to draw Cancel Glint first,
# when the panel drew in the last PANEL_SEEN_SECONDS (it is likely on screen):
# a tick (TICK_SECONDS) tags it for redraw, and the draw follows at once.
PANEL_WAIT_SECONDS = 0.3
PANEL_SEEN_SECONDS = 120.0


def _enabled(scene) -> bool:
    glint = getattr(scene, "glint", None)
    return bool(glint is not None and glint.enabled)


def _on_main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _progress(fraction: float, message: str) -> None:
    STATE.progress = f"export {fraction * 100.0:.0f}% ({message})"
    log(STATE.progress)


def _repair_setup(scene_name: str) -> None:
    scene = bpy.data.scenes.get(scene_name)
    if scene is not None and _enabled(scene):
        compositor.ensure(scene)
        log(f"compositor set-up of scene {scene_name!r} restored")


@persistent
def on_render_init(scene, *args):
    global _render
    _render = None
    STATE.rendering = False
    STATE.panel_drawn.clear()
    if not _enabled(scene):
        return
    job = _render = RenderJob(scene.name)
    STATE.cancel.clear()
    if not _announced["host"]:
        _announced["host"] = True
        note = host.untested_note()
        if note:
            log(note)
    if native.load() is None:
        log(f"reflections are off for this render: {native.error()}")
    elif _announced.get("core") != native.origin():
        _announced["core"] = native.origin()
        log(f"using {native.describe()}")
    try:
        turned_on = _ensure_setup(scene)
    except compositor.SetupIncomplete as exc:
        # New nodes and links are not made from the render thread while the UI
        # may be drawing or evaluating the same trees: the main thread does it.
        # After the job, too: the render composites with this very tree.
        STATE.after_render(lambda name=scene.name: _repair_setup(name))
        _skip(job, scene, f"the compositor set-up was changed ({exc}); Glint restores it now, render again")
        return
    except Exception as exc:  # never let a node-tree problem stop the render
        if writes.refused(exc):
            # Refused past writes.WAIT_SECONDS: Blender's flag is stuck. The
            # main thread can still write (host/writes.py), after the job.
            _note_stuck()
            STATE.after_render(lambda name=scene.name: _repair_setup(name))
            _skip(job, scene, f"Blender refused Python's writes from the render thread for "
                  f"{writes.WAIT_SECONDS:.0f} s (a fault of Blender 3.x and 4.x that can follow a Cycles "
                  f"render and lasts until it restarts); Glint writes the compositor's values now, render again")
            return
        traceback.print_exc()
        _skip(job, scene, f"could not set up the compositor ({type(exc).__name__}: {exc})")
        return
    if turned_on:  # an old file's compositor was off: say what changed, render with reflections
        log(f"scene {scene.name!r}: {turned_on}")
    if STATE.specular_source:
        log(f"the specular a reflection replaces comes from the {STATE.specular_source}")
    own = engines.own_reflections_note(scene)
    if own:
        log(own)
    STATE.rendering = True
    STATE.touch()


def _ensure_setup(scene):
    """compositor.ensure for a render about to start. On the render thread, up
    to Blender 4.x, a Python panel drawn on the main thread meanwhile makes
    Blender refuse this thread's writes: the values ensure writes (only where
    they differ) are written again once the draw has ended."""
    if _on_main_thread():  # a script's blocking render: no render thread, no draw meanwhile
        return _on_main(lambda: compositor.ensure(scene))
    return writes.retrying(lambda: compositor.ensure(scene, allow_changes=False))


def _on_main(fn):
    """fn() on the main thread; through host/writes.py's update where Blender's
    read-only flag was left set (refused from a timer or a handler, it is stuck)."""
    try:
        return fn()
    except (AttributeError, RuntimeError) as exc:
        if not writes.refused(exc):
            raise
    _note_stuck()
    return writes.run(fn)


def _note_stuck() -> None:
    """Say once that Blender's read-only flag is stuck; the panel shows it."""
    if not STATE.writes_stuck:
        STATE.writes_stuck = True
        log(STUCK_NOTE)


STUCK_NOTE = ("Blender refuses Python's writes to its data from timers and handlers since a render "
              "(a fault of Blender 3.x and 4.x; other add-ons fail too): Glint works around it; "
              "restarting Blender clears it")


def _region_text(report) -> str:
    x0, y0, x1, y1 = report.region
    share = (x1 - x0) * (y1 - y0) / max(1, report.width * report.height)
    return f"{x1 - x0}x{y1 - y0} ({share:.0%} of the frame)"


def _skip(job: RenderJob, scene, reason: str) -> None:
    """This render gets no reflections, for ``reason``: say so everywhere."""
    job.skip = reason
    log(f"this render gets no reflections: {reason}")
    STATE.last = FrameReport(frame=scene.frame_current, status="error", message=reason)
    _notify_ui(job, reason)


@persistent
def on_render_pre(scene, *args):
    job = _job_of(scene)
    if job is None:
        return
    job.target = (scene.frame_current, round(scene.frame_subframe, 6))
    job.done = False
    _let_the_panel_draw()
    try:
        # A frame Glint does not handle passes through. Only debug views and the
        # layers EXR show more than the UV image lets through: then every image is zeroed.
        g = scene.glint
        compositor.clear_images(only_pass_through=g.debug_view == "NONE" and not g.write_layers_exr)
    except Exception as exc:
        traceback.print_exc()
        log(f"could not clear Glint's images ({type(exc).__name__}: {exc})")


def _let_the_panel_draw() -> None:
    """On a Blender that draws nothing while the export runs, give the panel,
    if it is on screen, the moment to draw Cancel Glint before the export."""
    # On the main thread (a script's blocking render) the panel cannot draw meanwhile.
    if bpy.app.background or host.draws_during_export() or not STATE.rendering or _on_main_thread():
        return
    if time.monotonic() - STATE.panel_drawn_at > PANEL_SEEN_SECONDS:
        return
    STATE.panel_drawn.wait(PANEL_WAIT_SECONDS)


@persistent
def on_frame_change_post(scene, depsgraph=None, *args):
    if depsgraph is None or depsgraph.mode != "RENDER":
        return
    job = _job_of(scene)
    if job is None or job.done or job.target is None or job.skip:
        return
    ev = depsgraph.scene_eval
    if (ev.frame_current, round(ev.frame_subframe, 6)) != job.target:
        return  # a motion-blur sub-frame
    if depsgraph.view_layer.name != compositor.target_view_layer(scene).name:
        return
    job.done = True
    STATE.busy, STATE.progress = True, ""
    STATE.touch()
    try:
        report = frame.run(depsgraph, scene, should_stop=STATE.cancel.is_set, progress_report=_progress)
    except Exception as exc:  # an add-on bug must not take the render down
        traceback.print_exc()
        report = FrameReport(frame=ev.frame_current, status="error", message=f"{type(exc).__name__}: {exc}")
    finally:
        STATE.busy, STATE.progress = False, ""
    STATE.last = report
    t = ", ".join(f"{k} {v:.1f} ms" for k, v in report.timings_ms.items())
    if report.status == "ok":
        log(f"frame {report.frame}: reflections composited ({report.width}x{report.height}, "
            f"{report.triangles} triangles from {report.objects} objects, {report.culled} culled, "
            f"{report.reflective_pixels} reflective pixels, composited {_region_text(report)}, "
            f"backend {report.backend}; {t}; "
            f"{report.message})")
    elif report.status == "skipped":
        log(f"frame {report.frame}: nothing to reflect: {report.message} ({t or 'no work'})")
    else:
        log(f"frame {report.frame}: rendered WITHOUT reflections: {report.message}")
        # A cancel the user asked for is reported, not shown as an error pop-up.
        _notify_ui(job, report.message, level="WARNING" if report.status == "cancelled" else "ERROR")


def _notify_ui(job: RenderJob, message: str, level: str = "ERROR") -> None:
    """In the UI, report a frame without reflections from the main thread: the
    status bar and the Info log, and for errors Blender's report pop-up over the
    render window."""
    if bpy.app.background or job.ui_notice == message:
        return
    job.ui_notice = message
    # After the job: the report is an operator called under a context override,
    # which Blender 3.4.1 looks up without the GIL when another thread holds it;
    # a render thread in any add-on's handler at that moment crashes Blender.
    # (Operators called so mid-render crashed the UI test's driver one F12 in ten.)
    STATE.after_render(lambda: _show_report(message, level))


def _report_window(wm):
    """The window showing the Render Result if there is one (F12 opens it), else the first."""
    for win in wm.windows:
        for area in win.screen.areas:
            space = area.spaces.active
            if area.type == "IMAGE_EDITOR" and space.image is not None and space.image.type == "RENDER_RESULT":
                return win
    return wm.windows[0] if len(wm.windows) else None


def _show_report(message: str, level: str) -> None:
    wm = bpy.context.window_manager
    win = _report_window(wm) if wm is not None else None
    if win is None:
        return
    # A modal operator's report: Blender puts it in the status bar and the Info log
    # and, for an error, opens its report pop-up in the window.
    with bpy.context.temp_override(window=win):
        bpy.ops.glint.report("INVOKE_DEFAULT", level=level,
                             message=f"Glint: rendered without reflections: {message}")


def _redraw_panels() -> None:
    for wm in bpy.data.window_managers:
        for win in wm.windows:
            for area in win.screen.areas:
                if area.type == "PROPERTIES":
                    area.tag_redraw()


_seen = {"version": -1, "trimmed": 0.0}


def _run_queue(q) -> None:
    while True:
        try:
            fn = q.get_nowait()
        except queue.Empty:
            break
        try:
            _on_main(fn)
        except Exception:
            traceback.print_exc()


def _main_thread_tick():
    """Runs on the main thread: queued work from render threads, panel redraws
    (status line, progress, the Cancel button) when the state changed."""
    if not bpy.app.is_job_running("RENDER"):
        _run_queue(STATE.after_render_queue)
        if STATE.rendering:  # a render that ended without render_complete or render_cancel
            STATE.rendering = False
            STATE.touch()
    now = time.monotonic()
    if now - _seen["trimmed"] >= TRIM_SECONDS:
        _seen["trimmed"] = now
        try:
            native.release_buffers(idle_only=True)
        except Exception:
            traceback.print_exc()
    if STATE.version != _seen["version"]:
        _seen["version"] = STATE.version
        try:
            _redraw_panels()
        except Exception:
            traceback.print_exc()
    return TICK_SECONDS


@persistent
def on_render_end(scene, *args):
    global _render
    if _render is not None and _render.scene == scene.name:
        _render = None
        STATE.rendering = False
        STATE.touch()


@persistent
def on_load_post(*args):
    # Files made elsewhere (or saved before the group changed) get their
    # compositor set up on load; update callbacks do not run on load.
    compositor.forget_filled()
    native.release_buffers(idle_only=False)  # sized for the last file's frames
    for scene in bpy.data.scenes:
        if _enabled(scene):
            try:
                turned_on = _on_main(lambda scene=scene: compositor.ensure(scene))
                if turned_on:
                    log(f"scene {scene.name!r}: {turned_on}")
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
    writes.register()
    for name, fn in HANDLERS:
        lst = getattr(bpy.app.handlers, name)
        if fn not in lst:
            lst.append(fn)
    if not bpy.app.background and not bpy.app.timers.is_registered(_main_thread_tick):
        bpy.app.timers.register(_main_thread_tick, first_interval=TICK_SECONDS, persistent=True)


def unregister():
    for name, fn in HANDLERS:
        lst = getattr(bpy.app.handlers, name)
        while fn in lst:
            lst.remove(fn)
    if bpy.app.timers.is_registered(_main_thread_tick):
        bpy.app.timers.unregister(_main_thread_tick)
    native.release_buffers(idle_only=False)
    writes.unregister()

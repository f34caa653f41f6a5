"""Runs inside Blender WITH a window (under xvfb-run) for tests/blender/test_ui_render.py:
press F12 the way a user does, once or several times, and record what happened.

Usage: xvfb-run blender file.blend --addons glint --python ui_driver.py -- config.json

config keys: out (folder), size [w, h], engine, eevee_samples, cycles_samples,
glint {setting: value} ('enabled' last), python (code run after the settings),
mirror_objects [names] (their vertices and their mirror images in z = 0 through
Blender's world_to_camera_view, into the result), screenshot (bool, default true),
timeout (seconds per render), renders: a list of steps, one F12 each, with keys
  python            code run on the main thread just before the F12 (a user's edit)
  cancel_when_busy  press Glint's Cancel button during the export: true, once the panel has
                    drawn the export's progress; "drawn", once it has drawn the button
  check             a Python expression evaluated after the render, its value recorded
  animation         render the frame range (Ctrl F12) instead of one frame
  read_only         before the F12, leave Blender's Python read-only for good, the way
                    interleaved callbacks on two threads can (_leave_read_only); the
                    render's "read_only" says whether it could
  hold_read_only    seconds: as the render starts, hold a read-only callback on the main
                    thread that long, as a long panel draw would, while Glint's
                    render_init runs; the render's "held" is [start, end] on the
                    events' clock, "hold_met" when Glint's render_init began

F12 is ``render.render('INVOKE_DEFAULT')`` from a timer in the main window's
context: the render runs as a job on its own thread and opens the render window,
as the key does. For render i: <out>/render_<i>.exr (float) saved from the
Render Result, screenshots <out>/window_<w>_<i>.png. <out>/result.json holds,
per render, the handler calls (with the thread each ran on), Glint's status, the
Glint panel's draws, and at the end the Info log's reports. Quits Blender when
done, or exits with status 4 after a timeout.
"""
import json
import os
import sys
import threading
import time
import traceback

import bpy
from bpy_extras.object_utils import world_to_camera_view
from mathutils import Vector

cfg = json.load(open(sys.argv[sys.argv.index("--") + 1]))
OUT = cfg["out"]
os.makedirs(OUT, exist_ok=True)
scene = bpy.context.scene
sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import scene_config  # noqa: E402  (beside this file)
from glint.host import nodes as hn  # noqa: E402,F401  (steps' code reaches the compositor tree with it)
from glint.host import writes  # noqa: E402

scene_config.apply(scene, cfg)
r = scene.render
exec(cfg.get("python", ""))
# The Render Result is saved in the scene's format, set here once, so that
# collecting a render writes nothing to the scene.
r.image_settings.file_format, r.image_settings.color_depth = "OPEN_EXR", "32"

T0 = time.monotonic()
RENDERS = cfg.get("renders", [{}])
result = {"renders": [], "errors": [], "objects": {}, "reports_shown": []}


def _record_reports():
    """Glint's reports, as shown, with whether a render job was still running:
    one shown mid-render can crash Blender (docs/addon.md, *Reports from a render*)."""
    from glint import handlers
    show = handlers._show_report

    def recorded(message, level):
        result["reports_shown"].append(dict(message=message, level=level,
                                            job_running=bpy.app.is_job_running("RENDER")))
        return show(message, level)
    handlers._show_report = recorded


_record_reports()
for name in cfg.get("mirror_objects", []):
    ob = bpy.data.objects[name]
    pts = [ob.matrix_world @ v.co for v in ob.data.vertices]
    result["objects"][name] = {
        "real": [list(world_to_camera_view(scene, scene.camera, q)) for q in pts],
        "mirror": [list(world_to_camera_view(scene, scene.camera, Vector((q.x, q.y, -q.z)))) for q in pts]}


def _now():
    return round(time.monotonic() - T0, 3)


def _current():
    return result["renders"][-1] if result["renders"] else None


def _event(name, **extra):
    cur = _current()
    if cur is not None:
        cur["events"].append(dict(event=name, t=_now(), **extra))


def _recorder(name):
    def handler(*args):
        _event(name, main_thread=threading.current_thread() is threading.main_thread())
    return handler


for _name in ("render_init", "render_pre", "render_post", "render_complete", "render_cancel",
              "frame_change_post"):
    getattr(bpy.app.handlers, _name).append(_recorder(_name))


def _glint_state():
    try:
        import glint.state as st
    except ImportError:
        return None
    return st.STATE


def _glint_status():
    st = _glint_state()
    last = st.last if st is not None else None
    return None if last is None else {"status": last.status, "message": last.message, "backend": last.backend,
                                      "frame": last.frame, "timings": last.timings_ms}


def _override(win, area_type=None):
    area = next(a for a in win.screen.areas if area_type is None or a.type == area_type)
    region = next((rg for rg in area.regions if rg.type == "WINDOW"), area.regions[0])
    return bpy.context.temp_override(window=win, area=area, region=region)


def _main_window():
    return bpy.context.window_manager.windows[0]


def _biggest_area():
    return max(_main_window().screen.areas, key=lambda a: a.width * a.height)


def _open_glint_panel():
    """The main window's biggest area becomes Render Properties with Glint's panel
    open (it is DEFAULT_CLOSED) and its draws recorded; returns False until the
    editor has been drawn once (its tabs exist from then on)."""
    area = _biggest_area()
    if area.type != "PROPERTIES":
        area.type = "PROPERTIES"
        return False
    try:
        area.spaces.active.context = "RENDER"
    except TypeError:
        # The tabs are made by the editor's first draw, which a busy machine (CI
        # runs two Blenders at once) may not have done one tick later: the enum
        # has no "RENDER" yet. Wait for it, a while.
        if time.monotonic() - T0 > 30:
            raise
        return False
    try:
        import glint.ui as ui
    except ImportError:
        return True
    for cls in reversed(ui.CLASSES):
        bpy.utils.unregister_class(cls)
    ui.GLINT_PT_render.bl_options = set()
    draw = ui.GLINT_PT_render.draw

    def recorded_draw(self, context):
        draw(self, context)
        st = _glint_state()
        cur = _current()
        if cur is not None:
            cur["panel_draws"].append({"t": _now(), "status": st.last.status if st.last else None,
                                       "busy": st.busy, "progress": st.progress,
                                       "cancel": st.busy or st.rendering})

    ui.GLINT_PT_render.draw = recorded_draw
    for cls in ui.CLASSES:
        bpy.utils.register_class(cls)
    return True


def _scroll_to_glint():
    win = _main_window()
    area = _biggest_area()
    region = next(rg for rg in area.regions if rg.type == "WINDOW")
    with bpy.context.temp_override(window=win, area=area, region=region):
        for _ in range(20):  # Glint's panel is the last but one of the Render tab
            bpy.ops.view2d.scroll_down(page=True)


def _info_reports():
    """The Info log's reports (what the status bar showed), via the Info editor's copy."""
    win = _main_window()
    area = min(win.screen.areas, key=lambda a: a.width * a.height)
    old = area.type
    area.type = "INFO"
    wm = bpy.context.window_manager
    wm.clipboard = ""
    try:
        with bpy.context.temp_override(window=win, area=area):
            bpy.ops.info.select_all(action="SELECT")
            bpy.ops.info.report_copy()
        return wm.clipboard.splitlines()
    finally:
        area.type = old


def _screenshots(tag):
    wm = bpy.context.window_manager
    for w, win in enumerate(wm.windows):
        if any(a.type == "IMAGE_EDITOR" for a in win.screen.areas):
            with _override(win, "IMAGE_EDITOR"):
                bpy.ops.image.view_all(fit_view=True)
        with _override(win):
            try:
                bpy.ops.screen.screenshot(filepath=os.path.join(OUT, f"window_{w}_{tag}.png"))
            except Exception as exc:
                result["errors"].append(f"screenshot {w}: {exc}")


def _writes_allowed():
    """Whether Python may write to ID data, and call operators, at this moment.
    Blender forbids both while a read-only Python callback runs (a panel's draw,
    a Python render engine's method such as Cycles'), with one process-wide flag
    that each callback saves, sets and restores. Callbacks on the render thread
    and the main thread interleave (the GIL changes hands between them), so the
    flag can stay set after a render, for good: a timer, which is no callback of
    that kind, never sees it cleared. Tried with a write of the value already there."""
    try:
        r.image_settings.file_format = r.image_settings.file_format
    except AttributeError as exc:
        if writes.refused(exc):
            return False
        raise
    return True


def _with_writes(fn):
    """fn(), where it may write to the scene and call operators: where Blender
    refuses them, through the add-on's property update, which runs with writes
    allowed whatever the flag says (glint.host.writes.run; docs/addon.md,
    *Writes Blender refuses*)."""
    if _writes_allowed():
        return fn()
    _current()["writes_refused"] = _current().get("writes_refused", 0) + 1
    return writes.run(fn)


class GLINT_TEST_OT_read_only(bpy.types.Operator):
    """Its poll is a read-only callback: Blender sets the flag around it. Called
    on the main thread, it calls itself on another thread and returns once that
    call is inside; that one returns when _end_nested_poll says so."""
    bl_idname = "glint_test.read_only"
    bl_label = "Read-only callback"

    inside = threading.Event()
    release = threading.Event()
    thread = None

    @classmethod
    def poll(cls, context):
        if threading.current_thread() is threading.main_thread():
            _start_nested_poll()
        else:
            cls.inside.set()
            cls.release.wait(10)
        return False

    def execute(self, context):
        return {"FINISHED"}


bpy.utils.register_class(GLINT_TEST_OT_read_only)


class GLINT_TEST_OT_hold(bpy.types.Operator):
    """Its poll holds Blender's read-only flag for ``seconds``, sleeping (which
    lets the render thread's Python run meanwhile)."""
    bl_idname = "glint_test.hold"
    bl_label = "Hold a read-only callback"

    seconds = 0.0
    holding = threading.Event()

    @classmethod
    def poll(cls, context):
        cls.holding.set()
        time.sleep(cls.seconds)
        return False

    def execute(self, context):
        return {"FINISHED"}


bpy.utils.register_class(GLINT_TEST_OT_hold)
_hold_request = threading.Event()
_f12_returned = threading.Event()


def _first_render_init(*args):
    """First of the render_init handlers, on the render thread. It waits for
    the F12 call to return: made from a property update (_with_writes), the
    call runs with writes allowed, and a render thread started inside it must
    not see that. When the step asks, it then waits until the main thread
    holds the flag, so that the handlers after this one (Glint's) run while
    it does."""
    _f12_returned.wait(10)
    cur = _current()
    if cur is None or not RENDERS[len(result["renders"]) - 1].get("hold_read_only"):
        return
    GLINT_TEST_OT_hold.holding.clear()
    _hold_request.set()
    if GLINT_TEST_OT_hold.holding.wait(10):
        cur["hold_met"] = _now()


bpy.app.handlers.render_init.insert(0, _first_render_init)


def _hold_read_only(seconds):
    _hold_request.clear()
    GLINT_TEST_OT_hold.seconds = seconds
    start = _now()
    bpy.ops.glint_test.hold.poll()
    _current()["held"] = [start, _now()]


def _start_nested_poll():
    op = GLINT_TEST_OT_read_only
    op.inside.clear()
    op.release.clear()
    op.thread = threading.Thread(target=bpy.ops.glint_test.read_only.poll)
    op.thread.start()
    if not op.inside.wait(10):
        raise RuntimeError("the poll on the other thread never ran")


def _end_nested_poll():
    op = GLINT_TEST_OT_read_only
    op.release.set()
    op.thread.join()


def _leave_read_only():
    """Nest two callbacks across threads so that they end out of order: the
    main thread's read-only poll saves 'writable' and sets read-only; the other
    thread's saves 'read-only'; the main thread's ends first and restores
    'writable', the other's ends last and restores 'read-only', which nothing
    clears. A Cycles render and the panels drawn meanwhile can do the same.
    False where the flag is one per thread (Blender 5.x), which this cannot set."""
    bpy.ops.glint_test.read_only.poll()
    _end_nested_poll()
    return not _writes_allowed()


def _end_read_only():
    """The same nesting the other way round, so that Blender's own add-ons can
    unregister when it quits: the outer callback is a property update, which
    saves 'read-only' and allows writes; the other thread's poll saves 'writable'
    and, ending last, restores it."""
    _with_writes(_start_nested_poll)
    _end_nested_poll()
    if not _writes_allowed():
        raise RuntimeError("Blender is still read-only")


def _collect(i, step):
    cur = _current()
    cur["glint"] = _glint_status()
    cur["job_running"] = bpy.app.is_job_running("RENDER")
    if step.get("check"):
        cur["check"] = eval(step["check"])
    img = bpy.data.images.get("Render Result")
    cur["has_render_result"] = img is not None
    if img is not None:
        try:
            img.save_render(os.path.join(OUT, f"render_{i}.exr"), scene=scene)
        except Exception as exc:
            result["errors"].append(f"save_render render_{i}.exr: {exc}")


def _finish():
    st = _glint_state()
    if st is not None:
        with st.lock:
            result["glint_messages"] = list(st.messages)
    try:
        import glint.native as native
        result["native_error"] = native.error()
    except ImportError:
        pass
    try:
        result["info_reports"] = _info_reports()
    except Exception as exc:
        result["errors"].append(f"info reports: {exc}")
    result["windows"] = [{"screen": w.screen.name, "areas": [a.type for a in w.screen.areas]}
                         for w in bpy.context.window_manager.windows]


def _write():
    with open(os.path.join(OUT, "result.json"), "w") as f:
        json.dump(result, f, indent=1, default=str)


state = {"phase": "panel", "index": 0}
SHOTS = cfg.get("screenshot", True)


def tick():
    try:
        return _tick()
    except Exception:
        result["errors"].append(traceback.format_exc())
        _write()
        os._exit(3)


def _tick():
    phase = state["phase"]
    i = state["index"]
    if phase == "panel":
        if SHOTS and not _open_glint_panel():
            return 0.2
        state["phase"] = "scroll"
        return 0.2
    if phase == "scroll":
        if SHOTS:
            _scroll_to_glint()
        state["phase"] = "f12"
        return 0.2
    if phase == "f12":
        step = RENDERS[i]
        result["renders"].append({"events": [], "panel_draws": []})

        _with_writes(lambda: exec(step.get("python", ""), dict(globals())))
        if step.get("read_only"):
            _current()["read_only"] = _leave_read_only()

        def f12():
            _event("F12")  # before the call: the render thread starts within it
            with _override(_main_window()):
                return bpy.ops.render.render("INVOKE_DEFAULT", animation=bool(step.get("animation")))
        _f12_returned.clear()
        try:
            _current()["invoke"] = sorted(_with_writes(f12))
        finally:
            _f12_returned.set()
        state.update(phase="rendering", started=time.monotonic())
        return 0.05
    if phase == "rendering":
        step, cur, st = RENDERS[i], _current(), _glint_state()
        if _hold_request.is_set():  # asked for from render_init (_first_render_init)
            _hold_read_only(step["hold_read_only"])
        # True: once the panel has drawn the export's progress; "drawn": once it has
        # drawn the Cancel button in this render (Blender 5.x draws nothing new
        # while the export runs).
        when = step.get("cancel_when_busy")
        shown = any(d["progress"] if when is True else d["cancel"] for d in cur["panel_draws"])
        if when and st is not None and st.busy and shown and not state.get("cancelled"):
            # What the panel's "Cancel Glint" button runs, on the main thread, mid-export.
            # Called with no context override: Blender 3.4 looks a Python override
            # up without the GIL when another thread runs Python, and a render
            # thread in a handler then crashes it (see docs/addon.md, *Reports
            # from a render*). The operator needs no window.
            state["cancelled"] = True
            _event("cancel_glint", progress=st.progress)
            bpy.ops.glint.cancel()
        ended = any(e["event"] in ("render_complete", "render_cancel") for e in cur["events"])
        if ended and not bpy.app.is_job_running("RENDER"):
            state.update(phase="settle", settle=time.monotonic())
            return 0.1
        if time.monotonic() - state["started"] > cfg.get("timeout", 60):
            cur["timeout"] = True
            _finish()
            _write()
            os._exit(4)
        return 0.05
    if phase == "settle":
        # A few redraws of the render window and the panel before looking at them.
        if time.monotonic() - state["settle"] < 0.6:
            return 0.1
        if "collected" not in _current():
            _collect(i, RENDERS[i])
            _current()["collected"] = _now()
        # The screenshots, the next step's code and F12, and the Info log at the
        # end all write or call operators.
        if SHOTS:
            _with_writes(lambda: _screenshots(str(i)))
        state["index"] = i + 1
        state["phase"] = "f12" if i + 1 < len(RENDERS) else "done"
        return 0.1

    if not _writes_allowed():
        _end_read_only()

    def finish():
        _finish()
        _write()
        with _override(_main_window()):
            bpy.ops.wm.quit_blender()
    _with_writes(finish)
    return None


bpy.app.timers.register(tick, first_interval=0.3)

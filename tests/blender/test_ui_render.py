"""F12 in Blender's UI, not ``-b``: Blender with a window under Xvfb (Mesa's llvmpipe
through GLX), the render started the way the F12 key starts it
(``render.render('INVOKE_DEFAULT')`` in the window's context, see ui_driver.py), so
it runs as a job on its own thread with Glint's handlers on that thread while the
UI stays live. Checks: the frame in the Render Result has the reflections for Eevee,
Cycles and Workbench, against a render with Glint unticked in the same session and
against where Blender's world_to_camera_view puts the objects' mirror images; an
error (no native module) renders the plain frame with a report in the Info log and
the panel; a compositor set-up changed by the user is repaired on the main thread;
Glint's Cancel button stops a long export mid-render.

Skipped when ``xvfb-run`` is not installed (Debian: ``apt-get install xvfb xauth``;
scripts/setup.sh installs both).
"""
import json
import os
import shutil
import subprocess
import uuid

import numpy as np
import pytest

from glint_blender_helpers import (BLENDER, HERE, MIRROR_OBJECTS, ROOT, SIZE, Blender, core, dilate, erode,
                                   hull_mask)

pytestmark = pytest.mark.blender

XVFB_RUN = shutil.which("xvfb-run")
UI_DRIVER = os.path.join(HERE, "ui_driver.py")
PILLARS = [f"Pillar {i}" for i in range(4)]


@pytest.fixture(scope="module")
def xvfb(blender_ok):
    if XVFB_RUN is None:
        pytest.skip("xvfb-run not installed (apt-get install xvfb xauth): F12 needs Blender with a window")
    return XVFB_RUN


def crash_report(out: str) -> str:
    """Blender's own crash report (``<file>.crash.txt`` in TMPDIR, which run_ui sets
    to ``out``): its backtrace says whose code crashed, which the log cannot."""
    text = ""
    for name in sorted(os.listdir(out)):
        if name.endswith(".crash.txt"):
            with open(os.path.join(out, name), errors="replace") as f:
                text += f"\n--- {name}:\n{f.read()[-6000:]}"
    return text


def driver_errors(path: str) -> str:
    """What ui_driver.py caught before it exited with status 3 (it writes its
    tracebacks to result.json, not to the log)."""
    if not os.path.isfile(path):
        return ""
    try:
        with open(path) as f:
            errors = json.load(f).get("errors") or []
    except ValueError as exc:
        return f"\n--- result.json unreadable: {exc}"
    return "".join(f"\n--- ui_driver error:\n{e}" for e in errors)


def run_ui(setup, blend, out, config, timeout=150):
    """One Blender session with a window; returns (result dict, log)."""
    os.makedirs(out, exist_ok=True)
    cfg = {"out": out, "size": list(SIZE), "eevee_samples": 4, "cycles_samples": 4}
    cfg.update(config)
    cfg_path = os.path.join(out, f"ui-{uuid.uuid4().hex[:8]}.json")
    with open(cfg_path, "w") as f:
        json.dump(cfg, f)
    env = dict(setup.env, TMPDIR=out)  # Blender's quit.blend goes there
    cmd = [XVFB_RUN, "-a", "-s", "-screen 0 1280x800x24", BLENDER, "--factory-startup", "-noaudio", blend,
           "--addons", "glint", "--python", UI_DRIVER, "--", cfg_path]
    proc = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                          timeout=timeout)
    log = proc.stdout
    with open(os.path.join(out, "blender.log"), "w") as f:
        f.write(log)
    path = os.path.join(out, "result.json")
    assert proc.returncode == 0 and os.path.isfile(path), \
        f"Blender with a window failed or hung (exit {proc.returncode}):\n{log[-4000:]}{driver_errors(path)}" \
        f"{crash_report(out)}"
    with open(path) as f:
        res = json.load(f)
    assert not res["errors"], res["errors"]
    assert "Traceback" not in log, log[-4000:]
    # Every report Glint showed waited for the render job to end.
    assert not any(r["job_running"] for r in res["reports_shown"]), res["reports_shown"]
    return res, log


def frame(out, i):
    return core().read_exr(os.path.join(out, f"render_{i}.exr"))[0][""]


def assert_f12_ran_on_the_render_thread(render):
    events = [e["event"] for e in render["events"]]
    assert events[0] == "F12" and render["invoke"] == ["RUNNING_MODAL"], events
    assert events[-1] == "render_complete", events
    for name in ("render_init", "render_pre", "frame_change_post"):
        calls = [e for e in render["events"] if e["event"] == name]
        assert calls and not any(e["main_thread"] for e in calls), (name, calls)
    assert render["has_render_result"] and not render["job_running"]


def change_masks(res, names, w, h, spread):
    """Where Glint may change the frame: the objects' mirror images and the band
    between each object and its image (test_reflections explains the band), grown
    by ``spread`` pixels (2, plus the blur size where rough surfaces blur it)."""
    mirror, band, objects = (np.zeros((h, w), bool) for _ in range(3))
    for name in names:
        real, image = res["objects"][name]["real"], res["objects"][name]["mirror"]
        mirror |= hull_mask(image, w, h)
        band |= hull_mask(np.concatenate([real, image]), w, h)
        objects |= hull_mask(real, w, h)
    return dilate(mirror, spread), dilate(band, spread) & ~erode(objects, 2)


def assert_reflections(on, off, res, names, red_object=None, spread=2):
    h, w = on.shape[:2]
    changed = np.abs(on[..., :3] - off[..., :3]).max(axis=-1) > 0.02
    mirror, allowed = change_masks(res, names, w, h, spread)
    assert changed.sum() > 50, "Glint changed nothing: no reflections in the Render Result"
    outside = changed & ~allowed
    assert outside.sum() == 0, f"{outside.sum()} pixels changed where nothing is reflected"
    assert (changed & mirror).sum() / changed.sum() > 0.6
    if red_object:
        # The red sphere's mirror image: red with Glint, not without.
        image = hull_mask(res["objects"][red_object]["mirror"], w, h) & ~dilate(
            hull_mask(res["objects"][red_object]["real"], w, h), 2)
        m_on, m_off = on[image, :3].mean(axis=0), off[image, :3].mean(axis=0)
        assert m_on[0] > 2.0 * m_on[1] and m_on[0] > 2.0 * m_on[2], m_on
        assert not m_off[0] > 2.0 * m_off[1], m_off
        assert m_on[0] > m_off[0] + 0.05, (m_on, m_off)


def assert_panel_showed(render, status):
    """The Glint panel was drawn with the frame's status after the render ended."""
    end = next(e["t"] for e in render["events"] if e["event"] == "render_complete")
    assert any(d["t"] >= end and d["status"] == status for d in render["panel_draws"]), render["panel_draws"]


def skip_unless_left_read_only(render):
    if not render["read_only"]:
        pytest.skip("this Blender keeps the read-only flag per thread: two threads' callbacks cannot leave it set")


TICK_AND_RENDER = [{"python": "scene.glint.enabled = False"}, {"python": "scene.glint.enabled = True"}]


@pytest.mark.parametrize("sample, engine, names, red, spread", [
    ("mirror_floor", "Eevee", MIRROR_OBJECTS, "Red Sphere", 2),
    ("ortho_camera", "Workbench", MIRROR_OBJECTS, "Red Sphere", 2),
])
def test_f12_composites_reflections(xvfb, blender, samples, tmp_path, sample, engine, names, red, spread):
    """Untick Glint, F12; tick it, F12: the second Render Result has the reflections."""
    out = str(tmp_path / sample)
    res, log = run_ui(blender, samples[sample], out, {"renders": TICK_AND_RENDER, "mirror_objects": names})
    off_render, on_render = res["renders"]
    for render in res["renders"]:
        assert_f12_ran_on_the_render_thread(render)
    assert on_render["glint"]["status"] == "ok", on_render["glint"]
    assert "Glint: frame 1: reflections composited" in log
    assert_panel_showed(on_render, "ok")
    assert_reflections(frame(out, 1), frame(out, 0), res, names, red, spread)
    assert not res["info_reports"], res["info_reports"]


# A value of Glint's group set wrong after Glint was ticked (so that the
# enable's own set-up does not correct it), as a material's edit leaves the
# blur's switch: render_init must write it back.
DESYNC_GROUP = ("from glint import compositor as gc; n = gc.find_group().nodes['use_blur']; "
                "hn.set_switch(n, not hn.switch_is_on(n))")


def test_f12_while_a_panel_draws_writes_the_groups_values_once_it_ends(xvfb, blender, samples, tmp_path):
    """Up to 4.x a Python panel drawn on the main thread makes Blender refuse the
    render thread's writes meanwhile (docs/addon.md, *Writes Blender refuses*):
    render_init writes the group's values once the draw has ended."""
    out = str(tmp_path / "held")
    renders = [TICK_AND_RENDER[0],
               dict(python=TICK_AND_RENDER[1]["python"] + "; " + DESYNC_GROUP, hold_read_only=1.0)]
    res, log = run_ui(blender, samples["mirror_floor"], out, {"renders": renders, "mirror_objects": MIRROR_OBJECTS})
    on_render = res["renders"][1]
    start, end = on_render["held"]
    assert start <= on_render["hold_met"] <= end, on_render  # Glint's render_init began within the draw
    assert on_render["glint"]["status"] == "ok", on_render["glint"]
    assert_reflections(frame(out, 1), frame(out, 0), res, MIRROR_OBJECTS, "Red Sphere")


def test_f12_composites_reflections_in_a_blender_left_read_only(xvfb, blender, samples, tmp_path):
    """Callbacks on two threads can leave Blender refusing Python's writes for the
    rest of the session (docs/addon.md, *Writes Blender refuses*). A render after
    that still gets its reflections: Glint's render-thread writes are not refused.
    A render whose compositor values must change first renders without them, says
    so, and the main thread writes them: the next render has them."""
    out = str(tmp_path / "read_only")
    stuck = "__import__('glint.state', fromlist=['STATE']).STATE.writes_stuck"
    renders = [dict(TICK_AND_RENDER[0], check=stuck), dict(TICK_AND_RENDER[1], read_only=True),
               {"python": DESYNC_GROUP, "check": stuck}, {}]
    res, log = run_ui(blender, samples["mirror_floor"], out, {"renders": renders, "mirror_objects": MIRROR_OBJECTS})
    off, on, desynced, again = res["renders"]
    skip_unless_left_read_only(on)
    assert on["writes_refused"] >= 2 and desynced["writes_refused"] >= 2, res["renders"]  # F12, screenshots
    assert on["glint"]["status"] == "ok", on["glint"]
    assert_reflections(frame(out, 1), frame(out, 0), res, MIRROR_OBJECTS, "Red Sphere")
    assert desynced["glint"]["status"] == "error", desynced["glint"]
    assert "Blender refused Python's writes" in desynced["glint"]["message"]
    assert off["check"] is False and desynced["check"] is True  # the panel's warning
    assert "Glint: Blender refuses Python's writes to its data from timers and handlers" in log
    assert np.array_equal(frame(out, 2), frame(out, 0)), "the frame is not the plain render"
    assert again["glint"]["status"] == "ok", again["glint"]
    assert_reflections(frame(out, 3), frame(out, 0), res, MIRROR_OBJECTS, "Red Sphere")


def test_f12_in_cycles_leaves_its_true_reflections_alone(xvfb, blender, samples, tmp_path):
    """Cycles path-traces its reflections: ticking Glint changes nothing and says why."""
    out = str(tmp_path / "cycles")
    res, log = run_ui(blender, samples["metals_roughness"], out, {"renders": TICK_AND_RENDER,
                                                                  "mirror_objects": PILLARS})
    on_render = res["renders"][1]
    assert on_render["glint"]["status"] == "skipped", on_render["glint"]
    assert "Cycles traces true reflections" in on_render["glint"]["message"]
    assert np.array_equal(frame(out, 1), frame(out, 0)), "Glint changed a Cycles frame"
    assert not res["info_reports"], res["info_reports"]


@pytest.mark.parametrize("read_only", [False, True], ids=["writable", "read_only"])
def test_f12_without_native_module_reports_and_renders_the_plain_frame(xvfb, samples, tmp_path, read_only):
    """The report reaches the Info log even where Blender has left Python's
    writes and operator calls refused (host/writes.py)."""
    b = Blender(str(tmp_path / "home"), core_path=False, link_addon=False)
    # A plain copy (not a symlink into the checkout, which would find the build).
    shutil.copytree(os.path.join(ROOT, "addon", "glint"), os.path.join(b.scripts, "addons", "glint"),
                    ignore=shutil.ignore_patterns("__pycache__", "native"))
    empty = tmp_path / "empty"
    empty.mkdir()
    b.env["GLINT_CORE_PATH"] = str(empty)
    out = str(tmp_path / "out")
    renders = [TICK_AND_RENDER[0], dict(TICK_AND_RENDER[1], read_only=read_only)]
    res, log = run_ui(b, samples["mirror_floor"], out, {"renders": renders})
    on_render = res["renders"][1]
    if read_only:
        skip_unless_left_read_only(on_render)
    assert_f12_ran_on_the_render_thread(on_render)
    assert on_render["glint"]["status"] == "error"
    assert "the native module glint_core was not found" in on_render["glint"]["message"]
    assert "Glint: frame 1: rendered WITHOUT reflections: the native module glint_core was not found" in log
    assert any(line.startswith("Glint: rendered without reflections: the native module glint_core was not found")
               for line in res["info_reports"]), res["info_reports"]
    assert_panel_showed(on_render, "error")
    assert np.array_equal(frame(out, 1), frame(out, 0)), "the frame is not the plain render"


def test_f12_after_the_user_deleted_glints_node_repairs_it(xvfb, blender, samples, tmp_path):
    """The render thread does not add nodes: that frame is plain and reported, the main
    thread restores the set-up, and the next F12 has the reflections."""
    out = str(tmp_path / "repair")
    delete = ("t = hn.scene_tree(scene); t.nodes.remove(t.nodes['Glint']); "
              "t.links.new(t.nodes['Render Layers'].outputs['Image'], hn.frame_outputs(t)[0])")
    nodes = ("sorted(n.name for n in hn.scene_tree(scene).nodes "
             "if n.name not in {x.node.name for x in hn.frame_outputs(hn.scene_tree(scene))})")
    res, log = run_ui(blender, samples["mirror_floor"], out, {
        "mirror_objects": MIRROR_OBJECTS,
        "renders": [{"python": delete, "check": nodes}, {"check": nodes}]})
    first, second = res["renders"]
    assert first["glint"]["status"] == "error" and "the Glint node is missing" in first["glint"]["message"]
    # restored after the render (the sample's world is one colour: S from the world nodes)
    # (the frame's output, Composite or Group Output, left out: its name is the host's)
    assert first["check"] == ["Glint", "Glint World Colour", "Glint World Weight", "Render Layers"]
    assert any("the Glint node is missing" in line for line in res["info_reports"]), res["info_reports"]
    assert second["glint"]["status"] == "ok"
    assert_reflections(frame(out, 1), frame(out, 0), res, MIRROR_OBJECTS, "Red Sphere")


# 60 distinct meshes of 40k triangles: an export of ~2 s (~0.9 us a triangle), long
# enough for the panel to show its progress (reported at most once a second).
HEAVY = """
import bmesh
base = bpy.data.meshes.new("heavy")
bm = bmesh.new()
bmesh.ops.create_uvsphere(bm, u_segments=200, v_segments=100, radius=0.1)
bm.to_mesh(base)
bm.free()
base.materials.append(bpy.data.objects["Red Sphere"].active_material)
for i in range(60):
    ob = bpy.data.objects.new(f"heavy{i}", base.copy())
    scene.collection.objects.link(ob)
    ob.location = (-2 + (i % 10) * 0.4, 0, 0.3 + (i // 10) * 0.25)
"""


def blender_major() -> int:
    text = subprocess.run([BLENDER, "--version"], stdout=subprocess.PIPE, stderr=subprocess.DEVNULL,
                          text=True).stdout
    return int(text.split()[1].split(".")[0]) if text.startswith("Blender ") else 0


def test_cancel_glint_stops_a_long_export_during_f12(xvfb, blender, samples, tmp_path):
    # Blender 5.x draws nothing while the export runs (its timers and operators
    # still run; docs/addon.md, Limitations): there render_pre lets the panel draw
    # Cancel Glint first, and the driver presses it once drawn, while the export runs.
    redraws_during_export = blender_major() < 5
    out = str(tmp_path / "cancel")
    res, log = run_ui(blender, samples["mirror_floor"], out, {
        "engine": "BLENDER_WORKBENCH", "python": HEAVY,
        "renders": [{"cancel_when_busy": True if redraws_during_export else "drawn"}]})
    render = res["renders"][0]
    assert_f12_ran_on_the_render_thread(render)
    if redraws_during_export:
        # The panel was redrawn during the export with its progress and the Cancel
        # button, which the driver then pressed.
        assert any(d["busy"] and d["progress"].startswith("export ") for d in render["panel_draws"]), \
            render["panel_draws"]
    else:
        # Drawn before the export began, from render_init on.
        assert any(d["cancel"] and not d["busy"] for d in render["panel_draws"]), render["panel_draws"]
    # Pressed while the export ran (the driver presses only then).
    assert any(e["event"] == "cancel_glint" for e in render["events"]), render["events"]
    assert render["glint"]["status"] == "cancelled", render["glint"]
    assert "Glint: frame 1: rendered WITHOUT reflections: Glint export cancelled at" in log
    assert any(line.startswith("Glint: rendered without reflections: Glint export cancelled")
               for line in res["info_reports"]), res["info_reports"]
    assert [r["level"] for r in res["reports_shown"]] == ["WARNING"], res["reports_shown"]

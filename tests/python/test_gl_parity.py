"""backend="gl" against backend="cpu", stage by stage, on identical inputs.

The inputs are exact G-buffers: analytic scenes ray-cast in float64 numpy
(analytic.py: a mirror floor, spheres, boxes, a wall; perspective, shifted
perspective, orthographic and a general projection -- a perspective one with
its clip coordinates scaled; many of the perspective rays are cut at the near
plane) and a sphere-over-floor triangle mesh
rasterized by the CPU reference. Each stage gets the same inputs on both
backends (the CPU's output of the previous stage), so a difference is that
stage's own. The shares of agreeing pixels are printed (pytest -s shows them)
and asserted:

* trace: uv within 1e-4 and visibility within 1e-3 on >= 99.0% of pixels. The
  march is a chain of hit/miss decisions; one rounding difference in the
  shader (a driver that fuses a multiply-add despite `precise`) can flip a
  decision and move a pixel's answer by whole texels, so a few pixels may
  differ without either being wrong. On llvmpipe the share is 100%.
* the hiz march's antialiased outlines (antialias=1 and 4, with and without
  the reuse of rays, with the back-face layer and blocked="occluder"): the
  trace's bar on the whole frame and on the pixels the outlines changed.
* every other stage: all channels within 1e-4 on >= 99.9% of pixels.
* rasterizer: coverage agrees on >= 99.5% of pixels; where both cover,
  positions within 1e-4 (relative to max(1, |p|)) on >= 99.9%.

Also: the EGL-missing path (simulated with GLINT_EGL_LIBRARY pointing at a
file that does not exist) raises the clear error and "auto" falls back to the
CPU; calls from several Python threads; a clean exit.

Runs on llvmpipe in CI in well under a minute (small images).
"""
from __future__ import annotations

import math
import os
import subprocess
import sys
import textwrap
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import analytic as A
from glint_tables import SCREEN_MARCHES

pytestmark = pytest.mark.gl

TRACE_SHARE = 0.99
STAGE_SHARE = 0.999


# --- inputs --------------------------------------------------------------------------

GLOSSY_FLOOR = A.Material(color=(0.35, 0.35, 0.4), specular=(0.9, 0.9, 0.9), alpha=0.7)
SHINY_SPHERE = A.Material(color=(0.9, 0.1, 0.1), specular=(0.4, 0.4, 0.4), alpha=0.3)

def _general(scene_fn, factor=2.5):
    """The scene with its projection's clip coordinates scaled: invertible, but
    neither the perspective nor the orthographic form (the marches' general path)."""
    def make():
        return scene_fn(), factor
    return make


SCENES = {
    "persp": lambda: A.mirror_floor_scene("persp"),
    "persp-rough": lambda: A.mirror_floor_scene("persp", floor=GLOSSY_FLOOR, sphere_material=SHINY_SPHERE),
    "persp-shift": lambda: A.mirror_floor_scene("persp", shift=(0.08, -0.05), floor=GLOSSY_FLOOR),
    "ortho": lambda: A.mirror_floor_scene("ortho"),
    "ortho-rough": lambda: A.mirror_floor_scene("ortho", floor=GLOSSY_FLOOR, sphere_material=SHINY_SPHERE),
    "general": _general(lambda: A.mirror_floor_scene("persp", floor=GLOSSY_FLOOR)),
}
SIZES = [(160, 90), (128, 96)]


def uv_sphere(center, radius, n_lon, n_lat):
    """Triangles (T, 3, 3) and corner normals of a UV sphere, world space."""
    tris, nrms = [], []
    for i in range(n_lon):
        for j in range(n_lat):
            corners = []
            for a, b in ((i, j), (i + 1, j), (i + 1, j + 1), (i, j + 1)):
                th, ph = math.pi * b / n_lat, 2.0 * math.pi * a / n_lon
                n = np.array([math.sin(th) * math.cos(ph), math.sin(th) * math.sin(ph), math.cos(th)])
                corners.append((np.asarray(center) + radius * n, n))
            for k in ((0, 1, 2), (0, 2, 3)):
                tris.append([corners[q][0] for q in k])
                nrms.append([corners[q][1] for q in k])
    return np.array(tris), np.array(nrms)


def floor_grid(z, half, cells):
    xs = np.linspace(-half, half, cells + 1)
    tris, nrms = [], []
    for i in range(cells):
        for j in range(cells):
            a, b = (xs[i], xs[j], z), (xs[i + 1], xs[j], z)
            c, d = (xs[i + 1], xs[j + 1], z), (xs[i], xs[j + 1], z)
            tris += [[a, b, c], [a, c, d]]
            nrms += [[(0.0, 0.0, 1.0)] * 3] * 2
    return np.array(tris), np.array(nrms)


def mesh_inputs(kind, width, height):
    """A sphere on a floor as view-space triangles (about 3k), two materials."""
    st, sn = uv_sphere((-0.6, 0.6, 1.0), 0.8, 48, 24)
    ft, fn = floor_grid(0.0, 6.0, 24)
    scene = A.mirror_floor_scene(kind)
    vm = scene.camera.view_matrix()
    r, t = vm[:3, :3], vm[:3, 3]
    tris = np.concatenate([st, ft]) @ r.T + t
    nrms = np.concatenate([sn, fn]) @ r.T
    return {
        "positions": tris.astype(np.float32),
        "normals": nrms.astype(np.float32),
        "material_index": np.concatenate([np.zeros(len(st)), np.ones(len(ft))]).astype(np.int32),
        "materials": np.array([[0.4, 0.4, 0.4, 30.0], [0.9, 0.9, 0.9, 90.0]], np.float32),
        "projection": scene.camera.projection(width, height),
        "width": width,
        "height": height,
    }


def rasterized_gbuffer(glint, kind, width, height):
    """CPU-rasterized G-buffers of mesh_inputs, with a base colour per material."""
    m = mesh_inputs(kind, width, height)
    g = glint.rasterize(m["positions"], m["normals"], m["material_index"], m["materials"],
                        m["projection"], width, height, backend="cpu")
    seen = g["position"][..., 3] > 0
    color = np.zeros((height, width, 4), np.float32)
    color[..., 3] = 1.0
    color[..., :3] = np.where(seen[..., None], np.where(g["specular"][..., :1] > 0.5,
                                                        [0.3, 0.3, 0.35], [0.9, 0.2, 0.1]),
                              [0.05, 0.1, 0.3])
    return {"position": g["position"], "normal": g["normal"], "specular": g["specular"],
            "color": color, "projection": m["projection"]}


def gbuffers():
    for name, make in SCENES.items():
        for w, h in SIZES:
            yield pytest.param(name, w, h, id=f"{name}-{w}x{h}")
    for kind in ("persp", "ortho"):
        yield pytest.param(f"mesh-{kind}", 160, 90, id=f"mesh-{kind}-160x90")


_CACHE = {}


def gbuffer(glint, name, w, h):
    key = (name, w, h)
    if key not in _CACHE:
        if name.startswith("mesh-"):
            _CACHE[key] = rasterized_gbuffer(glint, name[5:], w, h)
        else:
            made = SCENES[name]()
            scene, factor = made if isinstance(made, tuple) else (made, 1.0)
            gb = A.render(scene, w, h, background=(0.05, 0.1, 0.3))
            gb["projection"] = gb["projection"] * factor
            _CACHE[key] = gb
    return _CACHE[key]


# --- comparison ----------------------------------------------------------------------


def share_trace(cpu, gl):
    uv_ok = np.abs(cpu[..., :2] - gl[..., :2]).max(axis=-1) <= 1e-4
    vis_ok = np.abs(cpu[..., 2:] - gl[..., 2:]).max(axis=-1) <= 1e-3
    return float((uv_ok & vis_ok).mean())


def share_stage(cpu, gl, tol=1e-4):
    return float((np.abs(cpu - gl).max(axis=-1) <= tol).mean())


def report(label, share, need, artifacts=None, cpu=None, gl=None):
    print(f"{label}: {share * 100:.3f}% of pixels agree (need {need * 100:.1f}%)")
    if artifacts is not None and share < need:
        artifacts.add(f"{label}-cpu", cpu)
        artifacts.add(f"{label}-gl", gl)
        artifacts.add(f"{label}-absdiff", np.abs(cpu - gl).max(axis=-1))
    assert share >= need, f"{label}: only {share * 100:.3f}% of pixels agree"


# --- stage by stage ----------------------------------------------------------------------


@pytest.mark.parametrize("march", SCREEN_MARCHES)
@pytest.mark.parametrize("name,w,h", list(gbuffers()))
def test_trace_matches_cpu(gl, name, w, h, march, artifacts):
    g = gbuffer(gl, name, w, h)
    args = (g["position"], g["normal"], g["projection"])
    for opts in ({}, {"max_distance": 6.0, "resolution": 0.8, "steps": 24, "thickness": 0.2},
                 {"resolution": 1.0, "steps": 8}):
        cpu = gl.trace(*args, march=march, backend="cpu", **opts)
        out = gl.trace(*args, march=march, backend="gl", **opts)
        assert out.dtype == np.float32 and out.shape == (h, w, 4)
        assert np.isfinite(out).all()
        assert (cpu[..., 2] > 0).sum() > 50, "the scene should reflect something"
        report(f"trace {march} {name} {w}x{h} {opts or 'defaults'}", share_trace(cpu, out), TRACE_SHARE,
               artifacts, cpu, out)


@pytest.mark.parametrize("name,w,h", list(gbuffers()))
def test_every_other_stage_matches_cpu(gl, name, w, h, artifacts):
    g = gbuffer(gl, name, w, h)
    uv = gl.trace(g["position"], g["normal"], g["projection"], backend="cpu")

    def both(label, fn, *args, **kw):
        cpu, out = fn(*args, backend="cpu", **kw), fn(*args, backend="gl", **kw)
        assert out.dtype == np.float32 and out.shape == cpu.shape
        report(f"{label} {name} {w}x{h}", share_stage(cpu, out), STAGE_SHARE, artifacts, cpu, out)
        return cpu

    color = both("reflection_color", gl.reflection_color, uv, g["color"])
    for size, sep in ((4, 1.0), (3, 2.5)):
        blurred = both(f"box_blur size={size} sep={sep}", gl.box_blur, color, size=size, separation=sep)
    blurred = gl.box_blur(color, backend="cpu")
    refl = both("reflection", gl.reflection, color, blurred, g["specular"])
    for mode in ("over", "seed"):
        both(f"combine {mode}", gl.combine, g["color"], refl, mode=mode)


@pytest.mark.parametrize("name,w,h", [("persp-rough", 160, 90), ("ortho-rough", 128, 96), ("mesh-persp", 160, 90)])
@pytest.mark.parametrize("march", SCREEN_MARCHES)
def test_pipeline_layers_match_cpu(gl, name, w, h, march, artifacts):
    g = gbuffer(gl, name, w, h)
    args = (g["position"], g["normal"], g["specular"], g["color"], g["projection"])
    cpu = gl.pipeline(*args, march=march, backend="cpu")
    out = gl.pipeline(*args, march=march, backend="gl")
    assert out["stats"]["backend"] == "gl" and cpu["stats"]["backend"] == "cpu"
    assert cpu["stats"]["reflective_pixels"] == out["stats"]["reflective_pixels"] > 0
    for layer in gl.LAYERS:
        need = TRACE_SHARE if layer == "uv" else STAGE_SHARE
        share = share_trace(cpu[layer], out[layer]) if layer == "uv" else share_stage(cpu[layer], out[layer])
        report(f"pipeline {march} {name} {w}x{h} layer {layer}", share, need, artifacts, cpu[layer], out[layer])


# --- the hiz march's antialiased outlines ------------------------------------------------


def analytic_back_layer(name, w, h):
    """The back-face layer of an analytic scene's G-buffer (gbuffer())."""
    key = ("back", name, w, h)
    if key not in _CACHE:
        made = SCENES[name]()
        scene = made[0] if isinstance(made, tuple) else made
        _CACHE[key] = A.back_layer(scene, _CACHE[(name, w, h)]).astype(np.float32)
    return _CACHE[key]


@pytest.mark.parametrize("occluder", [False, True], ids=["plain", "back-occluder"])
@pytest.mark.parametrize("resolution", [1.0, 0.3], ids=["every-ray", "reused-rays"])
@pytest.mark.parametrize("antialias", [1, 4])
@pytest.mark.parametrize("name,w,h,gated,least", [("persp", 160, 90, False, 50), ("persp", 161, 91, False, 50),
                                                  ("ortho", 128, 96, True, 10),
                                                  ("ortho-rough", 128, 96, True, 0)])
def test_hiz_antialias_matches_cpu(gl, name, w, h, gated, least, antialias, resolution, occluder, artifacts):
    """The outline pixels' extra rays (march_hiz.cpp and cpu/outline.cpp, *Antialiased outlines*)
    on the GL passes against the CPU's, where the mirror floor shows the
    sphere's, the box's and the wall's outlines. The pixels the outlines
    change are a few percent of the frame, so they are also compared on
    their own: a GL trace that skipped them would still pass on the whole.
    On the glossy floor (gated by its specular) the cone blur spreads every
    outline over more than a pixel, and neither backend adds rays there."""
    g = gbuffer(gl, name, w, h)
    kw = dict(march="hiz", resolution=resolution, specular=g["specular"] if gated else None)
    if occluder:
        kw.update(back_position=analytic_back_layer(name, w, h), blocked="occluder")
    args = (g["position"], g["normal"], g["projection"])
    plain = gl.trace(*args, backend="cpu", antialias=0, **kw)
    cpu = gl.trace(*args, backend="cpu", antialias=antialias, **kw)
    out = gl.trace(*args, backend="gl", antialias=antialias, **kw)
    assert out.dtype == np.float32 and out.shape == (h, w, 4)
    assert np.isfinite(out).all()
    changed = (cpu != plain).any(axis=-1)
    assert changed.sum() >= least, "the outlines should change some pixels"
    if occluder:
        assert ((cpu[..., 2] > 0) & (cpu[..., 3] <= 0)).sum() >= 5, "the scene should block some rays"
    label = f"trace hiz antialias={antialias} {name} {w}x{h} res={resolution}{' occluder' if occluder else ''}"
    report(label, share_trace(cpu, out), TRACE_SHARE, artifacts, cpu, out)
    if changed.any():
        report(f"{label} ({int(changed.sum())} changed pixels)", share_trace(cpu[changed], out[changed]),
               TRACE_SHARE, artifacts, cpu, out)


# --- the rasterizer ---------------------------------------------------------------------


@pytest.mark.parametrize("kind", ["persp", "ortho"])
@pytest.mark.parametrize("w,h", SIZES)
def test_rasterizer_matches_cpu(gl, kind, w, h, artifacts):
    m = mesh_inputs(kind, w, h)
    args = (m["positions"], m["normals"], m["material_index"], m["materials"], m["projection"], w, h)
    assert len(m["positions"]) > 2000
    cpu = gl.rasterize(*args, backend="cpu")
    out = gl.rasterize(*args, backend="gl")
    ca, cb = cpu["position"][..., 3] > 0, out["position"][..., 3] > 0
    assert ca.sum() > w * h // 4
    report(f"raster {kind} {w}x{h} coverage", float((ca == cb).mean()), 0.995, artifacts,
           cpu["position"], out["position"])
    both = ca & cb
    p_cpu, p_gl = cpu["position"][both][:, :3], out["position"][both][:, :3]
    rel = np.abs(p_cpu - p_gl).max(axis=1) / np.maximum(1.0, np.abs(p_cpu).max(axis=1))
    print(f"raster {kind} {w}x{h}: largest relative position difference {rel.max():.2e}")
    report(f"raster {kind} {w}x{h} positions", float((rel <= 1e-4).mean()), STAGE_SHARE)
    n_err = np.abs(cpu["normal"][both] - out["normal"][both]).max(axis=1)
    report(f"raster {kind} {w}x{h} normals (1e-3)", float((n_err <= 1e-3).mean()), STAGE_SHARE)
    assert np.array_equal(cpu["specular"][both], out["specular"][both])
    # Unseen pixels are all zeros on both.
    for layer in ("position", "normal", "specular"):
        assert not out[layer][~cb].any()


@pytest.mark.parametrize("kind", ["persp", "ortho"])
@pytest.mark.parametrize("w,h", SIZES)
def test_rasterizer_back_albedo_matches_cpu(gl, kind, w, h, artifacts):
    """back_albedo is copied from the material table, so where both backends
    find a back surface they give the same bits. The sphere's triangles take
    three materials in turn, so a triangle looked up wrongly shows."""
    m = mesh_inputs(kind, w, h)
    index = m["material_index"].copy()
    sphere = index == 0
    index[sphere] = np.arange(sphere.sum()) % 3
    index[~sphere] = 3
    # uv_sphere winds its triangles inward: turned outward, its far side is
    # the back layer.
    positions = m["positions"].copy()
    positions[sphere] = positions[sphere][:, ::-1]
    normals = m["normals"].copy()
    normals[sphere] = normals[sphere][:, ::-1]
    materials = np.repeat(m["materials"][:1], 4, axis=0)
    albedo = np.array([[0.9, 0.2, 0.1], [0.1, 0.8, 0.2], [0.2, 0.3, 1.25], [0.5, 0.5, 0.5]], np.float32)
    args = (positions, normals, index, materials, m["projection"], w, h)
    cpu = gl.rasterize(*args, back_layer=True, material_albedo=albedo, backend="cpu")
    out = gl.rasterize(*args, back_layer=True, material_albedo=albedo, backend="gl")
    ca, cb = cpu["back_position"][..., 3] > 0, out["back_position"][..., 3] > 0
    assert ca.sum() > 200
    report(f"raster {kind} {w}x{h} back coverage", float((ca == cb).mean()), 0.995, artifacts,
           cpu["back_position"], out["back_position"])
    both = ca & cb
    assert np.array_equal(cpu["back_albedo"][both], out["back_albedo"][both])
    assert len(np.unique(out["back_albedo"][both][:, 0])) == 3  # the sphere's three, not the floor's
    assert not out["back_albedo"][~cb].any()


# --- context, errors, threads -----------------------------------------------------------


def test_auto_picks_gl_and_says_so(gl):
    assert gl.backend_name("auto") == "gl"
    assert gl.backend_name("gl") == "gl"


def _run_python(code, **env):
    import glint_core

    full_env = dict(os.environ, **env)
    full_env["PYTHONPATH"] = os.path.dirname(glint_core.__file__) + os.pathsep + full_env.get("PYTHONPATH", "")
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], env=full_env, capture_output=True,
                          text=True, timeout=120)


def test_missing_egl_is_a_clear_error_and_auto_falls_back(glint):
    # Runs even without GL: it is the machine-without-EGL path.
    missing = "/nonexistent/glint-test/libEGL.so.1"
    proc = _run_python("""
        import numpy as np, glint_core as g
        pos = np.zeros((4, 4, 4), np.float32); nrm = np.zeros((4, 4, 3), np.float32)
        proj = np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, -1.002, -0.2], [0, 0, -1, 0]], np.float32)
        try:
            g.trace(pos, nrm, proj, backend="gl")
            print("NO ERROR")
        except g.BackendUnavailable as e:
            print("ERROR:", e)
        print("AUTO:", g.backend_name("auto"))
        out = g.pipeline(pos, nrm, np.ones((4, 4, 4), np.float32), np.ones((4, 4, 4), np.float32), proj,
                         backend="auto")
        print("PIPELINE:", out["stats"]["backend"])
    """, GLINT_EGL_LIBRARY=missing)
    assert proc.returncode == 0, proc.stderr
    lines = dict(line.split(": ", 1) for line in proc.stdout.splitlines() if ": " in line)
    if not glint.gl_compiled_in():
        assert "no OpenGL backend" in lines["ERROR"]
    else:
        assert missing in lines["ERROR"], proc.stdout
        assert "cannot load the EGL library" in lines["ERROR"], proc.stdout
        assert "GLINT_EGL_LIBRARY" in lines["ERROR"], proc.stdout
    assert lines["AUTO"] == "cpu"
    assert lines["PIPELINE"] == "cpu"


_PROBE = """
    import glint_core as g
    try:
        print("BACKEND:", g.backend_name("gl"))
    except g.BackendUnavailable as e:
        print("ERROR:", e)
    print("AUTO:", g.backend_name("auto"))
"""


def _probe(**env):
    proc = _run_python(_PROBE, **env)
    assert proc.returncode == 0, proc.stderr
    return dict(line.split(": ", 1) for line in proc.stdout.splitlines() if ": " in line)


def test_gl_too_old_names_the_version_found(gl):
    # Simulated with Mesa's version override; other drivers ignore the variable.
    out = _probe(MESA_GL_VERSION_OVERRIDE="3.3")
    if "BACKEND" in out:
        pytest.skip("this driver ignores MESA_GL_VERSION_OVERRIDE")
    assert "OpenGL 4.3 core is needed" in out["ERROR"], out
    assert "3.3" in out["ERROR"], out
    assert out["AUTO"] == "cpu"


def test_no_egl_display_is_a_clear_error(gl):
    # Simulated by pointing libglvnd at no EGL vendor: libEGL loads, but no
    # driver stands behind it. Skipped where EGL is not libglvnd's.
    out = _probe(__EGL_VENDOR_LIBRARY_FILENAMES="/nonexistent/glint-test-vendor.json")
    if "BACKEND" in out:
        pytest.skip("this EGL is not libglvnd's (the vendor variable had no effect)")
    assert "OpenGL backend unavailable" in out["ERROR"], out
    assert "display" in out["ERROR"], out
    assert out["AUTO"] == "cpu"


def test_process_using_gl_exits_cleanly(gl):
    proc = _run_python("""
        import threading, numpy as np, glint_core as g
        img = np.random.default_rng(0).random((30, 40, 4)).astype(np.float32)
        a = g.box_blur(img, backend="gl")
        # From another thread too: the context lives on its own worker thread.
        t = threading.Thread(target=lambda: g.box_blur(img, backend="gl")); t.start(); t.join()
        print("OK", a.shape)
    """)
    assert proc.returncode == 0, proc.stderr
    assert "OK (30, 40, 4)" in proc.stdout
    assert "Segmentation" not in proc.stderr and "Abort" not in proc.stderr


def test_forked_child_gets_a_clear_error_not_a_hang(gl):
    # A driver does not survive fork(): making a context in the child can
    # hang inside Mesa. The child must get BackendUnavailable and "auto" the
    # CPU, and the parent's context must keep working.
    proc = _run_python("""
        import os, sys, numpy as np, glint_core as g
        img = np.random.default_rng(0).random((30, 40, 4)).astype(np.float32)
        a = g.box_blur(img, backend="gl")
        pid = os.fork()
        if pid == 0:
            try:
                g.box_blur(img, backend="gl")
                print("CHILD: no error", flush=True)
            except g.BackendUnavailable as e:
                print("CHILD:", e, flush=True)
            print("CHILD AUTO:", g.backend_name("auto"), flush=True)
            sys.exit(0)  # a normal exit: the exit handlers must not wait on the parent's thread
        _, status = os.waitpid(pid, 0)
        print("CHILD STATUS:", status)
        print("PARENT:", float(np.abs(g.box_blur(img, backend="gl") - a).max()))
    """)
    assert proc.returncode == 0, proc.stderr
    lines = dict(line.split(": ", 1) for line in proc.stdout.splitlines() if ": " in line)
    assert "forked" in lines["CHILD"] and "spawn" in lines["CHILD"], proc.stdout
    assert lines["CHILD AUTO"] == "cpu"
    assert lines["CHILD STATUS"] == "0"
    assert lines["PARENT"] == "0.0"


def test_calls_from_several_python_threads(gl):
    g = gbuffer(gl, "persp", 128, 96)
    args = (g["position"], g["normal"], g["projection"])
    expected = gl.trace(*args, backend="cpu")
    with ThreadPoolExecutor(max_workers=4) as pool:
        results = list(pool.map(lambda _: gl.trace(*args, backend="gl"), range(8)))
    for r in results:
        assert share_trace(expected, r) >= TRACE_SHARE

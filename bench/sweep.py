#!/usr/bin/env python3
"""The speed / accuracy dial of one scene, measured: a grid over march,
resolution, steps, thickness, max_distance and image size, each point timed
(median of --repeat runs, per backend) and scored against march="exact".

Scenes (--scene, repeatable):
  analytic:NAME        a built-in analytic scene (tests/python/analytic.py):
                       floor, corridor, wall, ortho, and the extremes (see SCENES)
  npz:FILE             arrays position, normal, projection, vertices, triangles
                       [, specular, color, back_position] (bench/blend_gbuffer.py writes
                       them from a .blend through the add-on's exporter)
  blend:FILE           a .blend: exported at each --sizes through Blender first
  exr:FILE:MESH.npz    a G-buffer EXR (glint-exr's layer names) and its triangles

Writes <out>/<scene>.csv (one row per point and backend) and <out>/<scene>_<W>x<H>.png:
time against recall and against precision, the Pareto front marked, each preset
labelled. Where the scene has a specular buffer, only the pixels that reflect are traced
and scored (trace(specular=...)), as the add-on traces them. The grid keeps only the
knobs each march reads (glint_core.march_details()), so a march is never timed twice for
a knob it ignores.

  /usr/bin/python3 bench/sweep.py --scene analytic:floor --sizes 960x540 --out docs/sweeps
  /usr/bin/python3 bench/sweep.py --scene blend:blend_samples/mirror_floor.blend --sizes 960x540
"""
from __future__ import annotations

import argparse
import csv
import itertools
import math
import os
import statistics
import subprocess
import sys
import tempfile
import time

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(here)
sys.path.insert(0, os.path.join(root, "tests", "python"))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(root, "build")), "python"))

import glint_core  # noqa: E402

COLUMNS = ["scene", "width", "height", "backend", "march", "resolution", "steps", "thickness",
           "max_distance", "back_layer", "preset", "ms", "precision", "recall", "median_px", "p95_px",
           "false_reflections", "reported", "exact_visible", "image_mae"]
# The grid by default: every knob at values that span its useful range.
DEFAULT_GRID = {
    "resolution": [0.1, 0.3, 0.6, 1.0],
    "steps": [3, 5, 10, 16, 32],
    "thickness": [0.1, 0.25, 0.5, 1.0],
    "max_distance": [15.0],
}
KNOBS = list(DEFAULT_GRID)


# --- scenes ---------------------------------------------------------------------------


def _analytic_scenes():
    import analytic

    def far_floor():
        # Grazing rays along a long floor: the camera 0.2 above it.
        s = analytic.mirror_floor_scene()
        s.camera = analytic.Camera(eye=(0.0, -12.0, 0.2), target=(0.0, 20.0, 0.3), fov=math.radians(50.0),
                                   near=0.1, far=200.0)
        return s

    def scaled(k, near, far):
        def make():
            s = analytic.mirror_floor_scene()
            for o in s.objects:
                for f in ("point", "center", "lo", "hi"):
                    if hasattr(o, f):
                        setattr(o, f, tuple(np.asarray(getattr(o, f)) * k))
                if hasattr(o, "radius"):
                    o.radius *= k
            c = s.camera
            s.camera = analytic.Camera(eye=tuple(np.asarray(c.eye) * k), target=tuple(np.asarray(c.target) * k),
                                       fov=c.fov, near=near, far=far)
            return s, 15.0 * k
        return make

    def thin():
        s = analytic.mirror_floor_scene(sphere=False, box=False)
        s.objects.append(analytic.Box((-1.0, 0.0, 0.0), (1.0, 0.02, 1.5), analytic.RED))   # a sheet
        s.objects.append(analytic.Box((1.5, -1.0, 0.0), (1.55, -0.95, 2.0), analytic.GREEN))  # a pole
        return s

    def near_far():
        s = analytic.mirror_floor_scene()
        c = s.camera
        s.camera = analytic.Camera(eye=c.eye, target=c.target, fov=c.fov, near=1e-4, far=1e7)
        return s

    return {
        "floor": lambda: analytic.mirror_floor_scene(),
        "corridor": analytic.corridor_scene,
        "wall": analytic.facing_wall_scene,        # rays toward the camera
        "ortho": lambda: analytic.mirror_floor_scene("ortho"),
        "grazing": far_floor,
        "thin": thin,
        "near_far": near_far,                      # near 1e-4, far 1e7
        "scale_1e-3": scaled(1e-3, 1e-5, 1.0),
        "scale_1e4": scaled(1e4, 100.0, 1e7),
    }


def analytic_frame(name: str, width: int, height: int) -> dict:
    import analytic
    import analytic_mesh
    made = _analytic_scenes()[name]()
    scene, distance = made if isinstance(made, tuple) else (made, None)
    g = analytic.render(scene, width, height)
    v, t = analytic_mesh.scene_mesh(scene, plane_extent=1e3 * (distance / 15.0 if distance else 1.0))
    frame = {k: g[k] for k in ("position", "normal", "specular", "color", "projection")}
    frame.update(vertices=v, triangles=t, back_position=analytic.back_layer(scene, g))
    if distance:
        frame["max_distance"] = distance
    return frame


class SkipScene(Exception):
    """The scene has nothing to measure (no reflective material in view)."""


def npz_frame(path: str) -> dict:
    with np.load(path) as z:
        return {k: z[k] for k in z.files}


def blend_frame(path: str, width: int, height: int) -> dict:
    out = os.path.join(tempfile.mkdtemp(prefix="glint-sweep-"), "frame.npz")
    cmd = ["blender", "-b", "--factory-startup", "-noaudio", path, "--python",
           os.path.join(here, "blend_gbuffer.py"), "--", out, f"{width}x{height}"]
    env = dict(os.environ, GLINT_CORE_PATH=os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(root, "build")), "python"))
    done = subprocess.run(cmd, env=env, capture_output=True, text=True)
    skip = [line for line in done.stdout.splitlines() if line.startswith("blend_gbuffer: SKIP")]
    if skip:
        raise SkipScene(skip[0][len("blend_gbuffer: SKIP "):])
    if done.returncode != 0 or not os.path.exists(out):
        raise SystemExit(f"sweep: exporting {path} failed:\n{done.stdout[-2000:]}\n{done.stderr[-2000:]}")
    return npz_frame(out)


def exr_frame(spec: str) -> dict:
    path, mesh = spec.rsplit(":", 1)
    layers, header = glint_core.read_exr(path)
    frame = {k: layers[k] for k in ("position", "normal", "specular", "color", "back_position") if k in layers}
    if "projection" not in header:
        raise SystemExit(f"sweep: {path} has no glintProjection header (write it with glint-exr)")
    frame["projection"] = header["projection"]
    frame.update(npz_frame(mesh))
    return frame


def load_frame(spec: str, width: int, height: int) -> dict:
    kind, _, arg = spec.partition(":")
    if kind == "analytic":
        return analytic_frame(arg, width, height)
    if kind == "blend":
        return blend_frame(arg, width, height)
    if kind == "npz":
        return npz_frame(arg)
    if kind == "exr":
        return exr_frame(arg)
    raise SystemExit(f"sweep: --scene {spec!r}: expected analytic:NAME, npz:FILE, blend:FILE or exr:FILE:MESH.npz")


def scene_label(spec: str) -> str:
    kind, _, arg = spec.partition(":")
    return arg if kind == "analytic" else os.path.splitext(os.path.basename(arg.split(":")[0]))[0]


# --- the grid -------------------------------------------------------------------------


def grid_points(marches, grid: dict) -> list:
    """Every combination of the knobs each march reads; the knobs it ignores stay at
    their first value, so no march is timed twice for the same work."""
    details = glint_core.march_details()
    points = []
    for m in marches:
        reads = details[m]["options"]
        axes = [grid[k] if k in reads else grid[k][:1] for k in KNOBS]
        for values in itertools.product(*axes):
            points.append(dict(zip(KNOBS, values), march=m))
    return points


# Labelled beside the presets: the seed at the chapter's defaults, and the book's
# older linear march at its own (100 steps, thickness 1).
REFERENCE_POINTS = {
    "seed-defaults": dict(march="seed", max_distance=15.0, resolution=0.3, steps=10, thickness=0.5),
    "linear-book": dict(march="linear", max_distance=15.0, resolution=0.3, steps=100, thickness=1.0),
}


def preset_points() -> list:
    # float32 presets read back as 0.30000001192...: round to what a user typed.
    points = [dict({k: round(v, 6) if isinstance(v, float) else v for k, v in kw.items()}, preset=name)
              for name, kw in glint_core.presets().items()]
    return points + [dict(kw, preset=name) for name, kw in REFERENCE_POINTS.items()]


def pareto(times, scores) -> np.ndarray:
    """Mask of the points no other point beats on both axes (faster or as fast,
    and at least as good, strictly better on one)."""
    t = np.asarray(times, float)
    s = np.asarray(scores, float)
    keep = np.ones(len(t), bool)
    for i in range(len(t)):
        better = (t <= t[i]) & (s >= s[i]) & ((t < t[i]) | (s > s[i]))
        keep[i] = not better.any()
    return keep


# --- measuring ------------------------------------------------------------------------


def time_trace(frame, kw, backend, repeat):
    args = dict(kw)
    args.pop("preset", None)
    back = args.pop("back_layer", False)
    details = glint_core.march_details()[args["march"]]
    if details["needs_mesh"]:
        args["mesh"] = (frame["vertices"], frame["triangles"])
    if back and details["uses_back_position"] and "back_position" in frame:
        args["back_position"] = frame["back_position"]
    if frame.get("specular") is not None:  # only the pixels that reflect, as the add-on traces them
        args["specular"] = frame["specular"]
    call = lambda: glint_core.trace(frame["position"], frame["normal"], frame["projection"],  # noqa: E731
                                    backend=backend, **args)
    uv = call()  # warm-up: GL programs, Embree's threads, first-touch pages
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        uv = call()
        times.append((time.perf_counter() - t0) * 1e3)
    return uv, statistics.median(times)


def sweep(spec, sizes, marches, grid, backends, repeat, back_layer, log=print, label_backends=()) -> list:
    rows = []
    for width, height in sizes:
        frame = load_frame(spec, width, height)
        h, w = frame["position"].shape[:2]
        distance = float(frame.get("max_distance", max(grid["max_distance"])))
        exact = glint_core.trace(frame["position"], frame["normal"], frame["projection"], march="exact",
                                 mesh=(frame["vertices"], frame["triangles"]), max_distance=distance,
                                 specular=frame.get("specular"))
        scale = distance / 15.0
        points = [dict(p, max_distance=p["max_distance"] * scale) for p in grid_points(marches, grid)]
        points += [dict(p, max_distance=p["max_distance"] * scale, thickness=p["thickness"] * scale)
                   for p in preset_points()]
        if back_layer:
            points += [dict(p, back_layer=True) for p in points
                       if glint_core.march_details()[p["march"]]["uses_back_position"]]
        for p in points:
            extra = [b for b in label_backends if p.get("preset") and b not in backends]
            for backend in list(backends) + extra:
                try:
                    uv, ms = time_trace(frame, p, backend, repeat)
                except glint_core.BackendUnavailable as exc:
                    log(f"sweep: backend {backend} unavailable ({exc}); skipped")
                    continue
                m = glint_core.compare(uv, exact, color=frame.get("color"), specular=frame.get("specular"))
                row = {
                    "scene": scene_label(spec), "width": w, "height": h, "backend": backend,
                    "march": p["march"], "resolution": p["resolution"], "steps": p["steps"],
                    "thickness": p["thickness"], "max_distance": p["max_distance"],
                    "back_layer": int(bool(p.get("back_layer"))), "preset": p.get("preset", ""), "ms": ms,
                    "precision": m["precision"], "recall": m["recall"], "median_px": m["median_px"],
                    "p95_px": m["p95_px"], "false_reflections": m["false_reflections"],
                    "reported": m["reported"], "exact_visible": m["exact_visible"],
                    "image_mae": "" if m["image_mae"] is None else m["image_mae"],
                }
                rows.append(row)
                log(f"{row['scene']} {w}x{h} {backend:3s} {p['march']:6s} res={p['resolution']:<4} "
                    f"steps={p['steps']:<3} thick={p['thickness']:<6.3g} back={row['back_layer']} "
                    f"{row['preset']:8s} {ms:8.2f} ms  P={m['precision']:.4f} R={m['recall']:.4f}")
    return rows


def read_csv(path) -> list:
    with open(path) as f:
        rows = list(csv.DictReader(f))
    for r in rows:
        for k in ("ms", "precision", "recall", "resolution", "thickness", "max_distance"):
            r[k] = float(r[k])
        for k in ("width", "height", "steps", "back_layer"):
            r[k] = int(r[k])
    return rows


def write_plots(out_dir, label, rows):
    for w, h in sorted({(r["width"], r["height"]) for r in rows}):
        plot(os.path.join(out_dir, f"{label}_{w}x{h}.png"),
             [r for r in rows if (r["width"], r["height"]) == (w, h)], f"{label} {w}x{h}")


def write_csv(path, rows):
    with open(path, "w", newline="") as f:
        writer = csv.DictWriter(f, fieldnames=COLUMNS)
        writer.writeheader()
        for r in rows:
            writer.writerow({k: (f"{v:.6g}" if isinstance(v, float) else v) for k, v in r.items()})


def plot(path, rows, title):
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 2, figsize=(12, 4.8))
    colors = {m: f"C{i}" for i, m in enumerate(glint_core.marches())}
    backends = sorted({r["backend"] for r in rows})
    markers = dict(zip(backends, "os^"))
    for ax, metric in zip(axes, ("recall", "precision")):
        for backend in backends:
            sel = [r for r in rows if r["backend"] == backend]
            t = np.array([r["ms"] for r in sel])
            s = np.array([r[metric] for r in sel])
            for m in colors:
                k = [i for i, r in enumerate(sel) if r["march"] == m]
                if k:
                    ax.scatter(t[k], s[k], s=14, c=colors[m], marker=markers[backend], alpha=0.55,
                               label=f"{m} ({backend})")
            front = pareto(t, s)
            order = np.argsort(t[front])
            ax.step(t[front][order], s[front][order], where="post", c="k", lw=1.0, alpha=0.7)
            for k, (r, ti, si) in enumerate((r, ti, si) for r, ti, si in zip(sel, t, s) if r["preset"]):
                ax.scatter([ti], [si], s=50, facecolors="none", edgecolors="k")
                if backend == backends[0]:  # one label per point: the first backend's
                    ax.annotate(f"{r['preset']}{'+back' if r['back_layer'] else ''}", (ti, si), fontsize=7,
                                xytext=(4, -9 - 8 * (k % 3)), textcoords="offset points")
        ax.set_xscale("log")
        ax.set_xlabel("trace time, ms (median)")
        ax.set_ylabel(f"{metric} within 1.5 px of the exact hit")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="best")
    fig.suptitle(f"{title}: Pareto front (black), presets circled")
    fig.tight_layout()
    fig.savefig(path, dpi=90)
    plt.close(fig)


LABELS = ("seed-defaults", "linear-book", "draft", "balanced", "high", "exact")


def summary_table(paths) -> str:
    """Markdown: each labelled point of each CSV (presets and the two references),
    CPU time, GL time as a ratio to the CPU's, precision, recall, median pixel error."""
    lines = ["| scene | size | point | CPU ms | GL / CPU | precision | recall | median px | false |",
             "|---|---|---|---|---|---|---|---|---|"]
    for path in paths:
        with open(path) as f:
            rows = list(csv.DictReader(f))
        for label in LABELS:
            for back in ("0", "1"):
                sel = {r["backend"]: r for r in rows if r["preset"] == label and r["back_layer"] == back}
                if "cpu" not in sel:
                    continue
                c = sel["cpu"]
                ratio = f"{float(sel['gl']['ms']) / float(c['ms']):.2f}" if "gl" in sel else "-"
                name = label + (" + back layer" if back == "1" else "")
                lines.append(f"| {c['scene']} | {c['width']}x{c['height']} | {name} | {float(c['ms']):.0f} | {ratio} "
                             f"| {float(c['precision']):.3f} | {float(c['recall']):.3f} | "
                             f"{float(c['median_px']):.2f} | {c['false_reflections']} |")
    return "\n".join(lines)


def parse_sizes(text):
    out = []
    for s in text.split(","):
        w, _, h = s.lower().partition("x")
        out.append((int(w), int(h)))
    return out


def floats(text):
    return [float(v) for v in text.split(",")]


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--scene", action="append", default=[])
    ap.add_argument("--table", nargs="+", metavar="CSV",
                    help="print the markdown table of the labelled points of these CSVs, and stop")
    ap.add_argument("--replot", nargs="+", metavar="CSV", help="redraw the plots of these CSVs beside them, and stop")
    ap.add_argument("--sizes", type=parse_sizes, default=parse_sizes("960x540"))
    ap.add_argument("--march", default=",".join(m for m, d in glint_core.march_details().items()
                                                 if not d["needs_mesh"]),
                    help="marches to sweep (comma-separated); presets are always added")
    ap.add_argument("--resolution", type=floats, default=DEFAULT_GRID["resolution"])
    ap.add_argument("--steps", type=lambda t: [int(v) for v in t.split(",")], default=DEFAULT_GRID["steps"])
    ap.add_argument("--thickness", type=floats, default=DEFAULT_GRID["thickness"])
    ap.add_argument("--max-distance", type=floats, default=DEFAULT_GRID["max_distance"])
    ap.add_argument("--backends", default="cpu")
    ap.add_argument("--label-backends", default="",
                    help="also time the presets and reference points on these backends (e.g. gl)")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--no-back-layer", action="store_true", help="do not add back-layer points")
    ap.add_argument("--out", default=os.path.join(root, "docs", "sweeps"))
    ap.add_argument("--no-plot", action="store_true")
    args = ap.parse_args(argv)
    if args.table:
        print(summary_table(args.table))
        return
    if args.replot:
        for path in args.replot:
            write_plots(os.path.dirname(path) or ".", os.path.splitext(os.path.basename(path))[0], read_csv(path))
        return
    if not args.scene:
        ap.error("--scene is required (or --table)")
    marches = [m for m in args.march.split(",") if m]
    for m in marches:
        if m not in glint_core.marches():
            ap.error(f"--march: {m!r} is not one of {', '.join(glint_core.marches())}")
    grid = {"resolution": args.resolution, "steps": args.steps, "thickness": args.thickness,
            "max_distance": args.max_distance}
    os.makedirs(args.out, exist_ok=True)
    for spec in args.scene:
        try:
            rows = sweep(spec, args.sizes, marches, grid, args.backends.split(","), args.repeat,
                         not args.no_back_layer, label_backends=[b for b in args.label_backends.split(",") if b])
        except SkipScene as exc:
            print(f"sweep: {spec}: skipped, {exc}")
            continue
        label = scene_label(spec)
        write_csv(os.path.join(args.out, f"{label}.csv"), rows)
        if not args.no_plot:
            write_plots(args.out, label, rows)
        print(f"sweep: wrote {os.path.join(args.out, label)}.csv ({len(rows)} rows)")


if __name__ == "__main__":
    main()

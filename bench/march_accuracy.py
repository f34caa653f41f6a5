#!/usr/bin/env python3
"""Accuracy and cost of every march (and preset) on analytic scenes.

Each scene's G-buffer is ray-cast exactly in float64 (tests/python/analytic.py),
and so is every pixel's mirror hit; a march's reflected-uv buffer is scored
against those hits as docs/conventions.md defines it: a pixel *reports* when its
visibility > 1e-3, precision is the share of reports within 1.5 px of the exact
visible hit, recall the share of exact visible hits reported within 1.5 px.
Times are medians of --repeat runs, each backend and march in the same process, the
repeats of all marches of a scene taken in turn so that the machine's load falls on all alike.

--coverage also scores each pixel's visibility against the exact coverage of its
reflection: the share of a 4x4 grid of sub-pixel rays (a float64 render at four
times the size) whose mirror hit is visible. That is the answer an antialiased
frame shows, and what the `antialias` option approximates on outlines: "coverage
err" is the mean |visibility - coverage| over the pixels whose 16 rays all start on
the pixel's own reflector, "partial err" the same over those of them whose coverage
is strictly between 0 and 1 (the outlines). Pixels within the screen-edge fade of
any row's report are left out, since the fade is not coverage.

  /usr/bin/python3 bench/march_accuracy.py --sizes 640x480,1920x1080 --repeat 3
  /usr/bin/python3 bench/march_accuracy.py --sizes 960x540 --coverage
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(HERE, "..", "tests", "python"))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(HERE, "..", "build")), "python"))

import analytic as A  # noqa: E402
import glint_core  # noqa: E402
from reference_hiz import edge_fade  # noqa: E402  (the fade at the screen's edges)

MAX_DISTANCE = 15.0
SCENES = {
    "floor": lambda: A.mirror_floor_scene("persp"),
    "corridor": A.corridor_scene,
    "wall": A.facing_wall_scene,
}


def counts(uv, exact_uv, visible, tol=1.5):
    """(good, reported, visible): pixels reporting a hit within tol px of the exact
    one, pixels reporting any, pixels whose exact mirror hit is visible."""
    h, w = visible.shape
    rep = uv[..., 2] > 1e-3
    err = np.hypot((uv[..., 0] - exact_uv[..., 0]) * w, (uv[..., 1] - exact_uv[..., 1]) * h)
    good = rep & visible & (err <= tol)
    return int(good.sum()), int(rep.sum()), int(visible.sum())


def score(uv, exact_uv, visible, tol=1.5):
    good, rep, vis = counts(uv, exact_uv, visible, tol)
    return (good / rep if rep else 1.0), (good / vis if vis else 1.0)


def scene_data(name, w, h, cache_dir):
    path = os.path.join(cache_dir, f"{name}_{w}x{h}.npz") if cache_dir else None
    if path and os.path.exists(path):
        return dict(np.load(path))
    sc = SCENES[name]()
    gb = A.render(sc, w, h)
    mh = A.mirror_hits(sc, gb, MAX_DISTANCE, incident="view")
    d = dict(position=gb["position"], normal=gb["normal"], projection=gb["projection"],
             back=A.back_layer(sc, gb), exact_uv=mh["uv"], visible=mh["visible"])
    if path:
        os.makedirs(cache_dir, exist_ok=True)
        np.savez(path, **d)
    return d


COVERAGE_GRID = 4  # sub-pixel rays per side


def coverage_data(name, w, h, cache_dir):
    """The exact coverage of each pixel's reflection, and where it is defined (the
    pixel's 16 sub-pixel rays all start on its own reflector); cached like scene_data."""
    path = os.path.join(cache_dir, f"{name}_{w}x{h}_coverage{COVERAGE_GRID}.npz") if cache_dir else None
    if path and os.path.exists(path):
        return dict(np.load(path))
    sc = SCENES[name]()
    gb = A.render(sc, w, h)
    coverage, whole = A.reflection_coverage(sc, gb, MAX_DISTANCE, COVERAGE_GRID)
    d = dict(coverage=coverage, defined=whole & (gb["specular"][..., :3].mean(-1) > 0))
    if path:
        os.makedirs(cache_dir, exist_ok=True)
        np.savez(path, **d)
    return d


def coverage_errors(uvs, cov):
    """(coverage err, partial err) of each reflected-uv buffer, over the pixels every
    buffer leaves out of its screen-edge fade."""
    mask = cov["defined"].copy()
    for uv in uvs:
        mask &= (edge_fade(uv) == 1) | (uv[..., 2] == 0)
    partial = mask & (cov["coverage"] > 0) & (cov["coverage"] < 1)
    out = []
    for uv in uvs:
        err = np.abs(uv[..., 2] - cov["coverage"])
        out.append((err[mask].mean(), err[partial].mean() if partial.any() else float("nan")))
    return out


def timed_round_robin(fns, repeat):
    """[(median ms, last output)] of each fn, the repeats taken in turn (a, b, c, a, b, c, ...)
    so that a change in the machine's load while measuring falls on all of them alike."""
    times, outs = [[] for _ in fns], [None] * len(fns)
    for _ in range(repeat):
        for k, fn in enumerate(fns):
            t0 = time.perf_counter()
            outs[k] = fn()
            times[k].append((time.perf_counter() - t0) * 1000.0)
    return [(statistics.median(t), o) for t, o in zip(times, outs)]


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="640x480,1920x1080")
    ap.add_argument("--scenes", default=",".join(SCENES))
    ap.add_argument("--backends", default="cpu")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--cache", default=os.path.join(HERE, "..", "build", "bench-cache"),
                    help="where exact G-buffers are kept between runs ('' for none)")
    ap.add_argument("--only", default="",
                    help="comma-separated rows to run (e.g. 'seed (defaults),balanced'); '' for all")
    ap.add_argument("--coverage", action="store_true",
                    help="also score visibility against the exact 4x4 coverage (module docstring)")
    ap.add_argument("--antialias-levels", default="0",
                    help="with --coverage: the other antialias levels an antialiasing preset is also "
                         "run at, comma-separated (e.g. 0,1,2,3)")
    ap.add_argument("--counts", action="store_true",
                    help="also print the pixel counts behind precision and recall (good, reported, "
                         "visible), to compare two builds exactly")
    ap.add_argument("--cost", action="store_true",
                    help="instead: time of the seed and the balanced preset against max_distance "
                         "and image size on the floor scene")
    args = ap.parse_args()
    if args.cost:
        return cost_table(args)
    runs = [("seed (defaults)", dict(march="seed"), False, "seed (defaults)")]  # (label, kw, back, preset)
    for name, kw in glint_core.presets().items():
        if kw["march"] in glint_core.marches() and not glint_core.march_details()[kw["march"]]["needs_mesh"]:
            variants = [(name, kw)]
            if args.coverage and kw.get("antialias", 0) > 0:  # the knob's effect, in the same run
                variants += [(f"{name}, antialias {a}", dict(kw, antialias=a))
                             for a in (int(v) for v in args.antialias_levels.split(",")) if a != kw["antialias"]]
            for label, vkw in variants:
                runs.append((label, vkw, False, name))
                if glint_core.march_details()[kw["march"]]["uses_back_position"]:
                    runs.append((label + " + back layer", vkw, True, name))
    if args.only:
        keep = set(args.only.split(","))
        # A preset named keeps its variants (", antialias N", " + back layer"); the
        # seed's row is the ratios' base.
        runs = [runs[0]] + [r for r in runs[1:] if r[0] in keep or r[3] in keep]
    extra = (" coverage err | partial err |" if args.coverage else "") + (" good | reported | visible |" if args.counts else "")
    print("| scene | size | backend | march / preset | time ms | x seed | precision | recall |" + extra)
    print("|---|---|---|---|---|---|---|---|" + ("---|---|" if args.coverage else "") + ("---|---|---|" if args.counts else ""))
    for size in args.sizes.split(","):
        w, h = (int(v) for v in size.split("x"))
        for scene in args.scenes.split(","):
            d = scene_data(scene, w, h, args.cache)
            for backend in args.backends.split(","):
                calls = [lambda kw=kw, back=back: glint_core.trace(
                    d["position"], d["normal"], d["projection"], backend=backend, **kw,
                    **(dict(back_position=d["back"]) if back else {})) for _, kw, back, _ in runs]
                results = timed_round_robin(calls, args.repeat)
                seed_ms = results[0][0]
                cov = coverage_errors([uv for _, uv in results], coverage_data(scene, w, h, args.cache)) \
                    if args.coverage else [None] * len(results)
                for (label, _, _, _), (ms, uv), ce in zip(runs, results, cov):
                    p, r = score(uv, d["exact_uv"], d["visible"])
                    tail = f" {ce[0]:.4f} | {ce[1]:.3f} |" if ce else ""
                    if args.counts:
                        tail += " {} | {} | {} |".format(*counts(uv, d["exact_uv"], d["visible"]))
                    print(f"| {scene} | {w}x{h} | {backend} | {label} | {ms:.0f} | {ms / seed_ms:.2f} | "
                          f"{p:.4f} | {r:.4f} |{tail}", flush=True)


def cost_table(args):
    """How the cost grows: the seed's samples grow with the pixels a ray crosses, the
    Hi-Z walk's cells with the logarithm of that."""
    balanced = glint_core.presets()["balanced"]
    sizes = args.sizes.split(",")
    print("| size | max_distance | seed ms | balanced ms | balanced / seed |")
    print("|---|---|---|---|---|")
    for size in sizes:
        w, h = (int(v) for v in size.split("x"))
        d = scene_data("floor", w, h, args.cache)
        for md in (2.0, 5.0, 15.0, 100.0, 1e6):
            t = [ms for ms, _ in timed_round_robin(
                [lambda kw=kw: glint_core.trace(d["position"], d["normal"], d["projection"],
                                                **dict(kw, max_distance=md))
                 for kw in (dict(march="seed"), balanced)], args.repeat)]
            print(f"| {w}x{h} | {md:g} | {t[0]:.0f} | {t[1]:.0f} | {t[1] / t[0]:.2f} |", flush=True)


if __name__ == "__main__":
    main()

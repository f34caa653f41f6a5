#!/usr/bin/env python3
"""Cost and error of every trace knob against exact ray-traced ground truth.

For the analytic mirror-floor scene (tests/python/analytic.py: a mirror floor
under a red sphere and a green box, a blue wall behind), every pixel's exact
mirror hit is computed in float64. Each knob is then swept one at a time
around the seed defaults, and for each setting this prints:

  time      median wall time of glint_core.trace over --repeat runs (ms)
  recall    share of the pixels that SHOULD reflect something (exact hit on
            screen, visible to the camera, front side, within max_distance)
            where Glint reports visibility > 0 within 1.5 px of the exact uv
  err_px    mean distance in pixels between Glint's uv and the exact uv on
            those found pixels
  wrong     share of pixels with visibility > 0 whose uv is more than 3 px
            from the exact hit (or that have no exact visible hit at all):
            smeared or invented reflections

Usage (from a checkout, after scripts/setup.sh):
  /usr/bin/python3 bench/knob_sweep.py --size 480x270 --repeat 3 [--markdown docs/knobs.md]
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
import time

import numpy as np

here = os.path.dirname(os.path.abspath(__file__))
root = os.path.dirname(here)
sys.path.insert(0, os.path.join(root, "tests", "python"))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(root, "build")), "python"))

import analytic  # noqa: E402
import glint_core  # noqa: E402

DEFAULTS = dict(max_distance=15.0, resolution=0.3, steps=10, thickness=0.5, march="seed")
SWEEPS = [
    ("resolution", [0.05, 0.1, 0.2, 0.3, 0.5, 1.0]),
    ("steps", [0, 1, 5, 10, 20, 40]),
    ("thickness", [0.05, 0.1, 0.25, 0.5, 1.0, 2.0]),
    ("max_distance", [2.0, 5.0, 10.0, 15.0, 30.0, 1e6]),
    # Every march the core has that works from the G-buffer alone.
    ("march", [m for m, d in glint_core.march_details().items() if not d["needs_mesh"]]),
]


def measure(gb, truth, params, repeat, backend):
    times = []
    uv = None
    for _ in range(repeat):
        t0 = time.perf_counter()
        uv = glint_core.trace(gb["position"], gb["normal"], gb["projection"], backend=backend, **params)
        times.append((time.perf_counter() - t0) * 1000.0)
    h, w = uv.shape[:2]
    vis = uv[..., 2] > 0
    exact = truth["uv"]
    d_px = np.hypot((uv[..., 0] - exact[..., 0]) * w, (uv[..., 1] - exact[..., 1]) * h)
    should = truth["hit"] & truth["visible"] & truth["front"] & (truth["distance"] <= params["max_distance"])
    found = should & vis & (d_px <= 1.5)
    wrong = vis & (~should | (d_px > 3.0))
    return {
        "time": statistics.median(times),
        "recall": found.sum() / max(should.sum(), 1),
        "err_px": float(d_px[found].mean()) if found.any() else float("nan"),
        "wrong": wrong.sum() / max(vis.sum(), 1),
        "reflecting": should.sum(),
    }


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--size", default="480x270", help="WxH of the image (default 480x270)")
    ap.add_argument("--repeat", type=int, default=3, help="runs per setting; the median time is kept")
    ap.add_argument("--backend", default="cpu")
    ap.add_argument("--markdown", help="also write the tables to this file")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.lower().split("x"))

    scene = analytic.mirror_floor_scene("persp")
    gb = analytic.render(scene, w, h)
    truth = analytic.mirror_hits(scene, gb, max_distance=np.inf)
    lines = [f"Scene: analytic mirror floor, {w}x{h}, backend {args.backend}, "
             f"{os.cpu_count()} hardware threads; defaults {DEFAULTS}.", ""]
    for knob, values in SWEEPS:
        lines += [f"### {knob}", "", f"| {knob} | time (ms) | recall | err (px) | wrong |", "|---|---|---|---|---|"]
        for v in values:
            params = dict(DEFAULTS)
            params[knob] = v
            if knob == "march" and v == "linear":
                # The book's older march with its own defaults.
                params.update(steps=100, thickness=1.0)
            r = measure(gb, truth, params, args.repeat, args.backend)
            label = f"{v}" + (" (steps 100, thickness 1)" if knob == "march" and v == "linear" else "")
            lines.append(f"| {label} | {r['time']:.1f} | {r['recall']:.1%} | {r['err_px']:.2f} | {r['wrong']:.1%} |")
        lines.append("")
    # The image size is a knob too (Blender's render percentage): the same
    # scene and defaults at a quarter, half and full size of --size.
    lines += ["### image size (defaults)", "", "| size | time (ms) | recall | err (px) | wrong |",
              "|---|---|---|---|---|"]
    for scale in (0.25, 0.5, 1.0):
        sw, sh = max(1, round(w * scale)), max(1, round(h * scale))
        gbs = analytic.render(scene, sw, sh)
        truths = analytic.mirror_hits(scene, gbs, max_distance=np.inf)
        r = measure(gbs, truths, dict(DEFAULTS), args.repeat, args.backend)
        lines.append(f"| {sw}x{sh} | {r['time']:.1f} | {r['recall']:.1%} | {r['err_px']:.2f} | {r['wrong']:.1%} |")
    lines.append("")
    text = "\n".join(lines)
    print(text)
    if args.markdown:
        with open(args.markdown, "w") as f:
            f.write(text + "\n")


if __name__ == "__main__":
    main()

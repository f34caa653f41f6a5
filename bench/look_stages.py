#!/usr/bin/env python3
"""Cost of the look's stages (specular_weight, cone_blur; box_blur beside them)
as ratios to the trace of the same run, per backend.

The analytic mirror-floor scene (tests/python/analytic.py) with a rough
dielectric floor (F0 0.04, shininess alpha 0.5) under a metal sphere, rendered
once in float64; then glint_core.pipeline runs --repeat times per backend and
look, and each stage's median time is printed with its ratio to the median
trace of that same backend and look. Speed here is only ever a ratio measured
side by side (the machine is shared).

Usage (from a checkout, after a build):
  /usr/bin/python3 bench/look_stages.py --size 1920x1080 --repeat 3
"""
from __future__ import annotations

import argparse
import os
import statistics
import sys
from pathlib import Path

REPO = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(Path(os.environ.get("GLINT_BUILD_DIR", REPO / "build")) / "python"))
sys.path.insert(0, str(REPO / "tests" / "python"))

import analytic as A  # noqa: E402
import glint_core  # noqa: E402


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--size", default="1920x1080")
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--backends", default="cpu,gl")
    args = ap.parse_args()
    w, h = (int(v) for v in args.size.split("x"))
    floor = A.Material(color=(0.4, 0.4, 0.4), specular=(0.04, 0.04, 0.04), alpha=0.5)
    metal = A.Material(color=(0.9, 0.6, 0.2), specular=(0.9, 0.6, 0.2), alpha=0.8)
    gb = A.render(A.mirror_floor_scene("persp", floor=floor, sphere_material=metal), w, h)
    looks = {"physical+cone": dict(weighting="physical", blur="cone"),
             "seed+box": dict(weighting="seed", blur="box")}
    print(f"{w}x{h}, median of {args.repeat}; ratio = stage / trace of the same backend and look")
    print(f"{'backend':8} {'look':14} {'stage':17} {'ms':>9} {'/ trace':>8}")
    for backend in args.backends.split(","):
        try:
            glint_core.backend_name(backend)
        except glint_core.BackendUnavailable as exc:
            print(f"{backend}: unavailable ({exc})")
            continue
        for name, look in looks.items():
            # One warm-up run: the GL context, programs and the split-sum table.
            glint_core.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"],
                                gb["projection"], backend=backend, **look)
            runs = [glint_core.pipeline(gb["position"], gb["normal"], gb["specular"], gb["color"],
                                        gb["projection"], backend=backend, **look)["stats"]
                    for _ in range(args.repeat)]
            med = {s: statistics.median(r["timings_ms"][s] for r in runs) for s in runs[0]["timings_ms"]}
            for stage, ms in med.items():
                skipped = " (skipped)" if stage in runs[0]["skipped"] else ""
                print(f"{backend:8} {name:14} {stage:17} {ms:9.1f} {ms / med['trace']:8.3f}{skipped}")


if __name__ == "__main__":
    main()

"""What the add-on's one call into the core costs on a real frame: `composite_layers`
(the trace, the weights, the lods, the hidden sides) on the arguments the add-on passed
it while rendering frame_bench.py's scene, timed alone, several builds in turn.

Inside Blender, save the arguments of one render (the add-on from this checkout, the
core from GLINT_CORE_PATH):

  blender -b --factory-startup -noaudio --python bench/composite_bench.py -- \\
      --save build/bench-cache/frame_default_1920x1080.npz [--size 1920x1080] [--scene default]

Then, with the system Python, time the call on them, each build's calls in one
process and the builds in turn (`--rounds` times); the first calls of a process, which
fault in their buffers, are left out (`--warm`):

  /usr/bin/python3 bench/composite_bench.py --load build/bench-cache/frame_default_1920x1080.npz \\
      --builds build,/tmp/old/build [--rounds 3] [--calls 6] [--warm 2] [--threads 2]
"""
from __future__ import annotations

import argparse
import glob
import importlib.util
import json
import os
import statistics
import subprocess
import sys
import time

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))


def save(argv):
    """Inside Blender: render frame_bench's scene once with Glint and keep what the add-on
    handed composite_layers."""
    import bpy
    p = argparse.ArgumentParser(prog="composite_bench --save")
    p.add_argument("--save", required=True)
    p.add_argument("--size", default="1920x1080")
    p.add_argument("--scene", default="default", choices=("matte", "default"))
    a = p.parse_args(argv)
    sys.argv = [sys.argv[0], "--", "--size", a.size, "--rounds", "0", "--scenes", a.scene]
    sys.path.insert(0, HERE)
    import frame_bench as fb
    opts = fb._args()
    fb._register_addon(opts["addon"])
    from glint import native
    core = native.load()
    if core is None:
        sys.exit(f"composite_bench: {native.error()}")
    real = core.composite_layers

    def keep(position, normal, specular, projection, **kw):
        arrays = {k: v for k, v in kw.items() if isinstance(v, np.ndarray)}
        options = {k: v for k, v in kw.items() if not isinstance(v, np.ndarray) and k != "backend"}
        os.makedirs(os.path.dirname(os.path.abspath(a.save)), exist_ok=True)
        np.savez(a.save, position=position, normal=normal, specular=specular, projection=projection,
                 options=json.dumps(options), **arrays)
        return real(position, normal, specular, projection, **kw)

    core.composite_layers = keep
    scene, _ = fb.build_scene(opts["size"], opts["samples"], a.scene)
    fb.configure(scene, "glint", opts)
    bpy.ops.render.render(write_still=False)
    core.composite_layers = real
    if not os.path.exists(a.save):
        sys.exit("composite_bench: the render did not call composite_layers")
    print(f"composite_bench: saved {a.save}")


def time_one(build, path, calls, warm, threads):
    """In this process: `calls` calls of composite_layers with `build`'s core, the wall
    times of those after the first `warm`, in ms."""
    so = glob.glob(os.path.join(build, "python", "glint_core*.so"))
    if not so:
        sys.exit(f"composite_bench: no glint_core in {build}/python")
    spec = importlib.util.spec_from_file_location("glint_core", so[0])
    core = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(core)
    d = dict(np.load(path))
    options = json.loads(str(d.pop("options")))
    args = [d.pop(k) for k in ("position", "normal", "specular", "projection")]
    times = []
    for k in range(calls):
        t0 = time.perf_counter()
        out = core.composite_layers(*args, backend="cpu", threads=threads, **d, **options)
        if k >= warm:
            times.append((time.perf_counter() - t0) * 1e3)
        del out
    return times


def main():
    if "--save" in sys.argv:
        save(sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else sys.argv[1:])
        return
    p = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    p.add_argument("--load", required=True)
    p.add_argument("--builds", default=os.path.join(HERE, "..", "build"))
    p.add_argument("--rounds", type=int, default=3)
    p.add_argument("--calls", type=int, default=6)
    p.add_argument("--warm", type=int, default=2)
    p.add_argument("--threads", type=int, default=0)
    p.add_argument("--one", nargs=1, help=argparse.SUPPRESS)  # a child: one build, times as JSON
    a = p.parse_args()
    if a.one:
        print(json.dumps(time_one(a.one[0], a.load, a.calls, a.warm, a.threads)))
        return
    builds = a.builds.split(",")
    times = {b: [] for b in builds}
    for _ in range(a.rounds):
        for b in builds:  # a process per build and round: each core loads alone
            out = subprocess.run([sys.executable, __file__, "--load", a.load, "--one", b, "--calls", str(a.calls),
                                  "--warm", str(a.warm), "--threads", str(a.threads)],
                                 check=True, capture_output=True, text=True).stdout
            times[b] += json.loads(out.strip().splitlines()[-1])
    print(f"composite_layers on {os.path.basename(a.load)}, threads {a.threads or 'all'}, "
          f"{a.rounds} rounds of {a.calls - a.warm} timed calls per build, in turn")
    print("| build | min ms | median ms | max ms |")
    print("|---|---|---|---|")
    for b in builds:
        t = times[b]
        print(f"| {b} | {min(t):.0f} | {statistics.median(t):.0f} | {max(t):.0f} |")


if __name__ == "__main__":
    main()

"""The compositing phase alone: the time from the end of Eevee's render to the
end of the frame, for frame_bench.py's scene with Glint on, per variant of the
group, renders interleaved, medians.

Blender 3.4 has no handler around a render's compositing (composite_pre and
composite_post fire for the node editor only), so the phase is read from the
render's progress callbacks: the compositor reports every tile, Eevee once per
sample, and with one sample the longest gap between two callbacks is Eevee's
render. Usage, from a checkout after building:

  blender -b --factory-startup -noaudio --python bench/compositor_phase.py -- [--size 1920x1080] [--rounds 5] \
      [--scene matte|default] [--variants "Tiled,Tiled no hidden sides"]

The scene is frame_bench.py's, with its matte or its default (Principled defaults) materials.
"""
from __future__ import annotations

import os
import statistics
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_scene_kit as kit  # noqa: E402
import frame_bench as fb  # noqa: E402

# name -> (execution mode, node of the group muted or None, Fill Hidden Reflections)
VARIANTS = {"Tiled": ("TILED", None, True), "Full Frame": ("FULL_FRAME", None, True),
            "Tiled Map UV muted": ("TILED", "map_uv", True),
            "Tiled no hidden sides": ("TILED", None, False),
            # rep x S taken out whole, not at most the frame (a muted Darken passes it through)
            "Tiled unbounded": ("TILED", "taken_out", True)}


def main():
    opts = kit.script_options({"size": (1920, 1080), "rounds": 5, "scene": ["matte"], "variants": list(VARIANTS)},
                              {"size": kit.frame_size, "rounds": int, "scene": kit.names_among(fb.SCENES, "scene"),
                               "variants": kit.names_among(VARIANTS, "variants")})
    if len(opts["scene"]) != 1:
        raise ValueError(f"--scene: one of {', '.join(fb.SCENES)}")
    fb._register_addon(os.path.join(os.path.dirname(HERE), "addon"))
    scene, _ = fb.build_scene(opts["size"], 1, opts["scene"][0])
    fb.configure(scene, "glint", {"preset": "BALANCED", "backend": "AUTO"})
    bpy.ops.render.render()  # sets the compositor up, warms the caches
    stamps = []
    bpy.app.handlers.render_stats.append(lambda *a: stamps.append(time.perf_counter()))
    group = bpy.data.node_groups["Glint"]
    chosen = {name: VARIANTS[name] for name in opts["variants"]}
    res = {name: [] for name in chosen}
    for k in range(opts["rounds"] + 1):  # round 0 warms up
        for name, (mode, muted, hidden) in chosen.items():
            scene.node_tree.execution_mode = mode
            scene.glint.fill_hidden = hidden  # off: the group's use_hidden switch skips its three nodes
            for node in group.nodes:
                node.mute = node.name == muted
            stamps.clear()
            bpy.ops.render.render(write_still=False)
            _, i = max((stamps[j + 1] - stamps[j], j) for j in range(len(stamps) - 1))
            if k:
                res[name].append((stamps[-1] - stamps[i + 1]) * 1e3)
    for node in group.nodes:
        node.mute = False
    w, h = opts["size"]
    print(f"\ncompositor_phase: {w}x{h}, {opts['scene'][0]} scene, Glint balanced, medians of {opts['rounds']} rounds")
    for name, ms in res.items():
        print(f"  {name:<22}{statistics.median(ms):6.0f} ms   {sorted(round(x) for x in ms)}")


if __name__ == "__main__":
    main()

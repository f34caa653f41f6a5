"""What taking the replaced specular S from the world's colour saves against
Eevee's Specular passes (addon/glint/logic/world.py), and how far the two
composites differ. Renders bench/frame_bench.py's floor scene (a uniform world)
in one Blender process, alternating per round:

  plain    Eevee, Glint off (no passes)
  passes   Glint on, S from Eevee's Specular Light x Color: the world's Background
           colour comes through an RGB node, which renders the same world but is
           "linked", so Glint keeps the passes
  world    Glint on, S = world colour x W, the passes off

and prints the median render time of each, the ratios, and the mean absolute
difference of the passes and world composites over the reflecting pixels
(the trace's visibility > 0). Usage, from a checkout after building:

  blender -b --factory-startup -noaudio --python bench/world_specular_bench.py -- \
      [--size 480x270] [--rounds 3] [--samples 8]
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
from frame_bench import build_scene  # noqa: E402

OUT = "/tmp/glint_world_specular_bench_"


def configure(scene, mode):
    tree = scene.world.node_tree
    bg = tree.nodes["Background"]
    rgb = tree.nodes.get("bench colour")
    if rgb is None:
        rgb = tree.nodes.new("ShaderNodeRGB")
        rgb.name = "bench colour"
        rgb.outputs[0].default_value = bg.inputs["Color"].default_value
    for link in list(bg.inputs["Color"].links):
        tree.links.remove(link)
    if mode == "passes":
        tree.links.new(rgb.outputs[0], bg.inputs["Color"])
    scene.glint.enabled = mode != "plain"
    scene.glint.write_layers_exr = mode != "plain"
    scene.render.filepath = OUT + mode + "_"


def main():
    opts = kit.script_options({"size": (480, 270), "rounds": 3, "samples": 8},
                              {"size": kit.frame_size, "rounds": int, "samples": int})
    kit.register_addon(os.path.join(kit.ROOT, "addon"))
    from glint import native
    from glint.state import STATE
    core = native.load()
    scene, tris = build_scene(opts["size"], opts["samples"])
    kit.use_eevee(scene, own_reflections=False)  # this Blender's Eevee, its own reflections off
    scene.glint.backend = "CPU"
    walls = {"plain": [], "passes": [], "world": []}
    sources = {}
    modes = list(walls)
    for k in range(opts["rounds"] + 1):  # round 0 warms up
        for mode in modes[k % 3:] + modes[:k % 3]:
            configure(scene, mode)
            t0 = time.perf_counter()
            bpy.ops.render.render(write_still=False)
            wall = (time.perf_counter() - t0) * 1e3
            if mode != "plain":
                sources[mode] = STATE.specular_source
                if STATE.last is None or STATE.last.status != "ok":
                    raise RuntimeError(f"Glint did not run: {STATE.last}")
            if k:
                walls[mode].append(wall)
    if sources != {"passes": "Eevee passes", "world": "world colour"}:
        raise RuntimeError(f"S came from {sources}")
    med = {m: statistics.median(v) for m, v in walls.items()}
    layers = {m: core.read_exr(f"{OUT}{m}_glint_{scene.frame_current:04d}.exr")[0] for m in ("passes", "world")}
    vis = layers["world"]["Visibility"][..., 0] > 0
    diff = abs(layers["world"]["Image"][..., :3] - layers["passes"]["Image"][..., :3])[vis]
    base = layers["passes"]["Base"][..., :3][vis]
    s_p, s_w = layers["passes"]["EngineSpecular"][..., :3][vis], layers["world"]["EngineSpecular"][..., :3][vis]
    w, h = opts["size"]
    print(f"\nworld_specular_bench: {w}x{h} Eevee, {opts['samples']} samples, {tris} triangles, "
          f"medians of {opts['rounds']} rounds")
    for m in modes:
        print(f"  render, {m:<8} {med[m]:8.0f} ms  ({med[m] / med['plain']:.2f}x plain)")
    print(f"  world / passes     {med['world'] / med['passes']:.2f}x")
    print(f"  reflecting pixels  {int(vis.sum())}")
    print(f"  composite |world - passes|: mean {diff.mean():.5f}, 99th pct {float(sorted(diff.max(axis=1))[int(0.99 * (len(diff) - 1))]):.4f}"
          f" (mean frame value there {base.mean():.4f})")
    print(f"  S: mean passes {s_p.mean():.5f}, mean world {s_w.mean():.5f}, mean |diff| {abs(s_p - s_w).mean():.5f}")


main()

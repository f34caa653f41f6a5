"""What Glint adds to a frame whose render is nearly free: frame_bench.py's scene
rendered with Workbench, so that the difference is Glint's stages and its node
group in the compositor, with the engine's own noise out of it. Renders with
Glint on and off alternate per round; medians after a warm-up.

  blender -b --factory-startup -noaudio --python bench/workbench_frame.py -- \\
      [--size 1920x1080] [--rounds 7] [--scene default|matte] [--addon DIR] [--off SETTING,...]

``--addon`` another commit's add-on (``git archive <commit> addon | tar -x -C /tmp/old``),
to compare two group layouts in turn on the same core. ``--off`` names switches of
the Glint panel (boolean settings of ``scene.glint``, e.g. ``fill_hidden``): each
adds a render with Glint on and that setting off to every round, so what the
setting costs comes from the same rounds. docs/frame-cost.md (*The first level as a 3x3
filter*, *Hidden sides: what they cost*) has the figures.
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


def main():
    opts = kit.script_options(
        {"size": (1920, 1080), "rounds": 7, "scene": ["default"], "addon": os.path.join(os.path.dirname(HERE), "addon"),
         "off": ""},
        {"size": kit.frame_size, "rounds": int, "scene": kit.names_among(fb.SCENES, "scene"),
         "addon": os.path.abspath})
    if len(opts["scene"]) != 1:
        raise ValueError(f"--scene: one of {', '.join(fb.SCENES)}")
    fb._register_addon(opts["addon"])
    scene, _ = fb.build_scene(opts["size"], 1, opts["scene"][0])
    fb.configure(scene, "glint", {"preset": "BALANCED", "backend": "AUTO"})
    scene.render.engine = "BLENDER_WORKBENCH"
    switches = _switches(scene.glint, opts["off"])
    walls = {"on": [], "off": [], **{name: [] for name in switches}}
    for r in range(opts["rounds"] + 1):
        for variant in walls:
            scene.glint.enabled = variant != "off"
            for name in switches:
                setattr(scene.glint, name, name != variant)
            t0 = time.perf_counter()
            bpy.ops.render.render()
            if r:  # the first round faults in what the later ones reuse
                walls[variant].append((time.perf_counter() - t0) * 1e3)
    med = {k: statistics.median(v) for k, v in walls.items()}
    on, off = med["on"], med["off"]
    w, h = opts["size"]
    print(f"\nworkbench_frame: Blender {bpy.app.version_string}, {w}x{h}, {opts['scene'][0]} scene, "
          f"medians of {opts['rounds']}: Glint on {on:.0f} ms, off {off:.0f} ms, Glint adds {on - off:.0f} ms")
    for name in switches:
        print(f"workbench_frame: with {name} off, Glint adds {med[name] - off:.0f} ms: {name} costs {on - med[name]:.0f} ms")


def _switches(settings, names: str):
    """The boolean Glint settings named in ``--off`` (ValueError naming any
    that is not one)."""
    props = settings.bl_rna.properties
    wanted = [n.strip() for n in names.split(",") if n.strip()]
    choices = sorted(p.identifier for p in props
                     if p.type == "BOOLEAN" and not p.is_hidden and p.identifier != "enabled")
    bad = [n for n in wanted if n not in choices]
    if bad:
        raise ValueError(f"--off {names}: {', '.join(bad)} is not a switch of the Glint panel; choose among {','.join(choices)}")
    return wanted


if __name__ == "__main__":
    main()

"""What Glint adds to one Eevee frame, stage by stage, next to what Eevee's own SSR adds.

Builds a glossy floor (a dielectric, Principled Specular 0.5, Roughness 0.1) under a
few objects (a few thousand triangles), in one or both of two scenes:

  matte     the objects coloured, Specular 0: only the floor reflects
  default   the objects keep a new material's Principled defaults (Specular 0.5,
            Roughness 0.5, grey), as most objects of a user's scene do: every
            object is a rough reflector

then renders each scene's frame, in one Blender process, alternating per round:

  plain       Eevee, Screen Space Reflections off, Glint off, the compositor off
  composited  the same with the compositor on (the default Render Layers -> Composite
              tree, Post Processing > Compositing on), as most final renders have it
  ssr         Eevee with its own reflections on, Glint off, the compositor on: Legacy's
              SSR (half-resolution trace off) on Blender 3.x, Eevee Next's ray tracing
              at its defaults on 4.2+
  glint       Eevee, its own reflections off, Glint on (the preset given, backend Auto)

and prints the median of each: Blender's wall time for the render, what SSR and Glint
add to it against the composited frame (issue 23's measure: both frames composite, so
what the compositor costs anyway is not Glint's), what Glint adds against the frame
without a compositor (the figure of earlier runs, which holds the compositor's own
cost), Glint's stages from its log (export/gather, rasterize,
trace, images; also those of the warm-up frame, which pays for fresh memory and
contexts that later frames reuse), its render_pre clear of the full-size images (timed after the
frame, as the next frame pays it), and the compositor's share (what Glint adds to the
composited frame minus its stages and clear: its group's nodes). Usage, from a checkout after building:

  blender -b --factory-startup -noaudio --python bench/frame_bench.py -- \
      [--size 1920x1080] [--rounds 3] [--samples 8] [--preset BALANCED] [--backend AUTO] \
      [--scenes matte,default] [--addon <folder holding glint/>] [--antialias N] [--hidden-sides 0|1]

--antialias N sets the add-on's Antialias to N after the preset (the preset's other
values stay, the panel shows Custom); without it the preset's own value counts.
--hidden-sides 0 turns Hidden Sides in Their Colour off (1, the default, on).

The add-on is registered from this checkout (or --addon, e.g. an older commit's
``git archive`` to compare); the core comes from GLINT_CORE_PATH
(default: <checkout>/build/python).
"""
from __future__ import annotations

import inspect
import math
import os
import statistics
import sys
import time

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_scene_kit as kit  # noqa: E402
ROOT = os.path.dirname(HERE)


def _args():
    return kit.script_options(
        {"size": (1920, 1080), "rounds": 3, "samples": 8, "preset": "BALANCED", "backend": "AUTO",
         "scenes": ["matte", "default"], "addon": os.path.join(ROOT, "addon"), "antialias": -1,
         "hidden-sides": 1},
        {"size": kit.frame_size, "rounds": int, "samples": int, "preset": str.upper, "backend": str.upper,
         "scenes": kit.names_among(SCENES, "scenes"), "addon": os.path.abspath, "antialias": int,
         "hidden-sides": int})


SCENES = ("matte", "default")


_register_addon = kit.register_addon


_material = kit.principled


def _object_material(name, colour, materials):
    if materials == "default":
        return kit.default_material(name)
    return _material(name, colour, 0.5, specular=0.0)


def build_scene(size, samples, materials="matte"):
    scene = bpy.context.scene
    for ob in list(scene.objects):
        bpy.data.objects.remove(ob)
    r = scene.render
    kit.use_eevee(scene)
    r.resolution_x, r.resolution_y = size
    r.resolution_percentage = 100
    r.filepath = "/tmp/glint_frame_bench_"
    scene.eevee.taa_render_samples = samples
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.3, 0.35, 0.45, 1.0)
    bpy.ops.mesh.primitive_plane_add(size=16.0)
    bpy.context.object.data.materials.append(_material("Glossy Floor", (0.2, 0.2, 0.22), 0.1))
    objects = [
        ("primitive_uv_sphere_add", dict(radius=0.8, location=(0, 0, 0.8), segments=48, ring_count=24),
         (0.8, 0.05, 0.03)),
        ("primitive_cube_add", dict(size=1.1, location=(-2.3, 1.0, 0.55)), (0.05, 0.6, 0.08)),
        ("primitive_cylinder_add", dict(radius=0.5, depth=1.6, location=(2.3, 1.0, 0.8), vertices=48),
         (0.05, 0.1, 0.8)),
        ("primitive_torus_add", dict(location=(0.8, 2.6, 0.25), major_radius=0.8, minor_radius=0.25),
         (0.9, 0.7, 0.05)),
    ]
    for op, kwargs, colour in objects:
        getattr(bpy.ops.mesh, op)(**kwargs)
        ob = bpy.context.object
        ob.data.materials.append(_object_material(ob.name, colour, materials))
        bpy.ops.object.shade_smooth()
    bpy.ops.object.light_add(type="SUN", rotation=(math.radians(50), math.radians(10), math.radians(30)))
    bpy.context.object.data.energy = 3.0
    bpy.ops.object.camera_add(location=(0.0, -7.5, 2.2), rotation=(math.radians(78), 0.0, 0.0))
    scene.camera = bpy.context.object
    dg = bpy.context.evaluated_depsgraph_get()
    tris = 0
    for ob in scene.objects:
        if ob.type == "MESH":
            me = ob.evaluated_get(dg).to_mesh()
            me.calc_loop_triangles()
            tris += len(me.loop_triangles)
            ob.evaluated_get(dg).to_mesh_clear()
    return scene, tris


def composite_by_default(scene):
    """Give the scene the compositor a new file's Compositing workspace makes
    (host layer: Use Nodes on 3.4-4.5, a node group on 5.0+), before Glint is
    first enabled: Glint then does not own it and leaves it on when switched
    off, so that every mode but "plain" composites."""
    from glint.host import nodes as host_nodes
    host_nodes.scene_tree(scene, create=True)


def configure(scene, mode, opts):
    kit.use_eevee(scene, own_reflections=mode == "ssr")
    # Post Processing > Compositing: off for the frame without a compositor;
    # Glint would turn it on for its own frame anyway.
    scene.render.use_compositing = mode != "plain"
    g = scene.glint
    if mode == "glint":
        g.preset = opts["preset"]
        if opts.get("antialias", -1) >= 0:
            g.antialias = opts["antialias"]
        if hasattr(g, "hidden_sides"):  # an add-on from before them (--addon) has none
            g.hidden_sides = bool(opts.get("hidden-sides", 1))
        g.backend = opts["backend"]
        g.enabled = True
    else:
        g.enabled = False


def main():
    opts = _args()
    _register_addon(opts["addon"])
    for materials in opts["scenes"]:
        bench_scene(opts, materials)


def bench_scene(opts, materials):
    from glint.state import STATE
    scene, tris = build_scene(opts["size"], opts["samples"], materials)
    clear_ms = []
    from glint import compositor

    def timed_clear():
        """What the next frame's render_pre pays: the images are full-size now
        (the bench's own render_pre cleared the small ones that switching Glint
        off and on again leaves)."""
        # What render_pre does with no debug view, under the keyword of each
        # add-on version (a wrong keyword fell back to clearing every image).
        params = inspect.signature(compositor.clear_images).parameters
        kw = next(({k: True} for k in ("only_pass_through", "only_mask") if k in params), {})
        t0 = time.perf_counter()
        compositor.clear_images(**kw)
        clear_ms.append((time.perf_counter() - t0) * 1e3)
    composite_by_default(scene)
    walls = {"plain": [], "composited": [], "ssr": [], "glint": []}
    stages = {}
    first = {}  # the warm-up round's Glint stages: the process's first frame
    backends = set()
    modes = list(walls)
    for k in range(opts["rounds"] + 1):  # round 0 warms up (shaders, GL context, caches)
        for mode in modes[k % len(modes):] + modes[:k % len(modes)]:
            configure(scene, mode, opts)
            t0 = time.perf_counter()
            bpy.ops.render.render(write_still=False)
            wall = (time.perf_counter() - t0) * 1e3
            if k == 0:
                if mode == "glint" and STATE.last is not None:
                    first = dict(STATE.last.timings_ms)
                continue
            walls[mode].append(wall)
            if mode == "glint":
                last = STATE.last
                if last is None or last.status != "ok":
                    raise RuntimeError(f"Glint did not run: {last}")
                backends.add(last.backend)
                timed_clear()
                for name, ms in last.timings_ms.items():
                    stages.setdefault(name, []).append(ms)
    med = {m: statistics.median(v) for m, v in walls.items()}
    st = {name: statistics.median(v) for name, v in stages.items()}
    clear = statistics.median(clear_ms)
    added = med["glint"] - med["composited"]
    w, h = opts["size"]
    print(f"\nframe_bench: scene {materials}, Blender {bpy.app.version_string}, {w}x{h} Eevee, "
          f"{opts['samples']} samples, {tris} triangles, "
          f"preset {opts['preset']}"
          f"{'' if opts['antialias'] < 0 else ' with antialias ' + str(opts['antialias'])}"
          f"{'' if opts['hidden-sides'] else ', hidden sides off'}, "
          f"backend {opts['backend']} -> {'/'.join(sorted(backends))}, "
          f"medians of {opts['rounds']} rounds")
    print(f"  render, plain             {med['plain']:8.0f} ms   (no compositor)")
    print(f"  render, composited        {med['composited']:8.0f} ms   "
          f"(default tree: the compositor adds {med['composited'] - med['plain']:.0f} ms)")
    own = "Eevee " + kit.eevee_reflections_name(scene)
    print(f"  {own + ' adds':<26}{med['ssr'] - med['composited']:8.0f} ms   (to the composited frame)")
    print(f"  Glint adds                {added:8.0f} ms   (to the composited frame; "
          f"{med['glint'] - med['plain']:.0f} ms to the plain one)")
    for name in ("export", "rasterize", "trace", "images"):
        print(f"    {name:<22}{st.get(name, 0.0):8.1f} ms")
    print(f"    {'clear (render_pre)':<22}{clear:8.1f} ms")
    rest = added - sum(st.values())
    print(f"    {'compositor and rest':<22}{rest:8.0f} ms   (Glint adds - its stages: its group's nodes)")
    print(f"  Glint's stages in all     {sum(st.values()) + clear:8.1f} ms")
    # The first frame of a process pays what later ones reuse: fresh pages for
    # the buffers the core's pool then keeps, the GL context where GL is used.
    print("  first frame of the process (warm-up, not in the medians): "
          + ", ".join(f"{name} {first.get(name, 0.0):.0f}" for name in ("export", "rasterize", "trace", "images"))
          + f" ms, {sum(first.values()):.0f} ms in all")


if __name__ == "__main__":  # bench/world_specular_bench.py imports build_scene
    main()

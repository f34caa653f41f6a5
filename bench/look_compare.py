"""How Glint's reflections compare with Cycles' and with Eevee's own SSR, per scene.

Builds five sample scenes of its own (a glossy floor under coloured objects, the same
floor at roughness 0.3, a metal sphere in a room, a grazing corridor, the glossy floor
under objects that keep a new material's Principled defaults) and, for each,
isolates the reflections of the objects three ways:

  cycles  Cycles, every mesh visible to glossy rays minus the same frame with them all
          invisible to glossy rays (``visible_glossy = False``), which reflects the sky
          alone as Eevee's world probe does; same seed, so every path that never meets
          a reflected mesh is the same in both and cancels
  ssr     Eevee with its own reflections on minus Eevee with them off: Legacy's Screen
          Space Reflections on Blender 3.x, Eevee Next's ray tracing (at its defaults)
          on 4.2 and later
  glint   Eevee with Glint on (default preset, backend CPU) minus Eevee with it off
          (SSR off in both)
  glint_own  (only with --methods) Glint on over Eevee's own reflections (SSR or ray
          tracing on) minus plain Eevee: what a user gets who leaves Eevee's own on

Every frame is read back as linear float from an EXR (view transform Standard). Over
the reflecting pixels (on a reflecting surface, away from its edges, where Cycles'
difference is significant) it prints per method: strength = sum(m*c)/sum(c*c), the
projection of its reflection on Cycles'; error = L1(m - c)/L1(c); the false area (the
reflecting surfaces' pixels where Cycles' reflection is under the threshold but the
method changes the frame by more than it, over the reflecting pixels); the largest change
the method makes on the pixels that reflect nothing (off the reflecting surfaces); how
many pixels of the reflecting surfaces its frame leaves with a channel below 0; the
frame error, L1(frame - Cycles' frame)/L1(c) over the same pixels, the whole frame
judged rather than its change (with plain Eevee's, the frame every method starts from,
in the second table); and the median wall time it adds to the Eevee frame. The second
table also gives Glint's strength / error had Eevee shaded the scene as Cycles does: the
add-on's compositor group (its numpy model in tests/addon) run with Glint's layers on
Cycles' frame without reflections, which leaves Glint's own error (its hits, weights,
blur, bounce) without the base frame's; and how far that model is from Blender's own
composite on Eevee's frame (the model's gap, on the error's scale).
docs/look.md explains the method. Usage, from a checkout after building:

  blender -b --factory-startup -noaudio --python bench/look_compare.py -- \\
      [--size 480x270] [--cycles-samples 128] [--eevee-samples 32] [--threshold 0.01] \\
      [--rounds 2] [--out docs/look] [--addon <folder holding glint/>] [--scenes floor,rough,metal,corridor,default] \\
      [--cycles-cache DIR] [--arrays DIR] [--digits 2] [--methods ssr,glint]

--arrays DIR writes each scene's linear frames, differences, pixel masks and Glint's
last G-buffer, layers (uv, weight) and projection to DIR/<scene>.npz, for finding where
an error comes from (glint_core.trace reruns the march from them).
--digits N prints strength and error with N decimals (3 to tell two changes apart).
--methods picks the Eevee methods (Cycles is always the reference): ssr, glint and
glint_own, the last one rendering one more Eevee frame per round.
--cycles-cache keeps each scene's four Cycles frames in DIR and reads them back when the
scene, size, samples, Blender and the code that makes the frames are the same: Cycles is
most of a run's time and does not depend on Glint, so comparing Glint's changes needs it
once.

The add-on is registered from this checkout (or --addon); the core comes from
GLINT_CORE_PATH (default: <checkout>/build/python).
"""
from __future__ import annotations

import hashlib
import inspect
import math
import os
import statistics
import sys
import tempfile
import time

import bpy
import numpy as np
from mathutils import Vector

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_scene_kit as kit  # noqa: E402
ROOT = os.path.dirname(HERE)
SCENES = ("floor", "rough", "metal", "corridor", "default")
EEVEE_METHODS = ("ssr", "glint", "glint_own")
LUMA = np.array([0.2126, 0.7152, 0.0722], dtype=np.float64)  # Rec. 709, Blender's linear primaries
# Isolated reflections are signed (an object replaces the sky it hides): shown as
# 0.5 + GAIN * difference, so mid grey is "no change".
REFLECTION_GAIN = 2.0


def _at_least(parse, least, key):
    def check(value):
        v = parse(value)
        if (min(v) if isinstance(v, tuple) else v) < least:
            raise ValueError(f"--{key} {value}: too small (at least {least})")
        return v
    return check


def _args():
    return kit.script_options(
        {"size": (480, 270), "cycles-samples": 128, "eevee-samples": 32, "threshold": 0.01, "rounds": 2,
         "out": os.path.join(ROOT, "docs", "look"), "addon": os.path.join(ROOT, "addon"),
         "scenes": list(SCENES), "cycles-cache": "", "arrays": "", "digits": 2, "methods": ["ssr", "glint"]},
        {"size": _at_least(kit.frame_size, 8, "size"), "cycles-samples": _at_least(int, 2, "cycles-samples"),
         "eevee-samples": _at_least(int, 2, "eevee-samples"), "rounds": _at_least(int, 1, "rounds"),
         "threshold": float, "out": os.path.abspath, "addon": os.path.abspath,
         "scenes": kit.names_among(SCENES, "scenes"),
         "cycles-cache": os.path.abspath, "arrays": os.path.abspath,
         "digits": _at_least(int, 0, "digits"), "methods": kit.names_among(EEVEE_METHODS, "methods")})


_register_addon = kit.register_addon


# ----------------------------------------------------------------------------
# Scenes


_material = kit.principled


def _diffuse(name, colour):
    """A matte object: Specular 0, so it reflects nothing itself and only what it
    adds to the reflecting surface's reflection is measured."""
    return _material(name, colour, 0.5, specular=0.0)


def _add(op, material, smooth=True, **kwargs):
    getattr(bpy.ops.mesh, op)(**kwargs)
    ob = bpy.context.object
    ob.data.materials.append(material)
    if smooth:
        bpy.ops.object.shade_smooth()
    return ob


def _plane(name, size, location, rotation, material, scale=(1.0, 1.0, 1.0)):
    bpy.ops.mesh.primitive_plane_add(size=size, location=location, rotation=rotation)
    ob = bpy.context.object
    ob.name = name
    ob.scale = scale
    ob.data.materials.append(material)
    return ob


def _sun(rotation_deg, energy=3.0):
    bpy.ops.object.light_add(type="SUN", rotation=tuple(math.radians(a) for a in rotation_deg))
    bpy.context.object.data.energy = energy


def _camera(location, rotation_deg, lens=50.0):
    bpy.ops.object.camera_add(location=location, rotation=tuple(math.radians(a) for a in rotation_deg))
    cam = bpy.context.object
    cam.data.lens = lens
    bpy.context.scene.camera = cam


def _floor_scene(roughness, objects_material=None):
    """A glossy floor under four objects, matte (Specular 0) unless
    ``objects_material`` makes their materials."""
    made = objects_material or _diffuse
    floor = _plane("Glossy Floor", 16.0, (0, 0, 0), (0, 0, 0), _material("Floor", (0.2, 0.2, 0.22), roughness))
    objects = [
        _add("primitive_uv_sphere_add", made("Red", (0.8, 0.05, 0.03)),
             radius=0.8, location=(0, 0, 0.8), segments=48, ring_count=24),
        _add("primitive_cube_add", made("Green", (0.05, 0.6, 0.08)), smooth=False,
             size=1.1, location=(-2.3, 1.0, 0.55)),
        _add("primitive_cylinder_add", made("Blue", (0.05, 0.1, 0.8)),
             radius=0.5, depth=1.6, location=(2.3, 1.0, 0.8), vertices=48),
        _add("primitive_torus_add", made("Yellow", (0.9, 0.7, 0.05)),
             location=(0.8, 2.6, 0.25), major_radius=0.8, minor_radius=0.25),
    ]
    _sun((50, 10, 30))
    _camera((0.0, -7.5, 2.2), (78, 0, 0))
    return [floor] + (objects if objects_material else [])


def _metal_scene():
    """A metal sphere in a room seen from its open side, as a Cornell box is: the
    camera stands outside, so the floor and the three walls the sphere reflects are
    all in the frame. The room is open to the sky above and towards the camera."""
    half, height = 3.0, 4.0
    _plane("Floor", 2 * half, (0, 0, 0), (0, 0, 0), _diffuse("Floor", (0.5, 0.45, 0.4)))
    _plane("Back Wall", 2 * half, (0, half, height / 2), (math.radians(90), 0, 0),
           _diffuse("Back", (0.1, 0.3, 0.7)), scale=(1.0, height / (2 * half), 1.0))
    _plane("Left Wall", 2 * half, (-half, 0, height / 2), (math.radians(90), 0, math.radians(90)),
           _diffuse("Left", (0.7, 0.15, 0.1)), scale=(1.0, height / (2 * half), 1.0))
    _plane("Right Wall", 2 * half, (half, 0, height / 2), (math.radians(90), 0, math.radians(90)),
           _diffuse("Right", (0.15, 0.6, 0.15)), scale=(1.0, height / (2 * half), 1.0))
    _add("primitive_cube_add", _diffuse("Box", (0.9, 0.7, 0.05)), smooth=False,
         size=1.0, location=(-1.6, 1.2, 0.5))
    sphere = _add("primitive_uv_sphere_add", _material("Metal", (0.9, 0.9, 0.9), 0.1, metallic=1.0),
                  radius=1.0, location=(0.4, 0.0, 1.0), segments=64, ring_count=32)
    _sun((40, 0, 20))
    _camera((0.0, -11.0, 2.2), (84, 0, 0), lens=35.0)
    return [sphere]


def _corridor_scene():
    """Looking down a long corridor whose floor and walls are glossy; coloured
    pillars stand along the walls, the ceiling is open to the sky."""
    glossy = _material("Corridor", (0.25, 0.25, 0.27), 0.1)
    length, half_width, height = 40.0, 1.5, 3.0
    floor = _plane("Floor", 1.0, (0, length / 2 - 2, 0), (0, 0, 0), glossy, scale=(2 * half_width, length, 1))
    left = _plane("Left Wall", 1.0, (-half_width, length / 2 - 2, height / 2), (0, math.radians(90), 0), glossy,
                  scale=(height, length, 1))
    right = _plane("Right Wall", 1.0, (half_width, length / 2 - 2, height / 2), (0, math.radians(90), 0), glossy,
                   scale=(height, length, 1))
    colours = [(0.8, 0.05, 0.03), (0.05, 0.6, 0.08), (0.05, 0.1, 0.8), (0.9, 0.7, 0.05)]
    for k in range(6):
        side = -1 if k % 2 == 0 else 1
        _add("primitive_cube_add", _diffuse(f"Pillar {k}", colours[k % 4]), smooth=False,
             size=1.0, location=(side * (half_width - 0.3), 3.0 + 5.0 * k, 0.9), scale=(0.3, 0.3, 0.9))
    _plane("End Wall", 1.0, (0, length - 2, height / 2), (math.radians(90), 0, 0),
           _diffuse("End", (0.9, 0.85, 0.8)), scale=(2 * half_width, height, 1))
    _sun((30, 0, 15))
    _camera((0.0, -1.5, 0.8), (88, 0, 0), lens=28.0)
    return [floor, left, right]


BUILDERS = {
    "floor": lambda: _floor_scene(0.1),
    "rough": lambda: _floor_scene(0.3),
    "metal": _metal_scene,
    "corridor": _corridor_scene,
    "default": lambda: _floor_scene(0.1, lambda name, colour: kit.default_material(name)),
}


def build_scene(name, opts):
    scene = bpy.context.scene
    if scene.glint.enabled:
        scene.glint.enabled = False
    for ob in list(scene.objects):
        bpy.data.objects.remove(ob)
    for mat in list(bpy.data.materials):
        bpy.data.materials.remove(mat)
    r = scene.render
    r.resolution_x, r.resolution_y = opts["size"]
    r.resolution_percentage = 100
    r.film_transparent = False
    r.image_settings.file_format = "OPEN_EXR"
    r.image_settings.color_depth = "32"
    r.image_settings.exr_codec = "ZIP"
    vs = scene.view_settings
    vs.view_transform, vs.look, vs.exposure, vs.gamma = "Standard", "None", 0.0, 1.0
    scene.display_settings.display_device = "sRGB"
    scene.eevee.taa_render_samples = opts["eevee-samples"]
    # Eevee lights with the world unoccluded unless its ambient occlusion is on: the
    # corridor's walls then came out 30% brighter than Cycles' (docs/look.md), and every
    # reflection of them with it. On, at the rooms' scale, for Eevee, SSR and Glint alike.
    from glint.host import engines
    engines.set_eevee_ambient_occlusion(scene, 3.0)
    c = scene.cycles
    c.device = "CPU"
    c.samples = max(1, opts["cycles-samples"] // 2)  # two seeds, averaged
    c.use_adaptive_sampling = False  # would sample the two frames of a pair differently
    c.use_denoising = False
    c.use_animated_seed = False
    c.blur_glossy = 0.0
    world = scene.world or bpy.data.worlds.new("World")
    scene.world = world
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.3, 0.35, 0.45, 1.0)
    world.node_tree.nodes["Background"].inputs["Strength"].default_value = 1.0
    reflectors = BUILDERS[name]()
    meshes = [ob for ob in scene.objects if ob.type == "MESH"]
    return scene, reflectors, meshes


# ----------------------------------------------------------------------------
# Rendering and reading back


def render(scene, path):
    """Render the frame (compositor included) and read it back: linear float [h, w, 3],
    row 0 at the bottom; returns (pixels, wall ms)."""
    t0 = time.perf_counter()
    bpy.ops.render.render(write_still=False)
    ms = (time.perf_counter() - t0) * 1e3
    bpy.data.images["Render Result"].save_render(path, scene=scene)
    img = bpy.data.images.load(path, check_existing=False)
    try:
        w, h = img.size
        px = np.empty(w * h * 4, dtype=np.float32)
        img.pixels.foreach_get(px)
    finally:
        bpy.data.images.remove(img)
    os.remove(path)
    return px.reshape(h, w, 4)[:, :, :3].astype(np.float64), ms


def cycles_pair(scene, meshes, seed, tmp):
    """Every mesh, the reflecting surfaces too, is hidden from glossy rays in the
    frame without: the corridor's walls reflect each other and the floor, and SSR
    and Glint find those reflections too (their frame without reflects the world
    alone)."""
    scene.render.engine = "CYCLES"
    scene.cycles.seed = seed
    frames = {}
    for visible in (True, False):
        for ob in meshes:
            ob.visible_glossy = visible
        frames[visible], _ = render(scene, os.path.join(tmp, "frame.exr"))
    for ob in meshes:
        ob.visible_glossy = True
    return frames[True], frames[False]


def eevee(scene, mode, tmp, state, stages, snapshot):
    """Renders with Eevee plain, with its own reflections, with Glint, or with both
    (``glint_own``); Glint's stage timings go into ``stages``, and after a
    ``glint`` frame what :func:`glint_model_change` needs into ``snapshot``."""
    glint = mode in ("glint", "glint_own")
    kit.use_eevee(scene, own_reflections=mode in ("ssr", "glint_own"))
    g = scene.glint
    if glint:
        g.backend = "CPU"
        if not g.enabled:
            g.enabled = True
    elif g.enabled:
        g.enabled = False
    before = state.last
    px, ms = render(scene, os.path.join(tmp, "frame.exr"))
    if glint:
        # A new report, and an "ok" one: otherwise the frame is Eevee's alone and
        # every figure of Glint's would be of nothing.
        last = state.last
        if last is None or last is before or last.status != "ok":
            raise RuntimeError(f"Glint did not run on the frame: {last}")
        stages.update(getattr(last, "timings_ms", None) or {})
        if mode == "glint":
            snapshot["glint"] = glint_snapshot(scene, state)
    return px, ms


def surface_masks(scene, reflectors):
    """Per pixel (row 0 at the bottom): the camera ray through its centre hits a
    reflecting surface (``on``), or something else or nothing (``off``). Both are
    shrunk by a pixel so that antialiased edges, which mix the two, are in neither."""
    w, h = scene.render.resolution_x, scene.render.resolution_y
    cam = scene.camera
    dg = bpy.context.evaluated_depsgraph_get()
    frame = cam.data.view_frame(scene=scene)  # top right, bottom right, bottom left, top left
    tr, br, bl = (Vector(v) for v in frame[:3])
    mw = cam.matrix_world
    origin = mw.translation.copy()
    rot = mw.to_3x3()
    names = {ob.name for ob in reflectors}
    hit_reflector = np.zeros((h, w), dtype=bool)
    for y in range(h):
        fy = (y + 0.5) / h
        for x in range(w):
            fx = (x + 0.5) / w
            d = rot @ (bl + (br - bl) * fx + (tr - br) * fy)
            hit, _, _, _, ob, _ = scene.ray_cast(dg, origin, d.normalized())
            hit_reflector[y, x] = hit and ob is not None and ob.original.name in names

    def erode(m):
        out = m.copy()
        out[1:, :] &= m[:-1, :]
        out[:-1, :] &= m[1:, :]
        out[:, 1:] &= m[:, :-1]
        out[:, :-1] &= m[:, 1:]
        return out
    return erode(hit_reflector), erode(~hit_reflector)


# ----------------------------------------------------------------------------
# Figures


def _box3(a):
    padded = np.pad(a, ((1, 1), (1, 1), (0, 0)), mode="edge")
    h, w = a.shape[:2]
    return sum(padded[dy:dy + h, dx:dx + w] for dy in range(3) for dx in range(3)) / 9.0


def figures(diff, c, reflecting, elsewhere, quiet, threshold):
    """strength, error over the reflecting pixels; largest change elsewhere; false
    area: the pixels of the reflecting surfaces where Cycles' reflection is below the
    threshold (``quiet``) but the method changes the frame by more than it, as a share
    of the reflecting pixels."""
    m, ref = diff[reflecting], c[reflecting]
    strength = float((m * ref).sum() / (ref * ref).sum())
    error = float(np.abs(m - ref).sum() / np.abs(ref).sum())
    change = float(np.abs(diff[elsewhere]).max()) if elsewhere.any() else 0.0
    false_area = float((quiet & (np.abs(diff) @ LUMA > threshold)).sum() / reflecting.sum())
    return strength, error, change, false_area


def frame_error(frame, cycles_frame, c, reflecting):
    """The whole frame against Cycles' over the reflecting pixels, L1(frame -
    Cycles' frame) / L1(c), on the error's scale. The difference figures compare
    what a method changes with what the reflections change in Cycles; this one
    also sees what the method's frame started from, which they cancel: where
    Eevee's own ambient occlusion has already taken out part of the world's
    specular (Eevee Legacy), replacing all of it darkens the frame below Cycles'
    while its difference matches (docs/look.md, *Frame error*)."""
    return float(np.abs(frame[reflecting] - cycles_frame[reflecting]).sum() / np.abs(c[reflecting]).sum())


def _srgb(linear):
    x = np.clip(linear, 0.0, 1.0)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def write_png(path, display):
    """``display``: [h, w, 3] display values in [0, 1], row 0 at the bottom."""
    h, w = display.shape[:2]
    img = bpy.data.images.new(os.path.basename(path), w, h, alpha=False, float_buffer=False)
    try:
        rgba = np.ones((h, w, 4), dtype=np.float32)
        rgba[:, :, :3] = display
        img.pixels.foreach_set(rgba.ravel())
        img.filepath_raw = path
        img.file_format = "PNG"
        img.save()
    finally:
        bpy.data.images.remove(img)


def cycles_frames(name, scene, meshes, opts, tmp):
    """The two seeds' (with, without) pairs, from --cycles-cache when it has them.
    The key holds everything the frames depend on: the scene, size and samples,
    Blender's build, and the source of the code that builds the scenes and sets
    Cycles up (:data:`CYCLES_CODE`)."""
    path = None
    if opts["cycles-cache"]:
        source = "".join(inspect.getsource(f) for f in CYCLES_CODE)
        script = hashlib.sha1(source.encode()).hexdigest()[:12]
        w, h = opts["size"]
        key = f"{name}_{w}x{h}_{opts['cycles-samples']}_{bpy.app.version_string}_{bpy.app.build_hash.decode()}_{script}"
        path = os.path.join(opts["cycles-cache"], key.replace(" ", "-") + ".npz")
        if os.path.exists(path):
            z = np.load(path)
            return z["with_a"], z["without_a"], z["with_b"], z["without_b"]
    with_a, without_a = cycles_pair(scene, meshes, 1, tmp)
    with_b, without_b = cycles_pair(scene, meshes, 2, tmp)
    if path:
        os.makedirs(opts["cycles-cache"], exist_ok=True)
        np.savez(path, with_a=with_a, without_a=without_a, with_b=with_b, without_b=without_b)
    return with_a, without_a, with_b, without_b


# What the Cycles frames depend on besides the options: --cycles-cache keys on its source.
CYCLES_CODE = (_material, _diffuse, _add, _plane, _sun, _camera, _floor_scene, _metal_scene, _corridor_scene,
               build_scene, render, cycles_pair)


def glint_snapshot(scene, state):
    """What :func:`glint_model_change` needs of a Glint frame, taken just after it:
    Glint's layers, the Switches its group ran with and the world colour of S
    (None off the world colour's path: the passes' S has no Cycles counterpart)."""
    from glint import compositor
    from glint.host import engines, nodes as host_nodes
    from glint.logic import world as world_logic
    group = compositor.find_group()
    if group is None or not state.arrays:
        return None
    switch = {n: host_nodes.switch_is_on(group.nodes[n]) for n in ("use_passes", "use_bounce", "use_hidden", "use_blur")}
    if switch["use_passes"]:
        return None
    _, colour = world_logic.specular_source(compositor.describe_world(scene.world),
                                            engines.eevee_traces_reflections(scene))
    return dict(arrays=dict(state.arrays), switch=switch, colour=colour, soften=host_nodes.soften_is_a_filter())


def glint_model_change(frame, snap):
    """Glint's change to ``frame``: the add-on's compositor group, as its numpy
    model runs it (tests/addon/group_model.py: Map UV as a bilinear read, the
    blur levels as exact Gaussians), with the layers and Switches of a Glint
    frame (``snap``, :func:`glint_snapshot`'s). On Cycles' frame without
    reflections, in place of Eevee's plain frame, what is left of the error is
    Glint's own (its hits, weights, blur and bounce), not Eevee's shading. The
    model is this checkout's, whatever --addon is."""
    models = os.path.join(ROOT, "tests", "addon")
    if models not in sys.path:  # called twice a scene
        sys.path.insert(0, models)
    import group_model as gm
    from compositing_reference import gauss_clamp, map_uv
    from glint_addon_helpers import load_logic

    cg, gi = gm.cg, load_logic("group_images")
    uv, weight = (np.asarray(snap["arrays"][k], np.float32) for k in ("uv", "weight"))
    hidden = snap["arrays"].get("hidden")
    switch = snap["switch"]
    h, w = uv.shape[:2]
    blank = np.zeros_like(uv)
    images = {cg.IMAGE_UV: uv, cg.IMAGE_WEIGHT: weight,
              cg.IMAGE_HIDDEN: blank if hidden is None else np.asarray(hidden, np.float32),
              cg.IMAGE_DEBUG: blank, cg.IMAGE_POSITION: blank, cg.IMAGE_NORMAL: blank, cg.IMAGE_SPECULAR: blank,
              **gi.coarse_images(weight[..., 3], (0, 0, w, h), w, h)}
    base = np.concatenate([frame[..., :3], np.ones((h, w, 1))], axis=-1).astype(np.float32)
    light = np.broadcast_to(np.array((*snap["colour"], 1.0), np.float32), base.shape).copy()
    out = gm.evaluate_group(base, images, map_uv, gauss_clamp, specular_light=light, world_specular=True,
                            use_blur=switch["use_blur"], use_bounce=switch["use_bounce"],
                            use_hidden=switch["use_hidden"], soften_filters=snap["soften"],
                            whole_frame=True, scale_read_back=False)
    return out["Image"][..., :3] - base[..., :3]


def run_scene(name, opts, state, tmp):
    scene, reflectors, meshes = build_scene(name, opts)
    t0 = time.perf_counter()
    with_a, without_a, with_b, without_b = cycles_frames(name, scene, meshes, opts, tmp)
    cycles_s = time.perf_counter() - t0
    c_a, c_b = with_a - without_a, with_b - without_b
    c = (c_a + c_b) / 2
    cycles_frame = (with_a + with_b) / 2

    t0 = time.perf_counter()
    modes = ("plain", *opts["methods"])
    methods = ("cycles", *opts["methods"])
    frames, added_ms, timings, snapshot = {}, {m: [] for m in modes[1:]}, {}, {}
    for k in range(opts["rounds"] + 1):  # round 0 compiles shaders and warms caches: not timed
        walls = {}
        first = k % len(modes)
        for mode in modes[first:] + modes[:first]:
            frames[mode], walls[mode] = eevee(scene, mode, tmp, state, timings, snapshot)
        if k:
            for mode in added_ms:
                added_ms[mode].append(walls[mode] - walls["plain"])
    scene.glint.enabled = False
    eevee_s = time.perf_counter() - t0

    on, off = surface_masks(scene, reflectors)
    # Selected on Cycles' reflection averaged over 3x3 pixels, so that its noise does
    # not pick pixels; the figures then use the pixels as they are.
    reflecting = on & (np.abs(_box3(c)) @ LUMA > opts["threshold"])
    if not reflecting.any():
        raise RuntimeError(f"scene {name}: no pixel reflects more than --threshold {opts['threshold']}")
    diffs = {"cycles": c, **{m: frames[m] - frames["plain"] for m in opts["methods"]}}
    added = {"cycles": float("nan"), **{m: statistics.median(v) for m, v in added_ms.items()}}
    on_cycles = model_gap = None
    if snapshot.get("glint"):
        on_cycles = glint_model_change(cycles_frame - c, snapshot["glint"])
        # The model against Blender's own composite, on the frame Blender had: how far
        # the column can be trusted.
        on_plain = glint_model_change(frames["plain"], snapshot["glint"])
        model_gap = float(np.abs(on_plain[reflecting] - diffs["glint"][reflecting]).sum()
                          / np.abs(c[reflecting]).sum())
    quiet = on & ~reflecting
    rows = []
    for method in methods:
        strength, error, change, false_area = figures(diffs[method], c, reflecting, off, quiet, opts["threshold"])
        if method == "cycles":
            change = float(np.abs(c[off]).max()) if off.any() else 0.0
        # A compositor that takes out more light than the frame holds leaves
        # channels below 0: counted over the reflecting surfaces.
        frame = cycles_frame if method == "cycles" else frames[method]
        negative = int((on & (frame < -1e-4).any(axis=-1)).sum())
        rows.append((name, method, strength, error, frame_error(frame, cycles_frame, c, reflecting), change,
                     false_area, added[method], negative))
    # Cycles' own noise: one seed's reflection against the other's. The error of the
    # average of both (the reference) is about half of this.
    noise = figures(c_b, c_a, reflecting, off, quiet, opts["threshold"])[1]

    os.makedirs(opts["out"], exist_ok=True)
    for method in methods:
        frame = cycles_frame if method == "cycles" else frames[method]
        write_png(os.path.join(opts["out"], f"{name}_{method}.png"), _srgb(frame))
        write_png(os.path.join(opts["out"], f"{name}_{method}_reflection.png"),
                  np.clip(0.5 + REFLECTION_GAIN * diffs[method], 0.0, 1.0))
    mask = np.zeros(on.shape + (3,))
    mask[on] = (0.3, 0.3, 0.3)
    mask[reflecting] = (1.0, 1.0, 1.0)
    write_png(os.path.join(opts["out"], f"{name}_pixels.png"), mask)
    if opts["arrays"]:  # for locating an error: the linear frames, differences and masks
        os.makedirs(opts["arrays"], exist_ok=True)
        np.savez_compressed(os.path.join(opts["arrays"], f"{name}.npz"), reflecting=reflecting, on=on,
                            cycles_frame=cycles_frame, **{f"{m}_frame": frames[m] for m in modes},
                            **{f"{m}_diff": diffs[m] for m in methods},
                            **({} if on_cycles is None else {"glint_on_cycles_diff": on_cycles}),
                            **{f"glint_{k}": np.asarray(state.arrays[k]) for k in ("uv", "weight", "hidden", "position",
                                                                                  "normal", "specular", "projection")
                               if k in state.arrays})
    info = dict(pixels=int(reflecting.sum()), surface=int(on.sum()), elsewhere=int(off.sum()),
                on_cycles=None if on_cycles is None else figures(on_cycles, c, reflecting, off, quiet,
                                                                 opts["threshold"])[:2], model_gap=model_gap,
                noise=noise, plain_frame_error=frame_error(frames["plain"], cycles_frame, c, reflecting),
                cycles_s=cycles_s, eevee_s=eevee_s, glint_stages=timings)
    return rows, info


def main():
    opts = _args()
    _register_addon(opts["addon"])
    from glint.state import STATE
    all_rows, infos = [], {}
    with tempfile.TemporaryDirectory(prefix="glint_look_") as tmp:
        for name in opts["scenes"]:
            t0 = time.perf_counter()
            rows, info = run_scene(name, opts, STATE, tmp)
            info["total_s"] = time.perf_counter() - t0
            all_rows += rows
            infos[name] = info
            print(f"look_compare: {name} done in {info['total_s']:.0f} s", flush=True)
    w, h = opts["size"]
    print(f"\nlook_compare: Blender {bpy.app.version_string} (method ssr = Eevee's "
          f"{kit.eevee_reflections_name(bpy.context.scene)}), {w}x{h}, Cycles {opts['cycles-samples']} samples (2 seeds x "
          f"{opts['cycles-samples'] // 2}), Eevee {opts['eevee-samples']} samples, threshold "
          f"{opts['threshold']}, time added: median of {opts['rounds']} rounds, add-on {opts['addon']}\n")
    print("| scene | method | strength | error | frame error | false area | max change elsewhere "
          "| negative pixels | time added ms |")
    print("|---|---|---:|---:|---:|---:|---:|---:|---:|")
    k = opts["digits"]
    for name, method, strength, error, frame_err, change, false_area, added, negative in all_rows:
        ms = "-" if math.isnan(added) else f"{added:.0f}"
        print(f"| {name} | {method} | {strength:.{k}f} | {error:.{k}f} | {frame_err:.{k}f} | {false_area:.3f} "
              f"| {change:.4f} | {negative} | {ms} |")
    print("\n| scene | reflecting pixels | surface pixels | pixels elsewhere | Cycles seed-to-seed error "
          "| plain Eevee frame error | Glint on Cycles' frame | model's gap | Cycles s | Eevee s | Glint stages ms |")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---|")
    for name, i in infos.items():
        stages = ", ".join(f"{k} {v:.0f}" for k, v in i["glint_stages"].items())
        own = "-" if i["on_cycles"] is None else "{:.{k}f} / {:.{k}f}".format(*i["on_cycles"], k=k)
        gap = "-" if i["model_gap"] is None else f"{i['model_gap']:.3f}"
        print(f"| {name} | {i['pixels']} | {i['surface']} | {i['elsewhere']} | {i['noise']:.3f} "
              f"| {i['plain_frame_error']:.{k}f} | {own} | {gap} | {i['cycles_s']:.0f} | {i['eevee_s']:.0f} | {stages} |")


main()

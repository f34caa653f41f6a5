"""Make Glint's sample scenes.

    blender -b --factory-startup --python blend_samples/make_samples.py -- [outdir] [--only name,...]
                                                                         [--size 320x180]

Writes one small .blend per scene into ``outdir`` (default: this folder), each
with ``scene.glint.enabled = True``, tuned parameters and the compositor set up.
Run it again with another Blender to remake the files for that version; the
script uses only API that exists in 3.4 and 4.x (the Principled BSDF's inputs
are set by whichever names the running version has).

Scenes:
  mirror_floor        Eevee      a mirror floor with a red sphere, a green cube and a blue cone
  metals_roughness    Cycles     four metal tiles, roughness 0 / 0.25 / 0.4 / 0.6, under coloured pillars
  water_normal_map    Eevee      water with a tangent-space normal map (packed PNG) among rocks
  no_reflection       Eevee      only diffuse materials: Glint must change nothing
  ortho_camera        Workbench  an orthographic camera over a mirror floor
  animated_camera     Eevee      the camera circles a mirror floor over frames 1-4
"""
import math
import os
import sys

import bpy

HERE = os.path.dirname(os.path.abspath(__file__))
ADDON_PARENT = os.path.join(os.path.dirname(HERE), "addon")
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "bench"))
from blender_scene_kit import principled  # noqa: E402  (bench/, shared with the Blender benches)


def _args():
    argv = sys.argv[sys.argv.index("--") + 1:] if "--" in sys.argv else []
    out, only, size = HERE, None, (320, 180)
    i = 0
    while i < len(argv):
        a = argv[i]
        if a == "--only":
            only = set(argv[i + 1].split(","))
            i += 2
            continue
        if a == "--size":
            w, h = argv[i + 1].lower().split("x")
            size = (int(w), int(h))
            i += 2
            continue
        out = a
        i += 1
    return os.path.abspath(out), only, size


def _ensure_addon():
    """scene.glint must exist: enable the installed add-on, else the checkout's."""
    if hasattr(bpy.types.Scene, "glint"):
        return
    import addon_utils
    if any(mod.__name__ == "glint" for mod in addon_utils.modules(refresh=False)):
        addon_utils.enable("glint", default_set=False)
    if not hasattr(bpy.types.Scene, "glint"):
        sys.path.insert(0, ADDON_PARENT)
        import glint
        glint.register()


# ----------------------------------------------------------------------------
# helpers


def new_scene(name, engine, size):
    scene = bpy.data.scenes.new(name)
    for old in [s for s in bpy.data.scenes if s != scene]:
        bpy.data.scenes.remove(old)
    for coll in (bpy.data.objects, bpy.data.meshes, bpy.data.materials, bpy.data.cameras, bpy.data.lights,
                 bpy.data.images, bpy.data.worlds, bpy.data.node_groups, bpy.data.collections):
        for block in list(coll):
            if block.users == 0:
                coll.remove(block)
    from glint.host import engines  # this Blender's name for Eevee, and its own reflections
    if engine == "BLENDER_EEVEE":
        engine = engines.eevee_id()
    r = scene.render
    r.engine = engine
    r.resolution_x, r.resolution_y = size
    r.resolution_percentage = 100
    r.image_settings.file_format = "PNG"
    r.filepath = "//render/" + name + "_"
    r.dither_intensity = 0.0  # reproducible 8-bit output
    scene.frame_start = scene.frame_end = 1
    if engines.is_eevee(engine):
        scene.eevee.taa_render_samples = 16
        engines.set_eevee_traces_reflections(scene, False)  # Glint provides the reflections
    elif engine == "CYCLES":
        scene.cycles.samples = 16
        scene.cycles.use_denoising = False
        scene.cycles.device = "CPU"
    elif engine == "BLENDER_WORKBENCH":
        scene.display.shading.light = "STUDIO"
        scene.display.shading.color_type = "MATERIAL"
    world = bpy.data.worlds.new(name + " world")
    world.use_nodes = True
    world.node_tree.nodes["Background"].inputs["Color"].default_value = (0.05, 0.06, 0.08, 1.0)
    world.color = (0.05, 0.06, 0.08)
    scene.world = world
    if bpy.context.window is not None:
        bpy.context.window.scene = scene
    return scene


def link(scene, ob):
    scene.collection.objects.link(ob)
    return ob


def diffuse(name, base):
    """A Diffuse BSDF: no specular at all."""
    mat = bpy.data.materials.new(name)
    mat.use_nodes = True
    nt = mat.node_tree
    nt.nodes.remove(nt.nodes["Principled BSDF"])
    d = nt.nodes.new("ShaderNodeBsdfDiffuse")
    d.inputs["Color"].default_value = (*base, 1.0)
    nt.links.new(d.outputs["BSDF"], nt.nodes["Material Output"].inputs["Surface"])
    mat.diffuse_color = (*base, 1.0)
    return mat


def mesh_object(scene, name, verts, faces, mat, smooth=False, location=(0, 0, 0)):
    me = bpy.data.meshes.new(name)
    me.from_pydata(verts, [], faces)
    me.update()
    if smooth:
        me.polygons.foreach_set("use_smooth", [True] * len(me.polygons))
    me.materials.append(mat)
    ob = bpy.data.objects.new(name, me)
    ob.location = location
    return link(scene, ob)


def plane(scene, name, sx, sy, mat, location=(0, 0, 0), uv=False):
    v = [(-sx, -sy, 0), (sx, -sy, 0), (sx, sy, 0), (-sx, sy, 0)]
    ob = mesh_object(scene, name, v, [(0, 1, 2, 3)], mat, location=location)
    if uv:
        layer = ob.data.uv_layers.new(name="UVMap")
        for i, (u, w) in enumerate([(0, 0), (1, 0), (1, 1), (0, 1)]):
            layer.data[i].uv = (u * sx / 2, w * sy / 2)
    return ob


def uv_sphere(scene, name, radius, mat, location, segments=32, rings=16):
    verts = [(0, 0, radius)]
    for r in range(1, rings):
        th = math.pi * r / rings
        for s in range(segments):
            ph = 2 * math.pi * s / segments
            verts.append((radius * math.sin(th) * math.cos(ph), radius * math.sin(th) * math.sin(ph),
                          radius * math.cos(th)))
    verts.append((0, 0, -radius))
    faces = []
    for s in range(segments):
        faces.append((0, 1 + s, 1 + (s + 1) % segments))
    for r in range(rings - 2):
        a, b = 1 + r * segments, 1 + (r + 1) * segments
        for s in range(segments):
            faces.append((a + s, b + s, b + (s + 1) % segments, a + (s + 1) % segments))
    last = len(verts) - 1
    a = 1 + (rings - 2) * segments
    for s in range(segments):
        faces.append((a + (s + 1) % segments, a + s, last))
    return mesh_object(scene, name, verts, faces, mat, smooth=True, location=location)


def box(scene, name, size, mat, location):
    sx, sy, sz = size
    v = [(x * sx, y * sy, z * sz) for z in (-1, 1) for y in (-1, 1) for x in (-1, 1)]
    f = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    return mesh_object(scene, name, v, f, mat, location=location)


def cone(scene, name, radius, height, mat, location, segments=32):
    v = [(radius * math.cos(2 * math.pi * i / segments), radius * math.sin(2 * math.pi * i / segments), 0)
         for i in range(segments)] + [(0, 0, height), (0, 0, 0)]
    f = [(i, (i + 1) % segments, segments) for i in range(segments)]
    f += [((i + 1) % segments, i, segments + 1) for i in range(segments)]
    return mesh_object(scene, name, v, f, mat, smooth=False, location=location)


def cylinder(scene, name, radius, height, mat, location, segments=24):
    v = [(radius * math.cos(2 * math.pi * i / segments), radius * math.sin(2 * math.pi * i / segments), z)
         for z in (0, height) for i in range(segments)]
    f = [(i, (i + 1) % segments, segments + (i + 1) % segments, segments + i) for i in range(segments)]
    f.append(tuple(range(segments - 1, -1, -1)))
    f.append(tuple(range(segments, 2 * segments)))
    return mesh_object(scene, name, v, f, mat, smooth=True, location=location)


def camera(scene, location, target, lens=35.0, ortho_scale=None):
    cam = bpy.data.cameras.new("Camera")
    cam.lens = lens
    cam.clip_start, cam.clip_end = 0.1, 100.0
    if ortho_scale is not None:
        cam.type = "ORTHO"
        cam.ortho_scale = ortho_scale
    ob = link(scene, bpy.data.objects.new("Camera", cam))
    ob.location = location
    aim(ob, target)
    scene.camera = ob
    return ob


def aim(ob, target):
    from mathutils import Vector
    d = Vector(target) - Vector(ob.location)
    ob.rotation_euler = d.to_track_quat("-Z", "Y").to_euler()


def sun(scene, rotation=(math.radians(50), math.radians(10), math.radians(30)), energy=3.0):
    light = bpy.data.lights.new("Sun", "SUN")
    light.energy = energy
    ob = link(scene, bpy.data.objects.new("Sun", light))
    ob.rotation_euler = rotation
    return ob


# The samples' tuned parameters: finer and heavier than the Medium preset.
TUNED = dict(max_distance=20.0, resolution=1.0, steps=16, thickness=1.0)


def glint(scene, **params):
    g = scene.glint
    for key, value in params.items():
        setattr(g, key, value)
    g.enabled = True


def save(scene, outdir, name):
    path = os.path.join(outdir, name + ".blend")
    # A file holds the scene it was saved with: make this one the file's scene.
    if bpy.context.window is not None:
        bpy.context.window.scene = scene
    bpy.ops.wm.save_as_mainfile(filepath=path, compress=True, copy=False)
    print(f"make_samples: wrote {path} ({os.path.getsize(path)} bytes)")


# ----------------------------------------------------------------------------
# the scenes


def mirror_floor_and_objects(scene):
    """A mirror floor with a red sphere, a green cube and a blue cone on it."""
    plane(scene, "Mirror Floor", 8, 8, principled("Mirror", (0.9, 0.9, 0.9), metallic=1.0, roughness=0.0))
    red = principled("Red", (0.8, 0.03, 0.03), specular=0.0, roughness=0.6)
    green = principled("Green", (0.05, 0.6, 0.08), specular=0.0, roughness=0.6)
    blue = principled("Blue", (0.05, 0.1, 0.8), specular=0.0, roughness=0.6)
    uv_sphere(scene, "Red Sphere", 0.8, red, (0.0, 0.0, 1.0))
    box(scene, "Green Cube", (0.55, 0.55, 0.55), green, (-2.3, 1.0, 0.55))
    cone(scene, "Blue Cone", 0.6, 1.6, blue, (2.3, 1.0, 0.0))


def make_mirror_floor(outdir, size):
    scene = new_scene("mirror_floor", "BLENDER_EEVEE", size)
    mirror_floor_and_objects(scene)
    camera(scene, (0.0, -7.0, 2.2), (0.0, 0.0, 0.5))
    sun(scene)
    glint(scene, **TUNED)
    save(scene, outdir, "mirror_floor")


def make_metals(outdir, size):
    scene = new_scene("metals_roughness", "CYCLES", size)
    for i, rough in enumerate((0.0, 0.25, 0.4, 0.6)):
        x = -3.3 + 2.2 * i
        plane(scene, f"Metal {rough}", 1.0, 2.5, principled(f"Metal roughness {rough}", (0.95, 0.93, 0.88),
                                                            metallic=1.0, roughness=rough), location=(x, 0, 0))
        colour = [(0.8, 0.1, 0.05), (0.9, 0.7, 0.05), (0.1, 0.6, 0.1), (0.1, 0.2, 0.9)][i]
        cylinder(scene, f"Pillar {i}", 0.45, 1.8, principled(f"Pillar {i}", colour, specular=0.0, roughness=0.8),
                 (x, 1.2, 0.0))
    plane(scene, "Ground", 8, 8, diffuse("Ground", (0.2, 0.2, 0.2)), location=(0, 0, -0.01))
    camera(scene, (0.0, -6.5, 2.6), (0.0, 0.6, 0.4))
    sun(scene)
    glint(scene, **TUNED)
    save(scene, outdir, "metals_roughness")


def _normal_map_image(n=128):
    """A tangent-space normal map of a few crossing sine waves, encoded n * 0.5 + 0.5."""
    img = bpy.data.images.new("Water Normals", n, n, alpha=False)
    px = []
    waves = [(2, 1, 0.05, 0.0), (-1, 3, 0.03, 1.3), (5, -2, 0.015, 2.1)]
    for j in range(n):
        for i in range(n):
            x, y = i / n, j / n
            dx = dy = 0.0
            for kx, ky, amp, ph in waves:
                c = math.cos(2 * math.pi * (kx * x + ky * y) + ph) * 2 * math.pi * amp
                dx += c * kx
                dy += c * ky
            length = math.sqrt(dx * dx + dy * dy + 1.0)
            px += [(-dx / length) * 0.5 + 0.5, (-dy / length) * 0.5 + 0.5, (1.0 / length) * 0.5 + 0.5, 1.0]
    img.pixels[:] = px
    # Pack it as a PNG: write it out, load it back as a file image, embed that.
    import tempfile
    path = os.path.join(tempfile.mkdtemp(prefix="glint_samples_"), "water_normals.png")
    img.filepath_raw = path
    img.file_format = "PNG"
    img.save()
    bpy.data.images.remove(img)
    img = bpy.data.images.load(path)
    img.name = "Water Normals"
    img.colorspace_settings.name = "Non-Color"
    img.pack()
    img.filepath = "//water_normals.png"
    os.remove(path)
    return img


def make_water(outdir, size):
    scene = new_scene("water_normal_map", "BLENDER_EEVEE", size)
    # Stylised water: Glint's reflection strength is F0 (no Fresnel), so plain
    # water (F0 0.02) would barely show; Metallic 0.75 makes the reflection read.
    water = principled("Water", (0.35, 0.55, 0.65), metallic=0.75, roughness=0.05)
    nt = water.node_tree
    tex = nt.nodes.new("ShaderNodeTexImage")
    tex.image = _normal_map_image()
    nmap = nt.nodes.new("ShaderNodeNormalMap")
    nmap.inputs["Strength"].default_value = 0.35
    nt.links.new(tex.outputs["Color"], nmap.inputs["Color"])
    nt.links.new(nmap.outputs["Normal"], nt.nodes["Principled BSDF"].inputs["Normal"])
    plane(scene, "Water", 8, 8, water, uv=True)
    rock = principled("Rock", (0.45, 0.35, 0.25), specular=0.0, roughness=0.9)
    uv_sphere(scene, "Rock", 0.9, rock, (-1.6, 1.5, 0.3))
    box(scene, "Post", (0.25, 0.25, 1.2), principled("Post", (0.8, 0.5, 0.1), specular=0.0), (1.5, 0.8, 1.0))
    cylinder(scene, "Buoy", 0.35, 1.0, principled("Buoy", (0.9, 0.05, 0.05), specular=0.0), (0.2, 2.5, 0.0))
    camera(scene, (0.0, -7.5, 1.8), (0.0, 1.0, 0.4))
    sun(scene)
    glint(scene, **TUNED)
    save(scene, outdir, "water_normal_map")


def make_no_reflection(outdir, size):
    scene = new_scene("no_reflection", "BLENDER_EEVEE", size)
    plane(scene, "Floor", 8, 8, diffuse("Floor", (0.6, 0.6, 0.6)))
    uv_sphere(scene, "Sphere", 0.8, diffuse("Red", (0.8, 0.05, 0.05)), (0, 0, 0.8))
    box(scene, "Cube", (0.5, 0.5, 0.5), principled("Matte", (0.1, 0.5, 0.1), specular=0.0, roughness=1.0),
        (-2.0, 1.0, 0.5))
    camera(scene, (0.0, -7.0, 2.2), (0.0, 0.0, 0.5))
    sun(scene)
    glint(scene)
    save(scene, outdir, "no_reflection")


def make_ortho(outdir, size):
    scene = new_scene("ortho_camera", "BLENDER_WORKBENCH", size)
    mirror_floor_and_objects(scene)
    camera(scene, (0.0, -9.0, 4.0), (0.0, 0.0, 0.5), ortho_scale=7.0)
    sun(scene)
    glint(scene, **TUNED)
    save(scene, outdir, "ortho_camera")


def make_animated(outdir, size):
    scene = new_scene("animated_camera", "BLENDER_EEVEE", size)
    mirror_floor_and_objects(scene)
    cam = camera(scene, (0.0, -7.0, 2.2), (0.0, 0.0, 0.5))
    scene.frame_start, scene.frame_end = 1, 4
    for frame in range(1, 5):
        angle = math.radians(-25.0 + 50.0 * (frame - 1) / 3.0)
        cam.location = (7.0 * math.sin(angle), -7.0 * math.cos(angle), 2.2)
        aim(cam, (0.0, 0.0, 0.5))
        cam.keyframe_insert("location", frame=frame)
        cam.keyframe_insert("rotation_euler", frame=frame)
    scene.frame_set(1)
    sun(scene)
    glint(scene, **TUNED)
    save(scene, outdir, "animated_camera")


SCENES = {
    "mirror_floor": make_mirror_floor,
    "metals_roughness": make_metals,
    "water_normal_map": make_water,
    "no_reflection": make_no_reflection,
    "ortho_camera": make_ortho,
    "animated_camera": make_animated,
}


def main():
    outdir, only, size = _args()
    os.makedirs(outdir, exist_ok=True)
    bpy.context.preferences.filepaths.save_version = 0  # no .blend1 backups beside the samples
    _ensure_addon()
    for name, make in SCENES.items():
        if only is None or name in only:
            make(outdir, size)


main()

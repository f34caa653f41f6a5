"""What the compositor nodes Glint's group uses cost on this Blender, one kind at a time:
a Workbench render of an empty scene (so the render itself is nearly free) whose
compositor reads a float image the size of the frame and runs N nodes of one kind in a
chain, timed against the same render with no node (medians of --rounds renders after one
warm-up):

  fast_gauss  Blur, Fast Gaussian (the group's blur levels; its cost does not grow with
              the size, so one size stands for all)
  soften      the group's first blur level as this Blender's host layer makes it: the
              Filter node's 3x3 Soften after 4.1, the Blur node's sampled Gaussian of sigma 0.71 before
  map_uv      Map UV with a smooth uv image hitting every pixel (the group's reflection
              and second bounce)
  mix         Mix, Add (the group's many per-pixel mixes)
  read_back   the coarse levels' read-back of a canvas of one texel per 4x4 pixels, added
              to the frame: a Map UV reading it at the fine image's uv (the group's
              path after 4.1), with the Mix that adds it
  scale_back  the same read-back as a Blur of a tenth of a pixel and a Scale to the
              frame's size (the group's path on 3.x-4.1), with the Mix

  blender -b --factory-startup -noaudio --python bench/compositor_nodes.py -- \
      [--size 1920x1080] [--rounds 3] [--kinds fast_gauss:1,fast_gauss:4,soften:1,map_uv:1,mix:4]

docs/addon.md (The cost of a frame) has the figures and what they mean for a frame.
"""
from __future__ import annotations

import os
import statistics
import sys
import time

import bpy
import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, HERE)
import blender_scene_kit as kit  # noqa: E402

sys.path.insert(0, os.path.join(os.path.dirname(HERE), "addon"))
from glint import host  # noqa: E402  (the compositor tree of this Blender)
from glint.logic import compositing, group_images  # noqa: E402  (the fine image's name, the coarse canvas's grid)


def _args():
    return kit.script_options(
        {"size": (1920, 1080), "rounds": 3, "kinds": ["fast_gauss:1", "fast_gauss:4", "soften:1", "map_uv:1", "mix:4"]},
        {"size": kit.frame_size, "rounds": int, "kinds": lambda v: v.split(",")})


def _image(name, pixels):
    h, w = pixels.shape[:2]
    img = bpy.data.images.new(name, w, h, float_buffer=True)
    img.pixels.foreach_set(pixels.astype(np.float32).ravel())
    return img


def _scene(size):
    scene = bpy.context.scene
    for ob in list(scene.objects):
        bpy.data.objects.remove(ob)
    scene.render.engine = "BLENDER_WORKBENCH"
    scene.render.resolution_x, scene.render.resolution_y = size
    scene.render.resolution_percentage = 100
    bpy.ops.object.camera_add()
    scene.camera = bpy.context.object
    w, h = size
    rng = np.random.default_rng(1)
    frame = _image("bench frame", rng.random((h, w, 4)))
    cw, ch = group_images.coarse_size(w, h)
    _image("bench coarse", rng.random((ch, cw, 4)))
    grid = group_images.coarse_images(np.zeros((h, w), np.float32), (0, 0, w, h), w, h)
    _image("bench fine", grid[compositing.IMAGE_FINE])
    yy, xx = np.mgrid[0:h, 0:w].astype(np.float32)
    uv = np.ones((h, w, 4), np.float32)
    uv[..., 0] = (xx + 0.5) / w  # a smooth uv: Map UV's filter footprint stays a pixel
    uv[..., 1] = (yy + 0.5) / h
    return scene, frame, _image("bench uv", uv)


def _chain(tree, kind, count, frame, uv):
    """Image -> count nodes of `kind` -> the frame's output, made through the add-on's
    host layer (so the same node and options as Glint's group on every Blender)."""
    hn = host.nodes
    for node in list(tree.nodes):
        tree.nodes.remove(node)
    images = {"frame": frame, "uv": uv, "coarse": bpy.data.images["bench coarse"],
              "fine": bpy.data.images["bench fine"]}
    source = hn.new_node(tree, "image", {"image": "frame"}, images.get)
    out = hn.output_socket(source, "image", 0)
    for _ in range(count):
        if kind == "fast_gauss":
            node = hn.new_node(tree, "blur", {"sigma": 50.0})
            tree.links.new(out, hn.input_socket(node, "blur", 0))
            kind_out = "blur"
        elif kind == "map_uv":
            uv_node = hn.new_node(tree, "image", {"image": "uv"}, images.get)
            node = hn.new_node(tree, "map_uv", {})
            tree.links.new(out, hn.input_socket(node, "map_uv", 0))
            tree.links.new(hn.output_socket(uv_node, "image", 0), hn.input_socket(node, "map_uv", 1))
            kind_out = "map_uv"
        elif kind == "soften":  # the first blur level: a Filter node where the host runs it as one
            node = hn.new_node(tree, "soften", {"sigma": 0.71})
            tree.links.new(out, hn.input_socket(node, "soften", 0))
            kind_out = "soften"
        elif kind in ("mix", "read_back", "scale_back"):
            added = hn.output_socket(source, "image", 0)
            if kind != "mix":
                coarse = hn.output_socket(hn.new_node(tree, "image", {"image": "coarse"}, images.get), "image", 0)
                added = _read_back(tree, kind, coarse, images)
            node = hn.new_node(tree, "mix", {"blend": "ADD"})
            hn.input_socket(node, "mix", 0).default_value = 1.0
            tree.links.new(out, hn.input_socket(node, "mix", 1))
            tree.links.new(added, hn.input_socket(node, "mix", 2))
            kind_out = "mix"
        else:
            raise SystemExit(f"--kinds: unknown kind {kind!r} "
                             "(fast_gauss, soften, map_uv, mix, read_back, scale_back)")
        out = hn.output_socket(node, kind_out, 0)
    tree.links.new(out, hn.add_frame_output(tree, (600, 0)))


def _read_back(tree, kind, coarse, images):
    """The coarse canvas brought to the frame's size as the group's two paths do it."""
    hn = host.nodes
    if kind == "read_back":
        fine = hn.new_node(tree, "image", {"image": "fine"}, images.get)
        node = hn.new_node(tree, "map_uv", {})
        tree.links.new(coarse, hn.input_socket(node, "map_uv", 0))
        tree.links.new(hn.output_socket(fine, "image", 0), hn.input_socket(node, "map_uv", 1))
        return hn.output_socket(node, "map_uv", 0)
    kept = hn.new_node(tree, "keep", {})
    tree.links.new(coarse, hn.input_socket(kept, "keep", 0))
    node = hn.new_node(tree, "frame_scale", {})
    tree.links.new(hn.output_socket(kept, "keep", 0), hn.input_socket(node, "frame_scale", 0))
    return hn.output_socket(node, "frame_scale", 0)


def main():
    opts = _args()
    scene, frame, uv = _scene(opts["size"])
    tree = host.nodes.scene_tree(scene, create=True)
    scene.render.use_compositing = True
    runs = [("none", 0)] + [(k.split(":")[0], int(k.split(":")[1])) for k in opts["kinds"]]
    medians = {}
    for kind, count in runs:
        _chain(tree, kind, count, frame, uv)
        walls = []
        for r in range(opts["rounds"] + 1):
            t0 = time.perf_counter()
            bpy.ops.render.render()
            if r:
                walls.append((time.perf_counter() - t0) * 1e3)
        medians[(kind, count)] = statistics.median(walls)
    w, h = opts["size"]
    base = medians[("none", 0)]
    print(f"\ncompositor_nodes: Blender {bpy.app.version_string}, {w}x{h}, medians of {opts['rounds']} renders")
    print("| nodes | render ms | added ms | per node ms |")
    print("|---|---|---|---|")
    for (kind, count), ms in medians.items():
        per = (ms - base) / count if count else 0.0
        print(f"| {kind} x {count} | {ms:.0f} | {ms - base:.0f} | {per:.0f} |")


if __name__ == "__main__":
    main()

"""The compositor side: Glint's node group, its images, and its place in the
scene's node tree.

The group (``logic/compositing.py`` describes it) sits right after the Render
Layers node of the view layer Glint exports: every link that left the Render
Layers' Image output now leaves the group's Image output, so the Composite
node, the Viewer and any further user nodes see the frame with reflections.
Switching Glint off puts those links back and removes what Glint added.
"""
from __future__ import annotations

import hashlib
from typing import Dict, Optional, Tuple

import bpy
import numpy as np

from . import gather
from .host import data as host_data, engines, nodes as host_nodes, writes
from .logic import compositing as cg
from .logic import group_images as gi
from .logic import materials
from .logic import projection
from .logic import settings as settings_logic
from .logic import world as world_logic
from .state import STATE

LAYOUT_KEY = "glint_layout"


# A group saved with another hash (an older description, or lowered for a
# Blender whose nodes take their options otherwise) is rebuilt. MUTE_RULE is
# in it so that an older Glint, which never writes a node's mute, rebuilds a
# group this one muted parts of (cg.dead_nodes) instead of running it so.
MUTE_RULE = "dead nodes muted"
LAYOUT_HASH = hashlib.sha1((repr(sorted(cg.GROUP_NODES.items())) + repr(cg.GROUP_LINKS) +
                            repr(cg.GROUP_OUTPUTS) + repr(host_nodes.options_are_sockets()) +
                            host_nodes.lowered("soften") + MUTE_RULE).encode()).hexdigest()[:12]


# ----------------------------------------------------------------------------
# Images


def ensure_image(name: str, width: int = 4, height: int = 4):
    img = bpy.data.images.get(name)
    if img is None:
        img = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
        img.generated_color = (0.0, 0.0, 0.0, 1.0)
    # Data, not colour: no view transform, no premultiplication of the alpha.
    # Set only when different: each assignment runs an RNA update (the colour
    # space one frees the image's buffers and tags the depsgraph), which must
    # not happen per frame on a render thread. There, a new image's (one the
    # user deleted) may meet a panel's draw (host/writes.py).
    writes.retrying(lambda: _data_settings(img))
    return img


def _data_settings(img) -> None:
    if img.colorspace_settings.name != "Non-Color":
        img.colorspace_settings.name = "Non-Color"
    if img.alpha_mode != "CHANNEL_PACKED":
        img.alpha_mode = "CHANNEL_PACKED"
    if img.use_fake_user:
        img.use_fake_user = False


# Images written since they were last cleared. None: not known yet this session
# (a saved file may hold packed pixels), so the first clear clears them all.
_filled = None
# Per image, what its pixels were made from (``fill_images``'s ``keys``): an
# image whose key has not changed since it was written, and which no clear has
# zeroed since, is not written again.
_filled_from: Dict[str, object] = {}


# Per image, a buffer that a region's rows are gathered into for foreach_set
# (which wants contiguous memory): kept between frames, it is not a fresh
# allocation whose pages the kernel faults in and zeroes each frame (~5 ms
# for a 15 MB region at 1080p).
_gather: Dict[str, np.ndarray] = {}


def _contiguous(name: str, arr: np.ndarray) -> np.ndarray:
    arr = np.asarray(arr)
    if arr.dtype == np.float32 and arr.flags.c_contiguous:
        return arr
    buf = _gather.get(name)
    if buf is None or buf.size < arr.size:
        buf = _gather[name] = np.empty(arr.size, np.float32)
    out = buf[:arr.size].reshape(arr.shape)
    np.copyto(out, arr, casting="same_kind")
    return out


def _resize(img, w: int, h: int) -> None:
    """A generated image is regenerated at its new size (27 ms at 4K); scale()
    resamples the old pixels (224 ms from 1080p to 4K), but Blender lets it
    through where it refuses the attribute writes: on the render thread while
    the main thread draws a panel, and for good once its read-only flag is
    stuck (host/writes.py)."""
    if img.source == "GENERATED":
        try:
            img.generated_width, img.generated_height = w, h
        except AttributeError as exc:
            if not writes.refused(exc):
                raise
    if tuple(img.size) != (w, h):
        img.scale(w, h)


def fill_images(images: Dict[str, np.ndarray], keys: Optional[Dict[str, object]] = None) -> None:
    """Write float32 [h, w, 4] arrays (row 0 at the bottom) into the named images.
    ``keys``: per image, what its array was made from; an image that already
    holds the array of the same key is left as it is (the coarse levels' fine
    image depends only on the region: an animation whose region keeps still
    writes its 33 MB once)."""
    global _filled
    keys = keys or {}
    for name, arr in images.items():
        key = keys.get(name)
        if key is not None and _filled is not None and name in _filled and _filled_from.get(name) == key:
            continue
        _filled_from.pop(name, None)
        arr = _contiguous(name, arr)
        h, w = arr.shape[:2]
        img = ensure_image(name, w, h)
        if tuple(img.size) != (w, h):
            _resize(img, w, h)
        img.pixels.foreach_set(arr.ravel())
        img.update()
        if _filled is not None:
            _filled.add(name)
            if key is not None:
                _filled_from[name] = key


def forget_filled() -> None:
    """A newly loaded file may hold packed pixels in Glint's images: the next
    clear must zero them all, not only the ones this session wrote."""
    global _filled
    _filled = None


def clear_images(only_pass_through: bool = False) -> None:
    """Zero the Glint images that hold a frame: with a zero UV image (vis 0) the
    group passes the render through unchanged (D = 0, out = frame + 0), so a
    frame Glint cannot handle composites as if Glint were off. Images are not
    copied for the render (under F12 the node tree is, before
    ``frame_change_post``: a mute set there is not seen), so what is written
    here is what the compositor reads.

    ``only_pass_through``: zero the UV image alone, which is all the composited
    frame reads through; the weight and G-buffer images only reach the frame
    through it (or a debug view, or the layers EXR), and stay listed as filled
    for the next full clear. At 1920x1080 each image is 33 MB to write."""
    global _filled
    names = cg.ALL_IMAGES if _filled is None else sorted(_filled)
    if only_pass_through:
        names = [n for n in names if n == cg.PASS_THROUGH_IMAGE]
    for name in names:
        img = bpy.data.images.get(name)
        if img is None:
            continue
        w, h = img.size
        if w * h == 0:
            continue
        img.pixels.foreach_set(np.zeros(w * h * 4, dtype=np.float32))
        img.update()
    if not only_pass_through:
        _filled = set()
    elif _filled is not None:
        _filled.discard(cg.PASS_THROUGH_IMAGE)


# ----------------------------------------------------------------------------
# The node group


def find_group():
    """Glint's node group, or None: a compositor group carrying ``LAYOUT_KEY`` (every
    group Glint builds does), the one named ``GROUP_NAME`` if there are several.

    Not the name alone: node groups of every kind share one name space, and a
    user's own group called "Glint" (a shader group, say) would otherwise be taken
    for Glint's, never be current, and be rebuilt beside on every set-up (F12
    then never gets reflections) and removed when Glint is switched off."""
    ours = [g for g in bpy.data.node_groups if g.bl_idname == "CompositorNodeTree" and LAYOUT_KEY in g]
    return next((g for g in ours if g.name == cg.GROUP_NAME), ours[0] if ours else None)


def build_group():
    """(Re)build the node group from the description; returns it."""
    group = find_group()
    if _group_is_current(group):
        return group
    if group is None:
        group = bpy.data.node_groups.new(cg.GROUP_NAME, "CompositorNodeTree")
    group.nodes.clear()
    # A group saved by an older Glint is rebuilt in place. Its sockets are kept
    # when they are already the ones wanted: clearing them would cut every link
    # the scenes' trees make to the group node (the Composite's input with them),
    # and the upgraded file would render black.
    if host_nodes.group_sockets(group) != (list(cg.GROUP_INPUTS), list(cg.GROUP_OUTPUTS)):
        host_nodes.clear_group_sockets(group)
        for name, kind in cg.GROUP_INPUTS:
            sock = host_nodes.new_group_socket(group, name, kind, "INPUT")
            if name != "Image":  # an engine without the pass adds nothing to replace
                sock.default_value = (0.0, 0.0, 0.0, 1.0)
        for name, kind in cg.GROUP_OUTPUTS:
            host_nodes.new_group_socket(group, name, kind, "OUTPUT")
    nodes = {cg.GROUP_IN: group.nodes.new("NodeGroupInput"), cg.GROUP_OUT: group.nodes.new("NodeGroupOutput")}
    nodes[cg.GROUP_IN].location = (-900, 0)
    nodes[cg.GROUP_OUT].location = (1300, 0)
    for i, (name, (kind, props, defaults)) in enumerate(cg.GROUP_NODES.items()):
        node = host_nodes.new_node(group, kind, props, image_of=ensure_image)
        node.name = node.label = name
        node.location = (-600 + 250 * (i % 8), 600 - 220 * (i // 8))
        for index, value in defaults.items():
            host_nodes.input_socket(node, kind, index).default_value = value
        nodes[name] = node

    def kind(name):
        return cg.GROUP_NODES[name][0] if name in cg.GROUP_NODES else None

    for src, so, dst, di in cg.GROUP_LINKS:
        out = nodes[src].outputs[so] if kind(src) is None else host_nodes.output_socket(nodes[src], kind(src), so)
        inp = nodes[dst].inputs[di] if kind(dst) is None else host_nodes.input_socket(nodes[dst], kind(dst), di)
        group.links.new(out, inp)
    group[LAYOUT_KEY] = LAYOUT_HASH
    return group


def update_group(glint, rough: bool = True, bounce: bool = False, world_specular: bool = False,
                 frame_size: Optional[Tuple[int, int]] = None) -> None:
    """Push the values the group reads: the debug switches, whether the blur
    levels run (``rough``: some reflective material of the scene is rough),
    whether the second bounce does, whether S is the world colour x W
    (``world_specular``) and whether hidden sides are shown (the frame then
    fills the hidden image: ``settings.shows_hidden_sides``), where the
    coarse read-back's Scale reads for a ``frame_size`` (width, height) render
    (gi.coarse_grid_shift or gi.coarse_scale_offset, where the host needs
    one), and the mute of the nodes that only a Switch's dropped side reads."""
    group = find_group()
    if group is None:
        return
    hidden = settings_logic.shows_hidden_sides({"fill_hidden": glint.fill_hidden,
                                                "hidden_sides": glint.hidden_sides})
    states = cg.switch_states(glint.debug_view, rough, bounce, world_specular, hidden,
                              host_nodes.soften_is_a_filter(), not host_nodes.compositor_places_regions(),
                              host_nodes.coarse_read_back_by_scale())
    for name, check in states.items():
        node = group.nodes.get(name)
        if node is not None:
            host_nodes.set_switch(node, check)
    by_domain = host_nodes.scale_reads_by_domain()
    grid = group.nodes.get("coarse_grid")
    if grid is not None and by_domain and frame_size is not None:
        for index, value in enumerate(gi.coarse_grid_shift(*frame_size), start=1):
            sock = host_nodes.input_socket(grid, "translate", index)
            value = host_nodes.stored_float(value)
            if sock.default_value != value:
                sock.default_value = value
    scale = group.nodes.get("coarse_to_frame")
    if scale is not None and host_nodes.scale_offset_places_read() and frame_size is not None:
        host_nodes.set_scale_offset(scale, *gi.coarse_scale_offset(*frame_size))
    # What only a dropped side of a Switch reads is muted: Blender 5.x
    # computes both sides (cg.dead_nodes).
    dead = cg.dead_nodes(states)
    if not by_domain:
        dead = dead | {"coarse_grid"}  # no move to make: a muted node passes its image through
    for name in cg.GROUP_NODES:
        node = group.nodes.get(name)
        if node is not None and node.mute != (name in dead):
            node.mute = name in dead


def render_frame_size(scene) -> Optional[Tuple[int, int]]:
    """The (width, height) the scene renders and composites at, or None when
    it renders nothing (a percentage or a cropped render region that leaves no
    pixel)."""
    try:
        return gather.render_window(scene.render).image_size
    except projection.ProjectionError:
        return None


def scene_reflectors(scene) -> Tuple[int, bool]:
    """How many of the scene's objects count for Auto's second bounce (a sharp
    or metallic reflective material: ``logic.compositing.counts_for_second_bounce``),
    and whether a reflective material is rough enough for the blur (it has a lobe:
    every shininess but a mirror's, ``logic.materials.is_glossy``). Read from the materials, not the frame, because the render
    takes the node tree's values before the frame is exported (module docstring of
    handlers); objects hidden from the render are not counted."""
    of_material = {}  # material name -> (counts for the bounce, rough)
    count, rough = 0, False
    for ob in scene.objects:
        if ob.hide_render:
            continue
        counts = False
        for slot in getattr(ob, "material_slots", ()):
            mat = slot.material
            if mat is None:
                continue
            if mat.name not in of_material:
                spec, _ = gather.material_info(mat)
                of_material[mat.name] = (cg.counts_for_second_bounce(spec.reflective, spec.alpha, spec.amount),
                                         spec.reflective and materials.is_glossy(spec.alpha))
            c, g = of_material[mat.name]
            counts = counts or c
            rough = rough or g
        count += counts
    return count, rough


# ----------------------------------------------------------------------------
# The scene's tree


def target_view_layer(scene):
    name = scene.glint.view_layer
    if name and name in scene.view_layers:
        return scene.view_layers[name]
    for vl in scene.view_layers:
        if vl.use:
            return vl
    return scene.view_layers[0]


def _render_layers_node(tree, scene, view_layer):
    for node in tree.nodes:
        if node.bl_idname == "CompositorNodeRLayers" and node.layer == view_layer.name and \
                (node.scene is None or node.scene == scene):
            return node
    return None


def _is_default_tree(tree) -> bool:
    return tuple(sorted(n.bl_idname for n in tree.nodes)) in host_nodes.default_tree_kinds()


class SetupIncomplete(Exception):
    """The compositor set-up needs changes that :func:`ensure` was told not to make."""


def _group_is_current(group) -> bool:
    if group is None or group.get(LAYOUT_KEY) != LAYOUT_HASH:  # find_group checked the kind
        return False
    # Every image node still has its image (a user may have deleted one).
    for name, (kind, props, _) in cg.GROUP_NODES.items():
        if "image" in props:
            node = group.nodes.get(name)
            if node is None or node.image is None or node.image.name != props["image"]:
                return False
    return True


def _ensure_render_layers_node(tree, scene, view_layer, change):
    """The Render Layers node of ``view_layer``, made if the tree has none."""
    rl = _render_layers_node(tree, scene, view_layer)
    if rl is None:
        change(f"no Render Layers node for view layer {view_layer.name!r}")
        rl = tree.nodes.new("CompositorNodeRLayers")
        rl.scene = scene
        rl.layer = view_layer.name
        rl.location = (-300, 0)
    return rl


def _ensure_group_node(tree, group, rl, change):
    """The scene tree's Glint node, using ``group``; a new one takes over every
    link the Render Layers node's image fed, so everything that read the
    render's image now reads the composited one."""
    gnode = tree.nodes.get(cg.GROUP_NODE_NAME)
    if gnode is None or gnode.bl_idname != "CompositorNodeGroup":
        change("the Glint node is missing from the compositor")
        gnode = tree.nodes.new("CompositorNodeGroup")
        gnode.name = cg.GROUP_NODE_NAME
        gnode.label = "Glint Reflections"
        gnode.node_tree = group
        gnode.location = (rl.location.x + 300, rl.location.y)
        for link in list(rl.outputs["Image"].links):
            to_socket = link.to_socket
            tree.links.remove(link)
            tree.links.new(gnode.outputs["Image"], to_socket)
    elif gnode.node_tree != group:
        change("the Glint node uses another node group")
        gnode.node_tree = group
    return gnode


def ensure(scene, allow_changes: bool = True) -> Optional[str]:
    """Put the group in the scene's compositor (idempotent). Returns a sentence
    naming what Glint had to turn on for its reflections to reach the frame (an
    old file's compositor off, no Composite node, Post Processing > Compositing
    off), or None when nothing was needed.

    Nothing is written when the set-up is already in place, so a render thread
    can call this. With ``allow_changes=False`` a needed structural change (nodes,
    links, the group, its images) raises :class:`SetupIncomplete` instead; values
    the render needs now (Post Processing > Compositing, blur size, debug switches,
    the EXR folder, an old file's muted group node) are still written when they
    differ: the render copies its settings after ``render_init``."""
    def change(what: str) -> None:
        if not allow_changes:
            raise SetupIncomplete(what)

    glint = scene.glint
    turned_on = []
    if host_nodes.tree_switch_is_off(scene):
        change("the compositor's nodes are off")
        host_nodes.scene_tree(scene, create=True)
        glint.owns_use_nodes = True
        turned_on.append(host_nodes.tree_switch_label())
    tree = host_nodes.scene_tree(scene)
    group = find_group()
    if not _group_is_current(group):
        change("Glint's node group is missing or out of date")
        group = build_group()
    view_layer = target_view_layer(scene)
    rl = _ensure_render_layers_node(tree, scene, view_layer, change)
    gnode = _ensure_group_node(tree, group, rl, change)
    # The frame is what the Composite node (5.0+: the Group Output) receives:
    # a tree without one (an old file's Viewer-only tree) would write the bare
    # render, or refuse to render.
    if not host_nodes.frame_outputs(tree):
        change("the compositor has no Composite node")
        sock = host_nodes.add_frame_output(tree, (gnode.location.x + 300, gnode.location.y + 200))
        tree.links.new(gnode.outputs["Image"], sock)
        turned_on.append(f"{host_nodes.frame_output_label()} fed by Glint")
    # The group is never muted: a frame Glint does not handle gets zeroed images
    # instead (clear_images), which the render sees; older versions muted it.
    if gnode.mute:
        gnode.mute = False
    if not any(l.from_node == rl for l in gnode.inputs["Image"].links):
        change("the Glint node is not fed by the Render Layers node")
        tree.links.new(rl.outputs["Image"], gnode.inputs["Image"])
    _ensure_engine_passes(scene, tree, rl, gnode, view_layer, change, turned_on)
    reflective_objects, rough = scene_reflectors(scene)
    STATE.second_bounce = cg.use_second_bounce(glint.second_bounce, reflective_objects)
    update_group(glint, rough, STATE.second_bounce,  # values only, written when they differ
                 STATE.specular_source == world_logic.SOURCE_WORLD, render_frame_size(scene))
    # A Composite node that receives nothing writes a black frame: feed it
    # Glint's image (a group rebuilt by an older Glint could leave it so).
    for sock in host_nodes.frame_outputs(tree):
        if not sock.links:
            change("the Composite node receives nothing")
            tree.links.new(gnode.outputs["Image"], sock)
    _ensure_exr_node(scene, tree, gnode, change)
    if not scene.render.use_compositing:
        # A value, not a structure: set even from the render thread, before the
        # render reads it. Switching Glint off turns it off again.
        scene.render.use_compositing = True
        glint.owns_use_compositing = True
        turned_on.append("Output Properties > Post Processing > Compositing")
    if not turned_on:
        return None
    return f"turned on {' and '.join(turned_on)} so that its reflections reach the frame"


def describe_world(world) -> Optional[dict]:
    """The plain description of a world that :func:`world_logic.specular_source` reads."""
    if world is None:
        return None
    if not host_data.uses_nodes(world):
        return {"use_nodes": False, "color": tuple(world.color)}
    outputs = [n for n in world.node_tree.nodes if n.bl_idname == "ShaderNodeOutputWorld"]
    # Eevee renders the active output (is_active_output), targets ALL or EEVEE.
    active = [n for n in outputs if n.is_active_output and n.target in ("ALL", "EEVEE")] or outputs
    if not active:
        return {"use_nodes": True, "surface": None}
    links = active[0].inputs["Surface"].links
    if not links:
        return {"use_nodes": True, "surface": None}
    node = links[0].from_node
    if node.bl_idname != "ShaderNodeBackground":
        return {"use_nodes": True, "surface": {"kind": node.bl_idname, "color": None, "strength": None}}
    colour, strength = node.inputs["Color"], node.inputs["Strength"]
    return {"use_nodes": True, "surface": {
        "kind": node.bl_idname,
        "color": None if colour.is_linked else tuple(colour.default_value),
        "strength": None if strength.is_linked else float(strength.default_value)}}


def _link_once(tree, from_socket, to_socket, change, what: str) -> None:
    if not any(l.from_socket == from_socket for l in to_socket.links):
        change(what)
        for link in list(to_socket.links):
            tree.links.remove(link)
        tree.links.new(from_socket, to_socket)


def _ensure_node(tree, name: str, idname: str, location, change, missing: str):
    """The node called ``name`` of type ``idname``, made (and ``change`` told why) if absent."""
    node = tree.nodes.get(name)
    if node is None or node.bl_idname != idname:
        change(missing)
        node = tree.nodes.new(idname)
        node.name = node.label = name
        node.location = location
    return node


def _release_specular_passes(scene, view_layer) -> None:
    """Turn Eevee's Specular Light and Color passes off again if Glint turned them on."""
    if scene.glint.owns_specular_passes:
        for _, _, flag in cg.ENGINE_PASSES:
            setattr(view_layer, flag, False)
        scene.glint.owns_specular_passes = False


def _ensure_engine_passes(scene, tree, rl, gnode, view_layer, change, turned_on) -> None:
    """Feed the group the engine's own specular S (what a found reflection
    replaces). Eevee under a uniform world: the world colour (an RGB node) times
    the weight image W, no render pass (logic/world.py). Otherwise Eevee's
    Specular Light and Specular Color passes; an engine that does not write them
    leaves the sockets unavailable and the group's inputs at black (nothing
    replaced). Records the source in ``STATE.specular_source``."""
    eevee = engines.is_eevee(scene.render.engine)
    light_in, colour_in = (group_input for _, group_input, _ in cg.ENGINE_PASSES)
    STATE.specular_source = None
    if not eevee:
        rgb = tree.nodes.get(cg.WORLD_COLOUR_NODE)
        if rgb is not None and any(l.from_node == rgb for l in gnode.inputs[light_in].links):
            # Set up under Eevee: a black colour makes S = 0 (the engine has no
            # world specular to replace) with no change of structure, which a
            # render thread may not make.
            host_nodes.set_rgb_value(rgb, (0.0, 0.0, 0.0, 1.0))
            return
    source, colour = (world_logic.specular_source(describe_world(scene.world), engines.eevee_traces_reflections(scene))
                      if eevee else (world_logic.SOURCE_PASSES, None))
    if source == world_logic.SOURCE_WORLD:
        rgb = _ensure_node(tree, cg.WORLD_COLOUR_NODE, host_nodes.idname("rgb"), (gnode.location.x - 300,
                                                                             gnode.location.y - 250),
                           change, "the world colour node is missing")
        host_nodes.set_rgb_value(rgb, (*colour, 1.0))  # a value: written from the render thread too
        weight = _ensure_node(tree, cg.WORLD_WEIGHT_NODE, "CompositorNodeImage", (gnode.location.x - 300,
                                                                                 gnode.location.y - 450),
                              change, "the world weight node is missing")
        if weight.image is None or weight.image.name != cg.IMAGE_WEIGHT:
            change("the world weight node lost its image")
            weight.image = ensure_image(cg.IMAGE_WEIGHT)
        _link_once(tree, rgb.outputs[0], gnode.inputs[light_in], change, "S is not fed by the world colour")
        _link_once(tree, weight.outputs[0], gnode.inputs[colour_in], change, "S is not fed by the weight image")
        # Values: written even from the render thread, which copies the view
        # layers after render_init.
        _release_specular_passes(scene, view_layer)
    else:
        for name in (cg.WORLD_COLOUR_NODE, cg.WORLD_WEIGHT_NODE):
            if tree.nodes.get(name) is not None:
                change("the world colour nodes are no longer wanted")
                tree.nodes.remove(tree.nodes[name])
        # The passes first: a Blender may list a Render Layers output only once
        # its pass is on (values, which the render thread may write).
        if eevee:
            off = [flag for _, _, flag in cg.ENGINE_PASSES if not getattr(view_layer, flag)]
            if off:
                for flag in off:
                    setattr(view_layer, flag, True)
                scene.glint.owns_specular_passes = True
                turned_on.append("Eevee's Specular Light and Specular Color passes (what a reflection replaces)")
        for pass_key, group_input, _ in cg.ENGINE_PASSES:
            output = host_nodes.pass_output(rl, pass_key)
            if output is not None:
                _link_once(tree, output, gnode.inputs[group_input], change,
                           f"the engine's {group_input} pass is not linked to the Glint node")
    if eevee:
        STATE.specular_source = source


def turned_on_notice(scene) -> Optional[str]:
    """The panel's note of what Glint switched on in this scene, or None."""
    glint = scene.glint
    what = [label for flag, label in ((glint.owns_use_nodes, "the compositor's nodes"),
                                      (glint.owns_use_compositing, "Post Processing > Compositing"),
                                      (glint.owns_specular_passes, "Eevee's Specular Light and Color passes"))
            if flag]
    return f"Glint turned on {' and '.join(what)}" if what else None


def exr_base_path(scene) -> str:
    """'<output dir>/<output name>glint_' : the layers' EXR sits next to the frames."""
    # Frame-number placeholders belong to the frames' names, not the layers'.
    return (scene.render.filepath or "//").replace("#", "") + "glint_"


def _ensure_exr_node(scene, tree, gnode, change) -> None:
    node = tree.nodes.get(cg.EXR_NODE_NAME)
    if not scene.glint.write_layers_exr:
        if node is not None:
            change("the layers EXR node is no longer wanted")
            tree.nodes.remove(node)
        return
    if node is None:
        change("the layers EXR node is missing")
        node = host_nodes.new_exr_output(tree, [slot for slot, _ in cg.EXR_LAYERS],
                                         (gnode.location.x + 300, gnode.location.y - 300))
        node.name = cg.EXR_NODE_NAME
        node.label = "Glint layers (EXR)"
        for slot, output in cg.EXR_LAYERS:
            tree.links.new(gnode.outputs[output], host_nodes.exr_input(node, slot))
    host_nodes.set_exr_path(node, exr_base_path(scene))


def remove(scene) -> None:
    """Take Glint out of the compositor, reconnecting what it sat between."""
    tree = host_nodes.scene_tree(scene)
    glint = scene.glint
    if tree is not None:
        gnode = tree.nodes.get(cg.GROUP_NODE_NAME)
        if gnode is not None:
            sources = [l.from_socket for l in gnode.inputs["Image"].links]
            targets = [l.to_socket for l in gnode.outputs["Image"].links]
            tree.nodes.remove(gnode)
            if sources:
                for t in targets:
                    tree.links.new(sources[0], t)
        for name in (cg.EXR_NODE_NAME, cg.WORLD_COLOUR_NODE, cg.WORLD_WEIGHT_NODE):
            node = tree.nodes.get(name)
            if node is not None:
                tree.nodes.remove(node)
        if glint.owns_use_nodes and _is_default_tree(tree):
            host_nodes.release_tree(scene)
    if glint.owns_use_compositing:
        scene.render.use_compositing = False
    _release_specular_passes(scene, target_view_layer(scene))
    glint.owns_use_nodes = glint.owns_use_compositing = False
    still_used = any(s.glint.enabled and s != scene for s in bpy.data.scenes)
    if not still_used:
        group = find_group()
        if group is not None and group.users == 0:
            bpy.data.node_groups.remove(group)
        for name in cg.ALL_IMAGES + cg.LEGACY_IMAGES:
            img = bpy.data.images.get(name)
            if img is not None and img.users == 0:
                bpy.data.images.remove(img)

"""The compositor as the running Blender spells it.

``logic/compositing.py`` describes Glint's node group once, in abstract node
kinds (``mix``, ``math``, ``switch``, ``blur``, ...) whose inputs are numbered
the way the description links them. This module lowers that description onto
the compositor this Blender has:

* up to 4.5 the compositor is ``scene.node_tree`` behind ``scene.use_nodes``,
  with compositor-only Mix RGB and Math nodes and options held as node
  properties (Switch's ``check``, Blur's ``size_x`` and filter, Translate's
  ``wrap_axis``); a Composite node receives the frame;
* from 5.0 it is a node group of its own (``scene.compositing_node_group``)
  whose Group Output receives the frame; Mix and Math are the shader nodes
  (``ShaderNodeMix`` with named, type-dependent sockets), and options are
  input sockets (Switch's ``Switch``, Blur's ``Size`` vector and ``Type``
  menu, the Extension menus of Translate and Map UV); the Render Layers
  node names its passes in words ("Glossy Direct", not "GlossDir").

Every choice is a feature test (does this node type, socket or property
exist), so a Blender between the tested ones takes whichever form it has.
"""
from __future__ import annotations

import math
import struct
from typing import Dict, Tuple

import bpy


def _has_type(idname: str) -> bool:
    return hasattr(bpy.types, idname)


def options_are_sockets() -> bool:
    """5.0+: node options are input sockets and Mix/Math are the shader nodes."""
    return not _has_type("CompositorNodeMixRGB")


# ----------------------------------------------------------------------------
# The scene's compositor tree


def scene_tree(scene, create: bool = False):
    """The scene's compositor node tree, or None; with ``create`` one is made
    (3.4-4.5: Use Nodes on; 5.0+: a new compositing node group)."""
    if hasattr(scene, "compositing_node_group"):
        tree = scene.compositing_node_group
        if tree is None and create:
            tree = bpy.data.node_groups.new(f"{scene.name} Compositing", "CompositorNodeTree")
            scene.compositing_node_group = tree
            rl = tree.nodes.new("CompositorNodeRLayers")
            rl.location = (-300, 0)
            out = _ensure_group_output(tree)
            tree.links.new(rl.outputs["Image"], out.inputs[0])
        return tree
    if create and (not scene.use_nodes or scene.node_tree is None):
        scene.use_nodes = True
    return scene.node_tree if scene.use_nodes else None


def tree_switch_is_off(scene) -> bool:
    """Whether the compositor is switched off at the tree level (3.4-4.5's Use
    Nodes); 5.0+ has no such switch, the tree's presence is the switch."""
    if hasattr(scene, "compositing_node_group"):
        return scene.compositing_node_group is None
    return not scene.use_nodes or scene.node_tree is None


def tree_switch_label() -> str:
    """What the user sees turned on when :func:`scene_tree` made the tree."""
    if hasattr(bpy.types.Scene, "compositing_node_group"):
        return "a compositing node tree (Compositing workspace)"
    return "the compositor's nodes (Use Nodes)"


def frame_output_label() -> str:
    """The node :func:`add_frame_output` adds, in the user's words."""
    return "a Composite node" if _has_type("CompositorNodeComposite") else "the node tree's Group Output"


def release_tree(scene) -> None:
    """Undo what :func:`scene_tree` turned on, for a tree Glint made on its own."""
    if hasattr(scene, "compositing_node_group"):
        tree = scene.compositing_node_group
        scene.compositing_node_group = None
        if tree is not None and tree.users == 0:
            bpy.data.node_groups.remove(tree)
    else:
        scene.use_nodes = False


def _ensure_group_output(tree):
    out = next((n for n in tree.nodes if n.bl_idname == "NodeGroupOutput"), None)
    if out is None:
        out = tree.nodes.new("NodeGroupOutput")
        out.location = (600, 0)
    if not any(name == "Image" for name, _ in group_sockets(tree)[1]):
        new_group_socket(tree, "Image", "NodeSocketColor", "OUTPUT")
    return out


def frame_outputs(tree):
    """The sockets that take the composited frame: every Composite node's
    Image (3.4-4.5), or the Group Output's first input (5.0+)."""
    if _has_type("CompositorNodeComposite"):
        return [n.inputs["Image"] for n in tree.nodes if n.bl_idname == "CompositorNodeComposite"]
    return [n.inputs[0] for n in tree.nodes if n.bl_idname == "NodeGroupOutput" and len(n.inputs) > 1]


def add_frame_output(tree, location):
    """A node that takes the composited frame; returns its input socket."""
    if _has_type("CompositorNodeComposite"):
        comp = tree.nodes.new("CompositorNodeComposite")
        comp.location = location
        return comp.inputs["Image"]
    return _ensure_group_output(tree).inputs[0]


def default_tree_kinds() -> Tuple[Tuple[str, ...], ...]:
    """The node kinds of a compositor tree as Blender makes it, untouched."""
    if _has_type("CompositorNodeComposite"):
        return (("CompositorNodeComposite", "CompositorNodeRLayers"),
                ("CompositorNodeComposite", "CompositorNodeRLayers", "CompositorNodeViewer"))
    return (("CompositorNodeRLayers", "NodeGroupOutput"),
            ("CompositorNodeRLayers", "CompositorNodeViewer", "NodeGroupOutput"))


def compositor_places_regions() -> bool:
    """Whether a smaller image translated by the offset image lands where
    ``logic/group_images.image_region`` cut it from (the compositor then runs
    Map UV on the region only). True of the compositor of 3.x-4.1, whose trees
    still offer the Tiled and Full Frame execution models; the compositors
    after it take a Translate's offset as a single value, not from an image,
    and left the region's reflections out (tests/blender/test_region.py), so
    there the group works on the whole frame."""
    return "execution_mode" in bpy.types.CompositorNodeTree.bl_rna.properties


def scale_reads_by_domain() -> bool:
    """Whether a Scale (and a Translate after it) only transform the canvas's
    domain, which the Mix that meets the frame samples once, bilinearly and
    centred on the frame: the compositor 5.x shares with the GPU. There
    ``group_images.coarse_grid_shift`` makes the Scale read the coarse canvas
    where 3.x-4.1's does (checked on 5.2 to 2e-6 at 64x48, 66x50 and 68x52,
    and 7e-5 at 1920x1080; docs/addon.md). 4.4-4.5's compositor may read so
    too but is untested, so it keeps the fine image's Map UV; 4.2-4.3's Scale
    reads otherwise and is placed by its own offsets (scale_offset_places_read).
    Feature-tested by 5.0's node options as sockets, which came with it on
    every Blender tested."""
    return options_are_sockets()


def scale_offset_places_read() -> bool:
    """Whether the Scale's own offsets place its read where 3.x-4.1's Scale
    reads (``group_images.coarse_scale_offset``): 4.2-4.3's compositor, which
    realizes every node's output, so a Translate after the Scale would
    resample it (docs/frame-cost.md, *On 4.3: what a node costs, and how its Scale
    reads*). Measured
    on 4.3 to 4e-5 at 1920x1080 but for the frame's last row and column. No
    feature of the API tells this compositor from 4.4-4.5's, which were not
    measured, so the version range decides; they keep the Map UV."""
    return (not compositor_places_regions() and not options_are_sockets()
            and (4, 2) <= tuple(bpy.app.version[:2]) < (4, 4))


def coarse_read_back_by_scale() -> bool:
    """Whether the group brings the coarse levels back to the frame through
    its Scale (``frame_scale``; a tenth of a Map UV's cost on 3.4), rather than
    the fine image's Map UV: where regions are placed, or where the Scale's
    read can be placed on their grid."""
    return compositor_places_regions() or scale_reads_by_domain() or scale_offset_places_read()


def stored_float(value: float) -> float:
    """``value`` as a float property or socket holds it (single precision):
    what a value read back is compared with, so that a write that would change
    nothing is not made. Each write is an RNA update, and at render_init on the
    render thread one that Blender may refuse (host/writes.py)."""
    return struct.unpack("f", struct.pack("f", value))[0]


def set_scale_offset(node, x: float, y: float) -> None:
    """A ``frame_scale`` node's offsets, fractions of the frame's width (only
    where the options are properties: scale_offset_places_read)."""
    x, y = stored_float(x), stored_float(y)
    if (node.offset_x, node.offset_y) != (x, y):
        node.offset_x, node.offset_y = x, y


# Render Layers outputs by pass: 3.4-4.5 short names, 5.0+ words.
PASS_OUTPUTS = {"glossy_direct": ("GlossDir", "Glossy Direct"),
                "glossy_color": ("GlossCol", "Glossy Color")}


def pass_output(render_layers, pass_key: str):
    """The Render Layers output of a pass, or None when this Blender lists none.
    An output listed but not enabled (the engine does not write the pass) is
    returned all the same: linked, it gives black, and it comes alive when the
    pass is switched on."""
    for name in PASS_OUTPUTS[pass_key]:
        sock = render_layers.outputs.get(name)
        if sock is not None:
            return sock
    return None


# ----------------------------------------------------------------------------
# Node group interface (4.0 replaced inputs/outputs by ``interface``)


def new_group_socket(tree, name: str, socket_type: str, in_out: str):
    if hasattr(tree, "interface"):
        return tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    sockets = tree.inputs if in_out == "INPUT" else tree.outputs
    return sockets.new(socket_type, name)


def group_sockets(tree):
    """([(name, socket type)] of the inputs, of the outputs) of a node group."""
    if hasattr(tree, "interface"):
        items = [i for i in tree.interface.items_tree if i.item_type == "SOCKET"]
        return ([(i.name, i.socket_type) for i in items if i.in_out == "INPUT"],
                [(i.name, i.socket_type) for i in items if i.in_out == "OUTPUT"])
    return ([(i.name, i.bl_socket_idname) for i in tree.inputs],
            [(o.name, o.bl_socket_idname) for o in tree.outputs])


def clear_group_sockets(tree) -> None:
    if hasattr(tree, "interface"):
        tree.interface.clear()
    else:
        tree.inputs.clear()
        tree.outputs.clear()


# ----------------------------------------------------------------------------
# Node kinds


def fast_gauss_size_per_sigma() -> float:
    """The Fast Gaussian's size for a sigma of one pixel. The compositor of
    3.x-4.1 (the one with the Tiled execution model) blurs with sigma = size / 2;
    the compositor after it with sigma = size / 3 (its blur reads the size as a
    radius that holds 3 sigma). Measured by tests/blender/test_blur.py, which
    fits Blender's levels against numpy Gaussians: with size = 2 sigma, 3.4's
    matched the intended sigma (relative error 0.031), 4.3's and 5.2's 0.7 of it."""
    return 2.0 if compositor_places_regions() else 3.0


def soften_is_a_filter() -> bool:
    """Whether the group's first blur level (abstract kind ``soften``) is the
    Filter node's 3x3 Soften here, or a sampled Gaussian of the same sigma (the
    Blur node's Gaussian filter, not its Fast Gaussian). In the group at
    1920x1080 the filter made what Glint adds to a frame 0.9x on 4.3 and 5.2,
    and 1.08x on the Tiled-era compositor of 3.x-4.1
    (compositor_places_regions), whose filter reads its neighbours tile by
    tile; there the sampled Gaussian costs a fifth of the Fast Gaussian it
    replaced (docs/frame-cost.md, *The first level as a 3x3 filter*)."""
    return not compositor_places_regions()


# The Tiled-era Blur node's Gaussian filter: taps exp(-i^2 / (2 (r / 3)^2))
# for |i| <= ceil(r), r = size_x x the Size input, normalised over the taps
# inside the canvas (so sigma = r / 3). Checked on an impulse on 3.4: the
# sampled Gaussian of that sigma to five decimals, negative values kept.
GAUSS_RADIUS_PER_SIGMA = 3.0


def _blur_size(size: float) -> int:
    # 3.4-4.5's Blur node takes an integer size that the Size input scales,
    # which together give the exact size.
    return max(1, math.ceil(size))


def _set_blur_properties(node, filter_type: str, size: float) -> None:
    """A Blur node of 3.4-4.5 (options as properties) set to `filter_type` at
    `size` pixels: the integer size, scaled to the exact one by the Size input."""
    whole = _blur_size(size)
    for key, value in (("filter_type", filter_type), ("use_relative", False), ("use_bokeh", False),
                       ("use_gamma_correction", False), ("use_extended_bounds", False),
                       ("use_variable_size", False), ("size_x", whole), ("size_y", whole)):
        setattr(node, key, value)
    node.inputs[1].default_value = size / whole


# kind -> (idname up to 4.5, idname from 5.0)
_IDNAMES = {
    "image": ("CompositorNodeImage", "CompositorNodeImage"),
    "map_uv": ("CompositorNodeMapUV", "CompositorNodeMapUV"),
    "separate": ("CompositorNodeSeparateColor", "CompositorNodeSeparateColor"),
    "combine": ("CompositorNodeCombineColor", "CompositorNodeCombineColor"),
    "translate": ("CompositorNodeTranslate", "CompositorNodeTranslate"),
    "mix": ("CompositorNodeMixRGB", "ShaderNodeMix"),
    "math": ("CompositorNodeMath", "ShaderNodeMath"),
    "switch": ("CompositorNodeSwitch", "CompositorNodeSwitch"),
    "blur": ("CompositorNodeBlur", "CompositorNodeBlur"),
    "rgb": ("CompositorNodeRGB", "CompositorNodeRGB"),
    "frame_scale": ("CompositorNodeScale", "CompositorNodeScale"),
    "keep": ("CompositorNodeBlur", "CompositorNodeBlur"),
}
# keep: a Gaussian Blur this many pixels wide, whose taps off the centre are
# exp(-450) = 0 in float: the image unchanged, but made once into a buffer by
# the Tiled compositor, which evaluates a chain of simple operations anew for
# every read of a node that samples it (a Scale reads four texels per pixel).
KEEP_RADIUS = 0.1

# Sockets whose index moved: kind -> {abstract index: socket identifier}, 5.0+.
_SOCKET_INPUTS = {
    "mix": {0: "Factor_Float", 1: "A_Color", 2: "B_Color"},
    "switch": {0: "Off", 1: "On"},
}
_SOCKET_OUTPUTS = {"mix": {0: "Result_Color"}}
# Sockets whose index differs between hosts, on every host: kind -> {abstract
# index: socket identifier}. The Filter node's image is its second input up to
# 4.5 (after Fac) and its first from 5.0.
_NAMED_INPUTS = {"soften": {0: "Image"}}


def lowered(kind: str) -> str:
    """The kind a node is made as here: ``soften`` is a ``gauss`` (the Blur
    node's sampled Gaussian) where the host does not run the first level as
    the Filter node (soften_is_a_filter)."""
    return "gauss" if kind == "soften" and not soften_is_a_filter() else kind


def idname(kind: str) -> str:
    kind = lowered(kind)
    if kind == "soften":
        return "CompositorNodeFilter"
    if kind == "gauss":
        return _IDNAMES["blur"][0]
    return _IDNAMES[kind][1 if options_are_sockets() else 0]


def _set_menu(node, socket: str, value: str) -> None:
    sock = node.inputs.get(socket)
    if sock is not None:
        sock.default_value = value


def new_node(tree, kind: str, props: Dict[str, object], image_of=None):
    """A node of ``kind`` with the description's ``props`` applied."""
    sockets = options_are_sockets()
    kind = lowered(kind)
    node = tree.nodes.new(idname(kind))
    if kind == "image":
        node.image = image_of(props["image"])
    elif kind in ("separate", "combine"):
        node.mode = "RGB"
    elif kind == "mix":
        if sockets:
            node.data_type = "RGBA"
            node.clamp_factor = False
            node.clamp_result = False
        else:
            node.use_alpha = False
            node.use_clamp = False
        node.blend_type = props["blend"]
    elif kind == "math":
        node.operation = props["operation"]
        node.use_clamp = bool(props.get("clamp", False))
    elif kind == "switch":
        set_switch(node, bool(props.get("on", False)))
    elif kind == "blur":
        size = float(props["sigma"]) * fast_gauss_size_per_sigma()
        if sockets:
            _set_menu(node, "Type", "Fast Gaussian")
            node.inputs["Size"].default_value = (size, size)
            for name in ("Extend Bounds",):
                if name in node.inputs:
                    node.inputs[name].default_value = False
        else:
            _set_blur_properties(node, "FAST_GAUSS", size)
    elif kind == "gauss":  # only lowered for the Tiled-era compositor, whose options are properties
        _set_blur_properties(node, "GAUSS", float(props["sigma"]) * GAUSS_RADIUS_PER_SIGMA)
    elif kind == "soften":  # the Filter node
        # Soften is the Filter node's default type, at factor 1 (all filtered);
        # set anyway, so that a Blender whose default moved still softens.
        if sockets:
            _set_menu(node, "Type", "Soften")
        else:
            node.filter_type = "SOFTEN"
        _by_identifier(node.inputs, "Fac").default_value = 1.0
    elif kind == "translate":
        _set_translate(node, props, sockets)
    elif kind == "keep":
        if sockets:
            _set_menu(node, "Type", "Gaussian")
            node.inputs["Size"].default_value = (KEEP_RADIUS, KEEP_RADIUS)
        else:
            _set_blur_properties(node, "GAUSS", KEEP_RADIUS)
    elif kind == "frame_scale":
        # To the frame's size, bilinear: on 3.4 pixel x reads texel x n / W,
        # texel centres on whole numbers, 0 past the last (logic/compositing's
        # numpy model; checked on random images of 64x36 and 66x50).
        if sockets:
            _set_menu(node, "Type", "Render Size")
            _set_menu(node, "Frame Type", "Stretch")
            _set_menu(node, "Interpolation", "Bilinear")
        else:
            node.space = "RENDER_SIZE"
            node.frame_method = "STRETCH"
    elif kind == "map_uv":
        if not sockets:
            node.alpha = 0  # no fading by uv derivatives: Map UV only premultiplies by vis
        elif props.get("footprint"):
            # the filter sized by the uv's derivatives, as Map UV always filters before 5.0
            _set_menu(node, "Interpolation", "Anisotropic")
    return node


def _set_translate(node, props, sockets: bool) -> None:
    """Whole-pixel moves (logic/group_images.image_region): Nearest keeps them
    exact where a Blender interpolates (4.2+); 3.4 has no such option. The
    coarse read-back's move (onto "grid") is the last transform of the Scale
    before it, whose read it places (group_images.coarse_grid_shift): on 5.x
    the last node's interpolation is the one the Mix samples with."""
    if sockets:
        for name in ("Extension X", "Extension Y"):
            _set_menu(node, name, "Clip")
        _set_menu(node, "Interpolation", "Bilinear" if props.get("onto") == "grid" else "Nearest")
    else:
        node.use_relative = False
        node.wrap_axis = "NONE"
        if hasattr(node, "interpolation"):
            node.interpolation = "Nearest"


def _by_identifier(sockets, identifier: str):
    # Collections are keyed by name; the Mix node has three sockets named "A".
    return next(s for s in sockets if s.identifier == identifier)


def input_socket(node, kind: str, index: int):
    if kind in _NAMED_INPUTS:
        return _by_identifier(node.inputs, _NAMED_INPUTS[kind][index])
    if options_are_sockets() and kind in _SOCKET_INPUTS:
        return _by_identifier(node.inputs, _SOCKET_INPUTS[kind][index])
    if options_are_sockets() and kind == "switch":
        return node.inputs[index + 1]
    return node.inputs[index]


def output_socket(node, kind: str, index: int):
    if options_are_sockets() and kind in _SOCKET_OUTPUTS:
        return _by_identifier(node.outputs, _SOCKET_OUTPUTS[kind][index])
    return node.outputs[index]


def switch_is_on(node) -> bool:
    if "Switch" in node.inputs:
        return bool(node.inputs["Switch"].default_value)
    return bool(node.check)


def set_switch(node, on: bool) -> None:
    """Set a Switch when it differs (each write is an RNA update)."""
    if switch_is_on(node) == on:
        return
    if "Switch" in node.inputs:
        node.inputs["Switch"].default_value = on
    else:
        node.check = on


def rgb_value(node):
    return tuple(node.outputs[0].default_value)


def set_rgb_value(node, value) -> None:
    if rgb_value(node) != tuple(value):
        node.outputs[0].default_value = value


# ----------------------------------------------------------------------------
# The layers EXR (File Output): 5.0 renamed its folder and slots


def set_multilayer_exr(fmt) -> None:
    """Image settings for a multilayer EXR: 5.0 offers OPEN_EXR_MULTILAYER only
    once the media type is a multi-layer image."""
    if hasattr(fmt, "media_type"):
        fmt.media_type = "MULTI_LAYER_IMAGE"
    fmt.file_format = "OPEN_EXR_MULTILAYER"


def new_exr_output(tree, slots, location):
    node = tree.nodes.new("CompositorNodeOutputFile")
    node.location = location
    fmt = node.format
    set_multilayer_exr(fmt)
    fmt.color_depth = "32"
    fmt.exr_codec = "ZIP"
    if hasattr(node, "file_output_items"):
        node.file_output_items.clear()
        for slot in slots:
            node.file_output_items.new("RGBA", slot)
    else:
        node.layer_slots.clear()
        for slot in slots:
            node.layer_slots.new(slot)
    return node


def exr_input(node, slot: str):
    return node.inputs[slot]


# A 5.x File Output numbers only an animation's files unless its file name
# asks for the frame: a still (F12, a script's render) wrote `glint_.exr`, and
# every such render overwrote it. 3.x-4.x number every file, with 4 digits.
FRAME_NUMBER = "####"


def set_exr_path(node, path: str) -> None:
    """Point the layers EXR's File Output at ``path`` + the frame number; a node
    a 5.x Glint set up before FRAME_NUMBER gets it too."""
    if hasattr(node, "directory"):
        # 5.0 splits the old base path into a folder and a file name prefix.
        folder, _, name = path.rpartition("/")
        want = (folder + "/" if folder else "//", name + FRAME_NUMBER)
        if (node.directory, node.file_name) != want:
            node.directory, node.file_name = want
    elif node.base_path != path:
        node.base_path = path

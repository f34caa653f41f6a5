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
from typing import Dict, Optional

import bpy
import numpy as np

from .logic import compositing as cg

LAYOUT_KEY = "glint_layout"


def _layout_hash() -> str:
    text = repr(sorted(cg.GROUP_NODES.items())) + repr(cg.GROUP_LINKS) + repr(cg.GROUP_OUTPUTS)
    return hashlib.sha1(text.encode()).hexdigest()[:12]


# ----------------------------------------------------------------------------
# Images


def ensure_image(name: str, width: int = 4, height: int = 4):
    img = bpy.data.images.get(name)
    if img is None:
        img = bpy.data.images.new(name, width, height, alpha=True, float_buffer=True)
        img.generated_color = (0.0, 0.0, 0.0, 1.0)
    # Data, not colour: no view transform, no premultiplication of the alpha.
    img.colorspace_settings.name = "Non-Color"
    img.alpha_mode = "CHANNEL_PACKED"
    img.use_fake_user = False
    return img


def fill_images(images: Dict[str, np.ndarray]) -> None:
    """Write float32 [h, w, 4] arrays (row 0 at the bottom) into the named images."""
    for name, arr in images.items():
        arr = np.ascontiguousarray(arr, dtype=np.float32)
        h, w = arr.shape[:2]
        img = ensure_image(name, w, h)
        if tuple(img.size) != (w, h):
            if img.source == "GENERATED":
                img.generated_width, img.generated_height = w, h
            if tuple(img.size) != (w, h):
                img.scale(w, h)
        img.pixels.foreach_set(arr.ravel())
        img.update()


# ----------------------------------------------------------------------------
# The node group


def _new_socket(tree, name: str, socket_type: str, in_out: str):
    if hasattr(tree, "interface"):  # Blender 4.0+
        return tree.interface.new_socket(name, in_out=in_out, socket_type=socket_type)
    sockets = tree.inputs if in_out == "INPUT" else tree.outputs
    return sockets.new(socket_type, name)


def build_group():
    """(Re)build the node group from the description; returns it."""
    group = bpy.data.node_groups.get(cg.GROUP_NAME)
    if group is not None and group.get(LAYOUT_KEY) == _layout_hash() and group.bl_idname == "CompositorNodeTree":
        return group
    if group is None or group.bl_idname != "CompositorNodeTree":
        group = bpy.data.node_groups.new(cg.GROUP_NAME, "CompositorNodeTree")
    group.nodes.clear()
    if hasattr(group, "interface"):
        group.interface.clear()
    else:
        group.inputs.clear()
        group.outputs.clear()
    for name, kind in cg.GROUP_INPUTS:
        _new_socket(group, name, kind, "INPUT")
    for name, kind in cg.GROUP_OUTPUTS:
        _new_socket(group, name, kind, "OUTPUT")
    nodes = {cg.GROUP_IN: group.nodes.new("NodeGroupInput"), cg.GROUP_OUT: group.nodes.new("NodeGroupOutput")}
    nodes[cg.GROUP_IN].location = (-900, 0)
    nodes[cg.GROUP_OUT].location = (1300, 0)
    for i, (name, (kind, props, defaults)) in enumerate(cg.GROUP_NODES.items()):
        node = group.nodes.new(kind)
        node.name = node.label = name
        node.location = (-600 + 250 * (i % 8), 600 - 220 * (i // 8))
        for key, value in props.items():
            if key == "image":
                value = ensure_image(value)
            setattr(node, key, value)
        for index, value in defaults.items():
            node.inputs[index].default_value = value
        nodes[name] = node
    for src, so, dst, di in cg.GROUP_LINKS:
        group.links.new(nodes[src].outputs[so], nodes[dst].inputs[di])
    group[LAYOUT_KEY] = _layout_hash()
    return group


def update_group(glint) -> None:
    """Push the settings the group reads (blur size, debug switches)."""
    group = bpy.data.node_groups.get(cg.GROUP_NAME)
    if group is None:
        return
    blur = group.nodes.get("blur")
    if blur is not None and (blur.size_x != glint.blur_size or blur.size_y != glint.blur_size):
        blur.size_x = blur.size_y = glint.blur_size
    for name, check in cg.switch_states(glint.debug_view).items():
        node = group.nodes.get(name)
        if node is not None and node.check != check:
            node.check = check


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


def group_node(scene):
    tree = scene.node_tree if scene.use_nodes else None
    return tree.nodes.get(cg.GROUP_NODE_NAME) if tree is not None else None


def _is_default_tree(tree) -> bool:
    kinds = sorted(n.bl_idname for n in tree.nodes)
    return kinds in (["CompositorNodeComposite", "CompositorNodeRLayers"],
                     ["CompositorNodeComposite", "CompositorNodeRLayers", "CompositorNodeViewer"])


def ensure(scene) -> Optional[str]:
    """Put the group in the scene's compositor (idempotent). Returns a warning or None."""
    glint = scene.glint
    if not scene.use_nodes or scene.node_tree is None:
        scene.use_nodes = True
        glint.owns_use_nodes = True
    tree = scene.node_tree
    group = build_group()
    update_group(glint)
    view_layer = target_view_layer(scene)
    rl = _render_layers_node(tree, scene, view_layer)
    if rl is None:
        rl = tree.nodes.new("CompositorNodeRLayers")
        rl.scene = scene
        rl.layer = view_layer.name
        rl.location = (-300, 0)
    gnode = tree.nodes.get(cg.GROUP_NODE_NAME)
    if gnode is None or gnode.bl_idname != "CompositorNodeGroup":
        gnode = tree.nodes.new("CompositorNodeGroup")
        gnode.name = cg.GROUP_NODE_NAME
        gnode.label = "Glint Reflections"
        gnode.node_tree = group
        gnode.location = (rl.location.x + 300, rl.location.y)
        # Everything that read the render's image now reads the composited one.
        for link in list(rl.outputs["Image"].links):
            to_socket = link.to_socket
            tree.links.remove(link)
            tree.links.new(gnode.outputs["Image"], to_socket)
        if not gnode.outputs["Image"].links:
            comp = next((n for n in tree.nodes if n.bl_idname == "CompositorNodeComposite"), None)
            if comp is None:
                comp = tree.nodes.new("CompositorNodeComposite")
                comp.location = (gnode.location.x + 300, gnode.location.y)
            tree.links.new(gnode.outputs["Image"], comp.inputs["Image"])
    elif gnode.node_tree != group:
        gnode.node_tree = group
    if not any(l.from_node == rl for l in gnode.inputs["Image"].links):
        tree.links.new(rl.outputs["Image"], gnode.inputs["Image"])
    _ensure_exr_node(scene, tree, gnode)
    if not scene.render.use_compositing:
        return ("compositing is off (Output Properties > Post Processing > Compositing): "
                "reflections cannot be composited")
    return None


def exr_base_path(scene) -> str:
    """'<output dir>/<output name>glint_' : the layers' EXR sits next to the frames."""
    # Frame-number placeholders belong to the frames' names, not the layers'.
    return (scene.render.filepath or "//").replace("#", "") + "glint_"


def _ensure_exr_node(scene, tree, gnode) -> None:
    node = tree.nodes.get(cg.EXR_NODE_NAME)
    if not scene.glint.write_layers_exr:
        if node is not None:
            tree.nodes.remove(node)
        return
    if node is None:
        node = tree.nodes.new("CompositorNodeOutputFile")
        node.name = cg.EXR_NODE_NAME
        node.label = "Glint layers (EXR)"
        node.location = (gnode.location.x + 300, gnode.location.y - 300)
        node.format.file_format = "OPEN_EXR_MULTILAYER"
        node.format.color_depth = "32"
        node.format.exr_codec = "ZIP"
        node.layer_slots.clear()
        for slot, _ in cg.EXR_LAYERS:
            node.layer_slots.new(slot)
        for slot, output in cg.EXR_LAYERS:
            tree.links.new(gnode.outputs[output], node.inputs[slot])
    node.base_path = exr_base_path(scene)


def set_active(scene, active: bool) -> None:
    """Mute the group (the frame passes through unchanged) or let it composite."""
    gnode = group_node(scene)
    if gnode is not None and gnode.mute == active:
        gnode.mute = not active


def remove(scene) -> None:
    """Take Glint out of the compositor, reconnecting what it sat between."""
    tree = scene.node_tree
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
        exr = tree.nodes.get(cg.EXR_NODE_NAME)
        if exr is not None:
            tree.nodes.remove(exr)
        if glint.owns_use_nodes and _is_default_tree(tree):
            scene.use_nodes = False
    glint.owns_use_nodes = False
    still_used = any(s.glint.enabled and s != scene for s in bpy.data.scenes)
    if not still_used:
        group = bpy.data.node_groups.get(cg.GROUP_NAME)
        if group is not None and group.users == 0:
            bpy.data.node_groups.remove(group)
        for name in cg.ALL_IMAGES:
            img = bpy.data.images.get(name)
            if img is not None and img.users == 0:
                bpy.data.images.remove(img)

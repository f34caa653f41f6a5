"""Blender -> plain data: small gather functions, one per kind of thing.

Each function reads what Glint needs from an *evaluated* depsgraph (the one the
render hands to ``frame_change_post``) and returns numpy arrays or plain dicts
for the logic modules. Where Blenders differ in how the data is reached, the
host layer (``host/data.py``) reads it; the Principled BSDF's input names of
3.x and 4.x both pass through :func:`principled_inputs` as data, and
``logic/materials.principled_specular`` tells them apart by name.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Dict, List, Optional, Tuple

import numpy as np

from .host import data as host_data
from .logic import frustum, geometry, materials, projection

GEOMETRY_TYPES = {"MESH", "CURVE", "SURFACE", "FONT", "META"}

NO_SPECULAR_NODES = {
    "ShaderNodeBsdfDiffuse", "ShaderNodeEmission", "ShaderNodeBsdfTranslucent",
    "ShaderNodeBsdfTransparent", "ShaderNodeHoldout", "ShaderNodeSubsurfaceScattering",
    "ShaderNodeBsdfVelvet", "ShaderNodeBsdfSheen", "ShaderNodeBackground", "ShaderNodeBsdfHair",
    "ShaderNodeBsdfHairPrincipled", "ShaderNodeBsdfToon", "ShaderNodeBsdfRefraction",
    "ShaderNodeVolumeAbsorption", "ShaderNodeVolumeScatter", "ShaderNodeVolumePrincipled",
}


class SkipFrame(Exception):
    """The frame cannot get reflections (the message says why); it renders without."""


# ----------------------------------------------------------------------------
# Camera


@dataclass
class CameraInfo:
    projection: np.ndarray  # 4x4, float64
    view: np.ndarray  # 4x4 world -> view
    width: int
    height: int
    kind: str  # perspective / orthographic
    name: str
    # A render region not cropped to: the pixels the engine renders (the rest
    # of the frame stays black, and Glint leaves it so).
    rendered: Optional[projection.RenderWindow] = None


def camera(depsgraph) -> CameraInfo:
    """The render camera's projection (``calc_matrix_camera`` at the render's size,
    pixel aspect and percentage; shift and sensor fit included; narrowed to the
    render region when the render is cropped to it) and view matrix; with a render
    region not cropped to, where the engine renders (``rendered``)."""
    scene = depsgraph.scene_eval
    cam = scene.camera
    if cam is None:
        raise SkipFrame("the scene has no camera")
    cam = cam.evaluated_get(depsgraph)
    data = cam.data if cam.type == "CAMERA" else None
    if data is not None and data.type == "PANO":
        raise SkipFrame(f"camera {cam.name!r} is panoramic; screen-space reflections need a "
                        f"perspective or orthographic camera, so this frame is skipped")
    r = scene.render
    try:
        win = render_window(r)
    except projection.ProjectionError as exc:
        raise SkipFrame(str(exc)) from exc
    proj = np.array(cam.calc_matrix_camera(depsgraph, x=win.full_width, y=win.full_height,
                                           scale_x=r.pixel_aspect_x, scale_y=r.pixel_aspect_y), dtype=np.float64)
    try:
        kind = projection.classify_projection(proj)
    except projection.ProjectionError as exc:
        raise SkipFrame(f"camera {cam.name!r}: {exc}") from exc
    view = projection.view_matrix(np.array(cam.matrix_world, dtype=np.float64))
    if not win.cropped:  # the whole frame, and where the engine renders it
        whole = (win.width, win.height) == (win.full_width, win.full_height)
        return CameraInfo(proj, view, win.full_width, win.full_height, kind, cam.name, None if whole else win)
    # Cropped to a render region, the region is the screen: its rays that
    # leave it find no pixel to read, as at the frame's edges.
    proj = projection.window_projection(proj, win)
    return CameraInfo(proj, view, win.width, win.height, kind, cam.name)


def render_window(render) -> projection.RenderWindow:
    """The pixels ``scene.render`` produces: the whole frame, or its render region
    (*Render Region*), cropped to or not (*Crop to Render Region*)."""
    region = None
    if render.use_border:
        region = (render.border_min_x, render.border_max_x, render.border_min_y, render.border_max_y)
    return projection.render_window(render.resolution_x, render.resolution_y, render.resolution_percentage, region,
                                    render.use_crop_to_border)


# ----------------------------------------------------------------------------
# Materials


def _socket_value(socket):
    v = getattr(socket, "default_value", None)
    if v is None:
        return None
    try:
        return tuple(float(x) for x in v)
    except TypeError:
        return float(v)


def _linked_node(socket):
    """The node feeding ``socket`` (through reroutes), or None."""
    seen = 0
    while socket is not None and socket.is_linked and seen < 64:
        link = socket.links[0]
        if not link.is_valid or link.is_muted:
            return None
        node = link.from_node
        if node.bl_idname == "NodeReroute":
            socket = node.inputs[0]
            seen += 1
            continue
        return node
    return None


def principled_inputs(node) -> Dict[str, object]:
    """The Principled BSDF's unlinked input values by name (3.4's and 4.x's names
    both pass through; :func:`materials.principled_specular` tells them apart)."""
    out = {}
    for sock in node.inputs:
        if sock.type in {"VALUE", "RGBA", "VECTOR"} and hasattr(sock, "default_value"):
            out[sock.name] = _socket_value(sock)
    return out


def describe_shader(node, depth: int = 0) -> Optional[dict]:
    """A shader node (the one feeding Material Output > Surface) as a plain dict."""
    if node is None or depth > 32:
        return {"kind": "none"}
    idn = node.bl_idname
    if node.mute:
        return {"kind": "none"}
    if idn == "ShaderNodeBsdfPrincipled":
        return {"kind": "principled", "inputs": principled_inputs(node)}
    if idn in {"ShaderNodeBsdfGlossy", "ShaderNodeBsdfAnisotropic"}:
        return {"kind": "glossy", "color": _socket_value(node.inputs["Color"]),
                "roughness": _socket_value(node.inputs["Roughness"])}
    if idn == "ShaderNodeEeveeSpecular":
        return {"kind": "specular", "color": _socket_value(node.inputs["Specular"]),
                "roughness": _socket_value(node.inputs["Roughness"]),
                "base_color": _socket_value(node.inputs["Base Color"])}
    if idn == "ShaderNodeBsdfDiffuse":
        return {"kind": "diffuse", "color": _socket_value(node.inputs["Color"])}
    if idn == "ShaderNodeBsdfGlass":
        return {"kind": "glass", "ior": _socket_value(node.inputs["IOR"]),
                "roughness": _socket_value(node.inputs["Roughness"])}
    if idn == "ShaderNodeMixShader":
        fac_sock = node.inputs[0]
        fac = 0.5 if fac_sock.is_linked else _socket_value(fac_sock)
        return {"kind": "mix", "fac": fac, "a": describe_shader(_linked_node(node.inputs[1]), depth + 1),
                "b": describe_shader(_linked_node(node.inputs[2]), depth + 1)}
    if idn == "ShaderNodeAddShader":
        return {"kind": "add", "a": describe_shader(_linked_node(node.inputs[0]), depth + 1),
                "b": describe_shader(_linked_node(node.inputs[1]), depth + 1)}
    if idn in NO_SPECULAR_NODES:
        return {"kind": "none"}
    return None  # unknown (node groups, custom nodes): the caller falls back to viewport values


def _viewport(mat) -> dict:
    return {"kind": "viewport", "specular_color": tuple(mat.specular_color),
            "specular_intensity": mat.specular_intensity, "roughness": mat.roughness,
            "metallic": mat.metallic, "diffuse_color": tuple(mat.diffuse_color)}


def _surface_node(mat):
    tree = mat.node_tree
    outputs = [n for n in tree.nodes if n.bl_idname == "ShaderNodeOutputMaterial"]
    if not outputs:
        return None, False
    active = [n for n in outputs if n.is_active_output] or outputs
    return _linked_node(active[0].inputs["Surface"]), True


@dataclass
class NormalMapRef:
    image: object  # bpy.types.Image
    strength: float
    uv_map: str


def _normal_map_of(shader_node) -> Optional[NormalMapRef]:
    """A tangent-space Normal Map node fed by an Image Texture, on the shader's Normal."""
    if shader_node is None or "Normal" not in shader_node.inputs:
        return None
    nm = _linked_node(shader_node.inputs["Normal"])
    if nm is None or nm.bl_idname != "ShaderNodeNormalMap" or nm.space != "TANGENT":
        return None
    tex = _linked_node(nm.inputs["Color"])
    if tex is None or tex.bl_idname != "ShaderNodeTexImage" or tex.image is None:
        return None
    strength = nm.inputs["Strength"]
    return NormalMapRef(tex.image, 1.0 if strength.is_linked else float(strength.default_value), nm.uv_map)


def material_info(mat) -> Tuple[materials.SpecularSpec, Optional[NormalMapRef]]:
    """The specular spec of a material and its normal map, if any."""
    hardness = mat.get("hardness")
    if hardness is not None:
        try:
            hardness = float(hardness)
        except (TypeError, ValueError):
            hardness = None
    if not host_data.uses_nodes(mat):
        return materials.material_spec(_viewport(mat), hardness), None
    node, has_output = _surface_node(mat)
    if not has_output:
        return materials.material_spec(_viewport(mat), hardness), None
    desc = describe_shader(node)  # None: a shader Glint does not know
    if desc is None:
        desc = _viewport(mat)
    return materials.material_spec(desc, hardness), _normal_map_of(node)


class MaterialTable:
    """Global material rows for the rasterizer; row 0 is "no material" (no specular)."""

    def __init__(self):
        self.rows: List[Tuple[float, float, float, float]] = [materials.NO_MATERIAL.row()]
        self.albedo_rows: List[Tuple[float, float, float]] = [materials.NO_MATERIAL.albedo]
        self.reflective_rows: List[bool] = [materials.NO_MATERIAL.reflective]
        self.normal_map_of_row: List[int] = [-1]
        self.normal_maps: List[NormalMapRef] = []
        self._index: Dict[int, int] = {}
        self._map_index: Dict[int, int] = {}

    def index_of(self, mat) -> int:
        if mat is None:
            return 0
        key = mat.original.as_pointer() if hasattr(mat, "original") else mat.as_pointer()
        if key in self._index:
            return self._index[key]
        spec, nmap = material_info(mat)
        map_index = -1
        if nmap is not None and spec.reflective:
            ikey = nmap.image.as_pointer()
            if ikey not in self._map_index:
                self._map_index[ikey] = len(self.normal_maps)
                self.normal_maps.append(nmap)
            map_index = self._map_index[ikey]
        self.rows.append(spec.row())
        self.albedo_rows.append(spec.albedo)
        self.reflective_rows.append(spec.reflective)
        self.normal_map_of_row.append(map_index)
        self._index[key] = len(self.rows) - 1
        return self._index[key]

    def reflective(self, index: int) -> bool:
        """Whether the core traces the pixels of row ``index`` (SpecularSpec.reflective)."""
        return self.reflective_rows[index]

    def array(self) -> np.ndarray:
        return np.asarray(self.rows, dtype=np.float32).reshape(-1, 4)

    def albedo_array(self) -> np.ndarray:
        """[M, 3] diffuse albedo per row (the rasterizer's ``material_albedo``)."""
        return np.asarray(self.albedo_rows, dtype=np.float32).reshape(-1, 3)


def normal_map_pixels(ref: NormalMapRef) -> np.ndarray:
    """The image's pixels as [h, w, 3] with the node's strength baked in."""
    img = ref.image
    w, h = img.size
    if w == 0 or h == 0:
        raise ValueError(f"normal map image {img.name!r} has no pixels")
    buf = np.empty(w * h * img.channels, dtype=np.float32)
    img.pixels.foreach_get(buf)
    px = buf.reshape(h, w, img.channels)
    if img.channels < 3:
        raise ValueError(f"normal map image {img.name!r} has {img.channels} channels, expected 3 or 4")
    return geometry.normal_map_with_strength(px, ref.strength)


# ----------------------------------------------------------------------------
# Meshes


def mesh_arrays(mesh, uv_map: Optional[str] = None) -> geometry.MeshArrays:
    """Triangles, corner normals and (when ``uv_map`` is given) UVs and tangents."""
    mesh.calc_loop_triangles()
    t = len(mesh.loop_triangles)
    tri_verts = np.empty(t * 3, dtype=np.int32)
    tri_loops = np.empty(t * 3, dtype=np.int32)
    tri_mat = np.empty(t, dtype=np.int32)
    mesh.loop_triangles.foreach_get("vertices", tri_verts)
    mesh.loop_triangles.foreach_get("loops", tri_loops)
    mesh.loop_triangles.foreach_get("material_index", tri_mat)
    co = np.empty(len(mesh.vertices) * 3, dtype=np.float32)
    mesh.vertices.foreach_get("co", co)
    arrays = geometry.MeshArrays(co.reshape(-1, 3), tri_verts.reshape(-1, 3), tri_loops.reshape(-1, 3),
                                 tri_mat, host_data.corner_normals(mesh))
    if uv_map is not None and len(mesh.uv_layers):
        layer = mesh.uv_layers.get(uv_map) if uv_map else None
        layer = layer or mesh.uv_layers.active or mesh.uv_layers[0]
        nl = len(mesh.loops)
        uv = np.empty(nl * 2, dtype=np.float32)
        layer.data.foreach_get("uv", uv)
        arrays.corner_uvs = uv.reshape(-1, 2)
        try:
            mesh.calc_tangents(uvmap=layer.name)
        except RuntimeError:
            arrays.corner_tangents = None  # n-gons: no tangent space; the map is left out
        else:
            tan = np.empty(nl * 3, dtype=np.float32)
            sign = np.empty(nl, dtype=np.float32)
            mesh.loops.foreach_get("tangent", tan)
            mesh.loops.foreach_get("bitangent_sign", sign)
            arrays.corner_tangents = np.concatenate([tan.reshape(-1, 3), sign[:, None]], axis=1)
    return arrays


# ----------------------------------------------------------------------------
# The scene


@dataclass
class SceneExport:
    camera: CameraInfo
    triangles: geometry.Triangles
    materials: np.ndarray  # [M, 4]
    material_normal_map: np.ndarray  # [M] int32
    material_albedo: Optional[np.ndarray] = None  # [M, 3]
    normal_maps: List[np.ndarray] = field(default_factory=list)
    objects: int = 0
    culled: int = 0  # outside_view + out_of_reach
    any_reflective: bool = False
    outside_view: int = 0  # bounding box wholly outside the frustum
    out_of_reach: int = 0  # on screen, but no reflected ray can meet it

    def skipped_text(self) -> str:
        """What the export left out, for the log line."""
        return (f"{self.outside_view} objects outside the view and {self.out_of_reach} out of the "
                f"reflections' reach not exported")


def _visible_instance(inst) -> bool:
    ob = inst.object
    if ob.type not in GEOMETRY_TYPES:
        return False
    # The render depsgraph already leaves out objects hidden from render;
    # this also drops objects the camera's rays do not see.
    if not inst.is_instance and ob.original.hide_render:
        return False
    if getattr(ob, "visible_camera", True) is False:
        return False
    return True


def _instances_in_view(depsgraph, clip_from_world, table: MaterialTable):
    """(object, object-to-world, material rows of its slots) for every renderable
    geometry instance; the rows are None when its bounding box lies wholly outside
    the frustum. The object is valid only until the next step: Blender reuses one
    temporary object for instances."""
    for inst in depsgraph.object_instances:
        if not _visible_instance(inst):
            continue
        ob = inst.object
        m = np.array(inst.matrix_world, dtype=np.float64)
        if frustum.outside_frustum(clip_from_world @ m, frustum.box_corners(ob.bound_box)):
            yield ob, m, None
        else:
            yield ob, m, [table.index_of(slot.material) for slot in ob.material_slots]


# Screen rectangles are grown by this many pixels before they are compared: a
# march reads the pixel nearest its projected ray, up to a pixel off its line.
REACH_MARGIN_PX = 4.0


def reach_culling(cam: CameraInfo, boxes, reflective, max_distance: float):
    """Which in-view objects no reflected ray can meet (``frustum.out_of_reach``):
    ``boxes`` are their corners in view space, ``reflective`` whether a slot reflects."""
    margin = 2.0 * REACH_MARGIN_PX / min(cam.width, cam.height)
    proj = cam.projection
    rects = [frustum.screen_rect(proj, c, margin) for c in boxes]
    reach = [frustum.screen_rect(proj, frustum.grown_box_corners(c, max_distance), margin)
             for c, refl in zip(boxes, reflective) if refl]
    return frustum.out_of_reach(rects, reflective, reach)


def export_scene(depsgraph, progress=None, max_distance: Optional[float] = None) -> SceneExport:
    """Every visible mesh instance in the camera's view, as view-space triangles.

    Two passes over the instances: the first (cheap: bounding boxes and material
    slots) decides whether anything reflective is in view and, with
    ``max_distance``, which objects no reflected ray can meet; only then does the
    second fetch meshes, of the objects that matter. A scene without reflective
    materials costs one pass.
    """
    cam = camera(depsgraph)
    clip_from_world = cam.projection @ cam.view
    table = MaterialTable()
    culled = 0
    boxes, reflective = [], []
    for ob, m, slots in _instances_in_view(depsgraph, clip_from_world, table):
        if slots is None:
            culled += 1
            continue
        boxes.append(frustum.transform_points(cam.view @ m, frustum.box_corners(ob.bound_box)))
        reflective.append(any(table.reflective(i) for i in slots))
    any_reflective = any(reflective)
    skip = [False] * len(boxes)
    if any_reflective and max_distance is not None:
        skip = reach_culling(cam, boxes, reflective, max_distance)
    out_of_reach = sum(skip)
    if progress is not None:
        progress.total = len(boxes) - out_of_reach
    result = SceneExport(cam, geometry.concatenate([]), table.array(), np.asarray(table.normal_map_of_row, np.int32),
                         material_albedo=table.albedo_array(),
                         objects=len(boxes) - out_of_reach, culled=culled + out_of_reach,
                         any_reflective=any_reflective, outside_view=culled, out_of_reach=out_of_reach)
    if not any_reflective:
        return result

    parts: List[geometry.Triangles] = []
    cache: Dict[Tuple[int, Optional[str]], geometry.MeshArrays] = {}
    in_view = iter(skip)
    for ob, m, slots in _instances_in_view(depsgraph, clip_from_world, table):
        if slots is None or next(in_view):
            continue
        uv_map = None
        for i in slots:
            mi = table.normal_map_of_row[i]
            if mi >= 0:
                uv_map = table.normal_maps[mi].uv_map
                break
        key = (ob.data.as_pointer() if ob.data is not None else ob.as_pointer(), uv_map)
        arrays = cache.get(key)
        if arrays is None:
            mesh = ob.to_mesh()
            try:
                arrays = mesh_arrays(mesh, uv_map)
            finally:
                ob.to_mesh_clear()
            cache[key] = arrays
        if arrays.triangle_count:
            parts.append(geometry.mesh_to_view(arrays, cam.view @ m, slots, 0, with_uv_tangents=uv_map is not None))
        if progress is not None:
            progress.step(1, f"exported {ob.name}")
    result.triangles = geometry.concatenate(parts)
    result.normal_maps = [normal_map_pixels(ref) for ref in table.normal_maps]
    return result

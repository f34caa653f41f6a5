"""Scene data whose access differs between Blenders: mesh corner normals, and
whether a material or world is node-based (5.0 deprecates ``use_nodes``:
node trees are always on, and reading the flag warns)."""
from __future__ import annotations

import numpy as np


def corner_normals(mesh) -> np.ndarray:
    """One normal per face corner, [L, 3] float32. 4.1+ has ``Mesh.corner_normals``;
    earlier Blenders compute them into the loops with ``calc_normals_split``."""
    n = np.empty(len(mesh.loops) * 3, dtype=np.float32)
    if hasattr(mesh, "corner_normals"):
        mesh.corner_normals.foreach_get("vector", n)
    else:
        mesh.calc_normals_split()
        mesh.loops.foreach_get("normal", n)
    return n.reshape(-1, 3)


def _nodes_always_on(datablock) -> bool:
    prop = datablock.bl_rna.properties.get("use_nodes")
    # 5.0 keeps the flag only for old scripts, marked deprecated, and always true.
    return prop is None or bool(getattr(prop, "is_deprecated", False))


def uses_nodes(datablock) -> bool:
    """Whether a material or world is shaded by its node tree."""
    if _nodes_always_on(datablock):
        return datablock.node_tree is not None
    return bool(datablock.use_nodes) and datablock.node_tree is not None


def enable_nodes(datablock) -> None:
    """Make a new material or world node-based (a no-op where it always is)."""
    if not _nodes_always_on(datablock):
        datablock.use_nodes = True

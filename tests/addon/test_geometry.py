"""Mesh arrays -> view-space triangles, on meshes small enough to check by hand."""
import numpy as np
import pytest

from glint_addon_helpers import load_logic

g = load_logic("geometry")


def quad():
    """A unit quad in the XY plane, two triangles, two material slots."""
    co = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], np.float32)
    tri_verts = np.array([[0, 1, 2], [0, 2, 3]])
    tri_loops = np.array([[0, 1, 2], [0, 2, 3]])
    normals = np.tile([0.0, 0.0, 1.0], (4, 1)).astype(np.float32)
    uvs = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], np.float32)
    tangents = np.tile([1.0, 0.0, 0.0, 1.0], (4, 1)).astype(np.float32)
    return g.MeshArrays(co, tri_verts, tri_loops, np.array([0, 1]), normals, uvs, tangents)


def test_translation_and_slots():
    m = np.eye(4)
    m[:3, 3] = (0, 0, -5)
    t = g.mesh_to_view(quad(), m, [3, 7], 0)
    assert t.positions.dtype == np.float32 and t.positions.shape == (2, 3, 3)
    assert np.allclose(t.positions[1], [[0, 0, -5], [1, 1, -5], [0, 1, -5]])
    assert np.allclose(t.normals, [0, 0, 1])
    assert t.material_index.tolist() == [3, 7]
    assert t.uvs is None


def test_slot_past_the_end_uses_the_last_slot_and_no_slots_the_default():
    assert g.mesh_to_view(quad(), np.eye(4), [5], 0).material_index.tolist() == [5, 5]
    assert g.mesh_to_view(quad(), np.eye(4), [], 9).material_index.tolist() == [9, 9]


def test_rotation_carries_normals_and_tangents():
    # 90 degrees about X: +Z -> -Y, +Y -> +Z
    m = np.array([[1, 0, 0, 0], [0, 0, -1, 0], [0, 1, 0, 0], [0, 0, 0, 1]], float)
    t = g.mesh_to_view(quad(), m, [1], 0, with_uv_tangents=True)
    assert np.allclose(t.normals, [0, -1, 0])
    assert np.allclose(t.tangents[..., :3], [1, 0, 0]) and np.all(t.tangents[..., 3] == 1)
    assert np.allclose(t.uvs[0], [[0, 0], [1, 0], [1, 1]])


def test_mirroring_flips_the_bitangent_sign():
    m = np.diag([-1.0, 1.0, 1.0, 1.0])
    t = g.mesh_to_view(quad(), m, [1], 0, with_uv_tangents=True)
    assert np.all(t.tangents[..., 3] == -1)
    assert np.allclose(t.tangents[..., :3], [-1, 0, 0])
    assert np.allclose(t.normals, [0, 0, 1])


def test_non_uniform_scale_normals():
    co = np.array([[0, 0, 0], [1, -1, 0], [0, 0, 1]], np.float32)  # plane x + y = 0
    n = np.tile(np.array([1, 1, 0]) / np.sqrt(2), (3, 1))
    mesh = g.MeshArrays(co, np.array([[0, 1, 2]]), np.array([[0, 1, 2]]), np.array([0]), n)
    t = g.mesh_to_view(mesh, np.diag([2.0, 1.0, 1.0, 1.0]), [1], 0)
    expected = np.array([0.5, 1.0, 0.0]) / np.hypot(0.5, 1.0)
    assert np.allclose(t.normals[0], expected, atol=1e-6)


def test_concatenate_fills_missing_uvs():
    a = g.mesh_to_view(quad(), np.eye(4), [1], 0, with_uv_tangents=True)
    b = g.mesh_to_view(quad(), np.eye(4), [2], 0)
    c = g.concatenate([b, a])
    assert c.count == 4 and c.uvs.shape == (4, 3, 2) and c.tangents.shape == (4, 3, 4)
    assert np.all(c.uvs[:2] == 0) and np.allclose(c.uvs[2:], a.uvs)
    empty = g.concatenate([])
    assert empty.count == 0 and empty.positions.shape == (0, 3, 3)


def test_normal_map_strength():
    px = np.zeros((2, 2, 4), np.float32)
    px[..., :3] = (1.0, 0.5, 0.5)  # a normal along +X (tangent)
    assert np.allclose(g.normal_map_with_strength(px, 1.0), (1.0, 0.5, 0.5))
    assert np.allclose(g.normal_map_with_strength(px, 0.0), (0.5, 0.5, 1.0))
    half = g.normal_map_with_strength(px, 0.5)  # mix((0,0,1), (1,0,0), .5) = (.5, 0, .5) -> unit
    assert np.allclose(half, np.array([1, 0, 1]) / np.sqrt(2) * 0.5 + 0.5)
    with pytest.raises(ValueError):
        g.normal_map_with_strength(np.zeros((2, 2)), 1.0)

"""march="exact" against mirror hits computed here from the geometry.

The analytic scenes' G-buffers and their mirror hits come from ray casts in
float64 (analytic.py), independent of Embree. Boxes and planes are exact as
triangles; spheres are tessellated finely, so silhouettes may differ by a pixel.
"""
import math

import numpy as np
import pytest

import analytic
import analytic_mesh
from glint_tables import MESH_MARCHES

W, H = 160, 120
MAX_DISTANCE = 15.0


def exact(scene, gbuf, backend="cpu", **kw):
    kw.setdefault("max_distance", MAX_DISTANCE)
    return pytest.glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], march="exact",
                              mesh=analytic_mesh.scene_mesh(scene), backend=backend, **kw)


def pixel_error(uv, hits):
    return np.hypot((uv[..., 0] - hits["uv"][..., 0]) * W, (uv[..., 1] - hits["uv"][..., 1]) * H)


@pytest.fixture(autouse=True)
def _module(glint):
    pytest.glint = glint


def test_exact_is_in_the_tables(glint):
    assert "exact" in MESH_MARCHES
    preset = glint.presets()["exact"]
    assert preset["march"] == "exact"
    assert "mesh" in glint.preset_descriptions()["exact"]


def test_box_on_a_mirror_floor_matches_the_hand_computed_hits(glint):
    # Only planes and boxes: the triangles are the geometry, so every pixel must agree.
    scene = analytic.mirror_floor_scene(sphere=False)
    gbuf = analytic.render(scene, W, H)
    hits = analytic.mirror_hits(scene, gbuf, MAX_DISTANCE)
    uv = exact(scene, gbuf)
    reported = uv[..., 2] > 1e-3
    assert hits["visible"].sum() > 2000, "the scene must reflect something"
    assert np.array_equal(uv[..., 2] > 0, uv[..., 3] > 0)
    assert set(np.unique(uv[..., 2])) <= {0.0, 1.0}, "the exact march has no fades"
    # Pixels whose hit lies within a rounding step of an edge may go either way.
    mismatch = reported != hits["visible"]
    assert mismatch.sum() <= 0.001 * hits["visible"].sum(), mismatch.sum()
    both = reported & hits["visible"]
    assert pixel_error(uv, hits)[both].max() < 0.01


@pytest.mark.parametrize("name,make", [("floor", analytic.mirror_floor_scene),
                                       ("corridor", analytic.corridor_scene),
                                       ("wall", analytic.facing_wall_scene),
                                       ("ortho", lambda: analytic.mirror_floor_scene("ortho"))])
def test_scenes_with_spheres_agree_within_a_pixel(glint, name, make):
    scene = make()
    gbuf = analytic.render(scene, W, H)
    hits = analytic.mirror_hits(scene, gbuf, MAX_DISTANCE)
    uv = exact(scene, gbuf)
    reported = uv[..., 2] > 1e-3
    close = reported & hits["visible"] & (pixel_error(uv, hits) <= 1.5)
    assert close.sum() >= 0.995 * hits["visible"].sum()
    assert close.sum() >= 0.995 * reported.sum()


def test_hits_the_camera_cannot_see_are_not_reported(glint):
    # The mirror wall faces the camera: its rays come back and meet the far side
    # of the box, which the camera does not see. Boxes only, so the triangles
    # are the geometry and no silhouette is in doubt.
    scene = analytic.facing_wall_scene()
    scene.objects = [o for o in scene.objects if not isinstance(o, analytic.Sphere)]
    gbuf = analytic.render(scene, W, H)
    hits = analytic.mirror_hits(scene, gbuf, MAX_DISTANCE)
    hidden = hits["hit"] & hits["on_screen"] & ~hits["visible"]
    assert hidden.sum() > 100, "the scene must have hidden hits"
    uv = exact(scene, gbuf)
    assert (uv[..., 2][hidden] > 0).sum() <= 0.002 * hidden.sum()


def test_a_hit_beyond_max_distance_is_not_reported(glint):
    scene = analytic.mirror_floor_scene(sphere=False)
    gbuf = analytic.render(scene, W, H)
    short = 2.0
    hits = analytic.mirror_hits(scene, gbuf, math.inf)
    uv = exact(scene, gbuf, max_distance=short)
    far = hits["visible"] & (hits["distance"] > short * 1.001)
    near = hits["visible"] & (hits["distance"] < short * 0.999)
    assert far.sum() > 100 and near.sum() > 100
    assert not (uv[..., 2][far] > 0).any()
    assert (uv[..., 2][near] > 0).mean() > 0.999


def test_occluder_between_mirror_and_object_blocks_the_reflection(glint):
    # A slab hung between the floor and the box: the floor's rays towards the box
    # now meet the slab's underside first, which the camera does not see.
    scene = analytic.mirror_floor_scene(sphere=False, wall=False)
    base = analytic.render(scene, W, H)
    hits_before = analytic.mirror_hits(scene, base, MAX_DISTANCE)
    scene.objects.append(analytic.Box((0.8, -0.8, 0.3), (2.2, 0.6, 0.35)))
    gbuf = analytic.render(scene, W, H)
    hits = analytic.mirror_hits(scene, gbuf, MAX_DISTANCE)
    uv = exact(scene, gbuf)
    blocked = hits_before["visible"] & hits["hit"] & ~hits["visible"]
    assert blocked.sum() > 20
    assert not (uv[..., 2][blocked] > 0).any()


def test_gl_backend_gives_the_cpu_answer(glint):
    scene = analytic.mirror_floor_scene()
    gbuf = analytic.render(scene, W, H)
    cpu = exact(scene, gbuf)
    try:
        gl = exact(scene, gbuf, backend="gl")
    except glint.BackendUnavailable as exc:
        pytest.skip(f"no GL: {exc}")
    np.testing.assert_array_equal(cpu, gl)


def test_without_mesh_the_error_names_mesh(glint):
    gbuf = analytic.render(analytic.mirror_floor_scene(), 8, 6)
    with pytest.raises(ValueError, match="mesh"):
        glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], march="exact")
    with pytest.raises(ValueError, match="mesh"):
        glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], **glint.presets()["exact"])


@pytest.mark.parametrize("vertices,triangles,match", [
    (np.zeros((3, 2), np.float32), np.zeros((1, 3), np.int32), "vertices"),
    (np.zeros((3, 3), np.float32), np.array([[0, 1, 3]], np.int32), "vertex 3"),
    (np.array([[0, 0, 0], [1, 0, 0], [np.nan, 0, 0]], np.float32), np.array([[0, 1, 2]], np.int32), "finite"),
])
def test_bad_meshes_name_what_is_wrong(glint, vertices, triangles, match):
    gbuf = analytic.render(analytic.mirror_floor_scene(), 8, 6)
    with pytest.raises(ValueError, match=match):
        glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], march="exact",
                    mesh=(vertices, triangles))


def test_an_empty_mesh_reflects_nothing(glint):
    gbuf = analytic.render(analytic.mirror_floor_scene(), 16, 12)
    uv = glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], march="exact",
                     mesh=(np.zeros((0, 3), np.float32), np.zeros((0, 3), np.int32)))
    assert not uv.any()


@pytest.mark.parametrize("name,make", [("floor", lambda: analytic.mirror_floor_scene("persp")),
                                       ("corridor", analytic.corridor_scene)])
def test_antialiased_outlines_follow_the_coverage(glint, name, make):
    """antialias=4 (the exact preset's) gives an outline pixel the share of its five rays
    that hit: against the exact coverage (16 sub-pixel rays, float64 render) the summed
    |visibility - coverage| over the reflecting pixels falls by more than half (89 -> 27
    on the floor, 60 -> 30 on the corridor; docs/hiz.md, *Antialiased outlines*)."""
    scene = make()
    gbuf = analytic.render(scene, W, H)
    coverage, whole = analytic.reflection_coverage(scene, gbuf, 15.0)
    inside = whole & (gbuf["specular"][..., :3].mean(-1) > 0)
    err = {}
    for aa in (0, 4):
        uv = exact(scene, gbuf, specular=gbuf["specular"], antialias=aa)
        err[aa] = float(np.abs(uv[..., 2] - coverage)[inside].sum())
    print(name, err)
    assert err[4] <= 0.55 * err[0]

"""glint_core.ExactScene: the exact march's BVH kept between calls, in world space.

The figures it is held to come from elsewhere: the mirror hits of the analytic scenes
ray-cast in float64 (analytic.py), independent of Embree, and a scene built fresh for
every state, which a kept, refit or rebuilt scene must match bit for bit.
"""
import math
import threading

import numpy as np
import pytest

import analytic
import analytic_mesh

W, H = 160, 120
MAX_DISTANCE = 15.0


@pytest.fixture(autouse=True)
def _module(glint):
    pytest.glint = glint


def boxes_scene(box_at=(1.0, -0.6, 0.0), eye=(0.0, -7.0, 2.2)):
    """A mirror floor, a box on it and a wall: planes and boxes only, so the triangles
    are the geometry and the float64 hits are what the march must find."""
    scene = analytic.mirror_floor_scene(sphere=False)
    lo = np.asarray(box_at, float)
    scene.objects[1] = analytic.Box(tuple(lo), tuple(lo + (1.0, 1.0, 1.2)), analytic.GREEN)
    c = scene.camera
    scene.camera = analytic.Camera(eye=eye, target=c.target, fov=c.fov, near=c.near, far=c.far)
    return scene


def trace(gbuf, mesh):
    return pytest.glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], march="exact", mesh=mesh,
                              max_distance=MAX_DISTANCE)


def seen(scene, exact_scene):
    """The G-buffer of ``scene``'s camera and the exact march's uv through ``exact_scene``."""
    gbuf = analytic.render(scene, W, H)
    view = exact_scene.seen_from(analytic_mesh.view_to_world(scene.camera))
    return gbuf, trace(gbuf, view)


def fresh(scene):
    """What a scene built for this state alone gives."""
    s = pytest.glint.ExactScene(*analytic_mesh.scene_mesh(scene, world=True))
    return seen(scene, s)[1]


def assert_matches_the_float64_hits(scene, gbuf, uv):
    hits = analytic.mirror_hits(scene, gbuf, MAX_DISTANCE)
    assert hits["visible"].sum() > 1000, "the scene must reflect something"
    reported = uv[..., 2] > 0
    # Pixels whose hit lies within a rounding step of an edge may go either way.
    assert (reported != hits["visible"]).sum() <= 0.002 * hits["visible"].sum()
    both = reported & hits["visible"]
    err = np.hypot((uv[..., 0] - hits["uv"][..., 0]) * W, (uv[..., 1] - hits["uv"][..., 1]) * H)
    assert err[both].max() < 0.01


def test_a_camera_move_keeps_the_bvh_and_finds_the_new_hits():
    before = boxes_scene()
    scene = pytest.glint.ExactScene(*analytic_mesh.scene_mesh(before, world=True))
    assert scene.last_update["bvh"] == "built"
    gbuf, uv = seen(before, scene)
    assert_matches_the_float64_hits(before, gbuf, uv)
    moved = boxes_scene(eye=(-2.5, -6.0, 3.0))
    gbuf, uv = seen(moved, scene)
    assert scene.last_update["bvh"] == "built", "a camera move asks nothing of the BVH"
    assert_matches_the_float64_hits(moved, gbuf, uv)
    np.testing.assert_array_equal(uv, fresh(moved))


def test_moving_an_object_refits_and_gives_the_fresh_build_hits():
    before = boxes_scene()
    vertices, triangles = analytic_mesh.scene_mesh(before, world=True)
    scene = pytest.glint.ExactScene(vertices, triangles)
    seen(before, scene)
    moved = boxes_scene(box_at=(-1.5, 0.2, 0.0))
    moved_vertices, moved_triangles = analytic_mesh.scene_mesh(moved, world=True)
    np.testing.assert_array_equal(moved_triangles, triangles)
    report = scene.update(moved_vertices)
    assert report["bvh"] == "refit" and report["ms"] > 0
    assert scene.last_update == report
    gbuf, uv = seen(moved, scene)
    assert_matches_the_float64_hits(moved, gbuf, uv)
    np.testing.assert_array_equal(uv, fresh(moved))
    # Back where it was: the refit BVH still gives the first frame's answer.
    assert scene.update(vertices, triangles)["bvh"] == "refit"
    np.testing.assert_array_equal(seen(before, scene)[1], fresh(before))


def test_the_same_vertices_reuse_the_bvh():
    vertices, triangles = analytic_mesh.scene_mesh(boxes_scene(), world=True)
    scene = pytest.glint.ExactScene(vertices, triangles)
    assert scene.update(vertices.copy())["bvh"] == "reused"
    assert scene.update(vertices, triangles.copy())["bvh"] == "reused"


def test_other_triangles_rebuild():
    before = boxes_scene()
    scene = pytest.glint.ExactScene(*analytic_mesh.scene_mesh(before, world=True))
    grown = boxes_scene()
    grown.objects.append(analytic.Sphere((-0.6, 0.6, 1.0), 0.8, analytic.RED))
    vertices, triangles = analytic_mesh.scene_mesh(grown, world=True)
    assert scene.update(vertices, triangles)["bvh"] == "built"
    assert (scene.vertex_count, scene.triangle_count) == (len(vertices), len(triangles))
    np.testing.assert_array_equal(seen(grown, scene)[1], fresh(grown))
    # The same count of triangles, other vertices in them: rebuilt too.
    shuffled = triangles[:, [1, 2, 0]]
    assert scene.update(vertices, np.ascontiguousarray(shuffled))["bvh"] == "built"


def test_a_view_space_scene_is_the_array_form():
    scene_def = analytic.mirror_floor_scene()
    gbuf = analytic.render(scene_def, W, H)
    mesh = analytic_mesh.scene_mesh(scene_def)
    kept = pytest.glint.ExactScene(*mesh)
    np.testing.assert_array_equal(trace(gbuf, kept), trace(gbuf, mesh))
    np.testing.assert_array_equal(trace(gbuf, kept.seen_from(np.eye(4))), trace(gbuf, mesh))


def test_a_scaled_camera_matrix_keeps_distances_in_view_units():
    # Blender cameras can carry a scale: view_to_world maps the ray's parameter,
    # so max_distance stays in view units and the hits do not move.
    scene_def = boxes_scene()
    v, t = analytic_mesh.scene_mesh(scene_def, world=True)
    scale = np.diag([2.0, 2.0, 2.0, 1.0])
    kept = pytest.glint.ExactScene(v * np.float32(2.0), t)
    gbuf = analytic.render(scene_def, W, H)
    uv = trace(gbuf, kept.seen_from(scale @ analytic_mesh.view_to_world(scene_def.camera)))
    assert_matches_the_float64_hits(scene_def, gbuf, uv)


def test_pipeline_and_composite_layers_take_a_scene():
    scene_def = boxes_scene()
    gbuf = analytic.render(scene_def, W, H)
    kept = pytest.glint.ExactScene(*analytic_mesh.scene_mesh(scene_def, world=True))
    view = kept.seen_from(analytic_mesh.view_to_world(scene_def.camera))
    uv = trace(gbuf, view)
    layers = pytest.glint.pipeline(gbuf["position"], gbuf["normal"], gbuf["specular"], gbuf["color"],
                                   gbuf["projection"], march="exact", mesh=view, max_distance=MAX_DISTANCE)
    reflective = gbuf["specular"][..., :3].mean(-1) > 0
    np.testing.assert_array_equal(layers["uv"][reflective], uv[reflective])
    out = pytest.glint.composite_layers(gbuf["position"], gbuf["normal"], gbuf["specular"], gbuf["projection"],
                                        march="exact", mesh=view, max_distance=MAX_DISTANCE)
    np.testing.assert_array_equal(out["uv"][..., 2][reflective], uv[..., 2][reflective])


def test_traces_at_once_and_updates_between_them_see_one_state_or_the_other():
    a, b = boxes_scene(), boxes_scene(box_at=(-1.5, 0.2, 0.0))
    va, t = analytic_mesh.scene_mesh(a, world=True)
    vb, _ = analytic_mesh.scene_mesh(b, world=True)
    gbuf = analytic.render(a, W, H)
    view_to_world = analytic_mesh.view_to_world(a.camera)
    kept = pytest.glint.ExactScene(va, t)
    view = kept.seen_from(view_to_world)
    expected = [trace(gbuf, view)]
    kept.update(vb)
    expected.append(trace(gbuf, view))
    assert not np.array_equal(*expected), "the two states must differ where the camera looks"
    failures, stop = [], threading.Event()

    def tracer():
        try:
            for _ in range(6):
                uv = trace(gbuf, view)
                if not any(np.array_equal(uv, e) for e in expected):
                    failures.append("a trace saw neither state")
        except Exception as exc:  # noqa: BLE001 - reported below
            failures.append(repr(exc))

    def updater():
        k = 0
        while not stop.is_set():
            kept.update(va if k % 2 == 0 else vb)
            k += 1

    threads = [threading.Thread(target=tracer) for _ in range(4)]
    writer = threading.Thread(target=updater)
    writer.start()
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    stop.set()
    writer.join()
    assert not failures, failures[:3]


def test_the_scene_outlives_the_callers_reference():
    scene_def = boxes_scene()
    gbuf = analytic.render(scene_def, W, H)
    view = pytest.glint.ExactScene(*analytic_mesh.scene_mesh(scene_def, world=True)).seen_from(
        analytic_mesh.view_to_world(scene_def.camera))
    assert isinstance(view.scene, pytest.glint.ExactScene)
    np.testing.assert_array_equal(view.view_to_world, analytic_mesh.view_to_world(scene_def.camera))
    assert (trace(gbuf, view)[..., 2] > 0).sum() > 1000


def test_repr_says_what_the_bvh_last_did():
    kept = pytest.glint.ExactScene(*analytic_mesh.scene_mesh(boxes_scene(), world=True))
    assert "bvh: built" in repr(kept) and "triangles" in repr(kept)


def _tri():
    return np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0]], np.float32), np.array([[0, 1, 2]], np.int32)


@pytest.mark.parametrize("vertices,triangles,match", [
    (np.zeros((3, 3), np.float64), np.array([[0, 1, 2]], np.int32), "vertices"),
    (np.zeros((3, 2), np.float32), np.array([[0, 1, 2]], np.int32), "vertices"),
    (np.zeros((3, 3), np.float32), np.array([[0, 1, 2]], np.int64), "triangles"),
    (np.zeros((3, 3), np.float32), np.array([[0, 1, 3]], np.int32), "vertex 3"),
    (np.array([[0, 0, 0], [1, 0, 0], [math.nan, 0, 0]], np.float32), np.array([[0, 1, 2]], np.int32), "finite"),
])
def test_bad_scenes_name_what_is_wrong(glint, vertices, triangles, match):
    with pytest.raises(ValueError, match=match):
        glint.ExactScene(vertices, triangles)


def test_bad_updates_name_what_is_wrong(glint):
    kept = glint.ExactScene(*_tri())
    with pytest.raises(ValueError, match="vertices.*expected 3 vertices"):
        kept.update(np.zeros((4, 3), np.float32))
    with pytest.raises(ValueError, match="vertex 1 is not finite"):
        kept.update(np.array([[0, 0, 0], [math.inf, 0, 0], [0, 1, 0]], np.float32))
    with pytest.raises(ValueError, match="triangles"):
        kept.update(_tri()[0], np.array([[0, 1, 2]], np.uint32))
    with pytest.raises(ValueError, match="threads"):
        glint.ExactScene(*_tri(), threads=-1)
    assert kept.last_update["bvh"] == "built", "a refused update leaves the scene as it was"


@pytest.mark.parametrize("matrix,match", [
    (np.eye(3), r"view_to_world.*shape \(4, 4\)"),
    (np.diag([1.0, 1.0, 0.0, 1.0]), "view_to_world.*singular"),
    (np.array([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, -1, 0]], float), "view_to_world.*affine"),
    (np.full((4, 4), math.nan), "view_to_world.*finite"),
    ([[1, 0, 0, 0]] * 4, "view_to_world.*numpy array"),
])
def test_bad_camera_matrices_name_view_to_world(glint, matrix, match):
    with pytest.raises(ValueError, match=match):
        glint.ExactScene(*_tri()).seen_from(matrix)


def test_a_mesh_of_another_kind_names_mesh(glint):
    gbuf = analytic.render(boxes_scene(), 8, 6)
    with pytest.raises(ValueError, match="mesh.*ExactScene"):
        glint.trace(gbuf["position"], gbuf["normal"], gbuf["projection"], march="exact", mesh=42)

"""bench/sweep.py: a small sweep writes the CSV and plot the docs are made of,
and its Pareto front is right on points where it is known."""
import csv
import os
import sys

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
sys.path.insert(0, os.path.join(ROOT, "bench"))

import sweep  # noqa: E402


def _score(uv, hit_uv, visible, tolerance_px=1.5):
    """Precision and recall as the accuracy contract defines them: a pixel reports
    when its visibility is > 1e-3; a report is right within tolerance_px of a
    visible exact hit."""
    h, w = uv.shape[:2]
    reported = uv[..., 2] > 1e-3
    err = np.hypot((uv[..., 0] - hit_uv[..., 0]) * w, (uv[..., 1] - hit_uv[..., 1]) * h)
    right = reported & visible & (err <= tolerance_px)
    return right.sum() / max(reported.sum(), 1), right.sum() / max(visible.sum(), 1)


def test_the_sweeps_reference_is_the_exact_answer(glint):
    """Every row is scored against march='exact'; that reference is held here to
    float64 ray casts of the same analytic scene (independent of Embree), so a
    sweep cannot rate a march against a wrong answer."""
    import analytic
    scene = analytic.mirror_floor_scene()
    g = analytic.render(scene, 64, 48)
    frame = sweep.analytic_frame("floor", 64, 48)
    assert np.array_equal(frame["position"], g["position"])
    exact = glint.trace(frame["position"], frame["normal"], frame["projection"], march="exact",
                        mesh=(frame["vertices"], frame["triangles"]))
    hits = analytic.mirror_hits(scene, g, 15.0, incident="view")
    precision, recall = _score(exact, hits["uv"], hits["visible"])
    # Tessellated spheres: within 1.5 px on >= 99% (docs/marches.md).
    assert precision >= 0.99 and recall >= 0.99, (precision, recall)


def test_pareto_front_of_hand_made_points():
    times = [1.0, 2.0, 3.0, 2.5, 4.0, 1.0]
    scores = [0.5, 0.7, 0.9, 0.6, 0.9, 0.4]
    # (2.5, 0.6) is beaten by (2.0, 0.7); (4.0, 0.9) by (3.0, 0.9); (1.0, 0.4) by (1.0, 0.5).
    assert sweep.pareto(times, scores).tolist() == [True, True, True, False, False, False]


def test_grid_keeps_only_the_knobs_a_march_reads(glint):
    grid = {"resolution": [0.1, 0.5], "steps": [5, 10], "thickness": [0.5], "max_distance": [15.0]}
    points = sweep.grid_points(["seed", "hiz", "linear"], grid)
    seed = [p for p in points if p["march"] == "seed"]
    hiz = [p for p in points if p["march"] == "hiz"]
    linear = [p for p in points if p["march"] == "linear"]
    assert len(seed) == 4                      # resolution x steps
    assert len(hiz) == 4                       # resolution (reusing rays at <= 0.5) x steps
    assert len(linear) == 2                    # linear ignores resolution
    assert {p["resolution"] for p in linear} == {0.1}


def test_small_sweep_writes_the_expected_columns(glint, tmp_path):
    sweep.main(["--scene", "analytic:floor", "--sizes", "64x48", "--march", "seed,hiz", "--resolution", "0.3",
                "--steps", "5", "--thickness", "0.5", "--repeat", "1", "--out", str(tmp_path)])
    with open(tmp_path / "floor.csv") as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0].keys()) == sweep.COLUMNS
    presets = {r["preset"] for r in rows}
    assert set(glint.presets()) <= presets
    # The balanced row holds what its own trace scores against the exact march,
    # scored here by the definition (docs/conventions.md) rather than by compare(),
    # over the pixels that reflect (both traced with the specular buffer).
    frame = sweep.analytic_frame("floor", 64, 48)
    exact = glint.trace(frame["position"], frame["normal"], frame["projection"], march="exact",
                        mesh=(frame["vertices"], frame["triangles"]), specular=frame["specular"])
    uv = glint.trace(frame["position"], frame["normal"], frame["projection"], specular=frame["specular"],
                     **glint.presets()["balanced"])
    precision, recall = _score(uv, exact[..., :2], exact[..., 2] > 0)
    (row,) = [r for r in rows if r["preset"] == "balanced" and r["back_layer"] == "0"]
    assert float(row["precision"]) == pytest.approx(precision, rel=1e-5)
    assert float(row["recall"]) == pytest.approx(recall, rel=1e-5)
    for r in rows:
        assert 0.0 <= float(r["precision"]) <= 1.0 and 0.0 <= float(r["recall"]) <= 1.0
        assert float(r["ms"]) > 0 and (r["width"], r["height"]) == ("64", "48")
    assert (tmp_path / "floor_64x48.png").stat().st_size > 1000


@pytest.mark.parametrize("name", sorted(sweep._analytic_scenes()))
def test_every_march_stays_finite_on_the_extreme_scenes(glint, name):
    frame = sweep.analytic_frame(name, 48, 32)
    distance = float(frame.get("max_distance", 15.0))
    for march, d in glint.march_details().items():
        kw = {"mesh": (frame["vertices"], frame["triangles"])} if d["needs_mesh"] else {}
        uv = glint.trace(frame["position"], frame["normal"], frame["projection"], march=march,
                         max_distance=distance, **kw)
        assert np.isfinite(uv).all(), (name, march)

"""trace, pipeline and rasterize called from many Python threads at once (the GIL
is released around the native work) give exactly what the same calls give one at
a time, on the CPU and the GL backend. The serial results are the reference: the
backends are deterministic, so any difference is a race."""
from __future__ import annotations

import threading
from concurrent.futures import ThreadPoolExecutor

import numpy as np
import pytest

import analytic as A
from glint_tables import SCREEN_MARCHES

THREADS = 6
ROUNDS = 3


@pytest.fixture(scope="module")
def scene():
    sc = A.mirror_floor_scene()
    g = A.render(sc, 48, 32)
    g["projection32"] = g["projection"].astype(np.float32)
    return g


def backends(glint):
    out = ["cpu"]
    try:
        glint.backend_name("gl")
        out.append("gl")
    except glint.BackendUnavailable:
        pass
    return out


def quad_mesh():
    pos = np.array([[[-2, -1, -3], [2, -1, -3], [2, -1, -9]], [[-2, -1, -3], [2, -1, -9], [-2, -1, -9]],
                    [[-1, -1, -5], [1, -1, -5], [0, 1, -5]]], np.float32)
    nrm = np.array([[[0, 1, 0]] * 3, [[0, 1, 0]] * 3, [[0, 0, 1]] * 3], np.float32)
    mats = np.array([[0.8, 0.8, 0.8, 127.75], [0.2, 0.2, 0.2, 10.0]], np.float32)
    return pos, nrm, np.array([0, 0, 1], np.int32), mats


def calls(glint, g, backend):
    """Every kind of call, each a zero-argument function returning arrays."""
    out = []
    for march in SCREEN_MARCHES:
        out.append((f"trace/{march}", lambda m=march: {"uv": glint.trace(
            g["position"], g["normal"], g["projection32"], march=m, backend=backend)}))
    out.append(("pipeline", lambda: {k: v for k, v in glint.pipeline(
        g["position"], g["normal"], g["specular"], g["color"], g["projection32"],
        blur_size=2, backend=backend).items() if k != "stats"}))
    pos, nrm, idx, mats = quad_mesh()
    out.append(("rasterize", lambda: glint.rasterize(pos, nrm, idx, mats, g["projection32"], 40, 30,
                                                     back_layer=True, backend=backend)))
    return out


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_many_threads_give_the_serial_results(glint, scene, backend):
    if backend not in backends(glint):
        pytest.skip("no GL context here")
    work = calls(glint, scene, backend)
    serial = {name: fn() for name, fn in work}
    jobs = [(name, fn) for _ in range(ROUNDS) for name, fn in work]
    start = threading.Barrier(THREADS)

    def run(job):
        name, fn = job
        return name, fn()

    def first(job):  # line every thread up so the first calls really overlap
        start.wait()
        return run(job)

    with ThreadPoolExecutor(max_workers=THREADS) as pool:
        results = list(pool.map(first, jobs[:THREADS])) + list(pool.map(run, jobs[THREADS:]))
    assert len(results) == len(jobs)
    for name, got in results:
        want = serial[name]
        assert set(got) == set(want), name
        for layer in want:
            np.testing.assert_array_equal(got[layer], want[layer], err_msg=f"{name}: {layer}")


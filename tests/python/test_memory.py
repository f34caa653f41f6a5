"""Memory known before it is taken: requests too large for the memory limit are
refused up front with glint_core.MemoryLimitExceeded (a MemoryError) saying how
much they needed and how to raise the limit, before the inputs are even copied.

The refused requests are 32768x32768 (the largest size every entry point accepts):
their inputs are numpy broadcast views that take no memory, so a refusal that came
after a copy would show in the process's peak RSS."""
from __future__ import annotations

import resource
import struct
import time
from pathlib import Path

import numpy as np
import pytest

from glint_tables import SCREEN_MARCHES

SIDE = 32768
PIXELS = SIDE * SIDE
# Refusing must not cost memory: far below the 16 GiB one RGBA image of this size takes.
RSS_SLACK = 64 << 20


def peak_rss() -> int:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss * 1024


def huge(channels=4, value=0.0):
    return np.broadcast_to(np.full(channels, value, np.float32), (SIDE, SIDE, channels))


def perspective():
    return np.array([[1.5, 0, 0, 0], [0, 1.5, 0, 0], [0, 0, -1.002, -0.2002], [0, 0, -1, 0]],
                    np.float32)


def assert_refused(glint, exc_info, before, t0, lower_bound):
    elapsed = time.perf_counter() - t0
    exc = exc_info.value
    assert isinstance(exc, MemoryError)
    msg = str(exc)
    assert "memory_limit_mb" in msg and glint.MEMORY_LIMIT_ENV in msg, msg
    assert exc.needed_bytes > exc.limit_bytes
    # The estimate is at least the outputs alone, counted here independently.
    assert exc.needed_bytes >= lower_bound
    assert elapsed < 2.0, f"refusing took {elapsed:.2f} s"
    grown = peak_rss() - before
    assert grown < RSS_SLACK, f"peak RSS grew by {grown >> 20} MiB before refusing"


@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_rasterize_at_the_largest_size_is_refused_before_allocating(glint, backend):
    tri = np.array([[[-1, -1, -3], [1, -1, -3], [0, 1, -3]]], np.float32)
    nrm = np.tile(np.float32([0, 0, 1]), (1, 3, 1))
    before = peak_rss()
    t0 = time.perf_counter()
    with pytest.raises(glint.MemoryLimitExceeded) as info:
        glint.rasterize(tri, nrm, np.zeros(1, np.int32), np.ones((1, 4), np.float32),
                        perspective(), SIDE, SIDE, backend=backend)
    # position, normal and specular: three float32 RGBA images.
    assert_refused(glint, info, before, t0, 3 * 16 * PIXELS)
    assert f"{SIDE}x{SIDE}" in str(info.value)


@pytest.mark.parametrize("march", SCREEN_MARCHES)
@pytest.mark.parametrize("backend", ["cpu", "gl"])
def test_trace_at_the_largest_size_is_refused_before_copying(glint, march, backend):
    before = peak_rss()
    t0 = time.perf_counter()
    with pytest.raises(glint.MemoryLimitExceeded) as info:
        glint.trace(huge(4, 1.0), huge(3), perspective(), march=march, backend=backend)
    assert_refused(glint, info, before, t0, 16 * PIXELS)


def test_pipeline_at_the_largest_size_is_refused_before_copying(glint):
    before = peak_rss()
    t0 = time.perf_counter()
    with pytest.raises(glint.MemoryLimitExceeded) as info:
        glint.pipeline(huge(4, 1.0), huge(3), huge(4), huge(3), perspective())
    # Five float32 RGBA layers come back.
    assert_refused(glint, info, before, t0, 5 * 16 * PIXELS)


def test_the_default_limit_is_half_of_physical_memory(glint, monkeypatch):
    import os

    monkeypatch.delenv(glint.MEMORY_LIMIT_ENV, raising=False)
    phys = os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE")
    limit, source = glint.memory_limit()
    assert abs(limit - phys // 2) <= 1
    assert "default" in source


def test_the_option_and_the_variable_set_the_limit(glint, monkeypatch):
    monkeypatch.setenv(glint.MEMORY_LIMIT_ENV, "300")
    assert glint.memory_limit() == (300 << 20, glint.MEMORY_LIMIT_ENV)
    # The keyword wins over the variable.
    assert glint.memory_limit(12.5) == (int(12.5 * (1 << 20)), "memory_limit_mb")


def small_scene(n):
    y, x = np.mgrid[0:n, 0:n].astype(np.float32)
    pos = np.stack([(x - n / 2) / n, np.full_like(x, -1.0), -2.0 - 4.0 * y / n, np.ones_like(x)], -1)
    nrm = np.zeros((n, n, 3), np.float32)
    nrm[..., 1] = 1.0
    spec = np.ones((n, n, 4), np.float32)
    return pos.astype(np.float32), nrm, spec


def test_the_variable_refuses_what_it_does_not_allow(glint, monkeypatch):
    pos, nrm, _ = small_scene(256)
    monkeypatch.setenv(glint.MEMORY_LIMIT_ENV, "1")
    # At least the copies of position and normal and the returned uv: 3 x 1 MiB at 256x256.
    with pytest.raises(glint.MemoryLimitExceeded, match="1.0 MiB") as info:
        glint.trace(pos, nrm, perspective())
    assert info.value.limit_bytes == 1 << 20
    assert info.value.needed_bytes >= 3 * 16 * 256 * 256
    small = glint.trace(pos[:8, :8].copy(), nrm[:8, :8].copy(), perspective())
    assert small.shape == (8, 8, 4)
    # The keyword overrides the variable for one call.
    assert glint.trace(pos, nrm, perspective(), memory_limit_mb=64).shape == (256, 256, 4)


@pytest.mark.parametrize("value", [-1.0, float("nan"), float("inf")])
def test_a_bad_limit_names_the_keyword(glint, value):
    pos, nrm, _ = small_scene(4)
    with pytest.raises(ValueError, match="memory_limit_mb"):
        glint.trace(pos, nrm, perspective(), memory_limit_mb=value)


def test_a_malformed_variable_is_named(glint, monkeypatch):
    pos, nrm, _ = small_scene(4)
    monkeypatch.setenv(glint.MEMORY_LIMIT_ENV, "lots")
    with pytest.raises(ValueError, match=glint.MEMORY_LIMIT_ENV):
        glint.trace(pos, nrm, perspective())


def set_display_window(data: bytes, width: int, height: int) -> bytes:
    """The same EXR with its displayWindow header attribute (box2i: xmin, ymin, xmax,
    ymax as int32) set to width x height; the pixels and data window stay as they were."""
    key = b"displayWindow\x00box2i\x00" + struct.pack("<i", 16)
    at = data.index(key) + len(key)
    return data[:at] + struct.pack("<4i", 0, 0, width - 1, height - 1) + data[at + 16:]


def test_an_exr_header_promising_gigabytes_is_refused(glint, tmp_path):
    small = tmp_path / "small.exr"
    glint.write_exr(str(small), {"a": np.ones((2, 2, 4), np.float32), "b": np.ones((2, 2, 4), np.float32)},
                    compression="none")
    layers, _ = glint.read_exr(str(small))
    assert set(layers) == {"a", "b"}
    # A file of a few hundred bytes whose header says 32768x32768: two layers of
    # 16 GiB each, where before this check the reader zero-filled them all.
    liar = tmp_path / "liar.exr"
    liar.write_bytes(set_display_window(small.read_bytes(), SIDE, SIDE))
    assert liar.stat().st_size < 2048
    before = peak_rss()
    t0 = time.perf_counter()
    with pytest.raises(glint.MemoryLimitExceeded) as info:
        glint.read_exr(str(liar))
    assert_refused(glint, info, before, t0, 2 * 16 * PIXELS)
    assert "2 layers" in str(info.value)
    # Within its limit the same request is read (the data window, rest zero).
    with pytest.raises(glint.MemoryLimitExceeded):
        glint.read_exr(str(small), memory_limit_mb=0.001)


REGRESSIONS = sorted((Path(__file__).resolve().parents[2] / "fuzz" / "corpus" / "exr").glob("regress_*.exr"))


@pytest.mark.parametrize("path", REGRESSIONS, ids=[p.name for p in REGRESSIONS])
def test_exr_fuzz_findings_fail_cleanly_without_allocating(glint, path):
    """Files fuzz_exr found: under 1 KB each, their headers declare attribute sizes
    OpenEXR allocated (about 2 GB) before finding the file shorter."""
    assert path.stat().st_size < 1024
    before = peak_rss()
    t0 = time.perf_counter()
    with pytest.raises(RuntimeError, match="header attribute"):
        glint.read_exr(str(path))
    assert time.perf_counter() - t0 < 1.0
    assert peak_rss() - before < RSS_SLACK

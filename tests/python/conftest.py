"""Shared setup of the glint_core Python tests.

* Puts ``$GLINT_BUILD_DIR/python`` (default ``<repo>/build/python``) first on
  sys.path so ``import glint_core`` finds the module of that build, and stops
  the run with a clear message when it is not there.
* Puts this folder on sys.path for the helpers (analytic.py, reference_seed.py).
* Registers the ``slow`` and ``gl`` markers (no filtering by default).
* ``--glint-out DIR`` (or ``GLINT_TEST_OUT``; default ``$GLINT_BUILD_DIR/test-out``):
  where the ``artifacts`` fixture writes its images, only for a failed test.
"""
from __future__ import annotations

import os
import re
import struct
import sys
import zlib
from pathlib import Path

import numpy as np
import pytest

HERE = Path(__file__).resolve().parent
REPO = HERE.parent.parent
BUILD_DIR = Path(os.environ.get("GLINT_BUILD_DIR", REPO / "build")).resolve()
MODULE_DIR = BUILD_DIR / "python"

if str(HERE) not in sys.path:
    sys.path.insert(0, str(HERE))
sys.path.insert(0, str(MODULE_DIR))

try:
    import glint_core  # noqa: F401  (checked here once, used by every test module)
except ImportError as exc:  # pragma: no cover - the message is the point
    pytest.exit(
        f"glint_core is not importable from {MODULE_DIR} ({exc}).\n"
        f"Build it first:  cmake -S {REPO} -B {BUILD_DIR} -G Ninja && cmake --build {BUILD_DIR} -j2\n"
        "or point GLINT_BUILD_DIR at the build directory that holds python/glint_core*.so.",
        returncode=4,
    )


def pytest_addoption(parser):
    parser.addoption("--glint-out", action="store", default=None,
                     help="folder for diff images of failed glint tests "
                          "(default: $GLINT_TEST_OUT or $GLINT_BUILD_DIR/test-out)")


def pytest_configure(config):
    config.addinivalue_line("markers", "slow: takes more than a few seconds (still run by default)")
    config.addinivalue_line("markers", "gl: needs an EGL/OpenGL context")


def output_dir(config) -> Path:
    opt = config.getoption("--glint-out", default=None)
    return Path(opt or os.environ.get("GLINT_TEST_OUT") or BUILD_DIR / "test-out")


# --- images of failed tests ------------------------------------------------------------


def write_png(path, image, lo=None, hi=None):
    """Write a float image [H, W] or [H, W, C] (C = 1..4) as an 8-bit PNG.

    Values map linearly from [lo, hi] (default: the finite min / max) to 0..255;
    NaN shows as magenta-ish 255/0/255 in RGB images, 0 otherwise. Row 0 of
    the array is the BOTTOM row (docs/conventions.md), so rows are flipped for the file.
    """
    a = np.asarray(image, dtype=np.float64)
    if a.ndim == 2:
        a = a[..., None]
    if a.ndim != 3 or not 1 <= a.shape[2] <= 4:
        raise ValueError(f"image: expected [H, W] or [H, W, 1..4], got shape {a.shape}")
    finite = np.isfinite(a)
    if lo is None:
        lo = float(a[finite].min()) if finite.any() else 0.0
    if hi is None:
        hi = float(a[finite].max()) if finite.any() else 1.0
    scale = 255.0 / (hi - lo) if hi > lo else 0.0
    b = np.clip(np.where(finite, (a - lo) * scale, 0.0), 0, 255).round().astype(np.uint8)
    c = b.shape[2]
    if c == 2:  # (u, v) -> RGB with blue 0
        b = np.concatenate([b, np.zeros_like(b[..., :1])], axis=2)
        c = 3
    if c >= 3:
        nan = ~finite[..., :3].all(axis=2)
        b[nan, 0], b[nan, 1], b[nan, 2] = 255, 0, 255
    b = b[::-1]
    h, w = b.shape[:2]
    color_type = {1: 0, 3: 2, 4: 6}[c]
    raw = b"".join(b"\x00" + b[j].tobytes() for j in range(h))

    def chunk(tag, data):
        return (struct.pack(">I", len(data)) + tag + data
                + struct.pack(">I", zlib.crc32(tag + data) & 0xFFFFFFFF))

    png = (b"\x89PNG\r\n\x1a\n"
           + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8, color_type, 0, 0, 0))
           + chunk(b"IDAT", zlib.compress(raw, 6)) + chunk(b"IEND", b""))
    Path(path).write_bytes(png)


class Artifacts:
    """Images a test wants to see if it fails: ``artifacts.add(name, array)``.

    Each is written as ``<out>/<test id>/<name>.png`` (scaled for viewing) and
    ``.npy`` (exact values), only when the test fails.
    """

    def __init__(self):
        self.items = []

    def add(self, name, image, lo=None, hi=None):
        self.items.append((name, np.array(image, copy=True), lo, hi))

    def write(self, folder: Path):
        folder.mkdir(parents=True, exist_ok=True)
        for name, img, lo, hi in self.items:
            np.save(folder / f"{name}.npy", img)
            if img.ndim in (2, 3) and (img.ndim == 2 or img.shape[2] <= 4):
                write_png(folder / f"{name}.png", img, lo, hi)
        return folder


@pytest.fixture
def artifacts(request):
    art = Artifacts()
    request.node._glint_artifacts = art
    yield art


@pytest.hookimpl(hookwrapper=True)
def pytest_runtest_makereport(item, call):
    outcome = yield
    rep = outcome.get_result()
    art = getattr(item, "_glint_artifacts", None)
    if art is None or not art.items or not rep.failed or rep.when not in ("call", "setup"):
        return
    safe = re.sub(r"[^A-Za-z0-9_.=-]+", "_", item.nodeid)
    try:
        folder = art.write(output_dir(item.config) / safe)
        rep.sections.append(("glint artifacts", f"images written to {folder}"))
    except OSError as exc:  # never mask the real failure
        rep.sections.append(("glint artifacts", f"could not write images: {exc}"))


# --- shared helpers ----------------------------------------------------------------------


@pytest.fixture(scope="session")
def glint():
    """The glint_core module of the build under test."""
    import glint_core as g

    return g


@pytest.fixture(scope="session")
def gl(glint):
    """glint_core, after checking that backend="gl" can run here (else skip)."""
    if not glint.gl_compiled_in():
        pytest.skip("glint_core was built with GLINT_WITH_GL=OFF")
    try:
        glint.backend_name("gl")
    except glint.BackendUnavailable as exc:
        pytest.skip(f"no OpenGL context here: {exc}")
    return glint

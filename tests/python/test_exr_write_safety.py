"""A frame loses nothing: write_exr writes a temporary file beside the target and
renames it into place only when it is complete, so a full disk or a killed writer
never leaves a truncated file under the final name, and an older file there stays
whole. The faults are injected from outside the library: RLIMIT_FSIZE makes every
write past a size fail the way a full disk does (EFBIG instead of ENOSPC), and a
writer process is killed with SIGKILL mid-write."""
from __future__ import annotations

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import glint_core
import pytest

# The children import the module of the build under test, as conftest.py found it.
MODULE_DIR = os.path.dirname(glint_core.__file__)


def layers(n, value):
    img = np.full((n, n, 4), value, np.float32)
    return {"position": img, "normal": img + 1.0}


def run_child(code: str, timeout=60):
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code)], capture_output=True, text=True,
                          timeout=timeout, env={**os.environ, "PYTHONPATH": MODULE_DIR})


def leftovers(folder):
    return [p.name for p in folder.iterdir() if ".glint-tmp-" in p.name]


@pytest.mark.parametrize("existing", [True, False])
def test_a_full_disk_leaves_the_old_file_or_none(glint, tmp_path, existing):
    target = tmp_path / "frame_0001.exr"
    if existing:
        glint.write_exr(str(target), layers(8, 0.25), compression="none")
    old = target.read_bytes() if existing else None
    # 256x256, two layers, uncompressed: about 2 MiB, far over the 64 KiB allowed.
    r = run_child(f"""
        import resource, signal
        import numpy as np
        import glint_core
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)  # write() fails with EFBIG instead
        resource.setrlimit(resource.RLIMIT_FSIZE, (64 * 1024, resource.RLIM_INFINITY))
        img = np.full((256, 256, 4), 7.0, np.float32)
        try:
            glint_core.write_exr({str(target)!r}, {{"position": img, "normal": img}}, compression="none")
        except RuntimeError as e:
            print("REFUSED:", e)
        else:
            print("WROTE")
    """)
    assert r.returncode == 0, r.stderr
    assert "REFUSED:" in r.stdout and "cannot write EXR" in r.stdout, r.stdout
    if existing:
        assert target.read_bytes() == old
        got, _ = glint.read_exr(str(target))
        np.testing.assert_array_equal(got["position"], np.full((8, 8, 4), 0.25, np.float32))
    else:
        assert not target.exists()
    assert leftovers(tmp_path) == []


def test_a_killed_writer_never_leaves_a_truncated_file(glint, tmp_path):
    target = tmp_path / "frame.exr"
    n = 384  # ~4.5 MiB uncompressed: each write takes long enough to be cut short
    child = subprocess.Popen([sys.executable, "-c", textwrap.dedent(f"""
        import sys
        import numpy as np
        import glint_core
        img = np.full(({n}, {n}, 4), 3.0, np.float32)
        for i in range(100000):
            glint_core.write_exr({str(target)!r}, {{"position": img, "normal": img + 1}}, compression="none")
            if i == 0:
                print("FIRST", flush=True)
    """)], stdout=subprocess.PIPE, text=True, env={**os.environ, "PYTHONPATH": MODULE_DIR})
    try:
        assert child.stdout.readline().strip() == "FIRST"
        time.sleep(0.37)
    finally:
        child.send_signal(signal.SIGKILL)
        child.wait(timeout=30)
    got, header = glint.read_exr(str(target))
    assert (header["width"], header["height"]) == (n, n)
    np.testing.assert_array_equal(got["normal"], np.full((n, n, 4), 4.0, np.float32))
    # The killed write's temporary file may remain (hidden, named for the process);
    # never more than the one write that was cut short.
    assert len(leftovers(tmp_path)) <= 1


def test_an_unwritable_folder_creates_nothing(glint, tmp_path):
    target = tmp_path / "missing" / "frame.exr"
    with pytest.raises(RuntimeError, match="cannot write EXR"):
        glint.write_exr(str(target), layers(4, 1.0))
    assert not target.parent.exists()


def test_writing_over_a_file_replaces_it_whole(glint, tmp_path):
    target = tmp_path / "frame.exr"
    glint.write_exr(str(target), layers(16, 1.0))
    glint.write_exr(str(target), layers(4, 2.0))
    got, header = glint.read_exr(str(target))
    assert (header["width"], header["height"]) == (4, 4)
    np.testing.assert_array_equal(got["position"], np.full((4, 4, 4), 2.0, np.float32))
    assert leftovers(tmp_path) == []

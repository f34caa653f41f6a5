"""Running Blender for the add-on tests.

Every test run gets a private user-scripts folder whose ``addons/glint`` is a
symlink to this checkout's ``addon/glint`` (so the tests exercise the checkout,
installed the way scripts/install_addon.sh installs it), ``GLINT_CORE_PATH``
pointing at the build's python folder, and sample scenes freshly made by
``blend_samples/make_samples.py`` (which tests the script too).

Environment: GLINT_BUILD_DIR (default <checkout>/build), BLENDER (default blender).
"""
import json
import os
import shutil
import subprocess
import sys
import uuid

import numpy as np
import pytest

ROOT = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
HERE = os.path.dirname(os.path.abspath(__file__))
DRIVER = os.path.join(HERE, "driver.py")
BLENDER = os.environ.get("BLENDER", "blender")
BUILD = os.environ.get("GLINT_BUILD_DIR", os.path.join(ROOT, "build"))
CORE_DIR = os.path.join(BUILD, "python")
SIZE = (160, 90)


def have_blender():
    return shutil.which(BLENDER) is not None


def core():
    if CORE_DIR not in sys.path:
        sys.path.insert(0, CORE_DIR)
    import glint_core
    return glint_core


class Blender:
    """One isolated Blender set-up: user scripts/config folders and an env."""

    def __init__(self, root, core_path=True, link_addon=True):
        self.root = root
        self.scripts = os.path.join(root, "scripts")
        self.config = os.path.join(root, "config")
        os.makedirs(os.path.join(self.scripts, "addons"), exist_ok=True)
        os.makedirs(self.config, exist_ok=True)
        if link_addon:
            link = os.path.join(self.scripts, "addons", "glint")
            if not os.path.lexists(link):
                os.symlink(os.path.join(ROOT, "addon", "glint"), link)
        self.env = dict(os.environ)
        self.env["BLENDER_USER_SCRIPTS"] = self.scripts
        self.env["BLENDER_USER_CONFIG"] = self.config
        self.env.pop("GLINT_CORE_PATH", None)
        if core_path:
            self.env["GLINT_CORE_PATH"] = CORE_DIR

    def run(self, args, timeout=300, check=True, factory=True):
        """Run Blender; ``factory=False`` loads the saved preferences (enabled add-ons)."""
        cmd = [BLENDER, "-b"] + (["--factory-startup"] if factory else []) + ["-noaudio"] + list(args)
        proc = subprocess.run(cmd, env=self.env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                              text=True, timeout=timeout)
        if check and proc.returncode != 0:
            raise AssertionError(f"blender failed ({proc.returncode}): {' '.join(cmd)}\n{proc.stdout[-4000:]}")
        return proc.stdout

    def render(self, blend, out_dir, config=None, frames=("-f", "1"), addons=True, timeout=300, factory=True):
        """Render ``blend`` through driver.py (which applies ``config``); returns the log."""
        os.makedirs(out_dir, exist_ok=True)
        cfg = {"size": list(SIZE), "out": out_dir, "eevee_samples": 4, "cycles_samples": 4}
        cfg.update(config or {})
        cfg_path = os.path.join(out_dir, f"config-{uuid.uuid4().hex[:8]}.json")
        with open(cfg_path, "w") as f:
            json.dump(cfg, f)
        args = [blend]
        if addons:
            args += ["--addons", "glint"]
        args += ["--python", DRIVER] + list(frames) + ["--", cfg_path]
        log = self.run(args, timeout=timeout, factory=factory)
        with open(os.path.join(out_dir, "blender.log"), "a") as f:
            f.write(log)
        return log


def read_exr(path, layer=""):
    layers, header = core().read_exr(path)
    return layers[layer] if layer is not None else layers


def load_dump(out_dir, frame=1):
    return dict(np.load(os.path.join(out_dir, f"dump_{frame:04d}.npz"), allow_pickle=True))


# The mirror_floor sample's objects over its mirror (make_samples.py).
MIRROR_OBJECTS = ["Red Sphere", "Green Cube", "Blue Cone"]


def hull_mask(points_uv, w, h):
    """Pixels (centres) inside the convex hull of uv points."""
    pts = np.asarray(points_uv)[:, :2] * (w, h)
    # Andrew's monotone chain
    p = sorted(map(tuple, pts))

    def cross(o, a, b):
        return (a[0] - o[0]) * (b[1] - o[1]) - (a[1] - o[1]) * (b[0] - o[0])

    lower, upper = [], []
    for q in p:
        while len(lower) >= 2 and cross(lower[-2], lower[-1], q) <= 0:
            lower.pop()
        lower.append(q)
    for q in reversed(p):
        while len(upper) >= 2 and cross(upper[-2], upper[-1], q) <= 0:
            upper.pop()
        upper.append(q)
    hull = np.array(lower[:-1] + upper[:-1])
    ys, xs = np.mgrid[0:h, 0:w] + 0.5
    inside = np.ones((h, w), bool)
    for i in range(len(hull)):
        a, b = hull[i], hull[(i + 1) % len(hull)]
        inside &= (b[0] - a[0]) * (ys - a[1]) - (b[1] - a[1]) * (xs - a[0]) >= 0
    return inside


def dilate(mask, r):
    out = mask.copy()
    for dy in range(-r, r + 1):
        for dx in range(-r, r + 1):
            out |= np.roll(np.roll(mask, dy, 0), dx, 1)
    return out


def erode(mask, r):
    return ~dilate(~mask, r)


# Draws every Glint panel and the preferences into a recording fake layout (no UI in -b),
# checking each property and operator named exists; prints them and the labels.
PANELS = r"""
import bpy, types
class FakeLayout:
    # Records what a panel draws; checks every property and operator it names exists.
    def __init__(self, log): self.log = log
    def __getattr__(self, name): return None
    def __setattr__(self, name, value): object.__setattr__(self, name, value)
    def _sub(self, *a, **k): return FakeLayout(self.log)
    box = row = column = split = _sub
    def label(self, text="", icon="NONE"): self.log.append(("label", text))
    def prop(self, data, name, **k):
        assert name in data.bl_rna.properties, name
        self.log.append(("prop", name))
    def prop_search(self, data, name, sdata, sname, **k):
        assert name in data.bl_rna.properties and sname in sdata.bl_rna.properties
        self.log.append(("prop", name))
    def operator(self, idname, **k):
        mod, op = idname.split(".")
        assert hasattr(getattr(bpy.ops, mod), op), idname
        self.log.append(("operator", idname))
log = []
ctx = types.SimpleNamespace(scene=bpy.context.scene)
for name in ("GLINT_PT_render", "GLINT_PT_parameters", "GLINT_PT_backend", "GLINT_PT_debug"):
    cls = getattr(bpy.types, name)
    panel = types.SimpleNamespace(layout=FakeLayout(log))
    cls.draw(panel, ctx)
    if hasattr(cls, "draw_header"):
        cls.draw_header(panel, ctx)
import glint.preferences
glint.preferences.GLINT_AddonPreferences.draw(types.SimpleNamespace(layout=FakeLayout(log)), ctx)
print("PANELS", sorted({n for k, n in log if k in ("prop", "operator")}))
print("LABELS", [n for k, n in log if k == "label"])
"""


@pytest.fixture(scope="session")
def blender_ok():
    if not have_blender():
        pytest.skip("blender not found")
    if not os.path.isdir(CORE_DIR):
        pytest.skip(f"no glint_core build in {CORE_DIR} (set GLINT_BUILD_DIR)")
    return True


@pytest.fixture(scope="session")
def session_dir(tmp_path_factory, blender_ok):
    return str(tmp_path_factory.mktemp("glint_blender"))


@pytest.fixture(scope="session")
def blender(session_dir):
    return Blender(os.path.join(session_dir, "home"))


@pytest.fixture(scope="session")
def samples(session_dir, blender):
    """The sample scenes, made now by the script kept beside them."""
    out = os.path.join(session_dir, "samples")
    log = blender.run(["--python", os.path.join(ROOT, "blend_samples", "make_samples.py"), "--", out])
    names = ["mirror_floor", "metals_roughness", "water_normal_map", "no_reflection", "ortho_camera",
             "animated_camera"]
    paths = {n: os.path.join(out, n + ".blend") for n in names}
    for n, p in paths.items():
        assert os.path.isfile(p), f"make_samples.py did not write {n}.blend\n{log[-2000:]}"
    return paths


@pytest.fixture(scope="session")
def mirror_off(blender, samples, session_dir):
    """mirror_floor.blend rendered with Glint switched off: the base to compare with."""
    out = os.path.join(session_dir, "mirror_off")
    log = blender.render(samples["mirror_floor"], out, {"glint": {"enabled": False}})
    return out, log

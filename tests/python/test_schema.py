"""native/include/glint/schema.h is the single source of the options and of the
constants the backends and the add-on share. This compares every place that
reads it with glint_core: the add-on's generated copy (byte for byte with what
the build writes, and value for value), its panel limits and material mapping,
the keyword defaults of glint_core's functions, glint-exr's help and the shaders'
schema.glsl. A failure names the copy that drifted and how to bring it back."""
import inspect
import os
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

import glint_core
from glint_tables import addon_schema

REPO = Path(__file__).resolve().parents[2]
BUILD = Path(os.environ.get("GLINT_BUILD_DIR", REPO / "build")).resolve()
SCHEMA = glint_core.schema()
OPTIONS, CONSTANTS = SCHEMA["options"], SCHEMA["constants"]


def _same(a, b, kind):
    """Equal as the core stores them: float32 for float, exactly otherwise."""
    if kind == "float":
        return np.float32(a) == np.float32(b)
    return a == b


def test_the_addon_copy_is_what_the_build_writes():
    built = BUILD / "generated" / "schema.py"
    if not built.exists():
        pytest.skip(f"no {built}: build first")
    committed = REPO / "addon" / "glint" / "logic" / "schema.py"
    assert committed.read_bytes() == built.read_bytes(), (
        f"{committed} differs from the build's {built}: copy it over after changing schema.h")


def test_the_addon_copy_has_the_cores_values():
    mod = addon_schema()
    assert set(mod.CONSTANTS) == set(CONSTANTS)
    for name, value in CONSTANTS.items():
        kind = "float" if isinstance(value, float) and np.float32(value) == value else "exact"
        assert _same(getattr(mod, name), value, kind) or getattr(mod, name) == pytest.approx(value), name
    assert set(mod.OPTIONS) == set(OPTIONS)
    for name, opt in OPTIONS.items():
        mine = mod.OPTIONS[name]
        assert mine["type"] == opt["type"] and mine["unit"] == opt["unit"] and mine["doc"] == opt["doc"], name
        if opt["type"] == "name":
            assert mine["default"] == opt["default"] and mine["choices"] == opt["choices"], name
        else:
            assert _same(mine["default"], opt["default"], opt["type"]), name
            assert (mine["min"], mine["max"]) == (opt["min"], opt["max"]), name


def _signature_defaults(fn):
    """Keyword defaults from pybind11's signature line (the first of the docstring)."""
    sig = fn.__doc__.splitlines()[0]
    return dict(re.findall(r"(\w+): \w+ = ('[^']*'|[-+0-9.e]+)", sig))


@pytest.mark.parametrize("fn", ["trace", "composite_layers", "pipeline", "rasterize", "box_blur", "combine"])
def test_keyword_defaults_are_the_schemas(fn):
    aliases = {"size": "blur_size", "separation": "blur_separation", "mode": "combine"}
    found = _signature_defaults(getattr(glint_core, fn))
    checked = 0
    for keyword, text in found.items():
        name = aliases.get(keyword, keyword) if fn in ("box_blur", "combine") else keyword
        if name not in OPTIONS:
            continue
        opt = OPTIONS[name]
        value = text.strip("'") if opt["type"] == "name" else float(text)
        assert _same(value, opt["default"], opt["type"]), (fn, keyword, value, opt["default"])
        checked += 1
    assert checked > 0


@pytest.mark.parametrize("fn", ["trace", "pipeline"])
def test_docstrings_carry_the_option_lines(fn):
    doc = getattr(glint_core, fn).__doc__
    for name in ("max_distance", "steps", "march"):
        assert f"  {name} (" in doc and OPTIONS[name]["doc"] in doc, name


def test_the_panel_and_the_core_take_the_same_values():
    sys.path.insert(0, str(REPO / "tests" / "addon"))
    from glint_addon_helpers import load_logic
    settings, materials = load_logic("settings"), load_logic("materials")
    for name, (default, lo, hi, soft_lo, soft_hi, _) in settings.PARAMETERS.items():
        opt = OPTIONS[name]
        assert _same(default, opt["default"], opt["type"]) and lo == opt["min"] and hi == opt["max"], name
        assert lo <= soft_lo <= soft_hi <= hi, name
    assert settings.DEFAULT_PRESET.lower() == CONSTANTS["DEFAULT_PRESET"] and settings.DEFAULT_PRESET.lower() in glint_core.presets()
    assert settings.DEFAULT_MARCH.lower() == OPTIONS["march"]["default"] in glint_core.marches()
    assert materials.MAX_SHININESS == glint_core.MAX_SHININESS
    assert materials.MAX_HARDNESS == 511.0  # Blender Internal's largest hardness, from the book


def test_glint_exr_help_lists_every_option_with_its_default():
    exe = BUILD / "bin" / "glint-exr"
    if not exe.exists():
        pytest.skip(f"no {exe}")
    text = subprocess.run([str(exe), "--help"], capture_output=True, text=True, check=True).stdout
    flat = " ".join(text.split())
    for name, opt in OPTIONS.items():
        if name == "memory_limit_mb":
            continue  # no flag
        flag = "--" + name.replace("_", "-")
        assert flag in text, flag
        default = opt["default"] if opt["type"] == "name" else None
        if default is not None:
            assert f"[{default}]" in flat, flag
    assert "[15.0]" in flat and "[10]" in flat and "[0.3]" in flat


def test_the_shaders_read_the_schemas_constants():
    glsl = BUILD / "native" / "generated" / "schema.glsl"
    if not glsl.exists():
        pytest.skip(f"no {glsl} (a build without GL?)")
    found = dict(re.findall(r"const (?:float|int) (\w+) = ([^;]+);", glsl.read_text()))
    numbers = {k: v for k, v in CONSTANTS.items() if not isinstance(v, str)}
    assert set(found) == set(numbers)
    for name, value in numbers.items():
        assert np.float32(float(found[name])) == np.float32(value), name
    # No shader defines one of them again.
    for path in (REPO / "shaders").rglob("*"):
        if path.suffix in (".glsl", ".frag", ".vert", ".comp"):
            for name in numbers:
                assert not re.search(rf"const \w+ {name}\b", path.read_text()), (path, name)

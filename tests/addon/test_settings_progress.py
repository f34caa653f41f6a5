"""Presets, parameter limits and the progress/cancel helper."""
import pytest

from glint_addon_helpers import load_logic

s = load_logic("settings")
pr = load_logic("progress")


# Made-up tables in the shape glint_core returns them, for the functions'
# logic alone; the real tables are checked against the core further down.
PRESETS = {
    "quick": {"max_distance": 15.0, "resolution": 0.3, "steps": 5, "thickness": 0.5, "march": "walk",
              "antialias": 0},
    "careful": {"max_distance": 15.0, "resolution": 0.3, "steps": 10, "thickness": 0.5, "march": "walk",
                "antialias": 4},
}
DESCRIPTIONS = {"quick": "short walk", "careful": "the knee"}
DETAILS = {
    "points": {"description": "two-pass", "options": {"steps": "bisection iterations"}, "needs_mesh": False,
               "uses_back_position": False, "gl": True},
    "walk": {"description": "pyramid walk", "options": {"steps": "cells per level"}, "needs_mesh": False,
             "uses_back_position": True, "gl": False},
}


def test_parameter_defaults_are_the_seeds():
    """The seed chapter's maxDistance 15, resolution 0.3, steps 10, thickness 0.5."""
    defaults = {key: s.PARAMETERS[key][0] for key in ("max_distance", "resolution", "steps", "thickness")}
    assert defaults == {"max_distance": 15.0, "resolution": 0.3, "steps": 10, "thickness": 0.5}


def test_enum_items_come_from_the_tables():
    marches = s.march_items(DETAILS)
    assert [i[0] for i in marches] == ["POINTS", "WALK"] and [i[3] for i in marches] == [0, 1]
    assert "cells per level" in marches[1][2] and "Runs on the CPU" in marches[1][2]
    assert "Runs on the CPU" not in marches[0][2]
    presets = s.preset_items(PRESETS, DESCRIPTIONS)
    assert [i[0] for i in presets] == ["QUICK", "CAREFUL", "CUSTOM"]
    assert "the knee" in presets[1][2] and "steps 10" in presets[1][2]
    # Without the core, the stored choice is still listed (and Custom).
    assert [i[0] for i in s.march_items({}, current="HIZ")] == ["HIZ"]
    assert [i[0] for i in s.preset_items({}, {}, current="HIGH")] == ["HIGH", "CUSTOM"]


def test_the_menus_list_the_cores_tables(core):
    details, presets = core.march_details(), core.presets()
    marches = s.march_items(details)
    assert [i[0] for i in marches] == [name.upper() for name in details]
    for item, d in zip(marches, details.values()):
        assert all(meaning in item[2] for meaning in d["options"].values())
        assert ("Runs on the CPU" in item[2]) == (not d["gl"])
    items = s.preset_items(presets, core.preset_descriptions())
    assert [i[0] for i in items] == [name.upper() for name in presets] + [s.CUSTOM]
    assert s.DEFAULT_PRESET in [i[0] for i in items]
    for name, kw in presets.items():
        v = s.preset_values(presets, name.upper())
        assert v["march"] == kw["march"].upper() and v["steps"] == kw["steps"]
        assert v["resolution"] == pytest.approx(kw["resolution"], abs=1e-6)
        assert s.matching_preset(v, presets) == name.upper()


def test_presets_set_quality_only():
    v = s.preset_values(PRESETS, "CAREFUL")
    assert v == {"march": "WALK", "resolution": 0.3, "steps": 10, "antialias": 4}
    with pytest.raises(ValueError):
        s.preset_values(PRESETS, "ULTRA")


def test_matching_preset():
    careful = {"resolution": 0.3, "steps": 10, "march": "WALK", "antialias": 4}
    assert s.matching_preset(careful, PRESETS) == "CAREFUL"
    assert s.matching_preset({"resolution": 0.3000001, "steps": 5, "march": "WALK", "antialias": 0},
                             PRESETS) == "QUICK"
    assert s.matching_preset(dict(careful, steps=11), PRESETS) == "CUSTOM"
    assert s.matching_preset(dict(careful, march="POINTS"), PRESETS) == "CUSTOM"
    assert s.matching_preset(dict(careful, antialias=0), PRESETS) == "CUSTOM"


def test_a_named_preset_follows_the_core():
    raw = {"max_distance": 7, "resolution": 1.0, "steps": 64, "thickness": 0.2, "march": "POINTS"}
    kw = s.trace_kwargs(dict(raw, preset="CAREFUL"), PRESETS)
    assert kw == {"max_distance": 7.0, "resolution": 0.3, "steps": 10, "thickness": 0.2, "march": "walk",
                  "antialias": 4}
    assert s.trace_kwargs(dict(raw, preset="CUSTOM"), PRESETS)["march"] == "points"


def test_trace_kwargs():
    kw = s.trace_kwargs({"max_distance": 15, "resolution": 0.3, "steps": 10, "thickness": 0.5, "march": "SEED"})
    assert kw == {"max_distance": 15.0, "resolution": 0.3, "steps": 10, "thickness": 0.5, "march": "seed",
                  "antialias": 0}
    with pytest.raises(ValueError, match="antialias"):
        s.trace_kwargs({"max_distance": 15, "resolution": 0.3, "steps": 10, "thickness": 0.5, "march": "SEED",
                        "antialias": 5})
    with pytest.raises(ValueError, match="resolution"):
        s.trace_kwargs({"max_distance": 15, "resolution": 2.0, "steps": 10, "thickness": 0.5, "march": "SEED"})
    assert s.look_kwargs({}) == {"blocked": "occluder"}
    assert s.look_kwargs({"fill_hidden": False}) == {"blocked": "miss"}
    assert s.shows_hidden_sides({}) and not s.shows_hidden_sides({"fill_hidden": False, "hidden_sides": True})
    assert not s.shows_hidden_sides({"hidden_sides": False})
    assert s.look_kwargs({"hidden_sides": False}) == {"blocked": "occluder"}  # the object in front, still
    assert s.backend_name("AUTO") == "auto" and s.backend_name("GL") == "gl" and s.backend_name("CPU") == "cpu"
    with pytest.raises(ValueError):
        s.backend_name("VULKAN")


class FakeClock:
    def __init__(self):
        self.t = 0.0

    def __call__(self):
        return self.t


def test_progress_reports_at_most_every_interval_and_at_the_end():
    clock = FakeClock()
    seen = []
    p = pr.Progress(10, report=lambda f, msg: seen.append(round(f, 2)), interval=1.0, clock=clock)
    for i in range(10):
        clock.t += 0.25  # binary fractions: the comparisons are exact
        p.step()
    assert seen == [0.4, 0.8, 1.0]


def test_quick_work_reports_nothing():
    clock = FakeClock()
    seen = []
    p = pr.Progress(3, report=lambda f, msg: seen.append(f), interval=1.0, clock=clock)
    for _ in range(3):
        clock.t += 0.125
        p.step()
    assert seen == []


def test_progress_cancels():
    flag = {"stop": False}
    p = pr.Progress(5, should_stop=lambda: flag["stop"], label="export")
    p.step()
    flag["stop"] = True
    with pytest.raises(pr.Cancelled, match="export cancelled at 2/5"):
        p.step()


def test_timings_accumulate():
    clock = FakeClock()
    t = pr.Timings(clock=clock)
    with t.measure("export"):
        clock.t += 0.25
    with t.measure("export"):
        clock.t += 0.25
    with t.measure("trace"):
        clock.t += 1.0
    assert t.ms == {"export": 500.0, "trace": 1000.0}
    assert t.total() == 1500.0 and "export 500.0 ms" in t.summary()


def test_auto_backend_rule():
    s = load_logic("settings")
    # No GPU: GL would be llvmpipe on the same cores, slower at every size measured.
    assert s.auto_backend(3840 * 2160, 400_000, gpu=False) == "cpu"
    # A GPU: the CPU up to 960x540 and 100k triangles (both bounds inclusive), GL beyond.
    assert s.auto_backend(960 * 540, 100_000, gpu=True) == "cpu"
    assert s.auto_backend(320 * 240, 14, gpu=True) == "cpu"
    assert s.auto_backend(960 * 540 + 1, 10, gpu=True) == "auto"
    assert s.auto_backend(320 * 240, 100_001, gpu=True) == "auto"
    with pytest.raises(ValueError, match="pixels"):
        s.auto_backend(-1, 0, gpu=True)


def test_gpu_device_lookup(tmp_path):
    s = load_logic("settings")
    (tmp_path / "renderD128").write_text("")
    assert s.has_gpu_device((str(tmp_path / "renderD*"),), platform="linux") is True
    assert s.has_gpu_device((str(tmp_path / "card*"),), platform="linux") is False
    assert s.has_gpu_device((), platform="darwin") is True


class _GlFailure(RuntimeError):
    pass


def _calls(fail_on):
    seen = []

    def call(backend):
        seen.append(backend)
        if backend in fail_on:
            raise fail_on[backend]
        return f"done on {backend}"
    return call, seen


def test_auto_falls_back_to_the_cpu_when_gl_fails_mid_frame():
    call, seen = _calls({"gl": _GlFailure("glint GL: GL_CONTEXT_LOST in trace")})
    lines = []
    assert s.with_cpu_fallback(call, "gl", "auto", lines.append) == ("done on cpu", "cpu")
    assert seen == ["gl", "cpu"]
    assert len(lines) == 1 and "GL_CONTEXT_LOST" in lines[0] and "CPU" in lines[0]


@pytest.mark.parametrize("backend, requested, error", [
    ("gl", "gl", _GlFailure("lost")),        # pinned to GL: the user asked for it
    ("cpu", "auto", _GlFailure("core bug")),  # the CPU itself failed: nothing to fall back to
    ("gl", "auto", ValueError("position: bad shape")),  # bad input is bad on every backend
    ("gl", "auto", MemoryError("over the limit")),      # a refusal for memory has its own retry
])
def test_no_fallback_where_the_cpu_would_not_help(backend, requested, error):
    call, seen = _calls({backend: error})
    lines = []
    with pytest.raises(type(error)):
        s.with_cpu_fallback(call, backend, requested, lines.append)
    assert seen == [backend] and lines == []


def test_no_fallback_when_gl_works():
    call, seen = _calls({})
    assert s.with_cpu_fallback(call, "gl", "auto", print) == ("done on gl", "gl")
    assert seen == ["gl"]

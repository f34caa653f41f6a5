"""Presets, parameter limits and the progress/cancel helper."""
import pytest

from glint_addon_helpers import load_logic

s = load_logic("settings")
pr = load_logic("progress")


def test_medium_preset_is_the_seeds_defaults():
    v = s.preset_values("MEDIUM")
    assert v["resolution"] == 0.3 and v["steps"] == 10 and v["blur_size"] == 8 and v["march"] == "SEED"
    for key in ("max_distance", "resolution", "steps", "thickness", "blur_size"):
        assert key in s.PARAMETERS
    assert s.PARAMETERS["max_distance"][0] == 15.0 and s.PARAMETERS["thickness"][0] == 0.5


def test_presets_leave_scene_scale_parameters_alone():
    for name in s.PRESETS:
        assert "max_distance" not in s.PRESETS[name] and "thickness" not in s.PRESETS[name]


def test_matching_preset():
    assert s.matching_preset({"resolution": 0.6, "steps": 20, "blur_size": 8, "march": "SEED"}) == "HIGH"
    assert s.matching_preset({"resolution": 0.6000001, "steps": 20, "blur_size": 8, "march": "SEED"}) == "HIGH"
    assert s.matching_preset({"resolution": 0.5, "steps": 20, "blur_size": 8, "march": "SEED"}) == "CUSTOM"
    assert s.matching_preset({"resolution": 0.3, "steps": 10, "blur_size": 8, "march": "LINEAR"}) == "CUSTOM"
    with pytest.raises(ValueError):
        s.preset_values("ULTRA")


def test_trace_kwargs():
    kw = s.trace_kwargs({"max_distance": 15, "resolution": 0.3, "steps": 10, "thickness": 0.5, "march": "SEED"})
    assert kw == {"max_distance": 15.0, "resolution": 0.3, "steps": 10, "thickness": 0.5, "march": "seed"}
    with pytest.raises(ValueError, match="resolution"):
        s.trace_kwargs({"max_distance": 15, "resolution": 2.0, "steps": 10, "thickness": 0.5, "march": "SEED"})
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

"""docs/conventions.md, "Bad input": a ValueError that names the argument, never a crash,
hang or silent wrong image; non-finite values INSIDE the buffers are data."""
import numpy as np
import pytest

import analytic as A
import glint_core
from glint_tables import SCREEN_MARCHES

H, W = 12, 16


def good():
    rng = np.random.default_rng(3)
    pos = np.zeros((H, W, 4), np.float32)
    pos[..., 0] = rng.uniform(-1, 1, (H, W))
    pos[..., 1] = rng.uniform(-1, 1, (H, W))
    pos[..., 2] = -rng.uniform(2, 6, (H, W))
    pos[..., 3] = 1.0
    nrm = np.zeros((H, W, 3), np.float32)
    nrm[..., 1] = 1.0
    spec = np.ones((H, W, 4), np.float32)
    spec[..., 3] = 0.5
    color = np.full((H, W, 4), 0.5, np.float32)
    proj = A.projection_matrix("persp", W, H)
    return dict(position=pos, normal=nrm, specular=spec, color=color, projection=proj)


def call_trace(**over):
    a = good()
    del a["specular"], a["color"]
    kw = {k: over.pop(k) for k in list(over) if k not in a}
    a.update(over)
    return glint_core.trace(a["position"], a["normal"], a["projection"], **kw)


def call_pipeline(**over):
    a = good()
    kw = {k: over.pop(k) for k in list(over) if k not in a}
    a.update(over)
    return glint_core.pipeline(a["position"], a["normal"], a["specular"], a["color"],
                               a["projection"], **kw)


def expect_error(fn, name, **over):
    with pytest.raises(ValueError) as info:
        fn(**over)
    msg = str(info.value)
    assert name in msg, f"message does not name {name!r}: {msg!r}"
    assert "expected" in msg, f"message does not say what was expected: {msg!r}"
    return msg


POS = good()["position"]
NRM = good()["normal"]

BUFFER_CASES = {
    # argument: {case: bad value}
    "position": {
        "ndim_2": POS[..., 0],
        "ndim_4": POS[None],
        "channels_3": POS[..., :3].copy(),
        "channels_5": np.concatenate([POS, POS[..., :1]], axis=2),
        "float64": POS.astype(np.float64),
        "float16": POS.astype(np.float16),
        "int32": POS.astype(np.int32),
        "empty": POS[:0],
        "list": POS.tolist(),
        "none": None,
        "scalar": 1.0,
    },
    "normal": {
        "ndim_2": NRM[..., 0],
        "channels_2": NRM[..., :2].copy(),
        "channels_5": np.concatenate([NRM, NRM[..., :2]], axis=2),
        "float64": NRM.astype(np.float64),
        "smaller": NRM[:-1],
        "wider": np.concatenate([NRM, NRM[:, :1]], axis=1),
        "transposed_size": np.ascontiguousarray(NRM.transpose(1, 0, 2)),
        "list": NRM.tolist(),
    },
}

PROJ = good()["projection"]
PROJECTION_CASES = {
    "shape_3x3": PROJ[:3, :3].copy(),
    "shape_4x4x1": PROJ[..., None],
    "shape_16": PROJ.ravel(),
    "shape_4x3": PROJ[:, :3].copy(),
    "nan": np.where(np.eye(4, dtype=bool), np.nan, PROJ),
    "inf": PROJ + np.array([[np.inf, 0, 0, 0]] + [[0, 0, 0, 0]] * 3),
    "singular_zero": np.zeros((4, 4)),
    "singular_rank3": np.array([[1.0, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 1, 0]]),
    "int": np.eye(4, dtype=np.int64),
    "complex": PROJ.astype(np.complex128),
    "list": PROJ.tolist(),
}

PARAM_CASES = {
    "max_distance": [-1.0, np.nan, np.inf, -np.inf, 1e13],
    "resolution": [1.5, -0.1, np.nan],
    "steps": [-1, 10 ** 7],
    "thickness": [np.nan, -0.5, np.inf],
    "march": ["foo", "", "SEED"],
    "backend": ["foo", ""],
}

PIPELINE_ONLY = {
    "blur_size": [-1, 100000],
    "blur_separation": [0.0, 0.5, np.nan],
    "combine": ["foo", ""],
}


@pytest.mark.parametrize("arg, case", [(a, c) for a in BUFFER_CASES for c in BUFFER_CASES[a]])
def test_bad_buffer_trace(arg, case):
    expect_error(call_trace, arg, **{arg: BUFFER_CASES[arg][case]})


@pytest.mark.parametrize("arg, case", [(a, c) for a in BUFFER_CASES for c in BUFFER_CASES[a]])
def test_bad_buffer_pipeline(arg, case):
    expect_error(call_pipeline, arg, **{arg: BUFFER_CASES[arg][case]})


@pytest.mark.parametrize("arg", ["specular", "color"])
@pytest.mark.parametrize("case", ["ndim_2", "channels_2", "float64", "smaller", "list"])
def test_bad_pipeline_only_buffers(arg, case):
    base = good()[arg]
    bad = {"ndim_2": base[..., 0], "channels_2": base[..., :2].copy(),
           "float64": base.astype(np.float64), "smaller": base[:, :-1],
           "list": base.tolist()}[case]
    expect_error(call_pipeline, arg, **{arg: bad})


@pytest.mark.parametrize("case", list(PROJECTION_CASES))
@pytest.mark.parametrize("fn", [call_trace, call_pipeline], ids=["trace", "pipeline"])
def test_bad_projection(fn, case):
    expect_error(fn, "projection", projection=PROJECTION_CASES[case])


@pytest.mark.parametrize("arg, value", [(a, v) for a in PARAM_CASES for v in PARAM_CASES[a]])
@pytest.mark.parametrize("fn", [call_trace, call_pipeline], ids=["trace", "pipeline"])
def test_parameter_out_of_range(fn, arg, value):
    expect_error(fn, arg, **{arg: value})


@pytest.mark.parametrize("arg, value", [(a, v) for a in PIPELINE_ONLY for v in PIPELINE_ONLY[a]])
def test_pipeline_parameter_out_of_range(arg, value):
    expect_error(call_pipeline, arg, **{arg: value})


def test_stage_functions_check_their_arguments():
    a = good()
    img = a["color"]
    with pytest.raises(ValueError, match="size"):
        glint_core.box_blur(img, size=-1)
    with pytest.raises(ValueError, match="separation"):
        glint_core.box_blur(img, separation=0.5)
    with pytest.raises(ValueError, match="image"):
        glint_core.box_blur(img.astype(np.float64))
    with pytest.raises(ValueError, match="uv"):
        glint_core.reflection_color(img[..., :2].copy(), img)
    with pytest.raises(ValueError, match="color"):
        glint_core.reflection_color(img, img.tolist())
    with pytest.raises(ValueError, match="reflection_blur"):
        glint_core.reflection(img, img[:-1], img)
    with pytest.raises(ValueError, match="specular"):
        glint_core.reflection(img, img, img[:, :-1])
    with pytest.raises(ValueError, match="reflection"):
        glint_core.combine(img, img[:-1])
    with pytest.raises(ValueError, match="combine"):
        glint_core.combine(img, img, mode="foo")
    with pytest.raises(ValueError, match="backend"):
        glint_core.combine(img, img, backend="foo")


def test_accepted_variants_are_not_errors():
    """What docs/conventions.md allows must work: float32 or float64 projection, normals
    with 3 or 4 channels, non-contiguous views."""
    a = good()
    ref = call_trace()
    np.testing.assert_array_equal(call_trace(projection=a["projection"].astype(np.float32)),
                                  glint_core.trace(a["position"], a["normal"],
                                                   a["projection"].astype(np.float32)))
    n4 = np.concatenate([a["normal"], np.full((H, W, 1), 7.0, np.float32)], axis=2)
    np.testing.assert_array_equal(call_trace(normal=n4), ref)
    big = np.zeros((H, 2 * W, 4), np.float32)
    big[:, ::2] = a["position"]
    view = big[:, ::2]
    assert not view.flags.c_contiguous
    np.testing.assert_array_equal(call_trace(position=view), ref)


def _nothing_seen(pos, mask):
    out = pos.copy()
    out[mask] = 0.0  # w = 0: docs/conventions.md's "nothing seen"
    return out


@pytest.mark.parametrize("march", SCREEN_MARCHES)
@pytest.mark.parametrize("where", ["x", "y", "z", "w"])
@pytest.mark.parametrize("value", [np.nan, np.inf, -np.inf])
def test_non_finite_positions_are_nothing_seen(march, where, value):
    """A NaN or Inf anywhere in a position texel is not an error: that pixel
    reports (0, 0, 0, 0) and every other pixel's ray reads it as nothing seen,
    exactly as if its w were 0."""
    sc = A.mirror_floor_scene("persp")
    gb = A.render(sc, 48, 32)
    rng = np.random.default_rng(11)
    mask = np.zeros((32, 48), bool)
    mask.ravel()[rng.choice(48 * 32, 200, replace=False)] = True
    bad = gb["position"].copy()
    bad[mask, "xyzw".index(where)] = value
    got = glint_core.trace(bad, gb["normal"], gb["projection"], march=march, resolution=1.0)
    want = glint_core.trace(_nothing_seen(gb["position"], mask), gb["normal"], gb["projection"],
                            march=march, resolution=1.0)
    assert np.all(got[mask] == 0)
    np.testing.assert_array_equal(got, want)
    out = glint_core.pipeline(bad, gb["normal"], gb["specular"], gb["color"], gb["projection"],
                              march=march)
    for name in glint_core.LAYERS:
        assert np.isfinite(out[name]).all(), name


@pytest.mark.parametrize("value", [np.nan, np.inf, 0.0])
def test_bad_normals_only_silence_their_own_pixel(value):
    """A NaN / Inf / zero normal: that pixel reports (0, 0, 0, 0); its texel
    is still a seen surface for every other ray, so nothing else changes."""
    sc = A.mirror_floor_scene("persp")
    gb = A.render(sc, 48, 32)
    mask = np.zeros((32, 48), bool)
    mask[::3, ::4] = True
    nrm = gb["normal"].copy()
    nrm[mask, 0] = value
    if value == 0.0:
        nrm[mask] = 0.0
    got = glint_core.trace(gb["position"], nrm, gb["projection"])
    want = glint_core.trace(gb["position"], gb["normal"], gb["projection"])
    assert np.all(got[mask] == 0)
    np.testing.assert_array_equal(got[~mask], want[~mask])


@pytest.mark.parametrize("value", [-1, 1025])
def test_pipeline_threads_out_of_range(value):
    expect_error(call_pipeline, "threads", threads=value)


@pytest.mark.parametrize("value", [-1, 1025])
def test_trace_threads_out_of_range(value):
    # An earlier trace() passed threads on unchecked: -1 meant "all cores"
    # and a huge count started one thread per image row.
    expect_error(call_trace, "threads", threads=value)

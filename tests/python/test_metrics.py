"""glint_core.compare on hand-made buffers, where every figure is known."""
import numpy as np
import pytest

W, H = 40, 30


def uv_grid(vis_mask):
    """A buffer whose every pixel reports its own centre."""
    u = (np.arange(W) + 0.5) / W
    v = (np.arange(H) + 0.5) / H
    uv = np.zeros((H, W, 4), np.float32)
    uv[..., 0] = u[None, :]
    uv[..., 1] = v[:, None]
    uv[..., 2] = uv[..., 3] = vis_mask
    return uv


def test_a_perfect_buffer_scores_one(glint):
    exact = uv_grid(np.ones((H, W)))
    m = glint.compare(exact, exact)
    assert m["precision"] == 1.0 and m["recall"] == 1.0
    assert m["median_px"] == 0.0 and m["p95_px"] == 0.0 and m["false_reflections"] == 0
    assert m["reported"] == m["exact_visible"] == W * H


def test_a_two_pixel_shift_scores_zero_within_one_and_a_half(glint):
    exact = uv_grid(np.ones((H, W)))
    shifted = exact.copy()
    shifted[..., 0] += 2.0 / W
    m = glint.compare(shifted, exact)
    assert m["precision"] == 0.0 and m["recall"] == 0.0
    assert m["median_px"] == pytest.approx(2.0, abs=1e-4)
    assert m["p95_px"] == pytest.approx(2.0, abs=1e-4)
    # The same shift is right with a wider tolerance.
    assert glint.compare(shifted, exact, tolerance_px=2.01)["precision"] == 1.0


def test_false_and_missed_reflections_are_counted_apart(glint):
    truth = np.zeros((H, W))
    truth[:, : W // 2] = 1.0            # exact hits on the left half
    mine = np.zeros((H, W))
    mine[: H // 3, :] = 1.0             # reports on the bottom third, both halves
    m = glint.compare(uv_grid(mine), uv_grid(truth))
    right = (H // 3) * (W // 2)
    assert m["reported"] == (H // 3) * W
    assert m["exact_visible"] == H * (W // 2)
    assert m["false_reflections"] == (H // 3) * (W - W // 2)
    assert m["precision"] == pytest.approx(right / ((H // 3) * W))
    assert m["recall"] == pytest.approx(right / (H * (W // 2)))
    d = m["disagreement"]
    assert d[0, W - 1, 0] == 1.0 and d[0, W - 1, 1] == 0.0       # false: red
    assert d[0, 0, 1] == 1.0 and d[0, 0, 0] == 0.0               # right: green
    assert d[H - 1, 0, 2] == 1.0                                  # missed: blue
    assert d[H - 1, W - 1, 3] == 0.0                              # neither: clear


def test_a_faint_visibility_does_not_report(glint):
    exact = uv_grid(np.ones((H, W)))
    faint = uv_grid(np.full((H, W), 5e-4))
    m = glint.compare(faint, exact)
    assert m["reported"] == 0 and m["precision"] == 1.0 and m["recall"] == 0.0


def test_image_error_of_the_reflection_colour(glint):
    # Colour is a ramp in x: a one-pixel shift right changes every reflected
    # colour by one step of the ramp (clamped at the right edge).
    color = np.zeros((H, W, 4), np.float32)
    color[..., 0] = np.arange(W)[None, :] / W
    color[..., 3] = 1.0
    exact = uv_grid(np.ones((H, W)))
    shifted = exact.copy()
    shifted[..., 0] += 1.0 / W
    m = glint.compare(shifted, exact, color=color)
    expected = np.mean(np.minimum(np.arange(W) + 1, W - 1) / W - np.arange(W) / W) / 3.0
    assert m["image_mae"] == pytest.approx(expected, rel=1e-4)
    # With a specular buffer, only reflective pixels count.
    spec = np.zeros((H, W, 4), np.float32)
    spec[:, :10, :3] = 1.0
    m = glint.compare(shifted, exact, color=color, specular=spec)
    assert m["image_pixels"] == 10 * H
    assert m["image_mae"] == pytest.approx(1.0 / W / 3.0, rel=1e-4)
    assert glint.compare(shifted, exact)["image_mae"] is None


@pytest.mark.parametrize("kwargs,match", [
    ({"exact": np.zeros((H + 1, W, 4), np.float32)}, "exact"),
    ({"color": np.zeros((H, W + 1, 4), np.float32)}, "color"),
    ({"tolerance_px": -1.0}, "tolerance_px"),
    ({"tolerance_px": float("nan")}, "tolerance_px"),
])
def test_bad_arguments_are_named(glint, kwargs, match):
    args = {"uv": uv_grid(np.ones((H, W))), "exact": uv_grid(np.ones((H, W)))}
    args.update(kwargs)
    uv, exact = args.pop("uv"), args.pop("exact")
    with pytest.raises(ValueError, match=match):
        glint.compare(uv, exact, **args)


def test_nan_visibility_is_not_a_report(glint):
    exact = uv_grid(np.ones((H, W)))
    bad = exact.copy()
    bad[..., 2] = np.nan
    m = glint.compare(bad, exact)
    assert m["reported"] == 0 and np.isfinite(m["median_px"])

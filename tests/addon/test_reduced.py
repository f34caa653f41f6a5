"""Tracing at reduced resolution after a memory refusal: the sizes tried and the
stretch back to the frame, against numbers worked out by hand."""
import numpy as np
import pytest

from glint_addon_helpers import load_logic

r = load_logic("reduced")
MIB = 1024 * 1024


@pytest.mark.parametrize("w, h, f, expected", [
    (160, 90, 1, (160, 90)),
    (160, 90, 2, (80, 45)),
    (160, 90, 4, (40, 23)),    # 22.5 rounds up: the reduced pixels cover the frame
    (1920, 1080, 8, (240, 135)),
    (1, 8192, 8, (1, 1024)),   # a side never goes below one pixel
    (3, 3, 8, (1, 1)),
])
def test_reduced_size_divides_and_rounds_up(w, h, f, expected):
    assert r.reduced_size(w, h, f) == expected


@pytest.mark.parametrize("args", [(160, 90, 0), (160, 90, 1.5), (0, 90, 2)])
def test_reduced_size_refuses_bad_arguments(args):
    with pytest.raises(ValueError):
        r.reduced_size(*args)


@pytest.mark.parametrize("factor, needed, limit, expected", [
    (1, 0, 0, 2),                 # sizes unknown: halve
    (1, 3 * MIB, 1 * MIB, 2),     # sqrt(3) = 1.73: half the width fits a quarter of the memory
    (1, 5 * MIB, 1 * MIB, 4),     # sqrt(5) = 2.24 > 2: a quarter of the width
    (1, 64 * MIB, 1 * MIB, 8),    # sqrt(64) = 8: exactly the floor
    (1, 65 * MIB, 1 * MIB, None),  # not even 1/8 fits: no retry at all
    (2, 1.5 * MIB, 1 * MIB, 4),   # a refusal at 1/2 never asks for 1/2 again
    (4, 0, 0, 8),
    (8, 0, 0, None),              # the floor was refused: give up
    (2, 17 * MIB, 1 * MIB, None),  # sqrt(17) = 4.1 -> x8 -> 1/16, past the floor
])
def test_next_factor(factor, needed, limit, expected):
    assert r.next_factor(factor, needed, limit) == expected


def test_next_factor_respects_another_floor():
    assert r.next_factor(2, 0, 0, max_factor=2) is None
    assert r.next_factor(1, 0, 0, max_factor=2) == 2


def test_upsample_takes_the_pixel_under_each_centre():
    img = np.arange(6, dtype=np.float32).reshape(3, 2)  # 3 rows, 2 columns
    out = r.upsample_nearest(img, 5, 7)
    # Column of output x: floor((x + 0.5) * 2 / 5) -> centres 0.1 0.3 0.5 0.7 0.9 of the frame.
    cols = [0, 0, 1, 1, 1]
    # Row of output y: floor((y + 0.5) * 3 / 7) -> 0.21 0.64 1.07 1.5 1.93 2.36 2.79.
    rows = [0, 0, 1, 1, 1, 2, 2]
    expected = np.array([[img[y, x] for x in cols] for y in rows], np.float32)
    assert out.shape == (7, 5)
    assert np.array_equal(out, expected)


def test_upsample_by_two_repeats_each_pixel():
    img = np.array([[[0.1, 0.2, 1.0, 1.0], [0.0, 0.0, 0.0, 0.0]]], np.float32)  # 1x2 RGBA
    out = r.upsample_nearest(img, 4, 2)
    assert out.shape == (2, 4, 4)
    for y in range(2):
        assert np.array_equal(out[y, 0], img[0, 0]) and np.array_equal(out[y, 1], img[0, 0])
        assert np.array_equal(out[y, 2], img[0, 1]) and np.array_equal(out[y, 3], img[0, 1])


def test_upsample_keeps_only_uvs_the_trace_returned():
    # A hit (uv 0.7, 0.4, vis 1) beside a miss (0, 0, vis 0): bilinear weights would
    # give uvs on the segment between them (toward the corner) and partial visibility.
    rng = np.random.default_rng(3)
    uv = np.zeros((9, 13, 4), np.float32)
    hit = rng.random((9, 13)) > 0.5
    uv[hit] = rng.random((int(hit.sum()), 4)).astype(np.float32)
    uv[hit, 2] = 1.0
    out = r.upsample_nearest(uv, 50, 31)
    found = {tuple(p) for p in uv.reshape(-1, 4)}
    assert all(tuple(p) in found for p in out.reshape(-1, 4))
    assert set(np.unique(out[..., 2])) <= {0.0, 1.0}


def test_upsample_at_the_same_size_is_the_input():
    img = np.ones((4, 5, 4), np.float32)
    assert r.upsample_nearest(img, 5, 4) is img
    with pytest.raises(ValueError):
        r.upsample_nearest(img, 0, 4)


def test_the_report_says_the_size_and_why():
    text = r.describe(160, 90, 2, 3.0 * MIB, 1.5 * MIB)
    assert "80x45" in text and "1/2 of 160x90" in text
    assert "3.0 MiB" in text and "1.5 MiB" in text and "GLINT_MEMORY_LIMIT_MB" in text
    assert "40x23" in r.gave_up(160, 90, 4) and "1/4" in r.gave_up(160, 90, 4)
    assert "20x12" in r.gave_up(160, 90, 1)  # predicted: the floor, 1/8


def test_each_retry_is_logged_with_both_sizes():
    assert r.retrying(160, 90, 1, 2) == "over the memory limit at full size; trying 1/2: 80x45"
    assert r.retrying(160, 90, 4, 8) == "over the memory limit at 40x23 (1/4); trying 1/8: 20x12"

"""bench/motion_bench.py on a few small frames: the exact march scores zero against
itself, and hiz's outline confidence (a hit on an outline texel's inner half is taken
whole) keeps balanced closer to the exact reflection than halving every outline hit."""
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "bench"))
import motion_bench  # noqa: E402


def test_the_exact_march_scores_zero_and_balanced_stays_close():
    res = motion_bench.run((320, 180), 3, ["balanced"])
    assert res["exact"]["error"] == 0.0 and res["exact"]["flicker"] == 0.0
    assert res["exact"]["change"] > 0.0  # the camera moves
    bal = res["balanced"]
    print(f"balanced at 320x180: error {bal['error']:.4f}, change {bal['change'] / res['exact']['change']:.2f}x "
          f"exact's, flicker {bal['flicker']:.4f}")
    # 0.073 here (0.047 at 480x270 over 24 frames); halving every outline hit gave 0.120
    assert bal["error"] < 0.095
    assert 0.8 < bal["change"] / res["exact"]["change"] < 1.2


def test_outline_hits_on_the_inner_half_are_whole():
    """On the bench's frame, balanced's hits on outline texels: none below 0.5, and
    those at full confidence outnumber those at 0.5 (the old rule made them all 0.5)."""
    import glint_core
    w, h = 240, 135
    v, t, mat = motion_bench.scene()
    cam = motion_bench.camera(0)
    g, _ = motion_bench.render(v, t, mat, cam, w, h)
    uv = glint_core.trace(g["position"], g["normal"], motion_bench.projection(w, h), specular=g["specular"],
                          back_position=g["back_position"], **motion_bench.march_options("balanced:antialias=0"))
    vis = uv[..., 2]
    hx = np.clip((uv[..., 0] * w).astype(int), 0, w - 1)
    hy = np.clip((uv[..., 1] * h).astype(int), 0, h - 1)
    fade = motion_bench.edge_fade(uv)
    on = (vis > 0) & motion_bench.outline_texels(g["position"])[hy, hx] & (fade == 1)
    assert on.sum() > 20
    conf = vis[on]
    assert conf.min() >= 0.5 - 1e-6
    assert (conf > 1 - 1e-6).sum() > (np.abs(conf - 0.5) < 1e-6).sum()

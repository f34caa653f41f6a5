"""An independent reference of the compositor group's sampling and blur, written
from the formulas in logic/compositing.py's docstring, not from its node list:
test_compositing.py checks the group's wiring against it, and
tests/blender/test_blur.py checks Blender's own composite."""
import math

import numpy as np


def bilinear_clamp(img, u, v):
    h, w = img.shape[:2]
    x = u * w - 0.5
    y = v * h - 0.5
    x0 = np.floor(x)
    y0 = np.floor(y)
    ax = (x - x0)[..., None]
    ay = (y - y0)[..., None]
    xi0 = np.clip(x0, 0, w - 1).astype(int)
    xi1 = np.clip(x0 + 1, 0, w - 1).astype(int)
    yi0 = np.clip(y0, 0, h - 1).astype(int)
    yi1 = np.clip(y0 + 1, 0, h - 1).astype(int)
    bottom = img[yi0, xi0] * (1 - ax) + img[yi0, xi1] * ax
    top = img[yi1, xi0] * (1 - ax) + img[yi1, xi1] * ax
    return bottom * (1 - ay) + top * ay


def map_uv(image, uv_rgba):
    """Map UV modelled as a bilinear clamp-to-edge lookup premultiplied by the third channel."""
    vis = uv_rgba[..., 2:3]
    c = bilinear_clamp(image, uv_rgba[..., 0], uv_rgba[..., 1]) * vis
    return np.where(vis > 0, c, 0).astype(np.float32)


def gauss_clamp(img, sigma):
    """A separable Gaussian, clamp to edge, cut at 4 sigma (float64)."""
    r = max(1, int(math.ceil(4 * sigma)))
    k = np.exp(-0.5 * (np.arange(-r, r + 1) / sigma) ** 2)
    k /= k.sum()
    h, w = img.shape[:2]
    tmp = sum(k[i] * img[np.clip(np.arange(h) + i - r, 0, h - 1)] for i in range(2 * r + 1))
    out = sum(k[i] * tmp[:, np.clip(np.arange(w) + i - r, 0, w - 1)] for i in range(2 * r + 1))
    return out.astype(np.float32)


def binomial_3x3(img):
    """The 3x3 kernel (1 2 1; 2 4 2; 1 2 1) / 16, clamp to edge (float64)."""
    h, w = img.shape[:2]
    img = np.asarray(img, np.float64)
    rows = img[np.clip(np.arange(h) - 1, 0, h - 1)] + 2 * img + img[np.clip(np.arange(h) + 1, 0, h - 1)]
    cols = rows[:, np.clip(np.arange(w) - 1, 0, w - 1)] + 2 * rows + rows[:, np.clip(np.arange(w) + 1, 0, w - 1)]
    return (cols / 16).astype(np.float32)


def bilinear_zero(img, x, y):
    """img read bilinearly at texel coordinates (x, y), texel centres on whole
    numbers, 0 past the canvas (Blender 3.4's Scale to the render size)."""
    h, w = img.shape[:2]
    pad = np.zeros((h + 2, w + 2) + img.shape[2:])
    pad[1:-1, 1:-1] = img
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    ax, ay = (x - x0)[..., None], (y - y0)[..., None]

    def at(yy, xx):
        return pad[np.clip(yy + 1, 0, h + 1), np.clip(xx + 1, 0, w + 1)]

    return ((at(y0, x0) * (1 - ax) + at(y0, x0 + 1) * ax) * (1 - ay)
            + (at(y0 + 1, x0) * (1 - ax) + at(y0 + 1, x0 + 1) * ax) * ay)


def blurred_at_lod(D, lod, k=4, past_edge="zero"):
    """D at each pixel's lod between blur levels: lods 4, 6, 8 Gaussians of
    sigma 2^lod / 4.71 (half their energy within a disc half the footprint's
    size), and at lod 2 the 3x3 binomial filter (sigma sqrt(1/2), where the
    rule would give 0.85). The first on D, the wider three on a coarse canvas
    of (W // k + 1) x (H // k + 1) texels, texel (i, j) D read at the frame's
    pixel (i W / cw, j H / ch), blurred at sigma / k, mixed there by the mean
    lod of the pixels (lod > 0) whose read lies nearest it, and read back
    bilinearly at texel coordinates (x cw / W, y ch / H): with 0 past the
    last texel (``past_edge="zero"``, the Scale of 3.x-4.1) or the last texel
    repeated ("clamp", the fine image's Map UV)."""
    h, w = D.shape[:2]
    lods = [2.0, 4.0, 6.0, 8.0]
    sig = [2.0 ** l / (4 * math.sqrt(2 * math.log(2))) for l in lods]
    cw, ch = w // k + 1, h // k + 1
    cu = ((np.arange(cw) * (w / cw) + 0.5) / w)[None, :] * np.ones((ch, 1))
    cv = ((np.arange(ch) * (h / ch) + 0.5) / h)[:, None] * np.ones((1, cw))
    Dc = bilinear_clamp(D, cu, cv)
    tx = np.minimum(np.floor(np.arange(w) * cw / w + 0.5), cw - 1).astype(int)
    ty = np.minimum(np.floor(np.arange(h) * ch / h + 0.5), ch - 1).astype(int)
    total = np.zeros((ch, cw))
    n = np.zeros((ch, cw))
    yy, xx = np.meshgrid(ty, tx, indexing="ij")
    np.add.at(total, (yy, xx), np.where(lod > 0, lod, 0))
    np.add.at(n, (yy, xx), lod > 0)
    lod_c = np.where(n > 0, total / np.maximum(n, 1), 0)
    Q = gauss_clamp(Dc, sig[1] / k)
    for j in (2, 3):
        f = np.clip((lod_c - lods[j - 1]) / (lods[j] - lods[j - 1]), 0, 1)[..., None]
        Q = (1 - f) * Q + f * gauss_clamp(Dc, sig[j] / k)
    fx = (np.arange(w) * (cw / w))[None, :] * np.ones((h, 1))
    fy = (np.arange(h) * (ch / h))[:, None] * np.ones((1, w))
    if past_edge == "zero":
        back = bilinear_zero(Q, fx, fy)
    else:
        back = bilinear_clamp(Q, (fx + 0.5) / cw, (fy + 0.5) / ch)
    levels = [(0.0, D), (lods[0], binomial_3x3(D)), (lods[1], back)]
    R = np.array(D)
    for (l0, b0), (l1, b1) in zip(levels, levels[1:]):
        inside = (lod > l0) & (lod <= l1)
        f = ((lod - l0) / (l1 - l0))[..., None]
        R = np.where(inside[..., None], (1 - f) * b0 + f * b1, R)
    return np.where((lod > levels[-1][0])[..., None], levels[-1][1], R)

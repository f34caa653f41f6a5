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


def blurred_at_lod(D, lod, k=4):
    """D at each pixel's lod between blur levels: lods 4, 6, 8 Gaussians of
    sigma 2^lod / 4.71 (half their energy within a disc half the footprint's
    size), and at lod 2 the 3x3 binomial filter (sigma sqrt(1/2), where the
    rule would give 0.85). The first on D, the wider three on D read at the
    centres of k x k blocks, blurred at sigma / k, mixed there by each block's
    mean lod (over its pixels with lod > 0) and read back bilinearly at the
    pixels."""
    h, w = D.shape[:2]
    lods = [2.0, 4.0, 6.0, 8.0]
    sig = [2.0 ** l / (4 * math.sqrt(2 * math.log(2))) for l in lods]
    ch, cw = -(-h // k), -(-w // k)
    cu = ((np.arange(cw) * k + k / 2) / w)[None, :] * np.ones((ch, 1))
    cv = ((np.arange(ch) * k + k / 2) / h)[:, None] * np.ones((1, cw))
    Dc = bilinear_clamp(D, cu, cv)
    grid = np.zeros((ch * k, cw * k))
    grid[:h, :w] = lod
    blocks = grid.reshape(ch, k, cw, k)
    n = (blocks > 0).sum(axis=(1, 3))
    lod_c = np.where(n > 0, np.where(blocks > 0, blocks, 0).sum(axis=(1, 3)) / np.maximum(n, 1), 0)
    Q = gauss_clamp(Dc, sig[1] / k)
    for j in (2, 3):
        f = np.clip((lod_c - lods[j - 1]) / (lods[j] - lods[j - 1]), 0, 1)[..., None]
        Q = (1 - f) * Q + f * gauss_clamp(Dc, sig[j] / k)
    fu = (((np.arange(w) + 0.5) / k) / cw)[None, :] * np.ones((h, 1))
    fv = (((np.arange(h) + 0.5) / k) / ch)[:, None] * np.ones((1, w))
    levels = [(0.0, D), (lods[0], binomial_3x3(D)), (lods[1], bilinear_clamp(Q, fu, fv))]
    R = np.array(D)
    for (l0, b0), (l1, b1) in zip(levels, levels[1:]):
        inside = (lod > l0) & (lod <= l1)
        f = ((lod - l0) / (l1 - l0))[..., None]
        R = np.where(inside[..., None], (1 - f) * b0 + f * b1, R)
    return np.where((lod > levels[-1][0])[..., None], levels[-1][1], R)

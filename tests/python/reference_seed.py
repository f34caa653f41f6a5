"""A plain, slow float64 reference of the two reflected-UV marches.

Written from the sources, not from the core: ``trace_seed`` follows the seed
chapter (seeds/ssr-chapter.md, "Reflected UV Coordinates") with the four fixes of
docs/conventions.md; ``trace_linear`` follows the book's older march (seeds/
3d-game-shaders-for-beginners.md, "Reflected UVs"). One pixel at a time, Python
floats (IEEE double), no shortcuts: the first pass really visits every
k = 1 .. int(delta). Keep images small (tens of pixels a side).

Blender camera space instead of Panda3D's: the view distance of a point is -z
where the book uses y.

Each returns float64 [H, W, 4] = (u, v, visibility, visibility).

Rounding alternatives
---------------------
float32 (the core) and float64 (this file) can take different discrete
decisions where a value sits on its threshold: a probe on the edge between two
texels, a depth equal to 0 or to the thickness, delta next to an integer. This
is not rare: the seed's bisection converges onto texel edges by design (with
resolution 1 its very first probe lies exactly on one). Every such decision
closer to its threshold than float32 resolves (``EDGE_PX`` pixels,
``DEPTH_REL`` relative view distance) is recorded; with ``alternatives=True``
each pixel is re-run once per recorded decision with that decision taken the
other way, and the functions also return those outcomes: a float64
[H, W, MAX_ALTERNATIVES, 4] array (NaN where unused) and the count of ambiguous
decisions per pixel.
"""
from __future__ import annotations

import math

import numpy as np

EDGE_PX = 2e-4  # float32 frag coordinates of a 100 px image are good to ~1e-5 px
DEPTH_REL = 1e-5  # relative error of a float32 view distance through the projection
MAX_ALTERNATIVES = 6


def _f32(x: float) -> float:
    """A parameter as the core receives it (pybind11 float = float32)."""
    return float(np.float32(x))


def _finite(*vals) -> bool:
    return all(math.isfinite(v) for v in vals)


class _Decisions:
    """Discrete decisions of one pixel's march; near-threshold ones are counted
    and the one numbered ``flip`` (if any) is taken the other way."""

    def __init__(self, flip=None):
        self.flip = flip
        self.ambiguous = 0

    def _other_way(self, near: bool) -> bool:
        if not near:
            return False
        i = self.ambiguous
        self.ambiguous += 1
        return i == self.flip

    def less(self, a: float, b: float, eps: float) -> bool:
        """a < b."""
        r = a < b
        return (not r) if self._other_way(abs(a - b) < eps) else r

    def floor(self, f: float, eps: float = EDGE_PX) -> int:
        """floor(f); next to an integer the neighbouring integer is the alternative."""
        fl = math.floor(f)
        r = round(f)
        if self._other_way(abs(f - r) < eps):
            return r - 1 if fl == r else r
        return fl


class _Buffers:
    """The G-buffer as nested Python lists, and the texel read of fix 3 (docs/conventions.md)."""

    def __init__(self, position, normal, projection):
        position = np.asarray(position)
        normal = np.asarray(normal)
        self.h, self.w = position.shape[:2]
        self.pos = position[..., :4].astype(np.float64).tolist()
        self.nrm = normal[..., :3].astype(np.float64).tolist()
        self.P = np.asarray(projection, dtype=np.float64).tolist()
        self.d = _Decisions()
        self.eye_point, self.eye_dir = _camera_eye(np.asarray(projection, dtype=np.float64))

    def seen(self, texel) -> bool:
        # w = 0 marks "nothing seen"; a non-finite texel is treated the same.
        return texel[3] > 0.0 and _finite(*texel)

    def fetch(self, u: float, v: float):
        """The texel under uv (nearest: floor(uv * size)), or None where the
        sample is outside the image or on an unseen texel."""
        if not _finite(u, v):
            return None
        x = self.d.floor(u * self.w)
        y = self.d.floor(v * self.h)
        if x < 0 or y < 0 or x >= self.w or y >= self.h:
            return None
        t = self.pos[y][x]
        return t if self.seen(t) else None

    def clip(self, p):
        P = self.P
        return [P[r][0] * p[0] + P[r][1] * p[1] + P[r][2] * p[2] + P[r][3] for r in range(4)]

    def origin(self, x: int, y: int):
        """(position, unit position, unit normal) of a pixel, or None (fix 4 of docs/conventions.md)."""
        p = self.pos[y][x]
        if not self.seen(p):
            return None
        n = self.nrm[y][x]
        if not _finite(*n):
            return None
        ln = math.sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2])
        if self.eye_dir is not None:  # parallel view rays (orthographic)
            if ln == 0.0 or not _finite(ln):
                return None
            return p[:3], list(self.eye_dir), [c / ln for c in n]
        i = [p[k] - self.eye_point[k] for k in range(3)]
        lp = math.sqrt(i[0] * i[0] + i[1] * i[1] + i[2] * i[2])
        if ln == 0.0 or lp == 0.0 or not _finite(ln, lp):
            return None
        return p[:3], [c / lp for c in i], [c / ln for c in n]


def _camera_eye(P):
    """The camera centre: the homogeneous point that rows 0, 1 and 3 of the
    projection send to zero (found here by SVD). Returns (point, None) for a
    camera at a point, (None, unit direction into the scene) for parallel rays.
    The seed reflects normalize(position), which is this rule for a camera at
    the origin."""
    _, _, vt = np.linalg.svd(P[[0, 1, 3], :])
    e = vt[-1]
    if abs(e[3]) > 1e-12 * np.linalg.norm(e):
        return (e[:3] / e[3]).tolist(), None
    d = e[:3] / np.linalg.norm(e[:3])
    if P[2, :3] @ d < 0:  # into the scene: normalized depth grows
        d = -d
    return None, d.tolist()


def _reflect_unit(i, n):
    d = i[0] * n[0] + i[1] * n[1] + i[2] * n[2]
    r = [i[k] - 2.0 * d * n[k] for k in range(3)]
    lr = math.sqrt(r[0] * r[0] + r[1] * r[1] + r[2] * r[2])
    if lr == 0.0 or not math.isfinite(lr):
        return None
    return [c / lr for c in r]


def _clamp01(v: float) -> float:
    return 0.0 if v < 0.0 else (1.0 if v > 1.0 else v)


def _in_unit(d: _Decisions, c: float) -> bool:
    """0 <= c <= 1 (the seed's frustum test on a uv coordinate)."""
    return not d.less(c, 0.0, 1e-6) and not d.less(1.0, c, 1e-6)


def _is_hit(d: _Decisions, depth: float, thickness: float, scene_vd: float) -> bool:
    """The chapter's hit test, depth > 0 && depth < thickness."""
    eps = DEPTH_REL * (1.0 + abs(scene_vd))
    return d.less(0.0, depth, eps) and d.less(depth, thickness, eps)


def _seed_pixel(b: _Buffers, x: int, y: int, max_distance, resolution, steps, thickness):
    d = b.d
    o = b.origin(x, y)
    if o is None:
        return (0.0, 0.0, 0.0, 0.0)
    from_, unit_from, normal = o
    pivot = _reflect_unit(unit_from, normal)
    if pivot is None:
        return (0.0, 0.0, 0.0, 0.0)

    # Fix 2 (docs/conventions.md): cut the ray where it would cross the near plane. The test
    # "clip z + clip w >= 0" is affine in the length along the ray.
    def near_margin(length):
        c = b.clip([from_[k] + pivot[k] * length for k in range(3)])
        return c[2] + c[3]

    start_clip = b.clip(from_)
    g0 = near_margin(0.0)
    if not (g0 >= 0.0 and start_clip[3] > 0.0):
        return (0.0, 0.0, 0.0, 0.0)  # the pixel itself is not in front of the camera
    length = max_distance
    g1 = near_margin(max_distance)
    if g1 < 0.0:
        length = max_distance * g0 / (g0 - g1)

    start_view = from_
    end_view = [from_[k] + pivot[k] * length for k in range(3)]
    end_clip = b.clip(end_view)
    if not end_clip[3] > 0.0:
        return (0.0, 0.0, 0.0, 0.0)
    W, H = float(b.w), float(b.h)
    start_frag = ((start_clip[0] / start_clip[3] * 0.5 + 0.5) * W,
                  (start_clip[1] / start_clip[3] * 0.5 + 0.5) * H)
    end_frag = ((end_clip[0] / end_clip[3] * 0.5 + 0.5) * W,
                (end_clip[1] / end_clip[3] * 0.5 + 0.5) * H)

    frag = start_frag
    uv = (frag[0] / W, frag[1] / H)
    delta_x = end_frag[0] - start_frag[0]
    delta_y = end_frag[1] - start_frag[1]
    # How well float32 knows the end: its coordinates carry a few rounding
    # steps of |from| + length (and a cut ray must be pulled back by one or two
    # to stay in front); divided by a small w (an end on the near plane) that
    # error is magnified in every frag quantity derived from the end.
    p3 = math.sqrt(sum(c * c for c in b.P[3][:3]))
    reach = math.sqrt(sum(c * c for c in from_)) + length
    end_rel = 1e-6 + 4.0 * 2.0 ** -23 * reach * p3 / end_clip[3]
    use_x = not d.less(abs(delta_x), abs(delta_y),
                       EDGE_PX + (abs(delta_x) + abs(delta_y)) * end_rel)
    delta = (abs(delta_x) if use_x else abs(delta_y)) * _clamp01(resolution)
    inc = (delta_x / max(delta, 0.001), delta_y / max(delta, 0.001))

    # The ray's view distance at screen fraction t: 1/w is what varies linearly
    # across the screen (perspective-correct interpolation). With w = view
    # distance this is the chapter's (start * end) / mix(end, start, t); with
    # an orthographic w = 1 it is a plain mix.
    vd0, vd1 = -start_view[2], -end_view[2]
    w0, w1 = start_clip[3], end_clip[3]

    def ray_vd(t):
        return ((1.0 - t) * vd0 / w0 + t * vd1 / w1) / ((1.0 - t) / w0 + t / w1)

    def fraction(f):
        # Fix 1 (docs/conventions.md): only the axis in use is divided by.
        return (f[0] - start_frag[0]) / delta_x if use_x else (f[1] - start_frag[1]) / delta_y

    search0 = search1 = 0.0
    hit0 = hit1 = 0
    depth = thickness
    position_to = None  # texel of the last probe (None: a miss on nothing)

    for k in range(1, d.floor(delta, EDGE_PX + delta * end_rel) + 1):
        frag = (start_frag[0] + k * inc[0], start_frag[1] + k * inc[1])
        uv = (frag[0] / W, frag[1] / H)
        position_to = b.fetch(uv[0], uv[1])
        search1 = fraction(frag)
        if position_to is not None:
            depth = ray_vd(search1) - (-position_to[2])
            if _is_hit(d, depth, thickness, position_to[2]):
                hit0 = 1
                break
        search0 = search1

    search1 = search0 + (search1 - search0) / 2.0

    for _ in range(steps * hit0):
        frag = (start_frag[0] * (1.0 - search1) + end_frag[0] * search1,
                start_frag[1] * (1.0 - search1) + end_frag[1] * search1)
        uv = (frag[0] / W, frag[1] / H)
        position_to = b.fetch(uv[0], uv[1])
        hit = False
        if position_to is not None:
            depth = ray_vd(search1) - (-position_to[2])
            hit = _is_hit(d, depth, thickness, position_to[2])
        if hit:
            hit1 = 1
            search1 = search0 + (search1 - search0) / 2.0
        else:
            temp = search1
            search1 = search1 + (search1 - search0) / 2.0
            search0 = temp

    visibility = 0.0
    if hit1 and position_to is not None:
        facing = -(unit_from[0] * pivot[0] + unit_from[1] * pivot[1] + unit_from[2] * pivot[2])
        dist = math.sqrt(sum((position_to[k] - from_[k]) ** 2 for k in range(3)))
        visibility = (hit1 * position_to[3]
                      * (1.0 - max(facing, 0.0))
                      * (1.0 - _clamp01(depth / thickness))
                      * (1.0 - _clamp01(dist / max_distance))
                      * (1.0 if _in_unit(d, uv[0]) else 0.0)
                      * (1.0 if _in_unit(d, uv[1]) else 0.0))
        visibility = _clamp01(visibility)
    if not _finite(uv[0], uv[1]):
        return (0.0, 0.0, 0.0, 0.0)
    return (uv[0], uv[1], visibility, visibility)


def _linear_pixel(b: _Buffers, x: int, y: int, max_distance, steps, thickness):
    d = b.d
    o = b.origin(x, y)
    if o is None:
        return (0.0, 0.0, 0.0, 0.0)
    position, u_position, normal = o
    reflection = _reflect_unit(u_position, normal)
    if reflection is None:
        return (0.0, 0.0, 0.0, 0.0)
    step_size = max_distance / steps if steps > 0 else 0.0
    count = 1.0
    out = (0.0, 0.0, 0.0, 0.0)
    i = 0.0
    while i < steps:
        distance = count * step_size
        if d.less(max_distance, distance, DEPTH_REL * (1.0 + max_distance)):
            break
        sample = [position[k] + reflection[k] * distance for k in range(3)]
        c = b.clip(sample)
        if not c[3] > 0.0:
            break  # behind the eye: outside the frustum as much as past its sides
        ox = c[0] / c[3] * 0.5 + 0.5
        oy = c[1] / c[3] * 0.5 + 0.5
        oz = c[2] / c[3]
        if not (_in_unit(d, ox) and _in_unit(d, oy)
                and not d.less(oz, -1.0, 1e-6) and not d.less(1.0, oz, 1e-6)):
            break
        texel = b.fetch(ox, oy)
        sample_vd = -sample[2]
        hit = False
        if texel is not None:
            eps = DEPTH_REL * (1.0 + abs(sample_vd))
            scene_vd = -texel[2]
            hit = (not d.less(sample_vd, scene_vd, eps)
                   and not d.less(scene_vd + thickness, sample_vd, eps))
        if hit:
            vis = 1.0 - max(reflection[0] * -u_position[0] + reflection[1] * -u_position[1]
                            + reflection[2] * -u_position[2], 0.0)
            out = (ox, oy, vis, vis)
            # The book's step back, literally: the next distance is
            # count * new step size, not last miss + new step size.
            count -= 1.0
            max_distance = distance
            previous_distance = count * step_size
            steps_left = max(steps - i, 1.0)
            step_size = (max_distance - previous_distance) / steps_left
        else:
            count += 1.0
        i += 1.0
    return out


def _params(max_distance, resolution, steps, thickness):
    return _f32(max_distance), _f32(resolution), int(steps), _f32(thickness)


def _run(b: _Buffers, pixel, alternatives: bool):
    out = np.zeros((b.h, b.w, 4))
    alt = np.full((b.h, b.w, MAX_ALTERNATIVES, 4), np.nan) if alternatives else None
    n_amb = np.zeros((b.h, b.w), int)
    for y in range(b.h):
        for x in range(b.w):
            b.d = _Decisions()
            out[y, x] = pixel(x, y)
            n_amb[y, x] = b.d.ambiguous
            if alternatives:
                for i in range(min(n_amb[y, x], MAX_ALTERNATIVES)):
                    b.d = _Decisions(flip=i)
                    alt[y, x, i] = pixel(x, y)
    return (out, alt, n_amb) if alternatives else out


def trace_seed(position, normal, projection, *, max_distance=15.0, resolution=0.3, steps=10,
               thickness=0.5, alternatives=False):
    md, res, st, th = _params(max_distance, resolution, steps, thickness)
    b = _Buffers(position, normal, projection)
    return _run(b, lambda x, y: _seed_pixel(b, x, y, md, res, st, th), alternatives)


def trace_linear(position, normal, projection, *, max_distance=15.0, steps=10, thickness=0.5,
                 resolution=None, alternatives=False):
    """The book's march; ``resolution`` is accepted and ignored (it has none)."""
    md, _, st, th = _params(max_distance, 0.0, steps, thickness)
    b = _Buffers(position, normal, projection)
    return _run(b, lambda x, y: _linear_pixel(b, x, y, md, st, th), alternatives)


def trace(position, normal, projection, *, march="seed", **kw):
    if march == "seed":
        return trace_seed(position, normal, projection, **kw)
    if march == "linear":
        return trace_linear(position, normal, projection, **kw)
    raise ValueError(f"march: expected 'seed' or 'linear', got {march!r}")

"""Exact G-buffers of analytic scenes, and the exact mirror hit of every pixel.

Everything here is float64 numpy and independent of glint_core: the tests use it
as ground truth. Conventions are docs/conventions.md's:

* world space is Blender's (Z up); the camera's view space looks down -Z, +Y up;
* images are [row, col, channel] with row 0 at the BOTTOM; pixel (i, j) of a
  W x H image has its centre at uv ((i + 0.5) / W, (j + 0.5) / H);
* ``projection`` is an OpenGL matrix as Blender's ``calc_matrix_camera`` gives it
  (rows as printed: ``projection[3] == (0, 0, -1, 0)`` for a perspective camera),
  ``clip = P @ (x, y, z, 1)``, ``uv = clip.xy / clip.w * 0.5 + 0.5``.

Shapes: infinite planes, spheres and world-axis-aligned boxes, each with a
material (base colour, specular rgb, shininess alpha). A box makes a finite wall.
"""
from __future__ import annotations

import dataclasses
import math
from typing import Optional, Sequence

import numpy as np

_EPS_T = 1e-7  # self-intersection guard for rays starting on a surface


@dataclasses.dataclass
class Material:
    color: Sequence[float] = (0.5, 0.5, 0.5)
    specular: Sequence[float] = (0.0, 0.0, 0.0)
    alpha: float = 0.0  # the specular buffer's alpha: shininess mapped to [0, 1]


MIRROR = Material(color=(0.4, 0.4, 0.4), specular=(1.0, 1.0, 1.0), alpha=1.0)


@dataclasses.dataclass
class Plane:
    point: Sequence[float]
    normal: Sequence[float]
    material: Material = dataclasses.field(default_factory=Material)


@dataclasses.dataclass
class Sphere:
    center: Sequence[float]
    radius: float
    material: Material = dataclasses.field(default_factory=Material)


@dataclasses.dataclass
class Box:
    lo: Sequence[float]
    hi: Sequence[float]
    material: Material = dataclasses.field(default_factory=Material)


@dataclasses.dataclass
class Camera:
    """A Blender camera: placed by eye/target/up, lens by kind.

    ``fov`` is the angle across the LARGER image side (Blender's sensor fit AUTO);
    ``ortho_scale`` the extent across the larger side; ``shift`` Blender's lens
    shift, in units of the larger side.
    """

    eye: Sequence[float]
    target: Sequence[float]
    up: Sequence[float] = (0.0, 0.0, 1.0)
    kind: str = "persp"  # "persp" | "ortho"
    fov: float = math.radians(50.0)
    ortho_scale: float = 8.0
    near: float = 0.1
    far: float = 100.0
    shift: Sequence[float] = (0.0, 0.0)

    def view_matrix(self) -> np.ndarray:
        """World -> view (4x4)."""
        eye = np.asarray(self.eye, float)
        f = np.asarray(self.target, float) - eye
        f /= np.linalg.norm(f)
        r = np.cross(f, np.asarray(self.up, float))
        r /= np.linalg.norm(r)
        u = np.cross(r, f)
        m = np.eye(4)
        m[0, :3], m[1, :3], m[2, :3] = r, u, -f
        m[:3, 3] = -m[:3, :3] @ eye
        return m

    def projection(self, width: int, height: int) -> np.ndarray:
        return projection_matrix(self.kind, width, height, fov=self.fov, ortho_scale=self.ortho_scale,
                                 near=self.near, far=self.far, shift=self.shift)


def projection_matrix(kind, width, height, *, fov=math.radians(50.0), ortho_scale=8.0, near=0.1,
                      far=100.0, shift=(0.0, 0.0)) -> np.ndarray:
    """Blender's OpenGL projection for a W x H render (sensor fit AUTO)."""
    big = float(max(width, height))
    # Half extents of the view window (at distance 1 for perspective).
    half = math.tan(fov / 2.0) if kind == "persp" else ortho_scale / 2.0
    hx, hy = half * width / big, half * height / big
    # Lens shift moves the window by shift * (full larger extent).
    cx, cy = shift[0] * 2.0 * half, shift[1] * 2.0 * half
    l, r, b, t = cx - hx, cx + hx, cy - hy, cy + hy
    p = np.zeros((4, 4))
    if kind == "persp":
        # Window given at distance 1; glFrustum scales it to the near plane,
        # which cancels out of every entry below.
        p[0, 0] = 2.0 / (r - l)
        p[0, 2] = (r + l) / (r - l)
        p[1, 1] = 2.0 / (t - b)
        p[1, 2] = (t + b) / (t - b)
        p[2, 2] = -(far + near) / (far - near)
        p[2, 3] = -2.0 * far * near / (far - near)
        p[3, 2] = -1.0
    elif kind == "ortho":
        p[0, 0] = 2.0 / (r - l)
        p[0, 3] = -(r + l) / (r - l)
        p[1, 1] = 2.0 / (t - b)
        p[1, 3] = -(t + b) / (t - b)
        p[2, 2] = -2.0 / (far - near)
        p[2, 3] = -(far + near) / (far - near)
        p[3, 3] = 1.0
    else:
        raise ValueError(f"kind: expected 'persp' or 'ortho', got {kind!r}")
    return p


@dataclasses.dataclass
class Scene:
    objects: list
    camera: Camera


# --- geometry -------------------------------------------------------------------


def _intersect(obj, o: np.ndarray, d: np.ndarray):
    """Nearest t > _EPS_T of rays o + t d (N x 3, world) with obj; (t, normal).

    t is +inf where the ray misses. The normal is the geometric one (outward for
    closed shapes, the plane's own for planes), not yet turned to the viewer.
    """
    n_rays = o.shape[0]
    t = np.full(n_rays, np.inf)
    nrm = np.zeros((n_rays, 3))
    if isinstance(obj, Plane):
        pn = np.asarray(obj.normal, float)
        pn = pn / np.linalg.norm(pn)
        denom = d @ pn
        with np.errstate(divide="ignore", invalid="ignore"):
            tt = ((np.asarray(obj.point, float) - o) @ pn) / denom
        ok = (np.abs(denom) > 1e-15) & (tt > _EPS_T)
        t[ok] = tt[ok]
        nrm[:] = pn
    elif isinstance(obj, Sphere):
        c = np.asarray(obj.center, float)
        oc = o - c
        a = np.einsum("ij,ij->i", d, d)
        b = np.einsum("ij,ij->i", oc, d)
        cc = np.einsum("ij,ij->i", oc, oc) - obj.radius ** 2
        disc = b * b - a * cc
        ok = disc >= 0.0
        sq = np.sqrt(np.where(ok, disc, 0.0))
        t0 = (-b - sq) / a
        t1 = (-b + sq) / a
        tt = np.where(t0 > _EPS_T, t0, np.where(t1 > _EPS_T, t1, np.inf))
        tt[~ok] = np.inf
        t = tt
        hit = np.isfinite(t)
        nrm[hit] = (o[hit] + d[hit] * t[hit, None] - c) / obj.radius
    elif isinstance(obj, Box):
        lo, hi = np.asarray(obj.lo, float), np.asarray(obj.hi, float)
        with np.errstate(divide="ignore", invalid="ignore"):
            inv = 1.0 / d
            ta = (lo - o) * inv
            tb = (hi - o) * inv
        # A ray parallel to a slab and inside it: the slab does not constrain it.
        par = d == 0.0
        inside = (o >= lo) & (o <= hi)
        tmin_ax = np.where(par, np.where(inside, -np.inf, np.inf), np.minimum(ta, tb))
        tmax_ax = np.where(par, np.where(inside, np.inf, -np.inf), np.maximum(ta, tb))
        tmin = tmin_ax.max(axis=1)
        tmax = tmax_ax.min(axis=1)
        axis_in = tmin_ax.argmax(axis=1)
        axis_out = tmax_ax.argmin(axis=1)
        ok = (tmax >= tmin) & (tmax > _EPS_T)
        enter = ok & (tmin > _EPS_T)
        leave = ok & ~enter
        t[enter] = tmin[enter]
        t[leave] = tmax[leave]
        idx = np.arange(n_rays)
        ax = np.where(enter, axis_in, axis_out)
        sgn = np.sign(d[idx, ax])
        # Entering: the face's outward normal opposes d; leaving: it follows d.
        nrm[idx, ax] = np.where(enter, -sgn, sgn)
        nrm[~ok] = 0.0
    else:
        raise TypeError(f"unknown object {obj!r}")
    return t, nrm


def cast(objects, o: np.ndarray, d: np.ndarray):
    """First hit of rays o + t d (world): t (inf = none), object index (-1), normal."""
    best = np.full(o.shape[0], np.inf)
    idx = np.full(o.shape[0], -1)
    nrm = np.zeros_like(o)
    for k, obj in enumerate(objects):
        t, n = _intersect(obj, o, d)
        closer = t < best
        best[closer] = t[closer]
        idx[closer] = k
        nrm[closer] = n[closer]
    return best, idx, nrm


def pixel_ndc(width: int, height: int):
    """NDC x, y of every pixel centre, [H, W] each, row 0 at the bottom."""
    u = (np.arange(width) + 0.5) / width
    v = (np.arange(height) + 0.5) / height
    uu, vv = np.meshgrid(u, v)
    return uu * 2.0 - 1.0, vv * 2.0 - 1.0


def unproject_rays(projection: np.ndarray, ndc_x: np.ndarray, ndc_y: np.ndarray):
    """View-space camera rays through NDC points: origin on the near plane, unit direction."""
    inv = np.linalg.inv(projection)
    n = ndc_x.size
    near = np.stack([ndc_x.ravel(), ndc_y.ravel(), -np.ones(n), np.ones(n)], axis=1) @ inv.T
    far = np.stack([ndc_x.ravel(), ndc_y.ravel(), np.ones(n), np.ones(n)], axis=1) @ inv.T
    near = near[:, :3] / near[:, 3:]
    far = far[:, :3] / far[:, 3:]
    d = far - near
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    return near, d


def project(projection: np.ndarray, pts: np.ndarray):
    """View-space points (N x 3) -> (uv N x 2, clip N x 4)."""
    clip = np.concatenate([pts, np.ones((pts.shape[0], 1))], axis=1) @ projection.T
    with np.errstate(divide="ignore", invalid="ignore"):
        uv = clip[:, :2] / clip[:, 3:] * 0.5 + 0.5
    return uv, clip


def _to_world(view_m: np.ndarray, pts=None, dirs=None):
    r = view_m[:3, :3]
    out = []
    if pts is not None:
        out.append((pts - view_m[:3, 3]) @ r)  # r^T (p - t), row-wise
    if dirs is not None:
        out.append(dirs @ r)
    return out


def _to_view(view_m: np.ndarray, pts=None, dirs=None):
    r = view_m[:3, :3]
    out = []
    if pts is not None:
        out.append(pts @ r.T + view_m[:3, 3])
    if dirs is not None:
        out.append(dirs @ r.T)
    return out


def _first_seen(scene: Scene, projection: np.ndarray, ndc_x, ndc_y):
    """What the camera sees through NDC points: view position, view normal (facing
    the camera), object index (-1 = nothing), all float64, flattened."""
    vm = scene.camera.view_matrix()
    o_v, d_v = unproject_rays(projection, ndc_x, ndc_y)
    o_w, d_w = _to_world(vm, pts=o_v, dirs=d_v)
    t, idx, n_w = cast(scene.objects, o_w, d_w)
    hit = np.isfinite(t)
    pos_v = np.zeros_like(o_v)
    pos_v[hit] = o_v[hit] + d_v[hit] * t[hit, None]
    # Past the far plane the camera sees nothing.
    hit &= -pos_v[:, 2] <= scene.camera.far
    (n_v,) = _to_view(vm, dirs=n_w)
    # Two-sided shading: the stored normal faces the camera ray.
    flip = np.einsum("ij,ij->i", n_v, d_v) > 0.0
    n_v[flip] *= -1.0
    idx = np.where(hit, idx, -1)
    pos_v[~hit] = 0.0
    n_v[~hit] = 0.0
    return pos_v, n_v, idx


def render(scene: Scene, width: int, height: int, background=(0.0, 0.0, 0.0)):
    """Exact G-buffer of ``scene`` for a W x H image.

    Returns a dict: position float32 [H, W, 4] (view xyz, w = 1 seen / 0 not),
    normal float32 [H, W, 3], specular float32 [H, W, 4] (rgb, shininess alpha),
    color float32 [H, W, 4] (alpha 1), projection float64 4x4, object int [H, W]
    (-1 = nothing), and the float64 position64 / normal64 [H, W, 3].
    """
    proj = scene.camera.projection(width, height)
    nx, ny = pixel_ndc(width, height)
    pos, nrm, idx = _first_seen(scene, proj, nx, ny)
    seen = idx >= 0
    position = np.zeros((width * height, 4))
    position[:, :3] = pos
    position[:, 3] = seen
    specular = np.zeros((width * height, 4))
    color = np.zeros((width * height, 4))
    color[:, :3] = background
    color[:, 3] = 1.0
    for k, obj in enumerate(scene.objects):
        m = idx == k
        specular[m, :3] = obj.material.specular
        specular[m, 3] = obj.material.alpha
        color[m, :3] = obj.material.color
    shp = (height, width)
    return {
        "position": position.reshape(shp + (4,)).astype(np.float32),
        "normal": nrm.reshape(shp + (3,)).astype(np.float32),
        "specular": specular.reshape(shp + (4,)).astype(np.float32),
        "color": color.reshape(shp + (4,)).astype(np.float32),
        "projection": proj,
        "object": idx.reshape(shp),
        "position64": pos.reshape(shp + (3,)),
        "normal64": nrm.reshape(shp + (3,)),
    }


def mirror_hits(scene: Scene, gbuf: dict, max_distance: float = np.inf, incident: str = "view"):
    """The exact hit of every pixel's mirror ray, in double precision.

    The ray starts at the pixel's exact surface point and goes along the
    reflection of the incident direction about the exact normal. ``incident``:
    "position" reflects normalize(view position) -- the vector the seed
    reflects, which is the view ray of a perspective camera; "view" reflects
    the camera ray direction (differs for an orthographic camera).

    Returns a dict of [H, W] arrays: ``hit`` (a surface within max_distance),
    ``distance``, ``object``, ``uv`` [H, W, 2] of the projected hit, ``on_screen``
    (in front of the camera, inside the frustum), ``visible`` (the camera sees that
    very point: on screen and not occluded), ``front`` (the ray reaches the side of
    the surface that the camera sees, i.e. not a back-side hit), and ``pivot``
    [H, W, 3] (unit mirror direction, view space).
    """
    h, w = gbuf["object"].shape
    proj = gbuf["projection"]
    cam = scene.camera
    vm = cam.view_matrix()
    seen = (gbuf["object"] >= 0).ravel()
    p = gbuf["position64"].reshape(-1, 3)
    n = gbuf["normal64"].reshape(-1, 3)
    if incident == "position":
        with np.errstate(invalid="ignore", divide="ignore"):
            inc = p / np.linalg.norm(p, axis=1, keepdims=True)
    elif incident == "view":
        nx, ny = pixel_ndc(w, h)
        _, inc = unproject_rays(proj, nx, ny)
    else:
        raise ValueError(f"incident: expected 'position' or 'view', got {incident!r}")
    inc = np.where(seen[:, None], inc, 0.0)
    pivot = inc - 2.0 * np.einsum("ij,ij->i", n, inc)[:, None] * n
    norm = np.linalg.norm(pivot, axis=1, keepdims=True)
    pivot = np.where(norm > 0, pivot / np.where(norm > 0, norm, 1.0), 0.0)

    o_w, d_w = _to_world(vm, pts=p, dirs=pivot)
    t, idx, n_w = cast(scene.objects, o_w, np.where(seen[:, None], d_w, np.array([0.0, 0.0, 1.0])))
    hit = seen & np.isfinite(t) & (t <= max_distance)
    hp_w = o_w + d_w * np.where(hit, t, 0.0)[:, None]
    (hp_v,) = _to_view(vm, pts=hp_w)
    uv, clip = project(proj, hp_v)
    ndc_z = clip[:, 2] / np.where(clip[:, 3] != 0, clip[:, 3], 1.0)
    on_screen = (hit & (clip[:, 3] > 0) & (uv[:, 0] >= 0) & (uv[:, 0] <= 1) & (uv[:, 1] >= 0)
                 & (uv[:, 1] <= 1) & (ndc_z >= -1) & (ndc_z <= 1))
    # Occlusion: what the camera sees at that uv must be the hit point itself.
    visible = np.zeros_like(hit)
    if on_screen.any():
        sel = np.flatnonzero(on_screen)
        ndc = uv[sel] * 2.0 - 1.0
        pos_seen, _, idx_seen = _first_seen(scene, proj, ndc[:, 0], ndc[:, 1])
        err = np.linalg.norm(pos_seen - hp_v[sel], axis=1)
        scale = 1.0 + np.linalg.norm(hp_v[sel], axis=1)
        visible[sel] = (idx_seen >= 0) & (err <= 1e-6 * scale)
    # Back-side: the mirror ray and the camera approach the surface from
    # opposite sides of it.
    # The camera's ray to the hit point: from the eye (perspective), or along
    # the view axis (orthographic).
    if cam.kind == "persp":
        cam_dir = hp_w - np.linalg.inv(vm)[:3, 3]
    else:
        (axis,) = _to_world(vm, dirs=np.array([[0.0, 0.0, -1.0]]))
        cam_dir = np.broadcast_to(axis, hp_w.shape)
    side_ray = np.einsum("ij,ij->i", n_w, d_w)
    side_cam = np.einsum("ij,ij->i", n_w, cam_dir)
    front = hit & (side_ray * side_cam > 0)
    shp = (h, w)
    return {
        "hit": hit.reshape(shp),
        "distance": np.where(hit, t, np.inf).reshape(shp),
        "object": np.where(hit, idx, -1).reshape(shp),
        "uv": uv.reshape(shp + (2,)),
        "point": hp_v.reshape(shp + (3,)),
        "on_screen": on_screen.reshape(shp),
        "visible": visible.reshape(shp),
        "front": front.reshape(shp),
        "pivot": pivot.reshape(shp + (3,)),
    }


def near_plane_length(projection: np.ndarray, origin: np.ndarray, direction: np.ndarray,
                      max_distance: float) -> np.ndarray:
    """Length of each ray (N x 3 view space) cut so its end stays on or in front of
    the near plane (clip z >= -w); negative where the origin itself is not."""
    def g(pts):
        c = np.concatenate([pts, np.ones((pts.shape[0], 1))], axis=1) @ projection.T
        return c[:, 2] + c[:, 3]

    g0 = g(origin)
    g1 = g(origin + direction * max_distance)
    length = np.full(origin.shape[0], float(max_distance))
    cut = g1 < 0
    with np.errstate(divide="ignore", invalid="ignore"):
        length[cut] = max_distance * g0[cut] / (g0[cut] - g1[cut])
    length[~(g0 >= 0)] = -1.0
    return length


def path_state(gbuf: dict, pivot: np.ndarray, max_distance: float, thickness: float,
               samples: Optional[int] = None, margin: float = 0.02, stop: Optional[np.ndarray] = None,
               end_skip_px: float = 0.0):
    """Where each pixel's mirror ray runs in the image, sampled densely in screen space.

    For the on-screen part of every ray (cut at the near plane and at
    max_distance, and at ``stop`` [H, W] view-space lengths if given), each
    sample's view depth is compared with the texels around it (the nearest
    texel and its neighbours within 0.35 px, read from the float32 position
    buffer as the march reads it; with samples at most 0.4 px apart every point
    of the line is within 0.2 px of a sample, so every texel a march probe can
    read is looked at). Returns [H, W] booleans:

    ``clear``: the ray never runs behind any seen texel (it stays in front of
    every surface by more than ``margin``), so no march can report a hit;
    ``grazes``: it runs behind a seen texel by no more than thickness + margin
    somewhere (a hit is possible there).

    Samples within ``end_skip_px`` (along the major axis) of the segment's end
    are ignored: with ``stop`` = the exact hit distance, ``grazes`` then says
    whether some other surface could catch the ray before its true hit.
    """
    pos32 = gbuf["position"]
    h, w = pos32.shape[:2]
    proj = gbuf["projection"]
    seen_tex = pos32[..., 3] > 0
    tex_vd = -pos32[..., 2].astype(np.float64)
    p = gbuf["position64"].reshape(-1, 3)
    d = pivot.reshape(-1, 3)
    valid = (gbuf["object"].ravel() >= 0) & (np.linalg.norm(d, axis=1) > 0)
    length = near_plane_length(proj, p, d, max_distance)
    if stop is not None:
        length = np.minimum(length, stop.ravel())
    valid &= length >= 0
    clear = np.ones(p.shape[0], bool)
    grazes = np.zeros(p.shape[0], bool)
    sel = np.flatnonzero(valid)
    if sel.size == 0:
        return clear.reshape(h, w), grazes.reshape(h, w)
    a = p[sel]
    b = p[sel] + d[sel] * length[sel, None]
    _, ca = project(proj, a)
    _, cb = project(proj, b)
    fa = (ca[:, :2] / ca[:, 3:] * 0.5 + 0.5) * [w, h]
    fb = (cb[:, :2] / cb[:, 3:] * 0.5 + 0.5) * [w, h]
    # Clip the screen segment to the image (plus a pixel) so samples are dense
    # where they matter even when the end projects far away.
    s0 = np.zeros(sel.size)
    s1 = np.ones(sel.size)
    for axis, size in ((0, w), (1, h)):
        dd = fb[:, axis] - fa[:, axis]
        with np.errstate(divide="ignore", invalid="ignore"):
            ta = (-1.0 - fa[:, axis]) / dd
            tb = (size + 1.0 - fa[:, axis]) / dd
        lo = np.where(dd == 0, np.where((fa[:, axis] >= -1) & (fa[:, axis] <= size + 1), 0.0, 2.0),
                      np.minimum(ta, tb))
        hi = np.where(dd == 0, 1.0, np.maximum(ta, tb))
        s0 = np.maximum(s0, lo)
        s1 = np.minimum(s1, hi)
    # The clipped segment is at most the diagonal of the (w + 2) x (h + 2) box.
    longest = math.hypot(w + 2, h + 2)
    if samples is None:
        samples = int(math.ceil(longest / 0.4)) + 1
    assert samples >= 2 and longest / (samples - 1) <= 0.4, "samples too sparse for the image"
    s = s0[:, None] + (s1 - s0)[:, None] * np.linspace(0.0, 1.0, samples)[None, :]
    f = fa[:, None, :] + (fb - fa)[:, None, :] * s[..., None]
    # The march's first sample is a whole pixel (1 / resolution >= 1) from the
    # start along the major axis; nothing closer is ever read.
    major = np.abs(f - fa[:, None, :]).max(axis=2)
    live = (s1 >= s0)[:, None] & (major >= 1.0)
    if end_skip_px > 0:
        live &= np.abs(f - fb[:, None, :]).max(axis=2) >= end_skip_px
    # View depth along the ray at screen fraction s: 1/w is linear in screen space.
    wa, wb = ca[:, 3:4], cb[:, 3:4]
    vda, vdb = -a[:, 2:3], -b[:, 2:3]
    ray_vd = ((1 - s) * vda / wa + s * vdb / wb) / ((1 - s) / wa + s / wb)
    # A probe between two samples sees a ray depth between theirs (it is
    # monotonic along the ray): compare texels with that whole range.
    nb = np.stack([ray_vd, np.roll(ray_vd, 1, axis=1), np.roll(ray_vd, -1, axis=1)])
    nb[1, :, 0] = ray_vd[:, 0]
    nb[2, :, -1] = ray_vd[:, -1]
    vd_lo, vd_hi = nb.min(axis=0), nb.max(axis=0)
    behind_any = np.zeros(s.shape, bool)
    graze_any = np.zeros(s.shape, bool)
    # The texels meeting a 0.7 px box are those holding one of its corners.
    for ox in (-0.35, 0.35):
        for oy in (-0.35, 0.35):
            tx = np.floor(f[..., 0] + ox)
            ty = np.floor(f[..., 1] + oy)
            inside = live & (tx >= 0) & (tx < w) & (ty >= 0) & (ty < h)
            txi = np.where(inside, tx, 0).astype(int)
            tyi = np.where(inside, ty, 0).astype(int)
            ok = inside & seen_tex[tyi, txi]
            tv = tex_vd[tyi, txi]
            behind = ok & (vd_hi - tv > -margin)
            behind_any |= behind
            graze_any |= behind & (vd_lo - tv < thickness + margin)
    clear[sel] = ~behind_any.any(axis=1)
    grazes[sel] = graze_any.any(axis=1)
    return clear.reshape(h, w), grazes.reshape(h, w)


# --- ready-made scenes ------------------------------------------------------------

RED = Material(color=(0.9, 0.1, 0.1))
GREEN = Material(color=(0.1, 0.8, 0.2))
BLUE = Material(color=(0.15, 0.2, 0.9))


def mirror_floor_scene(kind: str = "persp", shift=(0.0, 0.0), sphere=True, box=True, wall=True,
                       floor: Material = MIRROR, sphere_material: Material = RED) -> Scene:
    """A mirror floor (z = 0) under a red sphere and a green box, a blue finite wall
    behind them, empty sky above; the camera looks slightly down at it."""
    objs = [Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), floor)]
    if sphere:
        objs.append(Sphere((-0.6, 0.6, 1.0), 0.8, sphere_material))
    if box:
        objs.append(Box((1.0, -0.6, 0.0), (2.0, 0.4, 1.2), GREEN))
    if wall:
        objs.append(Box((-6.0, 4.0, 0.0), (6.0, 4.4, 2.6), BLUE))
    if kind == "persp":
        cam = Camera(eye=(0.0, -7.0, 2.2), target=(0.0, 0.0, 0.9), fov=math.radians(55.0), near=0.1,
                     far=100.0, shift=shift)
    else:
        cam = Camera(eye=(0.0, -12.0, 5.0), target=(0.0, 0.0, 0.8), kind="ortho", ortho_scale=9.0,
                     near=0.1, far=100.0, shift=shift)
    return Scene(objs, cam)


def reflection_shares(scene: Scene, width: int, height: int, max_distance: float, grid: int = 4,
                      target: Optional[int] = None):
    """The exact shares of each pixel's reflection over a grid x grid lattice of
    sub-pixel rays (a render at ``grid`` times the size): ``seen``, the share whose
    mirror hit is visible, and ``unseen``, the share that hits a surface the camera
    does not see there (a hidden side, or off the screen); only hits on object
    ``target`` when given. Also ``objects`` [height, grid, width, grid]: what each
    sub-pixel ray starts on."""
    hi = render(scene, width * grid, height * grid)
    hits = mirror_hits(scene, hi, max_distance, incident="view")
    on = hits["hit"] if target is None else hits["hit"] & (hits["object"] == target)

    def share(mask):
        return mask.reshape(height, grid, width, grid).mean(axis=(1, 3))

    objects = hi["object"].reshape(height, grid, width, grid)
    return share(on & hits["visible"]), share(on & ~hits["visible"]), objects


def reflection_coverage(scene: Scene, gbuf: dict, max_distance: float, grid: int = 4):
    """The exact coverage of each pixel's reflection, what an antialiased frame shows:
    the share of a grid x grid lattice of sub-pixel rays (a render at ``grid`` times
    ``gbuf``'s size) whose mirror hit is visible. Returns (coverage, whole): ``whole``
    marks the pixels whose sub-pixel rays all start on the pixel's own object, where
    the coverage is the reflection's alone and not the reflector's own outline."""
    h, w = gbuf["object"].shape
    coverage, _, objects = reflection_shares(scene, w, h, max_distance, grid)
    whole = (objects == gbuf["object"][:, None, :, None]).all(axis=(1, 3))
    return coverage, whole


def back_layer(scene: Scene, gbuf: dict) -> np.ndarray:
    """The nearest back-facing surface behind each pixel's own, float32 [H, W, 4]
    (view xyz, w = 1 where there is one): what a rasterizer's back-face layer
    holds, and so each closed object's true thickness along the view ray."""
    h, w = gbuf["object"].shape
    vm = scene.camera.view_matrix()
    nx, ny = pixel_ndc(w, h)
    _, d_v = unproject_rays(gbuf["projection"], nx, ny)
    seen = (gbuf["object"] >= 0).ravel()
    o_v = gbuf["position64"].reshape(-1, 3).copy()
    out = np.zeros((w * h, 4))
    todo = seen.copy()
    for _ in range(4):  # a few surfaces deep is plenty for these scenes
        if not todo.any():
            break
        o_w, d_w = _to_world(vm, pts=o_v, dirs=d_v)
        t, idx, n_w = cast(scene.objects, o_w, d_w)
        hit = todo & np.isfinite(t)
        facing_away = np.einsum("ij,ij->i", n_w, d_w) > 0.0
        found = hit & facing_away
        p_new = o_v + d_v * np.where(np.isfinite(t), t, 0.0)[:, None]
        out[found, :3] = p_new[found]
        out[found, 3] = 1.0
        todo = hit & ~facing_away
        o_v = np.where(todo[:, None], p_new, o_v)
    return out.reshape(h, w, 4).astype(np.float32)


def corridor_scene() -> Scene:
    """A long mirror-floored corridor between two walls, seen from low down so that
    most floor rays graze: the case where point-sampling marches lose hits."""
    floor = Material(color=(0.3, 0.3, 0.3), specular=(1.0, 1.0, 1.0), alpha=1.0)
    objs = [
        Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), floor),
        Box((-2.2, -2.0, 0.0), (-1.8, 40.0, 3.0), RED),     # left wall
        Box((1.8, -2.0, 0.0), (2.2, 40.0, 3.0), GREEN),     # right wall
        Box((-1.8, 40.0, 0.0), (1.8, 40.4, 3.0), BLUE),     # far end
        Sphere((-0.7, 9.0, 0.6), 0.6, RED),
        Box((0.3, 16.0, 0.0), (1.2, 17.0, 1.4), BLUE),
    ]
    cam = Camera(eye=(0.0, -1.5, 0.45), target=(0.0, 30.0, 0.25), fov=math.radians(60.0), near=0.05,
                 far=200.0)
    return Scene(objs, cam)


def facing_wall_scene() -> Scene:
    """A mirror wall square to the camera with objects in front of it, so that
    reflected rays come back toward the camera (and toward the near plane)."""
    wall = Material(color=(0.2, 0.2, 0.25), specular=(1.0, 1.0, 1.0), alpha=1.0)
    objs = [
        Box((-6.0, 5.0, -1.0), (6.0, 5.4, 6.0), wall),
        Plane((0.0, 0.0, 0.0), (0.0, 0.0, 1.0), Material(color=(0.5, 0.45, 0.4))),
        Sphere((-1.0, 2.0, 0.8), 0.8, RED),
        Box((0.6, 1.0, 0.0), (1.6, 2.0, 1.5), GREEN),
        Sphere((1.8, 3.5, 0.4), 0.4, BLUE),
    ]
    cam = Camera(eye=(0.0, -4.0, 1.6), target=(0.0, 5.0, 1.4), fov=math.radians(55.0), near=0.1,
                 far=100.0)
    return Scene(objs, cam)

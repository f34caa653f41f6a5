#!/usr/bin/env python3
"""How steady each march's reflections are while the camera moves: a camera pass over a
mirror floor under two spheres resting on it, a box and thin pillars, rasterized by
glint_core at each frame, each march scored against the exact march of the same frame.

The reflection a viewer sees is modelled as the compositor makes it: a frame coloured by
a smooth world-space texture (so that its colours move with the objects, not with the
screen), sampled bilinearly at each pixel's reflected uv and weighted by the visibility.
Scores, over the floor's pixels (the only reflector), sums of absolute values:

  error    per frame, |R - E| / |E|: R the march's reflection, E the exact march's
           (E given the march's screen-edge fade where the march fades, so that the
           fade, a design choice, is not counted as error); median over the frames
  change   frame to frame, |R_t - R_t-1| / |E_t|: how much the reflection changes
           between frames, real motion and flicker together; the exact march's own
           value is the floor set by the motion and by pixel aliasing (the target is
           at most 1.1x exact's)
  flicker  frame to frame, |(R_t - R_t-1) - (E_t - E_t-1)| / |E_t|: the change the
           exact march does not have
  outline  the share of the error on the pixels whose exact hit lies on an object's
           outline (a texel next to one of another depth)
  dimmed   the share of the floor's hits, away from the screen's edges, reported below
           full visibility (hiz: on an outline texel's outer half, or located only to
           its texel; the seed: its own fades), and the share of those hits' light
           that the dimming takes (light lost)

  /usr/bin/python3 bench/motion_bench.py [--sizes 480x270,960x540] [--frames 24]
      [--marches seed,draft,balanced,high] [--backend cpu|gl] [--supersample 4]

A march may override one preset keyword: balanced:antialias=0.

The camera slides sideways and a little forward, about 1.5 pixels of screen motion per
frame at 480x270 for the nearer sphere; the pillars are about 4 pixels wide at 480x270.
docs/motion.md has the table and what it shows.
"""
from __future__ import annotations

import argparse
import math
import os
import statistics
import sys

import numpy as np

root = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.environ.get("GLINT_BUILD_DIR", os.path.join(root, "build")), "python"))
import glint_core  # noqa: E402
sys.path.insert(0, os.path.join(root, "tests", "python"))
from reference_hiz import edge_fade  # noqa: E402,F401  (hiz's fade at the screen's edges, written once)
from scene_meshes import box, perspective  # noqa: E402  (bench/, beside this script)

CONSTANTS = glint_core.schema()["constants"]
MAX_DISTANCE = 40.0
PITCH = math.radians(12.0)
EYE = np.array([0.0, 1.2, 0.0])
HALF_FOV = 0.5  # radians, vertical: f = (h / 2) / tan(0.5), 247 px at 270 rows
# Screen motion: the near sphere (6.5 ahead) moves ~1.5 px per frame at 270 rows.
STEP = np.array([1.5 * 6.5 / (135.0 / math.tan(HALF_FOV)), 0.0, -0.02])
PILLAR_WIDTH = 4.0 * 11.0 / (135.0 / math.tan(HALF_FOV))  # ~4 px at 270 rows, 11 ahead


def _sphere(centre, r, seg=48):
    th, ph = np.linspace(0, np.pi, seg + 1), np.linspace(0, 2 * np.pi, 2 * seg + 1)
    T, F = np.meshgrid(th, ph, indexing="ij")
    d = np.stack([np.sin(T) * np.cos(F), np.cos(T), np.sin(T) * np.sin(F)], -1).reshape(-1, 3)
    cols = 2 * seg + 1
    i = np.arange(seg)[:, None] * cols + np.arange(2 * seg)[None, :]
    quads = np.stack([i, i + cols, i + cols + 1, i + 1], -1).reshape(-1, 4)
    tris = np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])
    return np.asarray(centre) + r * d, tris


def _floor(n=24):
    xs, zs = np.linspace(-20.0, 20.0, n + 1), np.linspace(2.0, -45.0, n + 1)
    X, Z = np.meshgrid(xs, zs)
    v = np.stack([X, 0.0 * X, Z], -1).reshape(-1, 3)
    i = np.arange(n)[:, None] * (n + 1) + np.arange(n)[None, :]
    quads = np.stack([i, i + n + 1, i + n + 2, i + 1], -1).reshape(-1, 4)
    return v, np.concatenate([quads[:, [0, 1, 2]], quads[:, [0, 2, 3]]])


def _outward(v, t, up):
    """Winding so that each face's normal points out of its part (up for the floor):
    the rasterizer's back layer goes by it."""
    p = v[t]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    out = np.array([0.0, 1.0, 0.0]) if up else p.mean(1) - v.mean(0)
    flip = (n * out).sum(-1) < 0
    t = t.copy()
    t[flip] = t[flip][:, ::-1]
    return t


def scene():
    """World-space (vertices [N, 3], triangles [M, 3], material per triangle): material 0
    the mirror floor, 1 the objects (not reflective)."""
    parts = [_floor(), _sphere((-1.0, 0.8, -6.5), 0.8), _sphere((1.4, 0.5, -5.2), 0.5),
             box((2.4, 0.0, -9.5), (3.4, 1.2, -8.5))]
    parts += [box((x, 0.0, -11.0 - 0.5 * k), (x + PILLAR_WIDTH, 3.0, -11.0 - 0.5 * k + PILLAR_WIDTH))
              for k, x in enumerate((-3.2, -2.0, 0.3, 1.9))]
    verts, tris, mats, base = [], [], [], 0
    for k, (v, t) in enumerate(parts):
        t = _outward(v, t, up=k == 0)
        verts.append(v)
        tris.append(t + base)
        mats.append(np.full(len(t), 0 if k == 0 else 1, np.int32))
        base += len(v)
    return np.concatenate(verts), np.concatenate(tris).astype(np.int32), np.concatenate(mats)


def camera(frame: int) -> np.ndarray:
    """Camera to world: pitched down by PITCH, moved by STEP per frame."""
    cp, sp = math.cos(PITCH), math.sin(PITCH)
    m = np.eye(4)
    m[:3, :3] = np.array([[1, 0, 0], [0, cp, sp], [0, -sp, cp]])
    m[:3, 3] = EYE + np.array([-0.5, 0.0, 0.0]) + STEP * frame
    return m


def projection(w: int, h: int) -> np.ndarray:
    return perspective(w, h, fov=2.0 * HALF_FOV)


def texture(world: np.ndarray) -> np.ndarray:
    """A smooth colour per world point: what the frame shows there."""
    x, y, z = world[..., 0], world[..., 1], world[..., 2]
    return np.stack([0.55 + 0.45 * np.sin(2.1 * x + 1.3 * y), 0.55 + 0.45 * np.sin(1.7 * y + 2.3 * z),
                     0.55 + 0.45 * np.sin(2.9 * z + 0.7 * x + 1.1 * y)], -1).astype(np.float32)


def render(v_world, t, mat, cam, w, h):
    """The frame's G-buffer (with the back layer) and its colour."""
    v_view = ((v_world - cam[:3, 3]) @ cam[:3, :3]).astype(np.float32)
    pos = v_view[t]
    nrm = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    nrm /= np.linalg.norm(nrm, axis=1, keepdims=True) + 1e-30
    normals = np.repeat(nrm[:, None, :], 3, axis=1).astype(np.float32)
    materials = np.array([[1, 1, 1, CONSTANTS["MAX_SHININESS"]], [0, 0, 0, 0]], np.float32)
    g = glint_core.rasterize(pos, normals, mat, materials, projection(w, h), w, h, back_layer=True)
    p = g["position"]
    seen = p[..., 3] > 0
    world = p[..., :3] @ cam[:3, :3].T + cam[:3, 3]
    colour = np.where(seen[..., None], texture(world), 0.0).astype(np.float32)
    return g, colour


def sample(colour: np.ndarray, uv: np.ndarray) -> np.ndarray:
    """Bilinear read of the frame at each pixel's uv, times its visibility (Map UV)."""
    h, w = colour.shape[:2]
    x = np.clip(uv[..., 0] * w - 0.5, 0, w - 1)
    y = np.clip(uv[..., 1] * h - 0.5, 0, h - 1)
    x0, y0 = np.floor(x).astype(int), np.floor(y).astype(int)
    x1, y1 = np.minimum(x0 + 1, w - 1), np.minimum(y0 + 1, h - 1)
    fx, fy = (x - x0)[..., None], (y - y0)[..., None]
    c = ((colour[y0, x0] * (1 - fx) + colour[y0, x1] * fx) * (1 - fy)
         + (colour[y1, x0] * (1 - fx) + colour[y1, x1] * fx) * fy)
    return c * uv[..., 2:3]


def outline_texels(position: np.ndarray) -> np.ndarray:
    """Texels next to an unseen one or one much nearer or farther (2% of the distance)."""
    z = -position[..., 2]
    seen = position[..., 3] > 0
    out = np.zeros(z.shape, bool)
    for axis in (0, 1):
        for shift in (1, -1):
            zn = np.roll(z, shift, axis)
            sn = np.roll(seen, shift, axis)
            out |= seen & (~sn | (np.abs(zn - z) > 0.02 * z))
    return out


def march_options(name: str):
    """A preset's (or the seed's) trace keywords; "balanced:antialias=0" overrides one."""
    name, _, override = name.partition(":")
    opts = dict(max_distance=MAX_DISTANCE) if name == "seed" else dict(glint_core.presets()[name],
                                                                        max_distance=MAX_DISTANCE)
    if override:
        key, value = override.split("=")
        opts[key] = type(opts.get(key, 0))(value)
    return opts


def dimming(uv: np.ndarray, floor: np.ndarray):
    """(share of the hits below full visibility, share of their light lost), over the
    floor's hits away from the screen's edges (where the fade is the only dimming)."""
    hits = (uv[..., 2] > 0) & (edge_fade(uv) >= 1.0) & floor
    conf = uv[..., 2][hits]
    if conf.size == 0:
        return 0.0, 0.0
    return float((conf < 1 - 1e-6).mean()), float((1.0 - np.minimum(conf, 1.0)).mean())


def box_down(image: np.ndarray, s: int) -> np.ndarray:
    """The mean of each s x s block: a pixel's box filter over its s^2 samples."""
    hh, ww = image.shape[0] // s, image.shape[1] // s
    return image.reshape(hh, s, ww, s, -1).mean(axis=(1, 3)).astype(np.float32)


def supersampled(v_world, t, mat, cam, exact_scene, w, h, s):
    """The antialiased frame and exact reflection: the frame rasterized at s x s samples per
    pixel and exact-traced there, both box-filtered to w x h, as a renderer's antialiasing
    averages its samples. Returns (colour, E, E faded at the screen's edges)."""
    g, colour = render(v_world, t, mat, cam, w * s, h * s)
    uv = glint_core.trace(g["position"], g["normal"], projection(w * s, h * s), march="exact",
                          mesh=exact_scene.seen_from(cam), specular=g["specular"], max_distance=MAX_DISTANCE)
    faded = uv.copy()
    faded[..., 2] *= edge_fade(uv)
    return box_down(colour, s), box_down(sample(colour, uv), s), box_down(sample(colour, faded), s)


def run(size, frames, marches, backend="cpu", supersample=1, read_inside=True, settle=True):
    w, h = size
    v_world, t, mat = scene()
    exact_scene = glint_core.ExactScene(v_world.astype(np.float32), t)
    proj = projection(w, h)
    prev = {}
    rows = {m: {k: [] for k in ("error", "change", "flicker", "outline", "dimmed", "lost")} for m in marches + ["exact"]}
    for f in range(frames + 1):
        cam = camera(f)
        g, colour = render(v_world, t, mat, cam, w, h)
        P, N, S, B = g["position"], g["normal"], g["specular"], g["back_position"]
        floor = S[..., :3].mean(-1) > 0
        exact_uv = glint_core.trace(P, N, proj, march="exact", mesh=exact_scene.seen_from(cam), specular=S,
                                    max_distance=MAX_DISTANCE)
        # Where the exact hit lands on an outline texel.
        hit = exact_uv[..., 2] > 0
        hx = np.clip((exact_uv[..., 0] * w).astype(int), 0, w - 1)
        hy = np.clip((exact_uv[..., 1] * h).astype(int), 0, h - 1)
        on_outline = hit & outline_texels(P)[hy, hx] & floor
        E_plain = sample(colour, exact_uv)
        # what a march that fades at the screen's edges is scored against
        faded = exact_uv.copy()
        faded[..., 2] *= edge_fade(exact_uv)
        E_faded = sample(colour, faded)
        E_exact = E_plain
        if supersample > 1:
            # The frame as a renderer antialiases it, and the reflection with it: the
            # one-ray exact march is then scored too, for what its own aliasing costs.
            colour, E_plain, E_faded = supersampled(v_world, t, mat, cam, exact_scene, w, h, supersample)
            E_exact = sample(colour, exact_uv)
        cur = {"exact": (E_exact, E_plain)}
        dims = {"exact": dimming(exact_uv, floor)}
        for m in marches:
            opts = march_options(m)
            uv = glint_core.trace(P, N, proj, specular=S, back_position=B, backend=backend, **opts)
            if settle and opts.get("march") == "hiz":
                # The add-on's composite settles the hits hiz was unsure of inside a
                # reflection (docs/hiz.md, *Uncertain shares inside a reflection*);
                # no hidden side here, so a hit takes its whole fade.
                none = np.zeros_like(uv)
                uv = glint_core.settle_uncertain_shares(uv, none, none)[0]
            dims[m] = dimming(uv, floor)
            # The add-on's compositor reads the colour inside the objects' outlines
            # whichever march traced (docs/look-core.md, *Where the colour is read*);
            # the seed's row traces with the core's default thickness, and reads with it.
            thickness = {"thickness": opts["thickness"]} if "thickness" in opts else {}
            read = glint_core.read_inside_outlines(uv, P, back_position=B, **thickness) if read_inside else uv
            cur[m] = (sample(colour, read), E_faded if opts.get("march") == "hiz" else E_plain)
        for m, (R, E) in cur.items():
            norm = np.abs(E[floor]).sum() + 1e-12
            diff = np.abs(R - E)
            if f > 0:  # frame 0 only starts the changes
                rows[m]["error"].append(diff[floor].sum() / norm)
                rows[m]["outline"].append(diff[on_outline].sum() / (diff[floor].sum() + 1e-12))
                rows[m]["dimmed"].append(dims[m][0])
                rows[m]["lost"].append(dims[m][1])
                Rp, Ep = prev[m]
                both = floor & prev["floor"]
                rows[m]["change"].append(np.abs(R - Rp)[both].sum() / norm)
                rows[m]["flicker"].append(np.abs((R - Rp) - (E - Ep))[both].sum() / norm)
        prev = dict(cur)
        prev["floor"] = floor
    return {m: {k: statistics.median(v) for k, v in r.items()} for m, r in rows.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--sizes", default="480x270,960x540")
    ap.add_argument("--frames", type=int, default=24)
    ap.add_argument("--marches", default="seed,draft,balanced,high")
    ap.add_argument("--backend", default="cpu", help="the marches' backend (the exact march runs on the CPU)")
    ap.add_argument("--read-at-uv", action="store_true",
                    help="read the frame at the trace's uv everywhere, as before Glint's look read "
                         "outline texels one texel inside their object")
    ap.add_argument("--no-settle", action="store_true",
                    help="leave the hits hiz was unsure of as the trace reports them, as before the "
                         "add-on's composite settled those inside a reflection")
    ap.add_argument("--supersample", type=int, default=1,
                    help="score against the exact reflection of s x s samples per pixel, box-filtered, "
                         "with the frame antialiased the same way (1: one exact ray per pixel)")
    args = ap.parse_args()
    marches = args.marches.split(",")
    print(f"| size | march | error | change | change / exact's | flicker | error on outlines | hits dimmed "
          f"| light lost |  ({args.frames} frames, medians, backend {args.backend}, "
          f"reference {args.supersample}x{args.supersample} samples per pixel)")
    print("|---|---|---|---|---|---|---|---|---|")
    for size in args.sizes.split(","):
        w, h = (int(v) for v in size.split("x"))
        res = run((w, h), args.frames, marches, args.backend, args.supersample, not args.read_at_uv,
                  not args.no_settle)
        base = res["exact"]["change"]
        for m in ["exact"] + marches:
            r = res[m]
            print(f"| {w}x{h} | {m} | {r['error']:.4f} | {r['change']:.4f} | {r['change'] / base:.2f}x | "
                  f"{r['flicker']:.4f} | {100 * r['outline']:.0f}% | {100 * r['dimmed']:.1f}% | "
                  f"{100 * r['lost']:.2f}% |", flush=True)


if __name__ == "__main__":
    main()

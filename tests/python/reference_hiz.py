"""A plain, slow float64 reference of the "hiz" march, without the pyramid.

docs/hiz.md defines what the march finds: walking the reflected ray's
screen-space line texel by texel from the texel after its origin, the first
texel where the ray's depth span meets the texel's footprint range and the
texel's tangent plane says Hit (the ray crosses it from the front, or is
behind it by no more than a rounding slack, or is a late crossing: see _texel)
or Blocked (behind it within its thickness: report nothing, or with
blocked="occluder" that texel's centre, as (u, v, edge fade, 0); (u, v, edge
fade, ENTERED_HIDDEN) when the ray is deeper than HIDDEN_SHARE of the thickness
behind the texel's depth or comes into it from behind, which means it came in by
the object's hidden side). A texel's plane has its geometric normal, rebuilt
from the positions (plane_normals()), not its shading normal. The core reaches the same texel through a min/max
pyramid; this file visits every texel on the line, in Python floats (IEEE
double), so agreeing with it shows the pyramid never skips one.

Keep images small (tens of pixels a side). Returns float64 [H, W, 4].
"""
from __future__ import annotations

import math

import numpy as np

from glint_tables import addon_schema

# The method's constants are the core's (native/include/glint/schema.h, why
# each is what it is); the rules that use them are written out below.
_S = addon_schema()
CELL_NUDGE = _S.CELL_NUDGE
PLANE_TOLERANCE = _S.PLANE_TOLERANCE
BEHIND_SLACK = _S.BEHIND_SLACK
FOOTPRINT_SPREAD = _S.FOOTPRINT_SPREAD
EDGE_FADE = _S.EDGE_FADE   # share of the screen over which visibility fades at its edges
UNCERTAIN = _S.UNCERTAIN   # confidence of a hit located only to its texel, or at an outline texel's edge
ENTERED_HIDDEN = _S.ENTERED_HIDDEN  # an occluder's hit channel when the ray came in by the hidden side
HIDDEN_SHARE = _S.HIDDEN_SHARE  # deeper than this share of the thickness: came in from behind
CROSSING_DEPTH = _S.CROSSING_DEPTH  # with the back layer: further than this many thicknesses is off it


def edge_fade(uv: np.ndarray) -> np.ndarray:
    """hiz's visibility fade at the screen's edges, per pixel of a reflected-uv
    buffer [H, W, 4]: 1 inside, falling linearly to 0 within EDGE_FADE of the edge
    that the pixel's ray is heading for: the first one that the line from the
    pixel's centre through its hit meets beyond the hit (the nearest edge for a hit
    on the pixel's own centre)."""
    h, w = uv.shape[:2]
    y, x = np.mgrid[0:h, 0:w]
    return _fade((x + 0.5) / w, (y + 0.5) / h, uv[..., 0].astype(float), uv[..., 1].astype(float))


def _fade(ou, ov, u, v):
    du, dv = u - ou, v - ov
    mu = np.where(du > 0, 1 - u, u)
    mv = np.where(dv > 0, 1 - v, v)
    heading = np.where(mu * np.abs(dv) <= mv * np.abs(du), mu, mv)
    nearest = np.minimum(np.minimum(u, 1 - u), np.minimum(v, 1 - v))
    edge = np.where((du == 0) & (dv == 0), nearest, heading)
    return np.clip(edge / EDGE_FADE, 0, 1)


def _seen(p):
    return p[3] > 0 and all(math.isfinite(v) for v in p)


def _usable(n):
    return all(math.isfinite(v) for v in n) and any(v != 0 for v in n)


def plane_normals(pos, nrm):
    """Each texel's plane normal: per axis the difference to the seen
    neighbour whose side predicts the texel's depth better (the line through
    its two texels, or its own depth where the second is unseen; the high one
    on a tie),
    n = cross(dx, dy) facing the shading normal's side; the shading normal
    where an axis has no seen neighbour or the texel none usable."""
    h, w = pos.shape[:2]
    out = np.array(nrm[..., :3], float)

    def seen_at(x, y):
        return pos[y, x] if 0 <= x < w and 0 <= y < h and _seen(pos[y, x]) else None

    def miss(p, a1, a2):
        return abs(2.0 * a1[2] - a2[2] - p[2]) if a2 is not None else abs(a1[2] - p[2])

    def diff(x, y, ax, ay):
        p = pos[y, x, :3]
        lo, hi = seen_at(x - ax, y - ay), seen_at(x + ax, y + ay)
        if lo is not None and hi is not None and \
                miss(p, lo, seen_at(x - 2 * ax, y - 2 * ay)) < miss(p, hi, seen_at(x + 2 * ax, y + 2 * ay)):
            hi = None
        if hi is not None:
            return hi[:3] - p
        return None if lo is None else p - lo[:3]

    for y in range(h):
        for x in range(w):
            s = nrm[y, x, :3]
            if not _seen(pos[y, x]) or not _usable(s):
                continue
            ex, ey = diff(x, y, 1, 0), diff(x, y, 0, 1)
            if ex is None or ey is None:
                continue
            c = np.cross(ex, ey)
            length = np.linalg.norm(c)
            if not (length > 0 and math.isfinite(length)):
                continue
            out[y, x] = c / length * (-1.0 if s @ c < 0 else 1.0)
    return out


def _eye(proj):
    """The incident direction rule of the core: a perspective camera mirrors
    normalize(position); any other the ray from its eye (null vector of rows 0, 1, 3)."""
    P = np.asarray(proj, float)
    if np.allclose(P[3], [0, 0, -1, 0]):
        return ("origin", None)
    _, _, vt = np.linalg.svd(P[[0, 1, 3]])
    e = vt[-1]
    if abs(e[3]) > 1e-12 * np.linalg.norm(e):
        return ("point", e[:3] / e[3])
    d = e[:3] / np.linalg.norm(e[:3])
    if P[2, :3] @ d < 0:
        d = -d
    return ("direction", d)


def trace_hiz(position, normal, projection, *, max_distance=15.0, thickness=0.5, back_position=None,
              blocked="miss"):
    pos = np.asarray(position, float)
    nrm = np.asarray(normal, float)
    back = None if back_position is None else np.asarray(back_position, float)
    P = np.asarray(projection, float)
    H_inv = np.linalg.inv(P)
    h, w = pos.shape[:2]
    eye_kind, eye = _eye(P)
    out = np.zeros((h, w, 4))
    planes = plane_normals(pos, nrm)

    def texel_thickness(x, y):
        if back is not None and _seen(back[y, x]) and -back[y, x, 2] > -pos[y, x, 2]:
            return -back[y, x, 2] + pos[y, x, 2]
        return thickness

    def plane_row(x, y):
        n = planes[y, x]
        if not _usable(n):
            return None
        p = pos[y, x, :3]
        k = n @ p
        L = n @ H_inv[:3] - k * H_inv[3]
        return L if L[2] != 0 else None

    def plane_depth(L, sx, sy):
        sz = -(L[0] * sx + L[1] * sy + L[3]) / L[2]
        v = H_inv @ np.array([sx, sy, sz, 1.0])
        return -v[2] / v[3]

    def footprint(x, y):
        d = -pos[y, x, 2]
        t = texel_thickness(x, y)
        lo = hi = d
        L = plane_row(x, y)
        if L is not None:
            spread = FOOTPRINT_SPREAD * abs(d) + t
            for cx, cy in ((x, y), (x + 1, y), (x, y + 1), (x + 1, y + 1)):
                with np.errstate(all="ignore"):
                    cd = plane_depth(L, cx * 2.0 / w - 1.0, cy * 2.0 / h - 1.0)
                if not math.isfinite(cd):
                    continue
                cd = min(max(cd, d - spread), d + spread)
                lo, hi = min(lo, cd), max(hi, cd)
        return lo, hi + t

    ranges = {}

    def known_thickness(x, y):
        """The back-face layer's thickness at (x, y), or None where it has none."""
        if back is not None and _seen(back[y, x]) and -back[y, x, 2] > -pos[y, x, 2]:
            return -back[y, x, 2] + pos[y, x, 2]
        return None

    def outline_confidence(x, y, hx, hy):
        """A neighbour across an edge that is unseen or behind the texel's plane by
        more than its thickness puts the object's edge somewhere between the two
        centres: a hit d texels toward it from the centre is on the object with
        chance 1 - d (UNCERTAIN at the texel's edge). Unless the back layer places
        the edge: the thickness, extrapolated as a line from the texel opposite that
        neighbour through this one, reaches 0 at s = t / (t_in - t) texels; a hit
        with d <= s is on the object."""
        p, n = pos[y, x, :3], planes[y, x]
        lim = -texel_thickness(x, y) * np.linalg.norm(n)
        dx, dy = hx - (x + 0.5), hy - (y + 0.5)
        t = known_thickness(x, y)

        def across(qx, qy):
            return not _seen(pos[qy, qx]) or n @ (pos[qy, qx, :3] - p) < lim

        c = 1.0
        for qx, qy, toward in ((x - 1, y, -dx), (x + 1, y, dx), (x, y - 1, -dy), (x, y + 1, dy)):
            if not (0 <= qx < w and 0 <= qy < h) or not across(qx, qy):
                continue
            d = min(max(toward, 0.0), 0.5)
            ix, iy = 2 * x - qx, 2 * y - qy
            if t is not None and 0 <= ix < w and 0 <= iy < h and not across(ix, iy):
                t_in = known_thickness(ix, iy)
                if t_in is not None and t_in > t and d * (t_in - t) <= t:
                    continue
            c = min(c, 1.0 - 2.0 * (1.0 - UNCERTAIN) * d)
        return c

    def near_ok(v):
        c = P @ np.append(v, 1.0)
        return c[2] + c[3] >= 0 and c[3] > 0

    for y in range(h):
        for x in range(w):
            p = pos[y, x]
            if not _seen(p) or not _usable(nrm[y, x, :3]):
                continue
            frm = p[:3]
            if eye_kind == "origin":
                if not frm.any():
                    continue
                inc = frm / np.linalg.norm(frm)
            elif eye_kind == "point":
                inc = (frm - eye) / np.linalg.norm(frm - eye)
            else:
                inc = eye
            n = nrm[y, x, :3] / np.linalg.norm(nrm[y, x, :3])
            r = inc - 2.0 * (n @ inc) * n
            r /= np.linalg.norm(r)
            if not near_ok(frm):
                continue
            length = max_distance
            n0 = (P[2] + P[3]) @ np.append(frm, 1.0)
            n1 = (P[2] + P[3]) @ np.append(frm + r * length, 1.0)
            if n1 < 0:
                length *= n0 / (n0 - n1)
            end = frm + r * length
            c0, c1 = P @ np.append(frm, 1.0), P @ np.append(end, 1.0)
            if not (c0[3] > 0 and c1[3] > 0) or not length > 0:
                continue
            f0 = np.array([(c0[0] / c0[3] * 0.5 + 0.5) * w, (c0[1] / c0[3] * 0.5 + 0.5) * h])
            f1 = np.array([(c1[0] / c1[3] * 0.5 + 0.5) * w, (c1[1] / c1[3] * 0.5 + 0.5) * h])
            d = f1 - f0
            a0, a1 = frm / c0[3], end / c1[3]
            b0, b1 = 1.0 / c0[3], 1.0 / c1[3]

            def exit_of(box, t_end):
                te = t_end
                for ax in range(2):
                    if d[ax] > 0:
                        te = min(te, (box[2 + ax] - f0[ax]) / d[ax])
                    elif d[ax] < 0:
                        te = min(te, (box[ax] - f0[ax]) / d[ax])
                return te

            def depth(t):
                return -(a0[2] + t * (a1[2] - a0[2])) / (b0 + t * (b1 - b0))

            t_end = exit_of((0, 0, w, h), 1.0)
            if not t_end > 0:
                continue
            t = exit_of((x, y, x + 1, y + 1), t_end)
            result = None
            while t < t_end:
                q = f0 + t * d + np.sign(d) * CELL_NUDGE
                i, j = min(max(int(math.floor(q[0])), 0), w - 1), min(max(int(math.floor(q[1])), 0), h - 1)
                te = exit_of((i, j, i + 1, j + 1), t_end)
                if not te > t:
                    te = np.nextafter(t, np.inf)
                if _seen(pos[j, i]):
                    if (i, j) not in ranges:
                        ranges[(i, j)] = footprint(i, j)
                    lo, hi = ranges[(i, j)]
                    za, zb = depth(t), depth(te)
                    if max(za, zb) >= lo and min(za, zb) <= hi:
                        outcome, th = _texel(pos, planes, i, j, t, te, a0, a1, b0, b1, f0, d, w, h,
                                             plane_row, plane_depth, texel_thickness, depth,
                                             known_thickness(i, j) is not None)
                        if outcome in ("blocked", "entered"):
                            if blocked == "occluder":  # the texel's centre, no confidence
                                result = (i + 0.5) / w, (j + 0.5) / h, outcome
                            break
                        if outcome in ("hit", "hit on plane"):
                            q = f0 + th * d
                            conf = outline_confidence(i, j, q[0], q[1]) if outcome == "hit on plane" else UNCERTAIN
                            result = q[0] / w, q[1] / h, conf
                            break
                t = te
            if result is not None:
                u, v, conf = result
                fade = float(_fade((x + 0.5) / w, (y + 0.5) / h, u, v))
                if isinstance(conf, str):  # the occluder: shown, but no hit found
                    out[y, x] = (u, v, fade, ENTERED_HIDDEN if conf == "entered" else 0.0)
                else:
                    vis = conf * fade
                    out[y, x] = (u, v, vis, vis)
    return out


def _in_front_before(pos, planes, i, j, ta, a0, a1, b0, b1, f0, d, w, h):
    """Whether the ray, entering texel (i, j) at ta, lies in front of the plane of the
    texel it came from (a CELL_NUDGE step back along each axis it moves on); True
    where that texel is off the image, unseen or has no plane."""
    q = f0 + ta * d - np.sign(d) * CELL_NUDGE
    pi, pj = int(math.floor(q[0])), int(math.floor(q[1]))
    if (pi, pj) == (i, j) or not (0 <= pi < w and 0 <= pj < h):
        return True
    o, n = pos[pj, pi], planes[pj, pi]
    if not _seen(o) or not _usable(n):
        return True
    u = n / np.linalg.norm(n)
    tol = PLANE_TOLERANCE * np.linalg.norm(o[:3])
    b = b0 + ta * (b1 - b0)
    return u @ (a0 + ta * (a1 - a0)) - (u @ o[:3]) * b >= -tol * b


def _behind_convex_neighbours(pos, planes, i, j, u, tol, t0, tb, G_of, f0, d, w, h, thick):
    """At a convex crease (the texel's and a neighbour's centres each behind the
    other's plane, by less than the texel's thickness) the surface is the farther
    of the two planes. Looks at the neighbours across the two edges nearest the
    ray's point at t0: None when the ray stays in front of one of their planes to
    tb, else the first t >= t0 at which it is behind all of them."""
    p = pos[j, i, :3]
    q = f0 + t0 * d
    t = t0
    for qi, qj in ((i - 1 if q[0] < i + 0.5 else i + 1, j), (i, j - 1 if q[1] < j + 0.5 else j + 1)):
        if not (0 <= qi < w and 0 <= qj < h):
            continue
        o, n = pos[qj, qi], planes[qj, qi]
        if not _seen(o) or not _usable(n):
            continue
        g = u @ (o[:3] - p)
        if not g < -tol or g < -thick:  # not behind this texel's plane, or an outline
            continue
        qu = n / np.linalg.norm(n)
        qtol = PLANE_TOLERANCE * np.linalg.norm(o[:3])
        if not qu @ (p - o[:3]) < -qtol:  # concave or flat: this texel's plane is the nearer
            continue
        G, B = G_of(qu, qu @ o[:3])
        qa, qb = G(t), G(tb)
        if qa < -qtol * B(t):
            continue
        if not qb < -qtol * B(tb):
            return None
        t = t + (tb - t) * min(max(qa / (qa - qb), 0.0), 1.0)
    return t


def _texel(pos, planes, i, j, ta, tb, a0, a1, b0, b1, f0, d, w, h, plane_row, plane_depth,
           texel_thickness, depth, thickness_known):
    n = planes[j, i]
    if not _usable(n):
        return "hit", ta
    u = n / np.linalg.norm(n)
    p = pos[j, i, :3]
    np_ = u @ p
    tol = PLANE_TOLERANCE * np.linalg.norm(p)

    def G_of(uu, k):
        def G(t):
            return uu @ (a0 + t * (a1 - a0)) - k * (b0 + t * (b1 - b0))
        return G, B

    def B(t):
        return b0 + t * (b1 - b0)

    G = G_of(u, np_)[0]
    ga, gb = G(ta), G(tb)
    a_behind, b_behind = ga < -tol * B(ta), gb < -tol * B(tb)
    if not a_behind and not b_behind:
        return "pass", ta
    thick = texel_thickness(i, j)

    def off(t, guessed=False):
        """Further from the texel's own depth, in front or behind, than CROSSING_DEPTH
        times its thickness: off the object, whatever its tangent plane says (edge-on
        at a rounded object's outline). The back layer's thickness; the guessed one
        too with ``guessed`` (a ray behind the plane, not a crossing of it)."""
        return (thickness_known or guessed) and thick > 0 and abs(depth(t) + p[2]) > CROSSING_DEPTH * thick

    if not a_behind:
        f = min(max(ga / (ga - gb), 0.0), 1.0)
        t = _behind_convex_neighbours(pos, planes, i, j, u, tol, ta + (tb - ta) * f, tb, G_of, f0, d, w, h, thick)
        return ("pass", ta) if t is None or off(t) else ("hit on plane", t)
    t = _behind_convex_neighbours(pos, planes, i, j, u, tol, ta, tb, G_of, f0, d, w, h, thick)
    if t is None:
        return "pass", ta
    if t > ta:  # in front of a convex neighbour's plane when it entered: a crossing later, if any
        return ("hit on plane", t) if G(t) < -tol * B(t) and not off(t) else ("pass", ta)
    if off(ta, guessed=True):
        return "pass", ta
    L = plane_row(i, j)
    if L is None:
        return "hit", ta

    def behind_by(t):
        q = f0 + t * d
        return depth(t) - plane_depth(L, q[0] * 2.0 / w - 1.0, q[1] * 2.0 / h - 1.0)

    slack = BEHIND_SLACK * abs(p[2])
    da = behind_by(ta)
    if da <= slack:
        return "hit on plane", ta
    if da <= thick:  # inside: came in by the side it is nearer to, from the texel's own depth
        if depth(ta) + p[2] > HIDDEN_SHARE * thick:
            return "entered", ta
        # nearer the front: a crossing found late, reported as a hit where the ray
        # entered when the back layer gives the thickness, the ray stays behind the
        # plane to the exit and was in front of the previous texel's surface
        if b_behind and thickness_known and _in_front_before(pos, planes, i, j, ta, a0, a1, b0, b1, f0, d, w, h):
            return "hit on plane", ta
        return "blocked", ta
    if b_behind and behind_by(tb) <= thick:
        return "entered", tb
    return "pass", ta


# The reuse of rays at resolution <= 0.5 (docs/hiz.md, "Reusing neighbours'
# rays"), written from that description: pixels with both coordinates even keep
# their own ray's result; any other pixel takes its traced neighbours' common
# miss, or the mean of their hits when those lie within 3 pixels of each other
# and are of one kind (hits, occluders, hidden sides), or are all real hits
# within 6 pixels, with visibilities within 0.1, whose texels and the mean's
# texel lie on the first hit texel's plane (then with their mean visibility);
# provided that all of them lie on its own smooth surface; else
# its own ray's.
REUSE_COS, REUSE_DEPTH, REUSE_PIXELS = _S.REUSE_COS, _S.REUSE_DEPTH, _S.REUSE_PIXELS
REUSE_SPAN_PIXELS, REUSE_SPAN_VISIBILITY = _S.REUSE_SPAN_PIXELS, _S.REUSE_SPAN_VISIBILITY


def _kind(r):
    """A hit (1), an occluder found late (0), a hidden side entered (-1): neighbours
    of different kinds are not merged."""
    return 1 if r[3] > 0 else (0 if r[3] == 0 else -1)


def reuse_rays(position, normal, full):
    """The reused-ray result, given ``full``: every pixel's own-ray result (trace_hiz)."""
    h, w = full.shape[:2]
    out = np.array(full, dtype=np.float64)
    pos = np.asarray(position, np.float64)
    nrm = np.asarray(normal, np.float64)[..., :3]

    def texel(uv):
        i, j = math.floor(uv[0] * w), math.floor(uv[1] * h)
        return (j, i) if 0 <= i < w and 0 <= j < h else None

    def normals_agree(n, m):
        d = float(np.dot(n, m))
        return d > 0 and d * d >= REUSE_COS ** 2 * float(np.dot(n, n)) * float(np.dot(m, m))

    def on_plane(a, b):
        """The texel under uv b lies on the plane of the texel under uv a."""
        ta, tb = texel(a), texel(b)
        if ta is None or tb is None or not _seen(pos[ta]) or not _seen(pos[tb]):
            return False
        n = nrm[ta]
        if not normals_agree(n, nrm[tb]):
            return False
        return abs(float(np.dot(n, pos[tb][:3] - pos[ta][:3]))) <= REUSE_DEPTH * abs(pos[ta][2]) * math.sqrt(float(np.dot(n, n)))

    def same_surface(y, x, qy, qx):
        if not (0 <= qx < w and 0 <= qy < h):
            return False
        p, q = pos[y, x], pos[qy, qx]
        if not _seen(q) or not abs(q[2] - p[2]) <= REUSE_DEPTH * abs(p[2]):
            return False
        return normals_agree(nrm[y, x], nrm[qy, qx])

    for y in range(h):
        for x in range(w):
            if x % 2 == 0 and y % 2 == 0:
                continue
            if not _seen(pos[y, x]) or not all(math.isfinite(v) for v in nrm[y, x]):
                continue
            if y % 2 == 0:
                qs = [(y, x - 1), (y, x + 1)]
            elif x % 2 == 0:
                qs = [(y - 1, x), (y + 1, x)]
            else:
                qs = [(y - 1, x - 1), (y - 1, x + 1), (y + 1, x - 1), (y + 1, x + 1)]
            if not all(same_surface(y, x, qy, qx) for qy, qx in qs):
                continue
            got = [full[qy, qx] for qy, qx in qs]
            hits = [g for g in got if g[2] > 0]
            if not hits:
                out[y, x] = 0.0
                continue
            if len(hits) < len(got) or len({_kind(g) for g in got}) != 1:
                continue
            spread = max(math.hypot((a[0] - b[0]) * w, (a[1] - b[1]) * h) for a in got for b in got)
            mean = (np.mean([g[0] for g in got]), np.mean([g[1] for g in got]))
            if spread <= REUSE_PIXELS:
                out[y, x] = (mean[0], mean[1], min(g[2] for g in got), min(g[3] for g in got))
            elif (_kind(got[0]) == 1 and spread <= REUSE_SPAN_PIXELS
                  and max(g[2] for g in got) - min(g[2] for g in got) <= REUSE_SPAN_VISIBILITY
                  and all(on_plane(got[0], b) for b in got[1:] + [mean])):
                vis = np.mean([g[2] for g in got])  # on one plane, the mean visibility
                out[y, x] = (mean[0], mean[1], vis, vis)
    return out

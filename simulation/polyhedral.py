"""Image sources in a room of planar reflectors: polygonal walls and obstacle faces.

The shoebox's image sources (:mod:`simulation.multipath`) are all visible from every
node. In a polygonal room (L, T, U shapes) or around obstacles they are not: a reflection
point may fall off its wall, and a wall or an obstacle may stand between two points of a
path. This module follows Borish's image-source method (J. Acoust. Soc. Am. 75, 1984),
as pyroomacoustics' general rooms do:

1. **Reflectors** (:func:`reflectors`): every wall (the vertical rectangle over a floor-plan
   edge), the floor and the ceiling (the floor plan at z = 0 and z = height), and every
   obstacle face that is not on the room's boundary; each a plane n·x = d with its normal
   n into the air, and its amplitude β = √(1 − α).
2. **Images** (:func:`images`, per anchor, before the nodes): the image of a source in a
   reflector's plane, for every sequence of up to ``max_order`` reflections (no reflector
   twice in a row, at most ``obstacle_order`` on obstacle faces). An image is kept only if
   the image it mirrors lies on the air side of the reflector (the validity test: a path
   cannot reflect off the back of a wall), which prunes most sequences before any node.
3. **Paths** (:func:`paths`, per node and image): the path is traced back from the node to
   the image; each reflection point must lie on its reflector (within the wall rectangle,
   the floor-plan polygon or the obstacle face) and between its neighbours, and no
   segment of the path may cross another wall (in a non-convex room) or an obstacle face.
   The direct path is always path 0: its amplitude is 0 when something blocks it (no line
   of sight), and the other paths are simulated as they are, so that the receiver picks
   whatever arrives.

A path's amplitude is Π β · g(cos θ) · exp(−a·L/2) / (4π L), L its length (node to final
image), θ the angle of its first segment from the speaker's aim, as for the shoebox. The
loops over nodes, images and reflectors are compiled (numba) with early exits.
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from simulation import floorplan

#: reflector kinds: a wall rectangle over a floor-plan edge, the floor or ceiling polygon,
#: an axis-aligned obstacle face
WALL, PLAN, FACE = 0, 1, 2
#: a reflection point closer than this (m) to an end of its segment does not count, and a
#: crossing this close to a segment's end does not block it
EPS = 1e-9
#: (m) a face whose plane passes this close to an anchor counts as facing it (:func:`facing`)
FRONT_TOL = 1e-9


@dataclass(frozen=True)
class Reflectors:
    """The room's reflectors as arrays (F of them).

    kind (F,) int: :data:`WALL`, :data:`PLAN` or :data:`FACE`; normal (F, 3) unit, into
    the air; d (F,) the plane n·x = d; box (F, 6): a wall's edge (x0, y0, x1, y1) and its
    height range (z0, z1), a plan's z in box[:, 4], a face's (lo xyz, hi xyz); beta (F,)
    reflection amplitudes; obstacle (F,) bool; blocking (F,) bool: may stand between two
    points of the room (walls of a non-convex room, obstacle faces); plan (n, 2) the floor
    plan's corners; names (F,) for reports.
    """

    kind: np.ndarray
    normal: np.ndarray
    d: np.ndarray
    box: np.ndarray
    beta: np.ndarray
    obstacle: np.ndarray
    blocking: np.ndarray
    plan: np.ndarray
    names: tuple[str, ...]

    def __len__(self) -> int:
        return len(self.kind)


def reflectors(room) -> Reflectors:
    """The reflectors of a room (module docstring, step 1), walls first (corner order),
    then floor and ceiling, then obstacle faces."""
    corners = room.floor_corners
    h = room.size[2]
    rows = []  # (kind, normal, d, box, alpha, obstacle, blocking, name)
    concave = not room.is_convex
    for w in room.walls:
        n = w.normal
        rows.append((WALL, n, float(n[:2] @ w.start), [*w.start, *w.end, 0.0, h],
                     room.absorption[w.name], False, concave, w.name))  # fmt: skip
    for name, z, nz in (("floor", 0.0, 1.0), ("ceiling", h, -1.0)):
        rows.append((PLAN, np.array([0.0, 0.0, nz]), nz * z, [0, 0, 0, 0, z, 0],
                     room.absorption[name], False, False, name))  # fmt: skip
    shoebox = None if room.is_shoebox else corners
    for k, ob in enumerate(room.obstacles):
        for axis, side, flo, fhi in floorplan.face_rectangles(ob):
            if floorplan.on_boundary(axis, flo[axis], flo, fhi, room.size, shoebox):
                continue
            n = np.zeros(3)
            n[axis] = -1.0 if side == 0 else 1.0
            label = f"{ob.name or f'obstacle-{k}'}:{'-+'[side]}{'xyz'[axis]}"
            rows.append((FACE, n, float(n @ flo), [*flo, *fhi], ob.absorption, True, True,
                         label))  # fmt: skip
    kind, normal, d, box, alpha, obstacle, blocking, names = zip(*rows, strict=True)
    return Reflectors(
        kind=np.array(kind, dtype=np.int64),
        normal=np.array(normal, dtype=float),
        d=np.array(d, dtype=float),
        box=np.array(box, dtype=float),
        beta=np.sqrt(1.0 - np.array(alpha, dtype=float)),
        obstacle=np.array(obstacle, dtype=bool),
        blocking=np.array(blocking, dtype=bool),
        plan=np.ascontiguousarray(corners, dtype=float),
        names=tuple(names),
    )


def images(refl: Reflectors, source, max_order: int, obstacle_order: int):
    """The valid images of one source (3,) (module docstring, step 2).

    Returns (chain (I, K + 1, 3), seq (I, K), order (I,), beta (I,)): chain[i, j] the
    image after the first j reflections of sequence i (chain[i, 0] the source), seq[i, j]
    the reflector of reflection j + 1 (−1 past the order), and the product of the βs.
    Image 0 is the source itself (the direct path).
    """
    K = int(max_order)
    src = np.asarray(source, dtype=float)
    chain = np.zeros((1, K + 1, 3))
    chain[0, :] = src
    seq = np.full((1, K), -1, dtype=np.int64)
    order = np.zeros(1, dtype=np.int64)
    beta = np.ones(1)
    nobs = np.zeros(1, dtype=np.int64)
    out = [(chain, seq, order, beta)]
    last = (chain, seq, beta, nobs, np.full(1, -1, dtype=np.int64))
    for j in range(1, K + 1):
        ch, sq, bt, nb, prev = last
        pos = ch[:, j - 1]  # (n, 3) the images to mirror
        sd = pos @ refl.normal.T - refl.d  # (n, F) signed distance, > 0 on the air side
        ok = (sd > EPS) & (np.arange(len(refl))[None, :] != prev[:, None])
        ok &= (nb[:, None] + refl.obstacle[None, :]) <= obstacle_order
        ok &= refl.beta[None, :] > 0
        src_i, f = np.nonzero(ok)
        if not src_i.size:
            break
        new = ch[src_i].copy()
        mirrored = pos[src_i] - 2.0 * sd[src_i, f][:, None] * refl.normal[f]
        new[:, j:] = mirrored[:, None, :]
        nsq = sq[src_i].copy()
        nsq[:, j - 1] = f
        nbt = bt[src_i] * refl.beta[f]
        nnb = nb[src_i] + refl.obstacle[f]
        out.append((new, nsq, np.full(len(f), j, dtype=np.int64), nbt))
        last = (new, nsq, nbt, nnb, f)
    return tuple(np.concatenate([o[k] for o in out]) for k in range(4))


def image_count(room, obstacle_order: int | None = None, refl: Reflectors | None = None) -> int:
    """The valid images (step 2 of the module docstring, the direct path included) of an
    anchor on the ceiling above a point inside the floor plan, with at most ``obstacle_order``
    reflections on obstacle faces (None: the room's): what the paths of every anchor–node
    pair are traced against, so what a simulation in the room costs. ``refl``: the room's
    :func:`reflectors`, when the caller has them."""
    from shapely import Polygon

    c = Polygon(room.corners).representative_point() if room.corners is not None else None
    x, y = (c.x, c.y) if c is not None else (room.size[0] / 2, room.size[1] / 2)
    order = room.obstacle_order if obstacle_order is None else obstacle_order
    source = np.array([x, y, room.size[2] - room.anchor_offset])
    refl = reflectors(room) if refl is None else refl
    return len(images(refl, source, room.max_order, order)[0])


@numba.njit(cache=True, inline="always")
def _in_plan(plan, x, y):  # pragma: no cover - compiled
    """Point (x, y) in the floor plan (even-odd ray casting)."""
    n = plan.shape[0]
    inside = False
    j = n - 1
    for i in range(n):
        yi, yj = plan[i, 1], plan[j, 1]
        if (yi > y) != (yj > y):
            xi, xj = plan[i, 0], plan[j, 0]
            if x < xi + (y - yi) * (xj - xi) / (yj - yi):
                inside = not inside
        j = i
    return inside


@numba.njit(cache=True, inline="always")
def _on_reflector(kind, box, plan, f, p0, p1, p2, tol):  # pragma: no cover - compiled
    """Whether a point of reflector f's plane lies on the reflector."""
    k = kind[f]
    if k == 0:  # wall rectangle over the edge (x0, y0) → (x1, y1)
        ex, ey = box[f, 2] - box[f, 0], box[f, 3] - box[f, 1]
        s = ((p0 - box[f, 0]) * ex + (p1 - box[f, 1]) * ey) / (ex * ex + ey * ey)
        return -tol <= s <= 1.0 + tol and box[f, 4] - tol <= p2 <= box[f, 5] + tol
    if k == 1:
        return _in_plan(plan, p0, p1)
    return (
        box[f, 0] - tol <= p0 <= box[f, 3] + tol
        and box[f, 1] - tol <= p1 <= box[f, 4] + tol
        and box[f, 2] - tol <= p2 <= box[f, 5] + tol
    )


@numba.njit(cache=True, inline="always")
def _blocked(a0, a1, a2, b0, b1, b2, kind, normal, d, box, blocking, plan, skip1, skip2):
    # pragma: no cover - compiled
    """Whether the open segment a → b crosses a blocking reflector (other than skip1/2).
    A blocking reflector is a wall (box: its edge and height) or a face (box: lo, hi): the
    segment's bounding box must meet the reflector's before the plane is intersected."""
    v0, v1, v2 = b0 - a0, b1 - a1, b2 - a2
    s_lo0, s_hi0 = min(a0, b0), max(a0, b0)
    s_lo1, s_hi1 = min(a1, b1), max(a1, b1)
    s_lo2, s_hi2 = min(a2, b2), max(a2, b2)
    for g in range(kind.shape[0]):
        if not blocking[g] or g == skip1 or g == skip2:
            continue
        if kind[g] == 0:  # wall: x between its ends, y likewise, z within its height
            r_lo0, r_hi0 = min(box[g, 0], box[g, 2]), max(box[g, 0], box[g, 2])
            r_lo1, r_hi1 = min(box[g, 1], box[g, 3]), max(box[g, 1], box[g, 3])
            r_lo2, r_hi2 = box[g, 4], box[g, 5]
        else:
            r_lo0, r_hi0 = box[g, 0], box[g, 3]
            r_lo1, r_hi1 = box[g, 1], box[g, 4]
            r_lo2, r_hi2 = box[g, 2], box[g, 5]
        if (s_hi0 < r_lo0 or s_lo0 > r_hi0 or s_hi1 < r_lo1 or s_lo1 > r_hi1
                or s_hi2 < r_lo2 or s_lo2 > r_hi2):  # fmt: skip
            continue
        den = normal[g, 0] * v0 + normal[g, 1] * v1 + normal[g, 2] * v2
        if abs(den) < 1e-15:
            continue
        t = (d[g] - (normal[g, 0] * a0 + normal[g, 1] * a1 + normal[g, 2] * a2)) / den
        if t <= EPS or t >= 1.0 - EPS:
            continue
        if _on_reflector(kind, box, plan, g, a0 + t * v0, a1 + t * v1, a2 + t * v2, 1e-12):
            return True
    return False


@numba.njit(cache=True, inline="always")
def _trace(q0, q1, q2, chain, seq, i, order, kind, normal, d, box, blocking, plan, pts):
    # pragma: no cover - compiled
    """Trace image i's path back from the node (q0, q1, q2) (module docstring, step 3):
    first every reflection point on its reflector (cheap, most images fail here), then no
    segment blocked. Returns whether the path is valid; ``pts`` (K + 2, 3) then holds its
    points from the node (row 0) to the source (row order + 1)."""
    pts[0, 0], pts[0, 1], pts[0, 2] = q0, q1, q2
    t0, t1, t2 = q0, q1, q2
    for j in range(order, 0, -1):
        f = seq[i, j - 1]
        v0, v1, v2 = chain[i, j, 0] - t0, chain[i, j, 1] - t1, chain[i, j, 2] - t2
        den = normal[f, 0] * v0 + normal[f, 1] * v1 + normal[f, 2] * v2
        if abs(den) < 1e-15:
            return False
        t = (d[f] - (normal[f, 0] * t0 + normal[f, 1] * t1 + normal[f, 2] * t2)) / den
        if t <= EPS or t >= 1.0 - EPS:
            return False
        t0, t1, t2 = t0 + t * v0, t1 + t * v1, t2 + t * v2
        if not _on_reflector(kind, box, plan, f, t0, t1, t2, 1e-12):
            return False
        k = order - j + 1
        pts[k, 0], pts[k, 1], pts[k, 2] = t0, t1, t2
    k = order + 1
    pts[k, 0], pts[k, 1], pts[k, 2] = chain[i, 0, 0], chain[i, 0, 1], chain[i, 0, 2]
    # segment r runs from pts[r] to pts[r + 1]; its ends lie on the reflectors of
    # reflections order − r + 1 and order − r (none at the node and at the source)
    for r in range(order + 1):
        s1 = seq[i, order - r] if r > 0 else -1
        s2 = seq[i, order - r - 1] if r < order else -1
        if _blocked(pts[r, 0], pts[r, 1], pts[r, 2], pts[r + 1, 0], pts[r + 1, 1],
                    pts[r + 1, 2], kind, normal, d, box, blocking, plan, s1, s2):  # fmt: skip
            return False
    return True


@numba.njit(cache=True)
def _anchor_paths(nodes, lo, hi, chain, seq, order, kind, normal, d, box, blocking, plan,
                  out_node, out_image, out_first):  # fmt: skip
    # pragma: no cover - compiled
    """The valid reflected paths of one anchor's images ``lo + 1 … hi − 1`` at every node,
    appended as (node, image, first reflection point) rows to the ``out_*`` arrays.
    Images outer, nodes inner: the last reflection is tested first from signed distances
    (a node behind the last reflector, or a reflection point off it, ends the trace).
    Returns the number of rows, or −1 when the arrays are full."""
    P = nodes.shape[0]
    cap = out_node.shape[0]
    n_out = 0
    pts = np.empty((seq.shape[1] + 2, 3))
    for i in range(lo + 1, hi):
        k = order[i]
        f = seq[i, k - 1]
        n0, n1, n2 = normal[f, 0], normal[f, 1], normal[f, 2]
        img0, img1, img2 = chain[i, k, 0], chain[i, k, 1], chain[i, k, 2]
        di = n0 * img0 + n1 * img1 + n2 * img2 - d[f]  # < 0: the image is behind it
        for p in range(P):
            q0, q1, q2 = nodes[p, 0], nodes[p, 1], nodes[p, 2]
            dp = n0 * q0 + n1 * q1 + n2 * q2 - d[f]
            if dp <= EPS:
                continue
            t = dp / (dp - di)
            x0 = q0 + t * (img0 - q0)
            x1 = q1 + t * (img1 - q1)
            x2 = q2 + t * (img2 - q2)
            if not _on_reflector(kind, box, plan, f, x0, x1, x2, 1e-12):
                continue
            if k >= 2:  # the reflection before it, the same way, before the full trace
                g = seq[i, k - 2]
                dx = normal[g, 0] * x0 + normal[g, 1] * x1 + normal[g, 2] * x2 - d[g]
                dg = (normal[g, 0] * chain[i, k - 1, 0] + normal[g, 1] * chain[i, k - 1, 1]
                      + normal[g, 2] * chain[i, k - 1, 2] - d[g])  # fmt: skip
                if dx <= EPS or dg >= 0.0:
                    continue
                u = dx / (dx - dg)
                if not _on_reflector(kind, box, plan, g, x0 + u * (chain[i, k - 1, 0] - x0),
                                     x1 + u * (chain[i, k - 1, 1] - x1),
                                     x2 + u * (chain[i, k - 1, 2] - x2), 1e-12):  # fmt: skip
                    continue
            if not _trace(q0, q1, q2, chain, seq, i, k, kind, normal, d, box, blocking, plan,
                          pts):  # fmt: skip
                continue
            if n_out == cap:
                return -1
            out_node[n_out] = p
            out_image[n_out] = i
            out_first[n_out, 0] = pts[k, 0]
            out_first[n_out, 1] = pts[k, 1]
            out_first[n_out, 2] = pts[k, 2]
            n_out += 1
    return n_out


@numba.njit(cache=True)
def _direct_los(nodes, source, kind, normal, d, box, blocking, plan):  # pragma: no cover
    """(P,) bool: the segment from each node to the source is not blocked."""
    out = np.empty(nodes.shape[0], dtype=np.bool_)
    for p in range(nodes.shape[0]):
        out[p] = not _blocked(nodes[p, 0], nodes[p, 1], nodes[p, 2], source[0], source[1],
                              source[2], kind, normal, d, box, blocking, plan, -1, -1)  # fmt: skip
    return out


@numba.njit(cache=True)
def _hidden_used(x, layouts, owner, used, front, kind, normal, d, box, blocking, plan):
    # pragma: no cover - compiled
    """(N, M) bool: the segment from point x[i] to anchor j of layout owner[i] is blocked,
    tested only where used[i, j] (False elsewhere), on the faces the anchor faces (front
    (L, M, F), :func:`facing`)."""
    out = np.zeros(used.shape, dtype=np.bool_)
    for i in range(x.shape[0]):
        a = layouts[owner[i]]
        for j in range(used.shape[1]):
            if used[i, j]:
                out[i, j] = _blocked(x[i, 0], x[i, 1], x[i, 2], a[j, 0], a[j, 1], a[j, 2], kind,
                                     normal, d, box, front[owner[i], j], plan, -1,
                                     -1)  # fmt: skip
    return out


def hidden_anchors(room, layouts, owner, points, used) -> np.ndarray:
    """(N, M) bool: anchor j of layout ``owner[i]`` (layouts (L, M, 3)) is used by point i
    (points (N, 3), used (N, M)) and something of the room blocks the straight segment
    between them (as :func:`line_of_sight` tests it; only the used pairs are tested)."""
    used = np.ascontiguousarray(used, dtype=bool)
    if room.is_convex and not room.obstacles:
        return np.zeros(used.shape, dtype=bool)
    layouts = np.ascontiguousarray(layouts, dtype=float)
    return _hidden_used(np.ascontiguousarray(points, dtype=float), layouts,
                        np.ascontiguousarray(owner, dtype=np.int64), used,
                        facing(room, layouts), *blocking_map(room))  # fmt: skip


def paths(room, anchors: np.ndarray, nodes: np.ndarray, refl: Reflectors | None = None):
    """The valid paths from anchors (M, 3) to nodes (P, 3) (module docstring, step 3).

    Returns (length (P, M, I), first (P, M, I, 3), beta (P, M, I), valid (P, M, I),
    los (P, M)): path lengths (m), unit directions of each path's first segment from the
    anchor, the product of its reflections' β, which entries are paths (the rest padding),
    and whether the direct path is unobstructed. Path 0 is the direct path.
    """
    refl = reflectors(room) if refl is None else refl
    a = np.asarray(anchors, dtype=float)
    p = np.ascontiguousarray(nodes, dtype=float)
    P, M = len(p), len(a)
    geo = (refl.kind, refl.normal, refl.d, refl.box, refl.blocking, refl.plan)
    rows = []  # per anchor: (node, image, first point, chain, order, beta)
    for m, src in enumerate(a):
        chain, seq, order, beta = images(refl, src, room.max_order, room.obstacle_order)
        chain, seq = np.ascontiguousarray(chain), np.ascontiguousarray(seq)
        cap = max(256, 64 * P)  # about the paths per node of a reverberant room
        while True:
            node = np.empty(cap, dtype=np.int64)
            image = np.empty(cap, dtype=np.int64)
            first = np.empty((cap, 3))
            n = _anchor_paths(p, 0, len(chain), chain, seq, order, *geo, node, image, first)
            if n >= 0:
                break
            cap *= 4
        rows.append((m, node[:n], image[:n], first[:n], chain, order, beta))
    counts = np.ones((P, M), dtype=np.int64)  # the direct path's slot
    for m, node, *_ in rows:
        counts[:, m] += np.bincount(node, minlength=P)
    width = int(counts.max())
    length = np.zeros((P, M, width))
    direction = np.zeros((P, M, width, 3))
    b = np.zeros((P, M, width))
    valid = np.zeros((P, M, width), dtype=bool)
    los = np.empty((P, M), dtype=bool)
    for m, node, image, first, chain, order, beta in rows:
        src = a[m]
        v = p - src
        dist = np.linalg.norm(v, axis=1)
        length[:, m, 0] = dist
        direction[:, m, 0] = v / np.where(dist > 0, dist, 1.0)[:, None]
        los[:, m] = _direct_los(p, src, *geo)
        b[:, m, 0] = np.where(los[:, m], 1.0, 0.0)
        valid[:, m, 0] = True
        if not len(node):
            continue
        # slot of each row: 1 + its rank among its node's rows (rows come image by image)
        orderk = np.argsort(node, kind="stable")
        sorted_node = node[orderk]
        starts = np.searchsorted(sorted_node, sorted_node, side="left")
        slot = np.empty(len(node), dtype=np.int64)
        slot[orderk] = 1 + np.arange(len(node)) - starts
        img = chain[image, order[image]]
        length[node, m, slot] = np.linalg.norm(p[node] - img, axis=1)
        fv = first - src
        fn = np.linalg.norm(fv, axis=1)
        direction[node, m, slot] = fv / np.where(fn > 0, fn, 1.0)[:, None]
        b[node, m, slot] = beta[image]
        valid[node, m, slot] = True
    return length, direction, b, valid, los


#: the map of a room where nothing blocks a path (:func:`blocking_map`)
NO_MAP = (np.empty(0, dtype=np.int64), np.empty((0, 3)), np.empty(0), np.empty((0, 6)),
          np.empty(0, dtype=bool), np.empty((0, 2)))  # fmt: skip


#: the last room :func:`blocking_map` mapped and its map: a plan locates thousands of
#: batches in one room, and a room (frozen) does not change
_LAST_MAP: tuple = (None, NO_MAP)


def blocking_map(room) -> tuple:
    """The room's map of what can block a straight path, for :func:`sees`: (kind, normal,
    d, box, blocking, plan) of its blocking reflectors (walls of a non-convex floor plan,
    obstacle faces); empty arrays where nothing can block (a convex room without
    obstacles). The arrays are shared between calls for the same room: read them only."""
    global _LAST_MAP
    last, geo = _LAST_MAP  # one read: another thread may replace the pair
    if last is room:
        return geo
    geo = NO_MAP if room.is_convex and not room.obstacles else _map(room)
    _LAST_MAP = (room, geo)
    return geo


def facing(room, layouts) -> np.ndarray:
    """(L, M, F) bool: face f of the room's map (:func:`blocking_map`, F faces) can block a
    straight path to anchor j of ``layouts`` (L, M, 3) m, for :func:`sees_near`'s
    ``front``: the anchor lies on the face's air side. A path from an anchor in the air
    that crosses anything of the room leaves the air first through a face the anchor lies
    in front of, so a face behind the anchor never decides whether the path is blocked
    (the answers are those of all faces). An anchor outside the air (outside the room or
    inside an obstacle) keeps every face."""
    _, normal, d, *_ = blocking_map(room)
    a = np.asarray(layouts, dtype=float)
    front = np.einsum("lmk,fk->lmf", a, normal) - d > -FRONT_TOL
    if normal.shape[0]:
        in_air = room.contains(a.reshape(-1, 3)).reshape(a.shape[:-1])
        front |= ~in_air[..., None]
    return np.ascontiguousarray(front)


def _map(room) -> tuple:
    refl = reflectors(room)
    keep = refl.blocking
    return (np.ascontiguousarray(refl.kind[keep]), np.ascontiguousarray(refl.normal[keep]),
            np.ascontiguousarray(refl.d[keep]), np.ascontiguousarray(refl.box[keep]),
            np.ones(int(keep.sum()), dtype=bool), refl.plan)  # fmt: skip


@numba.njit(cache=True, inline="always")
def sees(geo, p, q) -> bool:  # pragma: no cover - compiled
    """Nothing of the map ``geo`` (:func:`blocking_map`) blocks the segment p (3,) → q (3,)."""
    kind, normal, d, box, blocking, plan = geo
    if kind.shape[0] == 0:
        return True
    return not _blocked(p[0], p[1], p[2], q[0], q[1], q[2], kind, normal, d, box, blocking,
                        plan, -1, -1)  # fmt: skip


@numba.njit(cache=True, inline="always")
def sees_near(geo, p, q, front, delta, every) -> bool:  # pragma: no cover - compiled
    """:func:`sees` from p (3,) and the six points ``delta`` m from p along the axes: from
    one of them (``every`` False: a position known to within centimetres does not hide an
    anchor it grazes) or from all (``every`` True: the anchor surely sees it); only the
    faces of the map that the anchor q (3,) faces are tested (``front`` (F,),
    :func:`facing`). A point across a face of the map from p (in a wall or an obstacle
    beside a position near it) is no place the tag can be, and is not tested. ``geo``: the
    room's map (:func:`blocking_map`), or a tuple that begins with it."""
    kind, normal, d, box, blocking, plan = geo[0], geo[1], geo[2], geo[3], geo[4], geo[5]
    if kind.shape[0] == 0:
        return True
    for k in range(7):
        o0 = delta * ((k == 1) - (k == 2))
        o1 = delta * ((k == 3) - (k == 4))
        o2 = delta * ((k == 5) - (k == 6))
        n0, n1, n2 = p[0] + o0, p[1] + o1, p[2] + o2
        free = not _blocked(n0, n1, n2, q[0], q[1], q[2], kind, normal, d, box, front, plan, -1,
                            -1)  # fmt: skip
        if free != every:
            if k > 0 and _blocked(p[0], p[1], p[2], n0, n1, n2, kind, normal, d, box,
                                  blocking, plan, -1, -1):  # fmt: skip
                continue  # the point is in a wall or an obstacle: it decides nothing
            return free
    return every


def line_of_sight(room, anchors, points) -> np.ndarray:
    """(..., P, M) bool: nothing blocks the straight segment from each point (P, 3) to
    each anchor (..., M, 3) (walls of a non-convex floor plan, obstacle faces). All true
    in a shoebox without obstacles."""
    a = np.asarray(anchors, dtype=float)
    p = np.ascontiguousarray(points, dtype=float)
    out_shape = (*a.shape[:-2], p.shape[0], a.shape[-2])
    if room.is_shoebox and not room.obstacles:
        return np.ones(out_shape, dtype=bool)
    geo = blocking_map(room)  # the blocking reflectors alone: what _blocked tests
    flat = a.reshape(-1, 3)
    cols = [_direct_los(p, np.ascontiguousarray(s), *geo) for s in flat]
    los = np.stack(cols, axis=-1) if cols else np.zeros((p.shape[0], 0), dtype=bool)
    lead = a.shape[:-2]
    M = a.shape[-2]
    los = los.reshape(p.shape[0], *lead, M)
    return np.moveaxis(los, 0, -2) if lead else los

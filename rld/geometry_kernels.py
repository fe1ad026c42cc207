"""numba kernels for the 2D geometry that the searches call in their inner loops.

Every function here takes plain floats or contiguous ``float64`` arrays and is compiled with
``cache=True``. The public, vectorized numpy interface is ``rld.geometry``; the searches
(``clc``) call these kernels directly from their own compiled code.

Conventions: a segment is given by its two endpoints; a zero-length segment is a point.
Tolerances are absolute, in metres (``EPS``), far below any cone-position accuracy.
"""

from __future__ import annotations

import math

import numpy as np

from rld._jit import njit

EPS = 1e-9


@njit(cache=True)
def cross2(ax, ay, bx, by):
    """z-component of the cross product of 2D vectors a and b."""
    return ax * by - ay * bx


@njit(cache=True)
def orient(ax, ay, bx, by, cx, cy):
    """Twice the signed area of triangle abc: > 0 counter-clockwise, < 0 clockwise."""
    return (bx - ax) * (cy - ay) - (by - ay) * (cx - ax)


@njit(cache=True)
def point_segment_param(px, py, ax, ay, bx, by):
    """Closest point on segment ab to p: returns (distance, t) with the point a + t (b - a),
    t in [0, 1] (t = 0 for a zero-length segment)."""
    dx = bx - ax
    dy = by - ay
    ll = dx * dx + dy * dy
    t = 0.0
    if ll > 0.0:
        t = ((px - ax) * dx + (py - ay) * dy) / ll
        if t < 0.0:
            t = 0.0
        elif t > 1.0:
            t = 1.0
    qx = ax + t * dx - px
    qy = ay + t * dy - py
    return math.sqrt(qx * qx + qy * qy), t


@njit(cache=True)
def point_segment_distance(px, py, ax, ay, bx, by):
    """Euclidean distance from point p to segment ab, metres."""
    d, _ = point_segment_param(px, py, ax, ay, bx, by)
    return d


@njit(cache=True)
def segment_parameter(px, py, ax, ay, bx, by):
    """Where the foot of p on the line through a-b lies: 0 at a, 1 at b, unclamped (a
    zero-length segment: its squared length floored at 1e-18 m^2)."""
    dx = bx - ax
    dy = by - ay
    return ((px - ax) * dx + (py - ay) * dy) / max(dx * dx + dy * dy, 1e-18)


@njit(cache=True)
def _on_segment(px, py, ax, ay, bx, by):
    """p, known collinear with ab, lies within ab's bounding box."""
    return (
        min(ax, bx) - EPS <= px <= max(ax, bx) + EPS
        and min(ay, by) - EPS <= py <= max(ay, by) + EPS
    )


@njit(cache=True)
def segments_intersect(ax, ay, bx, by, cx, cy, dx, dy):
    """Closed segments ab and cd share at least one point (crossing, touching or overlapping).

    Bounding boxes apart by more than EPS share no point. The test comes first: for two
    distant segments on one line the orientations are rounding noise of either sign, and the
    crossing test alone then reports a crossing (seen 2026-12-02 on a generated straight, two
    segments 37 m apart)."""
    if (min(cx, dx) > max(ax, bx) + EPS or max(cx, dx) < min(ax, bx) - EPS
            or min(cy, dy) > max(ay, by) + EPS or max(cy, dy) < min(ay, by) - EPS):
        return False
    o1 = orient(ax, ay, bx, by, cx, cy)
    o2 = orient(ax, ay, bx, by, dx, dy)
    o3 = orient(cx, cy, dx, dy, ax, ay)
    o4 = orient(cx, cy, dx, dy, bx, by)
    if ((o1 > 0 and o2 < 0) or (o1 < 0 and o2 > 0)) and (
        (o3 > 0 and o4 < 0) or (o3 < 0 and o4 > 0)
    ):
        return True
    if o1 == 0 and _on_segment(cx, cy, ax, ay, bx, by):
        return True
    if o2 == 0 and _on_segment(dx, dy, ax, ay, bx, by):
        return True
    if o3 == 0 and _on_segment(ax, ay, cx, cy, dx, dy):
        return True
    if o4 == 0 and _on_segment(bx, by, cx, cy, dx, dy):
        return True
    return False


@njit(cache=True)
def segments_cross(ax, ay, bx, by, cx, cy, dx, dy):
    """Proper intersection: ab and cd cross at a single point interior to both (touching at an
    endpoint or overlapping collinearly does not count). Bounding boxes apart cannot cross
    (the test comes first, as in ``segments_intersect``)."""
    if (min(cx, dx) > max(ax, bx) or max(cx, dx) < min(ax, bx) or min(cy, dy) > max(ay, by)
            or max(cy, dy) < min(ay, by)):
        return False
    o1 = orient(ax, ay, bx, by, cx, cy)
    o2 = orient(ax, ay, bx, by, dx, dy)
    o3 = orient(cx, cy, dx, dy, ax, ay)
    o4 = orient(cx, cy, dx, dy, bx, by)
    return ((o1 > 0 and o2 < 0) or (o1 < 0 and o2 > 0)) and (
        (o3 > 0 and o4 < 0) or (o3 < 0 and o4 > 0)
    )


@njit(cache=True)
def _parallel_overlap(ax, ay, bx, by, cx, cy, dx, dy):
    """Length of the overlap of the projections of ab and cd onto the longer one's direction,
    when the two are parallel (else -1)."""
    ux = bx - ax
    uy = by - ay
    vx = dx - cx
    vy = dy - cy
    lu = math.sqrt(ux * ux + uy * uy)
    lv = math.sqrt(vx * vx + vy * vy)
    if lu <= EPS or lv <= EPS:
        return -1.0
    if abs(cross2(ux, uy, vx, vy)) > EPS * lu * lv:
        return -1.0
    if lv > lu:
        ux = vx
        uy = vy
        lu = lv
    ux /= lu
    uy /= lu
    pa = ax * ux + ay * uy
    pb = bx * ux + by * uy
    pc = cx * ux + cy * uy
    pd = dx * ux + dy * uy
    return min(max(pa, pb), max(pc, pd)) - max(min(pa, pb), min(pc, pd))


@njit(cache=True)
def segment_distance_end(ax, ay, bx, by, cx, cy, dx, dy):
    """Minimum distance between segments ab and cd (metres), and RLD's End() (fig. 4).

    ``End`` is True when every closest pair of points joins an endpoint of ab with an endpoint
    of cd: the segments are closest only at their ends. It is False when the minimum is also
    attained at a point interior to either segment (a perpendicular foot, a proper crossing, a
    parallel overlap). Two segments touching at one shared endpoint have End True; a
    zero-length segment counts as its own endpoint.
    """
    if segments_intersect(ax, ay, bx, by, cx, cy, dx, dy):
        shared = (
            (ax == cx and ay == cy)
            or (ax == dx and ay == dy)
            or (bx == cx and by == cy)
            or (bx == dx and by == dy)
        )
        if not shared:
            return 0.0, False
        # A shared endpoint: the contact is that point only unless they overlap collinearly.
        if _parallel_overlap(ax, ay, bx, by, cx, cy, dx, dy) > EPS:
            return 0.0, False
        return 0.0, True
    d1, t1 = point_segment_param(ax, ay, cx, cy, dx, dy)
    d2, t2 = point_segment_param(bx, by, cx, cy, dx, dy)
    d3, t3 = point_segment_param(cx, cy, ax, ay, bx, by)
    d4, t4 = point_segment_param(dx, dy, ax, ay, bx, by)
    d = min(min(d1, d2), min(d3, d4))
    tol = EPS * (1.0 + d)
    end = True
    # An interior foot that attains the minimum means the closest pair is not end-to-end.
    if d1 <= d + tol and EPS < t1 < 1.0 - EPS:
        end = False
    if d2 <= d + tol and EPS < t2 < 1.0 - EPS:
        end = False
    if d3 <= d + tol and EPS < t3 < 1.0 - EPS:
        end = False
    if d4 <= d + tol and EPS < t4 < 1.0 - EPS:
        end = False
    # Parallel segments facing each other over a stretch are closest along all of it.
    if end and _parallel_overlap(ax, ay, bx, by, cx, cy, dx, dy) > EPS:
        end = False
    return d, end


@njit(cache=True)
def segment_distance(ax, ay, bx, by, cx, cy, dx, dy):
    """Minimum Euclidean distance between segments ab and cd, metres (RLD MinDist, eq. 7)."""
    d, _ = segment_distance_end(ax, ay, bx, by, cx, cy, dx, dy)
    return d


@njit(cache=True)
def turn_angle(ax, ay, bx, by, cx, cy):
    """Signed turn (radians, in (-pi, pi]) from segment ab to segment bc: 0 straight on,
    positive to the left. A zero-length segment has no direction and counts as a full
    reversal (pi), so it can never pass a turn limit."""
    ux = bx - ax
    uy = by - ay
    vx = cx - bx
    vy = cy - by
    if (ux == 0.0 and uy == 0.0) or (vx == 0.0 and vy == 0.0):
        return math.pi
    t = math.atan2(cross2(ux, uy, vx, vy), ux * vx + uy * vy)
    # An exact reversal can give a cross product of -0.0 and atan2 then -pi: keep (-pi, pi].
    return math.pi if t <= -math.pi else t


# ----------------------------------------------------------------------------------------------
# Loops over arrays, used by the vectorized wrappers in rld.geometry.


@njit(cache=True)
def point_segment_distance_many(p, a, b, out):
    for i in range(p.shape[0]):
        out[i] = point_segment_distance(p[i, 0], p[i, 1], a[i, 0], a[i, 1], b[i, 0], b[i, 1])


@njit(cache=True)
def segment_parameter_many(p, a, b, out):
    for i in range(p.shape[0]):
        out[i] = segment_parameter(p[i, 0], p[i, 1], a[i, 0], a[i, 1], b[i, 0], b[i, 1])


@njit(cache=True)
def segment_distance_end_many(a, b, c, d, out_d, out_end):
    for i in range(a.shape[0]):
        dist, end = segment_distance_end(
            a[i, 0], a[i, 1], b[i, 0], b[i, 1], c[i, 0], c[i, 1], d[i, 0], d[i, 1]
        )
        out_d[i] = dist
        out_end[i] = end


@njit(cache=True)
def segments_intersect_many(a, b, c, d, out):
    for i in range(a.shape[0]):
        out[i] = segments_intersect(
            a[i, 0], a[i, 1], b[i, 0], b[i, 1], c[i, 0], c[i, 1], d[i, 0], d[i, 1]
        )


@njit(cache=True)
def segments_cross_many(a, b, c, d, out):
    for i in range(a.shape[0]):
        out[i] = segments_cross(
            a[i, 0], a[i, 1], b[i, 0], b[i, 1], c[i, 0], c[i, 1], d[i, 0], d[i, 1]
        )


@njit(cache=True)
def turn_angle_many(a, b, c, out):
    for i in range(a.shape[0]):
        out[i] = turn_angle(a[i, 0], a[i, 1], b[i, 0], b[i, 1], c[i, 0], c[i, 1])


@njit(cache=True)
def polyline_turns(xy, closed, out):
    """out = the signed turn (``turn_angle``) at every interior vertex of the polyline ``xy``
    (k, 2): vertices 1..k-2 in order (k - 2 values) or, ``closed``, every vertex i from
    segment i-1,i to i,i+1 with wrap-around (k values)."""
    k = xy.shape[0]
    if closed:
        for i in range(k):
            a = (i - 1) % k
            c = (i + 1) % k
            out[i] = turn_angle(xy[a, 0], xy[a, 1], xy[i, 0], xy[i, 1], xy[c, 0], xy[c, 1])
        return
    for i in range(1, k - 1):
        out[i - 1] = turn_angle(xy[i - 1, 0], xy[i - 1, 1], xy[i, 0], xy[i, 1],
                                xy[i + 1, 0], xy[i + 1, 1])


@njit(cache=True)
def point_polyline_nearest(px, py, poly, seed):
    """Distance from point p to the polyline ``poly`` (k >= 2, 2) and the index of a nearest
    segment; segment ``seed`` is tried first (a good guess prunes the rest)."""
    j = seed
    best = point_segment_distance(px, py, poly[j, 0], poly[j, 1], poly[j + 1, 0], poly[j + 1, 1])
    for i in range(poly.shape[0] - 1):
        ax, ay, bx, by = poly[i, 0], poly[i, 1], poly[i + 1, 0], poly[i + 1, 1]
        # The gap to the segment's bounding box bounds its distance from below: skip it when
        # that already reaches the best (exact: the minimum cannot change).
        gx = max(min(ax, bx) - px, px - max(ax, bx), 0.0)
        gy = max(min(ay, by) - py, py - max(ay, by), 0.0)
        if gx * gx + gy * gy >= best * best:
            continue
        d = point_segment_distance(px, py, ax, ay, bx, by)
        if d < best:
            best = d
            j = i
    return best, j


@njit(cache=True)
def point_polyline_distance(px, py, poly):
    """Distance from point p to the polyline ``poly`` (k, 2); a single point if k == 1."""
    if poly.shape[0] == 1:
        return math.hypot(px - poly[0, 0], py - poly[0, 1])
    d, _ = point_polyline_nearest(px, py, poly, 0)
    return d


@njit(cache=True)
def point_polyline_distance_many(p, poly, out):
    """out[i] = distance from p[i] to the polyline ``poly`` (k >= 1, 2)."""
    if poly.shape[0] == 1:
        for i in range(p.shape[0]):
            out[i] = math.hypot(p[i, 0] - poly[0, 0], p[i, 1] - poly[0, 1])
        return
    near = 0  # the previous point's nearest segment: consecutive points are near each other
    for i in range(p.shape[0]):
        out[i], near = point_polyline_nearest(p[i, 0], p[i, 1], poly, near)


@njit(cache=True)
def polyline_segments_distance_many(q, poly, out):
    """out[i] = least distance from the segment q[i]-q[i+1] to the polyline ``poly`` (k >= 1,
    2; one point when k == 1), for i < len(q) - 1."""
    k = poly.shape[0]
    near = 0  # the previous query's nearest segment: consecutive queries are near each other
    for i in range(q.shape[0] - 1):
        ax, ay, bx, by = q[i, 0], q[i, 1], q[i + 1, 0], q[i + 1, 1]
        if k == 1:
            out[i] = point_segment_distance(poly[0, 0], poly[0, 1], ax, ay, bx, by)
            continue
        x0, x1, y0, y1 = min(ax, bx), max(ax, bx), min(ay, by), max(ay, by)
        best = segment_distance(ax, ay, bx, by, poly[near, 0], poly[near, 1], poly[near + 1, 0],
                                poly[near + 1, 1])
        for j in range(k - 1):
            cx, cy, dx, dy = poly[j, 0], poly[j, 1], poly[j + 1, 0], poly[j + 1, 1]
            # The gap between the two bounding boxes bounds the distance from below.
            gx = max(min(cx, dx) - x1, x0 - max(cx, dx), 0.0)
            gy = max(min(cy, dy) - y1, y0 - max(cy, dy), 0.0)
            if gx * gx + gy * gy >= best * best:
                continue
            d = segment_distance(ax, ay, bx, by, cx, cy, dx, dy)
            if d < best:
                best = d
                near = j
        out[i] = best


@njit(cache=True)
def ring_edges_touch(adjacent, ax, ay, bx, by, cx, cy, dx, dy):
    """The pair test of a simple ring, for its edges a-b and c-d (the one of lower index
    first): adjacent edges, which share one vertex, may come closest only at their ends (no
    fold-back, ``segment_distance_end``); others may not meet at all
    (``segments_intersect``). True when the pair breaks the ring. Used by
    ``polyline_self_intersects`` and by the CLC search's incremental ring check."""
    if adjacent:
        _, end = segment_distance_end(ax, ay, bx, by, cx, cy, dx, dy)
        return not end
    return segments_intersect(ax, ay, bx, by, cx, cy, dx, dy)


@njit(cache=True)
def polyline_self_intersects(ring):
    """Whether the closed ring ``ring`` (k, 2; last point joins the first) is not simple:
    two non-adjacent edges share a point, or two adjacent edges overlap."""
    k = ring.shape[0]
    if k < 3:
        return False
    for i in range(k):
        ax = ring[i, 0]
        ay = ring[i, 1]
        bx = ring[(i + 1) % k, 0]
        by = ring[(i + 1) % k, 1]
        if ax == bx and ay == by:
            return True
        x0, x1, y0, y1 = min(ax, bx), max(ax, bx), min(ay, by), max(ay, by)
        for j in range(i + 1, k):
            cx = ring[j, 0]
            cy = ring[j, 1]
            dx = ring[(j + 1) % k, 0]
            dy = ring[(j + 1) % k, 1]
            adjacent = j == i + 1 or (i == 0 and j == k - 1)
            if (not adjacent and (min(cx, dx) > x1 + EPS or max(cx, dx) < x0 - EPS
                                  or min(cy, dy) > y1 + EPS or max(cy, dy) < y0 - EPS)):
                continue  # segments_intersect's box test, this segment's box hoisted
            if ring_edges_touch(adjacent, ax, ay, bx, by, cx, cy, dx, dy):
                return True
    return False


@njit(cache=True)
def polylines_touch(p, q):
    """Whether any segment of the polyline ``p`` (k, 2) shares a point with any segment of the
    polyline ``q`` (m, 2) (``segments_intersect``: crossing, touching or overlapping). A
    polyline of fewer than two points has no segment and touches nothing."""
    for i in range(p.shape[0] - 1):
        ax, ay, bx, by = p[i, 0], p[i, 1], p[i + 1, 0], p[i + 1, 1]
        x0, x1, y0, y1 = min(ax, bx), max(ax, bx), min(ay, by), max(ay, by)
        for j in range(q.shape[0] - 1):
            cx, cy, dx, dy = q[j, 0], q[j, 1], q[j + 1, 0], q[j + 1, 1]
            # segments_intersect's own box test, with this segment's box computed once per
            # row (measured: 35 against 60 us on two rings of 100 cones).
            if (min(cx, dx) > x1 + EPS or max(cx, dx) < x0 - EPS or min(cy, dy) > y1 + EPS
                    or max(cy, dy) < y0 - EPS):
                continue
            if segments_intersect(ax, ay, bx, by, cx, cy, dx, dy):
                return True
    return False


# ----------------------------------------------------------------------------------------------
# Growable arrays, for kernels that do not know their output's size in advance.
#
# Copies between arrays are written as loops, never as ``b[:n] = a`` or ``b[i] = row``: numba
# lowers an array-valued slice assignment with a shape check whose error message is formatted
# by compiled string code (``raise_with_shape_context``), about 5 s of compilation on a cold
# start for an error that cannot happen here (the shapes match by construction).


@njit(cache=True)
def grow_int(a, need):
    """``a`` (1-d) if it holds ``need`` entries, else a copy at least twice as long."""
    if need <= a.shape[0]:
        return a
    b = np.empty(max(need, 2 * a.shape[0]), dtype=a.dtype)
    for i in range(a.shape[0]):
        b[i] = a[i]
    return b


@njit(cache=True)
def grow_rows(a, need):
    """``a`` (2-d) if it has ``need`` rows, else a copy with at least twice as many."""
    if need <= a.shape[0]:
        return a
    b = np.empty((max(need, 2 * a.shape[0]), a.shape[1]), dtype=a.dtype)
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            b[i, j] = a[i, j]
    return b


@njit(cache=True)
def grow_2d(a, rows, cols):
    """``a`` copied into the top-left corner of a new (rows, cols) array (rows, cols at least
    ``a``'s; the rest uninitialised)."""
    b = np.empty((rows, cols), dtype=a.dtype)
    for i in range(a.shape[0]):
        for j in range(a.shape[1]):
            b[i, j] = a[i, j]
    return b


# ----------------------------------------------------------------------------------------------
# Pairs of points within a radius (the candidate edges of both methods).


@njit(cache=True)
def _insertion_sort(a, k):
    """Sort a[:k] in place (k is small: the neighbours of one point)."""
    for i in range(1, k):
        v = a[i]
        j = i - 1
        while j >= 0 and a[j] > v:
            a[j + 1] = a[j]
            j -= 1
        a[j + 1] = v


#: ``pairs_within``'s cells are ``r * GRID_SLACK`` wide, a hair wider than r: two points within
#: r of each other are then in the same or adjacent cells even where x / r rounds across a
#: cell's edge.
GRID_SLACK = 1.0 + 1e-9


@njit(cache=True)
def pairs_within(pts, r):
    """Every pair (i, j), i < j, of the points ``pts`` (n, 2) at most ``r`` apart
    (``math.hypot``), as an (E, 2) int64 array sorted by i, then j, and True; or, when the
    grid below would be too large, an empty array and False (``rld.geometry.pairs_within``
    then numbers the cells itself and calls ``pairs_in_cells``).
    A grid of cells ``r`` wide (a hair wider): each point is compared with the points of its
    own cell and the eight around it. The grid is a dense array when it has at most
    16 n + 4096 cells (any map of a track). ``r`` > 0 and finite (the callers validate it).
    The sparse case is left to numpy so that a cold start does not compile numba's sort and
    ``np.unique`` for a case no track map reaches."""
    n = pts.shape[0]
    if n < 2:
        return np.empty((0, 2), dtype=np.int64), True
    cell = r * GRID_SLACK
    fx = np.empty(n)
    fy = np.empty(n)
    for i in range(n):
        fx[i] = math.floor(pts[i, 0] / cell)
        fy[i] = math.floor(pts[i, 1] / cell)
    x0 = x1 = fx[0]
    y0 = y1 = fy[0]
    for i in range(1, n):
        if fx[i] < x0:
            x0 = fx[i]
        if fx[i] > x1:
            x1 = fx[i]
        if fy[i] < y0:
            y0 = fy[i]
        if fy[i] > y1:
            y1 = fy[i]
    if not (x1 - x0 + 1.0) * (y1 - y0 + 1.0) <= 16.0 * n + 4096.0:
        return np.empty((0, 2), dtype=np.int64), False
    # Column and row from 0; a cell's key is col * w + row.
    w = int(y1 - y0) + 1
    ncol = int(x1 - x0) + 1
    col = np.empty(n, dtype=np.int64)
    row = np.empty(n, dtype=np.int64)
    nx = np.full((n, 3), -1, dtype=np.int64)
    ny = np.full((n, 3), -1, dtype=np.int64)
    for i in range(n):
        col[i] = int(fx[i] - x0)
        row[i] = int(fy[i] - y0)
        for d in range(3):
            if 0 <= col[i] + d - 1 < ncol:
                nx[i, d] = col[i] + d - 1
            if 0 <= row[i] + d - 1 < w:
                ny[i, d] = row[i] + d - 1
    return pairs_in_cells(pts, r, col, row, ncol, w, nx, ny), True


@njit(cache=True)
def pairs_in_cells(pts, r, col, row, ncol, w, nx, ny):
    """``pairs_within`` on a numbered grid: point i lies in column ``col[i]`` (of ``ncol``)
    and row ``row[i]`` (of ``w``); ``nx[i]`` ((3,), -1 for none) are the columns one step
    below, level and one step above its own, ``ny[i]`` the rows likewise."""
    n = pts.shape[0]
    ncell = ncol * w
    # Counting sort of the points by cell: cell c holds order[start[c]:start[c + 1]].
    start = np.zeros(ncell + 1, dtype=np.int64)
    for i in range(n):
        start[col[i] * w + row[i] + 1] += 1
    for c in range(ncell):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    order = np.empty(n, dtype=np.int64)
    for i in range(n):
        c = col[i] * w + row[i]
        order[fill[c]] = i
        fill[c] += 1
    out = np.empty((8 * n, 2), dtype=np.int64)
    m = 0
    nbr = np.empty(n, dtype=np.int64)
    for i in range(n):
        k = 0
        for a in range(3):
            tx = nx[i, a]
            if tx < 0:
                continue
            for b in range(3):
                ty = ny[i, b]
                if ty < 0:
                    continue
                c = tx * w + ty
                for s in range(start[c], start[c + 1]):
                    j = order[s]
                    if j > i and math.hypot(pts[j, 0] - pts[i, 0],
                                            pts[j, 1] - pts[i, 1]) <= r:
                        nbr[k] = j
                        k += 1
        _insertion_sort(nbr, k)
        out = grow_rows(out, m + k)
        for t in range(k):
            out[m, 0] = i
            out[m, 1] = nbr[t]
            m += 1
    return out[:m].copy()


@njit(cache=True)
def _pair_before(a, b):
    """Whether start-pair key row ``a`` sorts before ``b`` (``start_pairs_ranked``)."""
    for q in range(a.shape[0]):
        if a[q] < b[q]:
            return True
        if a[q] > b[q]:
            return False
    return False


@njit(cache=True)
def start_pairs_ranked(pts, px, py, c, s, radius, k, min_width):
    """The ``k`` best (left, right) start pairs of ``rld.constraints.starting_vertex_pairs``
    (CLC IV-C with our ordering), (m, 2) int64, m <= k: the cones within ``radius`` of the car
    at (px, py) with heading (c, s) = (cos yaw, sin yaw), left ones at local y > 0 and right
    ones at y < 0; ordered by (narrower than ``min_width``, the asymmetry rounded to a
    micrometre, the summed distance from the car, the left index, the right index), each
    ascending: the order of the numpy form's ``np.lexsort``, in one loop."""
    n = pts.shape[0]
    lx = np.empty(n)
    ly = np.empty(n)
    li = np.empty(n, dtype=np.int64)
    rx = np.empty(n)
    ry = np.empty(n)
    ri = np.empty(n, dtype=np.int64)
    nl = 0
    nr = 0
    for i in range(n):
        dx = pts[i, 0] - px
        dy = pts[i, 1] - py
        if not math.hypot(dx, dy) <= radius:
            continue
        x = c * dx + s * dy
        y = -s * dx + c * dy
        if y > 0:
            lx[nl] = x
            ly[nl] = y
            li[nl] = i
            nl += 1
        elif y < 0:
            rx[nr] = x
            ry[nr] = y
            ri[nr] = i
            nr += 1
    kk = max(k, 1)
    out = np.empty((kk, 2), dtype=np.int64)
    if nl == 0 or nr == 0:
        return out[:0]
    keys = np.empty((kk, 5))
    key = np.empty(5)
    m = 0
    for a in range(nl):
        for b in range(nr):
            dx = lx[a] - rx[b]
            key[0] = 1.0 if math.hypot(dx, ly[a] - ry[b]) < min_width else 0.0
            key[1] = np.rint(math.hypot(dx, ly[a] + ry[b]) * 1e6) / 1e6
            key[2] = math.hypot(lx[a], ly[a]) + math.hypot(rx[b], ry[b])
            key[3] = li[a]
            key[4] = ri[b]
            if m == kk and not _pair_before(key, keys[m - 1]):
                continue
            # Insert in order, dropping the last when full.
            j = m if m < kk else kk - 1
            while j > 0 and _pair_before(key, keys[j - 1]):
                for q in range(5):  # loops, not row assignments (see grow_int)
                    keys[j, q] = keys[j - 1, q]
                out[j, 0] = out[j - 1, 0]
                out[j, 1] = out[j - 1, 1]
                j -= 1
            for q in range(5):
                keys[j, q] = key[q]
            out[j, 0] = li[a]
            out[j, 1] = ri[b]
            if m < kk:
                m += 1
    return out[:m].copy()

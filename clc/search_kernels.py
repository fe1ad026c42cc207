"""numba kernels of the CLC path-pair enumeration (Ivanov & Markgraf 2024, Alg. 2 and 3), with
the constraints of section VI (eqs 6, 8-15) kept exactly after every extension; called only
through ``clc.search``. How and why: docs/clc.md, "The search kernels"."""

from __future__ import annotations

import math

import numpy as np
from numba.core.options import DefaultOptions

from rld._jit import njit
from rld.geometry_kernels import (
    grow_2d,
    grow_int,
    grow_rows,
    point_segment_distance,
    ring_edges_touch,
    segment_distance,
    turn_angle,
)

#: Options of the search's helpers that allocate nothing: compiled without numba's reference
#: counting (``_nrt=False``). With it, every call that passes arrays adjusts their reference
#: counts on entry and exit, atomic operations that took half the search's time (perf,
#: 2026-12-03: 4.0 -> 2.2 us per iteration without them, the same candidates). ``_nrt`` is
#: numba's own option (``numba.core.options``); a numba without it gets the plain options.
LEAF = {"cache": True, "_nrt": False} if hasattr(DefaultOptions, "_nrt") else {"cache": True}

#: Margin of the culling tests, metres: far above rounding, far below any cone distance.
CULL_MARGIN = 1e-7
#: Segments per block of the ring check's two-level bounding boxes.
BLOCK = 8
N_FEATURES = 8


@njit(**LEAF)
def _angle_between(ux, uy, vx, vy):
    """Unsigned angle between vectors u and v, radians in [0, pi]; pi if either is zero."""
    if (ux == 0.0 and uy == 0.0) or (vx == 0.0 and vy == 0.0):
        return math.pi
    return abs(math.atan2(ux * vy - uy * vx, ux * vx + uy * vy))


@njit(**LEAF)
def _option_turn(pts, path, n, v, hx, hy):
    """|turn| from the path's last segment (or the car heading for a single vertex) to the
    segment path[n-1] -> v."""
    c = path[n - 1]
    if n >= 2:
        p = path[n - 2]
        return abs(turn_angle(pts[p, 0], pts[p, 1], pts[c, 0], pts[c, 1], pts[v, 0], pts[v, 1]))
    return _angle_between(hx, hy, pts[v, 0] - pts[c, 0], pts[v, 1] - pts[c, 1])


@njit(**LEAF)
def _onward(pts, adj_ptr, adj_idx, c, v, in_path, max_turn, dist_weight, dead_end):
    """The look-ahead of the next-vertex decider: the best score |turn| + dist_weight *
    distance of a step from ``v`` onward (after c -> v) to a cone in no path and within the
    turn limit; ``dead_end`` when there is none."""
    best = np.inf
    for s in range(adj_ptr[v], adj_ptr[v + 1]):
        w = adj_idx[s]
        if w == c or in_path[w]:
            continue
        t = abs(turn_angle(pts[c, 0], pts[c, 1], pts[v, 0], pts[v, 1], pts[w, 0], pts[w, 1]))
        if t > max_turn:
            continue
        sc = t + dist_weight * math.hypot(pts[w, 0] - pts[v, 0], pts[w, 1] - pts[v, 1])
        if sc < best:
            best = sc
    return dead_end if best == np.inf else best


@njit(**LEAF)
def _option_score(pts, adj_ptr, adj_idx, path, n, v, in_path, max_turn, hx, hy, dist_weight,
                  lookahead, dead_end):
    """The next-vertex decider's score of extending ``path[:n]`` by ``v`` (CLC eq. 3 with a
    distance term): |turn| + dist_weight * distance, plus ``lookahead`` times the best such
    score of the step after it (``_onward``, ``dead_end`` when there is no step after it; 0:
    none, the one-step decider). The turn of a one-vertex path is taken from the car heading.
    ``inf`` when the turn exceeds ``max_turn`` (C_seg)."""
    c = path[n - 1]
    if n >= 2:
        p = path[n - 2]
        a = abs(turn_angle(pts[p, 0], pts[p, 1], pts[c, 0], pts[c, 1], pts[v, 0], pts[v, 1]))
        if a > max_turn:
            return np.inf
    else:
        a = _angle_between(hx, hy, pts[v, 0] - pts[c, 0], pts[v, 1] - pts[c, 1])
    score = a + dist_weight * math.hypot(pts[v, 0] - pts[c, 0], pts[v, 1] - pts[c, 1])
    if lookahead > 0.0:
        score += lookahead * _onward(pts, adj_ptr, adj_idx, c, v, in_path, max_turn,
                                     dist_weight, dead_end)
    return score


@njit(**LEAF)
def _score_options(pts, adj_ptr, adj_idx, path, n, tried, in_path, max_turn, hx, hy,
                   dist_weight, lookahead, dead_end, guide, guided, forbid, out, pen):
    """The next-vertex decider's scores (``_option_score``) of every neighbour of the path's
    end, into ``out[k]`` for neighbour slot k: ``inf`` for an option that is tried, in a path,
    beyond the turn limit (C_seg) or ``forbid`` (a vertex, or -1; only when the path is the
    whole guide); plus ``pen[v]``, the colour penalty of vertex v on this side (``pen`` may be
    empty: none; ``clc.search.SearchGraph.side_penalty``). A frame's scores hold for as long as the
    frame lives: its paths and the vertices in them are the same whenever the search is back at it,
    and its tried options only grow (they are skipped in ``_pick_option``), so ``enumerate_pairs``
    scores each frame once (the decider memoized, as the paper's implementation is, section V-A)."""
    c = path[n - 1]
    s0 = adj_ptr[c]
    skip = forbid if guided and n == guide.shape[0] else -1
    for k in range(adj_ptr[c + 1] - s0):
        v = adj_idx[s0 + k]
        if tried[k] or in_path[v] or v == skip:
            out[k] = np.inf
        else:
            out[k] = _option_score(pts, adj_ptr, adj_idx, path, n, v, in_path, max_turn, hx,
                                   hy, dist_weight, lookahead, dead_end)
            if pen.shape[0] > 0:
                out[k] += pen[v]


@njit(**LEAF)
def _pick_option(adj_ptr, adj_idx, c, n, tried, scores, guide, guided):
    """The next-vertex decider's choice among the untried neighbours of ``c`` (the path's end)
    with a finite score (``_score_options``): the warm-start guide's next vertex when the path
    is still a prefix of the guide and that vertex is an option, else the lowest score (ties:
    the first in the graph's order). Returns (slot, vertex) or (-1, -1)."""
    s0 = adj_ptr[c]
    want = -1
    if guided and n < guide.shape[0]:
        want = guide[n]
    best = -1
    best_v = -1
    best_score = np.inf
    for k in range(adj_ptr[c + 1] - s0):
        if tried[k]:
            continue
        score = scores[k]
        if score == np.inf:
            continue
        v = adj_idx[s0 + k]
        if v == want:
            return k, v
        if score < best_score:
            best_score = score
            best = k
            best_v = v
    return best, best_v


@njit(cache=True)
def _choose_option(pts, adj_ptr, adj_idx, path, n, tried, in_path, max_turn, hx, hy,
                   dist_weight, lookahead, dead_end, guide, guided, forbid, pen=None):
    """The next-vertex decider without the memo (``_score_options`` then ``_pick_option``):
    among the neighbours of the path's end that are untried at this frame, in no path and
    within the turn limit (C_seg), the one with the lowest ``_option_score``. The warm-start
    guide's next vertex wins when the path is still a prefix of the guide; when the path is
    the whole guide, ``forbid`` (a vertex, or -1) is not an option. Returns (slot, vertex) or
    (-1, -1). ``pen``: the colour penalties of the path's side (None: none)."""
    c = path[n - 1]
    scores = np.empty(adj_ptr[c + 1] - adj_ptr[c])
    p = np.zeros(0) if pen is None else pen
    _score_options(pts, adj_ptr, adj_idx, path, n, tried, in_path, max_turn, hx, hy,
                   dist_weight, lookahead, dead_end, guide, guided, forbid, scores, p)
    return _pick_option(adj_ptr, adj_idx, c, n, tried, scores, guide, guided)


@njit(cache=True)
def csr_from_edges(edges, n):
    """The search graph in CSR form from its edges (E, 2), i < j, sorted by (i, j) (as
    ``rld.constraints.candidate_edges`` returns them): ``(indptr (n + 1,), indices (2E,))``,
    each vertex's neighbours sorted by index. One pass fills both ends: vertex v receives its
    smaller neighbours (edges (i, v), i < v) before its larger ones (edges (v, j)), each in
    increasing order."""
    indptr = np.zeros(n + 1, dtype=np.int64)
    for e in range(edges.shape[0]):
        indptr[edges[e, 0] + 1] += 1
        indptr[edges[e, 1] + 1] += 1
    for v in range(n):
        indptr[v + 1] += indptr[v]
    fill = indptr[:-1].copy()
    indices = np.empty(2 * edges.shape[0], dtype=np.int64)
    for e in range(edges.shape[0]):
        a = edges[e, 0]
        b = edges[e, 1]
        indices[fill[a]] = b
        fill[a] += 1
        indices[fill[b]] = a
        fill[b] += 1
    return indptr, indices


@njit(cache=True)
def dead_end_score(pts, adj_ptr, adj_idx, max_turn, dist_weight):
    """The look-ahead's score of a cone with no step onward: the worst step the graph holds,
    phi_max + dist_weight * its longest edge."""
    longest = 0.0
    for v in range(pts.shape[0]):
        for s in range(adj_ptr[v], adj_ptr[v + 1]):
            w = adj_idx[s]
            d = math.hypot(pts[w, 0] - pts[v, 0], pts[w, 1] - pts[v, 1])
            if d > longest:
                longest = d
    return max_turn + dist_weight * longest


@njit(cache=True)
def contested_positions(pts, adj_ptr, adj_idx, path, other, hx, hy, max_turn, dist_weight,
                        lookahead, margin, reach, dead_end=-1.0, pen=None):
    """Positions j >= 1 of ``path`` (one boundary of a lane, ``other`` the other one) within
    ``reach`` metres of path length from its start at which the next-vertex decider had a
    close second: another option of path[:j] (not in either boundary, within the turn limit)
    whose ``_option_score`` is at most ``margin`` above that of path[j]. Returns the
    positions in order. ``dead_end``: ``dead_end_score`` of the graph when known (< 0: computed
    here). ``pen``: the colour penalties of the path's side, added to each score as the search
    adds them (``_score_options``; None: none)."""
    N = pts.shape[0]
    p = np.zeros(0) if pen is None else pen
    if dead_end < 0.0:
        dead_end = dead_end_score(pts, adj_ptr, adj_idx, max_turn, dist_weight)
    in_path = np.zeros(N, dtype=np.bool_)
    for v in other:
        in_path[v] = True
    out = np.empty(path.shape[0], dtype=np.int64)
    m = 0
    arc = 0.0
    for j in range(1, path.shape[0]):
        arc += math.hypot(pts[path[j], 0] - pts[path[j - 1], 0],
                          pts[path[j], 1] - pts[path[j - 1], 1])
        if arc > reach:
            break
        in_path[path[j - 1]] = True
        c = path[j - 1]
        chosen = _option_score(pts, adj_ptr, adj_idx, path, j, path[j], in_path, max_turn, hx,
                               hy, dist_weight, lookahead, dead_end)
        if p.shape[0] > 0:
            chosen += p[path[j]]
        second = np.inf
        for s in range(adj_ptr[c], adj_ptr[c + 1]):
            v = adj_idx[s]
            if v == path[j] or in_path[v]:
                continue
            sc = _option_score(pts, adj_ptr, adj_idx, path, j, v, in_path, max_turn, hx, hy,
                               dist_weight, lookahead, dead_end)
            if p.shape[0] > 0:
                sc += p[v]
            if sc < second:
                second = sc
        if second < np.inf and second - chosen <= margin:
            out[m] = j
            m += 1
    return out[:m]


@njit(cache=True)
def arc_behind(pts, path, px, py, hx, hy):
    """Path length (metres) of ``path`` behind the car at (px, py) with unit heading (hx, hy):
    from its start to where it crosses the line through the car across the heading (the whole
    path when it never does; 0 when it starts on or past the line)."""
    total = 0.0
    prev = (pts[path[0], 0] - px) * hx + (pts[path[0], 1] - py) * hy
    if prev >= 0.0:
        return 0.0
    for j in range(1, path.shape[0]):
        a, b = path[j - 1], path[j]
        seg = math.hypot(pts[b, 0] - pts[a, 0], pts[b, 1] - pts[a, 1])
        x = (pts[b, 0] - px) * hx + (pts[b, 1] - py) * hy
        if x >= 0.0:
            return total + seg * (-prev) / (x - prev)
        total += seg
        prev = x
    return total


@njit(**LEAF)
def _has_option(pts, adj_ptr, adj_idx, path, n, tried, in_path, max_turn):
    """Whether the path's end has any untried, unused neighbour within the turn limit."""
    c = path[n - 1]
    s0 = adj_ptr[c]
    for k in range(adj_ptr[c + 1] - s0):
        if tried[k]:
            continue
        v = adj_idx[s0 + k]
        if in_path[v]:
            continue
        if n >= 2:
            p = path[n - 2]
            t = turn_angle(pts[p, 0], pts[p, 1], pts[c, 0], pts[c, 1], pts[v, 0], pts[v, 1])
            if abs(t) > max_turn:
                continue
        return True
    return False


@njit(**LEAF)
def _lrd_diff(pts, a_prev, a_end, b_prev, b_end, hx, hy):
    """| theta_b - theta_a | of CLC eq. 4 for boundaries ending a_prev -> a_end and
    b_prev -> b_end (a_prev or b_prev < 0: a single vertex, use the car heading)."""
    if a_prev >= 0:
        ux = pts[a_end, 0] - pts[a_prev, 0]
        uy = pts[a_end, 1] - pts[a_prev, 1]
    else:
        ux = hx
        uy = hy
    if b_prev >= 0:
        vx = pts[b_end, 0] - pts[b_prev, 0]
        vy = pts[b_end, 1] - pts[b_prev, 1]
    else:
        vx = hx
        vy = hy
    wx = pts[b_end, 0] - pts[a_end, 0]
    wy = pts[b_end, 1] - pts[a_end, 1]
    ta = _angle_between(ux, uy, wx, wy)
    tb = _angle_between(vx, vy, -wx, -wy)
    return abs(tb - ta)


@njit(**LEAF)
def _query_to_target(pts, qa, qb, target, nt, tmid, trad):
    """Distance from a query (vertex qa if qb < 0, else segment qa-qb) to the polyline of the
    first ``nt`` vertices of ``target`` (a single point if nt == 1), exactly as
    ``rld.constraints.lane_widths`` computes it: the minimum over the target's segments.
    Segments are visited from the target's end (usually the nearest) and skipped when their
    bounding circle (``tmid``, ``trad``) lies farther than the best so far plus
    ``CULL_MARGIN``; a skipped segment cannot hold the minimum, so the value is exact."""
    if qb < 0:
        px = pts[qa, 0]
        py = pts[qa, 1]
        rq = 0.0
    else:
        px = 0.5 * (pts[qa, 0] + pts[qb, 0])
        py = 0.5 * (pts[qa, 1] + pts[qb, 1])
        rq = 0.5 * math.hypot(pts[qb, 0] - pts[qa, 0], pts[qb, 1] - pts[qa, 1])
    if nt == 1:
        t = target[0]
        if qb < 0:
            return math.hypot(px - pts[t, 0], py - pts[t, 1])
        return segment_distance(pts[qa, 0], pts[qa, 1], pts[qb, 0], pts[qb, 1],
                                pts[t, 0], pts[t, 1], pts[t, 0], pts[t, 1])
    best = np.inf
    for i in range(nt - 2, -1, -1):
        dx = tmid[i, 0] - px
        dy = tmid[i, 1] - py
        reach = best + CULL_MARGIN + rq + trad[i]
        if dx * dx + dy * dy > reach * reach:
            continue
        a = target[i]
        b = target[i + 1]
        if qb < 0:
            d = point_segment_distance(px, py, pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1])
        else:
            d = segment_distance(pts[qa, 0], pts[qa, 1], pts[qb, 0], pts[qb, 1],
                                 pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1])
        if d < best:
            best = d
    return best


@njit(**LEAF)
def _lower_other(pts, other, no, omid, orad, wv_old, ws_old, wv_new, ws_new, sa, sb):
    """The other boundary's query values after this boundary gained segment sa-sb (its target
    had at least two vertices before, so the values are minima over target segments).
    ``omid``, ``orad``: midpoints and half-lengths of the other boundary's segments. A query
    is recomputed only when the bounding circles allow the new segment to come closer than its
    value (plus ``CULL_MARGIN``), so every value is exactly the minimum."""
    mx = 0.5 * (pts[sa, 0] + pts[sb, 0])
    my = 0.5 * (pts[sa, 1] + pts[sb, 1])
    rs = 0.5 * math.hypot(pts[sb, 0] - pts[sa, 0], pts[sb, 1] - pts[sa, 1])
    for j in range(no):
        v = wv_old[j]
        q = other[j]
        dx = pts[q, 0] - mx
        dy = pts[q, 1] - my
        reach = v + CULL_MARGIN + rs
        if dx * dx + dy * dy <= reach * reach:
            d = point_segment_distance(pts[q, 0], pts[q, 1], pts[sa, 0], pts[sa, 1],
                                       pts[sb, 0], pts[sb, 1])
            if d < v:
                v = d
        wv_new[j] = v
    for j in range(no - 1):
        v = ws_old[j]
        dx = omid[j, 0] - mx
        dy = omid[j, 1] - my
        reach = v + CULL_MARGIN + rs + orad[j]
        if dx * dx + dy * dy <= reach * reach:
            qa = other[j]
            qb = other[j + 1]
            d = segment_distance(pts[qa, 0], pts[qa, 1], pts[qb, 0], pts[qb, 1],
                                 pts[sa, 0], pts[sa, 1], pts[sb, 0], pts[sb, 1])
            if d < v:
                v = d
        ws_new[j] = v


@njit(**LEAF)
def _recompute_all(pts, query, nq, target, nt, tmid, trad, wv, ws):
    for j in range(nq):
        wv[j] = _query_to_target(pts, query[j], -1, target, nt, tmid, trad)
    for j in range(nq - 1):
        ws[j] = _query_to_target(pts, query[j], query[j + 1], target, nt, tmid, trad)


@njit(**LEAF)
def _ring_edge(pts, L, nL, R, nR, e):
    """Endpoints (ax, ay, bx, by) of ring edge ``e`` of the lane ring L + reversed(R)."""
    k = nL + nR
    if e < nL - 1:
        a = L[e]
        b = L[e + 1]
    elif e == nL - 1:
        a = L[nL - 1]
        b = R[nR - 1]
    elif e < k - 1:
        p = e - nL  # ring vertex nL + p is R[nR - 1 - p]
        a = R[nR - 1 - p]
        b = R[nR - 2 - p]
    else:
        a = R[0]
        b = L[0]
    return pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1]


@njit(**LEAF)
def _pair_check_xy(k, e, f, ex0, ey0, ex1, ey1, fx0, fy0, fx1, fy1, bx0, bx1, by0, by1,
                   cx0, cx1, cy0, cy1):
    """Ring edges e (from (ex0, ey0) to (ex1, ey1), box bx0..by1) and f (likewise, box
    cx0..cy1) of a ring of ``k`` edges fail the pair test
    (``rld.geometry_kernels.ring_edges_touch``, the edge of lower index first); disjoint
    boxes of non-adjacent edges cannot touch. Scalars only: the ring check's inner loops pass
    no arrays, whose reference counts numba would otherwise adjust at every call."""
    i = min(e, f)
    j = max(e, f)
    adjacent = j == i + 1 or (i == 0 and j == k - 1)
    if not adjacent:
        m = CULL_MARGIN
        if bx1 + m < cx0 or cx1 + m < bx0 or by1 + m < cy0 or cy1 + m < by0:
            return False
    if e < f:
        return ring_edges_touch(adjacent, ex0, ey0, ex1, ey1, fx0, fy0, fx1, fy1)
    return ring_edges_touch(adjacent, fx0, fy0, fx1, fy1, ex0, ey0, ex1, ey1)


@njit(**LEAF)
def _edge_zero(pts, L, nL, R, nR, e):
    ax, ay, bx, by = _ring_edge(pts, L, nL, R, nR, e)
    return ax == bx and ay == by


@njit(**LEAF)
def _edge_vs_ring(pts, L, nL, R, nR, e, with_front, Lbox, Rbox, LblkBox, RblkBox):
    """Ring edge ``e`` is non-degenerate and passes the pair test against every other ring
    edge (the front edge l_n -> r_m only when ``with_front``). ``Lbox``, ``Rbox``: bounding
    boxes (min x, max x, min y, max y) of the boundary segments by path position;
    ``LblkBox``, ``RblkBox``: the boxes of complete blocks of ``BLOCK`` segments, which let
    whole blocks far from edge ``e`` be skipped."""
    k = nL + nR
    if k < 3:
        return True
    ax, ay, bx, by = _ring_edge(pts, L, nL, R, nR, e)
    if ax == bx and ay == by:
        return False
    bx0 = min(ax, bx)
    bx1 = max(ax, bx)
    by0 = min(ay, by)
    by1 = max(ay, by)
    m = CULL_MARGIN
    nb = (nL - 1) // BLOCK  # complete blocks of L segments
    for blk in range(nb + 1):
        lo = blk * BLOCK
        hi = min(lo + BLOCK, nL - 1)
        if blk < nb and (bx1 + m < LblkBox[blk, 0] or LblkBox[blk, 1] + m < bx0
                         or by1 + m < LblkBox[blk, 2] or LblkBox[blk, 3] + m < by0):
            continue
        for i in range(lo, hi):  # L segment i (l_i -> l_i+1) is ring edge i
            if i == e:
                continue
            p = L[i]
            q = L[i + 1]
            if _pair_check_xy(k, e, i, ax, ay, bx, by, pts[p, 0], pts[p, 1], pts[q, 0],
                              pts[q, 1], bx0, bx1, by0, by1, Lbox[i, 0], Lbox[i, 1],
                              Lbox[i, 2], Lbox[i, 3]):
                return False
    nb = (nR - 1) // BLOCK
    for blk in range(nb + 1):
        lo = blk * BLOCK
        hi = min(lo + BLOCK, nR - 1)
        if blk < nb and (bx1 + m < RblkBox[blk, 0] or RblkBox[blk, 1] + m < bx0
                         or by1 + m < RblkBox[blk, 2] or RblkBox[blk, 3] + m < by0):
            continue
        for j in range(lo, hi):  # R segment j is ring edge k - 2 - j, from r_j+1 to r_j
            f = k - 2 - j
            if f == e:
                continue
            p = R[j + 1]
            q = R[j]
            if _pair_check_xy(k, e, f, ax, ay, bx, by, pts[p, 0], pts[p, 1], pts[q, 0],
                              pts[q, 1], bx0, bx1, by0, by1, Rbox[j, 0], Rbox[j, 1],
                              Rbox[j, 2], Rbox[j, 3]):
                return False
    for f in (nL - 1, k - 1):  # the front and the back edge
        if f == e or (f == nL - 1 and not with_front):
            continue
        cx, cy, dx, dy = _ring_edge(pts, L, nL, R, nR, f)
        if _pair_check_xy(k, e, f, ax, ay, bx, by, cx, cy, dx, dy, bx0, bx1, by0, by1,
                          min(cx, dx), max(cx, dx), min(cy, dy), max(cy, dy)):
            return False
    return True


@njit(**LEAF)
def _segment_cache(pts, a, b, box, mid, rad, i):
    box[0] = min(pts[a, 0], pts[b, 0])
    box[1] = max(pts[a, 0], pts[b, 0])
    box[2] = min(pts[a, 1], pts[b, 1])
    box[3] = max(pts[a, 1], pts[b, 1])
    mid[0] = 0.5 * (pts[a, 0] + pts[b, 0])
    mid[1] = 0.5 * (pts[a, 1] + pts[b, 1])
    rad[i] = 0.5 * math.hypot(pts[b, 0] - pts[a, 0], pts[b, 1] - pts[a, 1])


@njit(**LEAF)
def _block_box(box, i, blk):
    """After segment ``i`` was added: when it completes a block, store the block's box."""
    if (i + 1) % BLOCK != 0:
        return
    b = i // BLOCK
    lo = b * BLOCK
    blk[b, 0] = box[lo, 0]
    blk[b, 1] = box[lo, 1]
    blk[b, 2] = box[lo, 2]
    blk[b, 3] = box[lo, 3]
    for j in range(lo + 1, lo + BLOCK):
        blk[b, 0] = min(blk[b, 0], box[j, 0])
        blk[b, 1] = max(blk[b, 1], box[j, 1])
        blk[b, 2] = min(blk[b, 2], box[j, 2])
        blk[b, 3] = max(blk[b, 3], box[j, 3])


@njit(**LEAF)
def _width_state(wvL, wsL, nL, wvR, wsR, nR, wmin, wmax):
    """(any value below w_min, any L query above w_max, any R query above w_max)."""
    short = False
    longL = False
    longR = False
    for i in range(nL):
        if wvL[i] < wmin:
            short = True
        elif wvL[i] > wmax:
            longL = True
    for i in range(nL - 1):
        if wsL[i] < wmin:
            short = True
        elif wsL[i] > wmax:
            longL = True
    for i in range(nR):
        if wvR[i] < wmin:
            short = True
        elif wvR[i] > wmax:
            longR = True
    for i in range(nR - 1):
        if wsR[i] < wmin:
            short = True
        elif wsR[i] > wmax:
            longR = True
    return short, longL, longR


@njit(**LEAF)
def _side_sums(pts, P, n, cum, cum2, tc, tc2):
    """Prefix sums at path position n - 1 after P gained its vertex there."""
    p = n - 1
    a = P[p - 1]
    b = P[p]
    d = math.hypot(pts[b, 0] - pts[a, 0], pts[b, 1] - pts[a, 1])
    cum[p] = cum[p - 1] + d
    cum2[p] = cum2[p - 1] + d * d
    if p >= 2:
        o = P[p - 2]
        t = turn_angle(pts[o, 0], pts[o, 1], pts[a, 0], pts[a, 1], pts[b, 0], pts[b, 1])
        tc[p] = tc[p - 1] + t
        tc2[p] = tc2[p - 1] + t * t
    else:
        tc[p] = 0.0
        tc2[p] = 0.0


@njit(**LEAF)
def _var_from_sums(s1, s2, m):
    if m < 2:
        return 0.0
    mean = s1 / m
    v = s2 / m - mean * mean
    return v if v > 0.0 else 0.0


@njit(**LEAF)
def _features(wvL, wsL, nL, wvR, wsR, nR, Lcum, Lcum2, Ltc, Ltc2, Rcum, Rcum2, Rtc, Rtc2,
              out):
    """The 8 ranking features of ``rld.costs.ranking_features`` (CLC section VII) from the
    search state: prefix sums of both boundaries and the current width values."""
    out[0] = 0.5 * (Lcum[nL - 1] + Rcum[nR - 1])
    out[1] = nL
    out[2] = nR
    s = 0.0
    m = 0
    for i in range(nL):
        s += wvL[i]
    for i in range(nL - 1):
        s += wsL[i]
    for i in range(nR):
        s += wvR[i]
    for i in range(nR - 1):
        s += wsR[i]
    m = 2 * nL + 2 * nR - 2
    mean = s / m
    v = 0.0
    for i in range(nL):
        v += (wvL[i] - mean) ** 2
    for i in range(nL - 1):
        v += (wsL[i] - mean) ** 2
    for i in range(nR):
        v += (wvR[i] - mean) ** 2
    for i in range(nR - 1):
        v += (wsR[i] - mean) ** 2
    out[3] = v / m if m >= 2 else 0.0
    out[4] = _var_from_sums(Lcum[nL - 1], Lcum2[nL - 1], nL - 1)
    out[5] = _var_from_sums(Rcum[nR - 1], Rcum2[nR - 1], nR - 1)
    out[6] = _var_from_sums(Ltc[nL - 1], Ltc2[nL - 1], nL - 2)
    out[7] = _var_from_sums(Rtc[nR - 1], Rtc2[nR - 1], nR - 2)


@njit(**LEAF)
def _grow_side(pts, P, nP, v, k, Q, nQ, triedP, triedQ, f, g, in_path, Pbox, Pmid, Prad,
               PblkBox, Pcum, Pcum2, Ptc, Ptc2, on_g, guide, wvP, wsP, wvQ, wsQ, Qmid, Qrad):
    """Extend boundary P (``nP`` vertices; Q the other boundary) by vertex ``v``, its end's
    option in slot ``k``, from frame ``f`` to frame ``g``: the tried options of both sides
    (P's option at f is tried; at g P starts afresh and Q keeps f's), the segment caches and
    prefix sums of P, P's guide flag, and the width values at g: P's unchanged, P's new
    queries to Q, and Q's values lowered to the new P segment (all of them computed when P
    had a single vertex before). The caller adds 1 to ``nP``."""
    triedP[f, k] = True
    for j in range(triedP.shape[1]):  # loops, not slice copies: those need numba's NRT
        triedP[g, j] = False
        triedQ[g, j] = triedQ[f, j]
    n = nP + 1
    P[nP] = v
    in_path[v] = True
    _segment_cache(pts, P[n - 2], v, Pbox[n - 2], Pmid[n - 2], Prad, n - 2)
    _block_box(Pbox, n - 2, PblkBox)
    _side_sums(pts, P, n, Pcum, Pcum2, Ptc, Ptc2)
    on_g[n - 1] = on_g[n - 2] and n - 1 < guide.shape[0] and guide[n - 1] == v
    for j in range(n - 1):
        wvP[g, j] = wvP[f, j]
    for j in range(n - 2):
        wsP[g, j] = wsP[f, j]
    wvP[g, n - 1] = _query_to_target(pts, v, -1, Q, nQ, Qmid, Qrad)
    wsP[g, n - 2] = _query_to_target(pts, P[n - 2], v, Q, nQ, Qmid, Qrad)
    if n == 2:
        _recompute_all(pts, Q, nQ, P, n, Pmid, Prad, wvQ[g], wsQ[g])
    else:
        _lower_other(pts, Q, nQ, Qmid, Qrad, wvQ[f], wsQ[f], wvQ[g], wsQ[g], P[n - 2], v)


@njit(cache=True)
def enumerate_pairs(pts, adj_ptr, adj_idx, start_l, start_r, hx, hy, max_turn, wmin, wmax,
                    dist_weight, lookahead, max_iterations, guide_l, guide_r, banned,
                    forbid_l=-1, forbid_r=-1, dead_end=-1.0, memo=True, pen_l=None,
                    pen_r=None):
    """CLC Alg. 2: enumerate the path pairs from (start_l, start_r) that satisfy CD (eq. 6),
    each boundary's first edge within ``max_turn`` of the heading (ours).

    ``pts`` (N, 2) float64 metres; ``adj_ptr`` (N+1,), ``adj_idx`` the search graph in CSR form
    (neighbours sorted by index); ``hx, hy`` the car's unit heading; ``max_turn`` phi_max (rad);
    ``wmin``, ``wmax`` the width bounds (m); ``dist_weight`` the NVD distance term (rad/m);
    ``lookahead`` the weight of the NVD's look-ahead step (0: none; a cone with no step
    onward scores as the worst step the graph holds, phi_max + dist_weight * longest edge);
    ``max_iterations`` it_max (<= 0: no limit); ``guide_l``, ``guide_r`` the warm-start paths
    (may be empty) the search follows first; ``banned`` vertices (may be empty) are in no
    path; ``forbid_l`` (``forbid_r``, -1: none) is not the next left (right) vertex right
    after the whole left (right) guide, but may come later (the contested-choice dives of
    ``clc.search``); ``dead_end`` the graph's ``dead_end_score`` when known (< 0: computed
    here); ``memo=False`` scores a frame's options again at every visit instead of once (the
    same search, slower: the tests' reference for the memo); ``pen_l``, ``pen_r`` (None: none)
    the decider's colour penalty of each vertex on the left and on the right (``_score_options``).

    Returns ``(left_flat, left_ptr, right_flat, right_ptr, features, iterations, complete)``:
    candidate k's left boundary is ``left_flat[left_ptr[k]:left_ptr[k+1]]`` (likewise right),
    its 8 ranking features ``features[k]`` (``rld.costs.ranking_features``, kept
    incrementally), in the order found; ``complete`` is True when the search ran out of
    options before the limit.
    """
    N = pts.shape[0]
    if dead_end < 0.0:
        dead_end = dead_end_score(pts, adj_ptr, adj_idx, max_turn, dist_weight)
    penL = np.zeros(0) if pen_l is None else pen_l
    penR = np.zeros(0) if pen_r is None else pen_r
    maxdeg = 1
    for v in range(N):
        d = adj_ptr[v + 1] - adj_ptr[v]
        if d > maxdeg:
            maxdeg = d
    L = np.empty(N, dtype=np.int64)
    R = np.empty(N, dtype=np.int64)
    in_path = np.zeros(N, dtype=np.bool_)
    L[0] = start_l
    R[0] = start_r
    nL = 1
    nR = 1
    for v in banned:
        in_path[v] = True
    in_path[start_l] = True
    in_path[start_r] = True
    # Per frame (depth): tried options of each side's end, the side that made the frame,
    # and the width query values.
    D = N + 1
    triedL = np.zeros((D, maxdeg), dtype=np.bool_)
    triedR = np.zeros((D, maxdeg), dtype=np.bool_)
    made_by = np.full(D, -1, dtype=np.int64)
    # The decider's memo: each side's option scores per frame (``_score_options``), valid
    # from the frame's first visit until an extension makes a new frame at that depth.
    scoreL = np.empty((D, maxdeg))
    scoreR = np.empty((D, maxdeg))
    scored = np.zeros(D, dtype=np.bool_)
    # Width values per frame (row) and path position (column). They start small and grow
    # (``grow_2d``) as the search goes deeper or the paths longer: a full (N + 1, N) block
    # per side was megabytes on a map of 400 cones, freshly paged in by every call (on one
    # such map the 250 iterations took 1.8 ms that way, 1.0 ms with the pages reused).
    cap = min(D, 64)
    wvL = np.empty((cap, cap))
    wsL = np.empty((cap, cap))
    wvR = np.empty((cap, cap))
    wsR = np.empty((cap, cap))
    # Guide prefix flags: on_gl[i] = L[:i+1] == guide_l[:i+1].
    on_gl = np.zeros(N, dtype=np.bool_)
    on_gr = np.zeros(N, dtype=np.bool_)
    on_gl[0] = guide_l.shape[0] > 0 and guide_l[0] == start_l
    on_gr[0] = guide_r.shape[0] > 0 and guide_r[0] == start_r

    cap = 64
    lf = np.empty(cap * 4, dtype=np.int64)
    rf = np.empty(cap * 4, dtype=np.int64)
    lp = np.zeros(cap + 1, dtype=np.int64)
    rp = np.zeros(cap + 1, dtype=np.int64)
    feats = np.empty((cap, 8))
    K = 0
    Lbox = np.empty((N, 4))
    Rbox = np.empty((N, 4))
    Lmid = np.empty((N, 2))
    Rmid = np.empty((N, 2))
    Lrad = np.empty(N)
    Rrad = np.empty(N)
    LblkBox = np.empty((N // BLOCK + 1, 4))
    RblkBox = np.empty((N // BLOCK + 1, 4))
    # Prefix sums by path position for the ranking features: length, squared segment length,
    # turn and squared turn (turns at vertices 1..i-1).
    Lcum = np.zeros(N)
    Lcum2 = np.zeros(N)
    Ltc = np.zeros(N)
    Ltc2 = np.zeros(N)
    Rcum = np.zeros(N)
    Rcum2 = np.zeros(N)
    Rtc = np.zeros(N)
    Rtc2 = np.zeros(N)

    d0 = math.hypot(pts[start_l, 0] - pts[start_r, 0], pts[start_l, 1] - pts[start_r, 1])
    wvL[0, 0] = d0
    wvR[0, 0] = d0
    iterations = 0
    complete = True
    if d0 < wmin or (pts[start_l, 0] == pts[start_r, 0] and pts[start_l, 1] == pts[start_r, 1]):
        # The start pair is already narrower than the lane can be: no extension can help, and
        # a zero-length back edge makes every ring non-simple.
        return lf[:0], lp[:1], rf[:0], rp[:1], feats[:0], 0, True
    depth = 0
    while True:
        if max_iterations > 0 and iterations >= max_iterations:
            complete = False
            break
        f = depth
        if not scored[f] or not memo:
            _score_options(pts, adj_ptr, adj_idx, L, nL, triedL[f], in_path, max_turn, hx, hy,
                           dist_weight, lookahead, dead_end, guide_l, on_gl[nL - 1], forbid_l,
                           scoreL[f], penL)
            _score_options(pts, adj_ptr, adj_idx, R, nR, triedR[f], in_path, max_turn, hx, hy,
                           dist_weight, lookahead, dead_end, guide_r, on_gr[nR - 1], forbid_r,
                           scoreR[f], penR)
            scored[f] = True
        kl, vl = _pick_option(adj_ptr, adj_idx, L[nL - 1], nL, triedL[f], scoreL[f], guide_l,
                              on_gl[nL - 1])
        kr, vr = _pick_option(adj_ptr, adj_idx, R[nR - 1], nR, triedR[f], scoreR[f], guide_r,
                              on_gr[nR - 1])
        if kl < 0 and kr < 0:
            # Frame exhausted: undo the extension that made it.
            if depth == 0:
                break
            s = made_by[depth]
            if s == 0:
                nL -= 1
                in_path[L[nL]] = False
            else:
                nR -= 1
                in_path[R[nR]] = False
            depth -= 1
            continue
        # Warm start: a side whose next guide cone is the chosen option goes first, so the
        # search rebuilds the previous lane before it explores beyond it.
        gl_next = on_gl[nL - 1] and nL < guide_l.shape[0] and kl >= 0 and vl == guide_l[nL]
        gr_next = on_gr[nR - 1] and nR < guide_r.shape[0] and kr >= 0 and vr == guide_r[nR]
        if kl < 0:
            side = 1
        elif kr < 0:
            side = 0
        elif gl_next != gr_next:
            side = 0 if gl_next else 1
        else:
            _, longL, longR = _width_state(wvL[f], wsL[f], nL, wvR[f], wsR[f], nR, wmin, wmax)
            if longL and not longR:
                side = 1  # an L query too wide: only R growing can fix it
            elif longR and not longL:
                side = 0
            else:
                pl = L[nL - 2] if nL >= 2 else -1
                pr = R[nR - 2] if nR >= 2 else -1
                # Left-right decider, eqs 4-5: the side whose extension keeps both equally
                # advanced.
                diff_l = _lrd_diff(pts, L[nL - 1], vl, pr, R[nR - 1], hx, hy)
                diff_r = _lrd_diff(pts, pl, L[nL - 1], R[nR - 1], vr, hx, hy)
                side = 0 if diff_l < diff_r else 1
        iterations += 1
        g = f + 1
        need_c = max(nL, nR) + 1  # the longer path after the extension
        if g >= wvL.shape[0] or need_c > wvL.shape[1]:
            rows = min(D, 2 * wvL.shape[0]) if g >= wvL.shape[0] else wvL.shape[0]
            cols = min(N, 2 * wvL.shape[1]) if need_c > wvL.shape[1] else wvL.shape[1]
            wvL = grow_2d(wvL, rows, cols)
            wsL = grow_2d(wsL, rows, cols)
            wvR = grow_2d(wvR, rows, cols)
            wsR = grow_2d(wsR, rows, cols)
        if side == 0:
            _grow_side(pts, L, nL, vl, kl, R, nR, triedL, triedR, f, g, in_path, Lbox, Lmid,
                       Lrad, LblkBox, Lcum, Lcum2, Ltc, Ltc2, on_gl, guide_l, wvL, wsL, wvR,
                       wsR, Rmid, Rrad)
            nL += 1
            new_edge = nL - 2
        else:
            _grow_side(pts, R, nR, vr, kr, L, nL, triedR, triedL, f, g, in_path, Rbox, Rmid,
                       Rrad, RblkBox, Rcum, Rcum2, Rtc, Rtc2, on_gr, guide_r, wvR, wsR, wvL,
                       wsL, Lmid, Lrad)
            nR += 1
            new_edge = nL  # the new R edge's ring index
        made_by[g] = side
        # C_poly: the new permanent edge, and (when nL + nR reaches 3) the back edge, which
        # only now becomes a ring edge; then the front edge.
        perm_ok = _edge_vs_ring(pts, L, nL, R, nR, new_edge, False, Lbox, Rbox, LblkBox,
                                RblkBox)
        if perm_ok and nL + nR == 3:
            perm_ok = not _edge_zero(pts, L, nL, R, nR, nL + nR - 1)
        short, longL, longR = _width_state(wvL[g], wsL[g], nL, wvR[g], wsR[g], nR, wmin, wmax)
        feasible = perm_ok and not short and not longL and not longR
        if feasible:
            feasible = _edge_vs_ring(pts, L, nL, R, nR, nL - 1, True, Lbox, Rbox, LblkBox,
                                     RblkBox)
        # A pair whose boundary leaves its start cone more than phi_max off the car's heading
        # (C_seg with the heading for the missing segment, as the decider takes it; ours) runs
        # back behind the car: no candidate. Its subtree is still walked, so the search, its
        # iterations and completeness stay the same (docs/clc.md, "First edges along the heading").
        emit = feasible
        if emit and nL >= 2 and _option_turn(pts, L, 1, L[1], hx, hy) > max_turn:
            emit = False
        if emit and nR >= 2 and _option_turn(pts, R, 1, R[1], hx, hy) > max_turn:
            emit = False
        if emit:
            need = lp[K] + nL
            if need > lf.shape[0]:
                lf = grow_int(lf, need)
            need = rp[K] + nR
            if need > rf.shape[0]:
                rf = grow_int(rf, need)
            if K + 2 > lp.shape[0]:
                lp = grow_int(lp, K + 2)
                rp = grow_int(rp, K + 2)
            if K + 1 > feats.shape[0]:
                feats = grow_rows(feats, K + 1)
            for i in range(nL):  # loops, not slice assignments (rld.geometry_kernels.grow_int)
                lf[lp[K] + i] = L[i]
            for i in range(nR):
                rf[rp[K] + i] = R[i]
            lp[K + 1] = lp[K] + nL
            rp[K + 1] = rp[K] + nR
            _features(wvL[g], wsL[g], nL, wvR[g], wsR[g], nR, Lcum, Lcum2, Ltc, Ltc2, Rcum,
                      Rcum2, Rtc, Rtc2, feats[K])
            K += 1
        # Backtracking decider (lemmas 1-3, made exact): a broken permanent ring edge or a
        # width below w_min is final; a width above w_max is final when the boundary that
        # could fix it has no option left in this subtree.
        backtrack = (not perm_ok) or short
        if not backtrack and longL:
            backtrack = not _has_option(pts, adj_ptr, adj_idx, R, nR, triedR[g], in_path,
                                        max_turn)
        if not backtrack and longR:
            backtrack = not _has_option(pts, adj_ptr, adj_idx, L, nL, triedL[g], in_path,
                                        max_turn)
        if backtrack:
            if side == 0:
                nL -= 1
                in_path[L[nL]] = False
            else:
                nR -= 1
                in_path[R[nR]] = False
        else:
            depth = g
            scored[g] = False  # a new frame at this depth
    return lf[: lp[K]], lp[: K + 1], rf[: rp[K]], rp[: K + 1], feats[:K], iterations, complete

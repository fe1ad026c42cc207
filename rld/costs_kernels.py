"""numba kernels of the CLC ranking features (Ivanov & Markgraf 2024, section VII), of the
turn roughness of CLC's dive judge (ours), and of RLD's objective terms (Brandes et al. 2020,
eqs 18, 20, 25, 29; the formulas live here once, ``rld.costs`` wraps them).

Called only through ``rld.costs``; plain float64 and int64 arrays in, outputs filled in place
(a float out for the roughness), nothing of numba leaks out. Turn angles come from the shared kernel
``rld.geometry_kernels.turn_angle``, so a turn means the same here as in C_seg (CLC eq. 15) and
in RLD's angle cost (eq. 20). Variances are population variances computed in two passes (mean
first, then the mean squared deviation, as ``numpy.var``), 0 for fewer than two values.
"""

from __future__ import annotations

import math

import numpy as np

from rld._jit import njit
from rld.geometry_kernels import point_polyline_distance_many, turn_angle

#: Length of the feature vector (``rld.costs.FEATURE_NAMES``).
N_FEATURES = 8


@njit(cache=True)
def _segment_stats(xy, closed):
    """Sum and population variance of the segment lengths of the polyline ``xy`` (k, 2),
    metres and m^2; a closed polyline (k >= 2) also has the segment from the last vertex back to
    the first."""
    k = xy.shape[0]
    ns = k if closed and k >= 2 else max(k - 1, 0)
    if ns == 0:
        return 0.0, 0.0
    total = 0.0
    for i in range(ns):
        j = (i + 1) % k
        total += math.hypot(xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1])
    if ns < 2:
        return total, 0.0
    mean = total / ns
    acc = 0.0
    for i in range(ns):
        j = (i + 1) % k
        d = math.hypot(xy[j, 0] - xy[i, 0], xy[j, 1] - xy[i, 1]) - mean
        acc += d * d
    return total, acc / ns


@njit(cache=True)
def _turn(xy, k, i):
    """Signed turn (rad) at vertex i of the ring ``xy[:k]``, from segment i-1,i to i,i+1."""
    a = (i - 1) % k
    c = (i + 1) % k
    return turn_angle(xy[a, 0], xy[a, 1], xy[i, 0], xy[i, 1], xy[c, 0], xy[c, 1])


@njit(cache=True)
def _turn_var(xy, closed):
    """Population variance (rad^2) of the signed turns at the interior vertices of ``xy`` (k, 2):
    vertices 1..k-2 of an open polyline, all k vertices of a closed one (k >= 3)."""
    k = xy.shape[0]
    if closed and k >= 3:
        lo, hi = 0, k
    else:
        lo, hi = 1, k - 1
    nt = hi - lo
    if nt < 2:
        return 0.0
    total = 0.0
    for i in range(lo, hi):
        total += _turn(xy, k, i)
    mean = total / nt
    acc = 0.0
    for i in range(lo, hi):
        d = _turn(xy, k, i) - mean
        acc += d * d
    return acc / nt


@njit(cache=True)
def _variance(x):
    """Population variance of the 1-D array ``x``; 0 for fewer than two values."""
    n = x.shape[0]
    if n < 2:
        return 0.0
    total = 0.0
    for i in range(n):
        total += x[i]
    mean = total / n
    acc = 0.0
    for i in range(n):
        d = x[i] - mean
        acc += d * d
    return acc / n


@njit(cache=True)
def _fill(L, R, widths, out, closed):
    len_l, seg_var_l = _segment_stats(L, closed)
    len_r, seg_var_r = _segment_stats(R, closed)
    out[0] = 0.5 * (len_l + len_r)
    out[1] = L.shape[0]
    out[2] = R.shape[0]
    out[3] = _variance(widths)
    out[4] = seg_var_l
    out[5] = seg_var_r
    out[6] = _turn_var(L, closed)
    out[7] = _turn_var(R, closed)


@njit(cache=True)
def lane_features(L, R, widths, out):
    """The 8 ranking features of CLC section VII of one open lane, written into ``out`` (8,).

    ``L`` (n, 2) and ``R`` (m, 2): float64 boundary points ordered from the car forward, metres;
    ``widths``: the lane's matching-line lengths W(L, R) (CLC eq. 12, metres). ``out``:
    [0] lane length, the mean of the two boundary polyline lengths (CLC eq. 7), m;
    [1] n and [2] m, the numbers of points; [3] variance of ``widths``, m^2;
    [4], [5] variance of the left and right segment lengths, m^2;
    [6], [7] variance of the left and right signed turn angles between consecutive segments
    (``turn_angle``), rad^2.

    A closed lane can be passed with its first point appended to each boundary: its closing
    segments then count, but the turn at the wrap (at the first vertex) is missing.
    ``closed_lane_features`` counts that turn too.
    """
    _fill(L, R, widths, out, False)


@njit(cache=True)
def closed_lane_features(L, R, widths, out):
    """``lane_features`` of a closed lane whose boundaries are the rings ``L`` (n, 2) and
    ``R`` (m, 2), first point not repeated: the closing segments count (for n >= 2) and so do
    the turns at every vertex (for n >= 3), as ``rld.geometry.polyline_turn_angles(closed=True)``
    and C_seg (CLC eq. 15) count them. ``widths`` are those of the closed lane
    (``rld.constraints.lane_widths(L, R, closed=True)``)."""
    _fill(L, R, widths, out, True)


# ----------------------------------------------------------------------------------------------
# RLD's objective terms (Brandes et al. 2020, eqs 18, 20, 25, 29) and the spacing regularity
# (ours): the one home of each formula. ``rld.costs`` wraps the array forms for numpy callers;
# ``open_path_costs`` sums them over many open paths at once (CLC's dive judge and ``rld_cost``
# ranker, where numpy's per-call overhead dominated: 146 us for one lane within the dive reach).


@njit(cache=True)
def spacing_term(length, expected, tolerance):
    """RLD eq. 18: ((D - d_e) / d_t)^4 for one edge of length D (metres)."""
    r = (length - expected) / tolerance
    r2 = r * r
    return r2 * r2


@njit(cache=True)
def angle_term(turn, tolerance):
    """RLD eq. 20 with theta_e = pi: (|turn| / theta_t)^4 for one signed turn (rad)."""
    r = abs(turn) / tolerance
    r2 = r * r
    return r2 * r2


@njit(cache=True)
def heading_term(ax, ay, bx, by, px, py, hx, hy, min_distance):
    """RLD eq. 25 for the edge a -> b: (|v x h| / d_car)^4, v = b - a (metres, not normalised),
    h the unit heading, d_car the distance from the car (px, py) to the edge's midpoint,
    floored at ``min_distance`` (ours: the paper divides by zero under the car)."""
    vx = bx - ax
    vy = by - ay
    cross = abs(vx * hy - vy * hx)
    d = max(math.hypot(0.5 * (ax + bx) - px, 0.5 * (ay + by) - py), min_distance)
    r = cross / d
    r2 = r * r
    return r2 * r2


@njit(cache=True)
def regularity_term(len_a, len_b, log_tolerance):
    """Spacing regularity (ours): (ln(D_a / D_b) / ln(rho_t))^2 for two consecutive edges."""
    r = math.log(len_a / len_b) / log_tolerance
    return r * r


@njit(cache=True)
def spacing_costs(lengths, expected, tolerance, out):
    for i in range(lengths.shape[0]):
        out[i] = spacing_term(lengths[i], expected, tolerance)


@njit(cache=True)
def angle_costs(turns, tolerance, out):
    for i in range(turns.shape[0]):
        out[i] = angle_term(turns[i], tolerance)


@njit(cache=True)
def heading_costs(a, b, px, py, hx, hy, min_distance, out):
    for i in range(a.shape[0]):
        out[i] = heading_term(a[i, 0], a[i, 1], b[i, 0], b[i, 1], px, py, hx, hy, min_distance)


@njit(cache=True)
def regularity_costs(len_a, len_b, log_tolerance, out):
    for i in range(len_a.shape[0]):
        out[i] = regularity_term(len_a[i], len_b[i], log_tolerance)


@njit(cache=True)
def open_path_costs(points, flat, ptr, px, py, hx, hy, expected, tolerance, w_spacing,
                    w_benefit, w_heading, min_distance, w_angle, angle_tolerance,
                    w_regularity, log_regularity, out):
    """RLD's objective (eq. 29, no colour) of each open path ``flat[ptr[k]:ptr[k + 1]]``
    (indices into ``points`` (N, 2), metres) into ``out[k]``: every edge's w_s s_ij + w_p p_ij
    - w_b (eqs 18, 25; ``w_heading`` 0 leaves the heading out), every interior cone's w_t
    t_ijk (eq. 20, the turn of ``geometry_kernels.turn_angle``) and, when ``w_regularity`` is
    not 0, its spacing regularity. A path of fewer than two cones costs 0."""
    for k in range(ptr.shape[0] - 1):
        lo = ptr[k]
        hi = ptr[k + 1]
        total = 0.0
        for i in range(lo, hi - 1):
            a = flat[i]
            b = flat[i + 1]
            ax, ay, bx, by = points[a, 0], points[a, 1], points[b, 0], points[b, 1]
            total += w_spacing * spacing_term(math.hypot(bx - ax, by - ay), expected,
                                              tolerance) - w_benefit
            if w_heading != 0.0:
                total += w_heading * heading_term(ax, ay, bx, by, px, py, hx, hy,
                                                  min_distance)
        for i in range(lo, hi - 2):
            a = flat[i]
            b = flat[i + 1]
            c = flat[i + 2]
            t = turn_angle(points[a, 0], points[a, 1], points[b, 0], points[b, 1],
                           points[c, 0], points[c, 1])
            total += w_angle * angle_term(t, angle_tolerance)
            if w_regularity != 0.0:
                total += w_regularity * regularity_term(
                    math.hypot(points[b, 0] - points[a, 0], points[b, 1] - points[a, 1]),
                    math.hypot(points[c, 0] - points[b, 0], points[c, 1] - points[b, 1]),
                    log_regularity)
        out[k] = total


@njit(cache=True)
def radius_cut(points, idx, px, py, radius):
    """How many cones ``rld.costs.within_radius`` keeps of the path ``idx`` (indices into
    ``points``): up to and with the first cone farther than ``radius`` (metres) from the car
    (px, py), at least two; all of them when none is that far."""
    n = idx.shape[0]
    for i in range(n):
        if math.hypot(points[idx[i], 0] - px, points[idx[i], 1] - py) > radius:
            return max(i + 1, 2) if n >= 2 else n
    return n


@njit(cache=True)
def width_second_differences(query, target, out):
    """out[k] (k < n - 2) = the second difference at query cone k + 1 of the matching-line
    lengths of ``query`` (n >= 3, 2) to the polyline ``target`` (m >= 2, 2), metres
    (``rld.costs.width_second_differences``)."""
    w = np.empty(query.shape[0])
    point_polyline_distance_many(query, target, w)
    for k in range(query.shape[0] - 2):
        out[k] = w[k] - 2.0 * w[k + 1] + w[k + 2]


@njit(cache=True)
def width_roughness(left, right):
    """Sum of the squared second differences of both boundaries' matching-line lengths, m^2
    (``rld.costs.width_roughness``); a side of fewer than 3 cones, or facing fewer than 2,
    adds 0."""
    total = 0.0
    for side in range(2):
        q = left if side == 0 else right
        t = right if side == 0 else left
        if q.shape[0] < 3 or t.shape[0] < 2:
            continue
        d2 = np.empty(q.shape[0] - 2)
        width_second_differences(q, t, d2)
        for k in range(d2.shape[0]):
            total += d2[k] * d2[k]
    return total


@njit(cache=True)
def reach_costs(points, lflat, lptr, rflat, rptr, px, py, hx, hy, radius, expected, tolerance,
                w_spacing, w_benefit, w_heading, min_distance, w_angle, angle_tolerance,
                w_regularity, log_regularity, w_width_rough, labels, w_color,
                near_radius, unknown, out):
    """For each open lane k (left ``lflat[lptr[k]:lptr[k + 1]]``, right likewise; indices into
    ``points`` (N, 2), metres), both boundaries cut at ``radius`` from the car (``radius_cut``)
    and ``out[k]`` = RLD's objective of the two cut paths (``open_path_costs``), + w_color
    times their colour cost (``boundary_color``, ``near_radius`` its start radius, ``unknown``
    its charge per unknown cone) when
    ``labels`` (side labels, (N,) int64) is not empty, + w_width_rough times their
    ``width_roughness`` when not 0, in that order: ``rld.costs.reach_costs``."""
    two = np.empty(2)
    ptr = np.empty(3, dtype=np.int64)
    for k in range(lptr.shape[0] - 1):
        L = lflat[lptr[k]:lptr[k + 1]]
        R = rflat[rptr[k]:rptr[k + 1]]
        L = L[:radius_cut(points, L, px, py, radius)]
        R = R[:radius_cut(points, R, px, py, radius)]
        flat = np.empty(L.shape[0] + R.shape[0], dtype=np.int64)
        nl = L.shape[0]
        for i in range(nl):  # loops, not slice assignments (rld.geometry_kernels.grow_int)
            flat[i] = L[i]
        for i in range(R.shape[0]):
            flat[nl + i] = R[i]
        ptr[0] = 0
        ptr[1] = L.shape[0]
        ptr[2] = flat.shape[0]
        open_path_costs(points, flat, ptr, px, py, hx, hy, expected, tolerance, w_spacing,
                        w_benefit, w_heading, min_distance, w_angle, angle_tolerance,
                        w_regularity, log_regularity, two)
        cost = 0.0 + (two[0] + two[1])
        if labels.shape[0] > 0 and w_color != 0.0:
            cost += w_color * (boundary_color(points, labels, L, False, px, py, hx, hy,
                                              near_radius, unknown)
                               + boundary_color(points, labels, R, False, px, py, hx, hy,
                                                near_radius, unknown))
        if w_width_rough != 0.0:
            lxy = np.empty((L.shape[0], 2))
            rxy = np.empty((R.shape[0], 2))
            for i in range(L.shape[0]):
                lxy[i, 0] = points[L[i], 0]
                lxy[i, 1] = points[L[i], 1]
            for i in range(R.shape[0]):
                rxy[i, 0] = points[R[i], 0]
                rxy[i, 1] = points[R[i], 1]
            cost += w_width_rough * width_roughness(lxy, rxy)
        out[k] = cost


@njit(cache=True)
def _differ(a, b):
    """Side labels ``a`` and ``b`` name different sides (left 1, right 2; unknown 0 and either
    3 name no side and differ from nothing)."""
    return (a == 1 or a == 2) and (b == 1 or b == 2) and a != b


@njit(cache=True)
def car_side(points, i, px, py, hx, hy):
    """The side of the car (px, py, unit heading hx, hy) cone i lies on, as a side label: 1
    left (car-frame y > 0), 2 right (y < 0), 0 on the axis."""
    y = hx * (points[i, 1] - py) - hy * (points[i, 0] - px)
    return 1 if y > 0.0 else (2 if y < 0.0 else 0)


@njit(cache=True)
def boundary_color(points, labels, path, closed, px, py, hx, hy, near_radius, unknown):
    """The colour cost of one boundary ``path`` (indices into ``points`` and ``labels``, side
    labels): 1/2 for each edge whose two cones' labels name different sides, 1/2 for each
    three consecutive cones whose middle one names no side and whose outer ones name
    different sides, (open paths) 1/2 for each end within ``near_radius`` of the car whose
    label contradicts the side of the car it lies on (``car_side``), and ``unknown`` for each
    cone labelled unknown (0). 0 for fewer than two cones. ``rld.costs.boundary_color_cost``."""
    n = path.shape[0]
    if n < 2:
        return 0.0
    total = 0.0
    if unknown != 0.0:
        for i in range(n):
            if labels[path[i]] == 0:
                total += unknown
    for e in range(n if closed and n > 2 else n - 1):
        if _differ(labels[path[e]], labels[path[(e + 1) % n]]):
            total += 0.5
    for t in range(n if closed and n > 2 else n - 2):
        mid = labels[path[(t + 1) % n]]
        if mid != 1 and mid != 2 and _differ(labels[path[t]], labels[path[(t + 2) % n]]):
            total += 0.5
    if not closed:
        for end in (path[0], path[n - 1]):
            if math.hypot(points[end, 0] - px, points[end, 1] - py) <= near_radius and \
                    _differ(labels[end], car_side(points, end, px, py, hx, hy)):
                total += 0.5
    return total


@njit(cache=True)
def lane_color_counts(points, labels, lflat, lptr, rflat, rptr, px, py, hx, hy, near_radius,
                      unknown, radius, out, counted):
    """For each open lane k (left ``lflat[lptr[k]:lptr[k + 1]]``, right likewise): ``out[k]`` =
    the ``boundary_color`` of its two boundaries, each cut at ``radius`` from the car (px, py)
    (``radius_cut``; ``radius`` <= 0: whole), and ``counted[k]`` the cones counted (those of
    sides of two cones or more): ``rld.costs.lane_color_costs``."""
    for k in range(lptr.shape[0] - 1):
        L = lflat[lptr[k]:lptr[k + 1]]
        R = rflat[rptr[k]:rptr[k + 1]]
        if radius > 0.0:
            L = L[:radius_cut(points, L, px, py, radius)]
            R = R[:radius_cut(points, R, px, py, radius)]
        out[k] = (boundary_color(points, labels, L, False, px, py, hx, hy, near_radius, unknown)
                  + boundary_color(points, labels, R, False, px, py, hx, hy, near_radius,
                                   unknown))
        counted[k] = (L.shape[0] if L.shape[0] >= 2 else 0) + \
            (R.shape[0] if R.shape[0] >= 2 else 0)

"""numba kernels of the CLC ranking features (Ivanov & Markgraf 2024, section VII) and of the
turn roughness of CLC's dive judge (ours).

Called only through ``rld.costs.ranking_features`` and ``rld.costs.turn_roughness``; plain
float64 arrays in, the (8,) feature vector filled in place (a float out for the roughness),
nothing of numba leaks out. Turn angles come from the shared kernel
``rld.geometry_kernels.turn_angle``, so a turn means the same here as in C_seg (CLC eq. 15) and
in RLD's angle cost (eq. 20). Variances are population variances computed in two passes (mean
first, then the mean squared deviation, as ``numpy.var``), 0 for fewer than two values.
"""

from __future__ import annotations

import math

from numba import njit

from rld.geometry_kernels import turn_angle

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
def turn_roughness(xy):
    """Sum of the squared differences (rad^2) of consecutive signed turns at the interior
    vertices 1..k-2 of the open polyline ``xy`` (k, 2); 0 for k < 4."""
    k = xy.shape[0]
    total = 0.0
    if k < 4:
        return total
    prev = _turn(xy, k, 1)
    for i in range(2, k - 1):
        t = _turn(xy, k, i)
        total += (t - prev) * (t - prev)
        prev = t
    return total


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

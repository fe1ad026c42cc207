"""numba kernels of the insertion rule (``rld.insertion``, called only through it): which cones
lie beside which edges, and the objective change of many insertions in one call, from the same
terms in the same order as ``rld.costs.lane_cost`` and ``boundary_color_cost`` (the same floats).
"""

from __future__ import annotations

import numpy as np

from rld._jit import njit
from rld.costs_kernels import boundary_color, open_path_costs
from rld.geometry_kernels import point_segment_distance, segment_parameter, turn_angle


@njit(cache=True)
def objective_deltas(points, flat, ptr, closed, sides, pos, cones, max_turn, expected,
                     tolerance, w_spacing, w_benefit, w_angle, angle_tolerance, w_regularity,
                     log_regularity, labels, w_color, unknown, out, ok):
    """For each k: cone ``cones[k]`` after position ``pos[k]`` of boundary ``sides[k]``
    (``flat[ptr[s]:ptr[s + 1]]``): ``ok[k]`` False past the turn limit, else ``out[k]`` = eq. 29
    (no heading; colour when ``labels`` is not empty) of the <= 5 cones about it less the <= 4."""
    local = np.empty(4, dtype=np.int64)
    with_c = np.empty(5, dtype=np.int64)
    lptr = np.zeros(2, dtype=np.int64)
    cost = np.empty(1)
    for k in range(sides.shape[0]):
        S = flat[ptr[sides[k]]:ptr[sides[k] + 1]]
        n = S.shape[0]
        i = pos[k]
        m = 0
        for d in range(-1, 3):  # _objective_delta's window: positions i - 1 .. i + 2
            j = i + d
            if closed:
                local[m] = S[j % n]
                m += 1
            elif 0 <= j < n:
                local[m] = S[j]
                m += 1
        at = 0
        while local[at] != S[i]:  # the first cone equal to S[i], as np.flatnonzero
            at += 1
        for j in range(at + 1):
            with_c[j] = local[j]
        with_c[at + 1] = cones[k]
        for j in range(at + 1, m):
            with_c[j + 1] = local[j]
        ok[k] = True
        for j in range(1, m):  # the turns of with_c (m + 1 cones), as polyline_turn_angles
            t = turn_angle(points[with_c[j - 1], 0], points[with_c[j - 1], 1],
                           points[with_c[j], 0], points[with_c[j], 1],
                           points[with_c[j + 1], 0], points[with_c[j + 1], 1])
            if abs(t) > max_turn:
                ok[k] = False
                break
        if not ok[k]:
            out[k] = np.nan
            continue
        lptr[1] = m + 1
        open_path_costs(points, with_c, lptr, 0.0, 0.0, 1.0, 0.0, expected, tolerance,
                        w_spacing, w_benefit, 0.0, 1.0, w_angle, angle_tolerance, w_regularity,
                        log_regularity, cost)
        a = cost[0]
        lptr[1] = m
        open_path_costs(points, local, lptr, 0.0, 0.0, 1.0, 0.0, expected, tolerance,
                        w_spacing, w_benefit, 0.0, 1.0, w_angle, angle_tolerance, w_regularity,
                        log_regularity, cost)
        delta = a - cost[0]
        if labels.shape[0]:  # the window's ends are no boundary ends: start radius -1 m
            delta += w_color * (
                boundary_color(points, labels, with_c[:m + 1], False, 0.0, 0.0, 1.0, 0.0, -1.0,
                               unknown)
                - boundary_color(points, labels, local[:m], False, 0.0, 0.0, 1.0, 0.0, -1.0,
                                 unknown))
        out[k] = delta


@njit(cache=True)
def beside(points, cones, edges, half_width, out):
    """out[k, e]: the foot of cone ``cones[k]`` lies strictly between the ends of edge
    ``edges[e]`` (``segment_parameter``), less than ``half_width`` (metres) from it."""
    for k in range(cones.shape[0]):
        px, py = points[cones[k], 0], points[cones[k], 1]
        for e in range(edges.shape[0]):
            ax, ay = points[edges[e, 0], 0], points[edges[e, 0], 1]
            bx, by = points[edges[e, 1], 0], points[edges[e, 1], 1]
            t = segment_parameter(px, py, ax, ay, bx, by)
            out[k, e] = (0.0 < t < 1.0
                         and point_segment_distance(px, py, ax, ay, bx, by) < half_width)

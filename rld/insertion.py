"""Cone insertion into a found lane: a cone beside an edge (a, b) of a boundary joins it as
a -> c -> b when that lowers RLD's objective (eq. 29, the shared ``lane_cost``) and breaks no
constraint; a boundary's far end extended by a map cone so (``extend_ends``). The one home of the
rules for the incremental solver's late insertions (``rld.incremental``) and CLC's far insertions
and end extensions (``clc.refine``, ``rld.api``); ours, in neither paper.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from rld import geometry as geo
from rld.constraints import blocked_by_fixed, lane_is_feasible
from rld.costs import boundary_color_cost, lane_cost
from rld.types import LaneParams, Pose

__all__ = ["boundary_edges", "insertion_delta", "insert_cones", "extend_ends", "MAX_END_CONES"]

#: Any pose: the objective changes the insertion makes carry no heading term.
_NO_POSE = Pose(0.0, 0.0, 0.0)


def boundary_edges(seq: np.ndarray, closed: bool = False) -> np.ndarray:
    """The edges (k, 2) of a boundary ``seq`` (cone indices in order), with the closing edge
    when ``closed``."""
    seq = np.asarray(seq, dtype=np.int64)
    seq = np.r_[seq, seq[:1]] if closed and seq.size else seq
    return np.column_stack([seq[:-1], seq[1:]])


def insertion_delta(points: np.ndarray, S: np.ndarray, i: int, c: int, lane_edges: np.ndarray,
                    params: LaneParams, closed: bool = False,
                    colors: np.ndarray | None = None) -> float | None:
    """The objective change of inserting cone ``c`` after position ``i`` of boundary ``S`` (the
    edges and turns it changes; with ``colors`` the colour cost's edge and skip terms too), or
    None when it breaks the turn limit or comes nearer than ``min_width_m`` to another edge
    of ``lane_edges`` (the whole lane's) or crosses one."""
    delta = _objective_delta(points, S, i, c, params, closed, colors)
    if delta is None or _blocked(points, S, i, c, lane_edges, params):
        return None
    return delta


def _objective_delta(points, S, i, c, params, closed, colors) -> float | None:
    """``insertion_delta`` without the width and crossing check (None: the turn limit): the
    cheap part, which rules most candidates out."""
    p = params
    n = S.size
    idx = [(i + k) % n if closed else i + k for k in (-1, 0, 1, 2)]
    idx = idx if closed else [j for j in idx if 0 <= j < n]
    local = S[idx]
    pos = int(np.flatnonzero(local == S[i])[0])
    with_c = np.insert(local, pos + 1, c)
    turns = geo.polyline_turn_angles(points[with_c])
    if np.any(np.abs(turns) > p.max_turn_angle_rad):
        return None
    delta = lane_cost(points, with_c, [], _NO_POSE, p, heading=False) - \
        lane_cost(points, local, [], _NO_POSE, p, heading=False)
    if colors is not None:
        # The window's ends are no boundary ends (a start radius of -1 m: no start term).
        delta += p.w_color * (
            boundary_color_cost(points, colors, with_c, _NO_POSE, -1.0, unknown=p.color_unknown)
            - boundary_color_cost(points, colors, local, _NO_POSE, -1.0,
                                  unknown=p.color_unknown))
    return delta


def _blocked(points, S, i, c, lane_edges, params) -> bool:
    """Whether the edges a -> c -> b cross or pinch another edge of ``lane_edges``."""
    a, b = int(S[i]), int(S[(i + 1) % S.size])
    same = np.all(np.sort(lane_edges, axis=1) == sorted((a, b)), axis=1)
    fixed = lane_edges[~same]
    # Only edges that can come within min_width_m of a -> c or c -> b (exact: a fixed edge
    # that near has its midpoint within this reach of c).
    u, v = points[fixed[:, 0]], points[fixed[:, 1]]
    new_len = max(float(np.hypot(*(points[a] - points[c]))),
                  float(np.hypot(*(points[b] - points[c]))))
    reach = new_len + params.min_width_m + 0.5 * np.hypot(*(v - u).T)
    fixed = fixed[np.hypot(*(0.5 * (u + v) - points[c]).T) <= reach + 1e-9]
    return bool(blocked_by_fixed(points, np.array([[a, c], [c, b]]), fixed,
                                 params.min_width_m).any())


def insert_cones(points: np.ndarray, sides: Sequence[np.ndarray], candidates: np.ndarray,
                 params: LaneParams, closed: bool = False, colors: np.ndarray | None = None,
                 allowed=None) -> tuple[list[np.ndarray], int]:
    """Each cone of ``candidates`` in turn joins the edge of ``sides`` (left, right) where
    inserting it lowers the objective most (``insertion_delta``), if any: an edge whose foot
    of the cone lies between its ends, less than half the minimum width from it.
    ``allowed(side, edges)``: a boolean mask of the edges that may take a cone (default all).
    Returns (the sides, insertions)."""
    sides = [np.asarray(S, dtype=np.int64).copy() for S in sides]
    half_width = params.min_width_m / 2
    count = 0
    for c in np.asarray(candidates, dtype=np.int64):
        per_side = [boundary_edges(S, closed) for S in sides]
        lane_edges = np.vstack(per_side)
        options = []
        for s_i, (S, e) in enumerate(zip(sides, per_side, strict=True)):
            if e.shape[0] == 0:
                continue
            a_xy, b_xy = points[e[:, 0]], points[e[:, 1]]
            t = geo.segment_parameter(points[c], a_xy, b_xy)
            ok = (t > 0) & (t < 1) & (geo.point_segment_distance(points[c], a_xy, b_xy)
                                       < half_width)
            if allowed is not None:
                ok &= allowed(s_i, e)
            for i in np.flatnonzero(ok):
                delta = _objective_delta(points, S, int(i), int(c), params, closed, colors)
                if delta is not None and delta < -1e-9:
                    options.append((delta, s_i, int(i)))
        # The cheapest edge the insertion breaks no constraint at (the check costs most).
        for _, s_i, i in sorted(options):
            if not _blocked(points, sides[s_i], i, int(c), lane_edges, params):
                sides[s_i] = np.insert(sides[s_i], i + 1, c)
                count += 1
                break
    return sides, count


#: The most cones ``extend_ends`` adds at one end of a boundary. Source: our choice (the
#: truth's ends that CLC missed on clean tracks were one or two cones).
MAX_END_CONES = 2


def extend_ends(points: np.ndarray, pose: Pose, sides: Sequence[np.ndarray],
                params: LaneParams, min_distance_m: float, colors: np.ndarray | None = None,
                max_cones: int = MAX_END_CONES) -> tuple[list[np.ndarray], int]:
    """Each open boundary (left, right) extended at its last cone by the map cone within
    ``max_cone_spacing_m`` that lowers RLD's objective most (``lane_cost``, eq. 29) where the
    lane stays feasible (``lane_is_feasible`` less w_max), both cones at least
    ``min_distance_m`` from the car; at most ``max_cones`` a side. Returns (sides, added)."""
    sides = [np.asarray(S, dtype=np.int64).copy() for S in sides]
    if min(S.size for S in sides) < 2:
        return sides, 0
    far = np.hypot(*(points - pose.xy).T) >= min_distance_m
    tree = None
    count = 0
    for s_i in (0, 1):
        for _ in range(max_cones):
            S = sides[s_i]
            if not far[S[-1]]:
                break
            tree = cKDTree(points) if tree is None else tree
            near = np.asarray(tree.query_ball_point(points[S[-1]], params.max_cone_spacing_m),
                              dtype=np.int64)
            cand = np.setdiff1d(near[far[near]], np.concatenate(sides))
            if cand.size == 0:
                break
            base = lane_cost(points, S, [], pose, params, colors=colors)
            trials = [np.r_[S, c] for c in cand]
            deltas = [lane_cost(points, T, [], pose, params, colors=colors) - base
                      for T in trials]
            added = False
            for k in np.argsort(deltas, kind="stable"):
                if deltas[k] >= -1e-9:
                    break
                new = list(sides)
                new[s_i] = trials[k]
                if lane_is_feasible(points[new[0]], points[new[1]], params, max_width=False):
                    sides, added = new, True
                    count += 1
                    break
            if not added:
                break
    return sides, count

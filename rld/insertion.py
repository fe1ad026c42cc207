"""Cone insertion into a found lane: a cone beside an edge (a, b) of a boundary joins it as
a -> c -> b when that lowers RLD's objective (eq. 29, the shared ``lane_cost``) and breaks no
constraint; a boundary's far end extended by a map cone so (``extend_ends``), a lap's first cone
(``extend_starts``); a cone near the car swapped for a map cone beside it where CLC's judge
prefers it (``swap_cones``). The one home of the rules for the incremental solver's late
insertions (``rld.incremental``) and CLC's far insertions, end extensions and swaps
(``clc.refine``, ``rld.api``); ours, in neither paper.
"""

from __future__ import annotations

import math
from collections.abc import Sequence

import numpy as np
from scipy.spatial import cKDTree

from rld import insertion_kernels as ik
from rld.constraints import blocked_by_fixed, lane_is_feasible
from rld.costs import JOG_THRESHOLD_M, jog_positions, lane_cost, reach_costs
from rld.types import LaneParams, Pose

__all__ = ["boundary_edges", "beside", "insertion_delta", "insert_cones", "extend_ends",
           "extend_starts", "swap_cones", "MAX_END_CONES", "START_LINE_M", "SWAP_RADIUS_M"]

#: ``extend_starts``: a cone farther than this (metres) from the line of a boundary's first edge
#: does not begin it (false positives beside the car). Chosen: docs/tuning.md#lap_start.
START_LINE_M = 1.0
#: ``swap_cones``: a boundary cone may give way to an unused map cone this near it, metres.
#: Chosen by measurement: docs/tuning.md#swap_cones.
SWAP_RADIUS_M = 1.5
#: No colours: the kernel's empty label array.
_NO_LABELS = np.zeros(0, dtype=np.int64)


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
    S = np.asarray(S, dtype=np.int64)
    delta, ok = _objective_deltas(points, [S], np.zeros(1, dtype=np.int64),
                                  np.array([i], dtype=np.int64), np.array([c], dtype=np.int64),
                                  params, closed, colors)
    if not ok[0] or _blocked(points, S, i, c, lane_edges, params):
        return None
    return float(delta[0])


def _objective_deltas(points, sides, side, pos, cones, params, closed, colors):
    """``insertion_delta`` without the width and crossing check, for cone ``cones[k]`` after
    position ``pos[k]`` of ``sides[side[k]]``, in one compiled call: (deltas, ok), ok False
    past the turn limit. The cheap part, which rules most candidates out."""
    p = params
    flat = np.ascontiguousarray(np.concatenate(sides), dtype=np.int64)
    ptr = np.concatenate([[0], np.cumsum([S.size for S in sides])]).astype(np.int64)
    out = np.empty(side.size)
    ok = np.empty(side.size, dtype=np.bool_)
    ik.objective_deltas(np.ascontiguousarray(points, dtype=np.float64), flat, ptr, bool(closed),
                        side, pos, cones, float(p.max_turn_angle_rad),
                        float(p.expected_spacing_m), float(p.spacing_tolerance_m),
                        float(p.w_spacing), float(p.w_benefit), float(p.w_angle),
                        float(p.angle_tolerance_rad), float(p.w_regularity),
                        math.log(p.regularity_tolerance) if p.w_regularity else 1.0,
                        _NO_LABELS if colors is None
                        else np.ascontiguousarray(colors, dtype=np.int64),
                        float(p.w_color), float(p.color_unknown), out, ok)
    return out, ok


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
    cands = np.asarray(candidates, dtype=np.int64).reshape(-1)
    count = first = 0
    while first < cands.size:
        # The options of every cone still to come against the sides as they are; after an
        # insertion, those of the cones after it again.
        rest = cands[first:]
        per_side = [boundary_edges(S, closed) for S in sides]
        lane_edges = np.vstack(per_side)
        found = [np.nonzero(beside(points, rest, e, params.min_width_m / 2,
                                    None if allowed is None or e.shape[0] == 0
                                    else allowed(s_i, e)))
                 for s_i, e in enumerate(per_side)]
        which = np.concatenate([f[0] for f in found])
        side = np.concatenate([np.full(f[0].size, s_i, dtype=np.int64)
                               for s_i, f in enumerate(found)])
        pos = np.concatenate([f[1] for f in found]).astype(np.int64)
        if which.size == 0:
            break
        delta, ok = _objective_deltas(points, sides, side, pos, rest[which], params, closed,
                                      colors)
        good = ok & (delta < -1e-9)
        which, side, pos, delta = which[good], side[good], pos[good], delta[good]
        done = None
        for k in np.unique(which).tolist():
            at = which == k
            # The cheapest edge the insertion breaks no constraint at (the check costs most).
            for _, s_i, i in sorted(zip(delta[at].tolist(), side[at].tolist(),
                                        pos[at].tolist(), strict=True)):
                c = int(rest[k])
                if not _blocked(points, sides[s_i], i, c, lane_edges, params):
                    sides[s_i] = np.insert(sides[s_i], i + 1, c)
                    count += 1
                    done = k
                    break
            if done is not None:
                break
        if done is None:
            break
        first += done + 1
    return sides, count


def beside(points: np.ndarray, cones: np.ndarray, edges: np.ndarray, half_width: float,
           allowed: np.ndarray | None = None) -> np.ndarray:
    """(cones, edges) bool, ``insert_cones``' test: the cone's foot lies strictly between the
    edge's ends, less than ``half_width`` (metres) from it, and the edge is ``allowed``."""
    out = np.zeros((cones.size, edges.shape[0]), dtype=np.bool_)
    if out.size:
        ik.beside(np.ascontiguousarray(points, dtype=np.float64),
                  np.ascontiguousarray(cones, dtype=np.int64),
                  np.ascontiguousarray(edges, dtype=np.int64), float(half_width), out)
    return out if allowed is None else out & allowed


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
            new = _cheapest(points, pose, sides, s_i, [np.r_[S, c] for c in cand], params,
                            colors)
            if new is None:
                break
            sides, count = new, count + 1
    return sides, count


def _cheapest(points, pose, sides, s_i, trials, params, colors):
    """``sides`` with side ``s_i`` replaced by the trial that lowers its ``lane_cost`` most
    where ``lane_is_feasible`` (less w_max) holds, or None when none lowers it so."""
    base = lane_cost(points, sides[s_i], [], pose, params, colors=colors)
    deltas = [lane_cost(points, T, [], pose, params, colors=colors) - base for T in trials]
    for k in np.argsort(deltas, kind="stable"):
        if deltas[k] >= -1e-9:
            return None
        new = list(sides)
        new[s_i] = trials[k]
        if lane_is_feasible(points[new[0]], points[new[1]], params, max_width=False):
            return new
    return None


def extend_starts(points: np.ndarray, pose: Pose, sides: Sequence[np.ndarray],
                  params: LaneParams, colors: np.ndarray | None = None
                  ) -> tuple[list[np.ndarray], int]:
    """Each open boundary (left, right) begun one cone earlier: by the map cone within
    ``max_cone_spacing_m`` of its first, between the car's line across and it along the heading,
    at most ``START_LINE_M`` off its first edge's line, that lowers RLD's objective most
    (``lane_cost``, eq. 29) where the lane stays feasible (less w_max). Returns (sides, added)."""
    sides = [np.asarray(S, dtype=np.int64).copy() for S in sides]
    if min(S.size for S in sides) < 2:
        return sides, 0
    along = (points - pose.xy) @ pose.heading
    tree = cKDTree(points)
    count = 0
    for s_i in (0, 1):
        S = sides[s_i]
        near = np.asarray(tree.query_ball_point(points[S[0]], params.max_cone_spacing_m),
                          dtype=np.int64)
        d = points[S[1]] - points[S[0]]
        d = d / max(float(np.hypot(*d)), 1e-12)
        v = points[near] - points[S[0]]
        off = np.abs(d[0] * v[:, 1] - d[1] * v[:, 0])  # from the first edge's line
        cand = np.setdiff1d(near[(along[near] >= 0) & (along[near] < along[S[0]])
                                 & (off <= START_LINE_M)], np.concatenate(sides))
        new = _cheapest(points, pose, sides, s_i, [np.r_[c, S] for c in cand], params, colors)
        if new is not None:
            sides, count = new, count + 1
    return sides, count


def swap_cones(points: np.ndarray, pose: Pose, sides: Sequence[np.ndarray], params: LaneParams,
               reach_m: float, colors: np.ndarray | None = None) -> tuple[list[np.ndarray], int]:
    """The open lane (left, right) with at most one cone swapped: of the lanes with one cone at a
    width jog (``jog_positions`` above ``JOG_THRESHOLD_M``) within ``reach_m`` replaced by an
    unused map cone within ``SWAP_RADIUS_M``, the one CLC's judge prefers most (``reach_costs``:
    eq. 29 plus the width roughness), if it beats the lane and stays feasible (less w_max)."""
    sides = [np.asarray(S, dtype=np.int64).copy() for S in sides]
    if min(S.size for S in sides) < 2:
        return sides, 0
    tree = cKDTree(points)
    used = set(np.concatenate(sides).tolist())
    trials = []
    for s_i, j in jog_positions(points, pose, sides[0], sides[1], JOG_THRESHOLD_M, reach_m):
        for c in tree.query_ball_point(points[sides[s_i][j]], SWAP_RADIUS_M):
            if c not in used:
                new = list(sides)
                new[s_i] = sides[s_i].copy()
                new[s_i][j] = c
                trials.append(new)
    if not trials:
        return sides, 0
    costs = reach_costs(points, pose, params, [sides, *trials], reach_m, colors)
    for k in np.argsort(costs[1:], kind="stable"):
        if costs[1 + k] >= costs[0] - 1e-9:
            break
        L, R = trials[k]
        if lane_is_feasible(points[L], points[R], params, max_width=False):
            return trials[k], 1
    return sides, 0

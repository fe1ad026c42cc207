"""CLC's refinement stage (ours, beyond Ivanov & Markgraf 2024): local edits of the ranked lane,
judged by RLD's objective within ``Refinement.reach_m`` of the car.

The depth-first search changes a choice near the car only after it has exhausted everything
beyond it, which under it_max it never does. ``refine`` takes the ranked winner and, in up to
``Refinement.rounds`` rounds, searches again from its close calls (*dives*: the close calls of
the next-vertex decider, the width jogs, every choice of a lane that stops short) and offers the
lane without one cone of a close pair; the *judge* (``dive_cost``: RLD's eq. 29 within the
reach, plus the width roughness) keeps the cheapest lane. It then closes the winner (IV-E), drops
a closed lane's false join cone, trims an open lane's cones behind the car, inserts the cones
it skips beyond the reach and extends its far ends. Every part but the last two is there because
switching it off alone raised a geometric critical rate on the choosing and the reporting sets
(docs/ablation.md); those two lie beyond that rule's reach by construction and serve the index
rule and the agreement with RLD (docs/clc.md). ``Refinement`` switches them, ``refine=None``
in ``ClcModel`` leaves the paper's pipeline.
"""

from __future__ import annotations

import math
import time
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from clc import search_kernels as sk
from clc.search import SearchGraph, SearchResult, closable, enumerate_candidates
from rld import geometry as geo
from rld.constraints import lane_is_feasible
from rld.costs import (
    JOG_THRESHOLD_M,
    REACH_M,
    jog_positions,
    lane_cost,
    open_path_costs,
    ranking_features,
    reach_costs,
    width_roughness,
    within_radius,
)
from rld.insertion import (
    beside,
    boundary_edges,
    extend_ends,
    extend_starts,
    insert_cones,
    swap_cones,
)
from rld.types import LaneParams, Pose

__all__ = ["Refinement", "DEFAULT", "refine", "dive_cost", "dive_costs", "jog_positions",
           "path_ahead", "contested_dives", "claim_dive", "dive_at", "pair_drops", "trim_behind",
           "drop_ring_join", "ring_join_change", "far_insertions", "COUNTS"]

#: What ``refine`` counts, as ``lane.stats`` keys.
COUNTS = ("dives", "dive_rounds", "short_lane_rounds", "jog_dives", "pair_drops", "dropped",
          "trimmed_behind", "inserted", "extended", "started_earlier", "swapped")


@dataclass(frozen=True)
class Refinement:
    """The parts of CLC's refinement stage and their settings; each default chosen by
    measurement (docs/tuning.md#<field>), each part kept by the ablation (docs/ablation.md).
    0 or False switches a part off; ``rounds=0`` leaves only the closing and the two trims."""

    rounds: int = 3
    """Rounds of dives and edits: a lane that wins a round has its own close calls revisited."""
    contested: bool = True
    """Dives at the close calls (``contested_dives`` at ``LaneParams.contested_margin``)."""
    jog_dives: int = 2
    """The most width-jog dives per round (``jog_positions``), largest jog first."""
    jog_threshold_m: float = JOG_THRESHOLD_M
    """A width jog: the second difference of the matching-line lengths above this, metres."""
    short_lane_m: float = 20.0
    """A boundary with less path ahead (metres) while the map reaches farther is short: every
    choice within the reach is revisited, the other side rebuilt too (the protocol's 20 m)."""
    pair_drops: bool = True
    """The lane without one cone of a close pair (``pair_drops``) is judged beside the dives."""
    pair_drop_m: float = 1.5
    """Two consecutive boundary cones nearer than this (metres) are a close pair."""
    dive_iterations: int = 40
    """Iterations of each dive beyond rebuilding the lane it follows."""
    reach_m: float = REACH_M
    """Metres of path ahead of the car within which close calls are revisited and the judge
    counts (the protocol's critical distance is 20 m)."""
    ring_join: bool = True
    """Drop a closed lane's join cone when the ring is cheaper without it (``drop_ring_join``)."""
    trim_behind: bool = True
    """Return an open lane from each boundary's first cone not behind the car
    (``trim_behind``)."""
    far_insertions: bool = True
    """Insert the cones the lane skips beyond ``reach_m`` along each boundary, where RLD's
    objective prefers them (``far_insertions``; the judge never looks there)."""
    end_extensions: bool = True
    """Extend each open boundary's last cone beyond ``reach_m`` from the car where RLD's
    objective prefers it (``rld.insertion.extend_ends``; the search stops short of the map)."""
    lap_start: bool = True
    """At the start of a lap (no start pair about the point ``start_lookback_m`` behind the
    car), begin each open boundary one cone earlier where RLD's objective prefers it
    (``rld.insertion.extend_starts``; the start pair about the car skips a cone beside it)."""
    swaps: bool = True
    """Swap one cone within ``reach_m`` for an unused map cone beside it where the judge prefers
    it (``rld.insertion.swap_cones``; a false positive near the line taken for a true cone)."""
    judge_color: bool = True
    """The judge's objective includes ``LaneParams.w_color`` times the colour cost when a call
    has colours (RLD's, as the rest of the judge). Chosen: docs/tuning.md#judge_color."""


#: The refinement ``ClcModel`` runs by default.
DEFAULT = Refinement()

Lane4 = tuple  # (left, right, closed, ranker score): the refinement's lane


def refine(points: np.ndarray, pose: Pose, params: LaneParams, res: SearchResult,
           winner: Lane4, score: Callable, colors: np.ndarray | None = None,
           edits: Refinement = DEFAULT, deadline: float = math.inf, lap_start: bool = False
           ) -> tuple[Lane4, dict, int, bool]:
    """The stage: dive rounds (when ``res`` is not complete and ``params.contested_margin`` >
    0), closing (IV-E), ring-join drop, trim-behind, far insertions, a lap's first cones (when
    ``lap_start``: no start pair behind the car), end extensions, swaps. ``score(candidates,
    features)``: the ranker's; ``colors`` reach the judge only with ``edits.judge_color``.
    Returns (lane, ``COUNTS``, dive iterations, cut short by ``deadline``)."""
    counts = dict.fromkeys(COUNTS, 0)
    iterations, cut = 0, False
    colors = colors if edits.judge_color else None  # the judge's; the search has its own
    if not res.complete and params.contested_margin > 0 and edits.rounds > 0:
        winner, iterations, cut = _rounds(points, pose, params, res, winner, score, colors,
                                          edits, deadline, counts)
    left, right, closed, value = winner
    if not closed and closable(res.graph, left, right):
        closed = lane_is_feasible(points[left], points[right], params, closed=True)
    if closed and edits.ring_join:
        left, right, counts["dropped"] = drop_ring_join(points, pose, params, res.graph, left,
                                                        right)
    if not closed and edits.trim_behind:
        left, right, counts["trimmed_behind"] = trim_behind(points, pose, params, left, right)
    if edits.far_insertions:
        left, right, counts["inserted"] = far_insertions(points, params, left, right,
                                                         bool(closed), edits.reach_m, colors)
    if not closed and edits.lap_start and lap_start:
        (left, right), counts["started_earlier"] = extend_starts(points, pose, (left, right),
                                                                 params, colors)
    if not closed and edits.end_extensions:
        (left, right), counts["extended"] = extend_ends(points, pose, (left, right), params,
                                                        edits.reach_m, colors)
    if not closed and edits.swaps:
        (left, right), counts["swapped"] = swap_cones(points, pose, (left, right), params,
                                                      edits.reach_m, colors)
    return (left, right, bool(closed), value), counts, iterations, cut


def _rounds(points, pose, p, res, winner, score, colors, edits, deadline, counts):
    """Up to ``edits.rounds`` rounds of dives and pair drops around ``winner``, each won by the
    lane ``dive_cost`` prefers (docs/clc.md, "Refinement")."""
    done: set[tuple] = set()
    iterations = rounds = 0
    cost = None  # the winner's, computed once a round has a contender
    beyond: list[bool] = []  # _short's memo: whether the map reaches beyond short_lane_m
    stopped: list[bool] = []  # a dive was not started at the deadline
    cut = False
    while rounds < edits.rounds:
        if time.perf_counter() > deadline:
            cut = True
            break
        rounds += 1
        left, right = winner[0], winner[1]
        budget = edits.dive_iterations + left.size + right.size
        margin = p.contested_margin if edits.contested else -np.inf
        dives = contested_dives(points, pose, p, res.graph, res.start, left, right, margin,
                                edits.reach_m, budget, skip=done, deadline=deadline,
                                stopped=stopped)
        if edits.short_lane_m > 0 and _short(points, pose, left, right, edits.short_lane_m,
                                             beyond):
            counts["short_lane_rounds"] += 1
            dives += contested_dives(points, pose, p, res.graph, res.start, left, right, np.inf,
                                     edits.reach_m, budget, skip=done, cut_other=True,
                                     deadline=deadline, stopped=stopped)
        jogs = (_jog_dives(points, pose, p, res, left, right, budget, done, edits, deadline,
                           stopped) if edits.jog_dives > 0 else [])
        counts["jog_dives"] += len(jogs)
        dives += jogs
        # Unchecked (check=False): the predicates only for a lane the judge prefers (_cheapest).
        drops = (pair_drops(points, pose, p, res.graph, left, right, edits.reach_m,
                            edits.pair_drop_m, check=False) if edits.pair_drops else [])
        counts["pair_drops"] += len(drops)
        # The judge's contenders in order (ties: the earlier): the drops, then each dive's best.
        contenders: list[tuple] = [(a, b, False, None) for a, b in drops]
        for dive in dives:
            counts["dives"] += 1
            iterations += dive.iterations
            if dive.candidates:
                s = score(dive.candidates, dive.features)
                k = int(np.argmax(s))
                contenders.append((*dive.candidates[k], float(s[k])))
        if not contenders:
            break
        if cost is None:
            cost = dive_cost(points, pose, p, *winner[:3], colors, edits.reach_m)
        best, best_cost = _cheapest(points, pose, p, contenders, cost, score, colors,
                                    edits.reach_m)
        if best is None:
            break
        winner, cost = best, best_cost
    counts["dive_rounds"] = rounds
    return winner, iterations, cut or bool(stopped)


def _cheapest(points, pose, p, contenders, cost, score, colors, reach_m):
    """The contender (left, right, closed, score or None for an unchecked drop) with the lowest
    ``dive_cost`` below ``cost`` (ties: the earlier), a drop only if ``lane_is_feasible``
    (checked cheapest first) and then scored; (None, cost) when none is."""
    costs = dive_costs(points, pose, p, contenders, colors, reach_m)
    for i in sorted(range(len(contenders)),
                    key=lambda i: costs[i] if math.isfinite(costs[i]) else math.inf):
        if not costs[i] < cost:
            break
        a, b, c, sc = contenders[i]
        if sc is None:
            if not lane_is_feasible(points[a], points[b], p):
                continue
            sc = float(score([(a, b, c)], ranking_features(points[a], points[b])[None, :])[0])
        return (a.copy(), b.copy(), c, sc), costs[i]
    return None, cost


def dive_cost(points: np.ndarray, pose: Pose, params: LaneParams, left: np.ndarray,
              right: np.ndarray, closed: bool = False, colors: np.ndarray | None = None,
              reach_m: float = Refinement.reach_m) -> float:
    """The judge's cost: RLD's objective (``lane_cost``, eq. 29, with ``colors``) of the lane
    cut at ``reach_m`` of the car (``within_radius``), plus ``params.w_width_roughness`` times
    the cut boundaries' ``width_roughness`` (ours); a closed lane's objective counts whole."""
    if not closed:
        return float(reach_costs(points, pose, params, [(left, right)], reach_m, colors)[0])
    a = within_radius(points, left, pose, reach_m)
    b = within_radius(points, right, pose, reach_m)
    cost = lane_cost(points, left, right, pose, params, closed=True, colors=colors)
    if params.w_width_roughness:
        cost += params.w_width_roughness * width_roughness(points[a], points[b])
    return cost


def dive_costs(points: np.ndarray, pose: Pose, params: LaneParams, lanes,
               colors: np.ndarray | None = None,
               reach_m: float = Refinement.reach_m) -> list[float]:
    """``dive_cost`` of every ``(left, right, closed, ...)`` of ``lanes``: the open ones in one
    compiled call (``rld.costs.reach_costs``), the closed ones one by one."""
    lanes = list(lanes)
    out = [0.0] * len(lanes)
    open_k = [k for k, lane in enumerate(lanes) if not lane[2]]
    if open_k:
        vals = reach_costs(points, pose, params, [lanes[k][:2] for k in open_k], reach_m, colors)
        for k, v in zip(open_k, vals.tolist(), strict=True):
            out[k] = v
    for k, lane in enumerate(lanes):
        if lane[2]:
            out[k] = dive_cost(points, pose, params, lane[0], lane[1], True, colors, reach_m)
    return out


def _jog_dives(points, pose, params, res, left, right, budget, done, edits=DEFAULT,
               deadline=math.inf, stopped=None):
    """Dives at the ``edits.jog_dives`` largest width jogs (``jog_positions``) not yet revisited
    (``done``); none starts after ``deadline`` (then ``True`` goes to ``stopped``)."""
    out = []
    for side, j in jog_positions(points, pose, left, right, edits.jog_threshold_m,
                                 edits.reach_m):
        if len(out) >= edits.jog_dives:
            break
        if time.perf_counter() > deadline:
            if stopped is not None:
                stopped.append(True)
            break
        path, other = (left, right) if side == 0 else (right, left)
        if claim_dive(done, side, path, j, other):
            out.append(dive_at(points, pose, params, res.graph, res.start, left, right, side,
                               j, budget)[0])
    return out


def _arc_behind(points: np.ndarray, path: np.ndarray, pose: Pose) -> float:
    """Path length (metres) of ``path`` up to where it crosses the line through the car across
    its heading (all of it when it never does, 0 when it starts past it)."""
    path = np.ascontiguousarray(path, dtype=np.int64)
    if path.size == 0:
        return 0.0
    return float(sk.arc_behind(points, path, float(pose.x), float(pose.y),
                               math.cos(pose.yaw), math.sin(pose.yaw)))


def path_ahead(points: np.ndarray, path: np.ndarray, pose: Pose) -> float:
    """Path length (metres) of ``path`` ahead of the car: its length less ``_arc_behind`` (0
    for one cone, or a path wholly behind the car)."""
    path = np.ascontiguousarray(path, dtype=np.int64)
    if path.size < 2:
        return 0.0
    return max(geo.polyline_length(points[path]) - _arc_behind(points, path, pose), 0.0)


def _short(points, pose, left, right, length_m, memo=None):
    """Whether a boundary has less than ``length_m`` of path ahead while the map holds a cone
    ahead of the car farther than that from it (the map's answer kept in ``memo`` if given)."""
    if min(path_ahead(points, left, pose), path_ahead(points, right, pose)) >= length_m:
        return False
    if memo is None or not memo:
        d = points - pose.xy
        far = bool(((d @ pose.heading > 0.0) & (np.hypot(d[:, 0], d[:, 1]) > length_m)).any())
        if memo is None:
            return far
        memo.append(far)
    return memo[0]


def contested_dives(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
                    start: tuple[int, int], left: np.ndarray, right: np.ndarray,
                    margin: float, reach_m: float, iterations: int,
                    skip: set | None = None, cut_other: bool = False,
                    deadline: float = math.inf,
                    stopped: list | None = None) -> list[SearchResult]:
    """Dives at the close calls of a lane: for every position j of ``left`` or ``right`` within
    ``reach_m`` of path ahead of the car where the decider's runner-up scored at most
    ``margin`` (rad) above the cone taken (``search_kernels.contested_positions``), a search of
    ``iterations`` follows the lane up to j and may not take that cone next (``dive_at``); when
    it took the cone later, a second search bans it. One result per search, left first.

    ``skip``: the dives already made (``claim_dive`` keys), updated. ``cut_other``: the other
    boundary is rebuilt from beside the choice too (``dive_at``; for a short lane, whose wrong
    choice may have bent the other side). No search starts after ``deadline``
    (``time.perf_counter()``); then ``True`` is appended to ``stopped``."""
    out = []
    hx, hy = float(np.cos(pose.yaw)), float(np.sin(pose.yaw))
    left = np.ascontiguousarray(left, dtype=np.int64)
    right = np.ascontiguousarray(right, dtype=np.int64)
    for side, path, other in ((0, left, right), (1, right, left)):
        reach = float(reach_m) + _arc_behind(points, path, pose)
        pos = sk.contested_positions(points, graph.indptr, graph.indices, path, other, hx, hy,
                                     float(params.max_turn_angle_rad),
                                     float(params.nvd_distance_weight),
                                     float(params.nvd_lookahead_weight), float(margin), reach,
                                     graph.dead_end(params),
                                     None if graph.side_penalty is None
                                     else graph.side_penalty[side])
        for j in pos:
            if time.perf_counter() > deadline:
                if stopped is not None:
                    stopped.append(True)
                return out
            if skip is not None and not claim_dive(skip, side, path, int(j), other, cut_other):
                continue
            res, guide = dive_at(points, pose, params, graph, start, left, right, side, int(j),
                                 iterations, cut_other)
            out.append(res)
            cone = int(path[j])
            lf, _, rf, _, _ = res.candidates.flat()
            if np.any(lf == cone) or np.any(rf == cone):
                out.append(enumerate_candidates(points, pose, params,
                                                max_iterations=iterations, graph=graph,
                                                start=start, guide=guide,
                                                banned=path[j:j + 1]))
    return out


def claim_dive(done: set, side: int, path: np.ndarray, j: int, other: np.ndarray,
               cut_other: bool = False) -> bool:
    """Whether the dive at position ``j`` of ``path`` (``side`` 0 left, 1 right) is still to be
    made, recorded in ``done`` if so; keyed by the path up to its cone, the other boundary and
    ``cut_other``, so that close-call and jog dives never repeat each other."""
    key = (side, path[:j + 1].tobytes(), other.tobytes(), bool(cut_other))
    if key in done:
        return False
    done.add(key)
    return True


def dive_at(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
            start: tuple[int, int], left: np.ndarray, right: np.ndarray, side: int, j: int,
            iterations: int, cut_other: bool = False) -> tuple[SearchResult, tuple]:
    """One dive: a search of ``iterations`` that follows the lane up to position ``j`` of
    boundary ``side`` and may not take its cone there (``forbid``); ``cut_other`` keeps of the
    other boundary only its cones up to the one nearest path[j - 1]. Returns (search, guide)."""
    path, other = (left, right) if side == 0 else (right, left)
    kept = other
    if cut_other and other.size > 1:
        d = points[other] - points[path[j - 1]]
        kept = other[: int(np.argmin(np.hypot(d[:, 0], d[:, 1]))) + 1]
    guide = (left[:j], kept) if side == 0 else (kept, right[:j])
    cone = int(path[j])
    res = enumerate_candidates(points, pose, params, max_iterations=iterations, graph=graph,
                               start=start, guide=guide,
                               forbid=(cone, -1) if side == 0 else (-1, cone))
    return res, guide


def pair_drops(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
               left: np.ndarray, right: np.ndarray, reach_m: float,
               pair_m: float = Refinement.pair_drop_m, check: bool = True
               ) -> list[tuple[np.ndarray, np.ndarray]]:
    """For every two consecutive cones of a boundary nearer than ``pair_m`` (metres), the first
    within ``reach_m`` (``within_radius``), the lane without the first and without the second:
    never a start cone, an interior one only where a graph edge joins its neighbours, and
    (``check``) only lanes passing ``lane_is_feasible``. A cone and a false positive beside it."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    out = []
    for side, p in enumerate(paths):
        if p.size < 3:
            continue
        head = within_radius(points, p, pose, reach_m).size
        for j in range(min(head, p.size - 1)):
            d = points[p[j + 1]] - points[p[j]]
            if math.hypot(d[0], d[1]) >= pair_m:
                continue
            for k in (j, j + 1):
                if k == 0 or (k < p.size - 1
                              and not graph.has_edge(int(p[k - 1]), int(p[k + 1]))):
                    continue
                trial = list(paths)
                trial[side] = np.delete(p, k)
                if not check or lane_is_feasible(points[trial[0]], points[trial[1]], params):
                    out.append((trial[0], trial[1]))
    return out


def trim_behind(points: np.ndarray, pose: Pose, params: LaneParams, left: np.ndarray,
                right: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """The open lane without the cones that begin a boundary behind the car
    (``geometry.leading_behind``, two cones a side kept) where ``lane_is_feasible`` still holds:
    both sides, else the left, else the right, else unchanged. Returns (left, right, trimmed)."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    cut = [geo.leading_behind(points[p], pose.xy, pose.heading) for p in paths]
    for take in ((True, True), (True, False), (False, True)):
        k = [c if t else 0 for c, t in zip(cut, take, strict=True)]
        if sum(k) == 0:
            continue
        trial = [p[j:] for p, j in zip(paths, k, strict=True)]
        if lane_is_feasible(points[trial[0]], points[trial[1]], params):
            return trial[0], trial[1], sum(k)
    return paths[0], paths[1], 0


def far_insertions(points: np.ndarray, params: LaneParams, left: np.ndarray, right: np.ndarray,
                   closed: bool, reach_m: float, colors: np.ndarray | None = None
                   ) -> tuple[np.ndarray, np.ndarray, int]:
    """The lane with the cones it skips inserted (``rld.insertion.insert_cones``: where RLD's
    objective drops) into its edges that begin ``reach_m`` or more along a boundary from its
    first cone, out of the judge's and the geometric rule's reach. Returns (left, right,
    insertions)."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]

    def far(side: int, e: np.ndarray) -> np.ndarray:  # the edges reach_m or more along
        lengths = np.hypot(*(points[e[:, 1]] - points[e[:, 0]]).T)
        return np.concatenate([[0.0], np.cumsum(lengths)[:-1]]) >= reach_m

    edges = [boundary_edges(p, closed) for p in paths]
    far_edges = np.vstack([e[far(s, e)] for s, e in enumerate(edges) if e.shape[0]]
                          or [np.zeros((0, 2), dtype=np.int64)])
    if far_edges.shape[0] == 0:
        return paths[0], paths[1], 0
    # The cones off the lane beside a far edge as insert_cones tests it, all at once.
    off = np.ones(points.shape[0], dtype=bool)
    off[np.concatenate(paths)] = False
    cand = np.flatnonzero(off)
    cand = cand[beside(points, cand, far_edges, 0.5 * params.min_width_m).any(axis=1)]
    if cand.size == 0:
        return paths[0], paths[1], 0
    (left, right), n = insert_cones(points, paths, cand, params, closed, colors, allowed=far)
    return left, right, n


def drop_ring_join(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
                   left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """A closed lane without a boundary's first cone (its ring's join; each side once, left
    first) where ``ring_join_change`` < 0, a graph edge joins the ring's last cone to its second
    and ``lane_is_feasible(closed=True)`` holds. Returns (left, right, cones dropped)."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    dropped = 0
    for side in (0, 1):
        p = paths[side]
        if p.size < 5 or not graph.has_edge(int(p[-1]), int(p[1])):
            continue
        if ring_join_change(points, pose, params, p) >= -1e-9:
            continue
        trial = list(paths)
        trial[side] = p[1:]
        if lane_is_feasible(points[trial[0]], points[trial[1]], params, closed=True):
            paths, dropped = trial, dropped + 1
    return paths[0], paths[1], dropped


def ring_join_change(points: np.ndarray, pose: Pose, params: LaneParams,
                     ring: np.ndarray) -> float:
    """The change of RLD's objective (eq. 29) of closed boundary ``ring`` (>= 5 cones) when its
    first cone is dropped: the terms of the five cones around it against the four without it
    (``open_path_costs``), equal to the change of ``lane_cost(closed=True)``."""
    p = np.asarray(ring, dtype=np.int64)
    if p.size < 5:
        raise ValueError(f"a ring of at least five cones is needed, got {p.size}")
    seqs = np.array([p[-2], p[-1], p[0], p[1], p[2], p[-2], p[-1], p[1], p[2]])
    cost = open_path_costs(points, seqs, np.array([0, 5, 9]), pose, params)
    return float(cost[1] - cost[0])

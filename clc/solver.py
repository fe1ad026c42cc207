"""The reusable CLC model (Ivanov & Markgraf 2024, Alg. 1): search, closings, ranking, warm
start.

``ClcModel.solve(points, pose)`` enumerates candidate lanes with ``clc.search`` and returns the
one the ranker scores highest as a ``Lane``. Warm start (IV-F, ``warm_start=True``): the previous
best lane is kept as positions; on the next call its cones are matched to the new map's cones
(nearest within 0.5 m: SLAM maps keep their cones), each boundary is cut to begin at the new
start vertex, and half the iterations follow it first (the lane grows at its far end), the other
half search afresh (so a wrong choice near the car can be undone); the ranker sees the
candidates of both. The guide only orders the search: with no iteration limit the candidates are
the same with or without it.

Closing (IV-E), deviation: the paper adds the closing of every closable candidate to the
candidates before ranking; we close only the ranked winner (when an edge joins each boundary's
last cone to its first and the closed lane passes the shared ``lane_is_feasible``). A closing
adds just the two closing edges to a candidate already found, and checking it costs the whole-path
predicate (about 0.5 ms on a full-lap lane), which for every closable candidate of a full map
(tens of them) would dominate the call.

Time: each search is bounded by ``max_iterations`` (its run time grows linearly with them, CLC
fig. 16), not by a clock inside the compiled loop. ``time_limit_s`` is checked between the
searches: past it, no search starts that would only refine a lane already found (runner-up
start pairs, the trapped search's rerun, the dives); ``lane.stats["cut_short"]`` says when that
happened and ``lane.stats["over_time_limit"]`` when the call still exceeded the budget (by at
most one search).
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
from scipy.spatial import cKDTree

from clc.ranker import get_ranker
from clc.search import (
    GRAPHS,
    claim_dive,
    closable,
    contested_dives,
    dive_at,
    drop_ring_join,
    enumerate_candidates,
    merge_results,
    outward_drops,
    pair_drops,
    path_ahead,
    skip_inserts,
    start_replacements,
    trim_behind,
    unhook,
)
from rld.constraints import lane_is_feasible, starting_vertex_pairs
from rld.costs import (
    lane_color_costs,
    lane_cost,
    ranking_features,
    reach_costs,
    turn_roughness,
    width_roughness,
    width_second_differences,
    within_radius,
)
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["ClcModel", "MATCH_TOLERANCE_M", "dive_cost", "dive_costs", "jog_positions",
           "start_pairs"]

log = logging.getLogger(__name__)

#: Warm start (``warm_start=True``): a previous lane cone is matched to the nearest map cone
#: within this many metres. Source: our choice, as ``rld.solver.MATCH_TOLERANCE_M``.
MATCH_TOLERANCE_M = 0.5
#: Iterations of each contested-choice dive (``clc.search.contested_dives``) beyond rebuilding
#: the lane it follows. Chosen by measurement: docs/tuning.md#dive_iterations.
DIVE_ITERATIONS = 40
#: How far along each boundary of the ranked lane (metres of path ahead of the car) close calls
#: are revisited, and the dive judge's radius; the protocol's critical distance is 20 m. Chosen
#: by measurement: docs/tuning.md#dive_reach_m.
DIVE_REACH_M = 25.0
#: Rounds of dives: a dive whose lane wins has its own close calls revisited. Chosen by
#: measurement: docs/tuning.md#dive_rounds.
DIVE_ROUNDS = 3
#: The dive judge's objective includes the colour cost (``LaneParams.w_color`` times
#: ``rld.costs.boundary_color_cost``) when a call has colours. Off: with ``w_color = 2`` it
#: raised the 0.5 m rate at A = 0.95 and 0.8. Chosen by measurement: docs/tuning.md#judge_color.
JUDGE_COLOR = False
#: The close-call dives (``contested_dives`` at ``LaneParams.contested_margin``); False turns
#: them off alone, keeping the rest of the dive rounds (for benchmarks/bench_ablation.py).
CONTESTED_DIVES = True
#: Jog dives (``jog_positions``): a width jog of the winner within the dive reach, where the second
#: difference of its matching-line lengths exceeds this (metres), is revisited like a close
#: call. Chosen by measurement: docs/tuning.md#jog_threshold_m.
JOG_THRESHOLD_M = 1.0
#: The most jog dives per round, the largest jogs first; 0 turns them off. Chosen by
#: measurement: docs/tuning.md#jog_dives.
JOG_DIVES = 2
#: The runner-up start pairs (``LaneParams.start_pairs``) are searched while the best candidate
#: so far has fewer than this many cones on its shorter side; the deepest wins (ties: the more
#: symmetric pair). Chosen by measurement: docs/tuning.md#min_start_depth.
MIN_START_DEPTH = 5
#: A winner with a boundary shorter than this (metres of path ahead of the car) while the map
#: holds cones farther ahead is *short*: every choice within the reach is revisited, the other
#: side rebuilt too; 0 turns it off. Source: the protocol's 20 m; docs/tuning.md#short_lane_m.
SHORT_LANE_M = 20.0
#: A main search that stops at it_max with fewer candidates than this was trapped: its start
#: pair is searched again with the give-up rule (``STALE_EXTENSIONS``) and both searches'
#: candidates ranked; 0 turns it off. Chosen by measurement: docs/tuning.md#trapped_candidates.
TRAPPED_CANDIDATES = 20
#: The give-up rule's run of infeasible extensions (``enumerate_candidates(stale=...)``).
#: Chosen by measurement: docs/tuning.md#stale_extensions.
STALE_EXTENSIONS = 8
#: In each dive round, the winner without one cone of a close pair (``clc.search.pair_drops``)
#: is judged beside the dives (``lane.stats["pair_drops"]``). Chosen by measurement:
#: docs/tuning.md#pair_drops.
PAIR_DROPS = True
#: The distance (metres) below which two consecutive boundary cones within the reach are a
#: close pair. Chosen by measurement: docs/tuning.md#pair_drop_m.
PAIR_DROP_M = 1.5
#: In each dive round, the winner with a skipped cone taken in (``clc.search.skip_inserts``)
#: is judged beside the dives (``lane.stats["skip_inserts"]``). Chosen by measurement:
#: docs/tuning.md#skip_inserts.
SKIP_INSERTS = True
#: In each dive round, the winner with a boundary's first cone replaced by a cone inside the lane
#: beside its first edge, at most this far from it (metres; ``clc.search.start_replacements``;
#: 0 turns it off). Chosen by measurement: docs/tuning.md#start_replace_m.
START_REPLACE_M = 1.5
#: A complete enumeration's pick is judged too, against its local edits only (a dive could only
#: find a lane the ranker has already seen). Chosen by measurement:
#: docs/tuning.md#judge_complete.
JUDGE_COMPLETE = True
#: After the dive rounds, up to this many passes in which the winner without one cone that bends
#: its boundary away from the lane (``clc.search.outward_drops``) is judged; 0 turns it off.
#: Chosen by measurement: docs/tuning.md#outward_drop_passes.
OUTWARD_DROP_PASSES = 2
#: What ``ClcModel._dive_rounds`` counts, as ``lane.stats`` keys.
ROUND_COUNTS = ("dives", "dive_rounds", "short_lane_rounds", "jog_dives", "pair_drops",
                "skip_inserts", "start_replacements", "outward_drops")
#: Drop a closed lane's join cone when the ring is cheaper without it (``drop_ring_join``).
#: Chosen by measurement: docs/tuning.md#ring_join.
RING_JOIN = True
#: Return an open lane from each boundary's first cone not behind the car
#: (``clc.search.trim_behind``). Chosen by measurement: docs/tuning.md#trim_behind.
TRIM_BEHIND = True
#: Undo a boundary's hook onto the other boundary's end (``clc.search.unhook``). Chosen by
#: measurement: docs/tuning.md#unhook.
UNHOOK = True


def dive_cost(points: np.ndarray, pose: Pose, params: LaneParams, left: np.ndarray,
              right: np.ndarray, closed: bool = False, colors: np.ndarray | None = None) -> float:
    """What the dive judge minimises (``ClcModel._dive_rounds``): RLD's objective (the shared
    ``lane_cost``, eq. 29) counted within ``DIVE_REACH_M`` of the car, plus
    ``params.w_width_roughness`` times the width roughness (``rld.costs.width_roughness``, ours)
    of the same part of each boundary (``within_radius``). The roughness tells a true cone from
    a false positive 0.6-1.5 m beside it when both make equally smooth lines: the false one
    jogs the width (measured in ``LaneParams.w_width_roughness``). Since 2026-12-03 also
    ``params.w_turn_roughness`` times the turn roughness of both boundaries' same parts
    (``rld.costs.turn_roughness``, ours): a false positive inserted between two true cones
    zigzags the boundary's turns without jogging the width much. With ``colors`` (side labels,
    since 2026-12-06) the objective includes ``params.w_color`` times the colour cost
    (``rld.costs.color_cost``). An open lane's is ``rld.costs.reach_costs`` (``dive_costs``
    weighs many at once)."""
    if not closed:
        return float(reach_costs(points, pose, params, [(left, right)], DIVE_REACH_M,
                                 colors)[0])
    # A closed lane's objective counts whole (``lane_cost``); its roughness, the cut sides'.
    a = within_radius(points, left, pose, DIVE_REACH_M)
    b = within_radius(points, right, pose, DIVE_REACH_M)
    cost = lane_cost(points, left, right, pose, params, closed=True, colors=colors)
    if params.w_width_roughness:
        cost += params.w_width_roughness * width_roughness(points[a], points[b])
    if params.w_turn_roughness:
        cost += params.w_turn_roughness * (turn_roughness(points[a]) + turn_roughness(points[b]))
    return cost


def dive_costs(points: np.ndarray, pose: Pose, params: LaneParams, lanes,
               colors: np.ndarray | None = None) -> list[float]:
    """``dive_cost`` of every ``(left, right, closed, ...)`` of ``lanes`` (with ``colors``):
    the open ones in one compiled call (``rld.costs.reach_costs``), the closed ones one by
    one."""
    lanes = list(lanes)
    out = [0.0] * len(lanes)
    open_k = [k for k, lane in enumerate(lanes) if not lane[2]]
    if open_k:
        vals = reach_costs(points, pose, params, [lanes[k][:2] for k in open_k], DIVE_REACH_M,
                           colors)
        for k, v in zip(open_k, vals.tolist(), strict=True):
            out[k] = v
    for k, lane in enumerate(lanes):
        if lane[2]:
            out[k] = dive_cost(points, pose, params, lane[0], lane[1], True, colors)
    return out


def jog_positions(points: np.ndarray, pose: Pose, left: np.ndarray, right: np.ndarray,
                  threshold_m: float, reach_m: float) -> list[tuple[int, int]]:
    """Where a lane's width jogs: the (side, j) of every cone ``left[j]`` (side 0) or
    ``right[j]`` (side 1) within ``reach_m`` of the car (``within_radius``) whose matching
    line to the other boundary (CLC eq. 9, ``point_polyline_distance``) differs from the mean of
    its two neighbours' by more than half of ``threshold_m``: the absolute second difference of
    the lengths exceeds ``threshold_m`` (metres). Largest jog first. A false positive 0.6-1.5 m
    beside the line that the lane takes is such a cone (``ClcModel._dive_rounds`` revisits
    it); a real lane's width changes smoothly."""
    out = []
    for side, path, other in ((0, left, right), (1, right, left)):
        idx = within_radius(points, path, pose, reach_m)
        d2 = np.abs(width_second_differences(points[idx], points[other]))
        out += [(-float(d2[k]), side, int(k) + 1) for k in np.flatnonzero(d2 > threshold_m)]
    return [(side, j) for _, side, j in sorted(out)]


def _jog_dives(points, pose, params, res, left, right, budget, done, deadline=math.inf,
               stopped=None):
    """Dives at the ``JOG_DIVES`` largest width jogs of the lane (``jog_positions``), as
    ``contested_dives`` does at a close call: follow the lane up to the cone, forbid it there,
    search on (without ``contested_dives``' second, banning search). Close calls already
    revisited (``done``, the same keys) are skipped. No dive starts after ``deadline``
    (``time.perf_counter()``); then ``True`` is appended to ``stopped``."""
    out = []
    for side, j in jog_positions(points, pose, left, right, JOG_THRESHOLD_M, DIVE_REACH_M):
        if len(out) >= JOG_DIVES:
            break
        if time.perf_counter() > deadline:
            if stopped is not None:
                stopped.append(True)
            break
        path, other = (left, right) if side == 0 else (right, left)
        if not claim_dive(done, side, path, j, other):
            continue
        out.append(dive_at(points, pose, params, res.graph, res.start, left, right, side, j,
                           budget)[0])
    return out


def _depth(res) -> int:
    """The most cones the shorter boundary of any candidate has (0: no candidate)."""
    if not res.candidates:
        return 0
    _, lp, _, rp, _ = res.candidates.flat()
    return int(np.minimum(np.diff(lp), np.diff(rp)).max())


def _map_beyond(points: np.ndarray, pose: Pose, length_m: float) -> bool:
    """Whether the map holds a cone ahead of the car (in front of the line through it across
    its heading) farther than ``length_m`` from it."""
    d = points - pose.xy
    far = (d @ pose.heading > 0.0) & (np.hypot(d[:, 0], d[:, 1]) > length_m)
    return bool(far.any())


def _short(points: np.ndarray, pose: Pose, left: np.ndarray, right: np.ndarray,
           length_m: float, memo: list[bool] | None = None) -> bool:
    """Whether a boundary of the lane reaches less than ``length_m`` metres of path ahead of
    the car (its path length less the part behind the car, ``clc.search.path_ahead``) while
    the map holds a cone ahead of the car farther than ``length_m`` from it (``_map_beyond``):
    the lane stops short of what the map shows. ``memo``, when given, keeps that second
    answer between calls (the dive rounds ask it at most once per solve, for a short lane)."""
    if min(path_ahead(points, left, pose), path_ahead(points, right, pose)) >= length_m:
        return False
    if memo is None:
        return _map_beyond(points, pose, length_m)
    if not memo:
        memo.append(_map_beyond(points, pose, length_m))
    return memo[0]


def start_pairs(points: np.ndarray, pose: Pose, params: LaneParams) -> list[tuple[int, int]]:
    """CLC's start pairs (IV-C, ``rld.constraints.starting_vertex_pairs``), best first, at most
    ``params.start_pairs``: those about the point ``params.start_lookback_m`` behind the car
    along its heading, then those about the car itself (the paper's), without repeats.

    Our addition (docs/clc.md, "Start cones behind the car"): about the car, the first cone of
    a boundary is a choice made with one edge of context, and a false positive 1-3 m beside
    the true first cone is as likely a start as the cone itself. Started behind the car, the
    search reaches that choice along the boundary it has already passed, where the next-vertex
    decider and the dive judge see the turn it makes; the lane is returned from its first cone
    not behind the car (``clc.search.trim_behind``). The pairs about the car follow, for a car
    with no cones behind it (the start of a lap); pairs narrower than ``start_min_width_m``
    still come after every wider pair, of either kind."""
    k = int(params.start_pairs)
    around = starting_vertex_pairs(points, pose, params.near_radius_m, k,
                                   params.start_min_width_m, params.start_behind_m,
                                   params.start_reach_m)
    back = float(params.start_lookback_m)
    if back <= 0:
        return around
    h = pose.heading
    behind = Pose(float(pose.x - back * h[0]), float(pose.y - back * h[1]), pose.yaw)
    first = starting_vertex_pairs(points, behind, params.near_radius_m, k,
                                  params.start_min_width_m, params.start_behind_m)
    pairs = first + [q for q in around if q not in first]
    # The pairs narrower than start_min_width_m still go after every wider one (a stable sort:
    # the order within each group stays).
    w = float(params.start_min_width_m)
    pairs.sort(key=lambda q: bool(np.hypot(*(points[q[0]] - points[q[1]])) < w))
    return pairs[:k]


def _match(prev_xy: np.ndarray, tree: cKDTree) -> np.ndarray:
    """Indices of the new cones nearest the previous boundary's positions, cut at the first
    one without a cone within the tolerance."""
    if prev_xy.shape[0] == 0:
        return np.zeros(0, dtype=np.int64)
    d, idx = tree.query(prev_xy, distance_upper_bound=MATCH_TOLERANCE_M)
    bad = np.flatnonzero(~np.isfinite(d))
    stop = bad[0] if bad.size else idx.size
    return np.asarray(idx[:stop], dtype=np.int64)


def _guide_from(seq: np.ndarray, start: int) -> np.ndarray:
    """The part of ``seq`` from ``start`` on (empty when ``start`` is not in it)."""
    hit = np.flatnonzero(seq == start)
    if hit.size == 0:
        return np.zeros(0, dtype=np.int64)
    out = seq[hit[0]:]
    _, first = np.unique(out, return_index=True)  # a repeated match ends the guide
    if first.size != out.size:
        out = out[: np.setdiff1d(np.arange(out.size), first).min()]
    return out


class ClcModel:
    """CLC with a pluggable ranker (``learned``, ``rld_cost``, ``longest`` or an object with
    ``score``), the search graph of IV-A (``radius``) or IV-B (``delaunay``), and warm starts
    from the previous lane (``warm_start=True``; off by default: docs/tuning.md#warm_start)."""

    def __init__(self, params: LaneParams, ranker="learned", graph: str = "radius",
                 warm_start: bool = False) -> None:
        if graph not in GRAPHS:
            raise ValueError(f"unknown search graph {graph!r}; use one of {GRAPHS}")
        self.params = params
        self.graph = graph
        self.warm_start = warm_start
        self.ranker_name = ranker if isinstance(ranker, str) else getattr(ranker, "name", "custom")
        try:
            self.ranker = get_ranker(ranker)
        except FileNotFoundError as exc:
            if ranker != "learned":
                raise
            log.warning("%s; ranking by lane length instead", exc)
            self.ranker = get_ranker("longest")
            self.ranker_name = "longest (no learned model)"
        self._prev: tuple[np.ndarray, np.ndarray] | None = None
        self._colors: np.ndarray | None = None  # this call's side labels (``solve``)
        self._judge_colors: np.ndarray | None = None  # the dive judge's (JUDGE_COLOR)
        #: Called as ``judge_hook(points, pose, winner, contenders)`` before each decision of
        #: the dive judge (``_cheapest``): ``winner`` is (left, right, closed, score), each
        #: contender (left, right, closed, score or None for an unchecked local edit). For
        #: ``rld bench clc-judge`` (benchmarks/bench_clc_judge.py); None in normal use.
        self.judge_hook = None

    def reset(self) -> None:
        """Forget the previous lane (no warm start on the next call)."""
        self._prev = None

    def _split_search(self, points, pose, start, guide):
        """Half the iterations follow the previous lane (its far end grows), half search from
        scratch (a wrong choice near the car can be undone); the ranker sees both."""
        it = self.params.max_iterations
        half = max(it // 2, 1) if it > 0 else 0
        a = enumerate_candidates(points, pose, self.params, graph=self.graph, start=start,
                                 guide=guide, max_iterations=half, colors=self._colors)
        b = enumerate_candidates(points, pose, self.params, graph=a.graph, start=start,
                                 max_iterations=max(it - half, 1) if it > 0 else 0)
        return merge_results(a, b)

    def _untrap(self, points, pose, res):
        """``(res, trapped)``: when the search was trapped (TRAPPED_CANDIDATES), ``res`` with
        the candidates of a second search from the same start pair under the give-up rule."""
        if (TRAPPED_CANDIDATES > 0 and not res.complete and res.start is not None
                and len(res.candidates) < TRAPPED_CANDIDATES):
            again = enumerate_candidates(points, pose, self.params, graph=res.graph,
                                         start=res.start, stale=STALE_EXTENSIONS)
            return merge_results(res, again), True
        return res, False

    def _dive_rounds(self, points, pose, res, winner, deadline=math.inf, search=True):
        """Up to DIVE_ROUNDS rounds of dives and local edits around ``winner`` (left, right,
        closed, score), judged by ``dive_cost`` within DIVE_REACH_M (m) of the car: returns the
        winner, ROUND_COUNTS, iterations, deadline hit. docs/clc.md, "Dive rounds"."""
        p = self.params
        done: set[tuple] = set()
        counts = dict.fromkeys(ROUND_COUNTS, 0)
        iterations = rounds = 0
        cost = None  # the winner's, computed once a dive has a lane to compare
        # Whether the map reaches beyond SHORT_LANE_M (_short): found at most once per call,
        # when a winner is short (it does not depend on the winner; 9 us on a 409-cone map).
        beyond: list[bool] = []
        cut = False
        stopped: list[bool] = []  # contested_dives stopped at the deadline
        while rounds < DIVE_ROUNDS:
            if time.perf_counter() > deadline:
                cut = True
                break
            rounds += 1
            left, right = winner[0], winner[1]
            budget = DIVE_ITERATIONS + left.size + right.size
            dives = []
            if search:
                dives = contested_dives(points, pose, p, res.graph, res.start, left, right,
                                        p.contested_margin if CONTESTED_DIVES else -np.inf,
                                        DIVE_REACH_M, budget, skip=done,
                                        deadline=deadline, stopped=stopped)
            if search and SHORT_LANE_M > 0 and _short(points, pose, left, right, SHORT_LANE_M,
                                                      beyond):
                # A short winner: also every choice within the reach, both boundaries rebuilt.
                counts["short_lane_rounds"] += 1
                dives += contested_dives(points, pose, p, res.graph, res.start, left, right,
                                         np.inf, DIVE_REACH_M, budget, skip=done,
                                         cut_other=True, deadline=deadline,
                                         stopped=stopped)
            if search and JOG_DIVES > 0:
                jogs = _jog_dives(points, pose, p, res, left, right, budget, done, deadline,
                                  stopped)
                counts["jog_dives"] += len(jogs)
                dives += jogs
            # The local edits of an open winner: the pair drops, then the skip inserts.
            # Unchecked (check=False): the predicates only for a lane the judge prefers, below.
            drops = (pair_drops(points, pose, p, res.graph, left, right, DIVE_REACH_M,
                                PAIR_DROP_M, check=False)
                     if PAIR_DROPS and not winner[2] else [])
            inserts = (skip_inserts(points, pose, p, res.graph, left, right, DIVE_REACH_M,
                                    check=False)
                       if SKIP_INSERTS and not winner[2] else [])
            counts["pair_drops"] += len(drops)
            counts["skip_inserts"] += len(inserts)
            starts = (start_replacements(points, pose, p, res.graph, left, right,
                                         START_REPLACE_M, PAIR_DROP_M, check=False)
                      if START_REPLACE_M > 0 and not winner[2] else [])
            counts["start_replacements"] += len(starts)
            # The lanes the judge weighs against the winner, in order (ties: the earlier lane):
            # the local edits (each scored by the ranker only if it wins), then each dive's
            # best.
            contenders: list[tuple] = [(a, b, False, None) for a, b in drops + inserts + starts]
            for dive in dives:
                counts["dives"] += 1
                iterations += dive.iterations
                if not dive.candidates:
                    continue
                s = self._score(points, pose, dive.candidates, dive.features)
                k = int(np.argmax(s))
                contenders.append((*dive.candidates[k], float(s[k])))
            if not contenders:
                break
            if cost is None:
                cost = dive_cost(points, pose, p, *winner[:3], self._judge_colors)
            if self.judge_hook is not None:
                self.judge_hook(points, pose, winner, contenders)
            best, best_cost, _ = self._cheapest(points, pose, contenders, cost)
            if best is None:
                break
            winner, cost = best, best_cost
        counts["dive_rounds"] = rounds
        # Outward drops, after the rounds: offered within them, a drop that wins a round sends
        # the next round's dives elsewhere, and the lanes they reach were worse (docs/clc.md at
        # commit 933288e).
        for _ in range(OUTWARD_DROP_PASSES):
            if winner[2] or time.perf_counter() > deadline:
                break
            # The predicates only for the lanes the judge prefers, cheapest first (each check
            # costs more than the judge): the same pick as checking every lane first.
            trials = outward_drops(points, pose, p, res.graph, winner[0], winner[1],
                                   DIVE_REACH_M, check=False)
            if not trials:
                break
            if cost is None:
                cost = dive_cost(points, pose, p, *winner[:3], self._judge_colors)
            trials = [(a, b, False, None) for a, b in trials]
            if self.judge_hook is not None:
                self.judge_hook(points, pose, winner, trials)
            best, best_cost, checked = self._cheapest(points, pose, trials, cost)
            counts["outward_drops"] += checked
            if best is None:
                break
            winner, cost = best, best_cost
        return (*winner, counts, iterations, cut or bool(stopped))

    def _cheapest(self, points, pose, contenders, cost):
        """The judge's pick among ``contenders`` (left, right, closed, ranker score or None for
        a local edit) against the winner's ``cost``: the one with the lowest ``dive_cost``
        below it (ties: the earlier contender). A local edit must pass the shared predicates
        (``lane_is_feasible``), checked only for the lanes below ``cost``, cheapest first (a
        check costs more than the judge; a dive's lanes are feasible already), and is scored by
        the ranker only if it wins. Returns (the pick or None, its cost, local edits checked)."""
        p = self.params
        costs = dive_costs(points, pose, p, contenders, self._judge_colors)
        checked = 0
        for i in sorted(range(len(contenders)),
                        key=lambda i: costs[i] if math.isfinite(costs[i]) else math.inf):
            if not costs[i] < cost:
                break
            a, b, c, sc = contenders[i]
            if sc is None:
                checked += 1
                if not lane_is_feasible(points[a], points[b], p):
                    continue
                f = ranking_features(points[a], points[b])[None, :]
                sc = float(self._score(points, pose, [(a, b, c)], f)[0])
            return (a.copy(), b.copy(), c, sc), costs[i], checked
        return None, cost, checked

    def _score(self, points, pose, candidates, features) -> np.ndarray:
        """The ranker's scores of ``candidates``, less ``params.rank_color_weight`` times each
        one's colour cost within ``DIVE_REACH_M`` per cone counted there
        (``rld.costs.lane_color_costs(share=True)``) when this call has colours: the learned
        ranker's features are fixed by its trained weights, so colour enters after it; per
        cone, so that it does not trade against the lane's length."""
        s = np.asarray(self.ranker.score(points, pose, self.params, candidates, features),
                       dtype=np.float64)
        w = self.params.rank_color_weight
        if self._colors is None or w == 0 or s.size == 0:
            return s
        return s - w * lane_color_costs(points, self._colors, candidates, pose, DIVE_REACH_M,
                                        share=True, near_radius_m=self.params.near_radius_m)

    def solve(self, points: np.ndarray, pose: Pose, colors=None, time_limit_s=None,
              confidence=None) -> Lane:
        t0 = time.perf_counter()
        self._colors = colors
        self._judge_colors = colors if JUDGE_COLOR else None
        # The compiled searches have no clock (max_iterations bounds each); the budget is
        # checked between them: past it, the searches that refine a lane already found (the
        # runner-up start pairs once a lane exists, the trapped search's rerun, the dives) are
        # skipped, and lane.stats["cut_short"] says so.
        deadline = t0 + time_limit_s if time_limit_s is not None else math.inf
        stats: dict = {"ranker": self.ranker_name, "graph": self.graph, "cut_short": False}
        pairs = start_pairs(points, pose, self.params)
        start = pairs[0] if pairs else None
        guide = None
        if self.warm_start and self._prev is not None and start is not None:
            tree = cKDTree(points)
            gl = _guide_from(_match(self._prev[0], tree), start[0])
            gr = _guide_from(_match(self._prev[1], tree), start[1])
            if gl.size > 1 or gr.size > 1:
                guide = (gl, gr)
                stats["warm_start_cones"] = int(gl.size + gr.size)
        if guide is None:
            res = enumerate_candidates(points, pose, self.params, graph=self.graph, start=start,
                                       colors=colors)
        else:
            res = self._split_search(points, pose, start, guide)
        # No feasible path pair from the best start pair: the runners-up, one at a time
        # (LaneParams.start_pairs), each with a fresh search.
        fallbacks, chosen, iterations = 0, 0, res.iterations
        depth = _depth(res)
        for rank, other in enumerate(pairs[1:], start=1):
            if depth >= MIN_START_DEPTH:
                break
            if depth > 0 and time.perf_counter() > deadline:
                stats["cut_short"] = True
                break
            nxt = enumerate_candidates(points, pose, self.params, graph=res.graph, start=other)
            fallbacks, iterations = fallbacks + 1, iterations + nxt.iterations
            d = _depth(nxt)
            if d > depth:
                res, chosen, depth = nxt, rank, d
        stats["start_fallbacks"] = fallbacks
        stats["trapped"] = False  # the search was trapped and run again (_untrap)
        if guide is None:
            before = res.iterations
            if time.perf_counter() > deadline:
                stats["cut_short"] = True
            else:
                res, stats["trapped"] = self._untrap(points, pose, res)
            iterations += res.iterations - before
        stats.update(iterations=iterations, complete=res.complete,
                     n_candidates=len(res.candidates), n_cones_used=int(points.shape[0]))
        if confidence is not None:
            stats["note"] = "CLC does not use confidence (section III-A)"
        if colors is not None and not (JUDGE_COLOR or self.params.nvd_color_weight
                                       or self.params.rank_color_weight):
            stats["note"] = "; ".join(filter(None, [stats.get("note"), (
                "colors unused: nvd_color_weight = rank_color_weight = 0 and JUDGE_COLOR off "
                "(docs/tuning.md#nvd_color_weight)")]))
        if res.start is None:
            self._prev = None
            return Lane.not_found(points, f"no cone within {self.params.near_radius_m} m of the "
                                  "car on each side (CLC IV-C)", stats=stats)
        stats["start"] = res.start
        if not res.candidates:
            self._prev = None
            return Lane.not_found(points, "no path pair from the start cones satisfies the "
                                  "lane constraints", stats=stats)
        scores = self._score(points, pose, res.candidates, res.features)
        best = int(np.argmax(scores))  # ties: the first found
        left, right, closed = res.candidates[best]
        left, right = left.copy(), right.copy()
        score = float(scores[best])
        counts = dict.fromkeys(ROUND_COUNTS, 0)
        if (not res.complete or JUDGE_COMPLETE) and self.params.contested_margin > 0:
            left, right, closed, score, counts, it, cut = self._dive_rounds(
                points, pose, res, (left, right, closed, score), deadline,
                search=not res.complete)
            stats["cut_short"] |= cut
            iterations += it
        stats.update(counts, iterations=iterations)
        stats["dropped"] = 0
        if not closed and closable(res.graph, left, right):
            closed = lane_is_feasible(points[left], points[right], self.params, closed=True)
        if closed and RING_JOIN:
            left, right, n = drop_ring_join(points, pose, self.params, res.graph, left, right)
            stats["dropped"] += n
        stats["trimmed_behind"] = 0
        if TRIM_BEHIND and not closed:
            left, right, stats["trimmed_behind"] = trim_behind(points, pose, self.params,
                                                               left, right)
        stats["unhooked"] = 0
        if UNHOOK and not closed:
            left, right, stats["unhooked"] = unhook(points, self.params, left, right)
        self._prev = (points[left].copy(), points[right].copy())
        elapsed = time.perf_counter() - t0
        if time_limit_s is not None:
            stats["over_time_limit"] = bool(elapsed > time_limit_s)
        status = LaneStatus.OPTIMAL if res.complete else LaneStatus.FEASIBLE
        message = ("every feasible path pair was enumerated" if res.complete else
                   f"the search stopped at it_max = {self.params.max_iterations} iterations")
        if chosen:
            message += (f"; from start pair {chosen + 1} by symmetry (the better ones had no "
                        f"feasible path pair with {MIN_START_DEPTH} cones a side)")
        return Lane(cones=points, left=left, right=right, status=status, message=message,
                    cost=score, closed=bool(closed), stats=stats)

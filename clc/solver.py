"""The reusable CLC model (Ivanov & Markgraf 2024, Alg. 1): search graph, start pairs, search,
ranking, then our refinement stage (``clc.refine``).

``ClcModel.solve(points, pose)`` enumerates candidate lanes with ``clc.search``, ranks them, and
hands the winner to ``clc.refine.refine`` (dives and pair drops judged by RLD's objective, the
closing of IV-E, ring-join drop, trim-behind), which returns the ``Lane``. Warm start (IV-F,
``warm_start=True``): the previous lane's cones are matched to the new map's (nearest within
0.5 m), each boundary cut to begin at the new start vertex; half the iterations follow it, half
search afresh, and the ranker sees both.

Closing (IV-E), deviation: the paper closes every closable candidate before ranking; we close
only the refined winner (checking a closing costs the whole-path predicate, ~0.5 ms on a lap).

Time: each search is bounded by ``max_iterations`` (CLC fig. 16), not by a clock inside the
compiled loop; ``time_limit_s`` is checked between searches: past it no dive starts,
``lane.stats["cut_short"]`` says so and ``lane.stats["over_time_limit"]`` when the call still
exceeded it (by at most one search).
"""

from __future__ import annotations

import logging
import math
import time

import numpy as np
from scipy.spatial import cKDTree

from clc.ranker import get_ranker
from clc.refine import DEFAULT, Refinement, refine
from clc.search import GRAPHS, enumerate_candidates, merge_results
from rld.constraints import starting_vertex_pairs
from rld.costs import lane_color_costs
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["ClcModel", "MATCH_TOLERANCE_M", "start_pairs"]

log = logging.getLogger(__name__)

#: Warm start (``warm_start=True``): a previous lane cone is matched to the nearest map cone
#: within this many metres. Source: our choice, as ``rld.solver.MATCH_TOLERANCE_M``.
MATCH_TOLERANCE_M = 0.5


def start_pairs(points: np.ndarray, pose: Pose, params: LaneParams) -> list[tuple[int, int]]:
    """CLC's start pairs (IV-C, ``rld.constraints.starting_vertex_pairs``), best first, at most
    ``params.start_pairs``: those about the point ``params.start_lookback_m`` behind the car
    along its heading, then those about the car itself (the paper's), without repeats.

    Our addition (docs/clc.md, "Start cones behind the car"): about the car, the first cone of
    a boundary is a choice made with one edge of context, and a false positive 1-3 m beside
    the true first cone is as likely a start as the cone itself. Started behind the car, the
    search reaches that choice along the boundary it has already passed, where the next-vertex
    decider and the dive judge see the turn it makes; the lane is returned from its first cone
    not behind the car (``clc.refine.trim_behind``). The pairs about the car follow, for a car
    with no cones behind it (the start of a lap); pairs narrower than ``start_min_width_m``
    still come after every wider pair, of either kind."""
    return _start_pairs(points, pose, params)[0]


def _start_pairs(points: np.ndarray, pose: Pose, params: LaneParams
                 ) -> tuple[list[tuple[int, int]], bool]:
    """``start_pairs``, and whether none lay about the point behind the car (the start of a
    lap; always False with ``start_lookback_m`` 0)."""
    k = int(params.start_pairs)
    around = starting_vertex_pairs(points, pose, params.near_radius_m, k,
                                   params.start_min_width_m, params.start_reach_m)
    back = float(params.start_lookback_m)
    if back <= 0:
        return around, False
    h = pose.heading
    behind = Pose(float(pose.x - back * h[0]), float(pose.y - back * h[1]), pose.yaw)
    first = starting_vertex_pairs(points, behind, params.near_radius_m, k,
                                  params.start_min_width_m)
    pairs = first + [q for q in around if q not in first]
    # The pairs narrower than start_min_width_m still go after every wider one (a stable sort:
    # the order within each group stays).
    w = float(params.start_min_width_m)
    pairs.sort(key=lambda q: bool(np.hypot(*(points[q[0]] - points[q[1]])) < w))
    return pairs[:k], not first


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
    ``score``), the search graph of IV-A (``radius``) or IV-B (``delaunay``), warm starts
    (``warm_start``; off: docs/tuning.md#warm_start) and our refinement stage (``refine``: a
    ``clc.refine.Refinement``; None for the paper's pipeline, closing only)."""

    def __init__(self, params: LaneParams, ranker="learned", graph: str = "radius",
                 warm_start: bool = False, refine: Refinement | None = DEFAULT) -> None:
        if graph not in GRAPHS:
            raise ValueError(f"unknown search graph {graph!r}; use one of {GRAPHS}")
        if refine is not None and not isinstance(refine, Refinement):
            raise ValueError(f"refine must be a clc.refine.Refinement or None, got {refine!r}")
        self.params = params
        self.graph = graph
        self.warm_start = warm_start
        self.refine = (Refinement(rounds=0, ring_join=False, trim_behind=False) if refine is None
                       else refine)
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

    def _score(self, points, pose, candidates, features) -> np.ndarray:
        """The ranker's scores, less ``params.rank_color_weight`` times each candidate's colour
        cost per cone within the refinement's reach (``lane_color_costs(share=True)``) when
        this call has colours: the learned ranker's features are fixed by its weights."""
        s = np.asarray(self.ranker.score(points, pose, self.params, candidates, features),
                       dtype=np.float64)
        w = self.params.rank_color_weight
        if self._colors is None or w == 0 or s.size == 0:
            return s
        return s - w * lane_color_costs(points, self._colors, candidates, pose,
                                        self.refine.reach_m, share=True,
                                        near_radius_m=self.params.near_radius_m,
                                        unknown=self.params.color_unknown)

    def solve(self, points: np.ndarray, pose: Pose, colors=None, time_limit_s=None,
              confidence=None) -> Lane:
        t0 = time.perf_counter()
        self._colors = colors
        deadline = t0 + time_limit_s if time_limit_s is not None else math.inf
        stats: dict = {"ranker": self.ranker_name, "graph": self.graph, "cut_short": False}
        pairs, lap_start = _start_pairs(points, pose, self.params)
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
        # (LaneParams.start_pairs), until one gives a lane.
        fallbacks, chosen, iterations = 0, 0, res.iterations
        for rank, other in enumerate(pairs[1:], start=1):
            if res.candidates:
                break
            nxt = enumerate_candidates(points, pose, self.params, graph=res.graph, start=other)
            fallbacks, iterations = fallbacks + 1, iterations + nxt.iterations
            if nxt.candidates:
                res, chosen = nxt, rank
        stats.update(start_fallbacks=fallbacks, complete=res.complete, iterations=iterations,
                     n_candidates=len(res.candidates), n_cones_used=int(points.shape[0]))
        if confidence is not None:
            stats["note"] = "CLC does not use confidence (section III-A)"
        if colors is not None and not (self.refine.judge_color or self.params.nvd_color_weight
                                       or self.params.rank_color_weight):
            stats["note"] = "; ".join(filter(None, [stats.get("note"), (
                "colors unused: nvd_color_weight = rank_color_weight = 0 and "
                "Refinement.judge_color off (docs/tuning.md#nvd_color_weight)")]))
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
        (left, right, closed, score), counts, it, cut = refine(
            points, pose, self.params, res, (left.copy(), right.copy(), closed,
                                             float(scores[best])),
            lambda c, f: self._score(points, pose, c, f), colors, self.refine, deadline,
            lap_start)
        stats.update(counts, iterations=iterations + it)
        stats["cut_short"] |= cut
        self._prev = (points[left].copy(), points[right].copy())
        if time_limit_s is not None:
            stats["over_time_limit"] = bool(time.perf_counter() - t0 > time_limit_s)
        status = LaneStatus.OPTIMAL if res.complete else LaneStatus.FEASIBLE
        message = ("every feasible path pair was enumerated" if res.complete else
                   f"the search stopped at it_max = {self.params.max_iterations} iterations")
        if chosen:
            message += (f"; from start pair {chosen + 1} by symmetry (the better ones had no "
                        "feasible path pair)")
        return Lane(cones=points, left=left, right=right, status=status, message=message,
                    cost=score, closed=bool(closed), stats=stats)

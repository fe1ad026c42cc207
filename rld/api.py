"""The public entry points: ``solve_lane`` (stateless) and ``LaneSolver`` (reusable).

Input is validated here, once; the methods behind receive clean arrays, with duplicate cones
merged (``rld.dedup``), and a lane they return with fewer than two cones on a side becomes
``NOT_FOUND`` here, for every method (``LaneSolver.solve``). A method is looked up
by name in ``METHODS``; a name that does not exist is a ``ValueError``, never a stand-in lane.
``rld.api`` reaches ``clc`` lazily, when a CLC solver is made, so ``clc`` may import the core.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from dataclasses import replace
from typing import Any

import numpy as np

from rld.baselines import nearest_chain
from rld.colors import (
    SIDE_LEFT,
    SIDE_RIGHT,
    parse_class_probs,
    parse_colors,
    side_labels,
    side_labels_from_probs,
)
from rld.dedup import merge_duplicates
from rld.types import MIN_CONES, Lane, LaneParams, Pose, as_cones, as_pose

__all__ = ["solve_lane", "LaneSolver", "METHODS", "DEFAULT_METHOD",
           "MIN_SIDE_CONES"]


class _NearestMethod:
    """The nearest-neighbour chain baseline (stateless)."""

    backends: tuple[str, ...] = ()
    rankers = False

    def __init__(self, params: LaneParams, backend: str | None = None, ranker=None) -> None:
        self.params = params

    def solve(self, points, pose, colors=None, time_limit_s=None, confidence=None) -> Lane:
        lane = nearest_chain(points, pose, self.params, colors=colors)
        if confidence is not None:
            lane.stats["note"] = "the nearest-neighbour chain ignores confidence"
        return lane


class _HuangMethod:
    """The fitted-centreline baseline after Huang et al. 2009 (``rld.huang``), stateless."""

    backends: tuple[str, ...] = ()
    rankers = False

    def __init__(self, params: LaneParams, backend: str | None = None, ranker=None) -> None:
        self.params = params

    def solve(self, points, pose, colors=None, time_limit_s=None, confidence=None) -> Lane:
        from rld.huang import huang_lane

        lane = huang_lane(points, pose, self.params)
        if colors is not None or confidence is not None:
            # Its evidence grid (eq. 3) is isotropic: no side until the parabola is fitted,
            # and then colour could only filter cones, a hard rule (docs/huang.md).
            lane.stats["note"] = "the fitted baseline ignores colors and confidence"
        return lane


class _RldMethod:
    """RLD (Brandes et al. 2020) with a reusable model and warm starts: the car's window, then
    up to ``params.max_windows - 1`` frontier windows chained on its end within the call's
    budget (``rld.incremental.IncrementalRld.chain``; not in the sided form). A reused solver
    keeps its chain: a later call re-solves the car's window, re-attaches the kept chain where
    they join and grows it for at most ``KEPT_GROWTH_S`` (a whole chain where they do not).
    The lane is returned from the car forward (``IncrementalRld.forward``), its far ends
    extended (``IncrementalRld.extend_ends``); a short one is tried again (``_retry``); where
    no window gives a lane, a reused solver holds its last (``IncrementalRld.hold``)."""

    backends: tuple[str, ...] = ("cpsat", "highs", "cvxpy", "auto")
    rankers = False
    sided = False

    def __init__(self, params: LaneParams, backend: str | None = None, ranker=None) -> None:
        from rld.solver import RldModel

        self.model = RldModel(params, backend=backend, sided=self.sided)
        self.retry = None  # the wider window of a short lane's retry (made on first use)
        self.backend = backend
        self.chainer = None
        self.kept = None  # the last call's chain (rld.incremental.KeptChain)
        if int(params.max_windows) > 1 and not self.sided:
            from rld.incremental import IncrementalRld

            # Frontier windows of max_cones, or the least that lets the lane grow.
            least = IncrementalRld.least_frontier_cones()
            self.chainer = IncrementalRld(params, backend=backend,
                                          frontier_max_cones=max(int(params.max_cones), least))

    def solve(self, points, pose, colors=None, time_limit_s=None, confidence=None) -> Lane:
        from rld.incremental import KEPT_GROWTH_S
        from rld.solver import DEFAULT_TIME_LIMIT_S

        t0 = time.perf_counter()
        budget = DEFAULT_TIME_LIMIT_S if time_limit_s is None else float(time_limit_s)
        lane = self.model.solve(points, pose, time_limit_s=time_limit_s, colors=colors,
                                confidence=confidence)
        kept, self.kept = self.kept, None
        if self.chainer is None:
            return lane
        if lane.ok:
            lane = self.chainer.chain(points, pose, lane, t0, budget,
                                      int(self.model.params.max_windows), colors=colors,
                                      kept=kept, grow_s=KEPT_GROWTH_S)
            self.kept = self.chainer.keep(points, pose, lane)  # the whole chain, to re-attach
            lane = self.chainer.extend_ends(points, pose,
                                            self.chainer.forward(points, pose, lane, colors),
                                            colors)
        if self.chainer.short(points, pose, lane):
            lane = self._retry(points, pose, lane, t0, budget, colors, confidence)
        if not lane.ok:  # no lane on this map, even tried again: the last call's, if it stands
            held = self.chainer.hold(points, pose, lane, kept, colors)
            if held is not None:
                lane, self.kept = held, self.chainer.keep(points, pose, held)
        return _swapped(points, pose, lane, self.model.params, colors)

    def _retry(self, points, pose, lane, t0, budget, colors, confidence) -> Lane:
        """A short lane (``IncrementalRld.short``) against a stateless chain from the car's
        window of ``RETRY_MAX_CONES`` cones, within the call's budget: the one RLD's objective
        (eq. 29) prefers within 25 m of the car wins (``lane_cost(radius_m=...)``)."""
        from rld.costs import REACH_M, lane_cost
        from rld.incremental import RETRY_MAX_CONES
        from rld.solver import RldModel

        left = budget - (time.perf_counter() - t0)
        if left <= 0:
            return lane
        p = self.model.params
        if self.retry is None:
            self.retry = RldModel(replace(p, max_cones=max(RETRY_MAX_CONES, int(p.max_cones))),
                                  backend=self.backend)
        wide = self.retry.solve(points, pose, time_limit_s=left, colors=colors,
                                confidence=confidence)
        if not wide.ok:
            return lane
        wide = self.chainer.chain(points, pose, wide, t0, budget, int(p.max_windows),
                                  colors=colors)
        view = self.chainer.extend_ends(points, pose,
                                        self.chainer.forward(points, pose, wide, colors), colors)

        def near_cost(x: Lane) -> float:
            return -np.inf if x.closed else lane_cost(points, x.left, x.right, pose, p,
                                                      colors=colors, radius_m=REACH_M)

        if lane.ok and near_cost(view) >= near_cost(lane):
            return lane
        self.kept = self.chainer.keep(points, pose, wide)
        view.stats["retry"] = True
        return view


class _RldSidedMethod(_RldMethod):
    """RLD with our side-aware formulation (one path per side, width bounded at the cones)."""

    sided = True


class _RldIncrementalMethod:
    """RLD on a growing map: keeps its lane and re-optimises the frontier (``rld.incremental``)."""

    backends: tuple[str, ...] = ("cpsat", "highs", "cvxpy", "auto")
    rankers = False

    @staticmethod
    def max_every() -> float:
        """The pose stride (poses lie 1 m apart) from which every call is a pose jump that
        restarts it: the evaluation must drive it below this."""
        from rld.incremental import POSE_JUMP_M

        return POSE_JUMP_M

    def __init__(self, params: LaneParams, backend: str | None = None, ranker=None,
                 **options) -> None:
        from rld.incremental import IncrementalRld

        self.model = IncrementalRld(params, backend=backend, **options)

    def solve(self, points, pose, colors=None, time_limit_s=None, confidence=None) -> Lane:
        return self.model.solve(points, pose, time_limit_s=time_limit_s, colors=colors,
                                confidence=confidence)


def _swapped(points, pose, lane: Lane, params: LaneParams, colors) -> Lane:
    """``rld``'s open ``lane`` with one cone near the car swapped where CLC's judge prefers it
    (``rld.insertion.swap_cones``, as CLC's refinement does), its cost recomputed; the kept
    chain is not touched. ``stats["swapped"]`` counts the swap."""
    from rld import insertion  # looked up per call, as benchmarks/bench_ends.py spies on it
    from rld.costs import REACH_M, lane_cost

    if not lane.ok or lane.closed:
        return lane
    (L, R), n = insertion.swap_cones(points, pose, (lane.left, lane.right), params, REACH_M,
                                     colors)
    if not n:
        return lane
    return Lane(cones=points, left=L, right=R, status=lane.status, message=lane.message,
                cost=lane_cost(points, L, R, pose, params, colors=colors),
                stats=dict(lane.stats, swapped=n))


class _ClcMethod:
    """CLC (Ivanov & Markgraf 2024): path-pair enumeration and a ranker, warm-started."""

    backends: tuple[str, ...] = ()
    rankers = True

    def __init__(self, params: LaneParams, backend: str | None = None, ranker=None,
                 **options) -> None:
        from clc.solver import ClcModel

        self.model = ClcModel(params, ranker=ranker or "learned", **options)

    def solve(self, points, pose, colors=None, time_limit_s=None, confidence=None) -> Lane:
        return self.model.solve(points, pose, colors=colors, time_limit_s=time_limit_s,
                                confidence=confidence)


#: method name -> class(params, backend) with .solve(points, pose, colors, time_limit_s) -> Lane
METHODS: dict[str, Callable[..., Any]] = {
    "rld": _RldMethod,
    "rld-sided": _RldSidedMethod,
    "rld-incremental": _RldIncrementalMethod,
    "clc": _ClcMethod,
    "nearest": _NearestMethod,
    "huang": _HuangMethod,
}
#: The method ``solve_lane`` uses when none is named.
DEFAULT_METHOD = "rld"
#: Fewest cones a side of a lane that ``LaneSolver.solve`` returns (issue 42): a boundary is
#: at least one edge. A method's lane with a shorter side becomes ``NOT_FOUND``.
MIN_SIDE_CONES = 2


def _check_method(method: str) -> str:
    if method not in METHODS:
        raise ValueError(
            f"unknown method {method!r}; available: {', '.join(sorted(METHODS))}"
        )
    return method


def _check_confidence(confidence: Any, n: int) -> np.ndarray | None:
    if confidence is None:
        return None
    try:
        arr = np.asarray(confidence, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"confidence must be numbers in [0, 1]: {exc}") from exc
    if arr.shape != (n,):
        raise ValueError(f"confidence must have one value per cone ({n}), got {arr.shape}")
    if not np.all(np.isfinite(arr)) or arr.min() < 0 or arr.max() > 1:
        raise ValueError("confidence must be finite numbers in [0, 1]")
    return arr


def _side_labels(colors: Any, class_probs: Any, n: int) -> np.ndarray | None:
    """The methods' per-cone side labels (``rld.colors``) from ``colors`` (class names or codes)
    or ``class_probs`` ((n, 5) probabilities); None when neither is given or no cone's class
    names a side (blue or yellow): then there is no colour evidence, and nothing to charge an
    unknown cone against (``LaneParams.color_unknown``)."""
    if colors is not None and class_probs is not None:
        raise ValueError("give colors or class_probs, not both")
    if colors is not None:
        labels = side_labels(parse_colors(colors, n))
    elif class_probs is not None:
        labels = side_labels_from_probs(parse_class_probs(class_probs, n))
    else:
        return None
    return labels if np.any((labels == SIDE_LEFT) | (labels == SIDE_RIGHT)) else None


class LaneSolver:
    """A reusable solver: keeps the method's prepared state and the previous solution between
    calls (the warm start of the RLD model and the CLC search, when they land).

    ``backend`` selects an RLD solver backend; ``ranker`` a CLC ranker (``learned``,
    ``rld_cost``, ``longest`` or an object with ``score``); a method without backends or
    rankers rejects them. ``options``: further keyword arguments of the method's model, e.g.
    ``{"warm_start": True, "graph": "delaunay"}`` for CLC (``clc.solver.ClcModel``).
    ``track=True`` runs the lane tracker of Huang et al. (``rld.tracker``) over the lanes:
    each returned lane then carries ``lane.stats["tracked"]``, a ``TrackedLane`` (the tracked
    centreline and its confidences) beside the raw lane.
    """

    def __init__(
        self,
        method: str = DEFAULT_METHOD,
        params: LaneParams | None = None,
        backend: str | None = None,
        ranker: Any = None,
        options: dict | None = None,
        track: bool = False,
    ) -> None:
        self.method = _check_method(method)
        self.params = params if params is not None else LaneParams()
        if not isinstance(self.params, LaneParams):
            raise ValueError("params must be a LaneParams")
        kind = METHODS[self.method]
        if backend is not None and not kind.backends:
            raise ValueError(f"method {method!r} has no solver backends (got {backend!r})")
        if ranker is not None and not kind.rankers:
            raise ValueError(f"method {method!r} takes no ranker (got {ranker!r})")
        self.backend = backend
        self.ranker = ranker
        try:
            self._impl = kind(self.params, backend=backend, ranker=ranker, **(options or {}))
        except TypeError as exc:
            raise ValueError(f"method {method!r} does not take options {options!r}: {exc}") \
                from exc
        self.previous: Lane | None = None
        self.tracker = None
        if track:
            from rld.tracker import LaneTracker

            self.tracker = LaneTracker()

    def solve(
        self,
        cones: Any,
        pose: Pose | Sequence[float],
        colors: Any = None,
        time_limit_s: float | None = None,
        confidence: Any = None,
        class_probs: Any = None,
    ) -> Lane:
        """Find the lane in ``cones`` ((N, 2) metres) ahead of ``pose`` ((x, y, yaw) or a
        ``Pose``). Raises ``ValueError`` on invalid input; returns a ``Lane`` with ``ok ==
        False`` when the input is valid but holds no lane. ``colors`` / ``class_probs``: see
        ``solve_lane``.

        Two rules hold for every method (issue 42). Duplicates: cones at most
        ``params.duplicate_radius_m`` (0.3 m) apart are merged before the method runs
        (``rld.dedup.merge_duplicates``: each group is its lowest-index cone, a known colour
        beats unknown, the largest confidence counts); the lane is mapped back, so its
        ``cones`` are the caller's (validated) and its indices point into them, and
        ``stats["duplicates_merged"]`` counts the cones merged away. Sides: a lane with fewer
        than ``MIN_SIDE_CONES`` (2) cones on a side is returned as ``NOT_FOUND``, its message
        naming the side and its count, the method's stats kept (``stats["short_lane"]``: the
        method's status, message and side counts)."""
        points = as_cones(cones)
        car = as_pose(pose)
        labels = _side_labels(colors, class_probs, points.shape[0])
        conf = _check_confidence(confidence, points.shape[0])
        if time_limit_s is not None and not (time_limit_s > 0):
            raise ValueError(f"time_limit_s must be positive, got {time_limit_s}")
        t0 = time.perf_counter()
        radius = self.params.duplicate_radius_m
        if radius > 0:
            merged, keep, m_labels, m_conf = merge_duplicates(points, radius, colors=labels,
                                                              confidence=conf)
        else:  # merging off
            merged, keep, m_labels, m_conf = points, None, labels, conf
        n_merged = int(points.shape[0] - merged.shape[0])
        if n_merged == 0:  # the method sees the caller's cones themselves
            merged, m_labels, m_conf = points, labels, conf
        if merged.shape[0] < MIN_CONES:
            lane = Lane.not_found(
                points, f"only {merged.shape[0]} distinct cones once those within "
                f"{radius:g} m of each other are merged; a lane needs {MIN_CONES}")
        else:
            lane = _at_least_two_a_side(
                self._impl.solve(merged, car, colors=m_labels, time_limit_s=time_limit_s,
                                 confidence=m_conf), merged)
            if n_merged:
                # Back to the caller's indices (the lowest of each group) and cones.
                lane = replace(lane, cones=points, left=keep[lane.left], right=keep[lane.right])
        elapsed = time.perf_counter() - t0
        lane.stats.setdefault("backend", self.backend)
        lane.stats.update(method=self.method, solve_time_s=elapsed, n_cones=int(points.shape[0]),
                          duplicates_merged=n_merged)
        lane.stats.setdefault("n_cones_used", int(merged.shape[0]))
        if self.tracker is not None:
            lane.stats["tracked"] = self.tracker.update(
                lane.centerline if lane.ok else None, car.xy, car.heading)
        self.previous = lane
        return lane


def _at_least_two_a_side(lane: Lane, points: np.ndarray) -> Lane:
    """``lane`` itself, or ``NOT_FOUND`` when it is a lane with a side of fewer than
    ``MIN_SIDE_CONES`` cones. Only the returned value changes: the method's own state (a
    warm start, ``rld-incremental``'s kept lane) is not touched; see docs/api.md."""
    if not lane.ok:
        return lane
    short = [(name, int(side.size)) for name, side in (("left", lane.left), ("right", lane.right))
             if side.size < MIN_SIDE_CONES]
    if not short:
        return lane
    why = " and ".join(f"the {name} side has {k} cone{'' if k == 1 else 's'}"
                       for name, k in short)
    stats = dict(lane.stats)
    stats["short_lane"] = {"status": lane.status.name, "message": lane.message,
                           "left": int(lane.left.size), "right": int(lane.right.size)}
    return Lane.not_found(points, f"{why}; a lane needs at least {MIN_SIDE_CONES} cones a side",
                          stats=stats)


def solve_lane(
    cones: Any,
    pose: Pose | Sequence[float],
    method: str = DEFAULT_METHOD,
    params: LaneParams | None = None,
    backend: str | None = None,
    colors: Any = None,
    time_limit_s: float | None = None,
    confidence: Any = None,
    ranker: Any = None,
    class_probs: Any = None,
) -> Lane:
    """Find the driving lane in ``cones`` ahead of the car at ``pose`` (stateless).

    ``cones``: array-like (N, 2), metres, in any order, false positives included.
    ``pose``: ``(x, y, yaw)`` (metres, radians) or a ``Pose``.
    ``method``: a name in ``METHODS``. ``params``: a ``LaneParams``. ``backend``: RLD solver
    backend. ``colors``: optional per-cone Formula Student classes (``blue``, ``yellow``,
    ``orange``, ``big_orange``, ``unknown``; ``left``/``right`` for blue/yellow) or their codes
    (0 unknown, 1 yellow, 2 blue, 3 orange, 4 big orange); or ``class_probs``, (N, 5)
    probabilities in that order (``rld.colors``). Evidence, never a hard rule: a cost for a
    cone on the side its class contradicts and for an unknown one (``rld.costs.
    boundary_color_cost``; ``LaneParams.w_color`` and ``color_unknown`` in RLD and its
    incremental form), a preference in the nearest-neighbour chain, a term after CLC's ranker
    and in its dive judge (``rank_color_weight``, ``clc.refine.Refinement.judge_color``; its
    search order, ``nvd_color_weight``, is off); the fitted baseline (``huang``) ignores it.
    ``confidence``: optional per-cone detection confidence in [0, 1], a cost for RLD
    (``LaneParams.w_confidence``). ``time_limit_s``: the solve's time budget (RLD default
    0.4 s; CLC is bounded by ``params.max_iterations`` instead). ``ranker``: the CLC ranker
    (default ``learned``). Duplicate cones are merged first and a lane has two cones a side at
    least, whatever the method (``LaneSolver.solve``).
    """
    return LaneSolver(method=method, params=params, backend=backend, ranker=ranker).solve(
        cones, pose, colors=colors, time_limit_s=time_limit_s, confidence=confidence,
        class_probs=class_probs)

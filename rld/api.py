"""The public entry points: ``solve_lane`` (stateless) and ``LaneSolver`` (reusable).

Input is validated here, once; the methods behind receive clean arrays. A method is looked up
by name in ``METHODS``; a name that does not exist is a ``ValueError``, never a stand-in lane.
The RLD program and the CLC search register here when they land (issues 3 and 4).
"""

from __future__ import annotations

import time
from collections.abc import Callable, Sequence
from typing import Any

import numpy as np

from rld.baselines import nearest_chain
from rld.types import Lane, LaneParams, Pose, as_cones, as_pose

__all__ = ["solve_lane", "LaneSolver", "METHODS", "DEFAULT_METHOD", "COLOR_CODES"]

#: method name -> function(points, pose, params) -> Lane
METHODS: dict[str, Callable[[np.ndarray, Pose, LaneParams], Lane]] = {
    "nearest": nearest_chain,
}
#: The method ``solve_lane`` uses when none is named.
DEFAULT_METHOD = "nearest"
#: Per-cone colour labels accepted in ``colors``.
COLOR_CODES = {"unknown": 0, "left": 1, "right": 2}


def _check_method(method: str) -> str:
    if method not in METHODS:
        raise ValueError(
            f"unknown method {method!r}; available: {', '.join(sorted(METHODS))}"
            " (rld and clc are not implemented yet)"
        )
    return method


def _check_colors(colors: Any, n: int) -> np.ndarray | None:
    if colors is None:
        return None
    arr = np.asarray(colors)
    if arr.shape != (n,):
        raise ValueError(f"colors must have one label per cone ({n}), got shape {arr.shape}")
    if arr.dtype.kind in "US":
        bad = set(arr.tolist()) - set(COLOR_CODES)
        if bad:
            raise ValueError(f"unknown colour labels {sorted(bad)}; use {sorted(COLOR_CODES)}")
        return np.array([COLOR_CODES[c] for c in arr.tolist()], dtype=np.int64)
    if not np.isin(arr, list(COLOR_CODES.values())).all():
        raise ValueError("colors must be 0 (unknown), 1 (left) or 2 (right)")
    return arr.astype(np.int64)


class LaneSolver:
    """A reusable solver: keeps the method's prepared state and the previous solution between
    calls (the warm start of the RLD model and the CLC search, when they land).

    ``backend`` selects an RLD solver backend; methods without backends reject it.
    """

    def __init__(
        self,
        method: str = DEFAULT_METHOD,
        params: LaneParams | None = None,
        backend: str | None = None,
    ) -> None:
        self.method = _check_method(method)
        self.params = params if params is not None else LaneParams()
        if not isinstance(self.params, LaneParams):
            raise ValueError("params must be a LaneParams")
        if backend is not None:
            raise ValueError(f"method {method!r} has no solver backends (got {backend!r})")
        self.backend = backend
        self.previous: Lane | None = None

    def solve(
        self,
        cones: Any,
        pose: Pose | Sequence[float],
        colors: Any = None,
        time_limit_s: float | None = None,
    ) -> Lane:
        """Find the lane in ``cones`` ((N, 2) metres) ahead of ``pose`` ((x, y, yaw) or a
        ``Pose``). Raises ``ValueError`` on invalid input; returns a ``Lane`` with ``ok ==
        False`` when the input is valid but holds no lane."""
        points = as_cones(cones)
        car = as_pose(pose)
        _check_colors(colors, points.shape[0])
        if time_limit_s is not None and not (time_limit_s > 0):
            raise ValueError(f"time_limit_s must be positive, got {time_limit_s}")
        t0 = time.perf_counter()
        lane = METHODS[self.method](points, car, self.params)
        elapsed = time.perf_counter() - t0
        lane.stats.update(
            method=self.method,
            backend=self.backend,
            solve_time_s=elapsed,
            n_cones=int(points.shape[0]),
        )
        lane.stats.setdefault("n_cones_used", int(points.shape[0]))
        self.previous = lane
        return lane


def solve_lane(
    cones: Any,
    pose: Pose | Sequence[float],
    method: str = DEFAULT_METHOD,
    params: LaneParams | None = None,
    backend: str | None = None,
    colors: Any = None,
    time_limit_s: float | None = None,
) -> Lane:
    """Find the driving lane in ``cones`` ahead of the car at ``pose`` (stateless).

    ``cones``: array-like (N, 2), metres, in any order, false positives included.
    ``pose``: ``(x, y, yaw)`` (metres, radians) or a ``Pose``.
    ``method``: a name in ``METHODS``. ``params``: a ``LaneParams``. ``backend``: RLD solver
    backend. ``colors``: optional per-cone labels (``unknown``/``left``/``right`` or 0/1/2).
    ``time_limit_s``: the solve's time budget.
    """
    return LaneSolver(method=method, params=params, backend=backend).solve(
        cones, pose, colors=colors, time_limit_s=time_limit_s
    )

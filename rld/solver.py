"""The reusable RLD model: cone window, program, backend, lazy cycle cuts, warm start.

``RldModel.solve(points, pose)`` takes the ``max_cones`` map cones nearest ahead of the car,
builds the program of ``rld.program`` over them, solves it with the chosen backend under the time
budget, adds cycle-elimination cuts (RLD eq. 5) for any cycle in the solution and re-solves until
the chosen edges are exactly two simple paths. When those paths fail the shared lane predicate
(``rld.constraints.lane_is_feasible``: C_seg, C_width, C_poly, which CLC enumerates under;
without C_width's upper bound, since the window can cut one boundary short), that lane is cut
off (``rld.program.lane_cut``) and the program solved again, up to
``MAX_LANE_CUT_ROUNDS`` times within the budget; a lane still rejected is returned as no lane.
When the program has no solution, or only lanes the predicate rejects, and it has a heading row
(eq. 9), it is solved once more without that row (``HEADING_FALLBACK``; in a tight bend the
boundaries beside the car turn more than the row's tolerance from the car's heading;
docs/formulation.md).
Returns a ``Lane`` in the caller's indices.

Warm start: the previous lane's boundaries are kept as positions; on the next call every
previous cone is matched to the nearest new window cone within 0.5 m (SLAM maps keep their cones)
and the previous edges that survive become the backend's hint (a CP-SAT hint, a HiGHS MIP start).

Window rule: cones not more than ``window_behind_m`` behind the car (measured along its heading,
so the cones beside it stay in), sorted by distance to the car, the first ``max_cones``. Method
``rld`` then chains further windows on this lane's end (``LaneParams.max_windows``,
``rld.incremental.IncrementalRld.chain``; docs/formulation.md).
"""

from __future__ import annotations

import time

import numpy as np
from scipy.spatial import cKDTree

from rld.backends import make_backend
from rld.backends.base import BackendResult
from rld.constraints import blocked_by_fixed, first_edges_ahead, lane_is_feasible, start_mask
from rld.program import build_program, cycle_cut, extract_paths, lane_cut
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["RldModel", "cone_window", "MATCH_TOLERANCE_M", "DEFAULT_TIME_LIMIT_S"]

#: Warm start: a previous lane cone is matched to the nearest window cone within this many
#: metres (SLAM maps keep their cones). Source: our choice.
MATCH_TOLERANCE_M = 0.5
#: The default solve budget, seconds. Source: RLD section IV-A (its success limit).
DEFAULT_TIME_LIMIT_S = 0.4
#: Most rounds of cycle cuts (RLD eq. 5) in one solve. Source: our choice.
MAX_CYCLE_ROUNDS = 25
#: Re-solves after the program's optimum failed the shared lane predicate (``lane_cut``), within
#: the budget. Source: our choice.
MAX_LANE_CUT_ROUNDS = 3
#: Solve again without the heading row (eq. 9) when no lane meets it. Chosen by measurement:
#: docs/tuning.md#heading_fallback.
HEADING_FALLBACK = True


def _split(program, x) -> tuple[list[list[int]], list[list[int]]]:
    """Paths and cycles of a solution. Sided: exactly one path per side, [left, right], or
    whatever is there when that fails (the caller reports it)."""
    if not program.sided:
        return extract_paths(program, x)
    lp, lc = extract_paths(program, x, 0)
    rp, rc = extract_paths(program, x, 1)
    return lp + rp, lc + rc


def cone_window(points: np.ndarray, pose: Pose, params: LaneParams) -> tuple[np.ndarray, float]:
    """Indices of the cones RLD takes (see the module docstring) and the horizon: the distance
    from the car to the farthest of them, metres."""
    d = points - pose.xy
    along = d @ pose.heading
    dist = np.hypot(d[:, 0], d[:, 1])
    ok = np.flatnonzero(along >= -params.window_behind_m)
    # Ties in distance go by position, so the window does not depend on the input order.
    key = np.round(dist[ok], 9)
    order = ok[np.lexsort((points[ok, 1], points[ok, 0], key))][: int(params.max_cones)]
    horizon = float(dist[order].max()) if order.size else 0.0
    return np.sort(order), horizon


class RldModel:
    """RLD with a backend (``cpsat``, ``highs``, ``cvxpy`` or ``cvxpy:SOLVER``) and the previous
    solution for warm starts. ``no_crossing`` adds the no-crossing rows (section V); ``sided``
    uses the side-aware formulation (``rld.program.build_program``)."""

    def __init__(
        self,
        params: LaneParams,
        backend: str | None = None,
        warm_start: bool = True,
        no_crossing: bool = True,
        sided: bool = False,
    ) -> None:
        self.params = params
        self.backend = make_backend(backend)
        self.warm_start = warm_start
        self.no_crossing = no_crossing
        self.sided = sided
        self._previous: list[np.ndarray] | None = None  # boundary positions of the last lane
        self._started = False  # the first build loads the kernels: outside the budget

    def reset(self) -> None:
        self._previous = None

    def _hint(self, program) -> tuple[np.ndarray | None, int]:
        if not self.warm_start or self._previous is None:
            return None, 0
        tree = cKDTree(program.points)
        per_side: list[list[int]] = []
        for xy in self._previous:
            chosen: list[int] = []
            if len(xy) >= 2:
                dist, idx = tree.query(xy, distance_upper_bound=MATCH_TOLERANCE_M)
                ok = np.isfinite(dist[:-1]) & np.isfinite(dist[1:])
                ids = program.edge_ids(idx[:-1][ok], idx[1:][ok])
                chosen = ids[ids >= 0].tolist()
            per_side.append(chosen)
        n = sum(len(c) for c in per_side)
        if n == 0:
            return None, 0
        if program.sided:
            return program.solution_from_edges(per_side[0], per_side[1]), n
        return program.solution_from_edges(np.array(per_side[0] + per_side[1])), n

    @staticmethod
    def _orient(program, paths, sub, pose) -> tuple[list[int], list[int]]:
        """(left, right) of a solution's two paths, each from its end nearer the car."""
        if program.sided:
            return paths[0], paths[1]
        # Left is the path whose first cone lies further to the car's left.
        y0 = [pose.to_local(sub[[p[0]]])[0, 1] for p in paths]
        return (paths[0], paths[1]) if y0[0] >= y0[1] else (paths[1], paths[0])

    def solve(
        self,
        points: np.ndarray,
        pose: Pose,
        time_limit_s: float | None = None,
        start: tuple[int, int] | None = None,
        colors: np.ndarray | None = None,
        confidence: np.ndarray | None = None,
        fixed_edges: list[tuple[int, int]] | None = None,
        window: np.ndarray | None = None,
        heading: bool = True,
        fixed_lane: np.ndarray | None = None,
    ) -> Lane:
        """Solve on validated ``points``. ``start`` (indices into ``points``) fixes the two near
        endpoints, for the cross-check with CLC's starting vertices and the incremental solver.
        ``colors`` and ``confidence`` (validated, one per cone) add their costs.
        ``fixed_edges`` (pairs of indices into ``points``) must be in the lane (their columns'
        lower bound is 1; ``rld.incremental`` ties its frontier to the confirmed lane so).
        ``window`` (indices into ``points``) replaces the cone window of the module docstring
        and ``heading=False`` drops the heading row and cost (``build_program``): both for the
        incremental solver's frontier, which is not seen from the car. ``fixed_lane`` (K, 2)
        indices into ``points``: lane edges already chosen outside the program; candidate
        edges that cross them or violate the minimum width against them are closed
        (``rld.constraints.blocked_by_fixed``)."""
        budget = DEFAULT_TIME_LIMIT_S if time_limit_s is None else float(time_limit_s)
        t0 = time.perf_counter()
        if start is None and start_mask(points, pose, self.params.near_radius_m,
                                        self.params.start_reach_m).sum() < 2:
            return Lane.not_found(
                points,
                f"fewer than two cones within near_radius_m = {self.params.near_radius_m} m of "
                "the car",
                stats={"backend": self.backend.name},
            )
        # Lanes the program allows but the shared predicate (C_seg, C_width, C_poly:
        # rld.constraints.lane_is_feasible, CLC's; not w_max, which the window's uneven ends
        # break on true lanes) rejects are cut off and the program solved again (lane_cut;
        # docs/formulation.md). Only for the car's own lane: the incremental solver's frontier
        # (a window given, fixed edges, a fixed lane) is not a lane from the car.
        check = window is None and not fixed_edges and fixed_lane is None
        if window is None:
            window, horizon = cone_window(points, pose, self.params)
        else:
            window = np.unique(np.asarray(window, dtype=np.int64))
            horizon = float(np.hypot(*(points[window] - pose.xy).T).max()) if window.size \
                else 0.0
        if start is not None:
            window = np.union1d(window, np.asarray(start))
        if fixed_edges:
            window = np.union1d(window, np.asarray(fixed_edges, dtype=np.int64).ravel())
        local_start = None
        if start is not None:
            local_start = (int(np.searchsorted(window, start[0])),
                           int(np.searchsorted(window, start[1])))
        sub = points[window]
        stats = {"n_cones_used": int(window.size), "horizon_m": horizon, "cycle_rounds": 0,
                 "backend": self.backend.name}
        if window.size < 4:
            return Lane.not_found(points, f"only {window.size} cones ahead of the car", stats=stats)
        program = build_program(sub, pose, self.params, no_crossing=self.no_crossing,
                                start=local_start,
                                strengthen=self.backend.strengthen_for(int(window.size)),
                                sided=self.sided,
                                colors=None if colors is None else colors[window],
                                confidence=None if confidence is None else confidence[window],
                                heading=heading)
        stats.update(program.stats)
        if fixed_edges:
            cols = program.block("a")
            for a, b in fixed_edges:
                k = int(program.edge_ids(np.searchsorted(window, a), np.searchsorted(window, b)))
                if k < 0:
                    return Lane.not_found(points, f"fixed edge ({a}, {b}) is not a candidate "
                                          "edge of the program", status=LaneStatus.INFEASIBLE,
                                          stats=stats)
                program.col_lo[cols.start + k] = 1.0
        if fixed_lane is not None and len(fixed_lane):
            blocked = blocked_by_fixed(points, window[program.edges], fixed_lane,
                                       self.params.min_width_m)
            for side in (0, 1) if program.sided else (0,):
                program.col_hi[program.block("a", side)][blocked] = 0.0
            stats["blocked_edges"] = int(blocked.sum())
        stats["build_time_s"] = time.perf_counter() - t0
        if program.near.sum() < 2:
            return Lane.not_found(
                points,
                f"fewer than two cones within near_radius_m = {self.params.near_radius_m} m",
                stats=stats,
            )
        hint, n_hinted = self._hint(program)
        stats["warm_start_edges"] = n_hinted
        result = None
        t_solve = time.perf_counter()
        # The budget counts the build (from t0), but not the model's first: the start-up
        # (kernels loaded from numba's cache; `rld warmup`) is no part of a map update.
        t_budget = t0 if self._started else t_solve
        self._started = True
        stats["lane_cut_rounds"] = 0
        verdicts: dict[tuple, bool] = {}  # each lane checked once

        def feasible(lt: list[int], rt: list[int]) -> bool:
            key = (tuple(lt), tuple(rt))
            if key not in verdicts:
                # The shared predicate, and each boundary leaving its first cone forward
                # (CLC's first-edge rule): a path from a cone beside the car back to one behind
                # it is no boundary (the window holds cones 4 m behind the car).
                verdicts[key] = lane_is_feasible(sub[lt], sub[rt], self.params,
                                                 max_width=False) and first_edges_ahead(
                    sub[lt], sub[rt], pose, self.params.max_turn_angle_rad)
            return verdicts[key]

        def solve_loop(result):
            """Solve with cycle and lane cuts; returns (result, rejected): ``rejected`` when
            the last lane found is one the shared predicate rejects (the cuts ran out)."""
            cuts = 0  # this loop's lane cuts (stats["lane_cut_rounds"] counts every loop's)
            while True:
                rejected = False
                while True:
                    remaining = budget - (time.perf_counter() - t_budget)
                    if remaining <= 0:  # the budget spent (by the build, or the last solve)
                        result = result or BackendResult("timeout", None)
                        break
                    result = self.backend.solve(program, remaining, hint)
                    if result.x is None:
                        break
                    paths, cycles = _split(program, result.x)
                    if not cycles:
                        break
                    stats["cycle_rounds"] += 1
                    if stats["cycle_rounds"] > MAX_CYCLE_ROUNDS:
                        break
                    for comp in cycles:
                        cycle_cut(program, comp)
                if not check or result.x is None:
                    break
                paths, cycles = _split(program, result.x)
                if cycles or len(paths) != 2:
                    break
                pl, pr = self._orient(program, paths, sub, pose)
                rejected = not feasible(pl, pr)
                if (not rejected
                        or cuts >= MAX_LANE_CUT_ROUNDS
                        or budget - (time.perf_counter() - t_budget) <= 0):
                    break
                cuts += 1
                stats["lane_cut_rounds"] += 1
                lane_cut(program, pl, pr)
            return result, rejected

        result, rejected = solve_loop(None)
        no_lane = rejected if result.x is not None else result.status == "infeasible"
        heading_rows = (program.family == "heading") if HEADING_FALLBACK and no_lane else None
        if (heading_rows is not None and heading_rows.any()
                and budget - (time.perf_counter() - t_budget) > 0):
            # Eq. 9 in a bend: the boundaries beside the car can turn more than
            # heading_tolerance_rad from the car's heading, and the row then leaves no lane at
            # all (or only lanes through rungs across the track, which the shared predicate
            # rejects). Solved again without it (the heading cost, eq. 25, still counts); the
            # lane cuts made so far stay.
            program.row_lo[heading_rows] = -np.inf
            stats["heading_relaxed"] = True
            result, _ = solve_loop(None)
        stats["solve_time_s"] = time.perf_counter() - t_solve
        if getattr(self.backend, "last_name", ""):
            stats["backend"] = f"{self.backend.name}:{self.backend.last_name}"
        stats["objective"] = result.objective
        stats["bound"] = result.bound
        if result.x is None:
            status = {"infeasible": LaneStatus.INFEASIBLE, "timeout": LaneStatus.TIMEOUT}.get(
                result.status, LaneStatus.NOT_FOUND)
            msg = {
                "infeasible": "the program has no solution: no lane satisfies the constraints",
                "timeout": f"no solution within the time limit of {budget:.3g} s",
            }.get(result.status, f"solver error: {result.message}")
            return Lane.not_found(points, msg, status=status, stats=stats)
        paths, cycles = _split(program, result.x)
        status = LaneStatus.OPTIMAL if result.status == "optimal" else LaneStatus.FEASIBLE
        message = ""
        if cycles:
            # Out of time with a cycle left: the two paths without it still form a lane graph
            # that meets every constraint, but it is no longer proven optimal.
            status, message = LaneStatus.FEASIBLE, "cycle dropped when the time budget ran out"
        if result.status == "feasible":
            message = message or f"time limit reached; gap {result.gap:.4g}"
        if stats.get("heading_relaxed"):
            message = "; ".join(m for m in (message, "no lane met the heading row (eq. 9); "
                                            "solved without it") if m)
        stats["gap"] = result.gap
        if len(paths) != 2:
            return Lane.not_found(points, f"solution has {len(paths)} paths", stats=stats)
        stats["formulation"] = "sided" if program.sided else "paper"
        left, right = self._orient(program, paths, sub, pose)
        # The verdict on the lane returned, whichever way the loop ended (a cycle dropped when
        # the budget ran out included).
        if check and not feasible(left, right):
            n = stats["lane_cut_rounds"]
            why = ("the round limit" if n >= MAX_LANE_CUT_ROUNDS else "the time budget")
            return Lane.not_found(
                points, f"the program's best lane fails the lane constraints (C_seg, C_width, "
                f"C_poly: rld.constraints.lane_is_feasible); {n} lane cuts before {why} ran "
                "out", stats=stats)
        self._previous = [sub[left], sub[right]]
        used = [program.edge_ids(p[:-1], p[1:]) for p in (np.asarray(left), np.asarray(right))]
        if program.sided:
            x_lane = program.solution_from_edges(used[0], used[1])
        else:
            x_lane = program.solution_from_edges(np.concatenate(used))
        lane_cost = program.objective(x_lane)
        return Lane(
            cones=points,
            left=window[left],
            right=window[right],
            status=status,
            message=message,
            cost=lane_cost,
            stats=stats,
        )

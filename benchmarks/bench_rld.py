"""RLD latency: the whole call (window, model update, solve, cycle cuts, extraction) for
n = 12, 16, 20, 30, 40 cones per backend, cold (a fresh solver per call) and warm (one solver
driven pose after pose, as on the car, so each call is hinted with the previous lane).

Instances: generated tracks (``rld.generator``), the evaluation protocol at R = 50 m with 20 %
false positives; every ``stride``-th pose of each lap, consecutive poses for the warm runs.
"""

from __future__ import annotations

import platform
import time

import numpy as np

from rld.api import LaneSolver
from rld.generator import generate_track
from rld.simulation import simulate_lap
from rld.types import LaneParams

SIZES = (12, 16, 20, 30, 40)
BACKENDS = ("cpsat", "highs", "cvxpy")


def _frames(n_tracks: int, stride: int, fp_rate: float = 0.2):
    for seed in range(n_tracks):
        lap = simulate_lap(generate_track(100 + seed), range_m=50.0, fp_rate=fp_rate, seed=seed)
        for k in range(0, len(lap), stride):
            yield lap, k


def _summary(seconds: list[float], statuses: list[str]) -> dict:
    """Calls, median / p95 / max in ms and the status counts of one benchmark cell."""
    ms = 1000 * np.array(seconds)
    n_opt, n_feas = statuses.count("OPTIMAL"), statuses.count("FEASIBLE")
    return {"calls": len(ms), "median_ms": float(np.median(ms)),
            "p95_ms": float(np.percentile(ms, 95)), "max_ms": float(ms.max()),
            "optimal": n_opt, "feasible": n_feas, "no_lane": len(statuses) - n_opt - n_feas}


def run(sizes=SIZES, backends=BACKENDS, n_tracks: int = 4, stride: int = 25,
        time_limit_s: float = 1.0, progress: bool = True, method: str = "rld") -> list[dict]:
    """One row per (backend, n, warm): median / p95 / max latency in ms and status counts."""
    from tqdm import tqdm

    frames = list(_frames(n_tracks, stride))
    rows = []
    total = len(sizes) * len(backends) * 2 * len(frames)
    bar = tqdm(total=total, desc=f"{method} latency", disable=not progress)
    for backend in backends:
        for n in sizes:
            params = LaneParams(max_cones=n, max_windows=1)  # one window of n cones
            # Compile and load everything once, outside the measurement.
            LaneSolver(method, params, backend).solve(frames[0][0].frame(0).cones,
                                                     frames[0][0].frame(0).pose)
            for warm in (False, True):
                lat, statuses = [], []
                solver = None
                for lap, k in frames:
                    if warm:
                        # Warm: the solver saw the previous pose (1 m back) of the same lap.
                        solver = LaneSolver(method, params, backend)
                        prev = lap.frame(max(k - 1, 0))
                        solver.solve(prev.cones, prev.pose, time_limit_s=time_limit_s)
                    else:
                        solver = LaneSolver(method, params, backend)
                    f = lap.frame(k)
                    t0 = time.perf_counter()
                    lane = solver.solve(f.cones, f.pose, time_limit_s=time_limit_s)
                    lat.append(time.perf_counter() - t0)
                    statuses.append(lane.status.name)
                    bar.update(1)
                rows.append({"method": method, "backend": backend, "n": n, "warm": warm,
                             **_summary(lat, statuses)})
    bar.close()
    return rows


def run_budget(sizes=(30, 40), budgets=(0.02, 0.05, 0.2), backends=BACKENDS,
               n_tracks: int = 4, stride: int = 25, progress: bool = True) -> list[dict]:
    """How far past its time budget a call runs: per (backend, n, budget), the call's time
    minus the budget minus the model update (``lane.stats["build_time_s"]``), in ms; what
    issue 3 bounds (the budget plus the model update). Cold calls, the instances of ``run``."""
    from tqdm import tqdm

    frames = [lap.frame(k) for lap, k in _frames(n_tracks, stride)]
    rows = []
    bar = tqdm(total=len(sizes) * len(budgets) * len(backends) * len(frames),
               desc="rld budget", disable=not progress)
    for backend in backends:
        for n in sizes:
            params = LaneParams(max_cones=n, max_windows=1)  # one window of n cones
            LaneSolver("rld", params, backend).solve(frames[0].cones, frames[0].pose)
            for budget in budgets:
                over, statuses = [], []
                for f in frames:
                    solver = LaneSolver("rld", params, backend)
                    t0 = time.perf_counter()
                    lane = solver.solve(f.cones, f.pose, time_limit_s=budget)
                    dt = time.perf_counter() - t0
                    over.append(dt - budget - lane.stats.get("build_time_s", 0.0))
                    statuses.append(lane.status.name)
                    bar.update(1)
                rows.append({"backend": backend, "n": n, "budget_s": budget,
                             **_summary(over, statuses)})
    bar.close()
    return rows


def budget_markdown(rows: list[dict]) -> str:
    lines = ["Time past the budget, excluding the model update (negative: finished early).",
             "",
             "| backend | n | budget (ms) | calls | median (ms) | p95 (ms) | max (ms) | optimal | "
             "feasible | no lane |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['backend']} | {r['n']} | {1000 * r['budget_s']:g} | {r['calls']} | "
                     f"{r['median_ms']:.1f} | {r['p95_ms']:.1f} | {r['max_ms']:.1f} | "
                     f"{r['optimal']} | {r['feasible']} | {r['no_lane']} |")
    return "\n".join(lines)


def machine() -> str:
    import os

    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"{platform.platform()}")


def to_markdown(rows: list[dict], time_limit_s: float) -> str:
    lines = [
        f"Time limit per call {time_limit_s:g} s; calls past it return the incumbent "
        "(FEASIBLE) or no lane.",
        "",
        "| method | backend | n | start | calls | median (ms) | p95 (ms) | max (ms) | optimal | "
        "feasible | no lane |",
        "|---|---|---|---|---|---|---|---|---|---|---|",
    ]
    for r in rows:
        lines.append(
            f"| {r['method']} | {r['backend']} | {r['n']} | "
            f"{'warm' if r['warm'] else 'cold'} | {r['calls']} | "
            f"{r['median_ms']:.1f} | {r['p95_ms']:.1f} | {r['max_ms']:.1f} | {r['optimal']} | "
            f"{r['feasible']} | {r['no_lane']} |"
        )
    return "\n".join(lines)

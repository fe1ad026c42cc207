"""20 Hz on real maps (issue 40, item 2): the whole ``solve`` call of a reused ``LaneSolver``
(window, model update, solves, cuts, chain, extraction) on the protocol's maps of the shared
tracks, each lap driven pose by pose by one solver, its first call left out; the default time
budget unless ``time_limit_s`` is given.

    rld bench latency --methods rld,rld-incremental,clc --fp-rate 0.3 --range-m 50

Per method: calls, median / p95 / max (ms) against the targets (10 / 25 / 50 ms), the calls
that ran past their budget by more than 10 %, and for ``rld`` the windows a call solved.
"""

from __future__ import annotations

import datetime
import platform
import time

import numpy as np

from benchmarks.bench_incremental import _tracks, dataset_available
from rld.api import LaneSolver
from rld.simulation import simulate_lap
from rld.solver import DEFAULT_TIME_LIMIT_S
from rld.tracks import DATASET_TRACKS

__all__ = ["run", "to_markdown", "dataset_available", "TARGETS_MS"]

#: Issue 40's targets, ms: median, p95, max.
TARGETS_MS = (10.0, 25.0, 50.0)
#: ``quick``: the first track, this many poses.
QUICK_POSES = 20


def run(methods=("rld", "rld-incremental", "clc"), range_m: float = 50.0, fp_rate: float = 0.3,
        every: int = 1, tracks=DATASET_TRACKS, time_limit_s: float | None = None,
        quick: bool = False, seed: int = 0, progress: bool = True) -> list[dict]:
    """One record per steady call (a solver's first call left out): method, track, pose,
    latency (s), status, and the chained windows of an ``rld`` call (-1 for other methods)."""
    from tqdm import tqdm

    ids = list(tracks)[:1] if quick else list(tracks)
    laps = [simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed)
            for track in _tracks(ids)]
    records = []
    for method in methods:
        for lap in laps:
            solver = LaneSolver(method)
            n = min(len(lap), QUICK_POSES) if quick else len(lap)
            for j, k in enumerate(tqdm(range(0, n, every), desc=f"{method} {lap.track.name}",
                                       disable=not progress, leave=False)):
                f = lap.frame(k)
                t0 = time.perf_counter()
                lane = solver.solve(f.cones, f.pose, time_limit_s=time_limit_s)
                latency = time.perf_counter() - t0
                if j == 0:
                    continue  # the first call loads the backends and compiles
                records.append({
                    "method": method, "track": lap.track.name, "pose": k, "latency_s": latency,
                    "status": lane.status.name,
                    "windows": int(lane.stats.get("chain", {}).get("windows", -1))})
    return records


def to_markdown(records: list[dict], range_m: float, fp_rate: float,
                time_limit_s: float | None, command: str = "") -> str:
    budget = DEFAULT_TIME_LIMIT_S if time_limit_s is None else time_limit_s
    head = (f"Command: `{command}`. " if command else "") + (
        f"Machine: {platform.machine()}, {_cores()} cores, Python {platform.python_version()}. "
        f"Date: {datetime.date.today().isoformat()}. R = {range_m:g} m, {fp_rate:.0%} false "
        f"positives, budget {budget:g} s a call (RLD's; CLC's own otherwise). Targets: median "
        f"<= {TARGETS_MS[0]:g}, p95 <= {TARGETS_MS[1]:g}, max <= {TARGETS_MS[2]:g} ms.")
    lines = [head, "",
             "| method | calls | median (ms) | p95 (ms) | max (ms) | targets met | over budget "
             "by > 10 % | windows a call, median / max |",
             "|---|---|---|---|---|---|---|---|"]
    for method in dict.fromkeys(r["method"] for r in records):
        recs = [r for r in records if r["method"] == method]
        lat = 1000.0 * np.array([r["latency_s"] for r in recs])
        q = (float(np.median(lat)), float(np.percentile(lat, 95)), float(lat.max()))
        met = "/".join("yes" if v <= t else "no" for v, t in zip(q, TARGETS_MS, strict=True))
        over = int(np.sum(lat > 1100.0 * budget)) if method.startswith("rld") else "-"
        win = np.array([r["windows"] for r in recs if r["windows"] >= 0])
        wtxt = f"{np.median(win):g} / {win.max()}" if win.size else "-"
        lines.append(f"| {method} | {len(recs)} | {q[0]:.1f} | {q[1]:.1f} | {q[2]:.1f} | {met} | "
                     f"{over} | {wtxt} |")
    return "\n".join(lines)


def _cores() -> int:
    import os

    return os.cpu_count() or 1

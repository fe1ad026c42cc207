"""CLC on the shared dataset tracks under the evaluation protocol (DESIGN.md).

- ``run``: latency (the whole ``LaneSolver.solve`` call, after compile) and accuracy per range
  and false-positive rate, one solver per lap driven pose after pose (warm starts, as on the
  car), every ``every``-th pose; the share of complete enumerations (the paper's Table II).
- ``run_iterations``: latency against it_max and against the map size (the paper's fig. 16).
- ``compile_time``: the first call in a fresh process with an empty numba cache, and with a
  warm cache (what a car computer pays once per boot).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time

import numpy as np

from rld.evaluation import run_protocol, summarize
from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track
from rld.types import LaneParams


def _tracks():
    folder = find_dataset_dir()
    if folder is None:
        raise FileNotFoundError("racetrack dataset not found (../shared/data/...)")
    return [load_dataset_track(folder, k) for k in DATASET_TRACKS]


def _warm_up(ranker, tracks=None) -> None:
    """Compile (or load from the cache) every kernel before timing: a toy lane, then a few
    real frames (dives, closings and fallbacks call kernels the toy lane does not reach; once,
    on an empty cache, the first timed pose took 1.7 s)."""
    from rld.api import LaneSolver

    pts = np.array([[0, 1.75], [4, 1.75], [0, -1.75], [4, -1.75], [8, 1.75], [8, -1.75]], float)
    LaneSolver(method="clc", ranker=ranker).solve(pts, (0.0, 0.0, 0.0))
    for track in (tracks or [])[:1]:
        run_protocol([track], method="clc", range_m=50.0, fp_rate=0.3, every=10,
                     stateful=True, ranker=ranker)


def run(ranges=(30.0, 50.0), fp_rates=(0.0, 0.1, 0.3, 0.5), every: int = 4, ranker=None,
        params: LaneParams | None = None, progress: bool = True) -> list[dict]:
    """One row per (range, false-positive rate): the protocol's summary plus completeness."""
    tracks = _tracks()
    _warm_up(ranker, tracks)
    rows = []
    for r in ranges:
        for fp in fp_rates:
            recs = run_protocol(tracks, method="clc", params=params, range_m=r, fp_rate=fp,
                                every=every, stateful=True, progress=progress, ranker=ranker)
            rows.append({"range_m": r, "fp_rate": fp, **summarize(recs)})
    return rows


def to_markdown(rows: list[dict]) -> str:
    lines = ["| R (m) | FP | poses | critical % (tolerant) | gt % | near_gt % | too_short % | "
             "mean IoU % | IoU20 % | pred / true length (m) | complete % | "
             "median / p95 / p99 / max latency (ms) |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['range_m']:.0f} | {r['fp_rate']:.0%} | {r['poses']} | {r['critical']:.1f} "
            f"({r['critical_tolerant']:.1f}) | {r['gt']:.1f} | {r['near_gt']:.1f} | "
            f"{r['too_short']:.1f} | {r['mean_iou']:.1f} | {r['mean_iou20']:.1f} | "
            f"{r['pred_length_m']:.0f} / {r['true_length_m']:.0f} | {r.get('complete', 0):.1f} | "
            f"{r['latency_median_ms']:.1f} / {r['latency_p95_ms']:.1f} / "
            f"{r['latency_p99_ms']:.1f} / {r['latency_max_ms']:.1f} |")
    return "\n".join(lines)


def run_iterations(it_maxes=(250, 500, 1000, 2500, 5000), fp_rate: float = 0.3,
                   range_m: float = 50.0, every: int = 8, ranker=None,
                   progress: bool = True) -> list[dict]:
    """Latency, critical failures and completeness against it_max, and (at the default it_max)
    latency against the map size."""
    tracks = _tracks()
    _warm_up(ranker, tracks)
    rows = []
    for it in it_maxes:
        recs = run_protocol(tracks, method="clc", params=LaneParams(max_iterations=it),
                            range_m=range_m, fp_rate=fp_rate, every=every, stateful=True,
                            progress=progress, ranker=ranker)
        lat = 1000.0 * np.array([r.latency_s for r in recs])
        rows.append({"it_max": it, "poses": len(recs), "median_ms": float(np.median(lat)),
                     "p95_ms": float(np.percentile(lat, 95)),
                     "critical": summarize(recs)["critical"],
                     "complete": summarize(recs).get("complete", 0.0)})
        if it == LaneParams().max_iterations:
            cones = np.array([r.n_cones for r in recs])
            edges = [0, 50, 100, 150, 200, 300, 10_000]
            for lo, hi in zip(edges[:-1], edges[1:], strict=True):
                sel = (cones >= lo) & (cones < hi)
                if sel.any():
                    rows.append({"map_cones": f"{lo}-{hi if hi < 10_000 else ''}",
                                 "poses": int(sel.sum()), "median_ms": float(np.median(lat[sel])),
                                 "p95_ms": float(np.percentile(lat[sel], 95))})
    return rows


def iterations_markdown(rows: list[dict]) -> str:
    a = ["| it_max | poses | median (ms) | p95 (ms) | critical % | complete % |",
         "|---|---|---|---|---|---|"]
    b = ["| map cones | poses | median (ms) | p95 (ms) |", "|---|---|---|---|"]
    for r in rows:
        if "it_max" in r:
            a.append(f"| {r['it_max']} | {r['poses']} | {r['median_ms']:.1f} | "
                     f"{r['p95_ms']:.1f} | {r['critical']:.1f} | {r['complete']:.1f} |")
        else:
            b.append(f"| {r['map_cones']} | {r['poses']} | {r['median_ms']:.1f} | "
                     f"{r['p95_ms']:.1f} |")
    return "\n".join(a) + "\n\n" + "\n".join(b)


_FIRST_CALL = """
import time
t0 = time.perf_counter()
import numpy as np
from rld import solve_lane
pts = np.array([[0, 1.75], [4, 1.75], [0, -1.75], [4, -1.75], [8, 1.75], [8, -1.75]], float)
t1 = time.perf_counter()
solve_lane(pts, (0.0, 0.0, 0.0), method="clc", ranker="longest")
t2 = time.perf_counter()
solve_lane(pts, (0.0, 0.0, 0.0), method="clc", ranker="longest")
t3 = time.perf_counter()
print(t1 - t0, t2 - t1, t3 - t2)
"""


def compile_time() -> dict:
    """Seconds for import, first call and second call in a fresh process: with an empty numba
    cache (compile) and then with the cache it left (load)."""
    out = {}
    with tempfile.TemporaryDirectory() as cache:
        env = dict(os.environ, NUMBA_CACHE_DIR=cache)
        for label in ("empty cache", "warm cache"):
            t0 = time.perf_counter()
            res = subprocess.run([sys.executable, "-c", _FIRST_CALL], env=env, check=True,
                                 capture_output=True, text=True)
            imp, first, second = (float(v) for v in res.stdout.split())
            out[label] = {"import_s": imp, "first_call_s": first, "second_call_s": second,
                          "process_s": time.perf_counter() - t0}
    return out

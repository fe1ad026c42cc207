"""Latency with colour against colourless (issue 41: within 10 %), paired on the same poses:
for each method, track, range and false-positive rate, one solver with the simulated classes
(``rld.simulation``, accuracy A, unknown share U) and one without, both kept for the lap as
on the car, called on every ``every``-th pose one after the other (the order alternating
from pose to pose, so that both meet the same load).

    python -m benchmarks.bench_color_latency --set reporting --every 16 --seed 5

prints per method the median and p95 of each run's latency (ms), the median of the paired
ratio (colour / colourless) and the number of poses; each lap's first call (start-up) is left
out.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from benchmarks import bench_color as bc


def measure(set_name: str = "reporting", methods=("clc", "rld"), accuracy: float = 0.95,
            unknown: float = bc.UNKNOWN, ranges=(30.0, 50.0), fp_rates=(0.0, 0.1, 0.3, 0.5),
            every: int = 16, seed: int = 5, generated: int = 4) -> dict[str, np.ndarray]:
    """Per method, an (n, 2) array of latencies (s): colourless, colour; paired by pose."""
    from rld import LaneSolver
    from rld.simulation import simulate_lap

    out: dict[str, list] = {m: [] for m in methods}
    flip = False
    for track in bc.tracks(set_name, generated):
        for r in ranges:
            for fp in fp_rates:
                lap = simulate_lap(track, range_m=r, fp_rate=fp, seed=seed,
                                   color_accuracy=accuracy, color_unknown=unknown)
                for m in methods:
                    solvers = (LaneSolver(m), LaneSolver(m))
                    for i, k in enumerate(range(0, len(lap), every)):
                        f = lap.frame(k)
                        t = [0.0, 0.0]
                        order = (1, 0) if flip else (0, 1)
                        flip = not flip
                        for j in order:
                            t0 = time.perf_counter()
                            solvers[j].solve(f.cones, f.pose,
                                             colors=None if j == 0 else f.colors)
                            t[j] = time.perf_counter() - t0
                        if i > 0:  # the lap's first call: start-up, not latency
                            out[m].append(t)
    return {m: np.asarray(v, dtype=float).reshape(-1, 2) for m, v in out.items()}


def table(lat: dict[str, np.ndarray]) -> str:
    lines = ["| method | poses | colourless median / p95 (ms) | colour median / p95 (ms) | "
             "paired ratio colour / colourless: median (of the medians: ratio) |",
             "|---|---|---|---|---|"]
    for m, v in lat.items():
        a, b = v[:, 0] * 1e3, v[:, 1] * 1e3
        lines.append(f"| {m} | {len(v)} | {np.median(a):.1f} / {np.percentile(a, 95):.1f} | "
                     f"{np.median(b):.1f} / {np.percentile(b, 95):.1f} | "
                     f"{np.median(b / a):.3f} ({np.median(b) / np.median(a):.3f}) |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--set", default="reporting", choices=sorted(bc.SETS))
    ap.add_argument("--methods", default="clc,rld")
    ap.add_argument("--accuracy", type=float, default=0.95)
    ap.add_argument("--every", type=int, default=16)
    ap.add_argument("--seed", type=int, default=5)
    ap.add_argument("--generated", type=int, default=4)
    a = ap.parse_args(argv)
    lat = measure(a.set, a.methods.split(","), a.accuracy, every=a.every, seed=a.seed,
                  generated=a.generated)
    print(table(lat))


if __name__ == "__main__":
    main()

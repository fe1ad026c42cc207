"""``rld warmup``: compile every numba kernel a method uses into the user kernel cache, for this
machine's CPU, ahead of the first real call (a car's start-up or install script).

The kernels are compiled on first use and cached on disk (``rld._jit.cache_dir()``); a fresh
install therefore pays the compilation on its first ``solve_lane`` (seconds to tens of seconds
per method, ``benchmarks/bench_startup.py``), every later process only loads the cache. This
module pays it up front: it solves a few frames of a generated track with each method, the
same calls a car makes, so exactly the kernels and signatures of those calls get compiled.
"""

from __future__ import annotations

import time
from collections.abc import Callable, Iterable

__all__ = ["warmup", "warmup_frames"]

#: (perception range m, false-positive rate, first pose as a fraction of the lap, poses in a
#: row, colour accuracy or None): short and long range, with false positives, without and with
#: colour; a few consecutive poses so that the warm-started and incremental paths run too.
FRAMES = ((30.0, 0.2, 1 / 3, 3, None), (50.0, 0.3, 2 / 3, 3, 0.9))


def warmup_frames(seed: int = 7):
    """The frames ``warmup`` solves, as lists of consecutive ``rld.simulation.Frame``s."""
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    track = generate_track(seed)
    runs = []
    for range_m, fp_rate, where, count, color in FRAMES:
        lap = simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed,
                           color_accuracy=color, color_unknown=0.1)
        first = int(len(lap) * where)
        runs.append([lap.frame(first + k) for k in range(count)])
    return runs


def warmup(methods: Iterable[str] | None = None,
           progress: Callable[[str], None] | None = None) -> dict[str, float]:
    """Compile (or load) every kernel of ``methods`` (default: all of ``rld.api.METHODS``) by
    solving ``warmup_frames()`` with each; returns the seconds each method took. ``progress``
    is called with the method's name after each frame (a progress bar's update)."""
    from rld._jit import host_kernels
    from rld.api import METHODS

    names = list(METHODS) if methods is None else list(methods)
    unknown = [m for m in names if m not in METHODS]
    if unknown:
        raise ValueError(f"unknown methods {unknown}; available: {', '.join(sorted(METHODS))}")
    runs = warmup_frames()
    seconds = {}
    with host_kernels():
        for m in names:
            seconds[m] = _solve_all(m, runs, progress)
    return seconds


def _solve_all(method: str, runs, progress) -> float:
    """Seconds to solve every frame of ``runs`` with ``method``, a new solver per run."""
    from rld.api import LaneSolver

    t0 = time.perf_counter()
    for frames in runs:
        solver = LaneSolver(method=method)
        for f in frames:
            solver.solve(f.cones, f.pose, colors=f.colors)
            if progress is not None:
                progress(method)
    return time.perf_counter() - t0


"""RLD against CLC through the public methods on windows of at most 30 cones (issue 40, item 4).

``python -m benchmarks.bench_crosscheck --plot docs/crosscheck_public.png`` cuts RLD's own
window of at most 30 cones (``rld.solver.cone_window``, ``max_cones=30``) from every 15th pose
of the six shared tracks (R = 30 m, no false positives), solves it with ``LaneSolver("rld")``
(the program over the whole window) and with ``LaneSolver("clc", ranker="rld_cost")`` with no
iteration limit in effect (``max_iterations`` 1e9), both otherwise at their defaults, and
compares the lanes from each side's first cone not behind the car (closed lanes as edge sets).
Each disagreement gets its cause: ``lap start`` (pose 0: no cone behind the car, the two start
rules take different cones beside it), ``RLD lane not CLC-feasible`` (it fails
``lane_is_feasible``, so CLC cannot return it) or ``first cone`` (the lanes differ only in one
side's first cone, which one lane has and the other not: RLD's path from behind the car passes
it, CLC's start pair takes it); anything else is ``unexplained``.
tests/test_crosscheck.py holds the figures.
"""

from __future__ import annotations

import argparse
import sys
from collections.abc import Sequence

import numpy as np

#: The six shared tracks.
TRACKS = (1, 2, 3, 4, 6, 7)


def ahead(points: np.ndarray, pose, lane) -> tuple:
    """A lane as the cross-check compares it: an open lane's sides from their first cone not
    behind the car (``geometry.leading_behind``), a closed lane's as sets of edges."""
    from rld import geometry as geo

    if lane.closed:
        return tuple(frozenset(tuple(sorted(e)) for e in zip(p.tolist(), np.roll(p, -1).tolist(),
                                                            strict=True))
                     for p in (lane.left, lane.right))
    return tuple(tuple(p[geo.leading_behind(points[p], pose.xy, pose.heading, keep=1):].tolist())
                 for p in (lane.left, lane.right))


def first_cone_only(a: tuple, b: tuple) -> bool:
    """Whether two open lanes as ``ahead`` gives them differ only in one side, which is the
    other lane's side with one cone more at its start."""
    if not all(isinstance(x, tuple) for x in (*a, *b)):
        return False  # a closed lane (edge sets)
    diff = [k for k in (0, 1) if a[k] != b[k]]
    if len(diff) != 1:
        return False
    x, y = sorted((a[diff[0]], b[diff[0]]), key=len)
    return len(y) == len(x) + 1 and y[1:] == x


def run(dataset_dir, tracks: Sequence[int] = TRACKS, fp_rate: float = 0.0, every: int = 15,
        range_m: float = 30.0) -> list[dict]:
    """One record per window: track, pose, the frame, its window's cones, both lanes, the
    solver's status and completeness, ``same`` and, when not, ``cause``."""
    from rld import LaneParams, LaneSolver
    from rld.constraints import lane_is_feasible
    from rld.simulation import simulate_lap
    from rld.solver import cone_window
    from rld.tracks import load_dataset_track

    window = LaneParams(max_cones=30)
    unlimited = LaneParams(max_cones=30, max_iterations=10**9)
    out = []
    for track in tracks:
        lap = simulate_lap(load_dataset_track(dataset_dir, track), range_m=range_m,
                           fp_rate=fp_rate, seed=0)
        for k in range(0, len(lap), every):
            f = lap.frame(k)
            idx, _ = cone_window(f.cones, f.pose, window)
            pts = f.cones[idx]
            rld = LaneSolver("rld", params=window).solve(pts, f.pose, time_limit_s=30.0)
            clc = LaneSolver("clc", params=unlimited, ranker="rld_cost").solve(pts, f.pose)
            rec = {"track": track, "pose": k, "frame": f, "idx": idx, "rld": rld, "clc": clc,
                   "optimal": rld.status.name == "OPTIMAL",
                   "complete": bool(clc.stats.get("complete")),
                   "same": ahead(pts, f.pose, rld) == ahead(pts, f.pose, clc)}
            if not rec["same"]:
                if k == 0:
                    rec["cause"] = "lap start"
                elif rld.ok and not lane_is_feasible(pts[rld.left], pts[rld.right], window,
                                                     closed=rld.closed):
                    rec["cause"] = "RLD lane not CLC-feasible"
                elif first_cone_only(ahead(pts, f.pose, rld), ahead(pts, f.pose, clc)):
                    rec["cause"] = "first cone"
                else:
                    rec["cause"] = "unexplained"
            out.append(rec)
    return out


def plot(records: list[dict], path: str) -> None:
    """Every disagreement side by side (RLD left, CLC right), the truth dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from rld.plotting import plot_scene

    bad = [r for r in records if not r["same"]]
    if not bad:
        return
    fig, axes = plt.subplots(len(bad), 2, figsize=(8, 3.2 * len(bad)), squeeze=False)
    for row, r in zip(axes, bad, strict=True):
        f, idx = r["frame"], r["idx"]
        inv = {int(v): i for i, v in enumerate(idx)}
        gl = np.array([inv[int(v)] for v in f.gt_left if int(v) in inv], dtype=np.int64)
        gr = np.array([inv[int(v)] for v in f.gt_right if int(v) in inv], dtype=np.int64)
        for ax, name in zip(row, ("rld", "clc"), strict=True):
            plot_scene(f.cones[idx], r[name], f.pose, gl, gr, title=(
                f"track {r['track']} pose {r['pose']}: {name} ({r['cause']})"), ax=ax)
    fig.tight_layout()
    fig.savefig(path, dpi=70)
    plt.close(fig)


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(prog="python -m benchmarks.bench_crosscheck",
                                 description=__doc__.splitlines()[0])
    ap.add_argument("--dataset", default=None, help="The racetrack dataset folder.")
    ap.add_argument("--fp-rate", type=float, default=0.0, help="False-positive rate.")
    ap.add_argument("--plot", default=None, help="Draw the disagreements to this PNG.")
    args = ap.parse_args(argv)
    from rld.tracks import find_dataset_dir

    folder = args.dataset or find_dataset_dir()
    if folder is None:
        raise SystemExit("the racetrack dataset was not found: give --dataset")
    recs = run(folder, fp_rate=args.fp_rate)
    same = sum(r["same"] for r in recs)
    print(f"{same} of {len(recs)} windows identical; RLD optimal in "
          f"{sum(r['optimal'] for r in recs)}, CLC complete in {sum(r['complete'] for r in recs)}")
    for r in recs:
        if not r["same"]:
            print(f"track {r['track']} pose {r['pose']}: {r['cause']}")
    if args.plot:
        plot(recs, args.plot)


if __name__ == "__main__":
    main(sys.argv[1:])

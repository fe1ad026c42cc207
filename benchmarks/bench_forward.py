"""``rld`` returns its chained lane from the car forward (``IncrementalRld.forward``): each pose's
lane scored as returned and as the chain was before that view (the cones behind the car kept),
exactly paired (the same lanes), one ``LaneSolver("rld")`` per lap, every 2nd pose of the shared
tracks. Choosing seeds 0-4, reporting seeds 5-9 (DESIGN.md, "Choosing and reporting").

    python -m benchmarks.bench_forward --seeds 5,6 --processes 2

prints the geometric critical rates > 1 m / > 0.5 m of both views pooled and per cell, the
poses the view fixed and broke, the paired difference with its 95 % lap-bootstrap interval
and the mean predicted length; ``--out`` also writes the records (JSON).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp


def _job(args) -> list[dict]:
    """Records of one (seed, range, rate) over the six shared tracks."""
    seed, range_m, fp_rate, every = args
    from scipy.spatial import cKDTree

    from rld.api import LaneSolver
    from rld.incremental import IncrementalRld
    from rld.metrics import score_lane
    from rld.simulation import simulate_lap
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track
    from rld.types import Lane

    seen: dict = {}
    forward = IncrementalRld.forward

    def spy(self, points, pose, lane, colors=None):
        seen["lane"], seen["points"] = lane, points
        return forward(self, points, pose, lane, colors)

    IncrementalRld.forward = spy
    folder = find_dataset_dir()
    out = []
    try:
        for t in DATASET_TRACKS:
            lap = simulate_lap(load_dataset_track(folder, t), range_m=range_m, fp_rate=fp_rate,
                               seed=seed)
            solver = LaneSolver("rld")
            for k in range(0, len(lap), every):
                f = lap.frame(k)
                seen.clear()
                lane = solver.solve(f.cones, f.pose)
                whole = lane
                if seen and seen["lane"].ok:  # the solver's (merged) cones -> the caller's
                    idx = cKDTree(f.cones).query(seen["points"])[1]
                    w = seen["lane"]
                    whole = Lane(cones=f.cones, left=idx[w.left], right=idx[w.right],
                                 status=w.status, closed=w.closed)
                a = score_lane(f, lane.left, lane.right, lane.ok, lane.closed)
                b = score_lane(f, whole.left, whole.right, whole.ok, whole.closed)
                out.append(dict(track=int(t), pose=k, seed=seed, range_m=range_m,
                                fp_rate=fp_rate, forward_m=a.deviation_m, whole_m=b.deviation_m,
                                forward_length_m=a.pred_length_m,
                                whole_length_m=b.pred_length_m))
    finally:
        IncrementalRld.forward = forward  # the pool reuses this process for other jobs
    return out


def run(seeds=(1, 2), ranges=(30.0, 50.0), fp_rates=(0.0, 0.3, 0.5), every: int = 2,
        processes: int = 2) -> list[dict]:
    jobs = [(s, r, f, every) for s in seeds for r in ranges for f in fp_rates]
    with mp.Pool(processes) as pool:
        parts = pool.map(_job, jobs, chunksize=1)
    return [r for part in parts for r in part]


def lap_interval(records: list[dict], d: float) -> tuple[float, float, float]:
    """Forward minus whole, points of the critical rate at ``d`` metres, with the project's
    paired 95 % lap-bootstrap interval (``bench_ends.lap_interval``)."""
    from benchmarks.bench_ends import lap_interval as paired

    return paired(records, d, ("whole", "forward"))


def table(records: list[dict]) -> str:
    from benchmarks.bench_ends import table as paired_table

    return paired_table(records, ("whole", "forward"), ("whole", "forward"), gt=False)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="1,2", help="false-positive seeds, comma-separated")
    ap.add_argument("--every", type=int, default=2, help="every k-th pose (keep it below 5)")
    ap.add_argument("--processes", type=int, default=2, help="worker processes")
    ap.add_argument("--out", default="", help="also write the records to this JSON file")
    a = ap.parse_args()
    recs = run(seeds=[int(s) for s in a.seeds.split(",")], every=a.every,
               processes=a.processes)
    if a.out:
        with open(a.out, "w") as fh:
            json.dump(recs, fh)
    print(table(recs))


if __name__ == "__main__":
    main()

"""A lane edit of ``rld.insertion`` (``--rule``): the end extensions (``extend_ends``, in ``rld``
and CLC), CLC's lap-start rule (``starts``, ``extend_starts``), the swaps (``swaps``,
``swap_cones``, in ``rld`` and CLC) or ``rld``'s held lane (``holds``,
``IncrementalRld.hold``: before it, no lane): each pose's lane scored as returned
and as it was before the rule, exactly paired (the same call), one ``LaneSolver`` per lap,
every 2nd pose of the shared tracks. Choosing seeds 0-4, reporting seeds 5-9 (DESIGN.md,
"Choosing and reporting").

    python -m benchmarks.bench_ends --method clc --seeds 1,2 --processes 2

prints the geometric critical rates > 1 m / > 0.5 m of both pooled and per cell, the poses the
extension fixed and broke, the paired difference with its 95 % lap-bootstrap interval, the
mean predicted length and the share of poses whose lane the index rule calls the truth
(``gt``); ``--out`` also writes the records (JSON).
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp

import numpy as np

#: The rules a run can pair: rule -> (the function the spy replaces, {method: the module
#: where that method looks it up}).
RULES = {"ends": ("extend_ends", {"rld": "rld.incremental", "clc": "clc.refine"}),
         "starts": ("extend_starts", {"clc": "clc.refine"}),
         "swaps": ("swap_cones", {"rld": "rld.insertion", "clc": "clc.refine"}),
         "holds": ("IncrementalRld.hold", {"rld": "rld.incremental"})}


def _job(args) -> list[dict]:
    """Records of one (method, seed, range, rate) over the six shared tracks."""
    method, seed, range_m, fp_rate, every, rule = args
    import importlib

    from scipy.spatial import cKDTree

    from rld.api import LaneSolver
    from rld.metrics import score_lane
    from rld.simulation import simulate_lap
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    name, modules = RULES[rule]
    if method not in modules:
        raise ValueError(f"rule {rule!r} is not in method {method!r}")
    module = importlib.import_module(modules[method])
    *owner_path, name = name.split(".")
    for part in owner_path:  # a method: replaced on its class
        module = getattr(module, part)
    original = getattr(module, name)
    seen: dict = {}

    def spy(points, pose, sides, *args, **kwargs):
        seen["sides"], seen["points"] = [np.array(s) for s in sides], points
        return original(points, pose, sides, *args, **kwargs)

    def held(self, points, pose, *args, **kwargs):
        out = original(self, points, pose, *args, **kwargs)
        if out is not None:  # before the rule: no lane
            seen["held"] = True
        return out

    setattr(module, name, held if owner_path else spy)
    folder = find_dataset_dir()
    out = []
    try:
        for t in DATASET_TRACKS:
            lap = simulate_lap(load_dataset_track(folder, t), range_m=range_m, fp_rate=fp_rate,
                               seed=seed)
            solver = LaneSolver(method)
            for k in range(0, len(lap), every):
                f = lap.frame(k)
                seen.clear()
                lane = solver.solve(f.cones, f.pose)
                a = score_lane(f, lane.left, lane.right, lane.ok, lane.closed)
                b = a
                if seen.get("held") and lane.ok:  # before the rule: no lane
                    none = np.zeros(0, dtype=np.int64)
                    b = score_lane(f, none, none, False, False)
                elif seen and lane.ok and not lane.closed:  # the solver's cones -> the caller's
                    idx = cKDTree(f.cones).query(seen["points"])[1]
                    left, right = (idx[s] for s in seen["sides"])
                    b = score_lane(f, left, right, True, False)
                out.append(dict(track=int(t), pose=k, seed=seed, range_m=range_m,
                                fp_rate=fp_rate, on_m=a.deviation_m, off_m=b.deviation_m,
                                on_length_m=a.pred_length_m, off_length_m=b.pred_length_m,
                                on_gt=a.category == "gt", off_gt=b.category == "gt"))
    finally:
        setattr(module, name, original)  # the pool reuses this process for other jobs
    return out


def run(method: str = "clc", seeds=(1, 2), ranges=(30.0, 50.0), fp_rates=(0.0, 0.3, 0.5),
        every: int = 2, processes: int = 2, rule: str = "ends") -> list[dict]:
    jobs = [(method, s, r, f, every, rule) for s in seeds for r in ranges for f in fp_rates]
    with mp.Pool(processes) as pool:
        parts = pool.map(_job, jobs, chunksize=1)
    return [r for part in parts for r in part]


def lap_interval(records: list[dict], d: float, keys=("off", "on")) -> tuple[float, float, float]:
    """The second view minus the first (``keys``: the records' ``<key>_m`` deviations), points
    of the critical rate at ``d`` metres, with the project's paired 95 % lap-bootstrap interval
    (``bench_color_weights.paired_interval``)."""
    from benchmarks.bench_color_weights import paired_interval

    first = [dict(r, deviation_m=r[f"{keys[0]}_m"]) for r in records]
    second = [dict(r, deviation_m=r[f"{keys[1]}_m"]) for r in records]
    return paired_interval(first, second, d)


def table(records: list[dict], keys=("off", "on"), names=("without", "with"),
          gt: bool = True) -> str:
    """Two views of each pose's lane (``keys``, shown as ``names``): both rates pooled and
    per cell, the poses the second fixed and broke, the paired difference, the lengths and,
    with ``gt``, the index rule's GT share."""
    a_, b_ = names
    lines = [f"| cells | poses | {a_} > 1 / > 0.5 m % | {b_} > 1 / > 0.5 m % | fixed / broken "
             f"(> 1 m; > 0.5 m) | difference, points [95 %] | length {a_} / {b_} (m) |"
             + (f" gt % {a_} / {b_} |" if gt else ""),
             "|---|---|---|---|---|---|---|" + ("---|" if gt else "")]
    cells = sorted({(r["range_m"], r["fp_rate"]) for r in records})
    for name, sel in [("all", records)] + [
            (f"{k[0]:g} m {k[1]:.0%}", [r for r in records if (r["range_m"], r["fp_rate"]) == k])
            for k in cells]:
        a = np.array([r[f"{keys[1]}_m"] for r in sel])
        b = np.array([r[f"{keys[0]}_m"] for r in sel])
        moved = "; ".join(f"{int(np.sum((b > d) & (a <= d)))} / {int(np.sum((a > d) & (b <= d)))}"
                          for d in (1.0, 0.5))
        diff = ", ".join("{:+.2f} [{:+.2f}, {:+.2f}]".format(*lap_interval(sel, d, keys))
                         for d in (1.0, 0.5)) if name == "all" else "-"
        line = (f"| {name} | {len(sel)} | {100 * np.mean(b > 1):.2f} / "
                f"{100 * np.mean(b > 0.5):.2f} | {100 * np.mean(a > 1):.2f} / "
                f"{100 * np.mean(a > 0.5):.2f} | {moved} | {diff} | "
                f"{np.mean([r[f'{keys[0]}_length_m'] for r in sel]):.1f} / "
                f"{np.mean([r[f'{keys[1]}_length_m'] for r in sel]):.1f} |")
        if gt:
            line += (f" {100 * np.mean([r[f'{keys[0]}_gt'] for r in sel]):.1f} / "
                     f"{100 * np.mean([r[f'{keys[1]}_gt'] for r in sel]):.1f} |")
        lines.append(line)
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--method", default="clc", choices=["clc", "rld"])
    ap.add_argument("--seeds", default="1,2", help="false-positive seeds, comma-separated")
    ap.add_argument("--every", type=int, default=2, help="every k-th pose (keep it below 5)")
    ap.add_argument("--processes", type=int, default=2, help="worker processes")
    ap.add_argument("--rule", default="ends", choices=sorted(RULES),
                    help="the rule paired: end extensions, CLC's lap-start rule, the swaps, "
                         "or rld's held lane")
    ap.add_argument("--fp-rates", default="0,0.3,0.5", help="false-positive rates")
    ap.add_argument("--out", default="", help="also write the records to this JSON file")
    a = ap.parse_args()
    recs = run(a.method, seeds=[int(s) for s in a.seeds.split(",")], every=a.every,
               processes=a.processes, rule=a.rule,
               fp_rates=[float(x) for x in a.fp_rates.split(",")])
    if a.out:
        with open(a.out, "w") as fh:
            json.dump(recs, fh)
    print(table(recs))


if __name__ == "__main__":
    main()

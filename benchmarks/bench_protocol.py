"""A method on the shared dataset tracks under the evaluation protocol (DESIGN.md), a quick
sample: every ``every``-th pose, one ``LaneSolver`` per lap (warm starts, as on the car).
The full ``rld eval`` comes with issue 5; this gives the figures of docs/benchmarks.md."""

from __future__ import annotations

from rld.evaluation import run_protocol, summarize
from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track


def run(method: str = "rld", backend: str | None = None, fp_rates=(0.0, 0.3),
        range_m: float = 50.0, every: int = 12, time_limit_s: float = 2.0,
        progress: bool = True) -> list[dict]:
    folder = find_dataset_dir()
    if folder is None:
        raise FileNotFoundError("racetrack dataset not found (../shared/data/...)")
    tracks = [load_dataset_track(folder, k) for k in DATASET_TRACKS]
    rows = []
    for fp in fp_rates:
        recs = run_protocol(tracks, method=method, backend=backend, range_m=range_m,
                            fp_rate=fp, every=every, stateful=True,
                            time_limit_s=time_limit_s, progress=progress)
        rows.append({"method": method, "fp_rate": fp, **summarize(recs)})
    return rows


def to_markdown(rows: list[dict]) -> str:
    lines = ["| method | FP | poses | critical % (tolerant) | gt % | near_gt % | too_short % | "
             "IoU20 % | pred / true length (m) | median / p95 latency (ms) |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(
            f"| {r['method']} | {r['fp_rate']:.0%} | {r['poses']} | {r['critical']:.1f} "
            f"({r['critical_tolerant']:.1f}) | {r['gt']:.1f} | {r['near_gt']:.1f} | "
            f"{r['too_short']:.1f} | {r['mean_iou20']:.0f} | {r['pred_length_m']:.0f} / "
            f"{r['true_length_m']:.0f} | {r['latency_median_ms']:.0f} / "
            f"{r['latency_p95_ms']:.0f} |")
    return "\n".join(lines)

"""A reused ``rld`` solver keeps its chain (``rld.incremental.KEPT_GROWTH_S``): against the
stateless chain (a fresh solver per pose) on the shared tracks, poses 2 m apart (``--every 2``)
so that one solver per lap re-attaches its chain, as on the car.

    python -m benchmarks.bench_kept --seeds 1,2 --growth 0.025,0.05,0.1 --processes 2

writes ``records.json`` and ``tables.md`` (in ``--out``): per variant, the geometric critical
rates > 1 m / > 0.5 m (pooled and per cell), the paired difference to the stateless chain with
its 95 % lap-bootstrap interval, mean predicted / true length and latency median / p95 / max.
Choosing seeds 0-4, reporting seeds 5-9 (DESIGN.md, "Choosing and reporting").
"""

from __future__ import annotations

import argparse
import itertools
import json
import multiprocessing as mp
from pathlib import Path

import numpy as np

STATELESS = "stateless"


def _job(args) -> list[dict]:
    """Records of one (variant, seed, range, rate) over the six shared tracks."""
    growth, seed, range_m, fp_rate, every = args
    import rld.incremental as inc
    from rld.evaluation import run_protocol
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    if growth is not None:
        inc.KEPT_GROWTH_S = growth
    folder = find_dataset_dir()
    tracks = [load_dataset_track(folder, k) for k in DATASET_TRACKS]
    recs = run_protocol(tracks, "rld", range_m=range_m, fp_rate=fp_rate, every=every,
                        seed=seed, stateful=growth is not None)
    label = STATELESS if growth is None else f"kept {growth:g} s"
    return [dict(r.to_dict(), method=label) for r in recs]


def run(growths=(0.05,), seeds=(1, 2), ranges=(30.0, 50.0), fp_rates=(0.0, 0.3, 0.5),
        every: int = 2, processes: int = 2) -> list[dict]:
    """Records (dicts) of the stateless chain and of a kept chain per growth budget (s)."""
    jobs = [(g, s, r, f, every) for g in (None, *growths)
            for s, r, f in itertools.product(seeds, ranges, fp_rates)]
    with mp.Pool(processes) as pool:
        parts = pool.map(_job, jobs, chunksize=1)
    return [r for part in parts for r in part]


def table(records: list[dict]) -> str:
    from benchmarks.bench_color_weights import paired_interval

    lines = ["| variant | poses | > 1 m % (vs stateless) | > 0.5 m % (vs stateless) | "
             "pred / true length (m) | latency median / p95 / max (ms) | per cell (R, FP): "
             "> 1 m / > 0.5 m %, length m |",
             "|---|---|---|---|---|---|---|"]
    by: dict[str, list[dict]] = {}
    for r in records:
        by.setdefault(r["method"], []).append(r)
    base = by.get(STATELESS)
    for name, recs in by.items():
        dev = np.array([r["deviation_m"] for r in recs])
        rates = []
        for d in (1.0, 0.5):
            txt = f"{100 * np.mean(dev > d):.2f}"
            if base is not None and name != STATELESS:
                p, lo, hi = paired_interval(base, recs, d)
                txt += f" ({p:+.2f} [{lo:+.2f}, {hi:+.2f}])"
            rates.append(txt)
        lat = 1000.0 * np.array([r["latency_s"] for r in recs if not r["first_call"]])
        cells = []
        for key in sorted({(r["range_m"], r["fp_rate"]) for r in recs}):
            c = [r for r in recs if (r["range_m"], r["fp_rate"]) == key]
            cd = np.array([r["deviation_m"] for r in c])
            cells.append(f"{key[0]:g} m {key[1]:.0%}: {100 * np.mean(cd > 1):.2f} / "
                         f"{100 * np.mean(cd > 0.5):.2f}, "
                         f"{np.mean([r['pred_length_m'] for r in c]):.0f}")
        lines.append(
            f"| {name} | {len(recs)} | {rates[0]} | {rates[1]} | "
            f"{np.mean([r['pred_length_m'] for r in recs]):.1f} / "
            f"{np.mean([r['true_length_m'] for r in recs]):.1f} | "
            f"{np.median(lat):.0f} / {np.percentile(lat, 95):.0f} / {lat.max():.0f} | "
            f"{'; '.join(cells)} |")
    return "\n".join(lines)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--seeds", default="1,2", help="false-positive seeds, comma-separated")
    ap.add_argument("--growth", default="0.05", help="KEPT_GROWTH_S values (s), comma-separated")
    ap.add_argument("--fp-rates", default="0,0.3,0.5", help="false-positive rates")
    ap.add_argument("--every", type=int, default=2, help="every k-th pose (keep it below 5)")
    ap.add_argument("--processes", type=int, default=2, help="worker processes")
    ap.add_argument("--out", default="bench_kept_out", help="output folder")
    a = ap.parse_args()
    recs = run(growths=[float(g) for g in a.growth.split(",")],
               seeds=[int(s) for s in a.seeds.split(",")],
               fp_rates=[float(f) for f in a.fp_rates.split(",")], every=a.every,
               processes=a.processes)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "records.json").write_text(json.dumps(recs))
    (out / "tables.md").write_text(table(recs) + "\n")
    print(table(recs))


if __name__ == "__main__":
    main()

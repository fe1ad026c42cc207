"""Chained windows in one ``rld`` call (issue 40, item 1): the stateless RLD with
``LaneParams.max_windows`` = 1 (the car's window alone) against more, on one set of DESIGN.md
("Choosing and reporting"): the shared tracks with the set's false-positive seeds and the first
``--generated`` tracks of the set's generated tracks, one ``LaneSolver`` per lap.

    nice -n 10 python -m benchmarks.bench_chain --set choosing --every 8 --windows 1,30

writes ``records.json`` (every pose) and ``tables.md``: per variant and false-positive rate,
geometric critical > 1 m / > 0.5 m (%), mean predicted / true length (m), too-short %, and
the median / p95 / max latency of steady calls (ms).
"""

from __future__ import annotations

import argparse
import json
import math
from pathlib import Path

import numpy as np

from benchmarks.bench_color import SETS, add_set_arguments, tracks


def run(set_name: str = "choosing", windows=(1, 30), ranges=(50.0,), fp_rates=(0.0, 0.3),
        every: int = 8, generated: int = 8, processes: int | None = None) -> list[dict]:
    """Records (dicts) of ``rld`` (its default budget) with each ``max_windows`` in
    ``windows``, labelled ``rld w=<n>``."""
    from rld.report import MethodSpec, evaluate
    from rld.types import LaneParams

    chosen = tracks(set_name, generated)
    out: list[dict] = []
    for w in windows:
        recs = evaluate(chosen, [MethodSpec("rld")], ranges=ranges, fp_rates=fp_rates, every=every,
                        seed=SETS[set_name], processes=processes,
                        params=LaneParams(max_windows=int(w)))
        for r in recs:
            d = r.to_dict()
            d["method"] = f"rld w={w}"
            out.append(d)
    return out


def table(records: list[dict]) -> str:
    """Markdown: one row per (variant, range, rate), every track and seed pooled."""
    lines = ["| variant | R (m) | FP | poses | geo critical > 1 m % | > 0.5 m % | "
             "pred / true length (m) | too short % | latency median / p95 / max (ms) |",
             "|---|---|---|---|---|---|---|---|---|"]
    keys = list(dict.fromkeys((r["method"], r["range_m"], r["fp_rate"]) for r in records))
    for m, rm, fp in keys:
        rows = [r for r in records if (r["method"], r["range_m"], r["fp_rate"]) == (m, rm, fp)]
        dev = np.array([r["deviation_m"] for r in rows], dtype=float)
        lat = 1000.0 * np.array([r["latency_s"] for r in rows if not r["first_call"]]
                                or [math.nan])
        lines.append(
            f"| {m} | {rm:g} | {fp:.0%} | {len(rows)} | {100 * np.mean(dev > 1.0):.2f} | "
            f"{100 * np.mean(dev > 0.5):.2f} | "
            f"{np.mean([r['pred_length_m'] for r in rows]):.1f} / "
            f"{np.mean([r['true_length_m'] for r in rows]):.1f} | "
            f"{100 * np.mean([r['too_short'] for r in rows]):.1f} | "
            f"{np.median(lat):.0f} / {np.percentile(lat, 95):.0f} / {lat.max():.0f} |")
    return "\n".join(lines) + "\n"


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_set_arguments(ap, "choosing", every=8, generated=8)
    ap.add_argument("--windows", default="1,30", help="comma-separated max_windows values")
    ap.add_argument("--ranges", default="50")
    ap.add_argument("--fp-rates", default="0,0.3")
    ap.add_argument("--out", default="chain_out")
    a = ap.parse_args(argv)
    records = run(a.set, [int(v) for v in a.windows.split(",")],
                  [float(v) for v in a.ranges.split(",")],
                  [float(v) for v in a.fp_rates.split(",")], a.every, a.generated,
                  a.processes)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "records.json").write_text(json.dumps(records))
    text = table(records)
    (out / "tables.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()

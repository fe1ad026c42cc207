"""Two ``rld eval`` runs compared pose by pose (DESIGN.md, "Choosing and reporting"): for one
method, the geometric critical rates at 1 m and 0.5 m of each run, the poses one run fixed and
broke, the paired difference (``other`` minus ``base``, % points) with its 95 % lap-bootstrap
interval (``bench_color_weights.paired_interval``: laps resampled within their cells), and the
mean predicted / true lane length; pooled, then per cell (range, rate).

    rld eval --methods rld --seed 1,2 --every 2 --out base
    rld eval --methods rld --seed 1,2 --every 2 --param window_behind_m=4 --out other
    rld bench paired base other --method rld

Only the poses both runs scored count (matched by track, pose, range, rate and seed). A change
is a gain when the interval excludes zero.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from benchmarks.bench_color_weights import _key, compare, paired_interval

DISTANCES_M = (1.0, 0.5)


def load_records(folder: str | Path, method: str) -> list[dict]:
    """The records of ``method`` in an ``rld eval`` output folder (its ``poses.jsonl``), the
    deviation of a pose with no lane as inf."""
    path = Path(folder) / "poses.jsonl"
    if not path.is_file():
        raise FileNotFoundError(f"{path} not found: give an `rld eval --out` folder")
    out = []
    with path.open() as fh:
        for line in fh:
            r = json.loads(line)
            if r["method"] != method:
                continue
            d = r.get("deviation_m")
            r["deviation_m"] = math.inf if d is None else float(d)
            out.append(r)
    if not out:
        raise ValueError(f"{path} holds no records of method {method!r}")
    return out


def matched(base: list[dict], other: list[dict]) -> tuple[list[dict], list[dict]]:
    """The records of the poses both runs scored, in ``base``'s order."""
    ko = {_key(r): r for r in other}
    b = [r for r in base if _key(r) in ko]
    return b, [ko[_key(r)] for r in b]


def _rate(recs: list[dict], d: float) -> float:
    return 100.0 * float(np.mean([r["deviation_m"] > d for r in recs])) if recs else math.nan


def _lengths(recs: list[dict]) -> tuple[float, float]:
    return (float(np.mean([r["pred_length_m"] for r in recs])),
            float(np.mean([r["true_length_m"] for r in recs])))


def _row(name: str, base: list[dict], other: list[dict]) -> str:
    cells = [name, str(len(base))]
    for d in DISTANCES_M:
        broke, fixed = compare(base, other, d)
        point, lo, hi = paired_interval(base, other, d)
        cells.append(f"{_rate(base, d):.2f} -> {_rate(other, d):.2f} ({point:+.2f} "
                     f"[{lo:+.2f}, {hi:+.2f}]; {fixed} fixed, {broke} broken)")
    (pb, t), (po, _) = _lengths(base), _lengths(other)
    cells.append(f"{pb:.1f} -> {po:.1f} / {t:.1f}")
    return "| " + " | ".join(cells) + " |"


def table(base: list[dict], other: list[dict]) -> str:
    """The comparison as a Markdown table: all matched poses, then each (range, rate) cell."""
    base, other = matched(base, other)
    if not base:
        raise ValueError("the two runs share no pose")
    lines = ["| poses | n | geometric critical > 1 m %: base -> other (difference [95 %], "
             "fixed, broken) | > 0.5 m % | length base -> other / true (m) |",
             "|---|---|---|---|---|",
             _row("all", base, other)]
    for cell in sorted({(r["range_m"], r["fp_rate"]) for r in base}):
        idx = [i for i, r in enumerate(base) if (r["range_m"], r["fp_rate"]) == cell]
        lines.append(_row(f"{cell[0]:g} m {cell[1]:.0%}", [base[i] for i in idx],
                          [other[i] for i in idx]))
    return "\n".join(lines)

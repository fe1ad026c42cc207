"""Choosing the colour weights (issue 41): geometric critical rates of one method (``clc`` by
default) on one set of DESIGN.md ("Choosing and reporting") for each setting of
(``nvd_color_weight``, ``rank_color_weight``, ``w_color``) at each colour accuracy, beside the
colourless run, with each setting's paired change against colourless (the same poses).
``w_color`` is RLD's weight, and CLC's dive judge's: a setting with ``w_color > 0`` runs CLC
with ``Refinement(judge_color=True)`` as the model's default (the workers are forked after it
is set), one with 0 with it off.

    python -m benchmarks.bench_color_weights --set choosing --every 32 --generated 4 \\
        --accuracies 0.95,0.8 --weights 0.5:1:2,0:0:2,0.25:0:0 --out colour_weights

A setting is ``nvd:rank:w_color`` or ``nvd:rank:w_color:color_unknown``; ``--windows 1`` runs
every setting (and colourless) with ``max_windows=1``. Writes ``<out>/<setting>_A<acc>.json``
(every pose; skipped when present, so a run can be resumed or extended) and prints, per setting
and accuracy, the pooled rates > 1 m / > 0.5 m (%), the mean lane length (% of the true), and
the poses where the setting is critical at 0.5 m and colourless is not, and the reverse.
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
from pathlib import Path

import numpy as np

from benchmarks import bench_color as bc


def setting_name(nvd: float, rank: float, judge: float, unknown: float | None = None) -> str:
    base = f"n{nvd:g}_r{rank:g}_j{judge:g}"
    return base if unknown is None else f"{base}_u{unknown:g}"


def parse_setting(text: str) -> tuple[float, float, float, float | None]:
    """``"0.25:0.5:2"`` -> (0.25, 0.5, 2.0, None): nvd_color_weight, rank_color_weight,
    w_color, and ``color_unknown`` when a fourth value is given (None: the default)."""
    parts = [float(v) for v in text.split(":")]
    if len(parts) not in (3, 4) or any(v < 0 or not math.isfinite(v) for v in parts):
        raise ValueError(f"a setting is nvd:rank:w_color[:color_unknown], weights >= 0; "
                         f"got {text!r}")
    return parts[0], parts[1], parts[2], (parts[3] if len(parts) == 4 else None)


def _key(r: dict) -> tuple:
    return (r["track"], r["pose"], r["range_m"], r["fp_rate"], r["seed"])


def compare(base: list[dict], other: list[dict], d: float = 0.5) -> tuple[int, int]:
    """(poses critical at ``d`` in ``other`` but not in ``base``, the reverse), paired by
    (track, pose, range, rate, seed)."""
    b = {_key(r): r["deviation_m"] > d for r in base}
    worse = better = 0
    for r in other:
        k = _key(r)
        if k not in b:
            continue
        o = r["deviation_m"] > d
        worse += int(o and not b[k])
        better += int(b[k] and not o)
    return worse, better


def paired_interval(base: list[dict], other: list[dict], d: float = 0.5,
                    seed: int = 0) -> tuple[float, float, float]:
    """(point, low, high) of the paired difference of the geometric critical % at ``d``
    (``other`` minus ``base``, % points) with the 95 % lap-bootstrap interval of
    ``benchmarks.bench_ablation.ratio_interval``: a lap (track, range, rate, seed) is the unit,
    resampled within its cell (shared or generated track, range, rate)."""
    from benchmarks.bench_ablation import ratio_interval

    b = {_key(r): r["deviation_m"] > d for r in base}
    laps: dict[tuple, list[float]] = {}
    for r in other:
        k = _key(r)
        if k in b:
            lap = (r["track"], r["range_m"], r["fp_rate"], r["seed"])
            laps.setdefault(lap, []).append(100.0 * ((r["deviation_m"] > d) - b[k]))
    keys = sorted(laps)
    num = np.array([sum(laps[k]) for k in keys])
    den = np.array([len(laps[k]) for k in keys], dtype=float)
    strata = [(str(k[0]).startswith("generated"), k[1], k[2]) for k in keys]
    return ratio_interval(num, den, strata, seed=seed)


def summary_row(name: str, acc, recs: list[dict], base: list[dict] | None) -> str:
    rate1, rate05, length = bc._rate(recs, 1.0), bc._rate(recs, 0.5), bc._length(recs)
    cells = [name, "colourless" if acc is None else f"{acc:g}", str(len(recs)),
             f"{rate1:.2f}", f"{rate05:.2f}", f"{length:.1f}"]
    if base is not None:
        worse, better = compare(base, recs)
        pt, lo, hi = paired_interval(base, recs)
        cells += [f"+{worse} / -{better}", f"{pt:+.2f} [{lo:+.2f}, {hi:+.2f}]"]
    else:
        cells += ["-", "-"]
    return "| " + " | ".join(cells) + " |"


def main(argv=None) -> None:
    from rld.types import LaneParams

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    bc.add_set_arguments(ap, "choosing", every=32, generated=4)
    ap.add_argument("--method", default="clc")
    ap.add_argument("--accuracies", default="0.95,0.8")
    ap.add_argument("--weights", required=True,
                    help="comma-separated settings nvd:rank:w_color")
    ap.add_argument("--out", default="colour_weights")
    ap.add_argument("--windows", type=int, default=None,
                    help="LaneParams.max_windows for every run, colourless too (rld's chain; "
                         "1: one window, cheaper to choose on)")
    a = ap.parse_args(argv)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    settings = [parse_setting(t) for t in a.weights.split(",") if t.strip()]
    accs = [float(v) for v in a.accuracies.split(",") if v.strip()]

    def load_or_run(path: Path, acc, params) -> list[dict]:
        from clc.refine import Refinement
        from clc.solver import ClcModel

        if path.exists():
            return json.loads(path.read_text())
        # The judge's colour is a Refinement field: the model's default refinement is swapped
        # for this run (the workers fork after it is set), then restored.
        saved = ClcModel.__init__.__defaults__
        ClcModel.__init__.__defaults__ = (*saved[:-1], Refinement(
            judge_color=params is not None and params.w_color > 0))
        try:
            recs = bc.run(a.set, [a.method], [acc], every=a.every, generated=a.generated,
                          processes=a.processes, params=params)
        finally:
            ClcModel.__init__.__defaults__ = saved
        path.write_text(json.dumps(recs))
        return recs

    default = LaneParams() if a.windows is None else LaneParams(max_windows=a.windows)
    base = load_or_run(out / "colourless.json", None, None if a.windows is None else default)
    lines = ["| setting (nvd, rank, w_color[, unknown]) | A | poses | > 1 m % | > 0.5 m % | "
             "length % | "
             "0.5 m vs colourless: worse / better poses | difference at 0.5 m, % points "
             "[95 % lap-bootstrap interval] |", "|---|---|---|---|---|---|---|---|",
             summary_row("colourless", None, base, None)]
    print(lines[-1], flush=True)
    for acc in accs:
        for nvd, rank, judge, unknown in settings:
            params = dataclasses.replace(default, nvd_color_weight=nvd, rank_color_weight=rank,
                                         w_color=judge)
            if unknown is not None:
                params = dataclasses.replace(params, color_unknown=unknown)
            name = setting_name(nvd, rank, judge, unknown)
            recs = load_or_run(out / f"{name}_A{acc:g}.json", acc, params)
            lines.append(summary_row(name, acc, recs, base))
            print(lines[-1], flush=True)
    text = "\n".join(lines) + "\n"
    (out / "summary.md").write_text(text)
    print(text)


if __name__ == "__main__":
    np.seterr(all="ignore")
    main()

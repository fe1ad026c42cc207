"""Colour as evidence (issue 41, item 4): every method's geometric critical rates with simulated
colour perception (``rld.simulation``: each labelled cone reports unknown with probability U,
else its true class with probability A) beside the colourless run, on one set of DESIGN.md
("Choosing and reporting"): the shared tracks with the set's false-positive seeds and the
set's generated tracks.

    python -m benchmarks.bench_color --set reporting --every 8 --out colour_out

writes ``records.json`` (every pose), ``tables.md`` (geometric critical at 1 m and 0.5 m and
the mean lane length per method, range and false-positive rate: colourless, A = 0.95, A = 0.8)
and ``color_accuracy.png`` (geometric critical at 0.5 m against A, per method, pooled over
ranges and rates, with the colourless figure as a dashed line).
"""

from __future__ import annotations

import argparse
import json
import math
from collections.abc import Sequence
from pathlib import Path

import numpy as np

#: (set name, false-positive seeds on the shared tracks) of DESIGN.md's choosing and reporting.
SETS = {"choosing": (0, 1, 2, 3, 4), "reporting": (5, 6, 7, 8, 9)}
#: The colour accuracies of the plot (0.5 is random labels); None is the colourless run.
ACCURACIES = (None, 0.5, 0.8, 0.95, 1.0)
#: The accuracies of the tables, beside the colourless one (issue 41).
TABLE_ACCURACIES = (0.95, 0.8)
UNKNOWN = 0.1


def tracks(set_name: str, generated: int) -> list:
    """The shared dataset tracks (when the dataset is there) and the first ``generated`` tracks
    of the generated set ``set_name``."""
    from rld.generator import generated_set
    from rld.tracks import find_dataset_dir, load_dataset_track

    out = []
    folder = find_dataset_dir()
    if folder is not None:
        numbers = sorted(int(p.stem.split("_")[-1]) for p in Path(folder).glob("cone_map_*.yaml"))
        out += [load_dataset_track(folder, k) for k in numbers]
    if generated:
        out += generated_set(set_name)[:generated]
    return out


def add_set_arguments(ap, set_name: str, every: int, generated: int) -> None:
    """The options every set benchmark shares: ``--set``, ``--every``, ``--generated`` and
    ``--processes``, with these defaults."""
    ap.add_argument("--set", default=set_name, choices=sorted(SETS))
    ap.add_argument("--every", type=int, default=every)
    ap.add_argument("--generated", type=int, default=generated,
                    help="the first N tracks of the set's generated tracks")
    ap.add_argument("--processes", type=int, default=None)


def run(set_name: str = "reporting", methods: Sequence[str] = ("rld", "clc"),
        accuracies: Sequence[float | None] = ACCURACIES, unknown: float = UNKNOWN,
        ranges=(30.0, 50.0), fp_rates=(0.0, 0.1, 0.3, 0.5), every: int = 4,
        generated: int = 8, processes: int | None = None, params=None) -> list[dict]:
    """Every (accuracy, method, track, range, rate, seed) of the set; records as dicts with
    ``accuracy`` (NaN: colourless) and ``base`` (the method's name) added. ``params``: every
    method's ``LaneParams`` (default: the defaults)."""
    from rld.report import evaluate, parse_method

    specs = [parse_method(m) for m in methods]
    chosen = tracks(set_name, generated)
    out: list[dict] = []
    for acc in accuracies:
        color = None if acc is None else (float(acc), float(unknown))
        recs = evaluate(chosen, specs, ranges=ranges, fp_rates=fp_rates, every=every,
                        seed=SETS[set_name], processes=processes, color=color,
                        params=params)
        for r in recs:
            d = r.to_dict()
            d["accuracy"] = math.nan if acc is None else float(acc)
            d["base"] = d["method"].split(" colour ")[0]
            out.append(d)
    return out


def _rate(rows: list[dict], d: float) -> float:
    dev = np.array([r["deviation_m"] for r in rows], dtype=float)
    return 100.0 * float(np.mean(dev > d)) if dev.size else math.nan


def _length(rows: list[dict]) -> float:
    pred = np.mean([r["pred_length_m"] for r in rows])
    true = np.mean([r["true_length_m"] for r in rows])
    return 100.0 * float(pred / true) if true > 0 else math.nan


def _select(records, base, acc, range_m=None, fp=None) -> list[dict]:
    same_acc = (lambda a: math.isnan(a)) if acc is None else (lambda a: a == acc)
    return [r for r in records if r["base"] == base and same_acc(r["accuracy"])
            and (range_m is None or r["range_m"] == range_m)
            and (fp is None or r["fp_rate"] == fp)]


def tables(records: list[dict], accuracies=TABLE_ACCURACIES) -> str:
    """Markdown: per method, range and rate, geometric critical > 1 m / > 0.5 m (%) and the
    mean lane length (% of the true), colourless then each of ``accuracies``."""
    cols = [None, *accuracies]
    names = ["colourless" if a is None else f"A = {a:g}" for a in cols]
    head = "| method | R (m) | FP | poses | " + " | ".join(
        f"{n}: > 1 m / > 0.5 m %, length %" for n in names) + " |"
    lines = [head, "|" + "---|" * (4 + len(cols))]
    bases = list(dict.fromkeys(r["base"] for r in records))
    ranges = sorted({r["range_m"] for r in records})
    fps = sorted({r["fp_rate"] for r in records})
    for b in bases:
        for rm in ranges:
            for fp in fps:
                cells, poses = [], 0
                for a in cols:
                    rows = _select(records, b, a, rm, fp)
                    poses = poses or len(rows)
                    cells.append("-" if not rows else
                                 f"{_rate(rows, 1.0):.2f} / {_rate(rows, 0.5):.2f}, "
                                 f"{_length(rows):.0f}")
                lines.append(f"| {b} | {rm:g} | {fp:.0%} | {poses} | " + " | ".join(cells) + " |")
    return "\n".join(lines) + "\n"


def plot(records: list[dict], path: str | Path) -> Path:
    """Geometric critical at 0.5 m (%) against colour accuracy, one line per method and
    false-positive rate (pooled over ranges); the colourless rate dashed."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    bases = list(dict.fromkeys(r["base"] for r in records))
    fps = sorted({r["fp_rate"] for r in records})
    accs = sorted({r["accuracy"] for r in records if not math.isnan(r["accuracy"])})
    fig, axes = plt.subplots(1, len(bases), figsize=(4.5 * len(bases), 3.6), squeeze=False,
                             sharey=True)
    for ax, b in zip(axes[0], bases, strict=True):
        for k, fp in enumerate(fps):
            color = f"C{k}"
            ys = [_rate(_select(records, b, a, fp=fp), 0.5) for a in accs]
            ax.plot(accs, ys, "o-", color=color, label=f"FP {fp:.0%}")
            base = _rate(_select(records, b, None, fp=fp), 0.5)
            if not math.isnan(base):
                ax.axhline(base, color=color, ls="--", lw=1)
        ax.set_title(f"{b} (dashed: colourless)")
        ax.set_xlabel("colour accuracy A (U = 0.1)")
        ax.grid(alpha=0.3)
    axes[0][0].set_ylabel("geometric critical > 0.5 m (%)")
    axes[0][-1].legend(fontsize=8)
    fig.tight_layout()
    path = Path(path)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_set_arguments(ap, "reporting", every=4, generated=8)
    ap.add_argument("--methods", default="rld,clc")
    ap.add_argument("--accuracies", default="none,0.5,0.8,0.95,1",
                    help="comma-separated A values; 'none' is the colourless run")
    ap.add_argument("--out", default="colour_out")
    a = ap.parse_args(argv)
    accs = [None if v.strip() == "none" else float(v) for v in a.accuracies.split(",")]
    records = run(a.set, a.methods.split(","), accs, every=a.every, generated=a.generated,
                  processes=a.processes)
    out = Path(a.out)
    out.mkdir(parents=True, exist_ok=True)
    (out / "records.json").write_text(json.dumps(records))
    text = tables(records)
    (out / "tables.md").write_text(text)
    print(text)
    print(f"wrote {plot(records, out / 'color_accuracy.png')}")


if __name__ == "__main__":
    main()

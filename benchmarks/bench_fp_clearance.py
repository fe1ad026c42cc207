"""How much of the failures come from false positives near the true boundaries
(``rld bench fp-clearance``).

The same experiments as the accuracy targets of issues 3 and 4, with one change: the false
positives are drawn only at least ``c`` metres from both true boundary lines
(``fp_clearance_m``; ``Track.boundary_distance``), the same number of them. ``c = 0`` is the
experiment itself. Sweeping ``c`` says where the failures that are left come from: when a
target is met from some ``c`` on, what stands between the method and the target is false
positives nearer than ``c`` to a true line. The protocol's tolerant rule forgives a false
positive within ``TOLERANT_DISTANCE_M`` (0.5 m) of a true line; the band between that and
``c`` is what a method must tell from the boundary by geometry alone.

- **CLC** (issue 4): the evaluation protocol on the shared dataset tracks
  (``run_protocol``, a fresh solver per pose, every pose), tolerant and strict critical poses
  per (range, rate) cell. ``fp_near_pct`` is the share of the lap's false positives that lie
  nearer than ``c`` to a true line when drawn as the protocol draws them (``c = 0``): the
  false positives that the clearance moves elsewhere.
- **RLD** (issue 3): the paper's experiment (``bench_rld_paper.run``, CP-SAT, n = 12), the
  inaccurate % (strict and tolerant) per false-positive ratio, the topologies pooled.

An analysis, not a target: the protocol and the paper's experiment keep their false positives
where they fall.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rld.metrics import CRITICAL

CELLS = ((30.0, 0.1), (30.0, 0.3), (50.0, 0.3))


def _clc_job(args) -> dict:
    from rld.evaluation import run_protocol
    from rld.tracks import find_dataset_dir, load_dataset_track

    tid, seed, range_m, fp_rate, clearance, every = args
    track = load_dataset_track(find_dataset_dir(), tid)
    recs = run_protocol([track], method="clc", range_m=range_m, fp_rate=fp_rate, seed=seed,
                        every=every, fp_clearance_m=clearance)
    return {"key": (clearance, range_m, fp_rate), "poses": len(recs),
            "tolerant": sum(r.category_tolerant in CRITICAL for r in recs),
            "strict": sum(r.category in CRITICAL for r in recs),
            "iou_sum": float(sum(r.iou for r in recs))}


def fp_line_distances(range_m: float, fp_rate: float, seeds: Sequence[int],
                      tracks: Sequence[int] | None = None) -> np.ndarray:
    """The distance from each of the protocol's false positives (drawn with no clearance) to
    the nearer true boundary line, metres, over the shared tracks and ``seeds``."""
    from rld.simulation import simulate_lap
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    folder = find_dataset_dir()
    out = [np.zeros(0)]
    for tid in tracks or DATASET_TRACKS:
        track = load_dataset_track(folder, tid)
        for seed in seeds:
            fp = simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed).false_positives
            out.append(track.boundary_distance(fp))
    return np.concatenate(out)


def run_clc(clearances: Sequence[float], seeds: Sequence[int] = (0, 1, 2, 3, 4),
            cells: Sequence[tuple[float, float]] = CELLS, every: int = 1, processes: int = 2,
            tracks: Sequence[int] | None = None, progress: bool = True) -> list[dict]:
    """One row per (clearance, range, rate): poses, tolerant and strict critical poses, mean
    IoU (%), and ``fp_near_pct`` (module docstring). Needs the dataset."""
    from multiprocessing import get_context

    from tqdm import tqdm

    from rld.tracks import DATASET_TRACKS, find_dataset_dir

    if find_dataset_dir() is None:
        raise FileNotFoundError("racetrack dataset not found (../shared/data/...)")
    tracks = list(tracks or DATASET_TRACKS)
    jobs = [(t, s, r, fp, float(c), every) for c in clearances for r, fp in cells
            for s in seeds for t in tracks]
    agg: dict[tuple, dict] = {}
    with get_context("spawn").Pool(max(1, int(processes))) as pool:
        for part in tqdm(pool.imap_unordered(_clc_job, jobs), total=len(jobs),
                         desc="fp clearance (clc)", unit="lap", disable=not progress):
            a = agg.setdefault(part["key"], {"poses": 0, "tolerant": 0, "strict": 0,
                                             "iou_sum": 0.0})
            for k in a:
                a[k] += part[k]
    dist = {(r, fp): fp_line_distances(r, fp, seeds, tracks) for r, fp in cells}
    rows = []
    for (c, r, fp), a in sorted(agg.items()):
        d = dist[(r, fp)]
        rows.append({"clearance_m": c, "range_m": r, "fp_rate": fp, "poses": a["poses"],
                     "critical_tolerant": a["tolerant"], "critical_strict": a["strict"],
                     "mean_iou_pct": 100.0 * a["iou_sum"] / a["poses"],
                     "fp_near_pct": 100.0 * float(np.mean(d < c)) if d.size else float("nan")})
    return rows


def run_rld(clearances: Sequence[float], seeds: Sequence[int] = (0, 1, 2, 3, 4),
            poses: int = 60, progress: bool = True) -> list[dict]:
    """One row per (clearance, ratio) of the paper's experiment, the topologies pooled:
    solves, inaccurate % (strict and tolerant)."""
    from benchmarks import bench_rld_paper

    rows = []
    for c in clearances:
        cells = bench_rld_paper.run(seeds=seeds, poses=poses, progress=progress,
                                    fp_clearance_m=float(c))
        for ratio in bench_rld_paper.RATIOS:
            sel = [r for r in cells if r["ratio"] == ratio]
            n = sum(r["solves"] for r in sel)

            def pooled(key, sel=sel, n=n):
                return sum(r[key] * r["solves"] for r in sel) / n

            rows.append({"clearance_m": float(c), "ratio": ratio, "solves": n,
                         "inaccurate_pct": pooled("inaccurate_pct"),
                         "inaccurate_tolerant_pct": pooled("inaccurate_tolerant_pct")})
    return rows


def to_markdown(clc_rows: Sequence[dict] = (), rld_rows: Sequence[dict] = ()) -> str:
    """The two tables of ``run_clc`` and ``run_rld`` (either may be empty)."""
    parts = []
    if clc_rows:
        lines = ["CLC, the evaluation protocol (a fresh solver per pose), critical poses:",
                 "",
                 "| clearance (m) | R | FP | poses | FPs nearer at 0 (%) | tolerant critical "
                 "| % | strict critical | % | mean IoU (%) |",
                 "|---|---|---|---|---|---|---|---|---|---|"]
        for r in clc_rows:
            n = r["poses"]
            lines.append(f"| {r['clearance_m']:g} | {r['range_m']:g} m | {r['fp_rate']:.0%} | "
                         f"{n} | {r['fp_near_pct']:.1f} | {r['critical_tolerant']} | "
                         f"{100 * r['critical_tolerant'] / n:.2f} | {r['critical_strict']} | "
                         f"{100 * r['critical_strict'] / n:.2f} | {r['mean_iou_pct']:.2f} |")
        parts.append("\n".join(lines))
    if rld_rows:
        lines = ["RLD, the paper's experiment (CP-SAT, n = 12), the topologies pooled:", "",
                 "| clearance (m) | false : real | solves | inaccurate (%) | tolerant (%) |",
                 "|---|---|---|---|---|"]
        for r in rld_rows:
            lines.append(f"| {r['clearance_m']:g} | {r['ratio']} | {r['solves']} | "
                         f"{r['inaccurate_pct']:.1f} | {r['inaccurate_tolerant_pct']:.1f} |")
        parts.append("\n".join(lines))
    return "\n\n".join(parts)


def plot(clc_rows: Sequence[dict], rld_rows: Sequence[dict], path: str) -> None:
    """Critical % (CLC, tolerant) and inaccurate % (RLD, tolerant) against the clearance, one
    line per cell, each panel with its issue's targets dashed; written to ``path``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    panels = [p for p in ((clc_rows, "CLC, the protocol (tolerant critical %)"),
                          (rld_rows, "RLD, the paper's experiment (tolerant inaccurate %)"))
              if p[0]]
    fig, axes = plt.subplots(1, len(panels), figsize=(5.5 * len(panels), 4), squeeze=False)
    for ax, (rows, title) in zip(axes[0], panels, strict=True):
        if rows is clc_rows:
            keys = sorted({(r["range_m"], r["fp_rate"]) for r in rows})
            for rng, fp in keys:
                sel = sorted((r for r in rows if (r["range_m"], r["fp_rate"]) == (rng, fp)),
                             key=lambda r: r["clearance_m"])
                ax.plot([r["clearance_m"] for r in sel],
                        [100 * r["critical_tolerant"] / r["poses"] for r in sel], "o-",
                        label=f"R = {rng:g} m, {fp:.0%}")
            ax.axhline(0.6, ls="--", c="k", lw=1, label="target 0.6 %")
        else:
            for ratio, target in (("1:5", 2.0), ("1:1", 5.0)):
                sel = sorted((r for r in rows if r["ratio"] == ratio),
                             key=lambda r: r["clearance_m"])
                line, = ax.plot([r["clearance_m"] for r in sel],
                                [r["inaccurate_tolerant_pct"] for r in sel], "o-",
                                label=f"{ratio}")
                ax.axhline(target, ls="--", c=line.get_color(), lw=1,
                           label=f"target {target:g} % ({ratio})")
        ax.set_xlabel("false positives' least distance from the true lines (m)")
        ax.set_title(title, fontsize=10)
        ax.set_ylim(bottom=0)
        ax.grid(alpha=0.3)
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def parse_clearances(text: str) -> list[float]:
    """``"0,0.5,1"`` -> [0.0, 0.5, 1.0]; each finite and >= 0."""
    out = [float(v) for v in text.split(",") if v.strip()]
    if not out or not all(np.isfinite(v) and v >= 0 for v in out):
        raise ValueError(f"clearances must be numbers >= 0, got {text!r}")
    return out

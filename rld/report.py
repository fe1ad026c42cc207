"""``rld eval``: the evaluation protocol (DESIGN.md) for any methods, ranges and false-positive
rates, across processes, with the records, tables and plots a reader wants.

A *method spec* is ``name`` or ``name:option``: the option is the backend for ``rld`` and
``rld-sided`` (``rld:highs``) and the ranker for ``clc`` (``clc:longest``). ``evaluate`` runs
every (spec, track, range, rate) as one job (one ``LaneSolver`` per lap, driven pose by pose as
on the car) and returns the per-pose records; ``write_outputs`` writes

- ``poses.jsonl``: one JSON object per scored pose,
- ``summary.json``: the protocol's figures per (method, range, rate),
- ``results.md``: the headline table (the geometric rule beside the lane's length), then
  Markdown tables shaped like the CLC paper's Table I (the index rule),
- ``categories.png``, ``iou.png``, ``latency_cdf.png``: the pictures.
"""

from __future__ import annotations

import json
import math
import os
import platform
from collections.abc import Iterable, Sequence
from concurrent.futures import ProcessPoolExecutor, as_completed
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rld.evaluation import PoseRecord, geometric_key, lap_interval, run_protocol, summarize
from rld.metrics import CATEGORIES, GEOMETRIC_DISTANCES_M
from rld.tracks import Track
from rld.types import LaneParams

__all__ = ["MethodSpec", "parse_method", "evaluate", "summaries", "headline_markdown",
           "table_markdown", "stability_markdown", "seeds_markdown",
           "write_outputs", "plot_summaries"]


@dataclass(frozen=True)
class MethodSpec:
    """A method and its option: ``backend`` (RLD) or ``ranker`` (CLC)."""

    method: str
    option: str | None = None

    @property
    def label(self) -> str:
        return self.method if self.option is None else f"{self.method}:{self.option}"

    def kwargs(self) -> dict:
        if self.option is None:
            return {}
        if self.method == "clc":
            return {"ranker": self.option}
        return {"backend": self.option}


def parse_method(text: str) -> MethodSpec:
    """``"rld"``, ``"rld:highs"``, ``"clc:longest"``, ... -> ``MethodSpec``; ValueError for a
    method or option that does not exist."""
    from rld.api import METHODS

    name, _, option = text.strip().partition(":")
    if name not in METHODS:
        raise ValueError(f"unknown method {name!r}; available: {', '.join(sorted(METHODS))}")
    spec = MethodSpec(name, option or None)
    if spec.option is not None:
        kind = METHODS[name]
        if name == "clc":
            from clc.ranker import RANKERS

            if spec.option not in RANKERS:
                raise ValueError(f"unknown ranker {spec.option!r}; use one of {RANKERS}")
        elif spec.option not in kind.backends:
            raise ValueError(f"method {name!r} has no option {spec.option!r}; backends: "
                             f"{', '.join(kind.backends) or 'none'}")
    return spec


def color_label(label: str, color: tuple[float, float] | None) -> str:
    """A method's label in the tables, with the simulated colour perception (A, U) if any."""
    return label if color is None else f"{label} colour A={color[0]:g} U={color[1]:g}"


def _job(spec: MethodSpec, track: Track, range_m: float, fp_rate: float, every: int, seed: int,
         plot_failures: str | None, params: LaneParams | None = None,
         color: tuple[float, float] | None = None) -> list[dict]:
    acc, unk = (None, 0.0) if color is None else color
    recs = run_protocol([track], method=spec.method, range_m=range_m, fp_rate=fp_rate,
                        every=every, seed=seed, stateful=True,
                        label=color_label(spec.label, color), plot_failures=plot_failures,
                        params=params, color_accuracy=acc, color_unknown=unk,
                        **spec.kwargs())
    return [r.to_dict() for r in recs]


def evaluate(tracks: Sequence[Track], specs: Sequence[MethodSpec], ranges=(30.0, 50.0),
             fp_rates=(0.0, 0.1, 0.3, 0.5), every: int = 1, seed: int | Sequence[int] = 0,
             processes: int | None = None, progress: bool = True,
             plot_failures: str | None = None,
             params: LaneParams | None = None,
             color: tuple[float, float] | None = None) -> list[PoseRecord]:
    """Every (spec, track, range, rate, seed) of the protocol; ``seed``: the false positives'
    seed, or several (each a lap of its own; ``summaries`` pools them and keeps each seed's
    critical rates). ``processes`` workers (default: the CPU count). ``params``: every
    method's ``LaneParams`` (default: the defaults). ``color``: (accuracy A, unknown share U)
    of the simulated colour perception (``rld.simulation``; default none), its classes given
    to every method, the labels suffixed (``color_label``). Records come back in a
    fixed order whatever the scheduling. A method that
    keeps its lane from call to call (``rld-incremental``) says how small ``every`` must be
    (its ``max_every``: 5, poses lie 1 m apart and a larger stride is a pose jump, which
    restarts it at every call)."""
    from tqdm import tqdm

    from rld.api import METHODS

    for s in specs:
        limit = getattr(METHODS[s.method], "max_every", None)
        if limit is not None and every >= limit():
            raise ValueError(f"{s.method} is driven pose by pose: use every < {limit():g} "
                             f"(got {every}); a larger stride restarts it at every call")

    seeds = [int(seed)] if isinstance(seed, int | np.integer) else [int(v) for v in seed]
    if not seeds or len(set(seeds)) != len(seeds):
        raise ValueError(f"seeds must be distinct and at least one, got {seeds}")
    jobs = [(s, t, r, fp, sd) for s in specs for r in ranges for fp in fp_rates for sd in seeds
            for t in tracks]
    n = processes or os.cpu_count() or 1
    out: dict[int, list[dict]] = {}
    bar = tqdm(total=len(jobs), desc="rld eval", unit="lap", disable=not progress)
    if n <= 1:
        for i, (s, t, r, fp, sd) in enumerate(jobs):
            out[i] = _job(s, t, r, fp, every, sd, plot_failures, params, color)
            bar.update(1)
    else:
        with ProcessPoolExecutor(max_workers=n) as pool:
            futures = {pool.submit(_job, s, t, r, fp, every, sd, plot_failures, params,
                                   color): i
                       for i, (s, t, r, fp, sd) in enumerate(jobs)}
            for fut in as_completed(futures):
                out[futures[fut]] = fut.result()
                bar.update(1)
    bar.close()
    return [PoseRecord(**d) for i in range(len(jobs)) for d in out[i]]


def summaries(records: Iterable[PoseRecord]) -> list[dict]:
    """``summarize`` per (method, range, rate), in first-seen order, over every seed's poses;
    ``seeds`` lists the seeds (sorted), and ``<key>_by_seed`` each seed's rate in that order
    (%) and ``<key>_interval`` the 95 % interval of the pooled rate, whole tracks and laps
    resampled (``lap_interval``), for the geometric keys and ``critical_tolerant``;
    ``critical_by_seed`` the strict index rule's."""
    groups: dict[tuple, list[PoseRecord]] = {}
    for r in records:
        groups.setdefault((r.method, r.range_m, r.fp_rate), []).append(r)
    rows = []
    for (m, rng, fp), recs in groups.items():
        seeds = sorted({r.seed for r in recs})
        pooled = summarize(recs)
        per = ([pooled] if len(seeds) == 1 else
               [summarize([r for r in recs if r.seed == sd]) for sd in seeds])
        row = {"method": m, "range_m": rng, "fp_rate": fp, **pooled,
               "seeds": seeds, "critical_by_seed": [p["critical"] for p in per],
               "critical_tolerant_by_seed": [p["critical_tolerant"] for p in per],
               "critical_tolerant_interval": list(lap_interval(recs))}
        for d in GEOMETRIC_DISTANCES_M:
            key = geometric_key(d)
            row[f"{key}_by_seed"] = [p[key] for p in per]
            row[f"{key}_interval"] = ([math.nan, math.nan] if math.isnan(pooled[key])
                                      else list(lap_interval(recs, geometric_m=d)))
        rows.append(row)
    return rows


def _pct(v) -> str:
    return "-" if v is None or (isinstance(v, float) and math.isnan(v)) else f"{v:.2f}"


def headline_markdown(rows: list[dict]) -> str:
    """The headline: geometric critical % at each ``GEOMETRIC_DISTANCES_M`` (DESIGN.md
    "Geometric critical"), beside the mean predicted / true length, the too-short share and
    IoU20, and the steady latency (first calls apart, as start-up)."""
    dists = " | ".join(f"geometric critical > {d:g} m %" for d in GEOMETRIC_DISTANCES_M)
    parts = [f"| method | R (m) | FP | poses | {dists} | pred / true length (m, %) | "
             "too short % | IoU20 % | median / p95 / max latency (ms) | start-up (ms) |",
             "|" + "---|" * (9 + len(GEOMETRIC_DISTANCES_M))]
    for r in rows:
        geo = " | ".join(_pct(r.get(geometric_key(d))) for d in GEOMETRIC_DISTANCES_M)
        start = r.get("startup_median_ms", math.nan)
        start = "-" if start is None or math.isnan(start) else f"{start:.0f}"
        ratio = r.get("length_ratio", math.nan)
        ratio = "-" if ratio is None or math.isnan(ratio) else f"{ratio:.0f}"
        parts.append(
            f"| {r['method']} | {r['range_m']:g} | {r['fp_rate']:.0%} | {r['poses']} | {geo} | "
            f"{r['pred_length_m']:.0f} / {r['true_length_m']:.0f} "
            f"({ratio}) | {_pct(r.get('short'))} | "
            f"{r['mean_iou20']:.1f} | {r['latency_median_ms']:.1f} / "
            f"{r['latency_p95_ms']:.1f} / {r['latency_max_ms']:.1f} | {start} |")
    return "\n".join(parts) + "\n"


def seeds_markdown(rows: list[dict]) -> str:
    """Each seed's geometric critical rates per method, range and false-positive rate, and the
    pooled rates with their 95 % intervals, tracks and laps resampled (``lap_interval``): one
    seed's false positives are a few persistent configurations, each seen from many poses in a
    row, so a single seed's rate moves by whole points. The index rule's tolerant rate last.
    Empty when every row has one seed."""
    if all(len(r.get("seeds", [])) < 2 for r in rows):
        return ""
    keys = [geometric_key(d) for d in GEOMETRIC_DISTANCES_M]
    names = [f"> {d:g} m" for d in GEOMETRIC_DISTANCES_M]
    parts = ["| method | R (m) | FP | seeds | "
             + " | ".join(f"geometric {n} % per seed" for n in names) + " | "
             + " | ".join(f"geometric {n} %, all seeds (95 % interval)" for n in names)
             + " | index rule, tolerant %, all seeds (95 % interval) |",
             "|" + "---|" * (5 + 2 * len(keys))]
    for r in rows:
        per = " | ".join(" / ".join(_pct(v) for v in r.get(f"{k}_by_seed", [])) for k in keys)
        pooled = " | ".join(
            f"{_pct(r.get(k))} ({_pct(r.get(f'{k}_interval', [math.nan] * 2)[0])} - "
            f"{_pct(r.get(f'{k}_interval', [math.nan] * 2)[1])})" for k in keys)
        lo, hi = r["critical_tolerant_interval"]
        parts.append(f"| {r['method']} | {r['range_m']:g} | {r['fp_rate']:.0%} | "
                     f"{', '.join(str(v) for v in r['seeds'])} | {per} | {pooled} | "
                     f"{r['critical_tolerant']:.2f} ({lo:.2f} - {hi:.2f}) |")
    return "\n".join(parts) + "\n"


def table_markdown(rows: list[dict]) -> str:
    """The index rule, paper-compatible: one table per (method, range), rows per false-positive
    rate, columns as the CLC paper's Table I plus the tolerant critical rate, IoU20, lengths
    and latency."""
    parts = []
    keys = []
    for row in rows:
        if (row["method"], row["range_m"]) not in keys:
            keys.append((row["method"], row["range_m"]))
    for method, rng in keys:
        parts.append(f"**{method}, R = {rng:g} m**\n")
        parts.append("| FP | poses | GT % | near-GT % | too short % | diverging >= 20 m % | "
                     "diverging < 20 m % | failed % | success % | critical % (tolerant) | "
                     "mean IoU % | IoU20 % | pred / true length (m) | median / p95 latency (ms) |")
        parts.append("|" + "---|" * 14)
        for r in rows:
            if (r["method"], r["range_m"]) != (method, rng):
                continue
            success = r["gt"] + r["near_gt"] + r["too_short"] + r["diverging_ge20"]
            parts.append(
                f"| {r['fp_rate']:.0%} | {r['poses']} | {r['gt']:.1f} | {r['near_gt']:.1f} | "
                f"{r['too_short']:.1f} | {r['diverging_ge20']:.1f} | {r['diverging_lt20']:.1f} "
                f"| {r['failed']:.1f} | {success:.1f} | {r['critical']:.1f} "
                f"({r['critical_tolerant']:.1f}) | {r['mean_iou']:.1f} | "
                f"{r['mean_iou20']:.1f} "
                f"| {r['pred_length_m']:.0f} / {r['true_length_m']:.0f} | "
                f"{r['latency_median_ms']:.1f} / {r['latency_p95_ms']:.1f} |")
        parts.append("")
    return "\n".join(parts)


def stability_markdown(rows: list[dict]) -> str:
    """The average stability ratio of Huang et al. (eq. 5) per method, range and false-positive
    rate at the radii of ``STABILITY_RADII_M``, of the raw lanes and of the tracked lanes
    (``rld.tracker``): the sideways movement of the lane where it crosses the circle, per metre
    driven (0 is perfectly stable)."""
    from rld.evaluation import STABILITY_RADII_M

    radii = [f"{r:g}" for r in STABILITY_RADII_M]
    head = " | ".join(f"raw {r} m" for r in radii) + " | " + " | ".join(
        f"tracked {r} m" for r in radii)
    parts = [f"| method | R (m) | FP | {head} |", "|" + "---|" * (3 + 2 * len(radii))]
    for r in rows:
        vals = [r.get(f"stability_{x}", math.nan) for x in radii] + [
            r.get(f"tracked_stability_{x}", math.nan) for x in radii]
        cells = " | ".join("-" if v is None or math.isnan(v) else f"{v:.3f}" for v in vals)
        parts.append(f"| {r['method']} | {r['range_m']:g} | {r['fp_rate']:.0%} | {cells} |")
    return "\n".join(parts) + "\n"


def plot_summaries(rows: list[dict], records: list[PoseRecord], folder: Path) -> list[Path]:
    """Categories per false-positive rate (stacked bars), IoU against the rate, latency CDF."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    folder = Path(folder)
    paths = []
    keys = list(dict.fromkeys((r["method"], r["range_m"]) for r in rows))
    colors = {"gt": "#1a9850", "near_gt": "#91cf60", "too_short": "#d9ef8b",
              "diverging_ge20": "#fee08b", "diverging_lt20": "#d73027", "failed": "#4d4d4d"}
    fig, axes = plt.subplots(1, len(keys), figsize=(4 * len(keys), 4), squeeze=False,
                             sharey=True)
    for ax, (m, rng) in zip(axes[0], keys, strict=True):
        sub = [r for r in rows if (r["method"], r["range_m"]) == (m, rng)]
        x = np.arange(len(sub))
        bottom = np.zeros(len(sub))
        for c in CATEGORIES:
            v = np.array([r[c] for r in sub])
            ax.bar(x, v, bottom=bottom, color=colors[c], label=c)
            bottom += v
        ax.set_xticks(x, [f"{r['fp_rate']:.0%}" for r in sub])
        ax.set_title(f"{m}, R = {rng:g} m")
        ax.set_xlabel("false positives")
    axes[0][0].set_ylabel("% of poses")
    axes[0][-1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.tight_layout()
    paths.append(folder / "categories.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(1, 2, figsize=(9, 4))
    for m, rng in keys:
        sub = [r for r in rows if (r["method"], r["range_m"]) == (m, rng)]
        fp = [100 * r["fp_rate"] for r in sub]
        ax[0].plot(fp, [r["mean_iou"] for r in sub], "o-", label=f"{m}, {rng:g} m")
        line = None
        for d, style in zip(GEOMETRIC_DISTANCES_M, ("o-", "s--"), strict=False):
            kw = {"color": line.get_color()} if line is not None else {}
            (ln,) = ax[1].plot(fp, [r.get(geometric_key(d), math.nan) for r in sub], style,
                               label=f"{m}, {rng:g} m, > {d:g} m", **kw)
            line = line or ln
    ax[0].set_ylabel("mean IoU %")
    ax[1].set_ylabel("geometric critical % (boundary off by more than d)")
    for a in ax:
        a.set_xlabel("false positives %")
        a.grid(alpha=0.3)
    ax[1].legend(fontsize=7)
    fig.tight_layout()
    paths.append(folder / "iou.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    fig, ax = plt.subplots(figsize=(5, 4))
    for m in dict.fromkeys(r.method for r in records):
        lat = np.sort([1000 * r.latency_s for r in records if r.method == m])
        ax.plot(lat, np.arange(1, lat.size + 1) / lat.size, label=m)
    ax.set_xscale("log")
    ax.set_xlabel("latency per call (ms)")
    ax.set_ylabel("fraction of calls")
    ax.grid(alpha=0.3)
    ax.legend()
    fig.tight_layout()
    paths.append(folder / "latency_cdf.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)

    # Stability against the radius (Huang et al. fig. 19), at the lowest false-positive rate.
    from rld.evaluation import STABILITY_RADII_M

    fig, ax = plt.subplots(figsize=(5, 4))
    for m, rng in keys:
        sub = sorted((r for r in rows if (r["method"], r["range_m"]) == (m, rng)),
                     key=lambda r: r["fp_rate"])
        if not sub or f"stability_{STABILITY_RADII_M[0]:g}" not in sub[0]:
            continue
        r0 = sub[0]
        raw = [r0[f"stability_{x:g}"] for x in STABILITY_RADII_M]
        trk = [r0[f"tracked_stability_{x:g}"] for x in STABILITY_RADII_M]
        line, = ax.plot(STABILITY_RADII_M, raw, "o-", label=f"{m}, {rng:g} m")
        ax.plot(STABILITY_RADII_M, trk, "o--", color=line.get_color(),
                label=f"{m}, {rng:g} m, tracked")
    ax.set_xlabel("radius r (m)")
    ax.set_ylabel("average stability ratio")
    ax.set_title("stability (Huang et al. eq. 5), lowest FP rate", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    paths.append(folder / "stability.png")
    fig.savefig(paths[-1], dpi=110)
    plt.close(fig)
    return paths


def _clean(v):
    if isinstance(v, float) and math.isnan(v):
        return None
    return v


def write_outputs(records: list[PoseRecord], folder: str | Path, header: str = "") -> dict:
    """Write the records, summaries, tables and plots into ``folder``; returns the paths."""
    folder = Path(folder)
    folder.mkdir(parents=True, exist_ok=True)
    with open(folder / "poses.jsonl", "w") as fh:
        for r in records:
            fh.write(json.dumps({k: _clean(v) for k, v in r.to_dict().items()}) + "\n")
    rows = summaries(records)
    (folder / "summary.json").write_text(
        json.dumps([{k: _clean(v) for k, v in r.items()} for r in rows], indent=1) + "\n")
    spread = seeds_markdown(rows)
    md = ((header + "\n\n" if header else "") + "**Headline: the geometric rule**\n\n"
          + headline_markdown(rows) + "\n**Index rule (paper-compatible)**\n\n"
          + table_markdown(rows)
          + ("\n**Seeds**\n\n" + spread if spread else "")
          + "\n**Stability** (Huang et al. eq. 5)\n\n" + stability_markdown(rows))
    (folder / "results.md").write_text(md)
    plots = plot_summaries(rows, records, folder)
    return {"poses": folder / "poses.jsonl", "summary": folder / "summary.json",
            "results": folder / "results.md", "plots": plots, "rows": rows}


def machine() -> str:
    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}"
            f", {platform.system()}")


#: The papers' own figures, quoted for comparison (their protocols differ from ours: the CLC
#: paper used nine tracks, its own C++ code and rules; RLD's figures are PEERS.md's measurement
#: of the published formulation under our protocol).
PAPER_FIGURES = """\
**CLC paper, Table I** (Ivanov & Markgraf 2024; 9 tracks, 1964 poses, R = 30 and 50 m pooled,
C++ on an i7-12700K, median < 5 ms, max 12 ms):

| FP | GT % | near-GT % | too short % | diverging >= 20 m % | diverging < 20 m % | mean IoU % |
|---|---|---|---|---|---|---|
| 0 % | 34.5 | 61.9 | 0.7 | 2.2 | 0.6 | 96.9 |
| 10 % | 24.9 | 70.9 | 0.5 | 2.9 | 0.8 | 96.0 |
| 30 % | 9.3 | 85.1 | 0.8 | 4.1 | 0.7 | 93.2 |
| 50 % | 2.1 | 70.9 | 2.6 | 19.3 | 5.0 | 79.5 |

**RLD as published** (Brandes et al. 2020, the BIP on the 12 or 20 cones nearest ahead, CP-SAT;
measured under our protocol in PEERS.md, R = 50 m, every 4th pose), critical % strict (tolerant,
by DESIGN.md's rule: before the tolerant rule forgave stand-ins, docs/protocol.md; compare on
the strict figures):

| n | 0 % | 10 % | 30 % | 50 % | lane length (m) |
|---|---|---|---|---|---|
| 12 | 5.0 (2.6) | 10.2 (5.8) | 20.7 (10.2) | 36.2 (22.2) | 9-11 |
| 20 | 5.0 (2.0) | 10.8 (5.0) | 26.5 (13.7) | 42.9 (25.1) | 15-18 |

The paper's own figure for RLD (fig. 7: 3.62 % inaccurate at 1:5 false positives) measures a
different thing (its quality checks on a 12-cone window), see docs/benchmarks.md.
"""


def results_page(rows: list[dict], header: str, images: Sequence[str] = ()) -> str:
    """docs/results.md: our Table I analogue per method and range, beside the papers' figures,
    and the given images (paths relative to the page). Regenerate with the command it names."""
    spread = seeds_markdown(rows)
    return "\n".join([
        "# Results on the shared tracks",
        "",
        "Generated by `rld eval` (do not edit by hand). The protocol and metrics are those of",
        "DESIGN.md (docs/protocol.md). Headline: geometric critical = a predicted boundary more",
        "than 1 m (or 0.5 m) off the true one within 20 m of the car, a side missing or starting",
        "beyond 20 m, or no lane; read it beside the lane's length. The index rule (critical =",
        "diverging from the true cone order below 20 m, or no lane) is the paper-compatible table.",
        "",
        header,
        "",
        "## Ours",
        "",
        *[f"![{Path(i).stem}]({i})" for i in images],
        "",
        "### Headline: the geometric rule",
        "",
        headline_markdown(rows),
        "### Index rule (paper-compatible, CLC Table I)",
        "",
        table_markdown(rows),
        *(["## Seeds", "",
           "The figures above pool every seed's poses. One seed's false positives are a few",
           "persistent configurations, each seen from many poses in a row, so a single seed's",
           "critical rate moves by whole points from seed to seed:", "",
           spread] if spread else []),
        "## Stability",
        "",
        "The average stability ratio of Huang et al. (2009, section 3.5, eq. 5) between",
        "consecutive poses (1 m apart), of each method's lanes and of the same lanes after the",
        "lane tracker of their section 2.3 (`rld.tracker`, confident control points only):",
        "",
        stability_markdown(rows),
        "## The papers' figures",
        "",
        PAPER_FIGURES,
    ])

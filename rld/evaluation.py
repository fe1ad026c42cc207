"""Run a method over the evaluation protocol and summarise the scores (DESIGN.md).

``run_protocol`` drives a method pose by pose along each track's lap (``rld.simulation``) and
scores every prediction (``rld.metrics``); ``summarize`` turns the records into the per-setting
figures of the protocol: geometric critical % at 1 m and 0.5 m (the headline), mean predicted
and true length and their ratio, too-short %, IoU20; % per category, critical % (strict and
tolerant), mean IoU; latency median / p95 / max of steady calls, start-up apart.
"""

from __future__ import annotations

import math
import time
from collections.abc import Iterable
from dataclasses import asdict, dataclass

import numpy as np

from rld.api import LaneSolver
from rld.metrics import CATEGORIES, CRITICAL, GEOMETRIC_DISTANCES_M, score_lane, stability_ratio
from rld.simulation import simulate_lap
from rld.tracks import Track
from rld.types import LaneParams

__all__ = ["PoseRecord", "run_protocol", "summarize", "geometric_key", "lap_interval",
           "STABILITY_RADII_M"]

#: The radii (m) at which the stability ratio of Huang et al. (eq. 5) is recorded.
STABILITY_RADII_M = (5.0, 10.0, 20.0)


@dataclass(frozen=True)
class PoseRecord:
    """One scored prediction."""

    track: str
    pose: int
    range_m: float
    fp_rate: float
    method: str
    status: str
    category: str
    category_tolerant: str
    iou: float
    iou20: float
    divergence_m: float
    pred_length_m: float
    true_length_m: float
    latency_s: float
    n_cones: int
    iterations: int = -1
    """Search iterations (CLC), -1 where the method has none."""
    complete: bool | None = None
    """The search was complete (CLC: every feasible pair enumerated); None where not a search."""
    stability_5: float = math.nan
    """Huang et al. eq. 5 between this lane's centreline and the previous pose's, radius 5 m;
    NaN when either has no lane or does not reach the circle. Likewise 10 and 20 m."""
    stability_10: float = math.nan
    stability_20: float = math.nan
    tracked_stability_5: float = math.nan
    """The same ratios for the tracked lane (``rld.tracker``, its confident control points)."""
    tracked_stability_10: float = math.nan
    tracked_stability_20: float = math.nan
    seed: int = 0
    """Seed of the lap's false positives (``simulate_lap``)."""
    deviation_m: float = math.nan
    """The geometric rule's deviation (``rld.metrics.geometric_deviation``, m; inf: no lane, or
    a side missing or starting beyond 20 m). NaN in records written before it."""
    too_short: bool = False
    """A lane found with a side under half its true length (``rld.metrics.too_short_sides``)."""
    first_call: bool = False
    """The solver's first call (lazy set-up, kernel compilation): start-up, not latency."""
    color_accuracy: float = math.nan
    """The simulated colour perception's accuracy A (``rld.simulation``); NaN without colour."""
    color_unknown: float = math.nan
    """Its share U of cones reported unknown; NaN without colour."""

    def to_dict(self) -> dict:
        return asdict(self)


def run_protocol(
    tracks: Iterable[Track],
    method: str = "rld",
    backend: str | None = None,
    params: LaneParams | None = None,
    range_m: float = 50.0,
    fp_rate: float = 0.0,
    seed: int = 0,
    every: int = 1,
    stateful: bool = False,
    time_limit_s: float | None = None,
    progress: bool = False,
    ranker=None,
    options: dict | None = None,
    label: str | None = None,
    plot_failures: str | None = None,
    fp_clearance_m: float = 0.0,
    color_accuracy: float | None = None,
    color_unknown: float = 0.0,
) -> list[PoseRecord]:
    """Score ``method`` at every ``every``-th pose of each track's lap.

    ``stateful`` keeps one ``LaneSolver`` per lap (warm starts, as on the car); otherwise each
    pose gets a fresh solver (the stateless ``solve_lane``). Latency is the whole call; a
    solver's first call (stateful), or the run's first call (stateless), is marked
    ``first_call``: ``summarize`` reports it as start-up time, apart from the latency.
    ``label`` names the method in the records (default: ``method``); ``plot_failures``, a
    folder, gets a picture of every critical failure (strict rule). ``fp_clearance_m``: the
    false positives' least distance from the true boundary lines, an analysis knob (0 in the
    protocol; ``rld.simulation``). ``color_accuracy`` / ``color_unknown``: simulated colour
    perception (``rld.simulation``), its classes passed to the method as ``colors``.
    """
    records: list[PoseRecord] = []
    tracks = list(tracks)
    bar = None
    if progress:
        from tqdm import tqdm

        bar = tqdm(total=None, desc=f"{method} R={range_m:g} FP={fp_rate:.0%}", unit="pose")

    def make() -> LaneSolver:
        return LaneSolver(method=method, params=params, backend=backend, ranker=ranker,
                          options=options)

    from rld.tracker import LaneTracker

    for track in tracks:
        lap = simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed,
                           fp_clearance_m=fp_clearance_m, color_accuracy=color_accuracy,
                           color_unknown=color_unknown)
        solver = make() if stateful else None
        tracker = LaneTracker()  # for the stability of the tracked lane, whatever the method
        prev = None  # (pose, raw centreline, tracked centreline) of the previous pose
        first = stateful or not records
        for k in range(0, len(lap), every):
            frame = lap.frame(k)
            s = solver or make()
            t0 = time.perf_counter()
            lane = s.solve(frame.cones, frame.pose, time_limit_s=time_limit_s,
                           colors=frame.colors)
            latency = time.perf_counter() - t0
            sc = score_lane(frame, lane.left, lane.right, lane.ok, lane.closed)
            raw = lane.centerline if lane.ok else None
            tracked = tracker.update(raw, frame.pose.xy, frame.pose.heading).confident(0.5)
            stab = _stability(prev, frame.pose, raw, tracked)
            prev = (frame.pose, raw, tracked)
            records.append(PoseRecord(
                track=track.name, pose=k, range_m=range_m, fp_rate=fp_rate,
                method=label or method,
                status=lane.status.name, category=sc.category,
                category_tolerant=sc.category_tolerant, iou=sc.iou, iou20=sc.iou20,
                divergence_m=sc.divergence_m, pred_length_m=sc.pred_length_m,
                true_length_m=sc.true_length_m, latency_s=latency,
                n_cones=int(frame.cones.shape[0]),
                iterations=int(lane.stats.get("iterations", -1)),
                complete=lane.stats.get("complete"),
                seed=int(seed),
                deviation_m=sc.deviation_m,
                too_short=sc.too_short,
                first_call=first,
                color_accuracy=math.nan if color_accuracy is None else float(color_accuracy),
                color_unknown=math.nan if color_accuracy is None else float(color_unknown),
                **stab,
            ))
            first = False
            if plot_failures and sc.critical_at(min(GEOMETRIC_DISTANCES_M)):
                _plot_failure(plot_failures, label or method, track.name, frame, lane, sc,
                              range_m, fp_rate, seed)
            if bar is not None:
                bar.update(1)
    if bar is not None:
        bar.close()
    return records


def _stability(prev, pose, raw, tracked) -> dict:
    """The stability ratios (eq. 5) of the raw and the tracked lane against the previous pose:
    the circle is centred at the previous position, d_v is the distance driven since."""
    out = {}
    for r in STABILITY_RADII_M:
        for name, line, k in (("stability", raw, 1), ("tracked_stability", tracked, 2)):
            v = math.nan
            if prev is not None and line is not None and prev[k] is not None \
                    and len(line) >= 2 and len(prev[k]) >= 2:
                moved = float(np.hypot(*(pose.xy - prev[0].xy)))
                v = stability_ratio(prev[k], line, prev[0].xy, r, moved)
            out[f"{name}_{r:g}"] = v
    return out


def _plot_failure(folder, method, track, frame, lane, sc, range_m, fp_rate, seed=0) -> None:
    from pathlib import Path

    from rld.plotting import plot_scene

    Path(folder).mkdir(parents=True, exist_ok=True)
    # The seed is in the name: runs over several seeds would otherwise overwrite each other.
    name = (f"{method}_{track}_R{range_m:g}_fp{round(100 * fp_rate)}_seed{seed}"
            f"_pose{frame.index}".replace(" ", "").replace(":", "-"))
    plot_scene(frame.cones, lane=lane, pose=frame.pose, gt_left=frame.gt_left,
               gt_right=frame.gt_right, false_positive=frame.is_false_positive,
               title=f"{method}, {track}, R {range_m:g} m, FP {fp_rate:.0%} (seed {seed}), "
                     f"pose {frame.index}: {sc.category} (tolerant: {sc.category_tolerant}), "
                     f"diverges at {sc.divergence_m:.1f} m, "
                     f"{sc.deviation_m:.2f} m off the true boundary within 20 m",
               path=str(Path(folder) / f"{name}.png"))


def geometric_key(distance_m: float) -> str:
    """``summarize``'s key of the geometric critical % at ``distance_m``: ``geo_critical_1m``,
    ``geo_critical_0.5m``."""
    return f"geo_critical_{distance_m:g}m"


def summarize(records: list[PoseRecord]) -> dict:
    """The protocol's figures for one setting (percentages in %, lengths in m, latency in ms):
    geometric critical % per ``GEOMETRIC_DISTANCES_M`` (``geometric_key``; NaN when a record
    predates the rule), ``length_ratio`` (% of the means), ``short`` (too-short %), then the
    index rule's categories. Latency percentiles leave out first calls (``startup_*``)."""
    n = len(records)
    if n == 0:
        return {"poses": 0}
    cats = [r.category for r in records]
    out: dict = {"poses": n}
    dev = np.array([r.deviation_m for r in records])
    for d in GEOMETRIC_DISTANCES_M:
        out[geometric_key(d)] = (math.nan if np.isnan(dev).any()
                                 else 100.0 * float(np.mean(dev > d)))
    out["short"] = 100.0 * float(np.mean([r.too_short for r in records]))
    for c in CATEGORIES:
        out[c] = 100.0 * cats.count(c) / n
    out["critical"] = 100.0 * sum(c in CRITICAL for c in cats) / n
    out["critical_tolerant"] = 100.0 * sum(r.category_tolerant in CRITICAL for r in records) / n
    iou20 = [r.iou20 for r in records if not math.isnan(r.iou20)]
    out["mean_iou"] = 100.0 * float(np.mean([r.iou for r in records]))
    out["mean_iou20"] = 100.0 * float(np.mean(iou20)) if iou20 else math.nan
    out["pred_length_m"] = float(np.mean([r.pred_length_m for r in records]))
    out["true_length_m"] = float(np.mean([r.true_length_m for r in records]))
    out["length_ratio"] = (100.0 * out["pred_length_m"] / out["true_length_m"]
                           if out["true_length_m"] > 0 else math.nan)
    start = 1000.0 * np.array([r.latency_s for r in records if r.first_call])
    out["startup_calls"] = int(start.size)
    out["startup_median_ms"] = float(np.median(start)) if start.size else math.nan
    out["startup_max_ms"] = float(start.max()) if start.size else math.nan
    steady = [r.latency_s for r in records if not r.first_call]
    lat = 1000.0 * np.array(steady or [r.latency_s for r in records])
    out["latency_median_ms"] = float(np.median(lat))
    out["latency_p95_ms"] = float(np.percentile(lat, 95))
    out["latency_max_ms"] = float(lat.max())
    out["latency_p99_ms"] = float(np.percentile(lat, 99))
    for r_m in STABILITY_RADII_M:
        for name in ("stability", "tracked_stability"):
            v = [getattr(r, f"{name}_{r_m:g}") for r in records]
            v = [x for x in v if not math.isnan(x)]
            out[f"{name}_{r_m:g}"] = float(np.mean(v)) if v else math.nan
    done = [r.complete for r in records if r.complete is not None]
    if done:
        out["complete"] = 100.0 * float(np.mean(done))
        out["iterations_median"] = float(np.median([r.iterations for r in records]))
    return out


def lap_interval(records: Iterable[PoseRecord], tolerant: bool = True, level: float = 0.95,
                 resamples: int = 2000, seed: int = 0,
                 geometric_m: float | None = None) -> tuple[float, float]:
    """A percentile bootstrap interval (%, ``level`` two-sided) of the pooled critical rate of
    ``records`` (the geometric rule at ``geometric_m`` metres when given, else the index rule,
    tolerant or strict), resampling ``resamples`` times from ``seed``: the tracks with
    replacement, then each drawn track's laps (one per false-positive seed). Whole laps, not
    poses: a lap's poses are far from independent (docs/protocol.md, step 4)."""
    if not 0.0 < level < 1.0:
        raise ValueError(f"level must be in (0, 1), got {level!r}")
    if resamples < 1:
        raise ValueError(f"resamples must be at least 1, got {resamples!r}")
    laps: dict[str, dict[int, list[int]]] = {}
    for r in records:
        if geometric_m is not None:
            hit = r.deviation_m > geometric_m
        else:
            hit = (r.category_tolerant if tolerant else r.category) in CRITICAL
        acc = laps.setdefault(r.track, {}).setdefault(r.seed, [0, 0])
        acc[0] += 1
        acc[1] += bool(hit)
    if not laps:
        raise ValueError("no records")
    rng = np.random.default_rng(seed)
    per_track = [np.array(list(v.values()), dtype=np.float64) for v in laps.values()]
    pick = rng.integers(0, len(per_track), size=(resamples, len(per_track)))
    n = np.zeros(pick.shape)
    hits = np.zeros(pick.shape)
    for t, lap in enumerate(per_track):
        slots = pick == t
        k = lap.shape[0]
        draw = lap[rng.integers(0, k, size=(int(slots.sum()), k))].sum(axis=1)
        n[slots], hits[slots] = draw[:, 0], draw[:, 1]
    rates = 100.0 * hits.sum(axis=1) / n.sum(axis=1)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(rates, [tail, 100.0 - tail])
    return float(lo), float(hi)

"""Incremental RLD (``method="rld-incremental"``, docs/incremental.md) on the shared dataset
tracks: latency per map update, and the cost of an update against the length of the kept lane.

For each false-positive rate, one fresh ``LaneSolver("rld-incremental")`` per track drives the
protocol's lap (``rld.simulation.simulate_lap``, seed 0) pose by pose, and every ``solve`` call
is timed whole (``time.perf_counter``: match, frontier window, program build and solve,
consistency checks, the returned view; restarts included). The solver is stateful, so the
benchmark must see every pose: ``every`` > 1 skips map updates and makes the car jump
``every`` metres between calls (from 6 on, the pose-jump rule restarts every call), which is
only for quick runs, not the car's figures.

Per call it records the mode (``start``, ``extend``, ``closed``; a restart is a ``start``
call), ``lane_cones`` (the kept lane), and for extend calls the frontier program's size: its
cones, columns and rows and its solve time (``lane.stats["frontier"]``, the stats of the last
frontier solve).
"""

from __future__ import annotations

import datetime
import os
import platform
import time
from collections import Counter

import numpy as np

from rld.api import LaneSolver
from rld.simulation import simulate_lap
from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

METHOD = "rld-incremental"
MODES = ("start", "extend", "closed")
#: Bins of ``lane_cones`` (kept lane, both sides) for the cost-against-length table.
LANE_BINS = (0, 25, 50, 100, 150, 200, 300)
#: ``--quick``: the first track only, this many poses.
QUICK_POSES = 50


def dataset_available() -> bool:
    return find_dataset_dir() is not None


def _tracks(ids):
    folder = find_dataset_dir()
    if folder is None:
        raise FileNotFoundError("racetrack dataset not found (set RLD_DATASET_DIR or put it in "
                                "../shared/data/fsd_racetrack_dataset)")
    return [load_dataset_track(folder, k) for k in ids]


def _warm_up(track, range_m: float) -> None:
    """Load the solver backend and compile what compiles, outside the measurement."""
    lap = simulate_lap(track, range_m=range_m, fp_rate=0.0, seed=0)
    solver = LaneSolver(METHOD)
    for k in range(min(5, len(lap))):
        f = lap.frame(k)
        solver.solve(f.cones, f.pose)


def run(range_m: float = 50.0, fp_rates=(0.0, 0.1, 0.3), every: int = 1,
        tracks=DATASET_TRACKS, quick: bool = False, seed: int = 0,
        progress: bool = True) -> list[dict]:
    """One record per ``solve`` call (module docstring)."""
    from tqdm import tqdm

    if every < 1:
        raise ValueError("every must be >= 1")
    track_objs = _tracks(list(tracks)[:1] if quick else tracks)
    _warm_up(track_objs[0], range_m)
    records = []
    for fp in fp_rates:
        for track in track_objs:
            lap = simulate_lap(track, range_m=range_m, fp_rate=fp, seed=seed)
            n = min(len(lap), QUICK_POSES) if quick else len(lap)
            solver = LaneSolver(METHOD)
            for k in tqdm(range(0, n, every), desc=f"{track.name} FP={fp:.0%}",
                          disable=not progress, leave=False):
                f = lap.frame(k)
                t0 = time.perf_counter()
                lane = solver.solve(f.cones, f.pose)
                latency = time.perf_counter() - t0
                st = lane.stats
                mode = st.get("mode", "start")
                rec = {"fp_rate": fp, "track": track.name, "pose": k, "mode": mode,
                       "ok": bool(lane.ok), "latency_s": latency,
                       "map_cones": int(f.cones.shape[0]),
                       "lane_cones": int(st.get("lane_cones", 0)),
                       "restart_reason": st.get("restart_reason"),
                       "restarts": int(st.get("restarts", 0)),
                       "rollbacks": int(st.get("rollbacks", 0))}
                if mode == "extend":
                    fr = st.get("frontier", {})
                    rec.update(n_cones_used=int(st.get("n_cones_used", 0)),
                               n_cols=fr.get("n_cols"), n_rows=fr.get("n_rows"),
                               solve_s=fr.get("solve_time_s"))
                records.append(rec)
    return records


def _lat(recs) -> np.ndarray:
    return 1000.0 * np.array([r["latency_s"] for r in recs], dtype=float)


def _fmt_lat(lat: np.ndarray) -> str:
    if lat.size == 0:
        return "- | - | -"
    return (f"{np.median(lat):.1f} | {np.percentile(lat, 95):.1f} | {lat.max():.1f}")


def _totals(recs) -> tuple[int, int]:
    """Restarts and rollbacks over the run: the last call's counters per (FP, track)."""
    last = {}
    for r in recs:
        last[(r["fp_rate"], r["track"])] = r
    return (sum(r["restarts"] for r in last.values()),
            sum(r["rollbacks"] for r in last.values()))


def _fp_rates(records) -> list[float]:
    return sorted({r["fp_rate"] for r in records})


def latency_markdown(records: list[dict]) -> str:
    """Table 1: latency per update, overall and per mode, per FP rate."""
    lines = ["| FP | mode | calls | median (ms) | p95 (ms) | max (ms) | no lane | restarts | "
             "rollbacks |",
             "|---|---|---|---|---|---|---|---|---|"]
    for fp in _fp_rates(records):
        recs = [r for r in records if r["fp_rate"] == fp]
        restarts, rollbacks = _totals(recs)
        groups = [("all", recs)] + [(m, [r for r in recs if r["mode"] == m]) for m in MODES]
        groups.insert(2, ("(of which restarts)", [r for r in recs if r["restart_reason"]]))
        for name, g in groups:
            tail = f"{restarts} | {rollbacks}" if name == "all" else " | "
            lines.append(f"| {fp:.0%} | {name} | {len(g)} | {_fmt_lat(_lat(g))} | "
                         f"{sum(not r['ok'] for r in g)} | {tail} |")
    return "\n".join(lines)


def restart_markdown(records: list[dict]) -> str:
    """Restarts by reason, per FP rate."""
    reasons = sorted({r["restart_reason"] for r in records if r["restart_reason"]})
    fps = _fp_rates(records)
    if not reasons:
        return "No restarts."
    lines = ["| restart reason | " + " | ".join(f"FP {fp:.0%}" for fp in fps) + " |",
             "|---|" + "---|" * len(fps)]
    counts = {fp: Counter(r["restart_reason"] for r in records
                          if r["fp_rate"] == fp and r["restart_reason"]) for fp in fps}
    for reason in reasons:
        lines.append(f"| {reason} | " + " | ".join(str(counts[fp][reason]) for fp in fps)
                     + " |")
    return "\n".join(lines)


def _bin_label(lo: int, hi: int | None) -> str:
    return f"{lo}-{hi}" if hi is not None else f"{lo}+"


def _ints(recs, key) -> np.ndarray:
    return np.array([r[key] for r in recs if r.get(key) is not None], dtype=float)


def growth_markdown(records: list[dict]) -> str:
    """Table 2: extend calls binned by the kept lane's cones: latency and frontier size."""
    lines = ["| FP | lane cones | calls | median (ms) | p95 (ms) | median solve (ms) | "
             "frontier cones median / max | frontier columns median / max |",
             "|---|---|---|---|---|---|---|---|"]
    edges = list(LANE_BINS) + [None]
    for fp in _fp_rates(records):
        ext = [r for r in records if r["fp_rate"] == fp and r["mode"] == "extend"]
        for lo, hi in zip(edges[:-1], edges[1:], strict=True):
            g = [r for r in ext if r["lane_cones"] >= lo and (hi is None or r["lane_cones"] < hi)]
            if not g:
                continue
            lat = _lat(g)
            solve = 1000.0 * _ints(g, "solve_s")
            cones, cols = _ints(g, "n_cones_used"), _ints(g, "n_cols")
            row = (f"| {fp:.0%} | {_bin_label(lo, hi)} | {len(g)} | {np.median(lat):.1f} | "
                   f"{np.percentile(lat, 95):.1f} | ")
            row += f"{np.median(solve):.1f} | " if solve.size else "- | "
            row += f"{np.median(cones):.0f} / {cones.max():.0f} | " if cones.size else "- | "
            row += f"{np.median(cols):.0f} / {cols.max():.0f} |" if cols.size else "- |"
            lines.append(row)
    return "\n".join(lines)


def correlation_lines(records: list[dict]) -> str:
    """Spearman rank correlation of latency and frontier columns with ``lane_cones``, extend
    calls, per FP rate."""
    from scipy.stats import spearmanr

    out = []
    for fp in _fp_rates(records):
        ext = [r for r in records if r["fp_rate"] == fp and r["mode"] == "extend"
               and r.get("n_cols") is not None]
        if len(ext) < 3:
            continue
        lane = np.array([r["lane_cones"] for r in ext], dtype=float)
        rho_lat = spearmanr(lane, _lat(ext)).statistic
        rho_cols = spearmanr(lane, _ints(ext, "n_cols")).statistic
        out.append(f"- FP {fp:.0%}: Spearman rho(lane cones, latency) = {rho_lat:.2f}, "
                   f"rho(lane cones, frontier columns) = {rho_cols:.2f} ({len(ext)} extend "
                   "calls)")
    return "\n".join(out)


def targets_markdown(records: list[dict], range_m: float) -> str:
    """The issue's latency targets at R = 50 m and 30 % false positives."""
    recs = [r for r in records if abs(r["fp_rate"] - 0.3) < 1e-9]
    if not recs or abs(range_m - 50.0) > 1e-9:
        return "Targets (R = 50 m, 30 % FP): not measured in this run."
    lat = _lat(recs)
    med, p95 = float(np.median(lat)), float(np.percentile(lat, 95))
    return "\n".join([
        "| target (R = 50 m, 30 % FP, all calls) | measured | met |", "|---|---|---|",
        f"| median <= 20 ms | {med:.1f} ms | {'yes' if med <= 20 else 'no'} |",
        f"| p95 <= 60 ms | {p95:.1f} ms | {'yes' if p95 <= 60 else 'no'} |"])


def machine() -> str:
    return (f"{platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
            f"{platform.platform()}")


def to_markdown(records: list[dict], range_m: float, command: str = "") -> str:
    tracks = sorted({r["track"] for r in records})
    head = (f"Command: `{command}`. " if command else "") + (
        f"Machine: {machine()}. Date: {datetime.date.today().isoformat()}. "
        f"R = {range_m:g} m, tracks {', '.join(tracks)}, {len(records)} calls. "
        "Latency is the whole `solve` call; default budget per program solve.")
    return "\n\n".join([
        head,
        "Latency per update:", latency_markdown(records),
        "Restarts by reason:", restart_markdown(records),
        "Extend calls against the kept lane's length (lane cones, both sides):",
        growth_markdown(records), correlation_lines(records),
        targets_markdown(records, range_m)])

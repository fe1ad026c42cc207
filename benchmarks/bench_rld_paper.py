"""RLD accuracy in the paper's own experiment (Brandes et al. 2020, section IV-B, fig. 7).

Three track topologies (a curvy generated circuit, a straight, a circle of 20 m radius), the
car at poses along each, the real cones within the perception range (20 m, at most 3 m behind
the car) plus uniform false positives at the ratios 1:5 and 1:1 (false : real) in the same
field. A solve is *accurate* when it
passes the paper's quality checks:

1. at most one cone differs from the expected boundary set (the true boundary cones of the
   window, from the car forward, without a gap);
2. one boundary on each side of the vehicle (the first left cone to the car's left, the first
   right cone to its right);
3. no edges cross;
4. the distance between the boundaries within the minimum and maximum width (every matching
   line of CLC's lane width, the shared ``lane_widths``).

A solve that returns no lane is inaccurate.
"""

from __future__ import annotations

import math

import numpy as np

from rld.api import LaneSolver
from rld.constraints import c_poly, lane_widths
from rld.generator import generate_track
from rld.solver import cone_window
from rld.tracks import Track
from rld.types import LaneParams, Pose

RATIOS = {"1:5": 0.2, "1:1": 1.0}


def _straight(rng) -> Track:
    xs = np.arange(0, 150, 4.0)
    left = np.column_stack([xs, np.full(xs.size, 2.0)])
    right = np.column_stack([xs, np.full(xs.size, -2.0)])
    cones = np.vstack([left, right]) + rng.normal(0, 0.15, size=(2 * xs.size, 2))
    n = xs.size
    return Track(cones, np.arange(2 * n), np.arange(n), np.arange(n, 2 * n), closed=False,
                 name="straight")


def _circle(rng) -> Track:
    r = 20.0
    k_in, k_out = int(2 * math.pi * (r - 2) / 3.5), int(2 * math.pi * (r + 2) / 3.5)
    a_in = np.arange(k_in) * 2 * math.pi / k_in
    a_out = np.arange(k_out) * 2 * math.pi / k_out
    left = (r - 2) * np.column_stack([np.cos(a_in), np.sin(a_in)])
    right = (r + 2) * np.column_stack([np.cos(a_out), np.sin(a_out)])
    cones = np.vstack([left, right]) + rng.normal(0, 0.15, size=(k_in + k_out, 2))
    return Track(cones, np.arange(k_in + k_out), np.arange(k_in), np.arange(k_in, k_in + k_out),
                 closed=True, name="circle")


def topologies(seed: int = 0) -> dict[str, Track]:
    rng = np.random.default_rng(seed)
    return {"curvy": generate_track(seed + 11), "straight": _straight(rng),
            "circle": _circle(rng)}


def _expected(track: Track, side: np.ndarray, window: np.ndarray, pose: Pose) -> list[int]:
    """The side's true cones in the window from the car forward, up to the first gap."""
    in_win = set(window.tolist())
    xy = track.cones[side]
    d = xy - pose.xy
    ahead = d @ pose.heading >= -2.0
    cand = [k for k in range(side.size) if ahead[k] and side[k] in in_win]
    if not cand:
        return []
    start = min(cand, key=lambda k: float(np.hypot(*d[k])))
    out = []
    n = side.size
    for step in range(n):
        k = (start + step) % n if track.closed else start + step
        if k >= n or side[k] not in in_win:
            break
        out.append(int(side[k]))
    return out


def _field(points: np.ndarray, pose: Pose, range_m: float) -> np.ndarray:
    """One frame's detections: within ``range_m`` of the car and at most 3 m behind it (the
    cones beside the car are seen; the paper's car had a wide field of view)."""
    d = points - pose.xy
    return (np.hypot(d[:, 0], d[:, 1]) <= range_m) & (d @ pose.heading >= -3.0)


def quality_ok(expected: set[int], lane, pose, params) -> bool:
    """The paper's quality checks (module docstring) for ``lane`` against the ``expected``
    boundary cones (indices into the lane's cones)."""
    if not lane.ok:
        return False
    got = set(lane.left.tolist()) | set(lane.right.tolist())
    exp = expected
    if len(exp ^ got) > 1:
        return False
    y = pose.to_local(np.vstack([lane.left_xy[:1], lane.right_xy[:1]]))[:, 1]
    if not (y[0] > 0 > y[1]):
        return False
    if not c_poly(lane.left_xy, lane.right_xy):
        return False
    w = lane_widths(lane.left_xy, lane.right_xy)
    return bool(np.all((w >= params.min_width_m) & (w <= params.max_width_m)))


def run(backend: str = "cpsat", n_cones: int = 12, poses: int = 60, range_m: float = 20.0,
        seed: int = 0, time_limit_s: float = 0.4, progress: bool = True, method: str = "rld",
        **overrides) -> list[dict]:
    """One row per (topology, ratio): inaccurate %, no-lane count, median latency.
    ``overrides`` are ``LaneParams`` fields."""
    import time

    from tqdm import tqdm

    params = LaneParams(max_cones=n_cones, **overrides)
    rows = []
    tracks = topologies(seed)
    bar = tqdm(total=len(tracks) * len(RATIOS) * poses, desc="rld paper", disable=not progress)
    for name, track in tracks.items():
        c = track.centerline(1.0)
        tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
        if not track.closed:
            c, tangent = c[5:-60], tangent[5:-60]  # keep the window on the straight
        rng = np.random.default_rng(seed)
        for ratio_name, ratio in RATIOS.items():
            bad = none = 0
            lat = []
            for k in np.linspace(0, c.shape[0] - 1, poses).astype(int):
                pose = Pose(float(c[k, 0]), float(c[k, 1]),
                            float(math.atan2(tangent[k, 1], tangent[k, 0])))
                idx = np.flatnonzero(_field(track.cones, pose, range_m))
                n_fp = int(round(ratio * idx.size))
                fp = []
                while len(fp) < n_fp:
                    cand = pose.xy + rng.uniform(-range_m, range_m, size=(4 * n_fp + 8, 2))
                    fp.extend(cand[_field(cand, pose, range_m)].tolist())
                fp = np.array(fp[:n_fp]).reshape(-1, 2)
                points = np.vstack([track.cones[idx], fp])
                window, _ = cone_window(points, pose, params)
                # The expected boundary cones, found on the whole track, in frame indices.
                in_track = idx[window[window < idx.size]]
                pos = {int(t): i for i, t in enumerate(idx)}
                expected = {pos[t] for side in (track.left, track.right)
                            for t in _expected(track, side, in_track, pose)}
                t0 = time.perf_counter()
                lane = LaneSolver(method, params, backend).solve(points, pose,
                                                                 time_limit_s=time_limit_s)
                lat.append(time.perf_counter() - t0)
                none += not lane.ok
                bad += not quality_ok(expected, lane, pose, params)
                bar.update(1)
            rows.append({"topology": name, "ratio": ratio_name, "solves": poses,
                         "inaccurate_pct": 100.0 * bad / poses, "no_lane": none,
                         "median_ms": 1000 * float(np.median(lat))})
    bar.close()
    return rows


def to_markdown(rows: list[dict]) -> str:
    lines = ["| topology | false : real | solves | inaccurate (%) | no lane | median (ms) |",
             "|---|---|---|---|---|---|"]
    for r in rows:
        lines.append(f"| {r['topology']} | {r['ratio']} | {r['solves']} | "
                     f"{r['inaccurate_pct']:.1f} | {r['no_lane']} | {r['median_ms']:.1f} |")
    for ratio in RATIOS:
        sel = [r for r in rows if r["ratio"] == ratio]
        tot = sum(r["solves"] for r in sel)
        bad = sum(r["inaccurate_pct"] * r["solves"] / 100 for r in sel)
        lines.append(f"| all | {ratio} | {tot} | {100 * bad / tot:.1f} | "
                     f"{sum(r['no_lane'] for r in sel)} | |")
    return "\n".join(lines)

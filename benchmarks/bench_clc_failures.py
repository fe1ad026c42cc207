"""Where CLC's critical poses come from (``rld bench clc-failures``).

Every pose that CLC gets critically wrong by the protocol's tolerant rule (DESIGN.md:
``diverging_lt20``) falls in one of three classes, by comparing the lane returned with the true
lane *from the lane's own start* (``truth_from_start``):

- ``truth_infeasible``: the true lane fails the shared lane predicate (``lane_is_feasible``:
  spacing, C_seg, C_width, C_poly). No search can return it; only the constraints can change.
- ``judge_prefers_wrong``: the true lane is feasible, and the dive judge (``clc.refine
  .dive_cost``: RLD's objective within ``Refinement.reach_m`` of the car plus the roughness)
  scores it no better than the lane returned. A search that found the truth would not pick it.
  Both lanes are costed as open sequences from their first cones (a closed truth, a ring, from
  the cone the comparison starts at): the judge costs a closed lane whole, and a closed truth
  would beat any open lane by its length alone, whatever happens near the car.
- ``search_miss``: the true lane is feasible and the judge prefers it, but the search never
  built it (under ``max_iterations``, with the dives and local edits).

A ``search_miss`` does not mean that a wider search would mend the pose: a wider search also
finds other lanes, and the judge may prefer one of those to both (the module's figures in
docs/benchmarks.md, with the wider searches measured against them). Each pose also records
where the lane leaves the truth: the side, the cone's position in the lane (0: the start
cone), its distance from the car, and whether the wrong cone is a false positive.

The frames, the solver (stateless, a fresh ``LaneSolver`` per pose, as ``rld eval``) and the
score are the evaluation protocol's; only the classification is this module's.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from rld.constraints import lane_is_feasible
from rld.metrics import score_lane, true_lane_extent
from rld.simulation import Frame
from rld.types import LaneParams

CLASSES = ("truth_infeasible", "judge_prefers_wrong", "search_miss")
#: How many true cones before the truth's first one a lane may start with and still be compared
#: from there (the protocol lets a lane begin with true cones beside or behind the car).
BEHIND_CONES = 2


def truth_from_start(frame: Frame, left: np.ndarray, right: np.ndarray
                     ) -> tuple[np.ndarray, np.ndarray]:
    """The true lane (frame indices) to compare the lane ``left``, ``right`` with, per side:
    the protocol's truth, an open one cut to both sides' common extent (``true_lane_extent``,
    as the IoU's); when the lane's first cone is one of the ``BEHIND_CONES`` true cones before
    the truth's first, an open truth is preceded by those cones and a closed one (a ring) is
    rotated to start there, so that a lane starting a true cone earlier (which the protocol
    allows) is compared from the same cone. When the lane's first cone is the truth's second
    (the protocol allows that too: ``rld.metrics.side_divergence``), the truth is compared from
    there as well: an open truth without its first cone, a ring rotated by one. Until
    2026-12-05 such a lane was compared with the whole truth, which earned the judge one more
    edge near the car and made the pose a search miss leaving the truth at its start cone,
    wherever it really diverged."""
    gl, gr = np.asarray(frame.gt_left, np.int64), np.asarray(frame.gt_right, np.int64)
    ring = frame.gt_closed
    if not ring:
        kl, kr = true_lane_extent(frame.cones[gl], frame.cones[gr])
        gl, gr = gl[:kl], gr[:kr]
    out = []
    for got, gt, seq in ((left, gl, frame.left_seq), (right, gr, frame.right_seq)):
        seq = np.asarray(seq, np.int64)
        if len(got) and gt.size:
            a, b = np.flatnonzero(seq == got[0]), np.flatnonzero(seq == gt[0])
            if a.size and b.size:
                lead = (int(b[0]) - int(a[0])) % seq.size
                pre = seq[(int(a[0]) + np.arange(lead)) % seq.size]
                if 0 < lead <= BEHIND_CONES and np.all(pre >= 0):
                    gt = np.roll(gt, lead) if ring else np.concatenate([pre, gt])
            if gt.size > 1 and got[0] == gt[1]:
                gt = np.roll(gt, -1) if ring else gt[1:]
        out.append(gt)
    return out[0], out[1]


@dataclass
class Failure:
    """One critical pose, classified (see the module docstring)."""

    track: int
    seed: int
    pose: int
    kind: str
    cost_gap: float
    """dive_cost(truth) - dive_cost(lane returned), both open: positive where the judge
    prefers the lane returned; nan where the truth is infeasible."""
    closed_truth: bool
    side: str
    """"left" or "right": the side that leaves the truth first (nearest the car)."""
    position: int
    """The wrong cone's index in that side of the lane (0: the start cone)."""
    distance_m: float
    """The wrong cone's distance from the car, metres."""
    false_positive: bool


def classify(frame: Frame, left: np.ndarray, right: np.ndarray,
             params: LaneParams) -> tuple[str, float]:
    """The class of the lane ``left``, ``right`` (frame indices) against ``frame``'s truth,
    and the judge's cost gap (truth minus lane, both open from their first cones; nan when the
    truth is infeasible)."""
    from clc.refine import dive_cost

    tl, tr = truth_from_start(frame, left, right)
    if len(tl) < 2 or len(tr) < 2 or not lane_is_feasible(frame.cones[tl], frame.cones[tr],
                                                          params, closed=frame.gt_closed):
        return "truth_infeasible", float("nan")
    # Both as open sequences from their start, so both are counted within the judge's reach:
    # the judge costs a closed lane whole (``lane_cost``), which any closed truth would win
    # against an open lane by its length alone, whatever happens near the car.
    gap = (dive_cost(frame.cones, frame.pose, params, tl, tr)
           - dive_cost(frame.cones, frame.pose, params, np.asarray(left), np.asarray(right)))
    return ("judge_prefers_wrong" if gap >= 0 else "search_miss"), float(gap)


def _leaves(frame: Frame, left: np.ndarray, right: np.ndarray):
    """(side, position, distance, false positive) of the first cone, over both sides the one
    nearest the car, where the lane leaves ``truth_from_start``; None when neither does."""
    truth = truth_from_start(frame, left, right)
    best = None
    for name, got, gt in (("left", left, truth[0]), ("right", right, truth[1])):
        n = min(len(got), len(gt))
        diff = np.flatnonzero(np.asarray(got[:n]) != np.asarray(gt[:n]))
        k = int(diff[0]) if diff.size else (n if len(got) > n else -1)
        if k < 0:
            continue
        c = int(got[k])
        d = float(np.hypot(*(frame.cones[c] - frame.pose.xy)))
        if best is None or d < best[2]:
            best = (name, k, d, bool(frame.source[c] < 0))
    return best


def _job(args) -> list[Failure]:
    from rld.api import LaneSolver
    from rld.simulation import simulate_lap
    from rld.tracks import find_dataset_dir, load_dataset_track

    tid, seed, range_m, fp_rate, every = args
    lap = simulate_lap(load_dataset_track(find_dataset_dir(), tid), range_m=range_m,
                       fp_rate=fp_rate, seed=seed)
    params = LaneParams()
    out = []
    for k in range(0, len(lap), every):
        frame = lap.frame(k)
        lane = LaneSolver("clc", params).solve(frame.cones, frame.pose)
        sc = score_lane(frame, lane.left, lane.right, lane.ok, lane.closed)
        if sc.category_tolerant != "diverging_lt20" or not lane.ok:
            continue
        kind, gap = classify(frame, lane.left, lane.right, params)
        where = _leaves(frame, lane.left, lane.right) or ("", -1, float("nan"), False)
        out.append(Failure(tid, seed, k, kind, gap, frame.gt_closed, *where))
    return out


def run(range_m: float = 30.0, fp_rate: float = 0.3, seeds: Sequence[int] = (0,),
        every: int = 1, processes: int = 2, progress: bool = True) -> dict:
    """Classify every tolerant-critical CLC pose of the shared tracks at one range and
    false-positive rate, the seeds pooled. Returns the pose count and the failures."""
    from multiprocessing import get_context

    from tqdm import tqdm

    from rld.simulation import simulate_lap
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    folder = find_dataset_dir()
    if folder is None:
        raise FileNotFoundError("racetrack dataset not found (../shared/data/...)")
    poses = sum(len(range(0, len(simulate_lap(load_dataset_track(folder, t), range_m=range_m,
                                                          fp_rate=0.0, seed=0)), every))
                for t in DATASET_TRACKS) * len(seeds)
    jobs = [(t, s, range_m, fp_rate, every) for s in seeds for t in DATASET_TRACKS]
    failures: list[Failure] = []
    with get_context("spawn").Pool(max(1, int(processes))) as pool:
        it = pool.imap_unordered(_job, jobs)
        for part in tqdm(it, total=len(jobs), desc=f"clc failures R={range_m:g} "
                         f"FP={fp_rate:.0%}", unit="lap", disable=not progress):
            failures.extend(part)
    failures.sort(key=lambda f: (f.track, f.seed, f.pose))
    return {"range_m": range_m, "fp_rate": fp_rate, "seeds": list(seeds), "every": every,
            "poses": poses, "failures": failures}


def to_markdown(results: Sequence[dict]) -> str:
    """One row per cell: critical poses by class, with the start-cone and closed-truth shares."""
    lines = ["| R | FP | poses | critical | truth infeasible | judge prefers wrong | "
             "search miss | at the start cone | onto a false positive | closed truth |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for r in results:
        f = r["failures"]
        c = Counter(x.kind for x in f)
        n = len(f)
        pct = 100.0 * n / r["poses"] if r["poses"] else float("nan")
        lines.append(
            f"| {r['range_m']:g} m | {r['fp_rate']:.0%} | {r['poses']} | {n} ({pct:.2f} %) | "
            + " | ".join(str(c[k]) for k in CLASSES)
            + f" | {sum(x.position == 0 for x in f)} | {sum(x.false_positive for x in f)} | "
            f"{sum(x.closed_truth for x in f)} |")
    return "\n".join(lines)

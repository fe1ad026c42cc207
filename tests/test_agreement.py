"""RLD and CLC agree on clean tracks (issue 5, item 2): regression tests.

On generated tracks without false positives and on the shared dataset tracks with none added,
at every k-th pose of the protocol (R = 50 m), ``solve_lane(..., method="rld")`` and
``solve_lane(..., method="clc")`` are compared (``rld.metrics.lanes_identical``, below).

What holds today, and what these tests assert:
- Wherever both lanes follow the ground truth (strict categories ``gt``, ``near_gt`` or
  ``too_short``, and neither diverges from it anywhere), they are the same lane over the
  common horizon: the two methods share the side convention, the order from the car forward
  and the boundary cones. (A ``near_gt`` lane may diverge 20 m or more from the car; where it
  does inside the common horizon the two lanes differ by its divergence, which is that
  method's own failure. Seen since 2026-12-01: CLC skipping a kinked cone 23 m ahead that
  RLD's objective, on CLC's longer lane, also prefers to skip.)
- The two methods do not yet agree at every pose: where they differ, one of them (or both)
  diverges from the ground truth (each method's own failures, docs/results.md), and RLD never
  alone. Since 2026-12-07 a pose counts as agreement only when the two lanes are identical
  (``rld.metrics.lanes_identical``: cone for cone from each side's first cone not behind the
  car to its end, a closed lane as its set of edges; no lane against no lane is no
  agreement), as issue 40 asks; the common horizon (``lanes_agree``) still decides what is a
  contradiction. Measured 2026-12-07, with CLC inserting the cones its lane skips beyond
  25 m along a boundary (``clc.refine.far_insertions``), RLD's window reaching 4 m behind
  the car (``window_behind_m``) and both lanes' far ends extended by one rule
  (``rld.insertion.extend_ends``), and CLC beginning a side at the cone beside the car at
  the start of a lap (``rld.insertion.extend_starts``): 101 of 105 (generated) and 56 of 72
  (dataset) identical (97 and 51 before the lap start). With the regularity term at 0.5
  (2026-12-08) 101 and 50: on shared track 4 RLD's loop now skips a true right cone 1.17 m
  after the one before it and 2.21 m before the next (5 poses, 18-47 m from the car, within
  0.5 m of the truth by the geometric rule), the one place RLD alone diverges
  (``DATASET_RLD_ALONE``). Left: shared track 3's loops, a closed against an open lane, far
  ends one cone apart, single cones (docs/benchmarks.md, issue 40 item 4). The floors sit at
  most 2 points under the figures, so that
  a regression in either method, or in the conventions they share, fails here with the
  poses and a picture of each disagreement; the nearest-neighbour chain, or RLD cut to 20 m,
  in RLD's place falls far under them.
"""

from __future__ import annotations

import math
from pathlib import Path

import pytest

from rld.api import solve_lane
from rld.generator import generate_track
from rld.metrics import lanes_agree, lanes_identical, score_lane
from rld.simulation import simulate_lap
from rld.tracks import load_dataset_track

# A time budget far above what these windows need, so that the result does not depend on
# the machine's load (a solve cut short by the default 0.4 s could return another lane).
TIME_LIMIT_S = 3.0
FOLLOWS_TRUTH = ("gt", "near_gt", "too_short")
#: The floors: the measured shares of identical lanes, less at most 2 points (docstring).
GENERATED_FLOOR, DATASET_FLOOR = 0.95, 0.68

#: The poses where RLD alone diverges from the truth on the shared tracks (track 4's squeezed
#: right cone, skipped under the regularity term; docstring), at most.
DATASET_RLD_ALONE = 6


def _compare(tracks, every: int, folder: Path) -> tuple[int, list[str], list[str]]:
    """Solve every ``every``-th pose with both methods; returns (poses, disagreements,
    contradictions), each a line naming the pose, with a plot path for disagreements.
    A disagreement: the two lanes are not identical (``lanes_identical``). A contradiction:
    both lanes follow the truth, yet they differ over their common horizon; or RLD alone
    strays (no lane, or it diverges from the truth where CLC does not)."""
    from rld.plotting import plot_scene

    n, disagree, contradict = 0, [], []
    for track in tracks:
        lap = simulate_lap(track, range_m=50.0, fp_rate=0.0, seed=0)
        for k in range(0, len(lap), every):
            f = lap.frame(k)
            lanes = {m: solve_lane(f.cones, f.pose, method=m, time_limit_s=TIME_LIMIT_S)
                     for m in ("rld", "clc")}
            n += 1
            if lanes_identical(lanes["rld"], lanes["clc"], f.pose):
                continue
            scores = {m: score_lane(f, lane.left, lane.right, lane.ok, lane.closed)
                      for m, lane in lanes.items()}
            cats = {m: s.category for m, s in scores.items()}
            path = folder / f"{track.name.replace(' ', '_')}_pose{k}.png"
            import matplotlib.pyplot as plt

            fig, axes = plt.subplots(1, 2, figsize=(14, 7))
            for ax, (m, lane) in zip(axes, lanes.items(), strict=True):
                plot_scene(f.cones, lane=lane, pose=f.pose, gt_left=f.gt_left,
                           gt_right=f.gt_right, title=f"{m}: {cats[m]}", ax=ax)
            fig.savefig(path, dpi=80)
            plt.close(fig)
            line = (f"{track.name} pose {k}: rld {cats['rld']}, clc {cats['clc']} "
                    f"(plot: {path})")
            disagree.append(line)
            # A lane exactly the truth (gt) against one that differs: the other's own miss
            # (CLC skipping a true cone at a closed loop's seam, say), not a convention.
            # Lanes of different lengths both on the truth are no contradiction: over their
            # common horizon (``lanes_agree``) they must be the same.
            if "gt" not in cats.values() and not lanes_agree(lanes["rld"], lanes["clc"]) and all(
                    lanes[m].ok and cats[m] in FOLLOWS_TRUTH
                    and math.isinf(scores[m].divergence_m) for m in lanes):
                contradict.append(line)
            ok = {m: lanes[m].ok and math.isinf(scores[m].divergence_m) for m in lanes}
            if ok["clc"] and not ok["rld"]:
                contradict.append("rld alone: " + line)
    return n, disagree, contradict


def _check(n: int, disagree: list[str], contradict: list[str], floor: float,
           rld_alone: int = 0, rld_alone_track: str = "") -> None:
    alone = [c for c in contradict if c.startswith("rld alone: ")]
    if len(alone) <= rld_alone and all(c.startswith(f"rld alone: {rld_alone_track} ")
                                       for c in alone):
        contradict = [c for c in contradict if c not in alone]
    assert not contradict, (
        "rld and clc both follow the ground truth but differ over their common horizon:\n"
        + "\n".join(contradict))
    rate = 1.0 - len(disagree) / n
    assert rate >= floor, (
        f"rld and clc agree on {rate:.1%} of {n} poses (floor {floor:.0%}); disagreements:\n"
        + "\n".join(disagree))


def test_rld_and_clc_agree_on_clean_generated_tracks(tmp_path):
    tracks = [generate_track(100 + s) for s in range(4)]
    n, disagree, contradict = _compare(tracks, every=10, folder=tmp_path)
    assert n == 105
    _check(n, disagree, contradict, floor=GENERATED_FLOOR)


def test_rld_and_clc_agree_on_the_dataset_tracks(dataset_dir, tmp_path):
    tracks = [load_dataset_track(dataset_dir, k) for k in (1, 2, 3, 4, 6, 7)]
    n, disagree, contradict = _compare(tracks, every=20, folder=tmp_path)
    assert n == 72
    _check(n, disagree, contradict, floor=DATASET_FLOOR, rld_alone=DATASET_RLD_ALONE,
           rld_alone_track="track 4")


def _cut_to_20_m(lane, pose):
    """``lane`` with each open side cut at its first cone farther than 20 m from the car."""
    from rld.costs import within_radius
    from rld.types import Lane

    if not lane.ok or lane.closed:
        return lane
    left, right = (within_radius(lane.cones, s, pose, 20.0) for s in (lane.left, lane.right))
    return Lane(cones=lane.cones, left=left, right=right, status=lane.status)


@pytest.mark.parametrize("who", ["rld", "clc"])
@pytest.mark.parametrize("stand_in", ["nearest", "cut to 20 m"])
def test_the_agreement_fails_when_a_method_is_replaced(who, stand_in, tmp_path, monkeypatch):
    # Done-when of issue 40: the nearest-neighbour chain, or the method's lane cut to 20 m, in
    # either method's place falls under the floor (on one generated track, every 10th pose).
    import sys

    me = sys.modules[__name__]
    real = me.solve_lane

    def patched(cones, pose, method, **kw):
        if method != who:
            return real(cones, pose, method=method, **kw)
        if stand_in == "nearest":
            return real(cones, pose, method="nearest", **kw)
        return _cut_to_20_m(real(cones, pose, method=who, **kw), pose)

    monkeypatch.setattr(me, "solve_lane", patched)
    n, disagree, _ = _compare([generate_track(100)], every=10, folder=tmp_path)
    assert 1.0 - len(disagree) / n < GENERATED_FLOOR - 0.1


@pytest.mark.parametrize("swap", ["sides", "order"])
def test_the_comparison_sees_a_swapped_lane(swap):
    # The comparison is not blind to the conventions it is meant to guard.
    lap = simulate_lap(generate_track(100), range_m=50.0, fp_rate=0.0, seed=0)
    f = lap.frame(40)
    lane = solve_lane(f.cones, f.pose, method="clc")
    assert lane.ok
    other = ((lane.right, lane.left) if swap == "sides"
             else (lane.left[::-1].copy(), lane.right[::-1].copy()))
    assert lanes_agree(lane, (lane.left, lane.right))
    assert not lanes_agree(lane, other)

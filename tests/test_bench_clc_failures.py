"""The classification of CLC's critical poses (benchmarks/bench_clc_failures.py) on lanes
built by hand from a generated lap's truth: each class, the truth compared from the lane's
own start, and where a lane leaves the truth."""

import math
from dataclasses import replace

import numpy as np
import pytest

from clc.refine import dive_cost
from rld.cli import _benchmark_module
from rld.generator import generate_track
from rld.simulation import simulate_lap
from rld.types import LaneParams

B = _benchmark_module("bench_clc_failures")  # benchmarks/ is not an installed package
PARAMS = LaneParams()


@pytest.fixture(scope="module")
def frame():
    """A pose in the middle of the lap: open truth of at least 5 cones a side, and the true
    cone before each side's first one already mapped."""
    lap = simulate_lap(generate_track(3), range_m=50.0, fp_rate=0.3, seed=0)
    for k in range(len(lap) // 3, len(lap)):
        f = lap.frame(k)
        if f.gt_closed or min(f.gt_left.size, f.gt_right.size) < 5:
            continue
        before = []
        for gt, seq in ((f.gt_left, f.left_seq), (f.gt_right, f.right_seq)):
            i = int(np.flatnonzero(seq == gt[0])[0])
            before.append(int(seq[i - 1]))
        if min(before) >= 0:
            return f
    pytest.fail("no suitable pose on the generated lap")


def _truth(f):
    return B.truth_from_start(f, f.gt_left, f.gt_right)


def test_truth_from_start_is_the_compared_truth(frame):
    tl, tr = _truth(frame)
    # The lane that is the truth is compared with the truth (cut to the common extent).
    assert np.array_equal(tl, frame.gt_left[: tl.size])
    assert np.array_equal(tr, frame.gt_right[: tr.size])
    # A lane starting one true cone earlier on the left is compared with the truth preceded
    # by that cone; the right side does not change.
    i = int(np.flatnonzero(frame.left_seq == frame.gt_left[0])[0])
    early = np.r_[frame.left_seq[i - 1], frame.gt_left]
    el, er = B.truth_from_start(frame, early, frame.gt_right)
    assert np.array_equal(el, np.r_[frame.left_seq[i - 1], tl])
    assert np.array_equal(er, tr)
    # Starting three true cones earlier is past BEHIND_CONES: not prepended.
    far = np.r_[frame.left_seq[i - 3: i], frame.gt_left]
    if np.all(frame.left_seq[i - 3: i] >= 0):
        assert np.array_equal(B.truth_from_start(frame, far, frame.gt_right)[0], tl)
    # A lane starting at the truth's second cone (allowed by the protocol) is compared with
    # the truth from there: it leaves it nowhere, and the judge sees no edge it lacks.
    late = tl[1:]
    ll, lr = B.truth_from_start(frame, late, frame.gt_right)
    assert np.array_equal(ll, late) and np.array_equal(lr, tr)
    assert B._leaves(frame, late, tr) is None
    assert B.classify(frame, late, tr, PARAMS) == ("judge_prefers_wrong", 0.0)
    # Starting at the third is not allowed: compared with the whole truth, left at cone 0.
    assert np.array_equal(B.truth_from_start(frame, tl[2:], frame.gt_right)[0], tl)
    assert B._leaves(frame, tl[2:], tr)[:2] == ("left", 0)



def test_truth_from_start_rotates_a_closed_truth():
    lap = simulate_lap(generate_track(3), range_m=50.0, fp_rate=0.3, seed=0)
    f = lap.frame(len(lap) - 5)
    assert f.gt_closed
    tl, tr = B.truth_from_start(f, f.gt_left, f.gt_right)
    assert np.array_equal(tl, f.gt_left) and np.array_equal(tr, f.gt_right)
    # A lane starting one true cone before the ring's first: the ring is compared from there,
    # and the lane that is that ring leaves it nowhere.
    early = np.r_[f.gt_left[-1], f.gt_left[:-1]]
    el, _ = B.truth_from_start(f, early, f.gt_right)
    assert np.array_equal(el, early)
    assert B._leaves(f, early, f.gt_right) is None
    # Three cones before is past BEHIND_CONES: compared with the ring as it is, and the lane
    # leaves it at its first cone.
    late = np.roll(f.gt_left, 3)
    assert np.array_equal(B.truth_from_start(f, late, f.gt_right)[0], f.gt_left)
    assert B._leaves(f, late, f.gt_right)[:2] == ("left", 0)
    # One cone after the ring's first (the lane skips it): the ring is rotated to the lane.
    after = np.roll(f.gt_left, -1)
    assert np.array_equal(B.truth_from_start(f, after, f.gt_right)[0], after)
    assert B._leaves(f, after, f.gt_right) is None

def test_classes(frame):
    tl, tr = _truth(frame)
    # The truth itself: the judge cannot prefer it to itself (gap 0), so never a search miss.
    kind, gap = B.classify(frame, tl, tr, PARAMS)
    assert (kind, gap) == ("judge_prefers_wrong", 0.0)
    # A lane whose left side stops after 4 cones, within the judge's reach: the truth earns
    # more edge benefit there, so the judge prefers it, by the difference of the dive costs.
    short = tl[:4]
    kind, gap = B.classify(frame, short, tr, PARAMS)
    want = (dive_cost(frame.cones, frame.pose, PARAMS, tl, tr)
            - dive_cost(frame.cones, frame.pose, PARAMS, short, tr))
    assert want < 0
    assert kind == "search_miss"
    assert gap == pytest.approx(want)
    # Cut beyond the reach (Refinement.reach_m) the judge sees no difference: not a search miss.
    kind, gap = B.classify(frame, tl[:-2], tr, PARAMS)
    assert (kind, gap) == ("judge_prefers_wrong", 0.0)
    # The same truth under a maximum width below the lane's: infeasible, no gap.
    narrow = replace(PARAMS, max_width_m=2.0, min_width_m=1.0)
    kind, gap = B.classify(frame, short, tr, narrow)
    assert kind == "truth_infeasible" and math.isnan(gap)


def test_where_the_lane_leaves_the_truth(frame):
    tl, tr = _truth(frame)
    assert B._leaves(frame, tl, tr) is None
    fp = int(np.flatnonzero(frame.is_false_positive)[0])
    wrong = tr.copy()
    wrong[2] = fp
    side, pos, dist, is_fp = B._leaves(frame, tl, wrong)
    assert (side, pos, is_fp) == ("right", 2, True)
    assert dist == pytest.approx(float(np.hypot(*(frame.cones[fp] - frame.pose.xy))))
    # Both sides wrong: the one whose wrong cone is nearer the car.
    wl = tl.copy()
    wl[1] = fp
    got = B._leaves(frame, wl, wrong)
    assert got[0] == "left" and got[1] == 1
    # A lane longer than the truth leaves it at the first extra cone.
    side, pos, _, _ = B._leaves(frame, np.r_[tl, fp], tr)
    assert (side, pos) == ("left", tl.size)


def test_table_counts_each_class():
    F = B.Failure
    res = {"range_m": 30.0, "fp_rate": 0.1, "poses": 200, "failures": [
        F(1, 0, 3, "search_miss", -1.0, False, "left", 0, 2.0, True),
        F(1, 0, 4, "search_miss", -1.0, True, "left", 3, 9.0, False),
        F(2, 0, 9, "judge_prefers_wrong", 0.5, False, "right", 0, 2.5, True),
        F(2, 0, 9, "truth_infeasible", math.nan, False, "right", 5, 12.0, True)]}
    row = B.to_markdown([res]).splitlines()[-1]
    assert row == "| 30 m | 10% | 200 | 4 (2.00 %) | 1 | 1 | 2 | 2 | 3 | 1 |"

"""The quality checks of the RLD paper's experiment (benchmarks/bench_rld_paper.py): the true
lane passes them on every pose, and each check catches what it is for."""

import numpy as np
import pytest

from rld.cli import _benchmark_module
from rld.types import LaneParams

B = _benchmark_module("bench_rld_paper")  # benchmarks/ is not an installed package

PARAMS = LaneParams(max_cones=12)


@pytest.fixture(scope="module")
def all_frames():
    return list(B.frames(seed=0, poses=20, params=PARAMS))


def test_true_lane_passes_every_check(all_frames):
    assert len(all_frames) == 3 * 2 * 20
    for f in all_frames:
        left, right = f.truth
        assert left.size >= 2 and right.size >= 2, (f.topology, f.ratio)
        assert B.quality_failures(f, left, right, PARAMS) == [], (f.topology, f.ratio)


def test_each_check_fails_what_it_is_for(all_frames):
    f = next(f for f in all_frames if f.topology == "straight" and f.ratio == "1:1")
    left, right = f.truth
    fps = sorted(set(range(f.points.shape[0])) - f.expected - f.behind - f.on_line)
    # One cone off the expected set is allowed, two are not.
    assert B.quality_failures(f, np.r_[left, fps[:1]], right, PARAMS) == []
    assert "set" in B.quality_failures(f, np.r_[left, fps[:1]], np.r_[right, fps[1:2]],
                                       PARAMS)
    assert "set" in B.quality_failures(f, left[:-1], right[:-1], PARAMS)
    # Sides swapped; a boundary crossing the other; the 4 m straight against narrower and
    # wider limits.
    assert "side" in B.quality_failures(f, right, left, PARAMS)
    assert "crossing" in B.quality_failures(f, left, right[::-1], PARAMS)
    for lo, hi in ((4.5, 6.5), (2.5, 3.5)):
        narrow = LaneParams(max_cones=12, min_width_m=lo, max_width_m=hi)
        assert B.quality_failures(f, left, right, narrow) == ["width"]
    assert B.quality_failures(f, [], right, PARAMS) == ["no lane"]


def test_behind_and_on_line_cones_are_neutral(all_frames):
    f = next(f for f in all_frames if f.behind)
    left, right = f.truth
    behind = np.array(sorted(f.behind))
    on_left = f.pose.to_local(f.points[behind])[:, 1] > 0
    lane = np.r_[behind[on_left], left], np.r_[behind[~on_left], right]
    assert B.quality_failures(f, *lane, PARAMS) == []
    g = next((g for g in all_frames if len(g.on_line) >= 2), None)
    if g is None:
        pytest.skip("no frame with two false positives on a boundary line")
    on = sorted(g.on_line)[:2]
    gl, gr = g.truth
    assert "set" in B.quality_failures(g, np.r_[gl, on], gr, PARAMS)
    assert "set" not in B.quality_failures(g, np.r_[gl, on], gr, PARAMS, tolerant=True)


def test_truth_in_program_is_the_shared_cost_and_never_beats_the_optimum(all_frames):
    """The diagnostic that splits inaccurate solves into the model's and the solver's: the
    true lane's objective in the solver's own program is the shared ``lane_cost``, and an
    optimal solve is never dearer than it (which would be a missed optimum)."""
    from rld.api import LaneSolver
    from rld.costs import lane_cost
    from rld.types import LaneStatus

    compared = 0
    for f in all_frames[::3]:
        truth = B.truth_in_program(f, PARAMS)
        if truth is None:
            continue
        assert truth == pytest.approx(lane_cost(f.points, *f.truth, f.pose, PARAMS), abs=1e-6)
        lane = LaneSolver("rld", PARAMS, "cpsat").solve(f.points, f.pose, time_limit_s=5.0)
        if lane.status == LaneStatus.OPTIMAL:
            assert lane.stats["objective"] <= truth + 1e-6, (f.topology, f.ratio)
            compared += 1
    assert compared >= 20
    # A straight's 4 m spacing is longer than a 3.5 m limit: the truth is no solution.
    f = next(f for f in all_frames if f.topology == "straight")
    assert B.truth_in_program(f, LaneParams(max_cones=12, max_cone_spacing_m=3.5)) is None


def test_pooled_seeds_are_the_sum_of_single_seeds():
    """``run`` over two seeds pools exactly what each seed gives alone, and tallies each."""
    kw = dict(poses=3, progress=False)
    both = B.run(seeds=(0, 1), **kw)
    alone = {s: B.run(seeds=(s,), **kw) for s in (0, 1)}
    for row in both:
        key = (row["topology"], row["ratio"])
        parts = [next(r for r in alone[s] if (r["topology"], r["ratio"]) == key) for s in (0, 1)]
        assert row["solves"] == sum(p["solves"] for p in parts)
        for pct in ("inaccurate_pct", "inaccurate_tolerant_pct"):
            pooled = sum(p[pct] * p["solves"] for p in parts) / row["solves"]
            assert abs(row[pct] - pooled) < 1e-9
        for s, p in zip((0, 1), parts, strict=True):
            n, bad, tol = row["per_seed"][s]
            assert n == p["solves"]
            assert abs(100 * bad / n - p["inaccurate_pct"]) < 1e-9
            assert abs(100 * tol / n - p["inaccurate_tolerant_pct"]) < 1e-9

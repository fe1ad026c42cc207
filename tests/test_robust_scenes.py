"""Scenes seen on real circuits (issue 39, item 6), built by hand, for every method.

The start line: a side's first cone stands 4.9 m ahead of the car and nothing of that side is
nearer, beyond ``near_radius_m`` (4.5 m); ``LaneParams.start_reach_m`` lets that side start
there (``rld.constraints.start_mask``).
"""

from __future__ import annotations

import numpy as np
import pytest

from rld import LaneParams, Pose, solve_lane

METHODS = ("nearest", "rld", "rld-sided", "rld-incremental", "clc")
WIDTH_M = 3.5
SPACING_M = 4.0
CAR = Pose(0.0, 0.0, 0.0)


def along(s, offset: float, curvature: float) -> np.ndarray:
    """Points at arc lengths ``s`` (metres) of a centreline that leaves the origin along +x
    with constant ``curvature`` (1/m, left positive), ``offset`` metres to its left."""
    s = np.asarray(s, dtype=np.float64)
    if curvature == 0:
        return np.column_stack([s, np.full(s.size, offset)])
    th = curvature * s
    centre = np.column_stack([np.sin(th), 1.0 - np.cos(th)]) / curvature
    return centre + offset * np.column_stack([-np.sin(th), np.cos(th)])


def start_line(first_left: float, first_right: float, curvature: float):
    """A lane 3.5 m wide, cones every 4 m on each side from arc length ``first_*`` to 40 m; a
    side that starts beside the car (``first_* < 4.5``) also has a cone 4 m behind that. Returns
    ``(cones, true_left, true_right)``: the true boundaries from their first cone not behind
    the car (indices into ``cones``)."""
    sides, truth, n = [], [], 0
    for first, offset in ((first_left, WIDTH_M / 2), (first_right, -WIDTH_M / 2)):
        s = np.arange(first, 40.0, SPACING_M)
        behind = [first - SPACING_M] if first < 4.5 else []
        sides.append(along(np.r_[behind, s], offset, curvature))
        truth.append(n + len(behind) + np.arange(s.size))
        n += len(behind) + s.size
    return np.vstack(sides), truth[0], truth[1]


# (first left, first right, curvature): one side 4.9 m ahead, or both; straight or gently
# curved (radius 50 m).
START_CASES = [(4.9, 0.5, 0.0), (0.5, 4.9, 0.0), (4.9, 4.9, 0.0), (4.9, 0.5, 0.02),
               (0.5, 4.9, -0.02), (4.9, 4.9, 0.02), (4.9, 4.9, -0.02)]
# The nearest-neighbour chain (left first) steps across a lane narrower than the cone spacing
# when a right cone lies nearer ahead than the next left one, whatever its start (its floor):
# its whole lane is checked where that does not happen, its start pair everywhere.
NEAREST_CASES = [(4.9, 0.5, 0.0), (4.9, 4.9, 0.0), (4.9, 0.5, 0.02), (4.9, 4.9, -0.02)]


@pytest.mark.parametrize("case", START_CASES)
def test_start_line_start_pair_is_the_true_first_cones(case):
    """The start pair of CLC (about the car, ``clc.solver.start_pairs``) and of the
    nearest-neighbour chain (``find_starting_vertices``)."""
    from clc.solver import start_pairs
    from rld.constraints import find_starting_vertices

    cones, true_left, true_right = start_line(*case)
    p = LaneParams()
    want = (int(true_left[0]), int(true_right[0]))
    assert find_starting_vertices(cones, CAR, p.near_radius_m, p.start_reach_m) == want
    assert find_starting_vertices(cones, CAR, p.near_radius_m) is None
    assert start_pairs(cones, CAR, p)[0] == want


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("case", START_CASES)
def test_start_line_first_cone_beyond_the_near_radius(method, case):
    if method == "nearest" and case not in NEAREST_CASES:
        pytest.skip("the nearest-neighbour chain zigzags here whatever its start (its floor)")
    cones, true_left, true_right = start_line(*case)
    d = np.hypot(*(cones[[true_left[0], true_right[0]]] - CAR.xy).T)
    assert (d > LaneParams().near_radius_m).tolist() == [case[0] > 4.5, case[1] > 4.5]
    lane = solve_lane(cones, CAR, method=method)
    assert lane.ok, lane.message
    for got, truth in ((lane.left, true_left), (lane.right, true_right)):
        assert got.size >= 2
        assert got[0] == truth[0]
        assert got.tolist() == truth[: got.size].tolist()


@pytest.mark.parametrize("method", METHODS)
def test_start_line_needs_the_reach(method):
    """With ``start_reach_m = 0`` (the papers' rule) the same scene has no lane."""
    cones, _, _ = start_line(4.9, 0.5, 0.0)
    lane = solve_lane(cones, CAR, method=method, params=LaneParams(start_reach_m=0.0))
    assert not lane.ok

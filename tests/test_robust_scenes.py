"""Two scenes seen on real circuits (issue 39, item 6), built by hand, for every method.

The start line: a side's first cone stands 4.9 m ahead of the car and nothing of that side is
nearer, beyond ``near_radius_m`` (4.5 m); ``LaneParams.start_reach_m`` lets that side start
there (``rld.constraints.start_mask``). The entry of a sparse hairpin whose legs are 4 m (3 m)
apart: the inner boundary's two legs are one cone spacing apart, and a lane must not run back
behind the car (CLC did: its boundaries left their start cones backwards, ``clc.search_kernels``).
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


def hairpin(gap_m: float, car_x: float, spacing_m: float = 5.0):
    """A left hairpin on a sparse map, the car at (car_x, 0) heading +x on the entry leg.

    Going leg 3.5 m wide about y = 0, cones every 5 m up to x = 10; a half turn about
    (10, c), c = (gap + 3.5) / 2, with no inner cone between the legs' ends (their inner
    boundaries are ``gap_m`` apart, one cone spacing) and three outer ones; the return leg
    along -x. Mapped: the going leg (driven) and the rest where it is not behind the car.
    Returns ``(cones, pose)``; true left boundary: the inner one, right: the outer one."""
    c = (gap_m + WIDTH_M) / 2
    sides = []
    for r, n_arc in ((gap_m / 2, 0), (gap_m / 2 + WIDTH_M, 3)):
        xs = np.arange(10.0, -20.0, -spacing_m)[::-1]
        a = np.linspace(-np.pi / 2, np.pi / 2, n_arc + 2)[1:]
        back = np.arange(10.0 - spacing_m, -20.0, -spacing_m)
        side = np.vstack([np.column_stack([xs, np.full(xs.size, c - r)]),
                          np.column_stack([10.0 + r * np.cos(a), c + r * np.sin(a)]),
                          np.column_stack([back, np.full(back.size, c + r)])])
        sides.append(side[(side[:, 1] < c) | (side[:, 0] >= car_x)])
    return np.vstack(sides), Pose(car_x, 0.0, 0.0)


@pytest.mark.parametrize("method", METHODS)
@pytest.mark.parametrize("gap_m, car_x", [(4.0, 6.5), (4.0, 7.5), (3.0, 7.0)])
def test_hairpin_entry_lane_does_not_run_back_behind_the_car(method, gap_m, car_x):
    """No cone after a side's first lies behind the car (car frame x < 0). Before the fix CLC
    returned the approach reversed here, from the cone ahead back along the legs behind."""
    cones, pose = hairpin(gap_m, car_x)
    lane = solve_lane(cones, pose, method=method)
    assert lane.ok, lane.message
    for xy in (lane.left_xy, lane.right_xy):
        x = pose.to_local(xy)[:, 0]
        assert (x[1:] >= 0).all(), x

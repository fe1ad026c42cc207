"""The shared insertion rule (``rld.insertion``) and CLC's far insertions
(``clc.refine.far_insertions``), on hand-built lanes."""

from __future__ import annotations

import numpy as np
import pytest

from clc.refine import far_insertions
from rld.costs import lane_cost
from rld.insertion import boundary_edges, insert_cones, insertion_delta
from rld.types import LaneParams, Pose

P = LaneParams()
#: Two straight boundaries 4 m apart, cones 3.5 m apart from x = 0 to 42 m: 13 a side.
XS = np.arange(0.0, 42.5, 3.5)
LEFT = np.column_stack([XS, np.full(XS.size, 2.0)])
RIGHT = np.column_stack([XS, np.full(XS.size, -2.0)])


def _lane_without(k: int, extra):
    """Points: left, right, then ``extra`` cones; the left side skips its cone ``k``."""
    pts = np.vstack([LEFT, RIGHT, np.asarray(extra, dtype=float).reshape(-1, 2)])
    n = XS.size
    left = np.array([i for i in range(n) if i != k])
    right = np.arange(n, 2 * n)
    return pts, left, right


def test_boundary_edges_with_and_without_the_closing_edge():
    assert boundary_edges(np.array([3, 5, 7])).tolist() == [[3, 5], [5, 7]]
    assert boundary_edges(np.array([3, 5, 7]), closed=True).tolist() == [[3, 5], [5, 7], [7, 3]]


def test_the_delta_is_the_objective_change_of_the_whole_boundary():
    # Hand-checked against lane_cost of the whole open boundary with and without the cone.
    pts, left, right = _lane_without(5, [])
    i = int(np.flatnonzero(left == 4)[0])
    edges = np.vstack([boundary_edges(left), boundary_edges(right)])
    delta = insertion_delta(pts, left, i, 5, edges, P)
    with_c = np.insert(left, i + 1, 5)
    whole = (lane_cost(pts, with_c, [], Pose(0, 0, 0), P, heading=False)
             - lane_cost(pts, left, [], Pose(0, 0, 0), P, heading=False))
    assert delta == pytest.approx(whole)
    assert delta < 0  # a 7 m edge split into two 3.5 m edges on a straight line


def test_a_skipped_cone_on_the_line_is_inserted_and_a_far_one_is_not():
    pts, left, right = _lane_without(5, [[17.5, 4.0]])  # cone 26: 2 m outside the left line
    (new_left, new_right), n = insert_cones(pts, (left, right), np.array([5, 26]), P)
    assert n == 1 and new_left.tolist() == list(range(XS.size)) and new_right.tolist() == \
        right.tolist()


def test_a_cone_that_would_pinch_the_lane_is_not_inserted():
    # A cone 1.6 m inside the left line beside a gap: joining it would bring the left
    # boundary within 2.5 m (min_width_m) of a right edge's interior (2.4 m).
    pts, left, right = _lane_without(5, [[15.75, 0.4]])
    i = int(np.flatnonzero(left == 4)[0])
    edges = np.vstack([boundary_edges(left), boundary_edges(right)])
    assert insertion_delta(pts, left, i, 26, edges, P) is None
    (_, _), n = insert_cones(pts, (left, right), np.array([26]), P)
    assert n == 0


def test_far_insertions_leave_the_first_reach_alone():
    # The left side skips cone 3 (10.5 m along) and cone 10 (35 m along): with a reach of 25 m
    # only the far one is inserted; with 5 m both.
    pts = np.vstack([LEFT, RIGHT])
    n = XS.size
    left = np.array([i for i in range(n) if i not in (3, 10)])
    right = np.arange(n, 2 * n)
    L, R, k = far_insertions(pts, P, left, right, closed=False, reach_m=25.0)
    assert k == 1 and 10 in L and 3 not in L and R.tolist() == right.tolist()
    L, R, k = far_insertions(pts, P, left, right, closed=False, reach_m=5.0)
    assert k == 2 and L.tolist() == list(range(n))

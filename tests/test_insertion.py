"""The shared insertion rule (``rld.insertion``) and CLC's far insertions
(``clc.refine.far_insertions``), on hand-built lanes."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clc.refine import far_insertions
from rld import geometry as geo
from rld.costs import boundary_color_cost, lane_cost
from rld.insertion import (
    _objective_deltas,
    beside,
    boundary_edges,
    insert_cones,
    insertion_delta,
)
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


def _window_delta(pts, S, i, c, p, closed, colors):
    """The objective change as the rule defined it before its kernel: ``lane_cost`` (and the
    colour cost) of the cones i - 1 .. i + 2 about the edge with and without ``c``; None past
    the turn limit."""
    n, no_pose = S.size, Pose(0.0, 0.0, 0.0)
    idx = [(i + k) % n if closed else i + k for k in (-1, 0, 1, 2)]
    local = S[idx if closed else [j for j in idx if 0 <= j < n]]
    with_c = np.insert(local, int(np.flatnonzero(local == S[i])[0]) + 1, c)
    if np.any(np.abs(geo.polyline_turn_angles(pts[with_c])) > p.max_turn_angle_rad):
        return None
    delta = lane_cost(pts, with_c, [], no_pose, p, heading=False) - \
        lane_cost(pts, local, [], no_pose, p, heading=False)
    if colors is not None:
        delta += p.w_color * (
            boundary_color_cost(pts, colors, with_c, no_pose, -1.0, unknown=p.color_unknown)
            - boundary_color_cost(pts, colors, local, no_pose, -1.0, unknown=p.color_unknown))
    return delta


@settings(max_examples=300)
@given(seed=st.integers(0, 2**32 - 1), n=st.integers(2, 9), closed=st.booleans(),
       colored=st.booleans(), regular=st.booleans(), bent=st.floats(0.0, 0.6))
def test_the_compiled_delta_is_the_lane_cost_difference(seed, n, closed, colored, regular,
                                                        bent):
    # A boundary along a bent line with jitter (or a ring), a cone near one of its edges.
    rng = np.random.default_rng(seed)
    p = LaneParams(w_regularity=0.3 if regular else 0.0)
    if closed:
        n = max(n, 2)
        ang = np.sort(rng.uniform(0, 2 * np.pi, n))
        S_xy = 12.0 * np.column_stack([np.cos(ang), np.sin(ang)])
    else:
        heading = np.cumsum(rng.normal(0.0, bent, n))
        S_xy = np.cumsum(3.5 * np.column_stack([np.cos(heading), np.sin(heading)]), axis=0)
    S_xy = S_xy + rng.normal(0.0, 0.3, S_xy.shape)
    i = int(rng.integers(0, n if closed else n - 1))
    a, b = S_xy[i], S_xy[(i + 1) % n]
    c_xy = a + rng.uniform(0.1, 0.9) * (b - a) + rng.normal(0.0, 1.0, 2)
    pts = np.vstack([S_xy, c_xy, rng.uniform(-20, 20, (3, 2))])
    order = rng.permutation(pts.shape[0])  # cone numbers need not follow the boundary
    pts = pts[np.argsort(order)]
    S, c = order[:n], int(order[n])
    colors = rng.integers(0, 4, pts.shape[0]) if colored else None
    delta, ok = _objective_deltas(pts, [S[::-1].copy(), S], np.array([1]), np.array([i]),
                                  np.array([c]), p, closed, colors)
    want = _window_delta(pts, S, i, c, p, closed, colors)
    assert bool(ok[0]) == (want is not None)
    if want is None:
        return
    assert delta[0] == want  # the same floats, not only close
    if n >= (4 if closed else 2):  # the window holds every term the insertion changes
        no_pose = Pose(0.0, 0.0, 0.0)
        whole = (lane_cost(pts, np.insert(S, i + 1, c), [], no_pose, p, closed=closed,
                           colors=colors, heading=False)
                 - lane_cost(pts, S, [], no_pose, p, closed=closed, colors=colors,
                             heading=False))
        assert delta[0] == pytest.approx(whole, rel=1e-9, abs=1e-9)


@given(seed=st.integers(0, 2**32 - 1))
def test_beside_is_the_foot_and_distance_test(seed):
    # Cones scattered about a few edges: the kernel against segment_parameter and
    # point_segment_distance broadcast, and against the allowed mask.
    rng = np.random.default_rng(seed)
    pts = rng.uniform(0.0, 10.0, (12, 2))
    cones, edges = np.arange(6), rng.integers(6, 12, (5, 2))
    p, a, b = pts[cones][:, None], pts[edges[:, 0]][None], pts[edges[:, 1]][None]
    t = geo.segment_parameter(p, a, b)
    want = (t > 0) & (t < 1) & (geo.point_segment_distance(p, a, b) < 1.25)
    assert np.array_equal(beside(pts, cones, edges, 1.25), want)
    allowed = rng.random(5) < 0.5
    assert np.array_equal(beside(pts, cones, edges, 1.25, allowed), want & allowed)

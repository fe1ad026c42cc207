import itertools
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from shapely.geometry import LineString, Point

from rld import constraints as C
from rld import geometry as geo
from rld.types import LaneParams, Pose

CAR = Pose(0.0, 0.0, 0.0)


def random_points(seed, n, size=15.0):
    return np.random.default_rng(seed).uniform(0, size, size=(n, 2))


# --- candidate edges ------------------------------------------------------------------------


def test_candidate_edges_hand_worked():
    pts = np.array([[0, 0], [2, 0], [4, 0], [10, 0], [4, 3]], float)
    e = C.candidate_edges(pts, 3.0)
    assert e.tolist() == [[0, 1], [1, 2], [2, 4]]
    # The limit is inclusive: distance exactly 3 counts.
    assert [2, 4] in e.tolist()


@settings(max_examples=60)
@given(st.integers(0, 10_000), st.integers(2, 40), st.floats(0.5, 8.0))
def test_candidate_edges_match_brute_force(seed, n, spacing):
    pts = random_points(seed, n)
    brute = [
        [i, j]
        for i, j in itertools.combinations(range(n), 2)
        if math.dist(pts[i], pts[j]) <= spacing
    ]
    assert C.candidate_edges(pts, spacing).tolist() == brute


# --- pairwise width conflicts (RLD eqs 6-8) and crossings -------------------------------------


def test_width_conflicts_hand_worked():
    pts = np.array(
        [
            [0, 0], [4, 0],  # edge 0: left boundary
            [0, 2], [4, 2],  # edge 1: 2 m away, parallel -> too narrow (End = 0)
            [0, 3], [4, 3],  # edge 2: 3 m away -> wide enough
            [5, 0], [8, 0],  # edge 3: same side, end to end with edge 0 (1 m gap, End = 1)
        ],
        float,
    )
    edges = np.array([[0, 1], [2, 3], [4, 5], [6, 7]])
    got = {tuple(p) for p in C.width_conflicts(pts, edges, 2.5).tolist()}
    # 0-1 too narrow; 1-2 are 1 m apart and parallel; 1-3 closest end to end ((4,2)-(5,0)).
    assert got == {(0, 1), (1, 2)}


def test_width_conflict_needs_interior_closeness():
    # A perpendicular approach: the end of one edge 1 m from the middle of the other.
    pts = np.array([[0, 0], [4, 0], [2, 1], [2, 4]], float)
    edges = np.array([[0, 1], [2, 3]])
    assert C.width_conflicts(pts, edges, 2.5).tolist() == [[0, 1]]
    # Edges sharing a cone never conflict (they are consecutive on one side).
    pts = np.array([[0, 0], [4, 0], [4, 1]], float)
    assert C.width_conflicts(pts, np.array([[0, 1], [1, 2]]), 2.5).shape == (0, 2)


def _brute_pairs(pts, edges, predicate):
    out = []
    for e, f in itertools.combinations(range(len(edges)), 2):
        if set(edges[e].tolist()) & set(edges[f].tolist()):
            continue
        if predicate(pts[edges[e]], pts[edges[f]]):
            out.append([e, f])
    return out


@settings(max_examples=40)
@given(st.integers(0, 10_000), st.integers(4, 25))
def test_width_conflicts_and_crossings_match_brute_force(seed, n):
    pts = random_points(seed, n)
    edges = C.candidate_edges(pts, 5.5)

    def narrow(a, b):
        d, end = geo.segment_distance_end(a[0], a[1], b[0], b[1])
        return bool(d < 2.5 and not end)

    def crossing(a, b):
        return LineString(a).intersects(LineString(b))

    assert C.width_conflicts(pts, edges, 2.5).tolist() == _brute_pairs(pts, edges, narrow)
    assert C.crossing_edge_pairs(pts, edges).tolist() == _brute_pairs(pts, edges, crossing)


# --- heading mask (eq. 9) and near-car mask (eq. 11) ------------------------------------------


def test_heading_mask_hand_worked():
    s30, c30 = math.sin(math.radians(30)), math.cos(math.radians(30))
    s60, c60 = math.sin(math.radians(60)), math.cos(math.radians(60))
    pts = np.array(
        [
            [-1, 2], [3, 2],  # parallel, 2 m away
            [1, 1], [1, 5],  # perpendicular
            [0, 10], [4, 10],  # parallel but 10 m away
            [0, -2], [3 * c30, -2 + 3 * s30],  # 30 degrees
            [0, -2], [3 * c60, -2 + 3 * s60],  # 60 degrees
            [3, -2], [-1, -2],  # parallel, pointing backwards: undirected, counts
        ],
        float,
    )
    edges = np.arange(12).reshape(6, 2)
    mask = C.heading_mask(pts, edges, CAR, radius_m=4.0, tolerance_rad=math.pi / 4)
    assert mask.tolist() == [True, False, False, True, False, True]


def test_near_car_mask():
    pts = np.array([[1, 1], [4.5, 0], [4.6, 0], [-3, -3]], float)
    assert C.near_car_mask(pts, CAR, 4.5).tolist() == [True, True, False, True]


# --- angle triples and the turn limit ---------------------------------------------------------


def test_angle_triples_hand_worked():
    # A right angle at cone 1: 0 -> 1 goes +x, 1 -> 2 goes +y (a left turn of pi/2).
    pts = np.array([[0, 0], [3, 0], [3, 3]], float)
    edges = C.candidate_edges(pts, 3.5)
    triples, turns = C.angle_triples(pts, edges)
    assert triples.tolist() == [[0, 1, 2, 0, 1]]
    assert turns[0] == pytest.approx(math.pi / 2)
    assert C.turn_within_limit(turns, math.pi / 2).tolist() == [True]  # closed limit
    assert C.turn_within_limit(turns, math.pi / 2 - 1e-6).tolist() == [False]


@settings(max_examples=40)
@given(st.integers(0, 10_000), st.integers(3, 20))
def test_angle_triples_match_brute_force(seed, n):
    pts = random_points(seed, n, size=10.0)
    edges = C.candidate_edges(pts, 5.0)
    eid = {tuple(e): k for k, e in enumerate(edges.tolist())}
    brute = set()
    for j in range(n):
        nb = sorted({b if a == j else a for a, b in eid if j in (a, b)})
        for i, k in itertools.combinations(nb, 2):
            brute.add((i, j, k, eid[tuple(sorted((i, j)))], eid[tuple(sorted((j, k)))]))
    triples, turns = C.angle_triples(pts, edges)
    assert set(map(tuple, triples.tolist())) == brute
    assert len(triples) == len(brute)
    for (i, j, k, _, _), t in zip(triples, turns, strict=True):
        h1 = math.atan2(*(pts[j] - pts[i])[::-1])
        h2 = math.atan2(*(pts[k] - pts[j])[::-1])
        expect = (h2 - h1 + math.pi) % (2 * math.pi) - math.pi
        assert abs(abs(t) - abs(expect)) < 1e-9


# --- CLC predicates on whole path pairs -------------------------------------------------------


def test_c_seg():
    left = np.array([[0, 0], [3, 0], [3, 3]], float)  # 90 degree turn
    right = np.array([[0, -3], [3, -3]], float)
    assert C.c_seg(left, right, math.pi / 2)
    assert not C.c_seg(left, right, math.radians(80))
    sharp = np.array([[0, 0], [3, 0], [0, 1]], float)
    assert not C.c_seg(sharp, right, math.pi / 2)


def test_c_poly_open_and_closed():
    left = np.array([[0, 2], [4, 2], [8, 2]], float)
    right = np.array([[0, -2], [4, -2], [8, -2]], float)
    assert C.c_poly(left, right)
    crossing_right = np.array([[0, -2], [4, -2], [8, 3]], float)  # crosses the left boundary
    assert not C.c_poly(left, crossing_right)
    outer = np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], float)
    inner = outer * 0.5
    assert C.c_poly(outer, inner, closed=True)
    shifted = inner + [4.0, 0.0]  # pokes through the outer ring
    assert not C.c_poly(outer, shifted, closed=True)


def test_lane_widths_hand_worked():
    L = np.array([[0, 0], [4, 0]], float)
    R = np.array([[0, 3], [4, 3]], float)
    np.testing.assert_allclose(C.lane_widths(L, R), [3, 3, 3, 3, 3, 3])
    R1 = np.array([[2, 3]], float)
    # Left vertices to the right point: sqrt(2^2 + 3^2); left segment to it: 3; the right
    # vertex to the left line: 3; the right boundary has no segment.
    np.testing.assert_allclose(C.lane_widths(L, R1), [math.sqrt(13)] * 2 + [3, 3])
    assert not C.c_width(L, R1, 2.5, 3.5)
    assert C.c_width(L, R1, 2.5, 4.0)
    assert not C.c_width(L, R1, 3.1, 4.0)


@settings(max_examples=60)
@given(st.integers(0, 10_000), st.integers(1, 6), st.integers(1, 6))
def test_lane_widths_against_shapely(seed, nl, nr):
    rng = np.random.default_rng(seed)
    L = np.cumsum(rng.uniform(0.5, 3, size=(nl, 2)), axis=0)
    R = np.cumsum(rng.uniform(0.5, 3, size=(nr, 2)), axis=0) + [0, 4]
    w = C.lane_widths(L, R)

    def geom(xy):
        return Point(xy[0]) if len(xy) == 1 else LineString(xy)

    # The narrowest matching line is the distance between the chains; the widest one is the
    # farthest any vertex of one chain is from the other chain.
    assert w.min() == pytest.approx(geom(L).distance(geom(R)), abs=1e-9)
    far = max(
        max(Point(p).distance(geom(R)) for p in L), max(Point(p).distance(geom(L)) for p in R)
    )
    assert w.max() == pytest.approx(far, abs=1e-9)


def test_lane_is_feasible_checks_every_constraint():
    p = LaneParams()
    left = np.array([[0, 2], [4, 2], [8, 2]], float)
    right = np.array([[0, -1.5], [4, -1.5], [8, -1.5]], float)
    assert C.lane_is_feasible(left, right, p)
    assert not C.lane_is_feasible(left, right * [1, 0.26], p)  # 2.39 m: too narrow
    assert C.lane_is_feasible(left, right * [1, 0.34], p)  # 2.51 m: just wide enough
    assert not C.lane_is_feasible(left, right * [1, 3.1], p)  # 6.65 m: too wide
    far = np.array([[0, 2], [6, 2]], float)  # 6 m spacing
    assert not C.lane_is_feasible(far, right[:2], p)
    zigzag = np.array([[0, 2], [4, 2], [0, 2.5]], float)
    assert not C.lane_is_feasible(zigzag, right, p)


def test_find_starting_vertices():
    pts = np.array([[1, 2], [1, -2], [0.5, 2.5], [3, -1.5], [30, 0]], float)
    assert C.find_starting_vertices(pts, CAR, 4.5) == (0, 1)
    # Only cones on the left: no start pair.
    assert C.find_starting_vertices(pts[[0, 2]], CAR, 4.5) is None
    # Far from every cone.
    assert C.find_starting_vertices(pts, Pose(100, 100, 0), 4.5) is None

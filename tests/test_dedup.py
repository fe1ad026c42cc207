"""Duplicate cones (issue 42, item 7): ``rld.dedup.merge_duplicates`` and its use in
``LaneSolver.solve``.

The bug: with every cone of a map doubled, RLD's lane was about half as long (its 20-cone
window took ten cones twice, and its spacing cost excludes the 0-0.39 m edges between a cone
and its copy), measured 2026-12-06 on ``generate_track(100)``, R = 50 m, frame 20: 8 + 7
cones, 42.4 m of boundary, against 5 + 5 cones, 25.4 m (on the generator before issue 39:
10 + 10, 61.0 m against 5 + 5, 28.7 m); CLC kept its length but with 5 cm jitter zigzagged
through both copies (16 + 17 -> 20 + 23 cones, the earlier generator). Now duplicates are
merged first and the lanes agree.
"""

from __future__ import annotations

import math
from collections import Counter

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from rld import LaneSolver, LaneStatus, solve_lane
from rld.dedup import DUPLICATE_RADIUS_M, merge_duplicates
from rld.generator import generate_track
from rld.simulation import simulate_lap
from rld.types import Lane


def brute_force(points, radius, colors, confidence):
    """The groups by union-find over every pair at most ``radius`` apart, and the rules of the
    docstring written out: lowest index, majority of known labels (a tie: 0), largest
    confidence."""
    n = len(points)
    parent = list(range(n))

    def find(i):
        while parent[i] != i:
            i = parent[i]
        return i

    for i in range(n):
        for j in range(i + 1, n):
            if math.dist(points[i], points[j]) <= radius:
                parent[find(i)] = find(j)
    groups: dict[int, list[int]] = {}
    for i in range(n):
        groups.setdefault(find(i), []).append(i)
    out = []
    for members in sorted(groups.values(), key=min):
        votes = Counter(colors[m] for m in members if colors[m] != 0).most_common()
        label = 0 if not votes or (len(votes) > 1 and votes[0][1] == votes[1][1]) \
            else votes[0][0]
        out.append((min(members), label, max(confidence[m] for m in members)))
    return out


@settings(max_examples=200)
@given(
    st.lists(st.tuples(st.floats(-2.0, 2.0), st.floats(-2.0, 2.0)), min_size=1, max_size=40),
    st.floats(0.0, 1.0),
    st.data(),
)
def test_merge_matches_a_brute_force_grouping(pts, radius, data):
    n = len(pts)
    # No pair within rounding of the radius, where "at most" could go either way.
    assume(all(abs(math.dist(a, b) - radius) > 1e-9 for i, a in enumerate(pts)
               for b in pts[i + 1:]))
    colors = data.draw(st.lists(st.sampled_from([0, 1, 2]), min_size=n, max_size=n))
    conf = data.draw(st.lists(st.floats(0.0, 1.0), min_size=n, max_size=n))
    points = np.array(pts, dtype=np.float64)
    kept, keep, mc, mconf = merge_duplicates(points, radius, np.array(colors), np.array(conf))
    expected = brute_force(pts, radius, colors, conf)
    assert keep.tolist() == [e[0] for e in expected]
    np.testing.assert_array_equal(kept, points[keep])
    assert mc.tolist() == [e[1] for e in expected]
    assert mconf.tolist() == [e[2] for e in expected]


def test_colour_and_confidence_rules():
    # Five groups, far apart; each pair / triple within 0.1 m.
    base = np.array([[0.0, 0.0], [10.0, 0.0], [20.0, 0.0], [30.0, 0.0], [40.0, 0.0]])
    groups = [[0, 5], [1, 6], [2, 7], [3, 8, 10], [4, 9]]
    points = np.zeros((11, 2))
    for g, members in enumerate(groups):
        for k, m in enumerate(members):
            points[m] = base[g] + [0.05 * k, 0.0]
    colors = np.zeros(11, dtype=np.int64)
    colors[[0, 5]] = [1, 0]  # left beats unknown
    colors[[1, 6]] = [0, 2]  # right beats unknown, whichever comes first
    colors[[2, 7]] = [1, 2]  # a tie of known labels: unknown
    colors[[3, 8, 10]] = [2, 1, 2]  # the majority of the known ones
    colors[[4, 9]] = [0, 0]
    conf = np.linspace(0.1, 0.9, 11)
    kept, keep, mc, mconf = merge_duplicates(points, colors=colors, confidence=conf)
    assert keep.tolist() == [0, 1, 2, 3, 4]
    np.testing.assert_array_equal(kept, base)  # the lowest member's position, not the mean
    assert mc.tolist() == [1, 2, 0, 2, 0]
    np.testing.assert_allclose(mconf, [conf[5], conf[6], conf[7], conf[10], conf[9]])
    # No colours, no confidence: None back.
    assert merge_duplicates(points)[2:] == (None, None)


def test_nothing_is_merged_beyond_the_radius():
    # A grid 0.31 m apart: every neighbour just beyond 0.3 m.
    g = np.arange(6) * 0.31
    points = np.array([[x, y] for x in g for y in g])
    kept, keep, _, _ = merge_duplicates(points)
    assert keep.tolist() == list(range(len(points)))
    np.testing.assert_array_equal(kept, points)
    # Just inside: a chain of 0.29 m steps is one cone, even where its ends are farther apart.
    chain = np.column_stack([np.arange(5) * 0.29, np.zeros(5)])
    assert merge_duplicates(chain)[1].tolist() == [0]
    assert merge_duplicates(chain, radius_m=0.2)[1].tolist() == list(range(5))
    # radius 0: only coincident points.
    assert merge_duplicates(np.array([[0.0, 0.0], [0.0, 0.0], [0.0, 1e-6]]), 0.0)[1].tolist() \
        == [0, 2]
    with pytest.raises(ValueError, match="radius_m"):
        merge_duplicates(points, radius_m=-1.0)
    assert DUPLICATE_RADIUS_M == 0.3


# A straight lane 4 m wide, cones 3 m apart (as tests/test_api.py).
LEFT = np.column_stack([np.arange(0, 30, 3.0), np.full(10, 2.0)])
RIGHT = np.column_stack([np.arange(0, 30, 3.0), np.full(10, -2.0)])
CONES = np.vstack([LEFT, RIGHT])
POSE = (1.0, 0.0, 0.0)


def test_the_api_reports_no_merge_on_a_clean_map():
    lane = solve_lane(CONES, POSE)
    assert lane.ok and lane.stats["duplicates_merged"] == 0


def test_the_method_sees_merged_cones_colours_and_confidence(monkeypatch):
    solver = LaneSolver("rld")
    seen = {}

    def fake(points, pose, colors=None, time_limit_s=None, confidence=None):
        seen.update(points=points, colors=colors, confidence=confidence)
        # Merged cones: 0 and 1 the groups of the first left and right cone, then the rest.
        return Lane(cones=points, left=np.r_[0, 2:11], right=np.r_[1, 11:20],
                    status=LaneStatus.FEASIBLE, stats={"probe": 1})

    monkeypatch.setattr(solver._impl, "solve", fake)
    # Copies first, so the group's lowest index is the copy's: the lane reports it.
    copies = CONES[[0, 10]] + [[0.1, 0.0], [0.0, -0.1]]
    cones = np.vstack([copies, CONES])
    # Class codes (rld.colors): 0 unknown, 2 blue (left), 1 yellow (right).
    colors = np.r_[[0, 1], np.full(10, 2), np.ones(10, dtype=int)]
    conf = np.r_[[0.9, 0.1], np.full(20, 0.5)]
    lane = solver.solve(cones, POSE, colors=colors, confidence=conf)
    assert seen["points"].shape == (20, 2)
    # Cone 0 (the copy of the first left cone, unknown) took the left side of its original;
    # the first right cone and its copy agree on right (side labels: 1 left, 2 right).
    assert seen["colors"][:2].tolist() == [1, 2] and seen["colors"].size == 20
    assert seen["confidence"][:2].tolist() == [0.9, 0.5]
    assert lane.stats["duplicates_merged"] == 2 and lane.stats["probe"] == 1
    assert lane.cones.shape == (22, 2)
    np.testing.assert_array_equal(lane.cones, cones)
    # The lane indexes the caller's array: each group by its lowest index.
    assert lane.left.tolist() == [0] + list(range(3, 12))
    assert lane.right.tolist() == [1] + list(range(13, 22))
    np.testing.assert_array_equal(lane.left_xy[0], copies[0])


def test_fewer_than_four_distinct_cones_is_no_lane():
    cones = np.array([[0.0, 2.0], [0.05, 2.0], [0.0, -2.0], [0.1, -2.0], [3.0, 2.0]])
    lane = solve_lane(cones, POSE)
    assert lane.status is LaneStatus.NOT_FOUND and "3 distinct cones" in lane.message
    assert lane.stats["duplicates_merged"] == 2


LAP = simulate_lap(generate_track(100), range_m=50.0)


@pytest.mark.parametrize("method", ["rld", "clc"])
@pytest.mark.parametrize("copies", ["exact", "jitter", "exact-shuffled"])
def test_every_cone_doubled_gives_the_lane_of_the_single_map(method, copies):
    rng = np.random.default_rng(1)
    for k in (20, 60, 100):
        f = LAP.frame(k)
        n = f.cones.shape[0]
        # A generous budget: RLD's lanes are then proved optimal, not cut by the clock.
        single = LaneSolver(method).solve(f.cones, f.pose, time_limit_s=5.0)
        assert single.ok and single.stats["duplicates_merged"] == 0
        noise = rng.normal(0.0, 0.05, f.cones.shape) if copies == "jitter" else 0.0
        stacked = np.vstack([f.cones, f.cones + noise])
        # Originals first, or every cone and copy shuffled (exact copies only: the merged
        # position is then still the original's).
        perm = rng.permutation(2 * n) if copies == "exact-shuffled" else np.arange(2 * n)
        doubled = stacked[perm]
        lane = LaneSolver(method).solve(doubled, f.pose, time_limit_s=5.0)
        assert lane.stats["duplicates_merged"] == n
        assert lane.ok and lane.status == single.status
        for side, ref in ((lane.left, single.left), (lane.right, single.right)):
            # The same cones, in the same order, at the same positions ...
            assert (perm[side] % n).tolist() == ref.tolist()
            np.testing.assert_array_equal(doubled[side], f.cones[ref])
            # ... each reported by the lower of its two indices.
            twin = np.argsort(perm)[(perm[side] + n) % (2 * n)]
            assert np.all(side < twin)


def test_incremental_on_a_doubled_growing_map_keeps_the_single_maps_lane():
    """rld-incremental keeps its lane as positions between calls: the merged cones' positions
    (the originals', which come first) match the single map's, call after call."""
    rng = np.random.default_rng(2)
    one, two = LaneSolver("rld-incremental"), LaneSolver("rld-incremental")
    for k in range(0, 60, 2):
        f = LAP.frame(k)
        a = one.solve(f.cones, f.pose, time_limit_s=5.0)
        b = two.solve(np.vstack([f.cones, f.cones + rng.normal(0, 0.05, f.cones.shape)]),
                      f.pose, time_limit_s=5.0)
        assert a.status == b.status and a.left.tolist() == b.left.tolist()
        assert a.right.tolist() == b.right.tolist()
    assert one._impl.model.restarts == two._impl.model.restarts

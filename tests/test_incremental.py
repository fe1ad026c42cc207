"""Incremental RLD on a growing map (``rld.incremental``, ``method="rld-incremental"``)."""

from __future__ import annotations

import numpy as np
import pytest

from rld.api import LaneSolver
from rld.constraints import crossing_edge_pairs, width_conflicts
from rld.generator import generate_track
from rld.metrics import score_lane
from rld.program import build_program
from rld.simulation import simulate_lap
from rld.solver import RldModel
from rld.types import LaneParams, LaneStatus, Pose


def drive(seed: int = 100, fp_rate: float = 0.0, range_m: float = 50.0, poses=None,
          options=None):
    lap = simulate_lap(generate_track(seed), range_m=range_m, fp_rate=fp_rate, seed=0)
    solver = LaneSolver("rld-incremental", options=options)
    model = solver._impl.model
    for k in range(len(lap)) if poses is None else poses:
        f = lap.frame(k)
        lane = solver.solve(f.cones, f.pose)
        yield k, f, lane, model


def test_kept_lane_never_changes_except_by_a_counted_rollback_restart_or_insertion():
    prev = None
    checked = 0
    for _, _, _lane, model in drive(100):
        if model.left_xy is None:
            prev = None
            continue
        now = (model.left_xy.copy(), model.right_xy.copy(), model.restarts, model.rollbacks,
               model.insertions)
        if prev is not None and now[2:] == prev[2:]:
            for old, new in ((prev[0], now[0]), (prev[1], now[1])):
                # Everything but the released frontier is kept, cone for cone.
                keep = max(len(old) - model.frontier_cones, 0)
                if model.closed and len(new) == len(old):
                    keep = len(old)
                np.testing.assert_array_equal(new[:keep], old[:keep])
                checked += 1
        prev = now
    assert checked > 400


def test_clean_closed_track_ends_as_the_whole_loop():
    *_, (k, f, lane, model) = drive(100)
    assert lane.ok and lane.closed and model.closed
    assert model.restarts == 0
    track = generate_track(100)
    # The loop's cones are the track's boundaries, in their cyclic order.
    for side, true in ((lane.left, track.left), (lane.right, track.right)):
        src = f.source[side]
        assert sorted(src.tolist()) == sorted(true.tolist())
        start = true.tolist().index(src[0])
        rolled = np.roll(true, -start)
        assert np.array_equal(src, rolled) or np.array_equal(src, np.roll(rolled[::-1], 1))
    sc = score_lane(f, lane.left, lane.right, lane.ok, lane.closed)
    assert sc.category in ("gt", "near_gt")
    assert lane.stats["mode"] == "closed" and lane.stats["n_cones_used"] == 0  # frozen


def driven(poses):
    """A solver driven over ``poses`` of the clean lap of generated track 100: (lap, solver,
    last frame, last lane)."""
    lap = simulate_lap(generate_track(100), range_m=50.0, fp_rate=0.0, seed=0)
    solver = LaneSolver("rld-incremental")
    for k in poses:
        f = lap.frame(k)
        lane = solver.solve(f.cones, f.pose)
    return lap, solver, f, lane


def test_a_pose_jump_restarts():
    lap, solver, _, lane = driven(range(20, 30))
    assert lane.stats["restarts"] == 0 and lane.stats["mode"] == "extend"
    f = lap.frame(60)  # 30 m further on: a jump
    lane = solver.solve(f.cones, f.pose)
    assert lane.stats["restarts"] == 1
    assert lane.stats["restart_reason"] == "pose jump" and lane.stats["mode"] == "start"


def test_a_moved_cone_restarts():
    _, solver, f, lane = driven(range(20, 26))
    cones = f.cones.copy()
    cones[lane.left[0]] += [0.8, 0.0]  # a lane cone moved by more than 0.5 m
    lane = solver.solve(cones, f.pose)
    assert lane.stats["restart_reason"] == "a lane cone moved or vanished"


def test_frontier_program_stays_bounded_as_the_lane_grows():
    sizes, lengths = [], []
    for _, _, lane, model in drive(100):
        if lane.stats.get("mode") == "extend":
            sizes.append(lane.stats["n_cones_used"])
            lengths.append(lane.stats["lane_cones"])
            # The window counts the junction cones: never more than frontier_max_cones in all.
            assert sizes[-1] <= model.frontier_max_cones
            # The frontier program's own stats come with the lane (what the benchmark reads).
            fr = lane.stats["frontier"]
            assert fr["n_cones_used"] == sizes[-1] and fr["n_cols"] > 0 and fr["n_rows"] > 0
            assert 0.0 <= fr["solve_time_s"] < 60.0
    assert max(lengths) > 60  # the lane grew to the whole loop ...
    # ... while the frontier program never took more than its window plus the junction cones.
    assert max(sizes) <= LaneParams().max_cones + 4
    # ... over a lane more than three times as long as the frontier bound.
    assert model.frontier_max_cones == LaneParams().max_cones
    assert max(lengths) > 3 * model.frontier_max_cones


@pytest.mark.parametrize("bound", [
    12,
])
def test_a_smaller_frontier_window_bounds_the_program_and_the_lane_still_grows(bound):
    sizes, lengths = [], []
    for _, _, lane, model in drive(100, poses=range(100), options={"frontier_max_cones": bound}):
        assert model.frontier_max_cones == bound
        if lane.stats.get("mode") == "extend":
            sizes.append(lane.stats["n_cones_used"])
            lengths.append(lane.stats["lane_cones"])
    assert sizes and max(sizes) <= bound
    assert max(lengths) > 3 * bound


# Regression: build_program(start=...) once counted one fixed_start row for two (scalar bounds),
# and a small frontier window then crashed in scipy (seed 100, 20 % FP, pose 7).
def test_a_small_frontier_window_does_not_crash():
    for _ in drive(100, fp_rate=0.2, poses=range(12),
                   options={"frontier_max_cones": 8, "frontier_cones": 1}):
        pass


def test_a_frontier_window_with_no_room_to_grow_is_refused():
    # 4 junction cones + 2 x 3 released ones leave no free cone at 10: the lane could not grow
    # (measured before the check: at most 20 lane cones, a restart every few poses).
    with pytest.raises(ValueError, match="frontier_max_cones"):
        LaneSolver("rld-incremental", options={"frontier_max_cones": 10})


@pytest.mark.parametrize("fp_rate", [0.0, 0.2])
def test_lanes_follow_the_truth_on_generated_tracks(fp_rate):
    # Measured 2026-12-06 (R = 50 m, every pose after the first two, the generator of issue
    # 39): geometric critical at 1 m 0 of 371 poses at 0 % and 20 % false positives, at 0.5 m
    # 0 and 22 (5.9 %); the bounds leave a few poses of margin.
    scores = [score_lane(f, lane.left, lane.right, lane.ok, lane.closed)
              for k, f, lane, _ in drive(100, fp_rate=fp_rate) if k >= 2]
    n = len(scores)
    assert sum(s.critical_at(1.0) for s in scores) <= 0.01 * n
    assert sum(s.critical_at(0.5) for s in scores) <= (0.01 if fp_rate == 0 else 0.07) * n


# --- the whole kept lane stays a lane ------------------------------------------------------


def _kept_lane_edges(model):
    """The kept lane as a points array (left cones, then right cones) and its edges, with the
    closing edges once the lane is closed."""
    left, right = model.left_xy, model.right_xy
    pts = np.ascontiguousarray(np.vstack([left, right]), dtype=np.float64)
    edges = []
    for first, n in ((0, len(left)), (len(left), len(right))):
        seq = np.arange(first, first + n)
        if model.closed:
            seq = np.r_[seq, seq[:1]]
        edges.append(np.column_stack([seq[:-1], seq[1:]]))
    return pts, np.sort(np.vstack(edges), axis=1)


@pytest.mark.parametrize(("seed", "fp_rate"), [(100, 0.0), (100, 0.2), (2, 0.2)])
def test_the_whole_kept_lane_never_crosses_or_pinches_itself(seed, fp_rate):
    # Measured 2026-11-26 (R = 50 m, every pose): no crossing and no width conflict after any
    # call on tracks 0-7 and 100-101, at 0 and 20 % FP, in every mode. Track 2 at 20 % FP has
    # restarts (11) on the way, track 100 closes.
    modes = {"start": 0, "extend": 0, "closed": 0}
    p = LaneParams()
    for k, _, lane, model in drive(seed, fp_rate=fp_rate):
        if model.left_xy is None:
            continue
        mode = lane.stats.get("mode")
        modes[mode] += 1
        pts, edges = _kept_lane_edges(model)
        # Distinct cones: the two boundaries share none and no boundary repeats one.
        assert np.unique(pts, axis=0).shape[0] == pts.shape[0], (k, mode)
        cross = crossing_edge_pairs(pts, edges)
        assert cross.shape[0] == 0, (
            f"pose {k}, mode {mode}, restart {lane.stats.get('restart_reason')}: crossing "
            f"edges {edges[cross].tolist()}")
        narrow = width_conflicts(pts, edges, p.min_width_m)
        assert narrow.shape[0] == 0, (
            f"pose {k}, mode {mode}: edges closer than min_width {edges[narrow].tolist()}")
    assert modes["extend"] > 100 and modes["start"] >= 1
    if seed == 100:
        assert modes["closed"] > 50  # the closing edges are checked too


# --- options and restarts -------------------------------------------------------------------


@pytest.mark.parametrize("options", [
    {"frontier_cones": 0},
    {"frontier_cones": -2},
    {"frontier_max_cones": 3},
    {"frontier_max_cones": 5},
    {"max_rollbacks": -1},
    {"no_such_option": 1},
])
def test_invalid_options_are_rejected(options):
    with pytest.raises(ValueError):
        LaneSolver("rld-incremental", options=options)


def test_valid_options_are_kept():
    model = LaneSolver("rld-incremental", options={
        "frontier_cones": 1, "frontier_max_cones": 7, "max_rollbacks": 0})._impl.model
    assert (model.frontier_cones, model.frontier_max_cones, model.max_rollbacks) == (1, 7, 0)


def test_a_map_that_loses_cones_restarts():
    lap, solver, f, lane = driven(range(20, 26))
    model = solver._impl.model
    assert lane.stats["mode"] == "extend" and lane.stats["restarts"] == 0
    # Drop the map cone farthest from every kept lane cone: no lane cone is lost, only the
    # count shows that the map shrank.
    kept = np.vstack([model.left_xy, model.right_xy])
    d = np.hypot(*(f.cones[:, None, :] - kept[None, :, :]).transpose(2, 0, 1)).min(axis=1)
    assert d.max() > 1.0
    cones = np.delete(f.cones, int(np.argmax(d)), axis=0)
    lane = solver.solve(cones, f.pose)
    assert lane.stats["restart_reason"] == "the map lost cones"
    assert lane.stats["mode"] == "start" and lane.stats["restarts"] == 1
    # The next, full map is no loss against the shrunken one: the solver extends again.
    f = lap.frame(26)
    lane = solver.solve(f.cones, f.pose)
    assert lane.ok and lane.stats["mode"] == "extend" and lane.stats["restarts"] == 1
    assert "restart_reason" not in lane.stats


# --- the frontier program's fixed start (build_program(start=...)) --------------------------

# Regressions: the fixed_start rows were once added with scalar bounds, so only m[start[0]]
# had a row of its own and m[start[1]] joined the next family's first row (a crash with no row
# after it; a wrong optimum when it joined a far-endpoint row: 27 of 116 frames).


def test_a_fixed_start_is_one_row_per_near_endpoint():
    pts = np.array([[0, 2.3], [3.5, 2.3], [7, 2.3], [0, -2.3], [3.5, -2.3], [7, -2.3]], float)
    prog = build_program(pts, Pose(-1.0, 0.0, 0.0), LaneParams(), start=(0, 3))
    rows = np.flatnonzero(prog.family == "fixed_start")
    assert rows.size == 2
    m0 = prog.block("m").start
    for r, cone in zip(rows, (0, 3), strict=True):
        row = prog.A.getrow(r)
        assert row.indices.tolist() == [m0 + cone] and row.data.tolist() == [1.0]
        assert prog.row_lo[r] == prog.row_hi[r] == 1.0
    # The start cones' endpoint columns are in no row of the edge families (here the heading
    # row is the one that follows).
    for cone in (0, 3):
        touching = set(prog.family[prog.A[:, [m0 + cone]].nonzero()[0]].tolist())
        assert not touching & {"heading", "far_endpoints", "width_conflict", "crossing"}


def test_a_fixed_start_without_heading_on_a_small_window():
    # Two rows of three cones 4.6 m apart: no diagonals (5.8 m), no width conflict, no crossing
    # and no far pair, so nothing follows the fixed-start rows once the heading row is gone.
    pts = np.array([[0, 2.3], [3.5, 2.3], [7, 2.3], [0, -2.3], [3.5, -2.3], [7, -2.3]], float)
    lane = RldModel(LaneParams()).solve(pts, Pose(-1.0, 0.0, 0.0), start=(0, 3), heading=False)
    assert lane.status == LaneStatus.OPTIMAL
    assert lane.left.tolist() == [0, 1, 2] and lane.right.tolist() == [3, 4, 5]


def test_fixing_the_optimal_lanes_own_start_keeps_the_optimum():
    f = simulate_lap(generate_track(100), range_m=50.0, fp_rate=0.2, seed=0).frame(21)
    p = LaneParams()
    free = RldModel(p, warm_start=False).solve(f.cones, f.pose, time_limit_s=5.0)
    assert free.status == LaneStatus.OPTIMAL
    start = (int(free.left[0]), int(free.right[0]))
    fixed = RldModel(p, warm_start=False).solve(f.cones, f.pose, time_limit_s=5.0, start=start)
    assert fixed.status == LaneStatus.OPTIMAL
    assert fixed.cost == pytest.approx(free.cost, abs=1e-6)


def test_a_cone_seen_late_beside_a_kept_edge_is_inserted():
    # A straight lane, cones 2.5 m apart; the left cone at x = 5 is missing from the first map
    # (seen late), so the kept lane bridges the 5 m gap. When it appears, it joins the lane
    # between its neighbours (a counted insertion), and nothing else changes.
    xs = np.arange(0.0, 40.0, 2.5)
    left = np.column_stack([xs, np.full(xs.size, 2.0)])
    right = np.column_stack([xs, np.full(xs.size, -2.0)])
    late = int(np.flatnonzero(xs == 5.0)[0])
    first = np.vstack([np.delete(left, late, axis=0), right])
    pose = (-1.0, 0.0, 0.0)
    solver = LaneSolver("rld-incremental")
    lane = solver.solve(first, pose)
    assert lane.ok and lane.stats["mode"] == "start"
    assert not np.any(np.all(np.isclose(lane.left_xy, [5.0, 2.0]), axis=1))
    second = np.vstack([first, left[late]])
    lane = solver.solve(second, pose)
    assert lane.ok and lane.stats["insertions"] == 1
    xy = lane.left_xy
    k = int(np.flatnonzero(np.all(np.isclose(xy, [5.0, 2.0]), axis=1))[0])
    np.testing.assert_allclose(xy[k - 1:k + 2, 0], [2.5, 5.0, 7.5])

"""Chained windows inside one ``rld`` call (``LaneParams.max_windows``,
``rld.incremental.IncrementalRld.chain``): hand-built tracks whose whole lane is known."""

from __future__ import annotations

import math
import time

import numpy as np
import pytest

from rld.api import LaneSolver, solve_lane
from rld.solver import RldModel
from rld.types import LaneParams, LaneStatus, Pose

SPACING_M = 3.5
CAR = Pose(0.0, 0.0, 0.0)
CHAINED = LaneParams(max_windows=30)


def straight(length_m: float = 150.0, half_width_m: float = 2.0) -> tuple[np.ndarray, int]:
    """Two parallel boundaries along +x from x = 0.5 m, a cone every 3.5 m: left cones first
    (y = +half_width_m), then the right ones; returns (cones, cones per side)."""
    x = np.arange(0.5, length_m, SPACING_M)
    left = np.column_stack([x, np.full(x.size, half_width_m)])
    right = np.column_stack([x, np.full(x.size, -half_width_m)])
    return np.vstack([left, right]), x.size


def bend(radius_m: float = 30.0, sweep_rad: float = 1.5 * math.pi,
         half_width_m: float = 2.0) -> tuple[np.ndarray, int, int, Pose]:
    """A left-hand arc about (0, radius_m) from the origin (the car, heading +x), then 30 m
    straight on: boundaries at radius_m -/+ half_width_m, cones about 3.5 m apart along each.
    Returns (cones: left then right, left count, right count, the car's pose)."""
    sides = []
    for r in (radius_m - half_width_m, radius_m + half_width_m):
        n = int(round(r * sweep_rad / SPACING_M))
        t = np.linspace(0.0, sweep_rad, n + 1)[:-1] + 0.5 / r  # the first cone 0.5 m ahead
        arc = np.column_stack([r * np.sin(t), radius_m - r * np.cos(t)])
        # Straight on from the last arc cone along its tangent, at the arc's spacing.
        tangent = np.array([math.cos(t[-1]), math.sin(t[-1])])
        step = r * (t[1] - t[0])
        on = arc[-1] + np.outer(np.arange(1, int(30.0 / step) + 1) * step, tangent)
        sides.append(np.vstack([arc, on]))
    return np.vstack(sides), len(sides[0]), len(sides[1]), CAR


def test_the_chained_lane_is_the_whole_straight_cone_for_cone():
    cones, n = straight()
    lane = solve_lane(cones, CAR, params=CHAINED, time_limit_s=5.0)
    assert lane.ok and not lane.closed
    np.testing.assert_array_equal(lane.left, np.arange(n))
    np.testing.assert_array_equal(lane.right, np.arange(n, 2 * n))
    assert lane.stats["chain"]["stop"] in ("no growth", "no frontier")
    assert lane.stats["chain"]["added_cones"] == 2 * n - 20  # beyond the car's window
    # The car's window alone (the paper's RLD) sees its 20 nearest cones: 10 a side.
    one = solve_lane(cones, CAR, params=LaneParams(max_windows=1), time_limit_s=5.0)
    np.testing.assert_array_equal(one.left, np.arange(10))
    np.testing.assert_array_equal(one.right, np.arange(n, n + 10))
    assert "chain" not in one.stats


def test_a_car_window_of_four_cones_a_side_still_chains():
    # Left cones 1.3 m apart, right 5.4 m: the car's 20-cone window holds 16 left and 4 right,
    # fewer than the 3 released plus the 2 junction cones; the chain keeps the right side's
    # first two and re-solves the rest, and reaches the end of both sides.
    xl, xr = np.arange(0.5, 150.0, 1.3), np.arange(0.5, 150.0, 5.4)
    cones = np.vstack([np.column_stack([xl, np.full(xl.size, 2.0)]),
                       np.column_stack([xr, np.full(xr.size, -2.0)])])
    one = solve_lane(cones, CAR, params=LaneParams(max_windows=1), time_limit_s=5.0)
    assert (one.left.size, one.right.size) == (16, 4)
    lane = solve_lane(cones, CAR, params=CHAINED, time_limit_s=10.0)
    np.testing.assert_array_equal(lane.left, np.arange(xl.size))
    np.testing.assert_array_equal(lane.right, np.arange(xl.size, xl.size + xr.size))


def test_the_chained_lane_is_the_whole_bend_cone_for_cone():
    cones, nl, nr, pose = bend()
    lane = solve_lane(cones, pose, params=CHAINED, time_limit_s=5.0)
    assert lane.ok
    np.testing.assert_array_equal(lane.left, np.arange(nl))
    np.testing.assert_array_equal(lane.right, np.arange(nl, nl + nr))


def ring() -> tuple[np.ndarray, int]:
    """Two concentric circles about (0, 27), radii 25 and 29 m, a cone about every 3.5 m: the
    car at the origin heading +x, the inner ring on its left. Returns (cones: inner then
    outer, inner count)."""
    sides = []
    for r in (25.0, 29.0):
        n = int(round(2 * math.pi * r / SPACING_M))
        t = np.arange(n) * 2 * math.pi / n + 0.5 / r
        sides.append(np.column_stack([r * np.sin(t), 27.0 - r * np.cos(t)]))
    return np.vstack(sides), len(sides[0])


def test_a_ring_closes_into_the_whole_loop():
    cones, nl = ring()
    lane = solve_lane(cones, CAR, params=CHAINED, time_limit_s=5.0)
    assert lane.ok and lane.closed and lane.stats["chain"]["stop"] == "closed"
    # Each side is its whole ring, in order, from the cone nearest the car.
    np.testing.assert_array_equal(lane.left, np.arange(nl))
    np.testing.assert_array_equal(lane.right, np.arange(nl, cones.shape[0]))


def test_max_windows_one_is_the_car_window_model_itself():
    cones, _ = straight(60.0)
    lane = solve_lane(cones, CAR, params=LaneParams(max_windows=1), time_limit_s=5.0)
    own = RldModel(LaneParams()).solve(cones, CAR, time_limit_s=5.0)
    np.testing.assert_array_equal(lane.left, own.left)
    np.testing.assert_array_equal(lane.right, own.right)
    assert lane.status is own.status and lane.cost == own.cost


def test_the_window_limit_stops_the_chain():
    cones, n = straight()
    lane = solve_lane(cones, CAR, params=LaneParams(max_windows=3), time_limit_s=5.0)
    chain = lane.stats["chain"]
    assert chain["stop"] == "window limit" and chain["windows"] == 3
    assert 20 < lane.left.size + lane.right.size < 2 * n
    np.testing.assert_array_equal(lane.left, np.arange(lane.left.size))  # a prefix of the truth


def test_the_time_budget_stops_the_chain_and_is_honoured():
    cones, n = straight(400.0)
    solver = LaneSolver("rld", params=LaneParams(max_windows=1000))
    # Set-up and compilation apart, on a map 1 km away: the call below does not keep its chain.
    solver.solve(cones + [0.0, 1000.0], Pose(0.0, 1000.0, 0.0), time_limit_s=5.0)
    budget = 0.08
    t0 = time.perf_counter()
    lane = solver.solve(cones, CAR, time_limit_s=budget)
    elapsed = time.perf_counter() - t0
    assert lane.ok and lane.stats["chain"]["stop"] == "time budget"
    assert lane.left.size < n  # 114 cones a side: more windows than the budget holds
    # The next window starts only when the longest so far still fits: at most the model
    # update and extraction of one window over (a generous margin for a loaded machine).
    assert elapsed < budget + 0.05


@pytest.mark.parametrize("bad", [
    np.array([[0.0, 1.0], [np.nan, 2.0], [3.0, 1.0], [3.0, -1.0]]),
    np.zeros((3, 2)),
    np.zeros((5, 3)),
])
def test_bad_input_is_refused_as_before(bad):
    for w in (1, 30):
        with pytest.raises(ValueError):
            solve_lane(bad, CAR, params=LaneParams(max_windows=w))


def test_no_lane_is_reported_as_by_the_single_window():
    cones, _ = straight(60.0)
    far = cones + np.array([40.0, 0.0])  # no cone within near_radius_m or start_reach_m
    lanes = [solve_lane(far, CAR, params=LaneParams(max_windows=w)) for w in (1, 30)]
    assert all(not lane.ok for lane in lanes)
    assert lanes[0].status is lanes[1].status is LaneStatus.NOT_FOUND
    assert lanes[0].message == lanes[1].message


def test_the_default_rld_is_chained():
    cones, n = straight()
    lane = solve_lane(cones, CAR, time_limit_s=5.0)
    assert LaneParams().max_windows == CHAINED.max_windows
    np.testing.assert_array_equal(lane.left, np.arange(n))


def test_max_windows_below_one_is_refused():
    with pytest.raises(ValueError, match="max_windows"):
        LaneParams(max_windows=0)


def _same(a, b) -> None:
    np.testing.assert_array_equal(a.left, b.left)
    np.testing.assert_array_equal(a.right, b.right)
    assert a.closed == b.closed


def test_a_reused_solver_keeps_its_chain_and_returns_the_stateless_lane():
    cones, n = straight()
    solver = LaneSolver("rld")
    first = solver.solve(cones, CAR, time_limit_s=5.0)
    assert first.stats["chain"]["kept_cones"] == 0  # nothing kept yet
    pose = Pose(2.0, 0.0, 0.0)
    lane = solver.solve(cones, pose, time_limit_s=5.0)
    chain = lane.stats["chain"]
    # The car's window re-solved, the rest re-attached; the kept end did not extend before,
    # on the same map it is not tried again.
    assert chain["kept_cones"] == 2 * n - 20 and chain["steps"] == 0 and not chain["cut"]
    assert chain["stop"] == first.stats["chain"]["stop"]
    _same(lane, solve_lane(cones, pose, time_limit_s=5.0))
    # From the car forward: the first cone a side (x = 0.5 m) is behind the car at x = 2 m.
    np.testing.assert_array_equal(lane.left, np.arange(1, n))
    assert chain["behind"] == 2 and solver._impl.kept.left_xy.shape[0] == n  # kept whole


def test_new_cones_near_the_kept_tail_cut_it_and_the_chain_grows_on():
    cones, n = straight()
    short = np.r_[0:n - 6, n:2 * n - 6]  # the last six cones a side not yet seen
    solver = LaneSolver("rld")
    first = solver.solve(cones[short], CAR, time_limit_s=5.0)
    assert first.left.size == n - 6
    pose = Pose(1.0, 0.0, 0.0)
    lane = solver.solve(cones, pose, time_limit_s=5.0)
    chain = lane.stats["chain"]
    assert chain["cut"] and chain["steps"] >= 1 and 0 < chain["kept_cones"] < 2 * (n - 6) - 20
    _same(lane, solve_lane(cones, pose, time_limit_s=5.0))
    np.testing.assert_array_equal(lane.right, np.arange(n + 1, 2 * n))  # from the car forward


def test_a_cone_gone_near_the_kept_tail_cuts_it_too():
    cones, n = straight()
    extra = np.vstack([cones, [[120.0, 6.5]]])  # a false positive 4.5 m beside the left side
    solver = LaneSolver("rld")
    first = solver.solve(extra, CAR, time_limit_s=5.0)
    np.testing.assert_array_equal(first.left, np.arange(n))  # the lane never took it
    pose = Pose(1.0, 0.0, 0.0)
    lane = solver.solve(cones, pose, time_limit_s=5.0)  # the map lost it
    assert lane.stats["chain"]["cut"] and lane.stats["chain"]["steps"] >= 1
    _same(lane, solve_lane(cones, pose, time_limit_s=5.0))


def test_a_pose_jump_forgets_the_chain():
    cones, _ = straight()
    solver = LaneSolver("rld")
    solver.solve(cones, CAR, time_limit_s=5.0)
    far = Pose(40.0, 0.0, 0.0)
    lane = solver.solve(cones, far, time_limit_s=5.0)
    assert lane.stats["chain"]["not_kept"] == "pose jump"
    _same(lane, solve_lane(cones, far, time_limit_s=5.0))


def test_a_kept_ring_stays_closed_and_runs_from_the_car():
    cones, _ = ring()
    solver = LaneSolver("rld")
    assert solver.solve(cones, CAR, time_limit_s=5.0).closed
    a = 4.0 / 27.0  # 4 m on along the centre line
    pose = Pose(27.0 * math.sin(a), 27.0 - 27.0 * math.cos(a), a)
    lane = solver.solve(cones, pose, time_limit_s=5.0)
    assert lane.closed and lane.stats["chain"]["kept_cones"] == cones.shape[0]
    _same(lane, solve_lane(cones, pose, time_limit_s=5.0))
    assert lane.left[0] != 0  # from the car: the ring rolled on


def test_a_lane_is_short_when_a_side_stays_within_20_m_of_the_car():
    from rld.incremental import IncrementalRld
    from rld.types import Lane

    cones, n = straight(60.0)

    def lane(k_left, k_right, closed=False):
        return Lane(cones=cones, left=np.arange(k_left), right=n + np.arange(k_right),
                    status=LaneStatus.OPTIMAL, closed=closed)

    short = IncrementalRld.short
    assert short(cones, CAR, lane(3, 3))  # both end at x = 7.5 m
    assert short(cones, CAR, lane(10, 3))  # one side does
    assert not short(cones, CAR, lane(10, 10))  # both reach x = 32 m
    assert not short(cones, CAR, lane(3, 3, closed=True))
    assert short(cones, CAR, Lane.not_found(cones, "none"))
    near, m = straight(15.0)  # no cone beyond 20 m: nothing to reach
    assert not short(near, CAR, Lane(cones=near, left=np.arange(2), right=m + np.arange(2),
                                     status=LaneStatus.OPTIMAL))


def test_a_short_lane_gives_way_to_the_wider_windows_lane_and_a_whole_one_does_not():
    from rld.types import Lane

    cones, n = straight(150.0)
    solver = LaneSolver("rld", params=CHAINED)
    method = solver._impl
    short = Lane(cones=cones, left=np.arange(3), right=n + np.arange(3),
                 status=LaneStatus.OPTIMAL)
    lane = method._retry(cones, CAR, short, time.perf_counter(), 5.0, None, None)
    assert lane.stats.get("retry") and lane.left.size > 10 and lane.right.size > 10
    np.testing.assert_array_equal(lane.left, np.arange(lane.left.size))  # the truth's prefix
    whole = solver.solve(cones, CAR, time_limit_s=5.0)
    assert "retry" not in whole.stats and whole.left.size == n
    assert method._retry(cones, CAR, whole, time.perf_counter(), 5.0, None, None) is whole


def _no_window_lane(monkeypatch) -> None:
    """Every RLD window program (the car's and the retry's) gives no lane."""
    from rld.types import Lane

    monkeypatch.setattr(RldModel, "solve",
                        lambda self, points, pose, **kw: Lane.not_found(points, "forced"))


def test_a_call_whose_windows_give_no_lane_holds_the_last_chain(monkeypatch):
    cones, n = straight()
    solver = LaneSolver("rld")
    assert solver.solve(cones, CAR, time_limit_s=5.0).left.size == n
    pose = Pose(2.0, 0.0, 0.0)
    with monkeypatch.context() as m:
        _no_window_lane(m)
        lane = solver.solve(cones, pose, time_limit_s=5.0)
    assert lane.ok and lane.status is LaneStatus.FEASIBLE and "held" in lane.message
    assert lane.stats["held"] == "forced"
    # The last call's lane, from the car forward (x = 0.5 m is behind the car at x = 2 m).
    np.testing.assert_array_equal(lane.left, np.arange(1, n))
    np.testing.assert_array_equal(lane.right, n + np.arange(1, n))
    # Held, it is kept: the next call re-attaches it, and finds the stateless lane.
    after = solver.solve(cones, Pose(4.0, 0.0, 0.0), time_limit_s=5.0)
    assert after.stats["chain"]["kept_cones"] > 0
    _same(after, solve_lane(cones, Pose(4.0, 0.0, 0.0), time_limit_s=5.0))


@pytest.mark.parametrize("case", ["fresh solver", "pose jump", "kept cone gone"])
def test_no_lane_stays_no_lane_where_the_last_chain_cannot_be_held(monkeypatch, case):
    cones, n = straight()
    solver = LaneSolver("rld")
    if case != "fresh solver":
        solver.solve(cones, CAR, time_limit_s=5.0)
    pose = Pose(40.0 if case == "pose jump" else 2.0, 0.0, 0.0)
    now = np.delete(cones, 10, axis=0) if case == "kept cone gone" else cones
    with monkeypatch.context() as m:
        _no_window_lane(m)
        lane = solver.solve(now, pose, time_limit_s=5.0)
    assert not lane.ok and lane.message == "forced"

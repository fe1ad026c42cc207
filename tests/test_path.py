"""``rld.path.lane_path`` / ``Lane.path`` (the centreline for planners) and ``Lane.to_dict`` /
``Lane.from_dict``: analytic lanes (circle, straight), invariance properties, real lanes solved
on the racetrack dataset (skipped without it) and the JSON round trip."""

from __future__ import annotations

import json
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from rld import Lane, LaneParams, LaneSolver, LaneStatus, solve_lane
from rld import geometry as geo
from rld.path import PATH_COLUMNS, LanePath, lane_path

R = 15.0  # centreline radius of the circular lanes, metres
HALF = 1.5  # boundaries at R -/+ 1.5 m: 3 m wide, the rules' narrowest track


def arc(radius: float, n: int, span: float = 2 * math.pi, closed: bool = True,
        offset: float = 0.0) -> np.ndarray:
    """``n`` cones on a circle about the origin, counter-clockwise from angle 0 over ``span``
    (a closed ring does not repeat its first cone); ``offset`` shifts them by that fraction of
    a cone step."""
    a = span * (np.arange(n) + offset) / (n if closed else n - 1)
    return np.column_stack([radius * np.cos(a), radius * np.sin(a)])


def sagitta(radius: float, n_per_quarter: int) -> float:
    """How far inside the circle the middle of a chord between neighbouring cones lies."""
    return radius * (1 - math.cos(math.pi / 4 / n_per_quarter))


def chords(p: LanePath) -> np.ndarray:
    return np.hypot(np.diff(p.x), np.diff(p.y))


def check_spacing_of(p: LanePath, spacing: float) -> None:
    """Every step of ``s`` is ``spacing`` but the last (open: the lane's end; closed: the step
    back to the first sample, ``length - s[-1]``), which is in (0, spacing]."""
    steps = np.diff(p.s)
    assert np.all(steps > 0)
    last = p.length - p.s[-1] if p.closed else steps[-1]
    body = steps if p.closed else steps[:-1]
    np.testing.assert_allclose(body, spacing, rtol=0, atol=1e-9)
    assert 0 < last <= spacing + 1e-9


# --------------------------------------------------------------------------------------------
# Analytic lanes
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("per_quarter, offset", [(8, 0.0), (8, 0.5), (12, 0.0), (12, 0.37)])
def test_closed_circle(per_quarter, offset):
    """A closed ring, left inside (counter-clockwise): curvature 1/R within 2 % everywhere
    (measured 0.33 % at 8 cones a quarter, 0.15 % at 12), widths 1.5 m to within the chords'
    sagitta (3.5 cm at 12 cones a quarter on the outer ring; 8 a quarter gives 7.9 cm)."""
    n = 4 * per_quarter
    left, right = arc(R - HALF, n), arc(R + HALF, n, offset=offset)
    p = lane_path(left, right, closed=True, spacing_m=0.5)
    assert p.closed and len(p) == int(2 * math.pi * R / 0.5) + 1
    np.testing.assert_allclose(p.curvature, 1 / R, rtol=0.02)
    np.testing.assert_allclose(np.hypot(p.x, p.y), R, atol=1e-3)
    assert p.length == pytest.approx(2 * math.pi * R, abs=1e-3)
    # The inner polyline's chords lie inside its circle (away from the centreline), the outer's
    # inside theirs (towards it).
    tol = 2e-3
    assert np.all(p.width_left >= HALF - tol)
    assert np.all(p.width_left <= HALF + sagitta(R - HALF, per_quarter) + tol)
    assert np.all(p.width_right <= HALF + tol)
    assert np.all(p.width_right >= HALF - sagitta(R + HALF, per_quarter) - tol)
    if per_quarter >= 12:
        np.testing.assert_allclose(p.width_left, HALF, atol=0.05)
        np.testing.assert_allclose(p.width_right, HALF, atol=0.05)
    # Heading: the tangent of a counter-clockwise circle.
    phi = np.arctan2(p.y, p.x)
    np.testing.assert_allclose(np.angle(np.exp(1j * (p.heading - phi - math.pi / 2))), 0,
                               atol=1e-3)
    check_spacing_of(p, 0.5)
    np.testing.assert_allclose(chords(p), 2 * R * math.sin(0.25 / R), atol=1e-5)


@pytest.mark.parametrize("per_quarter", [8, 12])
def test_open_half_circle(per_quarter):
    """Half a ring, open: curvature 1/R within 2 % from 2 m after the start to 2 m before the
    end (measured 0.48 % at 8 cones a quarter); at the very ends the boundary splines'
    not-a-knot conditions add up to 2.6 % (8 a quarter) and 1.2 % (12), so at 12 the whole
    path is within 2 %."""
    n = 2 * per_quarter + 1
    left = arc(R - HALF, n, math.pi, closed=False)
    right = arc(R + HALF, n, math.pi, closed=False)
    p = lane_path(left, right, closed=False, spacing_m=0.5)
    assert not p.closed
    assert p.length == pytest.approx(math.pi * R, abs=1e-3)
    inner = (p.s >= 2.0) & (p.s <= p.length - 2.0)
    np.testing.assert_allclose(p.curvature[inner], 1 / R, rtol=0.02)
    if per_quarter >= 12:
        np.testing.assert_allclose(p.curvature, 1 / R, rtol=0.02)
    np.testing.assert_allclose(np.hypot(p.x, p.y), R, atol=1e-3)
    np.testing.assert_allclose(p.xy[[0, -1]], [[R, 0], [-R, 0]], atol=1e-3)
    assert np.all(np.abs(p.width_left - HALF) <= sagitta(R - HALF, per_quarter) + 2e-3)
    assert np.all(np.abs(p.width_right - HALF) <= sagitta(R + HALF, per_quarter) + 2e-3)
    check_spacing_of(p, 0.5)


def test_turning_right_is_negative_curvature():
    """The same half ring driven the other way round (clockwise): left and right swap sides."""
    n = 25
    outer = arc(R + HALF, n, math.pi, closed=False)[::-1]
    inner = arc(R - HALF, n, math.pi, closed=False)[::-1]
    p = lane_path(outer, inner, closed=False)
    inside = (p.s >= 2.0) & (p.s <= p.length - 2.0)
    np.testing.assert_allclose(p.curvature[inside], -1 / R, rtol=0.02)


def test_straight_lane():
    """Curvature 0 (|k| < 1e-9), heading constant, widths exact, spacing exact (the last step
    reaches the lane's end and is shorter); the sides' cone spacings differ."""
    left = np.column_stack([np.linspace(0.0, 40.0, 11), np.full(11, 1.8)])
    right = np.column_stack([np.linspace(0.0, 40.0, 9), np.full(9, -1.8)])
    p = lane_path(left, right, closed=False, spacing_m=0.7)
    assert np.abs(p.curvature).max() < 1e-9
    assert np.abs(p.heading).max() < 1e-9
    np.testing.assert_allclose(p.y, 0.0, atol=1e-9)
    np.testing.assert_allclose(p.width_left, 1.8, atol=1e-9)
    np.testing.assert_allclose(p.width_right, 1.8, atol=1e-9)
    assert p.s[0] == 0 and p.s[-1] == pytest.approx(40.0) and p.length == pytest.approx(40.0)
    check_spacing_of(p, 0.7)
    np.testing.assert_allclose(chords(p), np.diff(p.s), atol=1e-9)
    np.testing.assert_allclose(p.x, p.s, atol=1e-9)
    assert np.diff(p.s)[-1] == pytest.approx(40.0 - 57 * 0.7)


def test_two_cones_a_side():
    p = lane_path([[0, 2], [5, 2]], [[0, -2], [5, -2]], closed=False, spacing_m=1.0)
    np.testing.assert_allclose(p.s, [0, 1, 2, 3, 4, 5], atol=1e-9)
    assert np.abs(p.curvature).max() < 1e-9


# --------------------------------------------------------------------------------------------
# Properties
# --------------------------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(
    width=st.floats(3.0, 6.5),
    length=st.floats(8.0, 60.0),
    step_left=st.floats(1.5, 5.0),
    step_right=st.floats(1.5, 5.0),
    yaw=st.floats(-math.pi, math.pi),
    tx=st.floats(-500.0, 500.0),
    ty=st.floats(-500.0, 500.0),
    spacing=st.floats(0.2, 2.0),
)
def test_straight_lanes_rotated_and_translated(width, length, step_left, step_right, yaw, tx,
                                               ty, spacing):
    """Any straight lane, anywhere, any heading: the widths are half its width, the heading is
    its direction, the curvature 0 and ``s`` strictly increasing at the asked spacing."""
    def side(y, step):
        n = max(int(math.ceil(length / step)), 1) + 1
        return np.column_stack([np.linspace(0.0, length, n), np.full(n, y)])

    c, s_ = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s_], [s_, c]])
    place = lambda xy: xy @ rot.T + [tx, ty]  # noqa: E731
    p = lane_path(place(side(width / 2, step_left)), place(side(-width / 2, step_right)),
                  closed=False, spacing_m=spacing)
    assert np.all(np.diff(p.s) > 0)
    check_spacing_of(p, spacing)
    assert p.length == pytest.approx(length, abs=1e-6)
    np.testing.assert_allclose(p.width_left, width / 2, atol=1e-6)
    np.testing.assert_allclose(p.width_right, width / 2, atol=1e-6)
    np.testing.assert_allclose(np.angle(np.exp(1j * (p.heading - yaw))), 0.0, atol=1e-9)
    assert np.abs(p.curvature).max() < 1e-9


@settings(max_examples=30, deadline=None)
@given(yaw=st.floats(-math.pi, math.pi), tx=st.floats(-500.0, 500.0),
       ty=st.floats(-500.0, 500.0), offset=st.floats(0.0, 1.0))
def test_a_moved_ring_keeps_its_curvature_and_widths(yaw, tx, ty, offset):
    """Moving a closed lane moves its path rigidly: curvature and widths stay, heading turns."""
    left, right = arc(R - HALF, 40), arc(R + HALF, 48, offset=offset)
    c, s_ = math.cos(yaw), math.sin(yaw)
    rot = np.array([[c, -s_], [s_, c]])
    p0 = lane_path(left, right, closed=True)
    p1 = lane_path(left @ rot.T + [tx, ty], right @ rot.T + [tx, ty], closed=True)
    assert len(p0) == len(p1)
    np.testing.assert_allclose(p1.s, p0.s, atol=1e-9)
    np.testing.assert_allclose(p1.curvature, p0.curvature, atol=1e-6)
    np.testing.assert_allclose(p1.width_left, p0.width_left, atol=1e-6)
    np.testing.assert_allclose(p1.width_right, p0.width_right, atol=1e-6)
    np.testing.assert_allclose(p1.xy, p0.xy @ rot.T + [tx, ty], atol=1e-6)
    np.testing.assert_allclose(np.angle(np.exp(1j * (p1.heading - p0.heading - yaw))), 0.0,
                               atol=1e-6)


# --------------------------------------------------------------------------------------------
# LanePath, Lane.path and errors
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("bad", [0, 0.0, -0.5, math.nan, math.inf, -math.inf, "0.5", None, True])
def test_bad_spacing_raises(bad):
    left, right = arc(R - HALF, 32), arc(R + HALF, 32)
    with pytest.raises(ValueError, match="spacing_m"):
        lane_path(left, right, closed=True, spacing_m=bad)
    lane = Lane(np.vstack([left, right]), np.arange(32), 32 + np.arange(32), LaneStatus.OPTIMAL,
                closed=True)
    with pytest.raises(ValueError, match="spacing_m"):
        lane.path(bad)
    with pytest.raises(ValueError, match="spacing_m"):
        Lane.not_found(lane.cones, "none").path(bad)


def test_too_few_points_raise():
    with pytest.raises(ValueError, match="left boundary"):
        lane_path([[0, 1]], [[0, -1], [3, -1]], closed=False)
    with pytest.raises(ValueError, match="right boundary of a closed lane"):
        lane_path(arc(R - HALF, 8), [[0, -1], [3, -1]], closed=True)
    with pytest.raises(ValueError, match=r"shape \(k, 2\)"):
        lane_path(np.zeros((4, 3)), [[0, -1], [3, -1]], closed=False)
    with pytest.raises(ValueError, match="non-finite"):
        lane_path([[0, 1], [math.nan, 1]], [[0, -1], [3, -1]], closed=False)


def test_lane_path_and_its_views():
    cones = np.vstack([arc(R - HALF, 40), arc(R + HALF, 40)])
    lane = Lane(cones, np.arange(40), 40 + np.arange(40), LaneStatus.OPTIMAL, closed=True)
    p = lane.path(1.0)
    q = lane_path(lane.left_xy, lane.right_xy, True, 1.0)
    np.testing.assert_array_equal(p.as_array(), q.as_array())
    arr = p.as_array()
    assert arr.shape == (len(p), 7)
    for k, name in enumerate(PATH_COLUMNS):
        np.testing.assert_array_equal(arr[:, k], getattr(p, name))
    d = json.loads(json.dumps(p.to_dict(), allow_nan=False))
    assert d["closed"] is True and d["length"] == p.length
    np.testing.assert_array_equal(np.array(d["curvature"]), p.curvature)
    with pytest.raises(ValueError):
        p.s[0] = 1.0  # read-only
    with pytest.raises(AttributeError):
        p.closed = False  # frozen


def test_a_lane_not_found_has_an_empty_path():
    lane = Lane.not_found(np.zeros((5, 2)), "no cone near the car")
    p = lane.path()
    assert isinstance(p, LanePath) and len(p) == 0 and p.length == 0.0
    assert p.as_array().shape == (0, 7)
    assert p.to_dict()["s"] == []


# --------------------------------------------------------------------------------------------
# Real lanes (the racetrack dataset)
# --------------------------------------------------------------------------------------------


REAL_TRACKS = (1, 3, 6)
REAL_FRAMES = range(0, 200, 40)


def on_line(xy: np.ndarray, true_xy: np.ndarray) -> bool:
    """Every cone of ``xy`` lies within 0.5 m of the closed polyline through ``true_xy``."""
    line = geo.boundary_line(true_xy, closed=True)
    return bool(np.all(geo.point_polyline_distance(xy, line) <= 0.5))


@pytest.mark.parametrize("method", ["clc", "rld"])
def test_real_lanes_have_widths_within_the_rules(dataset_dir, method):
    """Lanes solved on frames of three dataset tracks (30 m perception, no false positives).
    Where the solved lane is true (its cones within 0.5 m of their side's true line), each side's
    width lies in [min_width_m / 2 - 0.25, max_width_m] = [1.0, 6.5] m: the rules' 3 m (2.5 m
    with LaneParams' margin) halved, less 0.25 m for the outer polyline's chord sagitta and an
    off-centre midpoint in corners (measured 1.38-2.73 m), and the two sum to at least
    ``min_width_m`` (measured 2.91 m). Every lane's path is finite and evenly spaced. True
    lanes measured: CLC 9 of 15, RLD 14 of 15 (RLD's lane may start a cone behind the car)."""
    from rld.simulation import simulate_lap
    from rld.tracks import load_dataset_track

    params = LaneParams()
    lo, hi = params.min_width_m / 2 - 0.25, params.max_width_m
    checked = 0
    for number in REAL_TRACKS:
        track = load_dataset_track(dataset_dir, number)
        lap = simulate_lap(track, range_m=30.0)
        for k in REAL_FRAMES:
            frame = lap.frame(k)
            lane = solve_lane(frame.cones, frame.pose, method=method)
            if not lane.ok:
                continue
            p = lane.path()
            assert len(p) >= 2 and np.all(np.isfinite(p.as_array()))
            check_spacing_of(p, 0.5)
            true = on_line(lane.left_xy, track.left_xy) and on_line(lane.right_xy, track.right_xy)
            if not true:
                continue  # a solver's mistake is not the path's
            checked += 1
            for side in (p.width_left, p.width_right):
                assert lo <= side.min() and side.max() <= hi, (number, k, side.min(), side.max())
            assert (p.width_left + p.width_right).min() >= params.min_width_m
    assert checked >= 5, f"only {checked} solved lanes were true"


# --------------------------------------------------------------------------------------------
# Lane.to_dict / from_dict
# --------------------------------------------------------------------------------------------


def assert_same_lane(a: Lane, b: Lane) -> None:
    np.testing.assert_array_equal(a.cones, b.cones)
    np.testing.assert_array_equal(a.left, b.left)
    np.testing.assert_array_equal(a.right, b.right)
    assert a.left.dtype == b.left.dtype == np.int64 and b.cones.dtype == np.float64
    assert a.status is b.status and a.message == b.message and a.closed == b.closed
    assert a.cost == b.cost or (math.isnan(a.cost) and math.isnan(b.cost))


def round_trip(lane: Lane) -> Lane:
    return Lane.from_dict(json.loads(json.dumps(lane.to_dict(), allow_nan=False)))


STRAIGHT = np.array([[0, 2], [4, 2.1], [8, 1.9], [12, 2], [0, -2], [4, -2], [8, -2.1],
                     [12, -2], [30, 30]], float) + 0.1 * np.arange(9)[:, None] / 7


@pytest.mark.parametrize("method", ["rld", "clc", "nearest"])
def test_json_round_trip_of_a_found_lane(method):
    lane = solve_lane(STRAIGHT, (0.5, 0.0, 0.0), method=method)
    assert lane.ok
    back = round_trip(lane)
    assert_same_lane(lane, back)
    assert back.to_dict() == json.loads(lane.to_json())
    np.testing.assert_array_equal(back.path().as_array(), lane.path().as_array())


def test_json_round_trip_of_lanes_not_found():
    cones = np.array([[0, 0], [1, 0], [2, 0], [3, 0.5]])
    for status in (LaneStatus.NOT_FOUND, LaneStatus.INFEASIBLE, LaneStatus.TIMEOUT):
        lane = Lane.not_found(cones, f"why: {status.value} \u00e9", status=status,
                              stats={"n": np.int64(3), "t": np.float32(0.25), "nan": math.nan,
                                     "arr": np.arange(3), "flag": np.bool_(True),
                                     "nested": {1: (np.float64(2.5), [np.inf])}})
        d = lane.to_dict()
        assert d["cost"] is None and d["left"] == [] and d["status"] == status.name
        assert d["stats"] == {"n": 3, "t": 0.25, "nan": None, "arr": [0, 1, 2], "flag": True,
                              "nested": {"1": [2.5, [None]]}}
        assert_same_lane(lane, round_trip(lane))
    empty = Lane.not_found(np.zeros((0, 2)), "")
    assert_same_lane(empty, round_trip(empty))


def test_json_of_a_tracked_lane():
    """``stats["tracked"]`` (a dataclass of arrays) becomes a dict of lists."""
    solver = LaneSolver(method="nearest", track=True)
    lane = solver.solve(STRAIGHT, (0.5, 0.0, 0.0))
    d = json.loads(lane.to_json())
    assert isinstance(d["stats"]["tracked"]["centerline"], list)
    assert_same_lane(lane, Lane.from_dict(d))


@settings(max_examples=60, deadline=None)
@given(
    data=st.data(),
    n=st.integers(4, 30),
    status=st.sampled_from(list(LaneStatus)),
    cost=st.one_of(st.floats(allow_nan=False, allow_infinity=False), st.just(math.nan)),
    message=st.text(max_size=30),
    closed=st.booleans(),
)
def test_json_round_trip_property(data, n, status, cost, message, closed):
    cones = np.array(data.draw(st.lists(
        st.tuples(st.floats(-1e6, 1e6), st.floats(-1e6, 1e6)), min_size=n, max_size=n)))
    if status.ok:
        order = data.draw(st.permutations(range(n)))
        k = data.draw(st.integers(1, n - 1))
        left, right = order[:k], order[k:]
    else:
        left = right = []
    lane = Lane(cones, left, right, status, message=message, cost=cost, closed=closed)
    assert_same_lane(lane, round_trip(lane))


def test_from_dict_rejects():
    with pytest.raises(ValueError, match="keys"):
        Lane.from_dict({"cones": []})
    with pytest.raises(ValueError, match="status"):
        Lane.from_dict({"cones": [], "left": [], "right": [], "status": "LOST"})

"""The lane tracker of Huang et al. section 2.3 (``rld.tracker``)."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rld.tracker import LaneTracker, TrackerParams, match_score, project_onto


def straight(y: float = 0.0, length: float = 30.0) -> np.ndarray:
    return np.column_stack([np.linspace(0, length, 16), np.full(16, y)])


def test_match_score_hand_worked():
    lane = straight(0.0, 30.0)
    # A parallel candidate 0.5 m off over 20 m: every sample scores 1 + (1 - 0.5) / 1 = 1.5.
    cand = np.array([[5.0, 0.5], [25.0, 0.5]])
    assert match_score(cand, lane, tau_m=1.0) == pytest.approx(20 * 1.5)
    # On the lane: 2 per metre.
    assert match_score(np.array([[0.0, 0.0], [10.0, 0.0]]), lane, 1.0) == pytest.approx(20.0)
    # Only the longest stretch within tau counts: 10 m on the lane (20) plus the first metre
    # of the turn away, where d grows from 0 to 1 (integral of 2 - d: 1.5); the 4 m back on
    # the lane after the 5 m excursion are a shorter stretch.
    cand = np.array([[0, 0], [10, 0], [10, 5], [14, 5], [14, 0], [18, 0]], float)
    assert match_score(cand, lane, 1.0) == pytest.approx(21.5)
    # Farther than tau everywhere: no match.
    assert match_score(straight(3.0), lane, 1.0) == 0.0


@given(st.floats(0.0, 0.99), st.floats(2.0, 40.0))
def test_match_score_of_a_parallel_segment(offset, length):
    lane = np.array([[-10.0, 0.0], [60.0, 0.0]])
    cand = np.array([[0.0, offset], [length, offset]])
    assert match_score(cand, lane, 1.0, step_m=0.1) == pytest.approx(
        length * (2 - offset), rel=1e-6)


def test_project_onto_hand_worked():
    poly = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0]])
    q, d, s = project_onto(np.array([[5.0, 2.0], [12.0, 5.0], [-3.0, 4.0]]), poly)
    np.testing.assert_allclose(q, [[5, 0], [10, 5], [0, 0]])
    np.testing.assert_allclose(d, [2, 2, 5])
    np.testing.assert_allclose(s, [5, 15, 0])


def test_points_before_the_candidate_start_are_not_worn_down():
    """A lane tracked from x = 0 (control points every 2 m, confidence 0.3); the next
    candidate begins at x = 9 m. The points it passes (x >= 8 m, within tau = 1 m of its
    start) gain 0.2; those before its start, which it does not see, keep 0.3 (before
    2026-12-04 they lost 0.1); after five such updates ``confident`` still starts at x = 0."""
    tr = LaneTracker()
    tr.update(straight(0.0, 30.0))
    x = tr.points[:, 0].copy()
    p = tr.params
    out = tr.update(np.array([[9.0, 0.0], [30.0, 0.0]]))
    assert out.matched
    seen = x >= 9.0 - p.tau_m
    np.testing.assert_allclose(out.confidence[seen], p.initial_confidence + p.confidence_gain)
    np.testing.assert_allclose(out.confidence[~seen], p.initial_confidence)
    assert (~seen).sum() == 4  # x = 0, 2, 4, 6
    for _ in range(4):
        out = tr.update(np.array([[9.0, 0.0], [30.0, 0.0]]))
    assert out.confident(0.3).shape[0] == out.centerline.shape[0]
    # A candidate from x = -5 m, 3 m off the lane up to x = 9 m, still wears those down.
    tr = LaneTracker()
    tr.update(straight(0.0, 30.0))
    out = tr.update(np.array([[-5.0, 3.0], [9.0, 3.0], [9.0, 0.0], [30.0, 0.0]]))
    assert out.confidence[0] == pytest.approx(p.initial_confidence - p.confidence_decay)


def test_tracker_converges_on_a_fixed_lane():
    tr = LaneTracker()
    first = tr.update(straight(0.6))  # starts 0.6 m off the lane it will see from now on
    assert first.restarted
    errs = []
    for _ in range(12):
        out = tr.update(straight(0.0))
        assert out.matched
        errs.append(np.abs(out.centerline[:, 1]).max())
    # The moving average halves the error at every update (alpha = 0.5) ...
    np.testing.assert_allclose(errs, 0.6 * 0.5 ** np.arange(1, 13), atol=1e-9)
    # ... and every control point becomes fully confident.
    assert np.all(out.confidence == pytest.approx(1.0))
    assert out.centerline.shape[0] == 16  # 30 m at 2 m spacing


def test_tracker_rejects_a_single_outlier_frame():
    tr = LaneTracker()
    for _ in range(6):
        tr.update(straight(0.0))
    before = tr.points.copy()
    conf = tr.confidence.copy()
    out = tr.update(straight(4.0))  # a lane 4 m to the side: another lane, not this one
    assert not out.matched
    np.testing.assert_array_equal(out.centerline, before)  # nothing moved
    assert np.all(out.confidence < conf)  # but the tracker is less sure
    back = tr.update(straight(0.0))
    assert back.matched and np.abs(back.centerline[:, 1]).max() == 0.0


def test_tracker_restarts_after_repeated_misses():
    tr = LaneTracker(TrackerParams(max_misses=2))
    tr.update(straight(0.0))
    outs = [tr.update(straight(5.0)) for _ in range(3)]
    assert [o.matched for o in outs] == [False, False, True]
    assert outs[-1].restarted
    assert np.allclose(outs[-1].centerline[:, 1], 5.0)


def test_tracker_extends_along_a_longer_candidate_and_drops_what_is_behind():
    tr = LaneTracker()
    tr.update(straight(0.0, 20.0))
    out = tr.update(straight(0.0, 40.0), car_xy=np.array([10.0, 0.0]),
                    heading=np.array([1.0, 0.0]))
    assert out.matched
    xs = out.centerline[:, 0]
    assert xs.min() >= 6.0 - 1e-9  # 4 m behind the car at most
    assert xs.max() == pytest.approx(40.0)
    assert np.all(np.diff(xs) > 0) and np.diff(xs).max() <= 2.0 + 1e-9
    new = xs > 20.0 + 1e-9
    assert np.all(out.confidence[new] == TrackerParams().initial_confidence)


def test_unconfident_interior_points_are_interpolated():
    tr = LaneTracker(TrackerParams(min_confidence=0.25, confidence_decay=0.3))
    tr.update(straight(0.0))
    tr.points[5] += [0.0, 3.0]  # a control point knocked off the lane
    tr.confidence[:] = 1.0
    tr.confidence[5] = 0.2
    tr._clean(None, None)
    assert tr.points[5, 1] == pytest.approx(0.0)


def test_bad_candidates_and_params():
    with pytest.raises(ValueError):
        LaneTracker().update(np.array([[0.0, math.nan], [1.0, 0.0]]))
    with pytest.raises(ValueError):
        TrackerParams(alpha=0.0)
    out = LaneTracker().update(None)
    assert not out.matched and out.centerline.shape == (0, 2)


@pytest.mark.parametrize("method", ["rld", "clc"])
def test_lane_solver_tracks_its_lanes(method):
    from rld.api import LaneSolver
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    lap = simulate_lap(generate_track(100), range_m=30.0, fp_rate=0.0, seed=0)
    solver = LaneSolver(method, track=True)
    outs = []
    for k in range(20, 30):
        f = lap.frame(k)
        lane = solver.solve(f.cones, f.pose)
        assert lane.ok
        outs.append(lane.stats["tracked"])
    assert outs[0].restarted
    assert sum(o.matched for o in outs[1:]) >= 8  # consecutive lanes 1 m apart match
    last = outs[-1]
    # The tracked centreline stays near the raw one it was fed.
    from rld.tracker import project_onto

    # (Control points behind where the raw lane begins are kept up to 4 m behind the car.)
    _, d, arc = project_onto(last.confident(0.5), lane.centerline)
    d = d[arc > 0]
    assert d.size >= 3 and d.max() < 1.0
    assert "tracked" not in LaneSolver(method).solve(f.cones, f.pose).stats


def test_behind_start_hand_worked():
    """Behind the first point along the first segment (x <= 0 for a start at the origin
    heading +x), within tau = 1 m of that line; a repeated first point is skipped."""
    from rld.tracker import _behind_start

    pts = np.array([[-1.0, 0.0], [-3.0, 0.9], [-3.0, 1.1], [1.0, 0.0], [-2.0, -0.5],
                    [0.0, 0.0]])
    want = [True, True, False, False, True, True]
    cand = np.array([[0.0, 0.0], [1.0, 0.0], [5.0, 2.0]])
    assert _behind_start(pts, cand, 1.0).tolist() == want
    cand = np.array([[0.0, 0.0], [0.0, 0.0], [2.0, 0.0]])
    assert _behind_start(pts, cand, 1.0).tolist() == want
    assert not _behind_start(pts, np.zeros((3, 2)), 1.0).any()


def test_points_beside_the_candidate_start_still_wear_down():
    """A tracked lane along y = 0 from x = 0 with a stale point folded 3 m aside at (8, 3)
    (set by hand); the candidate begins at (9, 0). The stale point's nearest candidate point
    is the start, but it is not on the start's backward line: it loses 0.1; the points at
    x = 0..6 keep 0.3."""
    tr = LaneTracker()
    tr.update(straight(0.0, 30.0))
    p = tr.params
    tr.points = np.insert(tr.points, 4, [8.0, 3.0], axis=0)
    tr.confidence = np.insert(tr.confidence, 4, p.initial_confidence)
    out = tr.update(np.array([[9.0, 0.0], [30.0, 0.0]]))
    assert out.matched
    np.testing.assert_allclose(out.confidence[:4], p.initial_confidence)
    assert out.confidence[4] == pytest.approx(p.initial_confidence - p.confidence_decay)


def test_a_candidate_stopping_short_does_not_fold_the_lane():
    """Tracked lane x = 0..30 m on y = 0. A candidate on the lane up to x = 20 that then turns
    back to (14, -3): the last control point (30, 0) is 10 m from it, so nothing is
    appended (before 2026-12-05 its last 6.7 m were appended after x = 30, a fold)."""
    tr = LaneTracker()
    tr.update(straight(0.0, 30.0))
    out = tr.update(np.array([[0.0, 0.0], [20.0, 0.0], [14.0, -3.0]]))
    assert out.matched
    assert out.centerline.shape[0] == 16
    np.testing.assert_allclose(out.centerline[:, 1], 0.0)
    # A candidate that runs on past x = 30 still extends the lane, every 2 m.
    out = tr.update(np.array([[0.0, 0.0], [36.0, 0.0]]))
    np.testing.assert_allclose(out.centerline[-4:, 0], [30.0, 32.0, 34.0, 36.0])

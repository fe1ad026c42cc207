"""The evaluation protocol's simulation (DESIGN.md, "Evaluation protocol", steps 1-6).

The checks are brute force: perception fields in the car frame through ``Pose.to_local``, partial
maps and ground-truth lanes recomputed from the track, never from ``Lap``'s own bookkeeping.
"""

from __future__ import annotations

import math
from functools import cache

import numpy as np
import pytest

from rld.generator import generate_track
from rld.simulation import Frame, in_field, simulate_lap
from rld.tracks import Track
from rld.types import Pose

SEEDS = (2, 3)  # two of the smaller generated circuits (about 200-250 m a lap)
STRIDE = 10  # look at every 10th frame


@cache
def track(seed: int) -> Track:
    return generate_track(seed)


def ring_track(r_in=8.0, n_in=24, r_out=12.0, n_out=36) -> Track:
    """A circular track driven counter-clockwise: left (inner) and right (outer) rings of cones;
    cone i at angle 2 pi (i + 0.5) / n."""

    def ring(r, n):
        a = 2 * math.pi * (np.arange(n) + 0.5) / n
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    cones = np.vstack([ring(r_in, n_in), ring(r_out, n_out)])
    return Track(
        cones, np.arange(n_in + n_out), np.arange(n_in), n_in + np.arange(n_out), closed=True
    )


def poses(lap) -> list[Pose]:
    return [lap.pose(k) for k in range(len(lap))]


def field_brute(points: np.ndarray, pose: Pose, range_m: float) -> np.ndarray:
    """The half-disc ahead of the car, in the car frame."""
    loc = pose.to_local(points)
    return (loc[:, 0] >= 0.0) & (np.hypot(loc[:, 0], loc[:, 1]) <= range_m)


def seen_by(points: np.ndarray, lap, range_m: float) -> np.ndarray:
    """(K, P): point p has been in the field at some pose 0..k."""
    seen = np.array([field_brute(points, p, range_m) for p in poses(lap)])
    return np.logical_or.accumulate(seen, axis=0)


def frame_ks(lap) -> list[int]:
    return list(range(0, len(lap), STRIDE)) + [len(lap) - 1]


def position_of(lap, trk: Track, source: int) -> np.ndarray:
    return trk.cones[source] if source >= 0 else lap.false_positives[-1 - source]


# --------------------------------------------------------------------------------------------
# Step 1: poses
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed", SEEDS)
def test_poses_every_metre_over_one_lap(seed):
    trk = track(seed)
    lap = simulate_lap(trk, range_m=30.0)
    xy = np.array([p.xy for p in poses(lap)])
    steps = np.hypot(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T)  # closed: back to the start
    # Spaced every metre of arc length: chords of tight corners are a little shorter.
    assert steps.min() > 0.9 and steps.max() < 1.02
    assert np.median(steps) == pytest.approx(1.0, abs=0.01)
    lap_len = 0.5 * (trk.boundary_length("left") + trk.boundary_length("right"))
    assert len(lap) == pytest.approx(lap_len, rel=0.05)
    assert abs(steps.sum() - len(lap)) < 0.03 * len(lap)
    # The lap starts between the first cones of both boundaries.
    mid = 0.5 * (trk.cones[trk.left[0]] + trk.cones[trk.right[0]])
    assert np.hypot(*(xy[0] - mid)) < 1.0
    # Frames carry the lap's poses, and iterating gives one frame per pose.
    f = lap.frame(17)
    assert f.index == 17 and f.pose == lap.pose(17)
    assert sum(1 for _ in lap) == len(lap)


@pytest.mark.parametrize("seed", SEEDS)
def test_yaw_follows_the_tangent(seed):
    trk = track(seed)
    lap = simulate_lap(trk, range_m=30.0)
    ps = poses(lap)
    xy = np.array([p.xy for p in ps])
    ahead = np.roll(xy, -1, axis=0) - xy  # the next pose, 1 m on
    chord = np.arctan2(ahead[:, 1], ahead[:, 0])
    yaw = np.array([p.yaw for p in ps])
    err = np.abs(np.angle(np.exp(1j * (yaw - chord))))
    # The yaw is the central difference's direction, which lies between the chords before and
    # after the pose: it is off the forward chord by at most the turn between the two.
    turn = np.abs(np.angle(np.exp(1j * (chord - np.roll(chord, 1)))))
    inner = slice(1, -1) if not trk.closed else slice(None)
    assert np.all(err[inner] <= turn[inner] + 1e-9)
    # Corners are at least 6.5 m in radius on the centreline: no 1 m step turns by 0.3 rad.
    assert err.max() < 0.3
    # Driving in boundary order: the left boundary is on the left, the right on the right.
    left, right = trk.cones[trk.left], trk.cones[trk.right]
    for p in ps:
        for xy_side, sign in ((left, 1.0), (right, -1.0)):
            loc = p.to_local(xy_side)
            nearest = loc[np.argmin(np.hypot(loc[:, 0], loc[:, 1]))]
            assert sign * nearest[1] > 0.0


def test_yaw_on_a_ring_is_the_circle_tangent():
    lap = simulate_lap(ring_track(), range_m=10.0)
    xy = np.array([p.xy for p in poses(lap)])
    r = np.hypot(*xy.T)
    assert np.all(np.abs(r - 10.0) < 0.2)
    # Counter-clockwise: the tangent at angle a points at a + pi / 2.
    expected = np.arctan2(xy[:, 1], xy[:, 0]) + math.pi / 2
    yaw = np.array([p.yaw for p in poses(lap)])
    assert np.abs(np.angle(np.exp(1j * (yaw - expected)))).max() < 0.05
    # About 2 pi 10 = 62.8 m of lap.
    assert 60 <= len(lap) <= 63


def test_open_track_hand_worked():
    # A straight open track: cones every 5 m from x = 0 to 50 at y = +-2. The centreline runs
    # from x = 0 to 50: 51 poses 1 m apart, all heading +x.
    x = np.arange(0.0, 51.0, 5.0)
    cones = np.vstack(
        [np.column_stack([x, np.full(11, 2.0)]), np.column_stack([x, np.full(11, -2.0)])]
    )
    trk = Track(cones, np.arange(22), np.arange(11), 11 + np.arange(11), closed=False)
    lap = simulate_lap(trk, range_m=12.0)
    assert len(lap) == 51
    xy = np.array([p.xy for p in poses(lap)])
    np.testing.assert_allclose(xy, np.column_stack([np.arange(51.0), np.zeros(51)]), atol=1e-9)
    np.testing.assert_allclose([p.yaw for p in poses(lap)], 0.0, atol=1e-9)
    # A cone dx ahead and 2 m aside is within 12 m when dx <= sqrt(140) = 11.83 m. Pose 0 sees
    # x = 0, 5, 10 (x = 0 is beside the car, not behind it).
    f = lap.frame(0)
    assert f.source[f.gt_left].tolist() == [0, 1, 2]
    assert f.source[f.gt_right].tolist() == [11, 12, 13]
    # Pose 30 at x = 30: the map holds x = 0..40 (x = 40 is first seen from pose 29, x = 45 not
    # before pose 34). The truth starts beside the car at x = 30 and does not wrap.
    f = lap.frame(30)
    assert sorted(f.source.tolist()) == list(range(0, 9)) + list(range(11, 20))
    assert f.source[f.gt_left].tolist() == [6, 7, 8]
    assert f.source[f.gt_right].tolist() == [17, 18, 19]
    # At the end the whole map is known, yet an open lane is never "closed".
    f = lap.frame(50)
    assert f.source[f.gt_left].tolist() == [10]
    assert not f.gt_closed


# --------------------------------------------------------------------------------------------
# Step 2: the perception field
# --------------------------------------------------------------------------------------------


def test_in_field_hand_worked():
    car, h = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    pts = np.array(
        [
            (-1.0, 0.0),  # behind: out
            (5.0, 3.0),  # ahead, 5.8 m: in
            (11.0, 0.0),  # ahead, beyond 10 m: out
            (6.0, 7.9),  # ahead, 9.92 m: in
            (0.5, -9.9),  # just ahead, to the right, 9.91 m: in
            (-0.5, 9.0),  # beside but a little behind: out
            (-30.0, 2.0),  # far behind: out
        ]
    )
    np.testing.assert_array_equal(
        in_field(pts, car, h, 10.0), [False, True, False, True, True, False, False]
    )
    # The car at (10, 10) heading +y.
    pts = np.array(
        [
            (10.0, 5.0),  # behind: out
            (17.0, 12.0),  # ahead to the right, 7.3 m: in
            (10.0, 21.0),  # straight ahead, 11 m: out
            (2.0, 15.0),  # ahead to the left, 9.43 m: in
            (15.0, 9.5),  # to the right, slightly behind: out
        ]
    )
    got = in_field(pts, np.array([10.0, 10.0]), np.array([0.0, 1.0]), 10.0)
    np.testing.assert_array_equal(got, [False, True, False, True, False])
    # Radius scales the disc: at 12 m the point 11 m ahead is in.
    got = in_field(pts, np.array([10.0, 10.0]), np.array([0.0, 1.0]), 12.0)
    np.testing.assert_array_equal(got, [False, True, True, True, False])


def test_in_field_many_poses_matches_brute_force():
    rng = np.random.default_rng(7)
    pts = rng.uniform(-40, 40, size=(300, 2))
    yaw = rng.uniform(-math.pi, math.pi, size=6)
    xy = rng.uniform(-10, 10, size=(6, 2))
    heading = np.column_stack([np.cos(yaw), np.sin(yaw)])
    got = in_field(pts, xy, heading, 25.0)
    assert got.shape == (6, 300)
    for k in range(6):
        want = field_brute(pts, Pose(xy[k, 0], xy[k, 1], yaw[k]), 25.0)
        np.testing.assert_array_equal(got[k], want)
        np.testing.assert_array_equal(in_field(pts, xy[k], heading[k], 25.0), want)
    assert 0 < got.sum() < got.size


# --------------------------------------------------------------------------------------------
# Steps 3 and 6: the partial map, shuffled
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("seed,range_m,fp_rate", [(2, 30.0, 0.3), (3, 20.0, 0.1)])
def test_partial_map_is_everything_seen_so_far(seed, range_m, fp_rate):
    trk = track(seed)
    lap = simulate_lap(trk, range_m=range_m, fp_rate=fp_rate, seed=seed)
    n_real = trk.cones.shape[0]
    points = np.vstack([trk.cones, lap.false_positives])
    seen = seen_by(points, lap, range_m)
    # Source code of every point: track index, or -1 - k for false positive k.
    codes = np.concatenate([np.arange(n_real), -1 - np.arange(len(lap.false_positives))])
    prev: set[int] = set()
    position: dict[int, np.ndarray] = {}
    orders = []
    for k in frame_ks(lap):
        f = lap.frame(k)
        assert isinstance(f, Frame)
        src = f.source
        assert src.shape == (f.cones.shape[0],)
        assert np.unique(src).size == src.size
        # Exactly the points that have been in the field at some pose 0..k.
        assert set(src.tolist()) == set(codes[seen[k]].tolist()), k
        # The map only grows.
        assert prev <= set(src.tolist())
        prev = set(src.tolist())
        # Positions through ``source``, and the same in every frame.
        for i, s in enumerate(src.tolist()):
            np.testing.assert_array_equal(f.cones[i], position_of(lap, trk, s))
            if s in position:
                np.testing.assert_array_equal(position[s], f.cones[i])
            position[s] = f.cones[i]
        assert np.array_equal(f.is_false_positive, src < 0)
        orders.append(src)
    # Late in the lap the map holds everything: real cones and false positives.
    assert prev == set(codes.tolist())
    # Shuffled: neither in track order nor in the same order from frame to frame.
    last = orders[-1]
    assert not np.all(np.diff(last[last >= 0]) > 0)
    a, b = orders[-2], orders[-1]
    common = [s for s in b.tolist() if s in set(a.tolist())]
    assert [s for s in a.tolist() if s in set(common)] != common


def test_first_frame_is_what_the_first_pose_sees():
    trk = track(2)
    lap = simulate_lap(trk, range_m=15.0)
    f = lap.frame(0)
    want = np.flatnonzero(field_brute(trk.cones, lap.pose(0), 15.0))
    assert sorted(f.source.tolist()) == want.tolist()
    assert 0 < want.size < trk.cones.shape[0] / 4


def test_unlabelled_cones_join_the_map():
    trk = track(3)
    # Two extra real cones on no boundary: one beside the start, one half a lap on.
    half = len(trk.left) // 2
    extra = np.array(
        [
            0.5 * (trk.cones[trk.left[2]] + trk.cones[trk.right[2]]),
            0.5 * (trk.cones[trk.left[half]] + trk.cones[trk.right[half]]),
        ]
    )
    n = trk.cones.shape[0]
    t2 = Track(np.vstack([trk.cones, extra]), np.arange(n + 2), trk.left, trk.right, closed=True)
    lap = simulate_lap(t2, range_m=20.0)
    seen = seen_by(t2.cones, lap, 20.0)
    assert seen[0, n] and not seen[0, n + 1]
    for k in (0, len(lap) // 2 + 20, len(lap) - 1):
        f = lap.frame(k)
        src = set(f.source.tolist())
        for j in (n, n + 1):
            assert (j in src) == bool(seen[k, j])
            # An unlabelled cone is never part of the ground truth.
            assert j not in set(f.source[f.gt_left].tolist()) | set(f.source[f.gt_right].tolist())
    assert {n, n + 1} <= set(lap.frame(len(lap) - 1).source.tolist())


def test_frames_are_reproducible():
    trk = track(2)
    a = simulate_lap(trk, range_m=30.0, fp_rate=0.3, seed=11)
    b = simulate_lap(trk, range_m=30.0, fp_rate=0.3, seed=11)
    for k in (0, 57, len(a) - 1):
        fa, fb = a.frame(k), b.frame(k)
        np.testing.assert_array_equal(fa.source, fb.source)
        np.testing.assert_array_equal(fa.cones, fb.cones)
        np.testing.assert_array_equal(fa.gt_left, fb.gt_left)
        np.testing.assert_array_equal(fa.gt_right, fb.gt_right)


# --------------------------------------------------------------------------------------------
# Step 4: false positives
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("rate,count", [(0.0, 0), (0.1, 7), (0.3, 26), (0.5, 60)])
def test_false_positive_count_hand_worked(rate, count):
    # The ring has 24 + 36 = 60 real cones: round(r / (1 - r) * 60) is
    # 0.1 -> 60 / 9 = 6.67 -> 7, 0.3 -> 180 / 7 = 25.71 -> 26, 0.5 -> 60.
    trk = ring_track()
    assert trk.cones.shape[0] == 60
    lap = simulate_lap(trk, range_m=10.0, fp_rate=rate, seed=1)
    assert lap.false_positives.shape == (count, 2)
    last = lap.frame(len(lap) - 1)
    assert int(np.sum(last.source < 0)) == count


@pytest.mark.parametrize("rate", [0.1, 0.3, 0.5])
@pytest.mark.parametrize("seed", SEEDS)
def test_false_positive_count_formula(seed, rate):
    trk = track(seed)
    lap = simulate_lap(trk, range_m=30.0, fp_rate=rate, seed=seed)
    n_real = trk.cones.shape[0]
    expected = round(rate / (1 - rate) * n_real)
    assert len(lap.false_positives) == expected
    # Every one of them joins the map within the lap.
    last = lap.frame(len(lap) - 1)
    assert int(np.sum(last.source < 0)) == expected
    assert sorted(last.source[last.source < 0].tolist()) == list(range(-expected, 0))
    assert int(np.sum(last.source >= 0)) == n_real


def test_false_positives_persistent_and_seeded():
    trk = track(2)
    lap = simulate_lap(trk, range_m=30.0, fp_rate=0.3, seed=5)
    fps = lap.false_positives
    again = simulate_lap(trk, range_m=30.0, fp_rate=0.3, seed=5).false_positives
    other = simulate_lap(trk, range_m=30.0, fp_rate=0.3, seed=6).false_positives
    np.testing.assert_array_equal(fps, again)
    assert fps.shape == other.shape
    assert not np.any(np.all(np.isclose(fps[:, None, :], other[None, :, :]), axis=2))
    # The same positions in every frame where present.
    for k in frame_ks(lap):
        f = lap.frame(k)
        m = f.source < 0
        np.testing.assert_array_equal(f.cones[m], fps[-1 - f.source[m]])
    # fp_rate 0: no false positives at all.
    clean = simulate_lap(trk, range_m=30.0, fp_rate=0.0, seed=5)
    assert clean.false_positives.shape == (0, 2)
    assert np.all(clean.frame(len(clean) - 1).source >= 0)


@pytest.mark.parametrize("seed", SEEDS)
def test_false_positives_lie_in_the_union_of_the_fields(seed):
    trk = track(seed)
    range_m = 20.0
    lap = simulate_lap(trk, range_m=range_m, fp_rate=0.9, seed=seed)  # about 1200 points
    fps = lap.false_positives
    assert len(fps) == round(9 * trk.cones.shape[0])
    seen = seen_by(fps, lap, range_m)
    assert seen[-1].all()
    ps = poses(lap)
    centre = np.array([p.xy for p in ps])
    heading = np.array([p.heading for p in ps])
    # Spread over the whole union: along each of 8 directions u, the union reaches
    # max_k (c_k . u + R) where u points ahead of pose k, else c_k . u + R |h_k x u| (an end of
    # the half-disc's diameter). The farthest false positive comes within 3 m of it.
    for a in np.arange(8) * math.pi / 4:
        u = np.array([math.cos(a), math.sin(a)])
        cross = np.abs(heading[:, 0] * u[1] - heading[:, 1] * u[0])
        reach = np.max(centre @ u + np.where(heading @ u >= 0, range_m, range_m * cross))
        far = float(np.max(fps @ u))
        assert reach - 3.0 < far <= reach + 1e-9, a
    # Uniform over the union: the share of false positives within 3 m of the centreline matches
    # the share of the union's area there (Monte Carlo on the union), within 4 sigma.
    lo, hi = centre.min(axis=0) - range_m, centre.max(axis=0) + range_m
    rng = np.random.default_rng(0)
    cand = rng.uniform(lo, hi, size=(6000, 2))
    cand = cand[seen_by(cand, lap, range_m)[-1]]

    def near_road(p):
        d = np.hypot(*(p[:, None, :] - centre[None, :, :]).transpose(2, 0, 1))
        return d.min(axis=1) < 3.0

    share = near_road(cand).mean()
    n = len(fps)
    got = near_road(fps).sum()
    sigma = math.sqrt(n * share * (1 - share))
    assert 0.05 < share < 0.6
    assert abs(got - n * share) < 4 * sigma + 1


# --------------------------------------------------------------------------------------------
# Step 5: the ground-truth lane
# --------------------------------------------------------------------------------------------


def check_gt_side(f: Frame, trk: Track, side: np.ndarray, gt: np.ndarray, seq: np.ndarray):
    in_map = set(f.source.tolist())
    n = side.size
    # The whole boundary as frame indices, -1 where not yet in the map.
    assert seq.shape == (n,)
    for i in range(n):
        if side[i] in in_map:
            assert seq[i] >= 0 and f.source[seq[i]] == side[i]
        else:
            assert seq[i] == -1
    src = f.source[gt]
    assert all(s in in_map for s in src.tolist())
    # The candidates: labelled cones of this side, in the map, not behind the car.
    loc = f.pose.to_local(trk.cones[side])
    ok = (loc[:, 0] >= 0) & np.array([s in in_map for s in side.tolist()])
    if not ok.any():
        assert gt.size == 0
        return
    start = int(np.argmin(np.where(ok, np.hypot(loc[:, 0], loc[:, 1]), np.inf)))
    assert gt.size >= 1
    pos = {int(c): i for i, c in enumerate(side)}
    idx = [pos[int(s)] for s in src]
    assert idx[0] == start
    # Follows the boundary order, one cone at a time (cyclic on a closed track).
    assert all((b - a) % n == 1 for a, b in zip(idx[:-1], idx[1:], strict=False))
    assert len(idx) <= n
    # Stops before the first cone not yet in the map (or after the whole loop).
    if len(idx) < n:
        nxt = (idx[-1] + 1) % n
        assert side[nxt] not in in_map
    return start


@pytest.mark.parametrize("seed,range_m", [(2, 30.0), (3, 50.0), (2, 12.0)])
def test_ground_truth_lane(seed, range_m):
    trk = track(seed)
    lap = simulate_lap(trk, range_m=range_m, fp_rate=0.1, seed=seed)
    starts = {"left": [], "right": []}
    for k in frame_ks(lap):
        f = lap.frame(k)
        for name, side, gt, seq in (
            ("left", trk.left, f.gt_left, f.left_seq),
            ("right", trk.right, f.gt_right, f.right_seq),
        ):
            start = check_gt_side(f, trk, side, gt, seq)
            starts[name].append(start)
            # Only real labelled cones.
            assert np.all(f.source[gt] >= 0)
    # The start moves forward along the boundary as the car drives (a few cones per 10 m).
    for name, side in (("left", trk.left), ("right", trk.right)):
        s = np.array(starts[name][:-1])
        adv = np.diff(s) % side.size
        assert adv.max() <= 10 and adv.sum() > 0.8 * side.size


def test_ground_truth_is_the_whole_loop_late_at_50m():
    for seed in SEEDS:
        trk = track(seed)
        lap = simulate_lap(trk, range_m=50.0)
        first, last = lap.frame(0), lap.frame(len(lap) - 1)
        assert not first.gt_closed
        assert last.gt_closed
        assert last.gt_left.size == trk.left.size and last.gt_right.size == trk.right.size
        assert set(last.source[last.gt_left].tolist()) == set(trk.left.tolist())
        # Early on with a short range it is not.
        short = simulate_lap(trk, range_m=12.0)
        mid = short.frame(len(short) // 2)
        assert not mid.gt_closed
        assert 0 < mid.gt_left.size < trk.left.size


def test_ground_truth_on_a_ring_hand_worked():
    # Ring: left cone i at r 8, angle 15 (i + 0.5) deg; right cone j at r 12, angle 10 (j + 0.5)
    # deg (track index 24 + j). The lap starts at the midpoint of left 0 (7.5 deg) and right 0
    # (5 deg): (9.943, 1.045), at about 6 deg, heading along the tangent (-sin 6, cos 6).
    # With range 5 m:
    #   left 0 (7.93, 1.04): 2.0 m, ahead;  left 1 (7.39, 3.06): 3.25 m, ahead;
    #   left 2 (6.35, 4.87): 5.25 m, out of range;
    #   right 0 (11.95, 1.05): ahead component -0.21 m, behind the car;
    #   right 1 (11.59, 3.11): 2.64 m, ahead; right 2 (10.88, 5.07): 4.13 m, ahead;
    #   right 3 (9.83, 6.88): 5.84 m, out of range.
    trk = ring_track()
    lap = simulate_lap(trk, range_m=5.0)
    f = lap.frame(0)
    np.testing.assert_allclose(f.pose.xy, (9.943, 1.045), atol=2e-3)
    # Right 0, behind the car from the start, is not in the map yet.
    assert sorted(f.source.tolist()) == [0, 1, 25, 26]
    # The ground truth starts at the nearest cone not behind the car (right 1, not right 0).
    assert f.source[f.gt_left].tolist() == [0, 1]
    assert f.source[f.gt_right].tolist() == [25, 26]
    assert not f.gt_closed


# --------------------------------------------------------------------------------------------
# Validation
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("fp_rate", [-0.1, 1.0, 1.5, math.nan])
def test_bad_fp_rate(fp_rate):
    with pytest.raises(ValueError, match="fp_rate"):
        simulate_lap(ring_track(), range_m=10.0, fp_rate=fp_rate)


@pytest.mark.parametrize("range_m", [0.0, -5.0, math.nan, math.inf])
def test_bad_range(range_m):
    with pytest.raises(ValueError, match="range"):
        simulate_lap(ring_track(), range_m=range_m)


def test_edge_values_are_accepted():
    lap = simulate_lap(ring_track(), range_m=0.5, fp_rate=0.0)
    assert len(lap) > 0
    lap = simulate_lap(ring_track(n_in=16, n_out=24), range_m=10.0, fp_rate=0.99)
    assert lap.false_positives.shape == (3960, 2)  # 0.99 / 0.01 * 40

"""Per-pose metrics of the evaluation protocol (DESIGN.md, "Evaluation protocol", step 7) and the
stability ratio of Huang et al. (2009, section 3.5, eq. 5).

Every expected number below is worked out by hand in the comments (or by a brute force that
does not share code with ``rld.metrics``).
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from rld.generator import generate_track
from rld.metrics import (
    CATEGORIES,
    GEOMETRIC_STEP_M,
    PoseScore,
    _from_line,
    candidate_ious,
    categorize,
    circle_crossing,
    kept_part,
    lane_iou,
    lane_iou20,
    lanes_agree,
    reference_line,
    score_lane,
    side_agreement,
    side_deviation,
    side_divergence,
    stability_ratio,
    true_lane_extent,
    truncate_polyline,
)
from rld.simulation import Frame, simulate_lap
from rld.types import Pose

SQRT13 = math.sqrt(13.0)  # car at the origin to the first cone at (3, +-2)
ORIGIN = Pose(0.0, 0.0, 0.0)


# --------------------------------------------------------------------------------------------
# Hand-built frames
# --------------------------------------------------------------------------------------------


class Hand:
    """A hand-built frame over explicit boundaries.

    ``L[i]``, ``R[i]``, ``X[k]`` are the frame indices of left cone i, right cone i and extra
    (false-positive) point k; ``gt_left`` / ``gt_right`` are positions along the boundaries;
    ``missing_left`` / ``missing_right`` are positions not yet in the map. ``perm`` shuffles the
    frame (to check that nothing depends on the frame order).
    """

    def __init__(
        self,
        left_xy,
        right_xy,
        gt_left=None,
        gt_right=None,
        extra=(),
        pose=ORIGIN,
        closed=False,
        missing_left=(),
        missing_right=(),
        perm_seed=None,
    ):
        left_xy = np.asarray(left_xy, float).reshape(-1, 2)
        right_xy = np.asarray(right_xy, float).reshape(-1, 2)
        extra = np.asarray(extra, float).reshape(-1, 2)
        nl, nr, nx = len(left_xy), len(right_xy), len(extra)
        allxy = np.vstack([left_xy, right_xy, extra])
        source_all = np.concatenate([np.arange(nl + nr), -1 - np.arange(nx)])
        keep = np.ones(len(allxy), dtype=bool)
        keep[np.asarray(missing_left, dtype=int)] = False
        keep[nl + np.asarray(missing_right, dtype=int)] = False
        members = np.flatnonzero(keep)
        if perm_seed is not None:
            members = members[np.random.default_rng(perm_seed).permutation(members.size)]
        to_frame = np.full(len(allxy), -1, dtype=np.int64)
        to_frame[members] = np.arange(members.size)
        self.L = to_frame[:nl]
        self.R = to_frame[nl : nl + nr]
        self.X = to_frame[nl + nr :]
        gl = np.arange(nl) if gt_left is None else np.asarray(gt_left, dtype=int)
        gr = np.arange(nr) if gt_right is None else np.asarray(gt_right, dtype=int)
        self.frame = Frame(
            index=0,
            pose=pose,
            cones=allxy[members],
            source=source_all[members],
            gt_left=self.L[gl],
            gt_right=self.R[gr],
            left_seq=self.L.copy(),
            right_seq=self.R.copy(),
            closed=closed,
        )

    def score(self, left, right, ok=True, closed=False) -> PoseScore:
        return score_lane(self.frame, np.asarray(left, int), np.asarray(right, int), ok, closed)


def straight(n, spacing=3.0, first=3.0, half_width=2.0):
    """n cones per side along +x, ``spacing`` apart from x = ``first``, at y = +-half_width."""
    x = first + spacing * np.arange(n)
    return (
        np.column_stack([x, np.full(n, half_width)]),
        np.column_stack([x, np.full(n, -half_width)]),
    )


# --------------------------------------------------------------------------------------------
# The ground truth scores "gt"
# --------------------------------------------------------------------------------------------


@pytest.mark.parametrize("perm_seed", [None, 3])
def test_ground_truth_is_gt_on_hand_frame(perm_seed):
    left, right = straight(6)
    h = Hand(left, right, perm_seed=perm_seed)
    s = h.score(h.frame.gt_left, h.frame.gt_right)
    assert s.category == s.category_tolerant == "gt"
    assert s.exact
    assert s.iou == pytest.approx(1.0)
    assert s.iou20 == pytest.approx(1.0)
    assert s.divergence_m == math.inf and s.divergence_tolerant_m == math.inf
    assert not s.critical and not s.critical_tolerant
    # Lengths: 5 gaps of 3 m per side.
    assert s.true_length_m == pytest.approx(15.0)
    assert s.pred_length_m == pytest.approx(15.0)


@pytest.mark.parametrize("seed", [0, 3])
def test_ground_truth_is_gt_on_simulated_frames(seed):
    lap = simulate_lap(generate_track(seed), range_m=50.0, fp_rate=0.3, seed=seed)
    ks = list(range(5, len(lap), 60)) + [len(lap) - 1]
    saw_closed = False
    for k in ks:
        f = lap.frame(k)
        assert f.gt_left.size >= 3 and f.gt_right.size >= 3
        s = score_lane(f, f.gt_left, f.gt_right, closed=f.gt_closed)
        saw_closed |= f.gt_closed
        assert s.category == "gt" and s.category_tolerant == "gt", k
        assert s.exact
        # The true polygon ends where a side runs past the other's reach (true_lane_extent);
        # the truth's own untrimmed sides then cover a little more than it.
        trimmed = true_lane_extent(f.cones[f.gt_left], f.cones[f.gt_right]) != (
            f.gt_left.size, f.gt_right.size)
        if trimmed and not f.gt_closed:
            assert 0.95 <= s.iou <= 1.0 + 1e-9
        else:
            assert s.iou == pytest.approx(1.0)
        assert s.iou20 == pytest.approx(1.0)
        assert s.deviation_m == pytest.approx(0.0, abs=1e-9)
        assert s.divergence_m == math.inf
        assert not s.critical
    assert saw_closed  # the last frame at R = 50 holds the whole loop


# --------------------------------------------------------------------------------------------
# Divergence and categories
# --------------------------------------------------------------------------------------------


def hairpin():
    """A left U-turn: out along +x (left y=+2, right y=-2, cones at x=3,6,9,12), a half turn
    around (12, 6) (left radius 4, right radius 8), and back along -x (left y=10, right y=14,
    cones at x=9,6,3). The infield between the legs is 8 m wide."""
    lx = [(3, 2), (6, 2), (9, 2), (12, 2)]
    lx += [(12 + 4 * math.cos(a), 6 + 4 * math.sin(a)) for a in np.radians([-45, 0, 45, 90])]
    lx += [(9, 10), (6, 10), (3, 10)]
    rx = [(3, -2), (6, -2), (9, -2), (12, -2)]
    rx += [
        (12 + 8 * math.cos(a), 6 + 8 * math.sin(a)) for a in np.radians([-60, -30, 0, 30, 60, 90])
    ]
    rx += [(9, 14), (6, 14), (3, 14)]
    return np.array(lx), np.array(rx)


def test_shortcut_across_the_infield_is_critical():
    left, right = hairpin()
    h = Hand(left, right)
    # The left boundary takes (3,2), (6,2), (9,2), then cuts across the infield to (9,10) on the
    # way back and follows it: a shortcut at about 10 m.
    pred_left = h.L[[0, 1, 2, 8, 9, 10]]
    s = h.score(pred_left, h.frame.gt_right)
    # Arc along the truth from the car to the last matched cone (9, 2): sqrt(3^2+2^2) + 3 + 3.
    expected = SQRT13 + 6.0
    assert expected == pytest.approx(9.6056, abs=1e-4)
    assert s.category == "diverging_lt20"
    assert s.critical
    assert s.divergence_m == pytest.approx(expected)
    # (9, 10) is a boundary cone: the tolerant rule does not excuse it.
    assert s.category_tolerant == "diverging_lt20" and s.critical_tolerant
    assert s.divergence_tolerant_m == pytest.approx(expected)
    assert not s.exact


def test_lane_divergence_is_the_minimum_over_sides():
    left, right = straight(20)
    h = Hand(left, right, extra=[(30.0, 5.0), (12.0, -5.0)])
    # Left leaves after left cone 8 (x = 27): sqrt(13) + 24. Right leaves after right cone 2
    # (x = 9): sqrt(13) + 6.
    pl = np.concatenate([h.L[:9], h.X[[0]], h.L[10:]])
    pr = np.concatenate([h.R[:3], h.X[[1]], h.R[4:]])
    assert h.score(pl, h.frame.gt_right).divergence_m == pytest.approx(SQRT13 + 24.0)
    assert h.score(h.frame.gt_left, pr).divergence_m == pytest.approx(SQRT13 + 6.0)
    s = h.score(pl, pr)
    assert s.divergence_m == pytest.approx(SQRT13 + 6.0)
    assert s.category == "diverging_lt20"


def test_cut_two_cones_short_is_too_short():
    # 4 cones per side, 3 m apart: each true side is 9 m long.
    left, right = straight(4)
    h = Hand(left, right)
    s = h.score(h.L[:2], h.R[:2])  # 3 m < 4.5 m
    assert s.category == "too_short" and s.category_tolerant == "too_short"
    assert not s.critical
    assert s.divergence_m == math.inf
    assert s.pred_length_m == pytest.approx(3.0) and s.true_length_m == pytest.approx(9.0)
    # One side short is enough.
    assert h.score(h.L[:2], h.R).category == "too_short"
    # One cone short keeps 6 m >= 4.5 m: near_gt.
    s1 = h.score(h.L[:3], h.R[:3])
    assert s1.category == "near_gt"
    assert s1.divergence_m == math.inf


def test_stopping_early_but_keeping_more_than_half_is_near_gt():
    # 20 cones per side, x = 3..60: each side 57 m. Half: 28.5 m.
    left, right = straight(20)
    h = Hand(left, right)
    assert h.score(h.L[:12], h.R).category == "near_gt"  # 33 m
    assert h.score(h.L[:10], h.R).category == "too_short"  # 27 m


def test_divergence_after_20m_with_high_iou_is_near_gt():
    left, right = straight(20)
    # Left cone 9 at (30, 2) replaced by a point 0.3 m off the line.
    h = Hand(left, right, extra=[(30.0, 2.3)])
    pl = np.concatenate([h.L[:9], h.X[[0]], h.L[10:]])
    s = h.score(pl, h.R)
    # Truth: rectangle [3, 60] x [-2, 2] = 228 m^2. Prediction adds a triangle of base 6 m
    # (27..33) and height 0.3 m = 0.9 m^2.
    assert s.iou == pytest.approx(228.0 / 228.9)
    assert s.divergence_m == pytest.approx(SQRT13 + 24.0)  # last match at x = 27
    assert s.category == "near_gt"
    assert not s.critical


def test_divergence_after_20m_with_low_iou_is_diverging_ge20():
    left, right = straight(20)
    h = Hand(left, right, extra=[(27.0, -1.0)])
    pl = np.concatenate([h.L[:9], h.X[[0]]])
    s = h.score(pl, h.R)
    # Prediction: [3, 27] x [-2, 2] (96 m^2) plus the triangle (27,-1), (60,-2), (27,-2)
    # (0.5 * 33 * 1 = 16.5 m^2), all inside the truth (228 m^2): IoU = 112.5 / 228.
    assert s.iou == pytest.approx(112.5 / 228.0)
    assert s.divergence_m == pytest.approx(SQRT13 + 24.0)
    assert s.category == "diverging_ge20"
    assert not s.critical


def test_cone_taken_after_the_truth_ends_diverges():
    left, right = straight(4)
    h = Hand(left, right, extra=[(15.0, 2.0)])  # on the extension of the left line, past its end
    s = h.score(np.concatenate([h.L, h.X]), h.R)
    # Every true cone was matched: sqrt(13) + 9 m.
    assert s.divergence_m == pytest.approx(SQRT13 + 9.0)
    assert s.category == "diverging_lt20"


def test_prefix_rule():
    # Left and right cones at x = -16.5 + 3 i, i = 0..15: six behind the car, ten ahead. The truth
    # starts at i = 6 (x = 1.5, the nearest not behind the car).
    x = -16.5 + 3.0 * np.arange(16)
    left = np.column_stack([x, np.full(16, 2.0)])
    right = np.column_stack([x, np.full(16, -2.0)])
    h = Hand(left, right, gt_left=range(6, 16), gt_right=range(6, 16), extra=[(1.5, 0.0)])
    gr = h.frame.gt_right

    def left_cat(pos, first=()):
        pl = np.concatenate([np.asarray(first, int), h.L[list(pos)]])
        return h.score(pl, gr)

    # Up to five boundary cones preceding gt[0] are fine.
    for n_pre in range(1, 6):
        s = left_cat(range(6 - n_pre, 16))
        assert s.category == "near_gt" and s.divergence_m == math.inf, n_pre
        assert not s.exact
    # Six are not: the first cone is neither a permitted prefix nor gt[0] / gt[1].
    s = left_cat(range(0, 16))
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0 and s.critical
    # gt[0] may be skipped (start at gt[1]), also after a prefix ...
    s = left_cat(range(7, 16))
    assert s.category == "near_gt" and s.divergence_m == math.inf
    s = left_cat([4, 5] + list(range(7, 16)))
    assert s.category == "near_gt" and s.divergence_m == math.inf
    # ... but not gt[0] and gt[1] both.
    s = left_cat(range(8, 16))
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0
    # A prefix walking backwards is not a prefix.
    s = left_cat([5, 4] + list(range(6, 16)))
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0
    # Starting with a cone of the wrong kind (the other boundary, or a false positive) diverges
    # at 0 m.
    s = left_cat(range(6, 16), first=[h.R[6]])
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0 and s.critical
    s = left_cat(range(6, 16), first=[h.X[0]])
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0 and s.critical


def test_prefix_rule_wraps_around_a_closed_boundary():
    # A ring: left (inner) radius 8 with 16 cones, right radius 12 with 24 cones, driven
    # counter-clockwise; the car at (10, 0) heading +y. Cone i sits at angle 2 pi (i + 0.5) / n,
    # so left 0 and right 0 are just ahead of the car and the last ones just behind it.
    def ring(r, n):
        a = 2 * math.pi * (np.arange(n) + 0.5) / n
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    left, right = ring(8.0, 16), ring(12.0, 24)
    kwargs = dict(
        gt_left=range(0, 8),
        gt_right=range(0, 12),
        pose=Pose(10.0, 0.0, math.pi / 2),
        missing_left=range(8, 12),
        missing_right=range(12, 20),
    )
    closed = Hand(left, right, closed=True, **kwargs)
    f = closed.frame
    assert (f.left_seq[8:12] == -1).all() and (f.right_seq[12:20] == -1).all()
    pl = closed.L[[14, 15] + list(range(0, 8))]  # two cones before gt[0], across the wrap
    s = closed.score(pl, f.gt_right)
    assert s.category == "near_gt" and s.divergence_m == math.inf
    # The same prediction on an open boundary: 14 and 15 come after 0, not before it.
    opened = Hand(left, right, closed=False, **kwargs)
    s = opened.score(opened.L[[14, 15] + list(range(0, 8))], opened.frame.gt_right)
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0


def test_tolerant_rule_uses_the_closing_segment_of_a_closed_boundary():
    # Same ring; a false positive 0.2 m outside the chord from left 15 (-11.25 deg) to left 0
    # (+11.25 deg), whose midpoint is (8 cos 11.25 deg, 0). Its nearest other left segment is
    # more than 1 m away, so only the closing segment makes it "on the line".
    def ring(r, n):
        a = 2 * math.pi * (np.arange(n) + 0.5) / n
        return np.column_stack([r * np.cos(a), r * np.sin(a)])

    fp = (8 * math.cos(math.radians(11.25)) + 0.2, 0.0)
    h = Hand(
        ring(8.0, 16),
        ring(12.0, 24),
        gt_left=range(0, 16),
        gt_right=range(0, 24),
        extra=[fp],
        pose=Pose(10.0, 0.0, math.pi / 2),
        closed=True,
    )
    pl = np.concatenate([h.X, h.L])
    s = h.score(pl, h.R, closed=True)
    assert s.category == "diverging_lt20" and s.divergence_m == 0.0
    assert s.category_tolerant == "near_gt" and s.divergence_tolerant_m == math.inf


def test_tolerant_rule_skips_points_on_the_true_line():
    left, right = straight(10)
    # Between left cones 2 (x=9) and 3 (x=12): 0.3 m, 0.45 m, 0.6 m and 1 m off the left line.
    h = Hand(left, right, extra=[(10.5, 2.3), (10.5, 1.55), (10.5, 2.6), (10.5, 3.0)])
    strict_div = SQRT13 + 6.0  # last true cone before the point: x = 9
    for k, tolerated in ((0, True), (1, True), (2, False), (3, False)):
        pl = np.concatenate([h.L[:3], h.X[[k]], h.L[3:]])
        s = h.score(pl, h.R)
        assert s.category == "diverging_lt20" and s.critical, k
        assert s.divergence_m == pytest.approx(strict_div), k
        if tolerated:
            assert s.category_tolerant == "near_gt" and not s.critical_tolerant, k
            assert s.divergence_tolerant_m == math.inf, k
        else:
            assert s.category_tolerant == "diverging_lt20" and s.critical_tolerant, k
            assert s.divergence_tolerant_m == pytest.approx(strict_div), k


def test_tolerant_rule_lets_a_point_on_the_line_stand_in_for_a_true_cone():
    left, right = straight(10)
    # Left cone 3 stands at (12, 2); a false positive 0.1 m off the line, 0.22 m from it.
    h = Hand(left, right, extra=[(12.2, 2.1)])
    strict_div = SQRT13 + 6.0  # the last true cone matched before it: x = 9
    instead = np.concatenate([h.L[:3], h.X, h.L[4:]])  # the FP in place of cone 3
    besides = np.concatenate([h.L[:3], h.X, h.L[3:]])  # the FP and cone 3 (forgiven before)
    for pl in (instead, besides):
        s = h.score(pl, h.R)
        assert s.category == "diverging_lt20" and s.divergence_m == pytest.approx(strict_div)
        assert s.category_tolerant == "near_gt" and s.divergence_tolerant_m == math.inf
    # Cone 3 skipped with no point in its place: a divergence under both rules.
    s = h.score(np.concatenate([h.L[:3], h.L[4:]]), h.R)
    assert s.divergence_m == s.divergence_tolerant_m == pytest.approx(strict_div)


def test_a_stand_in_must_keep_the_skipped_true_cone_within_half_a_metre():
    # A left boundary that turns: (9, 2) -> (11.5, 4) -> (12, 7). A false positive on the line
    # beside (9, 2) and then (12, 7): the skipped cone (11.5, 4) lies 1.01 m from that polyline
    # (the segment from (9.3, 2.1) to (12, 7): cross product 5.65 over its length 5.595).
    left = np.array([(3, 2), (6, 2), (9, 2), (11.5, 4), (12, 7), (12, 10)], float)
    right = np.array([(3, -2), (6, -2), (9, -2), (14, 1), (16, 6), (16, 10)], float)
    h = Hand(left, right, extra=[(9.3, 2.1)])
    s = h.score(np.concatenate([h.L[:3], h.X, h.L[4:]]), h.R)
    assert s.critical_tolerant
    assert s.divergence_tolerant_m == pytest.approx(SQRT13 + 6.0)
    # Moved to (10, 3) the skipped cone is 0.18 m from it (cross 1.0 / 5.595): forgiven.
    left[3] = (10.0, 3.0)
    h = Hand(left, right, extra=[(9.3, 2.1)])
    assert not h.score(np.concatenate([h.L[:3], h.X, h.L[4:]]), h.R).critical_tolerant


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(st.integers(0, 8), st.floats(-0.8, 0.8), st.booleans()),
                min_size=1, max_size=4))
def test_tolerant_divergence_is_never_nearer_than_strict(points):
    """Points near the left line (offset up to 0.8 m), each inserted after true cone i or put in
    its place: the tolerant rule forgives at least what the strict one does."""
    left, right = straight(10)
    extra = [(left[i, 0] + 1.0, left[i, 1] + dy) for i, dy, _ in points]
    h = Hand(left, right, extra=extra)
    pl = list(h.L)
    # Apply from the back so the positions stay valid; a replacement drops true cone i + 1.
    for k in sorted(range(len(points)), key=lambda k: -points[k][0]):
        i, _, replace = points[k]
        at = pl.index(h.L[i]) + 1
        if replace and at < len(pl) and pl[at] in h.L:
            pl[at] = h.X[k]
        else:
            pl.insert(at, h.X[k])
    s = h.score(np.array(pl), h.R)
    assert s.divergence_tolerant_m >= s.divergence_m
    assert not (s.critical_tolerant and not s.critical)


def test_tolerant_rule_does_not_excuse_boundary_cones():
    # A right cone 0.3 m from the left line (a very narrow lane) is on a boundary: not skipped.
    left = np.array([(3, 2), (6, 2), (9, 2), (12, 2)], float)
    right = np.array([(3, -2), (6, -2), (10.5, 1.7), (12, -2)], float)
    h = Hand(left, right)
    pl = np.concatenate([h.L[:3], h.R[[2]], h.L[3:]])
    s = h.score(pl, h.R)
    assert s.category_tolerant == "diverging_lt20"
    assert s.divergence_tolerant_m == pytest.approx(SQRT13 + 6.0)


def test_failed():
    left, right = straight(4)
    h = Hand(left, right)
    s = h.score(h.L, h.R, ok=False)
    assert s.category == s.category_tolerant == "failed"
    assert s.critical and s.critical_tolerant
    assert s.iou == 0.0
    assert s.true_length_m == pytest.approx(9.0)
    s = h.score([], [])
    assert s.category == s.category_tolerant == "failed" and s.critical
    # One empty side is not "failed": it stopped early at 0 m.
    s = h.score(h.L, [])
    assert s.category == "too_short" and not s.critical


def test_categories_and_precedence():
    assert set(CATEGORIES) == {
        "gt",
        "near_gt",
        "too_short",
        "diverging_ge20",
        "diverging_lt20",
        "failed",
    }
    from rld.metrics import SideDivergence

    fine = SideDivergence(False, math.inf, False, 5)
    short = SideDivergence(False, math.inf, True, 2)
    near = SideDivergence(True, 19.99, False, 3)
    far = SideDivergence(True, 20.0, False, 8)
    lens, true = (10.0, 10.0), (10.0, 10.0)
    assert categorize(False, True, (fine, fine), 1.0, lens, true) == "failed"
    assert categorize(True, True, (near, near), 0.0, lens, true) == "gt"
    assert categorize(True, False, (near, far), 1.0, lens, true) == "diverging_lt20"
    assert categorize(True, False, (fine, far), 0.9, lens, true) == "near_gt"
    assert categorize(True, False, (fine, far), 0.899, lens, true) == "diverging_ge20"
    assert categorize(True, False, (fine, far), math.nan, lens, true) == "diverging_ge20"
    assert categorize(True, False, (short, fine), 0.5, (4.99, 10.0), true) == "too_short"
    assert categorize(True, False, (short, fine), 0.5, (5.0, 10.0), true) == "near_gt"
    assert categorize(True, False, (fine, fine), 0.5, (1.0, 1.0), true) == "near_gt"


def test_side_divergence_direct():
    cones = np.array([(3, 2), (6, 2), (9, 2), (12, 2), (5, 5)], float)
    gt = np.array([0, 1, 2, 3])
    car = np.zeros(2)
    d = side_divergence(np.array([0, 1, 2, 3]), gt, gt, cones, car, False)
    assert not d.diverged and not d.stopped_early and d.matched == 4
    d = side_divergence(np.array([0, 1]), gt, gt, cones, car, False)
    assert not d.diverged and d.stopped_early and d.matched == 2
    d = side_divergence(np.array([0, 1, 4]), gt, gt, cones, car, False)
    assert d.diverged and d.matched == 2 and d.distance_m == pytest.approx(SQRT13 + 3.0)
    d = side_divergence(np.array([1, 2, 4]), gt, gt, cones, car, False)  # skipped gt[0]
    assert d.diverged and d.distance_m == pytest.approx(SQRT13 + 6.0)
    d = side_divergence(np.zeros(0, int), gt, gt, cones, car, False)
    assert not d.diverged and d.stopped_early
    d = side_divergence(np.array([0]), np.zeros(0, int), gt, cones, car, False)
    assert d.diverged and d.distance_m == 0.0
    skip = np.array([False, False, False, False, True])
    d = side_divergence(np.array([0, 1, 4, 2, 3]), gt, gt, cones, car, False, skip)
    assert not d.diverged and d.matched == 4


# --------------------------------------------------------------------------------------------
# IoU and IoU20
# --------------------------------------------------------------------------------------------


def rect_lane(x0, x1, half_width, n=5):
    x = np.linspace(x0, x1, n)
    return (
        np.column_stack([x, np.full(n, half_width)]),
        np.column_stack([x, np.full(n, -half_width)]),
    )


def test_lane_iou_hand_worked():
    a = rect_lane(0, 10, 2)  # 10 x 4
    b = rect_lane(0, 5, 2)  # 5 x 4, sharing the end at x = 0
    assert lane_iou(*a, *b) == pytest.approx(0.5)
    assert lane_iou(*b, *a) == pytest.approx(0.5)
    assert lane_iou(*a, *a) == pytest.approx(1.0)
    # Disjoint lanes.
    assert lane_iou(*rect_lane(0, 10, 2), *rect_lane(20, 30, 2)) == 0.0
    # Overlap in both directions: [0,10]x[-2,2] vs [5,15]x[-1,1]: 10 / (40 + 20 - 10).
    assert lane_iou(*a, *rect_lane(5, 15, 1)) == pytest.approx(10.0 / 50.0)
    # No area at all: NaN.
    assert math.isnan(
        lane_iou(np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)), np.zeros((0, 2)))
    )


def test_lane_iou_repairs_crossed_boundaries():
    # Left from (0,2) to (10,-2), right from (0,-2) to (10,2): a bow-tie, repaired into two
    # triangles meeting at (5, 0), each 0.5 * 4 * 5 = 10 m^2, inside the 10 x 4 rectangle.
    bow_l = np.array([(0, 2), (10, -2)], float)
    bow_r = np.array([(0, -2), (10, 2)], float)
    assert lane_iou(bow_l, bow_r, *rect_lane(0, 10, 2)) == pytest.approx(20.0 / 40.0)


def test_lane_iou_closed_lanes():
    def square(h):
        return np.array([(-h, -h), (h, -h), (h, h), (-h, h)], float)

    # Annulus between squares of side 8 and 4: 64 - 16 = 48; between 8 and 2: 64 - 4 = 60.
    # The first lies inside the second: IoU = 48 / 60.
    assert lane_iou(square(2), square(4), square(2), square(4), True, True) == pytest.approx(1.0)
    assert lane_iou(square(2), square(4), square(1), square(4), True, True) == pytest.approx(0.8)
    # The inner ring may be on either side.
    assert lane_iou(square(4), square(2), square(1), square(4), True, True) == pytest.approx(0.8)


@settings(max_examples=60)
@given(
    a=st.floats(1.0, 50.0),
    b=st.floats(1.0, 50.0),
    wa=st.floats(0.5, 4.0),
    wb=st.floats(0.5, 4.0),
)
def test_lane_iou_of_rectangles(a, b, wa, wb):
    inter = min(a, b) * 2 * min(wa, wb)
    union = a * 2 * wa + b * 2 * wb - inter
    assert lane_iou(*rect_lane(0, a, wa, 7), *rect_lane(0, b, wb, 4)) == pytest.approx(
        inter / union, rel=1e-9
    )


def test_lane_iou20_cuts_at_20m():
    heading = np.array([1.0, 0.0])
    # Truth: cones every 5 m from x = 0 to 40, y = +-2 (160 m^2).
    gl, gr = rect_lane(0, 40, 2, 9)
    # Prediction: the same for the first 20 m, then the left side moves out to y = 4 at x = 25.
    pl = gl.copy()
    pl[5:, 1] = 4.0
    # Full IoU: extra triangle (20..25, height 2) = 5 and rectangle [25,40]x[2,4] = 30.
    assert lane_iou(pl, gr, gl, gr) == pytest.approx(160.0 / 195.0)
    assert lane_iou20(pl, gr, gl, gr, heading) == pytest.approx(1.0)
    # A short horizon that is right: IoU 0.5, IoU20 1.
    sl, sr = rect_lane(0, 20, 2, 5)
    assert lane_iou(sl, sr, gl, gr) == pytest.approx(0.5)
    assert lane_iou20(sl, sr, gl, gr, heading) == pytest.approx(1.0)
    # A short horizon that is wrong (half as wide): [0,20]x[-1,1] inside [0,20]x[-2,2].
    wl, wr = rect_lane(0, 20, 1, 5)
    assert lane_iou20(wl, wr, gl, gr, heading) == pytest.approx(40.0 / 80.0)


def test_lane_iou20_measures_from_the_first_true_cones():
    heading = np.array([1.0, 0.0])
    gl, gr = rect_lane(0, 40, 2, 9)
    # The prediction starts 5 m behind the first true cones: its 20 m are measured from where
    # it crosses the line x = 0, so they end at x = 20 like the truth's, and the part behind
    # x = 0 is dropped: IoU20 = 1. (Until 2026-12-02 they were measured from its first cone,
    # ended at x = 15 and gave 60 / 80.)
    pl, pr = rect_lane(-5, 40, 2, 10)
    # Starting behind and half as wide: [0, 20] x 2 inside [0, 20] x 4: 40 / 80.
    wl, wr = rect_lane(-5, 40, 1, 10)
    # Mirrored: driving along -x.
    m = np.array([-1.0, 1.0])
    # Rotated by 37 degrees about an arbitrary point.
    c, s = math.cos(0.65), math.sin(0.65)
    rot = np.array([[c, -s], [s, c]])

    def tf(p):
        return p @ rot.T + np.array([12.0, -7.0])

    for f, h in ((lambda p: p, heading), (lambda p: p * m, -heading), (tf, rot @ heading)):
        assert lane_iou20(f(pl), f(pr), f(gl), f(gr), h) == pytest.approx(1.0)
        assert lane_iou20(f(wl), f(wr), f(gl), f(gr), h) == pytest.approx(0.5)
        # Without a heading the whole-lane IoU counts the 5 m behind against it: 160 / 180;
        # with one, what lies behind x = 0 is dropped.
        assert lane_iou(f(pl), f(pr), f(gl), f(gr)) == pytest.approx(160.0 / 180.0)
        assert lane_iou(f(pl), f(pr), f(gl), f(gr), heading=h) == pytest.approx(1.0)


def test_from_line_hand_worked():
    a0, n = np.array([0.0, 0.0]), np.array([1.0, 0.0])
    xy = np.array([(-4, 0), (-2, 1), (2, 3), (5, 3)], float)
    # Crosses x = 0 halfway between (-2, 1) and (2, 3), at (0, 2).
    np.testing.assert_allclose(_from_line(xy, a0, n), [(0, 2), (2, 3), (5, 3)])
    np.testing.assert_allclose(_from_line(xy[2:], a0, n), xy[2:])
    assert _from_line(xy[:2], a0, n).shape == (0, 2)


def test_true_lane_extent_hand_worked():
    # Left: 4 cones at x = 0, 4, 8, 12 (y = 2); right: 9 cones at x = 0..32 (y = -2), running
    # on past the left's end. Distances of the right cones to the left polyline: 4 while
    # beside it (x <= 12), then hypot(x - 12, 4): 5.66 at x = 16, 8.94 at x = 20. So the right
    # keeps x = 0..16 (5 cones), the left all 4.
    left = np.column_stack([np.arange(0, 13, 4.0), np.full(4, 2.0)])
    right = np.column_stack([np.arange(0, 33, 4.0), np.full(9, -2.0)])
    assert true_lane_extent(left, right) == (4, 5)
    assert true_lane_extent(right, left) == (5, 4)
    assert true_lane_extent(left, right, reach_m=4.5) == (4, 4)
    assert true_lane_extent(left, right, reach_m=9.0) == (4, 6)
    # Sides beside each other all along are kept whole; an empty side leaves the other alone.
    assert true_lane_extent(left, right[:4]) == (4, 4)
    assert true_lane_extent(left, np.zeros((0, 2))) == (4, 0)
    # A first cone already too far is kept (at least one cone per side).
    assert true_lane_extent(left + [0.0, 10.0], right[:4]) == (1, 1)


def test_score_lane_cuts_the_true_lane_to_both_sides_extent():
    # The right truth runs 15 m on past the left's end (x = 3..24 against 3..39).
    left, right = straight(13)
    h = Hand(left, right, gt_left=np.arange(8), gt_right=np.arange(13), missing_left=[8])
    # A lane whose sides both end at x = 24 (left) and x = 27 (right: the last right cone
    # within 6.5 m of the left polyline, hypot(3, 4) = 5): the true polygon is cut the same
    # way, IoU 1. Before 2026-12-02 the whole truth's polygon, closing with a diagonal from
    # (24, 2) to (39, -2), was [3, 24] x 4 = 84 plus a triangle of 0.5 * 15 * 4 = 30, and the
    # lane's 84 + 0.5 * 3 * 4 = 90 inside it: 90 / 114.
    s = h.score(h.L[:8], h.R[:9])
    c = h.frame.cones
    assert lane_iou(c[h.L[:8]], c[h.R[:9]], c[h.frame.gt_left], c[h.frame.gt_right]) == (
        pytest.approx(90.0 / 114.0))
    assert s.iou == pytest.approx(1.0)
    assert s.iou20 == pytest.approx(1.0)
    # The categories still follow each side's whole truth: the right stops before its end
    # but is past half of it.
    assert s.category == "near_gt"
    assert s.true_length_m == pytest.approx((21.0 + 36.0) / 2)


def test_candidate_ious_hand_worked():
    # The frame of the test above: the whole-truth polygon would give 90 / 114, the protocol's
    # truth (cut to both sides' extent) 1; a lane of the left's first 4 cones and the right's
    # first 4 (x = 3..12 on both sides, 9 x 4 = 36 inside the cut truth's 21 x 4 + 6 = 90)
    # gives 36 / 90.
    left, right = straight(13)
    h = Hand(left, right, gt_left=np.arange(8), gt_right=np.arange(13), missing_left=[8])
    got = candidate_ious(h.frame, [(h.L[:8], h.R[:9], False), (h.L[:4], h.R[:4], False)])
    assert got == pytest.approx([1.0, 36.0 / 90.0])
    assert candidate_ious(h.frame, []).shape == (0,)


@pytest.mark.parametrize("seed", [0, 4])
def test_candidate_ious_equal_score_lane_on_clc_candidates(seed):
    """The vectorized IoU that CLC's ranker trains on is the protocol's IoU, candidate by
    candidate, open and closed truths, with false positives (the map's whole candidate list)."""
    from clc.search import enumerate_candidates
    from rld.types import LaneParams

    lap = simulate_lap(generate_track(seed), range_m=50.0, fp_rate=0.3, seed=seed)
    checked = 0
    for k in list(range(3, len(lap), 45)) + [len(lap) - 1]:
        f = lap.frame(k)
        cands = enumerate_candidates(f.cones, f.pose, LaneParams(max_iterations=60)).candidates
        if not cands:
            continue
        got = candidate_ious(f, cands)
        want = [score_lane(f, a, b, closed=c).iou for a, b, c in cands]
        assert got == pytest.approx(want, abs=1e-9), k
        checked += len(cands)
    assert checked > 50


def test_lane_iou20_nan_without_a_true_lane():
    gl, gr = rect_lane(0, 40, 2, 9)
    assert math.isnan(lane_iou20(gl, gr, np.zeros((0, 2)), gr, np.array([1.0, 0.0])))
    assert math.isnan(lane_iou20(gl, gr, gl, np.zeros((0, 2)), np.array([1.0, 0.0])))


def test_score_lane_reports_iou20_of_a_short_correct_lane():
    left, right = straight(14)  # x = 3..42
    h = Hand(left, right)
    # Truth: x = 3..42 (39 m); IoU20 keeps x = 3..23 of it.
    # The first 8 cones per side (x = 3..24, 21 m): IoU 21 / 39, IoU20 1 (both cut at x = 23).
    s = h.score(h.L[:8], h.R[:8])
    assert s.iou == pytest.approx(21.0 / 39.0)
    assert s.iou20 == pytest.approx(1.0)
    assert s.category == "near_gt"  # 21 m >= 19.5 m
    # The first 7 (x = 3..21, 18 m): IoU 18 / 39, IoU20 18 / 20.
    s = h.score(h.L[:7], h.R[:7])
    assert s.iou == pytest.approx(18.0 / 39.0)
    assert s.iou20 == pytest.approx(0.9)
    assert s.category == "too_short"


# --------------------------------------------------------------------------------------------
# truncate_polyline
# --------------------------------------------------------------------------------------------


def test_truncate_polyline_hand_worked():
    xy = np.array([(0, 0), (3, 0), (3, 4)], float)  # 3 + 4 = 7 m
    np.testing.assert_allclose(truncate_polyline(xy, 5.0), [(0, 0), (3, 0), (3, 2)])
    np.testing.assert_allclose(truncate_polyline(xy, 1.5), [(0, 0), (1.5, 0)])
    np.testing.assert_allclose(truncate_polyline(xy, 3.0), [(0, 0), (3, 0)])
    np.testing.assert_allclose(truncate_polyline(xy, 7.0), xy)
    np.testing.assert_allclose(truncate_polyline(xy, 20.0), xy)
    np.testing.assert_allclose(truncate_polyline(xy, 0.0), [(0, 0)])
    one = np.array([(1.0, 2.0)])
    np.testing.assert_allclose(truncate_polyline(one, 5.0), one)
    assert truncate_polyline(np.zeros((0, 2)), 5.0).shape == (0, 2)
    # The input is not modified, and a copy is returned.
    out = truncate_polyline(xy, 20.0)
    out[0] = 99
    assert xy[0, 0] == 0


@settings(max_examples=60)
@given(
    pts=st.lists(st.tuples(st.floats(-30, 30), st.floats(-30, 30)), min_size=2, max_size=8),
    length=st.floats(0.01, 100.0),
)
def test_truncate_polyline_brute_force(pts, length):
    xy = np.array(pts, float)
    total = float(np.hypot(*np.diff(xy, axis=0).T).sum())
    out = truncate_polyline(xy, length)
    got = float(np.hypot(*np.diff(out, axis=0).T).sum()) if len(out) > 1 else 0.0
    assert got == pytest.approx(min(length, total), abs=1e-7)
    # A prefix of the input, plus at most one interpolated end point on the next segment.
    k = len(out) - 1
    np.testing.assert_array_equal(out[:k], xy[:k])
    if k < len(xy):
        a, b = xy[k - 1], xy[k]
        cross = (b - a)[0] * (out[k] - a)[1] - (b - a)[1] * (out[k] - a)[0]
        assert abs(cross) <= 1e-6 * max(1.0, float(np.hypot(*(b - a))) ** 2)


# --------------------------------------------------------------------------------------------
# circle_crossing and the stability ratio (Huang et al. 2009, eq. 5)
# --------------------------------------------------------------------------------------------


def test_circle_crossing_hand_worked():
    c = np.zeros(2)
    # Leaves the r = 5 circle on the segment (3,0)-(3,10) at (3, 4).
    p = circle_crossing(np.array([(0, 0), (3, 0), (3, 10)], float), c, 5.0)
    np.testing.assert_allclose(p, (3, 4))
    # Starting outside: the entry at (5, 0) does not count, the exit at (0, 5) does.
    p = circle_crossing(np.array([(20, 0), (0, 0), (0, 20)], float), c, 5.0)
    np.testing.assert_allclose(p, (0, 5), atol=1e-12)
    # The first exit of several.
    p = circle_crossing(np.array([(0, 0), (10, 0), (0, 3), (0, 10)], float), c, 5.0)
    np.testing.assert_allclose(p, (5, 0), atol=1e-12)
    # Ending exactly on the circle.
    np.testing.assert_allclose(circle_crossing(np.array([(0, 0), (5, 0)], float), c, 5.0), (5, 0))
    # Off-centre circle.
    p = circle_crossing(np.array([(1, 1), (1, 11)], float), np.array([1.0, 1.0]), 5.0)
    np.testing.assert_allclose(p, (1, 6))
    # Never reaching the circle, or a single point.
    assert circle_crossing(np.array([(0, 0), (3, 0), (3, 3)], float), c, 5.0) is None
    assert circle_crossing(np.array([(0, 0)], float), c, 5.0) is None


def test_circle_crossing_segment_passing_through():
    c = np.zeros(2)
    # From (-20, 1) to (20, 1): it enters the r = 5 circle at (-sqrt(24), 1) and leaves it at
    # (sqrt(24), 1).
    p = circle_crossing(np.array([(-20, 1), (20, 1)], float), c, 5.0)
    assert p is not None
    np.testing.assert_allclose(p, (math.sqrt(24.0), 1.0))
    # The same after a first segment that stays outside.
    p = circle_crossing(np.array([(-20, 30), (-20, 1), (20, 1)], float), c, 5.0)
    np.testing.assert_allclose(p, (math.sqrt(24.0), 1.0))
    # A tangent touch at (0, 5) is no crossing; the line does not leave the circle.
    assert circle_crossing(np.array([(-20, 5), (20, 5)], float), c, 5.0) is None
    # Starting on the circle and moving out: never inside, so it never leaves.
    assert circle_crossing(np.array([(5, 0), (10, 0)], float), c, 5.0) is None
    # Starting on the circle and moving in: it leaves on the far side at (-5, 0).
    p = circle_crossing(np.array([(5, 0), (-10, 0)], float), c, 5.0)
    np.testing.assert_allclose(p, (-5, 0), atol=1e-12)


def _first_exit_brute(xy: np.ndarray, r: float, step: float = 0.005):
    """Densely sampled: the first sample at or beyond r that follows a sample inside."""
    samples = []
    for a, b in zip(xy[:-1], xy[1:], strict=False):
        n = max(2, int(np.hypot(*(b - a)) / step) + 2)
        t = np.linspace(0.0, 1.0, n)[:, None]
        samples.append(a + t * (b - a))
    dense = np.vstack(samples)
    inside = np.hypot(*dense.T) < r
    exits = np.flatnonzero(~inside[1:] & inside[:-1]) + 1
    return dense[exits[0]] if exits.size else None


@settings(max_examples=60)
@given(
    pts=st.lists(st.tuples(st.floats(-25, 25), st.floats(-25, 25)), min_size=1, max_size=5),
    r=st.floats(1.0, 20.0),
    from_centre=st.booleans(),
)
def test_circle_crossing_brute_force(pts, r, from_centre):
    # Lines from the car forward (starting at the centre), or from anywhere.
    xy = np.array(pts, float)
    if from_centre or len(xy) < 2:
        xy = np.vstack([[0.0, 0.0], xy])
    # Skip near-tangent cases, which a sampled line cannot resolve.
    a, b = xy[:-1], xy[1:]
    u = b - a
    t = np.clip(-np.einsum("ij,ij->i", a, u) / np.maximum(np.einsum("ij,ij->i", u, u), 1e-12), 0, 1)
    closest = np.hypot(*(a + t[:, None] * u).T)
    assume(np.all(np.abs(closest - r) > 0.05))
    want = _first_exit_brute(xy, r)
    p = circle_crossing(xy, np.zeros(2), r)
    if want is None:
        assert p is None
    else:
        assert p is not None
        assert float(np.hypot(*p)) == pytest.approx(r, abs=1e-7)
        assert float(np.hypot(*(p - want))) < 0.02


def test_stability_ratio_hand_worked():
    c = np.zeros(2)
    line0 = np.array([(0, 0), (20, 0)], float)
    line1 = np.array([(0, 0.3), (20, 0.3)], float)
    # p0 = (10, 0), p1 = (sqrt(100 - 0.09), 0.3).
    expected = math.hypot(10 - math.sqrt(99.91), 0.3)
    assert stability_ratio(line0, line1, c, 10.0, 1.0) == pytest.approx(expected, rel=1e-9)
    assert stability_ratio(line0, line1, c, 10.0, 1.0) == pytest.approx(0.3, abs=1e-3)
    assert stability_ratio(line0, line1, c, 10.0, 2.0) == pytest.approx(expected / 2, rel=1e-9)
    # p0 = (10, 0), p1 = (6, 8) on the line to (12, 16): |p0 - p1| = sqrt(80); d_v = 2.
    line2 = np.array([(0, 0), (12, 16)], float)
    assert stability_ratio(line0, line2, c, 10.0, 2.0) == pytest.approx(math.sqrt(20.0))
    # The same, the whole scene shifted.
    off = np.array([100.0, -50.0])
    assert stability_ratio(line0 + off, line2 + off, off, 10.0, 2.0) == pytest.approx(
        math.sqrt(20.0)
    )
    # Identical estimates: 0.
    assert stability_ratio(line0, line0, c, 10.0, 1.0) == 0.0


def test_stability_ratio_nan_cases():
    c = np.zeros(2)
    long = np.array([(0, 0), (20, 0)], float)
    short = np.array([(0, 0), (5, 0)], float)
    assert math.isnan(stability_ratio(long, short, c, 10.0, 1.0))
    assert math.isnan(stability_ratio(short, long, c, 10.0, 1.0))
    # The car did not move (a different estimate, so the ratio would otherwise be infinite).
    moved = np.array([(0, 1), (20, 1)], float)
    assert math.isnan(stability_ratio(long, moved, c, 10.0, 0.0))
    assert math.isnan(stability_ratio(long, moved, c, 10.0, -1.0))


def test_circle_crossing_at_a_segment_end():
    # Found by hypothesis: the segment ends exactly on the circle; rounding put the exit at
    # t = 1 + 1e-16 and it was missed.
    line = np.array([[0.0, -16.212230297207142], [0.0, 1.0]])
    p = circle_crossing(line, np.zeros(2), 1.0)
    assert p is not None and p == pytest.approx([0.0, 1.0], abs=1e-9)


# --- agreement of two lanes over their common horizon (the RLD-CLC agreement tests) ---------


@pytest.mark.parametrize(
    ("a", "b", "expected"),
    [
        ([1, 2, 3], [1, 2, 3], 3),  # identical
        ([1, 2, 3, 4, 5], [1, 2, 3], 3),  # one stops earlier
        ([0, 1, 2, 3], [1, 2, 3, 4], 3),  # one starts a cone earlier, the other goes on
        ([1, 2, 3], [0, 1, 2], 2),  # b starts earlier: cut b at a's start
        ([1, 2, 9], [1, 2, 3], -1),  # a different third cone
        ([5, 6, 7], [1, 2, 3], -1),  # nothing in common
        ([1, 3, 2], [1, 2, 3], -1),  # same cones, other order
        ([], [1, 2], -1),
    ],
)
def test_side_agreement_hand_worked(a, b, expected):
    assert side_agreement(np.array(a), np.array(b)) == expected
    # Symmetric in its arguments.
    assert side_agreement(np.array(b), np.array(a)) == expected


@given(st.lists(st.integers(0, 30), min_size=1, max_size=12, unique=True),
       st.integers(0, 11), st.integers(0, 11))
def test_side_agreement_of_two_windows_of_one_sequence(seq, i, j):
    # Two windows of one sequence that overlap agree over exactly their overlap.
    i, j = min(i, len(seq) - 1), min(j, len(seq) - 1)
    a, b = np.array(seq[i:]), np.array(seq[j:j + 3])
    lo, hi = max(i, j), min(len(seq), j + 3)
    expected = hi - lo if hi > lo else -1
    assert side_agreement(a, b) == expected


def test_lanes_agree_needs_both_sides_and_counts_no_lane():
    left, right = np.array([1, 2, 3]), np.array([4, 5, 6])
    assert lanes_agree((left, right), (left[:2], right))
    assert not lanes_agree((left, right), (left, np.array([4, 7, 6])))
    assert not lanes_agree((left, right), (left[:1], right))  # one shared cone is too few
    assert lanes_agree((left, right), (left[:1], right), min_common=1)
    assert lanes_agree(None, None)
    assert not lanes_agree((left, right), None)


@settings(max_examples=60)
@given(na=st.integers(1, 30), nb=st.integers(1, 30), hw=st.floats(0.5, 3.0))
def test_true_lane_extent_of_parallel_sides(na, nb, hw):
    # Sides 2 * hw apart, cones every metre from x = 0: the shorter is kept whole, the longer
    # up to x <= end + sqrt(reach^2 - (2 hw)^2), the last x at which a cone is within reach of
    # the shorter side's end.
    a = np.column_stack([np.arange(na, dtype=float), np.full(na, hw)])
    b = np.column_stack([np.arange(nb, dtype=float), np.full(nb, -hw)])
    end = min(na, nb) - 1
    reach_x = math.sqrt(6.5**2 - (2 * hw) ** 2)
    past = [x for x in range(max(na, nb)) if x > end + reach_x + 1e-9]
    longer = past[0] if past else max(na, nb)
    assume(not past or abs(past[0] - end - reach_x) > 1e-6)
    want = (longer, nb) if na > nb else (na, longer) if nb > na else (na, nb)
    assert true_lane_extent(a, b) == want


@settings(max_examples=300)
@given(
    pts=st.lists(st.tuples(st.floats(-30, 30), st.floats(-30, 30)), min_size=2, max_size=8),
    i=st.integers(0, 7),
    j=st.integers(0, 7),
)
def test_from_line_through_the_polylines_own_points(pts, i, j):
    # The line through two of the polyline's own points, where rounding decides which side a
    # point on it falls (a lane starting with the first true cone): never a division by zero,
    # the result starts on or ahead of the line and ends with the input's last points.
    xy = np.array(pts, float)
    a, b = xy[i % len(xy)], xy[j % len(xy)]
    assume(np.hypot(*(b - a)) > 1e-3)
    u = (b - a) / np.hypot(*(b - a))
    n = np.array([-u[1], u[0]])
    out = _from_line(xy, a, n)
    side = (xy - a) @ n
    if not np.any(side >= 0):
        assert out.shape == (0, 2)
        return
    k = int(np.flatnonzero(side >= 0)[0])
    np.testing.assert_array_equal(out[-(len(xy) - k):], xy[k:])
    assert out.shape[0] == len(xy) - k + (k > 0)
    assert (out[0] - a) @ n >= -1e-9


# --------------------------------------------------------------------------------------------
# The geometric rule (DESIGN.md, "Geometric critical"): how far a lane strays within 20 m
# --------------------------------------------------------------------------------------------


def test_every_category_has_a_meaning():
    from rld.metrics import CATEGORY_MEANING

    assert set(CATEGORY_MEANING) == set(CATEGORIES)


def test_geometric_true_lane_is_zero_and_not_short():
    left, right = straight(10)
    h = Hand(left, right)
    s = h.score(h.L, h.R)
    assert s.deviation_m == pytest.approx(0.0, abs=1e-12)
    assert not s.critical_at(0.5) and not s.too_short


def test_geometric_skipped_true_cone_on_the_line_is_not_critical():
    # Left cone 3 (x = 12) skipped: the lane runs (9, 2) -> (15, 2), on the true line. The
    # index rule calls it critical (diverging at sqrt(13) + 6 m); the car cannot tell.
    left, right = straight(10)
    h = Hand(left, right)
    s = h.score(np.delete(h.L, 3), h.R)
    assert s.critical  # the index rule
    assert s.deviation_m == pytest.approx(0.0, abs=1e-12)
    assert not s.critical_at(0.5) and not s.critical_at(1.0)


def test_geometric_false_positive_0_7_m_off_the_line():
    # A false positive at (12, 2.7) instead of left cone 3 (12, 2): 0.7 m off the line y = 2.
    left, right = straight(10)
    h = Hand(left, right, extra=[(12.0, 2.7)])
    s = h.score(np.concatenate([h.L[:3], h.X, h.L[4:]]), h.R)
    assert s.deviation_m == pytest.approx(0.7, abs=1e-9)
    assert s.critical_at(0.5) and not s.critical_at(1.0)


def test_geometric_jump_to_the_other_boundary_is_critical():
    # The left side takes left cones 0-2 then jumps to right cone 3 (12, -2) and on along the
    # right boundary: 4 m off the left line at (12, -2), 10.6 m from the car.
    left, right = straight(10)
    h = Hand(left, right)
    s = h.score(np.concatenate([h.L[:3], h.R[3:6]]), h.R[:3])
    assert s.deviation_m == pytest.approx(4.0, abs=1e-9)
    assert s.critical_at(1.0)


def test_geometric_shortcut_across_a_4_m_hairpin_is_critical():
    # A hairpin whose legs are 4 m apart: left boundary out along y = 2 (x = 3..15), round
    # (15, 4) with radius 2, and back along y = 6; the right boundary outside it at radius 6.
    # The predicted left side cuts from (12, 2) straight across to (12, 6) on the way back:
    # the cut's midpoint (12, 4) is 3 m from the turn's nearest cone (15, 4) ... and the
    # reference through the turn: the nearest point of the true line is 2 m away (the legs).
    lx = [(3, 2), (6, 2), (9, 2), (12, 2), (15, 2), (17, 4), (15, 6), (12, 6), (9, 6)]
    rx = [(3, -2), (6, -2), (9, -2), (12, -2), (15, -2), (18.5, -0.5), (21, 4), (18.5, 8.5),
          (15, 10), (12, 10), (9, 10)]
    h = Hand(lx, rx)
    s = h.score(h.L[[0, 1, 2, 3, 7, 8]], h.R)
    # Samples along x = 12 from y = 2 to 6; the line's nearest parts are y = 2 and y = 6 (the
    # legs, 2 m away at y = 4) and the turn (x >= 15, 3 m away): 2 m.
    assert s.deviation_m == pytest.approx(2.0, abs=1e-9)
    assert s.critical_at(1.0)


def test_geometric_missing_or_far_side_is_critical():
    left, right = straight(12)
    h = Hand(left, right)
    # One cone on the left while its truth has twelve.
    assert h.score(h.L[:1], h.R).deviation_m == math.inf
    # The left side starts at left cone 7 (x = 24, 22.1 m from the car): beyond 20 m.
    assert h.score(h.L[7:], h.R).deviation_m == math.inf
    # Starting at left cone 5 (x = 18, 18.1 m away) is fine: on the line.
    assert h.score(h.L[5:], h.R).deviation_m == pytest.approx(0.0, abs=1e-12)
    # No lane.
    assert h.score(h.L, h.R, ok=False).deviation_m == math.inf
    # A truth of one cone: a one-cone side is measured, not critical by count.
    h1 = Hand(left[:1], right)
    assert h1.score(h1.L, h1.R).deviation_m == pytest.approx(0.0, abs=1e-12)


def test_geometric_lane_stopping_after_5_m_is_too_short_not_critical():
    # Cones 3 m apart from x = 3: two cones a side is a 3 m lane (5 m of lane ahead of the
    # car incl. the 3 m to the first cone) against 27 m of truth.
    left, right = straight(10)
    h = Hand(left, right)
    s = h.score(h.L[:2], h.R[:2])
    assert s.deviation_m == pytest.approx(0.0, abs=1e-12)
    assert not s.critical_at(0.5)
    assert s.too_short


def test_geometric_counts_only_20_m_of_arc_from_the_car():
    # On the true line up to x = 21 (18 m from the first cone at x = 3, the car 3 m behind it
    # on the extended line: s0 = -3), then a point 5 m off at x = 24: the cut at s0 + 20 = 17
    # m, x = 20, is before it. Two cones later the lane is wrong, but beyond the 20 m.
    left, right = straight(10)
    h = Hand(left, right, extra=[(24.0, 7.0)])
    s = h.score(np.concatenate([h.L[:7], h.X]), h.R)
    assert s.deviation_m == pytest.approx(0.0, abs=1e-12)
    # Car 3 m further on (x = 6): s0 = 3, the cut at 23 m of arc: 5 m along the edge
    # (21, 2) -> (24, 7) of length sqrt(34), which rises 5 m per sqrt(34): 25 / sqrt(34) m
    # off the line.
    h2 = Hand(left, right, extra=[(24.0, 7.0)], pose=Pose(6.0, 0.0, 0.0))
    s2 = h2.score(np.concatenate([h2.L[:7], h2.X]), h2.R)
    assert s2.deviation_m == pytest.approx(25.0 / math.sqrt(34.0), abs=1e-9)


def test_geometric_reference_starts_two_cones_before_the_truth():
    # The truth starts at cone 2 (the car at x = 8.9, cones 0 and 1 behind); a lane that starts
    # with cone 1 (beside the car) is on the reference: not off.
    left, right = straight(10)
    h = Hand(left, right, gt_left=range(2, 10), gt_right=range(2, 10), pose=Pose(8.9, 0, 0))
    assert h.score(h.L[1:], h.R[1:]).deviation_m == pytest.approx(0.0, abs=1e-12)
    np.testing.assert_allclose(reference_line(h.frame, "left"), left)  # cones 0..9
    # Starting three cones back (cone 0, 8.9 m behind... 6.2 m): its first segment is not on
    # the reference (which starts at cone 0 here too: the list has only two before cone 2).
    assert h.score(h.L, h.R).deviation_m == pytest.approx(0.0, abs=1e-12)


def test_geometric_reference_wraps_on_a_closed_boundary():
    # A closed square boundary, the truth from cone 1 round to cone 0 (the whole loop): the
    # reference starts two before cone 1 (cones 7, 0) and wraps.
    sq = np.array([(0, 0), (5, 0), (10, 0), (10, 5), (10, 10), (5, 10), (0, 10), (0, 5)], float)
    inner = np.array([(2, 2), (5, 2), (8, 2), (8, 5), (8, 8), (5, 8), (2, 8), (2, 5)], float)
    h = Hand(inner, sq, gt_left=[1, 2, 3, 4, 5, 6, 7, 0], gt_right=[1, 2, 3, 4, 5, 6, 7, 0],
             closed=True, pose=Pose(5.0, 1.0, 0.0))
    ref = reference_line(h.frame, "left")
    np.testing.assert_allclose(ref[:3], inner[[7, 0, 1]])
    assert ref.shape[0] == 10  # two before, then all eight
    s = h.score(h.frame.gt_left, h.frame.gt_right, closed=True)
    assert s.deviation_m == pytest.approx(0.0, abs=1e-12)


def test_kept_part_hand_worked():
    pred = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 30.0]])
    # Car beside the start: s0 = 0, cut at 20 m: (10, 10).
    np.testing.assert_allclose(kept_part(pred, np.array([0.0, 1.0])),
                               [[0, 0], [10, 0], [10, 10]])
    # Car 5 m behind the first cone on its extended line: s0 = -5, cut at 15 m: (10, 5).
    np.testing.assert_allclose(kept_part(pred, np.array([-5.0, 0.0])),
                               [[0, 0], [10, 0], [10, 5]])
    # Car 25 m behind: nothing but the first cone.
    np.testing.assert_allclose(kept_part(pred, np.array([-25.0, 0.0])), [[0, 0]])
    # Beside the second segment (s0 = 10 + 8): everything to 38 m, the whole polyline (40 m)
    # cut at 38: (10, 28).
    np.testing.assert_allclose(kept_part(pred, np.array([11.0, 8.0])),
                               [[0, 0], [10, 0], [10, 28]])


def _brute_deviation(pred, ref, car, step=0.005):
    """The rule by its words, sampled densely, no code shared with rld.metrics: the car's
    nearest of many points on the first three segments (the first extended back 25 m) for s0,
    then samples every 5 mm to s0 + 20 m."""
    seg = np.diff(pred, axis=0)
    lens = np.hypot(seg[:, 0], seg[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(lens)])
    best, s0 = math.inf, 0.0
    for i in range(min(3, len(seg))):
        lo = -25.0 / lens[i] if i == 0 else 0.0
        ts = np.concatenate([[0.0, 1.0], np.linspace(lo, 1.0, 40001)])
        pts = pred[i] + ts[:, None] * seg[i]
        d = np.hypot(*(pts - car).T)
        k = int(np.argmin(d))
        if d[k] < best - 0.005:  # a tie (within the sampling's error) keeps the earlier one
            best, s0 = float(d[k]), cum[i] + ts[k] * lens[i]
    end = s0 + 20.0
    samples = [pred[0]]
    for i in range(len(seg)):
        if cum[i] >= end:
            break
        n = max(int(np.ceil(lens[i] / step)), 1)
        for k in range(1, n + 1):
            s = cum[i] + lens[i] * k / n
            if s > end:
                samples.append(pred[i] + seg[i] * (end - cum[i]) / lens[i])
                break
            samples.append(pred[i] + seg[i] * k / n)

    def dist(p):
        out = math.inf
        for a, b in zip(ref[:-1], ref[1:], strict=True):
            d = b - a
            dd = float(d @ d)
            t = 0.0 if dd < 1e-18 else min(max(float((p - a) @ d) / dd, 0.0), 1.0)
            out = min(out, float(np.hypot(*(p - a - t * d))))
        return out

    return max(dist(p) for p in samples)


@settings(max_examples=60, deadline=None)
@given(st.lists(st.tuples(st.floats(-25, 25), st.floats(-25, 25)), min_size=2, max_size=7),
       st.lists(st.tuples(st.floats(-25, 25), st.floats(-25, 25)), min_size=2, max_size=7),
       st.tuples(st.floats(-10, 10), st.floats(-10, 10)))
def test_geometric_side_deviation_against_dense_sampling(pred, ref, car):
    pred, ref, car = np.array(pred), np.array(ref), np.array(car)
    assume(np.all(np.hypot(*np.diff(pred, axis=0).T) > 1e-3))
    assume(np.hypot(*(pred[0] - car)) <= 20.0)
    # No near-tie between two of the first three segments that would put s0 apart: the rule
    # keeps the earlier on a tie, and a sampled tie is only exact to the sampling's error.
    near = []
    for i in range(min(3, len(pred) - 1)):
        a, d = pred[i], pred[i + 1] - pred[i]
        t = float((car - a) @ d / (d @ d))
        t = min(t, 1.0) if i == 0 else min(max(t, 0.0), 1.0)
        near.append((float(np.hypot(*(car - a - t * d))),
                     float(np.hypot(*np.diff(pred[: i + 1], axis=0).T).sum())
                     + t * float(np.hypot(*d))))
    dmin = min(d for d, _ in near)
    close = [(d, s) for d, s in near if d < dmin + 0.01]
    assume(max(s for _, s in close) - min(s for _, s in close) < 1e-6
           or all(d - dmin <= 1e-9 for d, _ in close))
    got = side_deviation(pred, ref, car)
    want = _brute_deviation(pred, ref, car)
    # Ours samples every 0.25 m (the rule's step) where the brute force samples every 5 mm:
    # distance to a polyline is 1-Lipschitz, so ours is at most 0.125 m below it, and above it
    # by at most the brute force's errors at the cut (its step, and s0 to 5 mm).
    assert want - GEOMETRIC_STEP_M / 2 - 1e-6 <= got <= want + 0.01 + 1e-6


def _lane(left, right, closed):
    from rld.types import Lane, LaneStatus

    cones = np.zeros((10, 2))
    return Lane(cones=cones, left=np.array(left), right=np.array(right),
                status=LaneStatus.OPTIMAL, closed=closed)


@pytest.mark.parametrize(
    ("a", "closed_a", "b", "closed_b", "agree"),
    [
        ([0, 1, 2, 3], True, [3, 0, 1, 2], True, True),  # one loop, started elsewhere
        ([0, 1, 2, 3], True, [0, 1, 3, 2], True, False),  # same cones, other edges
        ([0, 1, 2, 3], True, [2, 3, 0], False, True),  # an open boundary along the loop
        ([0, 1, 2, 3], True, [2, 3, 1], False, False),  # it leaves the loop
        ([0, 1, 2, 3], True, [3, 0, 1], False, True),  # read across the loop's seam
    ],
)
def test_lanes_agree_reads_closed_boundaries_as_loops(a, closed_a, b, closed_b, agree):
    right = [5, 6, 7]  # the same on both, open, unless both lanes are closed
    la, lb = _lane(a, right, closed_a), _lane(b, right, closed_b)
    assert lanes_agree(la, lb) is agree
    assert lanes_agree(lb, la) is agree


def test_lanes_identical_cone_for_cone_to_the_end():
    from rld.metrics import lanes_identical
    from rld.types import Lane, LaneStatus, Pose

    # Cones 0-5 along y = 2 (left), 6-11 along y = -2 (right), x = -3 .. 12 m; the car at 0.
    xs = np.arange(-3.0, 15.0, 3.0)
    pts = np.vstack([np.column_stack([xs, np.full(6, 2.0)]),
                     np.column_stack([xs, np.full(6, -2.0)])])
    car = Pose(0.0, 0.0, 0.0)

    def lane(left, right, closed=False):
        return Lane(cones=pts, left=np.array(left), right=np.array(right),
                    status=LaneStatus.OPTIMAL, closed=closed)

    full = lane(range(6), range(6, 12))
    assert lanes_identical(full, lane(range(1, 6), range(7, 12)), car)  # cone behind: trimmed
    assert not lanes_identical(full, lane(range(5), range(6, 12)), car)  # cut short
    assert not lanes_identical(full, lane(range(6, 12), range(6)), car)  # sides swapped
    none = Lane.not_found(pts, "none")
    assert not lanes_identical(none, none, car)  # no lane against no lane
    loop_a, loop_b = lane([0, 1, 2, 3], [6, 7, 8, 9], True), lane([2, 3, 0, 1], [9, 6, 7, 8], True)
    assert lanes_identical(loop_a, loop_b, car)  # the same edges, another start
    assert not lanes_identical(loop_a, lane([0, 1, 2, 3], [6, 7, 8, 9]), car)  # open vs closed

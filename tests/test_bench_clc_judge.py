"""The dive judge's decision benchmark (benchmarks/bench_clc_judge.py): its terms are the
judge's cost, its rule is the judge's, the fit finds a separating weight, and the decisions
collected are mixed and labelled by the protocol's tolerant rule."""

import numpy as np
import pytest

from clc.solver import dive_costs
from rld.cli import _benchmark_module
from rld.generator import generate_track
from rld.metrics import diverges_early, score_lane, tolerant_skips
from rld.simulation import simulate_lap
from rld.types import LaneParams

B = _benchmark_module("bench_clc_judge")  # benchmarks/ is not an installed package
PARAMS = LaneParams()


@pytest.fixture(scope="module")
def lap():
    return simulate_lap(generate_track(3), range_m=30.0, fp_rate=0.3, seed=0)


def _frame(lap):
    for k in range(len(lap) // 3, len(lap)):
        f = lap.frame(k)
        if not f.gt_closed and min(f.gt_left.size, f.gt_right.size) >= 6:
            return f
    pytest.fail("no open pose with 6 true cones a side")


def test_terms_weighted_are_the_judges_cost(lap):
    f = _frame(lap)
    gl, gr = f.gt_left, f.gt_right
    lanes = [(gl, gr), (np.delete(gl, 2), gr), (gl[:4], gr[:3])]
    t = B.terms(f.cones, f.pose, PARAMS, lanes)
    assert t.shape == (3, len(B.TERMS))
    want = dive_costs(f.cones, f.pose, PARAMS, [(a, b, False) for a, b in lanes])
    assert np.allclose(t @ B.judge_weights(PARAMS), want, atol=1e-9)
    # The edge count within the reach, negative: the truth has one edge more than itself
    # without its third left cone.
    assert t[0, 1] == pytest.approx(t[1, 1] - 1.0)
    assert np.all(t[:, [0, 2, 3, 5, 6]] >= 0)


def test_pick_and_accuracy_by_hand():
    w = np.array([1.0, 2.5, 0, 0, 0, 0, 0])
    rows = np.zeros((3, 7))
    rows[:, 1] = [-3, -3, -4]  # costs -7.5, -7.5, -10
    assert B.pick(rows, w) == 2
    rows[2, 0] = 2.5  # -7.5: a tie with the winner keeps the winner
    assert B.pick(rows, w) == 0
    rows[1, 0] = -0.1  # strictly cheaper than the winner
    assert B.pick(rows, w) == 1
    d = [B.Decision(0, 0, 0, rows, np.array([False, True, False])),
         B.Decision(0, 0, 1, rows, np.array([True, False, False]))]
    assert B.accuracy(d, w) == 0.5
    assert np.isnan(B.accuracy([], w))


def test_fit_finds_the_separating_term():
    # Today's weights keep the wrong winner; the right contender has the smaller width
    # roughness (term 5) and one edge fewer. A width weight above 2.5 / (3 - 1) = 1.25 picks it.
    rows = np.zeros((2, 7))
    rows[:, 1] = [-5, -4]
    rows[:, 5] = [3.0, 1.0]
    d = [B.Decision(0, 0, k, rows, np.array([False, True])) for k in range(3)]
    w0 = B.judge_weights(PARAMS)
    assert B.accuracy(d, w0) == 0.0
    w = B.fit(d, w0)
    assert B.accuracy(d, w) == 1.0
    assert w[5] * 2.0 > 2.5 and w[1] == w0[1]
    assert np.array_equal(B.fit([], w0), w0)  # nothing to fit: today's weights


def test_diverges_early_is_the_tolerant_critical_rule(lap):
    seen = set()
    for k in range(0, len(lap), 25):
        f = lap.frame(k)
        skips = tolerant_skips(f)
        gl, gr = f.gt_left, f.gt_right
        others = np.setdiff1d(np.arange(f.cones.shape[0]), np.r_[gl, gr])
        lanes = [(gl, gr), (gl[:3], gr)]
        if gl.size >= 3 and others.size:
            lanes.append((np.r_[gl[:1], others[:1], gl[1:]], gr))
        empty = np.zeros(0, dtype=np.int64)
        assert diverges_early(f, empty, empty, skips)  # score_lane's "failed"
        assert score_lane(f, empty, empty, True, False).critical_tolerant
        for a, b in lanes:
            want = score_lane(f, a, b, True, False).critical_tolerant
            assert diverges_early(f, a, b, skips) == want
            assert diverges_early(f, a, b) == want
            seen.add(want)
    assert seen == {True, False}  # both answers were checked


def test_collect_keeps_mixed_decisions_labelled_by_the_protocol():
    track = generate_track(3)
    out = B.collect(track, 3, 30.0, 0.3, seed=0, every=6)
    assert out, "no mixed decision on the lap"
    for d in out:
        assert d.terms.shape == (d.right.size, len(B.TERMS)) and d.right.size >= 2
        assert d.right.any() and not d.right.all()

"""CLC ranking (section VII): the features by hand, the rankers, the learned model's file and
the training pairs (eq. 14)."""

from __future__ import annotations

import math
import os

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clc.ranker import (
    DEFAULT_MODEL,
    LearnedRanker,
    LongestRanker,
    RldCostRanker,
    get_ranker,
)
from clc.train import RankingList, pairwise_dataset, save_ranker, top_pick_iou
from rld import LaneParams, Pose
from rld.costs import FEATURE_NAMES, lane_cost, ranking_features


def test_features_by_hand():
    left = np.array([[0.0, 0.0], [3.0, 0.0], [6.0, 1.0], [8.0, 3.0]])
    right = np.array([[0.0, -4.0], [4.0, -4.0]])
    f = ranking_features(left, right)
    seg = np.array([3.0, math.sqrt(10.0), math.sqrt(8.0)])
    t1 = math.atan2(3.0 * 1.0 - 0.0 * 3.0, 3.0 * 3.0 + 0.0 * 1.0)  # (3,0) -> (3,1)
    t2 = math.atan2(3.0 * 2.0 - 1.0 * 2.0, 3.0 * 2.0 + 1.0 * 2.0)  # (3,1) -> (2,2)
    assert f[0] == pytest.approx((seg.sum() + 4.0) / 2)
    assert f[1] == 4 and f[2] == 2
    assert f[4] == pytest.approx(np.var(seg))
    assert f[5] == 0.0  # one segment
    assert f[6] == pytest.approx(np.var([t1, t2]))
    assert f[7] == 0.0  # no turn
    # Widths: every left vertex and segment against the right segment y = -4, x in [0, 4],
    # and the right ones against the left polyline.
    widths = [4.0, 4.0, math.hypot(2.0, 5.0), math.hypot(4.0, 7.0),  # left vertices
              4.0, 4.0, math.hypot(2.0, 5.0),                         # left segments
              4.0, math.hypot(1.0, 4.0),                              # right vertices
              4.0]                                                    # right segment
    assert f[3] == pytest.approx(np.var(widths))
    assert len(FEATURE_NAMES) == 8


def test_closed_features_count_the_closing_segments():
    t = np.linspace(0, 2 * np.pi, 8, endpoint=False)
    inner = np.column_stack([10 * np.cos(t), 10 * np.sin(t)])
    outer = 1.4 * inner
    f = ranking_features(outer, inner, closed=True)
    side = 2 * 10 * math.sin(math.pi / 8)
    assert f[0] == pytest.approx(8 * side * (1 + 1.4) / 2)
    assert f[4] == pytest.approx(0.0, abs=1e-20) and f[6] == pytest.approx(0.0, abs=1e-20)


CANDS = [(np.array([0, 1]), np.array([4, 5]), False),
         (np.array([0, 1, 2]), np.array([4, 5, 6]), False),
         (np.array([0, 1, 2, 3]), np.array([4, 5, 6]), False)]
PTS = np.array([[0, 2], [3, 2], [6, 2], [9, 2], [0, -2], [3, -2], [6, -2]], float)


def _features():
    return np.array([ranking_features(PTS[a], PTS[b], c) for a, b, c in CANDS])


def test_longest_ranker_picks_the_longest():
    s = LongestRanker().score(PTS, Pose(0, 0, 0), LaneParams(), CANDS, _features())
    assert int(np.argmax(s)) == 2


def test_rld_cost_ranker_is_minus_the_rld_objective():
    params, pose = LaneParams(), Pose(0.0, 0.0, 0.0)
    s = RldCostRanker().score(PTS, pose, params, CANDS, _features())
    want = [-lane_cost(PTS, a, b, pose, params, closed=c) for a, b, c in CANDS]
    np.testing.assert_allclose(s, want)


def _weights(seed=0, hidden=5):
    rng = np.random.default_rng(seed)
    return {"W1": rng.normal(size=(8, hidden)), "b1": rng.normal(size=hidden),
            "w2": rng.normal(size=hidden), "b2": np.float64(0.3),
            "mean": rng.normal(size=8), "std": rng.uniform(0.5, 2.0, size=8),
            "feature_names": np.array(FEATURE_NAMES)}


def test_learned_ranker_round_trip(tmp_path):
    w = _weights()
    path = save_ranker(w, tmp_path / "r.npz", {"note": "test"})
    assert path.with_suffix(".json").exists()
    r = LearnedRanker.load(path)
    x = _features()
    z = (x - w["mean"]) / w["std"]
    by_hand = np.array([sum(w["w2"][h] * max(0.0, z[k] @ w["W1"][:, h] + w["b1"][h])
                            for h in range(5)) + 0.3 for k in range(len(CANDS))])
    np.testing.assert_allclose(r.score(PTS, None, None, CANDS, x), by_hand)


def test_learned_ranker_load_is_read_once_until_the_file_changes(tmp_path):
    w = _weights()
    path = save_ranker(w, tmp_path / "r.npz", {"note": "test"})
    r = LearnedRanker.load(path)
    assert LearnedRanker.load(path) is r  # a stateless solve_lane reads it once
    assert not r.W1.flags.writeable  # shared between solvers, so read-only
    x = _features()
    before = r.net(x)
    w2 = _weights(seed=1)
    save_ranker(w2, path, {"note": "retrained"})
    os.utime(path, ns=(0, path.stat().st_mtime_ns + 10**9))  # whatever the clock's resolution
    r2 = LearnedRanker.load(path)
    assert r2 is not r
    assert not np.allclose(r2.net(x), before)
    np.testing.assert_array_equal(r.net(x), before)  # the first instance is untouched
    # Building one from the caller's arrays copies them: the caller's stay writeable.
    arrays = {k: np.array(v) for k, v in _weights().items()}
    LearnedRanker(arrays["W1"], arrays["b1"], arrays["w2"], arrays["b2"], arrays["mean"],
                  arrays["std"])
    arrays["W1"][0, 0] = 1.0


def test_learned_ranker_rejects_bad_files(tmp_path):
    with pytest.raises(FileNotFoundError, match="train-ranker"):
        LearnedRanker.load(tmp_path / "missing.npz")
    w = _weights()
    w["W1"] = w["W1"][:7]
    np.savez(tmp_path / "bad.npz", **w)
    with pytest.raises(ValueError, match="W1"):
        LearnedRanker.load(tmp_path / "bad.npz")
    w = _weights()
    w["feature_names"] = np.array(FEATURE_NAMES[::-1])
    np.savez(tmp_path / "names.npz", **w)
    with pytest.raises(ValueError, match="features"):
        LearnedRanker.load(tmp_path / "names.npz")


def test_get_ranker():
    assert get_ranker("longest").name == "longest"
    assert get_ranker("rld_cost").name == "rld_cost"
    custom = LongestRanker()
    assert get_ranker(custom) is custom
    with pytest.raises(ValueError, match="unknown ranker"):
        get_ranker("nope")


@pytest.mark.skipif(not DEFAULT_MODEL.exists(), reason="no packaged ranker")
def test_packaged_ranker_prefers_the_whole_true_lane():
    r = get_ranker("learned")
    assert r.name == "learned"
    xs = np.arange(0.0, 30.0, 3.0)
    L = np.column_stack([xs, np.full_like(xs, 2.0)])
    R = np.column_stack([xs, np.full_like(xs, -2.0)])
    true = ranking_features(L, R)
    prefixes = [ranking_features(L[:k], R[:k]) for k in range(3, 10)]
    # The right boundary hooking onto the left's last cone (90 degrees): longer, but wrong.
    hook = ranking_features(L[:-1], np.vstack([R, L[-1:]]))
    s = r.score(None, None, None, [None] * 9, np.vstack([true, hook] + prefixes))
    assert int(np.argmax(s)) == 0


def test_pairwise_targets_follow_eq_14():
    lists = [RankingList(np.arange(24, dtype=float).reshape(3, 8), np.array([0.9, 0.5, 0.1]),
                         "t", 0, 0.0, 50.0)]
    x1, x2, p = pairwise_dataset(lists, lambda_iou=10.0, pairs_per_list=200, seed=1)
    i = (x1[:, 0] / 8).astype(int)
    j = (x2[:, 0] / 8).astype(int)
    iou = lists[0].iou
    np.testing.assert_allclose(p, 1 / (1 + np.exp(-10.0 * (iou[i] - iou[j]))))
    assert np.all(i != j)


def test_top_pick_iou_reports_the_oracle():
    lists = [RankingList(np.array([[5.0] + [0] * 7, [9.0] + [0] * 7]), np.array([0.2, 0.8]),
                         "t", 0, 0.0, 50.0)]
    out = top_pick_iou(LongestRanker(), lists)
    assert out["mean_iou_top"] == 0.8 and out["mean_iou_oracle"] == 0.8


def test_training_learns_a_monotone_preference():
    pytest.importorskip("torch")
    from clc.train import train_ranker

    rng = np.random.default_rng(0)
    lists = []
    for _ in range(60):
        f = rng.normal(size=(12, 8))
        lists.append(RankingList(f, 1 / (1 + np.exp(-f[:, 0])), "t", 0, 0.0, 50.0))
    arrays = train_ranker(lists[:40], epochs=30, batch_size=512, progress=False)
    r = LearnedRanker(arrays["W1"], arrays["b1"], arrays["w2"], arrays["b2"], arrays["mean"],
                      arrays["std"])
    held = top_pick_iou(r, lists[40:])
    assert held["mean_iou_top"] >= held["mean_iou_oracle"] - 0.02


@settings(max_examples=30, deadline=None)
@given(seed=st.integers(0, 2**31 - 1), fp=st.sampled_from([0.0, 0.3]))
def test_rld_cost_ranker_on_a_search_list_is_lane_cost_per_candidate(seed, fp):
    """The vectorised score of a whole candidate list (``open_path_costs``) equals minus the
    shared ``lane_cost`` of every candidate, closed ones included."""
    from clc.search import enumerate_candidates
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    lap = simulate_lap(generate_track(seed % 50), range_m=30.0, fp_rate=fp, seed=seed)
    f = lap.frame(int(seed % len(lap)))
    params = LaneParams(max_iterations=60)
    res = enumerate_candidates(f.cones, f.pose, params, close_loops=True)
    if len(res.candidates) == 0:
        return
    got = RldCostRanker().score(f.cones, f.pose, params, res.candidates, res.features)
    want = [-lane_cost(f.cones, a, b, f.pose, params, closed=c) for a, b, c in res.candidates]
    np.testing.assert_allclose(got, want, rtol=1e-9, atol=1e-9)

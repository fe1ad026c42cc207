"""CLC ranking (section VII): the feature kernels of ``rld.costs_kernels`` against hand-worked
lanes and a plain-numpy reimplementation, the rankers of ``clc.ranker`` (numpy only), the
learned ranker's file, and the training utilities of ``clc.train`` (eq. 14)."""

from __future__ import annotations

import json
import math
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from clc import ranker as ranker_mod
from clc.ranker import RANKERS, LearnedRanker, LongestRanker, RldCostRanker, get_ranker
from clc.train import heldout_mean_best_iou, pairwise_dataset, save_ranker
from rld import costs_kernels as ck
from rld.constraints import lane_widths
from rld.costs import FEATURE_NAMES, lane_cost, ranking_features
from rld.types import LaneParams, Pose

# ----------------------------------------------------------------------------------------------
# Features by hand


def test_feature_names_match_the_kernel():
    assert len(FEATURE_NAMES) == ck.N_FEATURES == 8
    assert len(set(FEATURE_NAMES)) == 8


def test_straight_lane_features_by_hand():
    # Left: 3 points, segments 2 m and 3 m; right: 2 points, one 4 m segment; 3 m apart.
    left = np.array([[0.0, 1.5], [2.0, 1.5], [5.0, 1.5]])
    right = np.array([[0.0, -1.5], [4.0, -1.5]])
    f = ranking_features(left, right)
    assert f.shape == (8,) and f.dtype == np.float64
    assert f[0] == pytest.approx((5.0 + 4.0) / 2)
    assert f[1] == 3 and f[2] == 2
    # Matching lines: every vertex and segment is 3 m from the other side, except the left's
    # last vertex (5, 1.5), sqrt(1 + 9) from the right's end (4, -1.5): 7 values of 3 and one
    # of sqrt(10), a two-point distribution with p = 1/8, variance p (1 - p) d^2.
    assert f[3] == pytest.approx(7 / 64 * (math.sqrt(10.0) - 3.0) ** 2)
    assert f[4] == pytest.approx(0.25)  # lengths 2 and 3: mean 2.5, deviations +-0.5
    assert f[5] == 0.0  # one segment
    assert f[6] == 0.0  # one turn (0 rad)
    assert f[7] == 0.0  # no turn


def test_zigzag_features_by_hand():
    # Turns +45 and -45 degrees; segment lengths 1, sqrt(2), 1.
    L = np.array([[0.0, 0.0], [1.0, 0.0], [2.0, 1.0], [3.0, 1.0]])
    R = np.array([[0.0, -3.0], [3.0, -3.0]])
    widths = np.array([1.0, 2.0, 3.0, 4.0])
    out = np.full(8, np.nan)
    ck.lane_features(L, R, widths, out)
    assert out[0] == pytest.approx((2.0 + math.sqrt(2.0) + 3.0) / 2)
    assert out[1] == 4 and out[2] == 2
    assert out[3] == pytest.approx(1.25)
    assert out[4] == pytest.approx(2 / 9 * (math.sqrt(2.0) - 1.0) ** 2)
    assert out[5] == 0.0
    assert out[6] == pytest.approx((math.pi / 4) ** 2)
    assert out[7] == 0.0


def test_single_points_and_empty_widths_give_zero_variances():
    out = np.full(8, np.nan)
    ck.lane_features(np.array([[0.0, 0.0]]), np.array([[0.0, -3.0]]), np.zeros(0), out)
    np.testing.assert_array_equal(out, [0.0, 1.0, 1.0, 0.0, 0.0, 0.0, 0.0, 0.0])
    ck.lane_features(np.array([[0.0, 0.0]]), np.array([[0.0, -3.0]]), np.array([3.0]), out)
    assert out[3] == 0.0


def test_closed_square_lane_by_hand():
    outer = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    inner = np.array([[3.0, 3.0], [7.0, 3.0], [7.0, 7.0], [3.0, 7.0]])
    f = ranking_features(outer, inner, closed=True)
    assert f[0] == pytest.approx((40.0 + 16.0) / 2)  # closing segments count
    assert f[1] == 4 and f[2] == 4  # the first point is not counted twice
    assert f[4] == 0.0 and f[5] == 0.0
    assert f[6] == 0.0 and f[7] == 0.0  # four turns of +90 degrees, the wrap included


def test_appending_the_first_point_loses_only_the_wrap_turn():
    """What ``lane_features``'s docstring says of closed lanes passed as open ones."""
    outer = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [0.0, 10.0]])
    inner = np.array([[3.0, 3.0], [7.0, 3.0], [7.0, 7.0], [3.0, 7.0]])
    w = lane_widths(outer, inner, closed=True)
    closed, appended = np.empty(8), np.empty(8)
    ck.closed_lane_features(outer, inner, w, closed)
    ck.lane_features(np.vstack([outer, outer[:1]]), np.vstack([inner, inner[:1]]), w, appended)
    np.testing.assert_allclose(appended[[0, 3, 4, 5]], closed[[0, 3, 4, 5]])
    np.testing.assert_array_equal(appended[1:3], closed[1:3] + 1)
    # A kinked ring: with the wrap turn missing the turn variances differ.
    kinked = np.array([[0.0, 0.0], [10.0, 0.0], [10.0, 10.0], [5.0, 12.0], [0.0, 10.0]])
    w = lane_widths(kinked, inner, closed=True)
    ck.closed_lane_features(kinked, inner, w, closed)
    ck.lane_features(np.vstack([kinked, kinked[:1]]), np.vstack([inner, inner[:1]]), w,
                     appended)
    assert appended[6] != pytest.approx(closed[6])


# ----------------------------------------------------------------------------------------------
# The kernel against plain numpy


def _turn_ref(a: np.ndarray, b: np.ndarray, c: np.ndarray) -> float:
    """Signed turn a-b-c with the shared conventions: pi for a zero-length segment, (-pi, pi]."""
    u, v = b - a, c - b
    if not u.any() or not v.any():
        return math.pi
    t = math.atan2(u[0] * v[1] - u[1] * v[0], u[0] * v[0] + u[1] * v[1])
    return math.pi if t <= -math.pi else t


def _var_ref(x) -> float:
    x = np.asarray(x, dtype=np.float64)
    return float(np.var(x)) if x.size >= 2 else 0.0


def _features_ref(L: np.ndarray, R: np.ndarray, closed: bool) -> np.ndarray:
    out = np.zeros(8)
    for k, xy in enumerate((L, R)):
        n = xy.shape[0]
        ring = np.vstack([xy, xy[:1]]) if closed and n >= 2 else xy
        seg = [float(np.hypot(*(ring[i + 1] - ring[i]))) for i in range(ring.shape[0] - 1)]
        if closed and n >= 3:
            turns = [_turn_ref(xy[i - 1], xy[i], xy[(i + 1) % n]) for i in range(n)]
        else:
            turns = [_turn_ref(xy[i - 1], xy[i], xy[i + 1]) for i in range(1, n - 1)]
        out[0] += sum(seg) / 2
        out[1 + k] = n
        out[4 + k] = _var_ref(seg)
        out[6 + k] = _var_ref(turns)
    out[3] = _var_ref(lane_widths(L, R, closed))
    return out


# Coordinates on a 0.25 m grid, so hypothesis also tries repeated points (zero-length
# segments) and exact reversals.
coord = st.integers(-200, 200).map(lambda v: v / 4.0)
polyline = st.lists(st.tuples(coord, coord), min_size=1, max_size=12).map(
    lambda p: np.array(p, dtype=np.float64))


@given(polyline, polyline)
def test_open_kernel_agrees_with_numpy(L, R):
    widths = lane_widths(L, R)
    out = np.empty(8)
    ck.lane_features(L, R, widths, out)
    want = _features_ref(L, R, closed=False)
    np.testing.assert_allclose(out, want, rtol=1e-9, atol=1e-9)
    np.testing.assert_allclose(ranking_features(L, R), want, rtol=1e-9, atol=1e-9)


@given(polyline, polyline)
def test_closed_kernel_agrees_with_numpy(L, R):
    want = _features_ref(L, R, closed=True)
    np.testing.assert_allclose(ranking_features(L, R, closed=True), want, rtol=1e-9, atol=1e-9)


@given(st.lists(st.floats(-1e3, 1e3), max_size=30))
def test_width_variance_is_the_population_variance(widths):
    w = np.array(widths, dtype=np.float64)
    out = np.empty(8)
    ck.lane_features(np.zeros((1, 2)), np.ones((1, 2)), w, out)
    assert out[3] == pytest.approx(_var_ref(w), rel=1e-9, abs=1e-9)


def test_random_lanes_agree_with_numpy():
    rng = np.random.default_rng(7)
    for _ in range(200):
        n, m = rng.integers(1, 15, size=2)
        L = np.cumsum(rng.normal(size=(n, 2)) * 3, axis=0)
        R = np.cumsum(rng.normal(size=(m, 2)) * 3, axis=0) + [0.0, -3.5]
        for closed in (False, True):
            np.testing.assert_allclose(ranking_features(L, R, closed),
                                       _features_ref(L, R, closed), rtol=1e-9, atol=1e-9)


# ----------------------------------------------------------------------------------------------
# Rankers

PTS = np.array([[0, 2], [3, 2], [6, 2], [9, 2], [0, -2], [3, -2], [6, -2], [9, -2], [12, 2]],
               dtype=float)
CANDS = [(np.array([0, 1]), np.array([4, 5]), False),
         (np.array([0, 1, 2, 3]), np.array([4, 5, 6, 7]), False),
         (np.array([0, 1, 2]), np.array([4, 5, 6]), False),
         (np.array([0, 1, 2, 3, 8]), np.array([4, 5, 6, 7]), False)]
POSE = Pose(-1.0, 0.0, 0.0)


def _features(cands=CANDS) -> np.ndarray:
    return np.array([ranking_features(PTS[a], PTS[b], c) for a, b, c in cands])


def test_longest_ranker_picks_the_longest():
    s = LongestRanker().score(PTS, POSE, LaneParams(), CANDS, _features())
    assert s.shape == (len(CANDS),)
    assert int(np.argmax(s)) == 3
    np.testing.assert_array_equal(np.argsort(-s), [3, 1, 2, 0])


def test_longest_ranker_breaks_length_ties_by_cone_count():
    f = np.zeros((2, 8))
    f[:, 0] = 20.0
    f[0, 1:3] = (4, 4)
    f[1, 1:3] = (5, 4)
    s = LongestRanker().score(None, None, None, [None, None], f)
    assert s[1] > s[0]
    f[1, 0] = 20.001  # a longer lane beats any number of extra cones
    f[0, 1:3] = (50, 50)
    assert int(np.argmax(LongestRanker().score(None, None, None, [None, None], f))) == 1


def test_rld_cost_ranker_is_minus_lane_cost():
    params = LaneParams()
    ring = [(np.array([0, 1, 2]), np.array([4, 5, 6]), True)]
    cands = CANDS + ring
    s = RldCostRanker().score(PTS, POSE, params, cands, _features(cands))
    want = [-lane_cost(PTS, a, b, POSE, params, closed=c) for a, b, c in cands]
    np.testing.assert_array_equal(s, want)
    assert s.dtype == np.float64


def _weights(seed: int = 0, hidden: int = 100) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    return {"W1": rng.normal(size=(8, hidden)), "b1": rng.normal(size=hidden),
            "w2": rng.normal(size=hidden), "b2": np.float64(-0.7),
            "mean": rng.normal(size=8), "std": rng.uniform(0.5, 2.0, size=8),
            "feature_names": np.array(FEATURE_NAMES)}


def _forward_by_hand(w: dict[str, np.ndarray], x: np.ndarray) -> np.ndarray:
    out = []
    for row in x:
        z = [(row[i] - w["mean"][i]) / w["std"][i] for i in range(8)]
        s = float(w["b2"])
        for h in range(w["b1"].size):
            a = w["b1"][h] + sum(z[i] * w["W1"][i, h] for i in range(8))
            s += w["w2"][h] * max(a, 0.0)
        out.append(s)
    return np.array(out)


def test_learned_ranker_round_trip(tmp_path):
    w = _weights()
    path = save_ranker(w, tmp_path / "ranker.npz", {"seed": 3, "scores": {"held_out": 0.9}})
    card = json.loads(path.with_suffix(".json").read_text())
    assert card["features"] == list(FEATURE_NAMES)
    assert card["layers"] == [8, 100, 1]
    assert card["seed"] == 3 and card["scores"] == {"held_out": 0.9}
    r = LearnedRanker.load(path)
    assert r.name == "learned"
    x = _features()
    s = r.score(PTS, POSE, LaneParams(), CANDS, x)
    np.testing.assert_allclose(s, _forward_by_hand(w, x), rtol=1e-12, atol=1e-12)
    # Same weights in memory, same scores.
    direct = LearnedRanker(w["W1"], w["b1"], w["w2"], w["b2"], w["mean"], w["std"])
    np.testing.assert_array_equal(direct.score(None, None, None, CANDS, x), s)


def test_missing_model_says_how_to_train(tmp_path, monkeypatch):
    with pytest.raises(FileNotFoundError, match="rld train-ranker") as info:
        LearnedRanker.load(tmp_path / "nothing.npz")
    assert "longest" in str(info.value)
    monkeypatch.setattr(ranker_mod, "DEFAULT_MODEL", tmp_path / "nothing.npz")
    with pytest.raises(FileNotFoundError, match="train-ranker"):
        get_ranker("learned")


@pytest.mark.parametrize(("key", "value", "message"), [
    ("W1", np.zeros((7, 100)), "W1"),
    ("W1", np.zeros((8, 99)), "W1"),
    ("b1", np.zeros((100, 1)), "b1"),
    ("w2", np.zeros(99), "w2"),
    ("b2", np.zeros(1), "b2"),
    ("mean", np.zeros(7), "mean"),
    ("std", np.ones(9), "std"),
    ("std", np.zeros(8), "std"),
    ("W1", np.full((8, 100), np.nan), "W1"),
    ("feature_names", np.array(FEATURE_NAMES[::-1]), "features"),
    ("feature_names", None, "missing"),
])
def test_bad_model_files_are_value_errors(tmp_path, key, value, message):
    w = _weights()
    if value is None:
        del w[key]
    else:
        w[key] = value
    np.savez(tmp_path / "bad.npz", **w)
    with pytest.raises(ValueError, match=message):
        LearnedRanker.load(tmp_path / "bad.npz")


def test_get_ranker_by_name_and_object():
    assert RANKERS == ("learned", "rld_cost", "longest")
    assert isinstance(get_ranker("longest"), LongestRanker)
    assert isinstance(get_ranker("rld_cost"), RldCostRanker)

    class Custom:
        name = "custom"

        def score(self, points, pose, params, candidates, features):
            return -np.asarray(features)[:, 0]

    custom = Custom()
    assert get_ranker(custom) is custom
    with pytest.raises(ValueError, match="unknown ranker") as info:
        get_ranker("nope")
    assert all(name in str(info.value) for name in RANKERS)


def test_ranker_module_does_not_import_torch():
    code = ("import sys, clc.ranker, clc.train, rld.costs; "
            "assert 'torch' not in sys.modules, 'torch imported'")
    subprocess.run([sys.executable, "-c", code], check=True)


# ----------------------------------------------------------------------------------------------
# Training utilities


def test_pairwise_dataset_follows_eq_14_on_plain_pairs():
    f = np.arange(32, dtype=float).reshape(4, 8)
    iou = np.array([0.9, 0.5, 0.5, 0.1])
    x1, x2, p = pairwise_dataset([(f, iou)], pairs_per_list=200, seed=4)
    i = (x1[:, 0] // 8).astype(int)
    j = (x2[:, 0] // 8).astype(int)
    assert p.size > 0 and np.all(i != j)
    np.testing.assert_allclose(p, 1 / (1 + np.exp(-20.0 * (iou[i] - iou[j]))))
    again = pairwise_dataset([(f, iou)], pairs_per_list=200, seed=4)
    for a, b in zip((x1, x2, p), again, strict=True):
        np.testing.assert_array_equal(a, b)
    with pytest.raises(ValueError, match="features"):
        pairwise_dataset([(f[:, :7], iou)])
    with pytest.raises(ValueError, match="IoU"):
        pairwise_dataset([(f, iou[:3])])


def test_heldout_mean_best_iou_by_hand():
    f1 = np.zeros((2, 8))
    f1[:, 0] = (5.0, 9.0)
    f2 = np.zeros((3, 8))
    f2[:, 0] = (7.0, 3.0, 1.0)
    lists = [(f1, np.array([0.2, 0.8])), (f2, np.array([0.4, 0.9, 0.6]))]
    top, oracle = heldout_mean_best_iou(LongestRanker(), lists)
    assert top == pytest.approx((0.8 + 0.4) / 2)
    assert oracle == pytest.approx((0.8 + 0.9) / 2)


def _synthetic_lists(rng: np.random.Generator, count: int) -> list[tuple[np.ndarray, np.ndarray]]:
    """Lists whose IoU is a monotone function of feature 0 (lane length); the other features are
    noise on very different scales (the standardisation has to cope)."""
    out = []
    for _ in range(count):
        k = int(rng.integers(5, 20))
        f = rng.normal(size=(k, 8)) * [20.0, 5.0, 5.0, 0.1, 1.0, 1.0, 0.01, 0.01]
        f[:, 0] += 40.0
        out.append((f, 1.0 / (1.0 + np.exp(-(f[:, 0] - 40.0) / 10.0))))
    return out


def test_training_learns_a_monotone_preference(tmp_path):
    pytest.importorskip("torch")
    from clc.train import train_ranker

    rng = np.random.default_rng(0)
    train, held = _synthetic_lists(rng, 200), _synthetic_lists(rng, 50)
    arrays = train_ranker(train, seed=0, epochs=30, batch_size=1024, progress=False)
    assert arrays["W1"].shape == (8, 100) and arrays["b2"].shape == ()
    path = save_ranker(arrays, tmp_path / "trained.npz", {"note": "synthetic"})
    r = LearnedRanker.load(path)
    hits = [int(np.argmax(r.score(None, None, None, [None] * f.shape[0], f)))
            == int(np.argmax(iou)) for f, iou in held]
    assert np.mean(hits) >= 0.9
    top, oracle = heldout_mean_best_iou(r, held)
    assert top == pytest.approx(oracle, abs=0.01)
    # Seeded: the same data and seed give the same weights.
    runs = [train_ranker(train[:20], seed=1, epochs=2, batch_size=256, progress=False)
            for _ in range(2)]
    for key in ("W1", "b1", "w2", "b2", "mean", "std"):
        np.testing.assert_array_equal(runs[0][key], runs[1][key])

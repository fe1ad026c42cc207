"""Cone colour classes (``rld.colors``, issue 41): names, the public planner's integer codes,
class probabilities, what each class says about the side, and the API's errors."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from rld import LaneSolver, solve_lane
from rld.colors import (
    CLASSES,
    SIDE_EITHER,
    SIDE_LEFT,
    SIDE_RIGHT,
    SIDE_UNKNOWN,
    parse_class_probs,
    parse_colors,
    side_labels,
    side_labels_from_probs,
)

XS = np.arange(0.0, 21.0, 3.5)
CONES = np.vstack([np.column_stack([XS, np.full(XS.size, 2.0)]),
                   np.column_stack([XS, np.full(XS.size, -2.0)])])
POSE = (1.0, 0.0, 0.0)


def test_names_codes_and_aliases():
    names = ["unknown", "yellow", "blue", "orange", "big_orange", "left", "right", "Blue "]
    assert parse_colors(names, 8).tolist() == [0, 1, 2, 3, 4, 2, 1, 2]
    # The public planner's numbering: 0 unknown, 1 yellow, 2 blue, 3 orange, 4 big orange.
    assert parse_colors([0, 1, 2, 3, 4], 5).tolist() == [0, 1, 2, 3, 4]
    assert parse_colors(np.array([2.0, 1.0]), 2).tolist() == [2, 1]
    assert CLASSES[parse_colors(["left"], 1)[0]] == "blue"


def test_side_of_each_class():
    # Blue marks the left boundary, yellow the right (the rules); orange and big orange belong
    # to either; unknown says nothing.
    assert side_labels(np.arange(5)).tolist() == [SIDE_UNKNOWN, SIDE_RIGHT, SIDE_LEFT,
                                                  SIDE_EITHER, SIDE_EITHER]


def test_bad_colours_raise():
    for bad, msg in ((["purple"], "unknown colour classes"), ([5], "0..4"), ([-1], "0..4"),
                     ([1.5], "class codes"), ([True], "class codes"), ([np.nan], "class codes")):
        with pytest.raises(ValueError, match=msg):
            parse_colors(bad, 1)
    with pytest.raises(ValueError, match="one class per cone"):
        parse_colors(["blue"], 2)


def test_class_probs_checked_and_read():
    probs = np.array([[0.0, 0.1, 0.9, 0.0, 0.0],     # blue: left
                      [0.2, 0.6, 0.2, 0.0, 0.0],     # yellow: right
                      [0.1, 0.45, 0.45, 0.0, 0.0],   # neither has half: unknown
                      [0.0, 0.0, 0.0, 1.0, 0.0],     # orange: either side
                      [0.0, 0.1, 0.1, 0.4, 0.4]])    # the oranges together: either side
    assert side_labels_from_probs(parse_class_probs(probs, 5)).tolist() == [
        SIDE_LEFT, SIDE_RIGHT, SIDE_UNKNOWN, SIDE_EITHER, SIDE_EITHER]
    probs = probs[:4]
    with pytest.raises(ValueError, match="shape"):
        parse_class_probs(probs[:, :4], 4)
    with pytest.raises(ValueError, match="sum to 1"):
        parse_class_probs(probs * 0.99, 4)
    with pytest.raises(ValueError, match=r"\[0, 1\]"):
        parse_class_probs(np.array([[1.5, -0.5, 0, 0, 0]]), 1)
    # Within the stated tolerance, accepted.
    parse_class_probs(probs + np.array([5e-7, 0, 0, 0, 0]), 4)


@given(st.lists(st.sampled_from(range(5)), min_size=1, max_size=30))
def test_one_hot_probs_give_the_codes_sides(codes):
    probs = np.eye(5)[codes]
    np.testing.assert_array_equal(side_labels_from_probs(probs), side_labels(np.array(codes)))


def test_the_api_takes_names_codes_and_probs_alike():
    names = ["blue"] * XS.size + ["yellow"] * XS.size
    codes = [2] * XS.size + [1] * XS.size
    probs = np.eye(5)[codes]
    lanes = [solve_lane(CONES, POSE, method="rld", colors=names, time_limit_s=5),
             solve_lane(CONES, POSE, method="rld", colors=codes, time_limit_s=5),
             solve_lane(CONES, POSE, method="rld", class_probs=probs, time_limit_s=5)]
    assert all(lane.ok for lane in lanes)
    for lane in lanes[1:]:
        assert lane.left.tolist() == lanes[0].left.tolist()
        assert lane.right.tolist() == lanes[0].right.tolist()
        assert lane.cost == pytest.approx(lanes[0].cost)
    with pytest.raises(ValueError, match="not both"):
        LaneSolver("rld").solve(CONES, POSE, colors=names, class_probs=probs)


def test_no_class_naming_a_side_is_no_colour():
    # Every cone unknown or orange: no side evidence, the call is colourless (rld.api), so the
    # unknown charge (LaneParams.color_unknown) does not shorten the lane.
    plain = solve_lane(CONES, POSE, method="rld", time_limit_s=5)
    for colors in (["unknown"] * 12, ["orange"] * 6 + ["unknown"] * 6):
        lane = solve_lane(CONES, POSE, method="rld", colors=colors, time_limit_s=5)
        assert lane.left.tolist() == plain.left.tolist()
        assert lane.cost == pytest.approx(plain.cost)
    # One blue cone among unknowns: colour, and each unknown cone of the lane is charged.
    colors = ["blue"] + ["unknown"] * 11
    lane = solve_lane(CONES, POSE, method="rld", colors=colors, time_limit_s=5)
    p = LaneSolver("rld").params
    assert (lane.left.tolist(), lane.right.tolist()) == (plain.left.tolist(), plain.right.tolist())
    unknown = sum(colors[i] == "unknown" for i in (*lane.left, *lane.right))
    assert unknown == lane.left.size + lane.right.size - int(0 in lane.left)
    assert lane.cost == pytest.approx(plain.cost + p.w_color * p.color_unknown * unknown)


def test_the_public_integers_mean_classes_not_sides():
    # 1 is yellow (right) now, not left: with rld-sided, whose colour cost is per side, labels
    # given as the old integers (1 left, 2 right) are swapped and cost w_color per cone.
    right_way = solve_lane(CONES, POSE, method="rld-sided", colors=[2] * 6 + [1] * 6,
                           time_limit_s=5)
    old_way = solve_lane(CONES, POSE, method="rld-sided", colors=[1] * 6 + [2] * 6,
                         time_limit_s=5)
    assert right_way.ok and old_way.ok
    assert old_way.cost > right_way.cost


# --------------------------------------------------------------------------------------------
# Simulated colour perception in the protocol (rld.simulation, issue 41 item 2)
# --------------------------------------------------------------------------------------------


def test_no_colour_unless_asked_and_the_same_false_positives():
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    track = generate_track(3)
    plain = simulate_lap(track, range_m=30.0, fp_rate=0.3, seed=4)
    coloured = simulate_lap(track, range_m=30.0, fp_rate=0.3, seed=4, color_accuracy=0.9,
                            color_unknown=0.1)
    assert plain.frame(50).colors is None
    np.testing.assert_array_equal(plain.false_positives, coloured.false_positives)
    f, g = plain.frame(50), coloured.frame(50)
    np.testing.assert_array_equal(f.cones, g.cones)
    assert g.colors.shape == (g.cones.shape[0],)


def test_perfect_colour_reports_each_boundary_its_class():
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    track = generate_track(5)
    lap = simulate_lap(track, range_m=30.0, fp_rate=0.3, seed=1, color_accuracy=1.0,
                       color_unknown=0.0)
    c = lap.point_colors
    assert (c[track.left] == CLASSES.index("blue")).all()
    assert (c[track.right] == CLASSES.index("yellow")).all()
    fp = c[track.cones.shape[0]:]
    assert set(fp.tolist()) <= {0, 1, 2} and len(set(fp.tolist())) == 3  # all three occur
    # One class per cone for the whole lap: a cone keeps its class from frame to frame.
    for k in (40, 120):
        f = lap.frame(k)
        real = f.source >= 0
        np.testing.assert_array_equal(f.colors[real], c[f.source[real]])
        fps = ~real
        np.testing.assert_array_equal(f.colors[fps], c[track.cones.shape[0] - 1 - f.source[fps]])


def test_colour_shares_match_the_model():
    # A = 0.8, U = 0.1 over the labelled cones of eight generated tracks: unknown 10 %, the true
    # class 0.9 * 0.8 = 72 %, the other side's 18 %; each within four binomial standard errors.
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    counts = np.zeros(3)
    for seed in range(8):
        track = generate_track(seed)
        c = simulate_lap(track, range_m=30.0, seed=seed, color_accuracy=0.8,
                         color_unknown=0.1).point_colors
        for side, true, other in ((track.left, 2, 1), (track.right, 1, 2)):
            counts += [(c[side] == 0).sum(), (c[side] == true).sum(), (c[side] == other).sum()]
    n = counts.sum()
    for got, p in zip(counts / n, (0.1, 0.72, 0.18), strict=True):
        assert abs(got - p) <= 4 * np.sqrt(p * (1 - p) / n), (got, p, n)


def test_colour_is_seeded_and_checked():
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    track = generate_track(2)
    a = simulate_lap(track, seed=3, color_accuracy=0.7, color_unknown=0.2).point_colors
    b = simulate_lap(track, seed=3, color_accuracy=0.7, color_unknown=0.2).point_colors
    c = simulate_lap(track, seed=4, color_accuracy=0.7, color_unknown=0.2).point_colors
    np.testing.assert_array_equal(a, b)
    assert (a != c).any()
    for bad in (dict(color_accuracy=1.5), dict(color_accuracy=0.9, color_unknown=-0.1)):
        with pytest.raises(ValueError, match="probability"):
            simulate_lap(track, **bad)


def test_the_protocol_passes_the_colours_to_the_method(monkeypatch):
    from rld.evaluation import run_protocol
    from rld.generator import generate_track

    seen = []
    original = LaneSolver.solve

    def spy(self, cones, pose, colors=None, **kw):
        seen.append(colors)
        return original(self, cones, pose, colors=colors, **kw)

    monkeypatch.setattr(LaneSolver, "solve", spy)
    recs = run_protocol([generate_track(1)], method="nearest", range_m=30.0, every=100,
                        color_accuracy=0.95, color_unknown=0.1)
    assert seen and all(c is not None for c in seen)
    assert recs[0].color_accuracy == 0.95 and recs[0].color_unknown == 0.1
    seen.clear()
    recs = run_protocol([generate_track(1)], method="nearest", range_m=30.0, every=100)
    assert all(c is None for c in seen) and np.isnan(recs[0].color_accuracy)


def test_eval_labels_the_colour_setting_and_refuses_bad_values():
    from click.testing import CliRunner

    from rld.cli import main
    from rld.generator import generate_track
    from rld.report import evaluate, parse_method

    recs = evaluate([generate_track(3)], [parse_method("nearest")], ranges=(30.0,),
                    fp_rates=(0.0,), every=60, processes=1, progress=False, color=(0.95, 0.1))
    assert {r.method for r in recs} == {"nearest colour A=0.95 U=0.1"}
    out = CliRunner().invoke(main, ["eval", "--generated", "1", "--color-accuracy", "1.5"])
    assert out.exit_code == 2 and "--color-accuracy" in out.output

"""Colour as evidence in every method (issue 41, item 3): a cost per cone on the side its class
contradicts and per unknown cone (``rld.costs.boundary_color_cost``), never a hard rule.

On generated tracks (``rld.generator``, ``rld.simulation``) with 30 % false positives: perfect
labels give lanes at least as good as none, 10 % of the true cones' labels swapped still give
the lane, every label swapped gives lanes no worse than none; by the protocol's geometric rule
(``rld.metrics.geometric_deviation``, critical above 1 m). Plus hand-built scenes where the
colour must change the lane, and one where it must not.
"""

from __future__ import annotations

import numpy as np
import pytest

from rld import LaneParams, LaneSolver, Pose, solve_lane
from rld.colors import CLASSES
from rld.generator import generate_track
from rld.metrics import geometric_deviation
from rld.simulation import simulate_lap

BLUE, YELLOW, UNKNOWN = (CLASSES.index(c) for c in ("blue", "yellow", "unknown"))
#: The methods that use colour (``huang`` does not: docs/huang.md).
METHODS = ("rld", "rld-sided", "rld-incremental", "clc", "nearest")
#: Generated tracks and poses of the scenes: R = 30 m, 30 % false positives (seed 1), every 4th
#: pose of the first 120 (the incremental solver needs poses at most 5 m apart to keep its
#: lane). Tracks picked where RLD and CLC have critical poses without colour.
TRACKS = (4, 6, 11)
POSES = range(0, 120, 4)


def _laps():
    return [simulate_lap(generate_track(t), range_m=30.0, fp_rate=0.3, seed=1,
                         color_accuracy=1.0, color_unknown=0.0) for t in TRACKS]


def _relabel(lap, mode: str, share: float = 0.1) -> np.ndarray | None:
    """The lap's class codes with perfect labels (``perfect``), ``share`` of the true cones'
    blue/yellow swapped (``some``, seeded), every true label swapped (``all``), or None
    (``none``: no colour)."""
    if mode == "none":
        return None
    codes = lap.point_colors.copy()
    true = np.concatenate([lap.track.left, lap.track.right])
    if mode == "some":
        rng = np.random.default_rng(7)
        true = rng.choice(true, size=int(round(share * true.size)), replace=False)
    elif mode != "all":
        return codes
    codes[true] = np.where(codes[true] == BLUE, YELLOW, BLUE)
    return codes


def _deviations(method: str, mode: str) -> list[float]:
    """The geometric deviation (m) of ``method``'s lane at every scene pose, colours by
    ``_relabel(mode)``; one solver per lap, as on the car."""
    out = []
    for lap in _laps():
        codes = _relabel(lap, mode)
        solver = LaneSolver(method)
        for k in POSES:
            f = lap.frame(k)
            colors = None if codes is None else codes[_members(lap, f)]
            lane = solver.solve(f.cones, f.pose, colors=colors, time_limit_s=2.0)
            out.append(geometric_deviation(f, lane.left, lane.right, lane.ok, lane.closed))
    return out


def _members(lap, frame) -> np.ndarray:
    """Indices into ``lap.all_points`` of the frame's cones (``Frame.source`` mapped back)."""
    n_real = lap.track.cones.shape[0]
    return np.where(frame.source >= 0, frame.source, n_real - 1 - frame.source)


@pytest.fixture(scope="module")
def deviations():
    """Per method and labelling, the deviations of every scene pose (computed once)."""
    return {(m, mode): _deviations(m, mode) for m in METHODS
            for mode in ("none", "perfect", "some", "all")}


def _critical(devs, d=1.0) -> int:
    return int(sum(x > d for x in devs))


def test_the_scenes_have_something_to_gain(deviations):
    # Not vacuous: without colour the scenes have critical poses for the graph methods.
    assert sum(_critical(deviations[(m, "none")]) for m in METHODS) >= 3


def test_members_map_frames_back_to_the_lap():
    lap = _laps()[0]
    f = lap.frame(30)
    np.testing.assert_array_equal(lap.point_colors[_members(lap, f)], f.colors)


@pytest.mark.parametrize("method", METHODS)
def test_perfect_labels_at_least_as_good_as_none(deviations, method):
    assert _critical(deviations[(method, "perfect")]) <= _critical(deviations[(method, "none")])


#: Where a few swapped labels break the lane today (2026-12-07): on generated track 4, pose 64,
#: the nearest-neighbour chain's right side turns onto unknown false positives before a
#: blue-labelled true cone (COLOR_PENALTY_M). Strict: the test says when that is fixed. (RLD's
#: break here, a swapped first cone outweighing 1.3 of geometry at w_color = 2, went with
#: w_color = 0.35.)
_SWAP_BREAKS = {"nearest"}


@pytest.mark.parametrize("method", [
    pytest.param(m, marks=pytest.mark.xfail(strict=True, reason="one swapped label breaks "
                                            "the lane at one pose (_SWAP_BREAKS)"))
    if m in _SWAP_BREAKS else m for m in METHODS])
def test_some_labels_swapped_still_find_the_lane(deviations, method):
    # On every scene pose whose colourless lane is not critical, 10 % of the true cones
    # labelled as the other side leave the lane found and not critical at 1 m.
    # At least 20 such poses (not vacuous; the nearest-neighbour chain finds the lane at 26 of
    # the 90 colourless).
    none, some = deviations[(method, "none")], deviations[(method, "some")]
    kept = [s for n, s in zip(none, some, strict=True) if n <= 1.0]
    assert len(kept) >= 20
    assert _critical(kept) == 0


@pytest.mark.parametrize("method", METHODS)
def test_every_label_swapped_no_worse_than_none(deviations, method):
    assert _critical(deviations[(method, "all")]) <= _critical(deviations[(method, "none")])


# --------------------------------------------------------------------------------------------
# Hand-built scenes
# --------------------------------------------------------------------------------------------

#: A straight lane 4 m wide, cones 3.5 m apart, the car at x = 1 between them.
XS = np.arange(0.0, 24.5, 3.5)
LEFT = np.column_stack([XS, np.full(XS.size, 2.0)])
RIGHT = np.column_stack([XS, np.full(XS.size, -2.0)])
CAR = Pose(1.0, 0.0, 0.0)


def _scene_with_decoy():
    """The straight lane plus a decoy cone 0.65 m inside the left boundary between its fourth
    and fifth cones: colourless and without the regularity term (``_PLAIN``), RLD's left
    boundary takes it (one more edge's benefit, 2.5, for about 1.8 in spacing and angle costs:
    a gain of about 0.7); labelled yellow (the right side's class: w_color more), it is left
    out when w_color exceeds that gain. The default regularity weight (0.5) leaves it out on
    its own (two cones at a ratio of 2: 1.0 more)."""
    decoy = np.array([[12.25, 1.35]])
    return np.vstack([LEFT, RIGHT, decoy]), LEFT.shape[0] + RIGHT.shape[0]


def _contradictions(lane, codes) -> int:
    """Cones of the lane whose class names the other side."""
    codes = np.asarray(codes)
    return int((codes[lane.left] == "yellow").sum() + (codes[lane.right] == "blue").sum())


#: The paper's geometry alone (no regularity term); a colour weight above the decoy's gain
#: there (about 0.7) and one below it.
_PLAIN = LaneParams(w_regularity=0.0)
_STRONG = LaneParams(w_color=2.0, w_regularity=0.0)
_WEAK = LaneParams(w_color=0.35, w_regularity=0.0)


@pytest.mark.parametrize("method", ["rld", "rld-sided", "rld-incremental"])
def test_a_cone_of_the_other_side_is_left_out(method):
    pts, decoy = _scene_with_decoy()
    codes = ["blue"] * XS.size + ["yellow"] * XS.size + ["yellow"]
    plain = solve_lane(pts, CAR, method=method, time_limit_s=5, params=_PLAIN)
    assert decoy not in solve_lane(pts, CAR, method=method, time_limit_s=5).left  # regularity
    coloured = solve_lane(pts, CAR, method=method, colors=codes, time_limit_s=5, params=_STRONG)
    assert plain.ok and _contradictions(plain, codes) >= 1  # the geometry alone errs
    assert coloured.ok and _contradictions(coloured, codes) == 0
    # The boundaries are runs of the true cones, from beside the car on.
    for side, first in ((coloured.left, 0), (coloured.right, XS.size)):
        assert side.tolist() == list(range(side[0], side[0] + side.size))
        assert first <= side[0] <= first + 1 and side.size >= 5
    # Evidence, not a rule: a weight below the gain (the default, 0.35) keeps the decoy.
    weak = solve_lane(pts, CAR, method=method, colors=codes, time_limit_s=5, params=_WEAK)
    assert decoy in weak.left
    # Orange classes never cost: with the decoy orange, RLD takes it. Unknown costs
    # color_unknown (1) times w_color (2), more than the decoy gains: left out.
    if method in ("rld", "rld-sided"):
        for cls in ("orange", "big_orange"):
            lane = solve_lane(pts, CAR, method=method, colors=codes[:-1] + [cls],
                              time_limit_s=5, params=_STRONG)
            assert decoy in lane.left and lane.cost == pytest.approx(plain.cost), cls
        lane = solve_lane(pts, CAR, method=method, colors=codes[:-1] + ["unknown"],
                          time_limit_s=5, params=_STRONG)
        assert decoy not in lane.left and lane.cost == pytest.approx(coloured.cost)
        assert plain.cost < lane.cost < plain.cost + 1.0


def test_clc_decider_orders_by_class():
    # The left boundary at its fourth cone: a cone 1.5 m on, 0.15 m off the line, scores 0.68
    # in the next-vertex decider against 0.92 for the true cone 3.5 m on (the distance term).
    # Labelled yellow with a penalty of 0.5 rad (``color_penalties``) it comes second; with
    # 0.1 rad, or labelled blue or unknown, it stays first: an order, not a rule.
    import clc.search_kernels as sk
    from clc.search import color_penalties, search_graph

    pts = np.vstack([LEFT, RIGHT, [[12.0, 2.15]]])
    decoy = pts.shape[0] - 1

    def first(label, weight):
        p = LaneParams(nvd_color_weight=weight)
        labels = np.r_[np.ones(XS.size), np.full(XS.size, 2), [label]].astype(np.int64)
        g = search_graph(pts, p, colors=labels)
        path = np.r_[2, 3, np.full(pts.shape[0] - 2, -1)].astype(np.int64)
        in_path = np.isin(np.arange(pts.shape[0]), [2, 3])
        tried = np.zeros(g.indptr[4] - g.indptr[3], dtype=bool)
        pen = None if g.side_penalty is None else g.side_penalty[0]
        return sk._choose_option(pts, g.indptr, g.indices, path, 2, tried, in_path,
                                 p.max_turn_angle_rad, 1.0, 0.0, p.nvd_distance_weight,
                                 p.nvd_lookahead_weight, g.dead_end(p),
                                 np.zeros(0, dtype=np.int64), False, -1, pen)[1]

    assert first(2, 0.5) == 4
    assert first(2, 0.1) == decoy and first(1, 0.5) == decoy and first(0, 0.5) == decoy
    assert color_penalties(None, LaneParams()) is None
    assert color_penalties(np.ones(3, dtype=np.int64), LaneParams(nvd_color_weight=0)) is None


def test_clc_ranking_term_undoes_a_hook():
    # Colourless, CLC's pick hooks its right boundary onto the last left cone. The term after
    # the ranker (``rank_color_weight``, off by default: no gain measured) charges the hook's
    # change of class, and the lane without it wins.
    pts = np.vstack([LEFT, RIGHT])
    codes = ["blue"] * XS.size + ["yellow"] * XS.size
    plain = solve_lane(pts, CAR, method="clc")
    assert plain.ok and _contradictions(plain, codes) == 1
    lane = solve_lane(pts, CAR, method="clc", colors=codes,
                      params=LaneParams(rank_color_weight=1.0))
    assert lane.ok and _contradictions(lane, codes) == 0


def test_colour_is_no_hard_rule():
    # Every cone of the lane labelled as the other side: the lane is the one the right labels
    # give (for RLD also the colourless one); RLD charges its two starts on the wrong class
    # (1/2 each, ``boundary_color_cost``), and the weight 0 turns the cost off.
    pts = np.vstack([LEFT, RIGHT])
    right = ["blue"] * XS.size + ["yellow"] * XS.size
    swapped = ["yellow"] * XS.size + ["blue"] * XS.size
    for method in ("rld", "rld-sided"):
        plain = solve_lane(pts, CAR, method=method, time_limit_s=5)
        lane = solve_lane(pts, CAR, method=method, colors=swapped, time_limit_s=5)
        assert lane.left.tolist() == plain.left.tolist()
        assert lane.right.tolist() == plain.right.tolist()
        assert lane.cost == pytest.approx(plain.cost + LaneParams().w_color * 1.0)
        off = solve_lane(pts, CAR, method=method, colors=swapped, time_limit_s=5,
                         params=LaneParams(w_color=0.0))
        assert off.cost == pytest.approx(plain.cost)
    for method in METHODS:
        good = solve_lane(pts, CAR, method=method, colors=right, time_limit_s=5)
        lane = solve_lane(pts, CAR, method=method, colors=swapped, time_limit_s=5)
        assert good.ok and lane.ok, method
        assert lane.left.tolist() == good.left.tolist(), method
        assert lane.right.tolist() == good.right.tolist(), method


def test_nearest_prefers_its_own_side():
    # A false positive 2.7 m ahead of the second left cone, nearer than the third (3.5 m):
    # colourless the chain steps onto it; labelled yellow it counts COLOR_PENALTY_M farther
    # and is passed for the blue cone. Labelled blue, or with every label swapped (the chain's
    # side is what most of its labels say), the geometry decides as without colour.
    from rld.baselines import COLOR_PENALTY_M

    fp = np.array([[6.2, 2.3]])
    assert np.hypot(*(fp[0] - LEFT[1])) + COLOR_PENALTY_M > 3.5 > np.hypot(*(fp[0] - LEFT[1]))
    pts = np.vstack([LEFT, RIGHT, fp])
    k = pts.shape[0] - 1
    plain = solve_lane(pts, CAR, method="nearest")
    assert k in plain.left
    codes = ["blue"] * XS.size + ["yellow"] * XS.size + ["yellow"]
    lane = solve_lane(pts, CAR, method="nearest", colors=codes)
    assert k not in lane.left and lane.left.tolist()[:3] == [0, 1, 2]
    same = solve_lane(pts, CAR, method="nearest", colors=codes[:-1] + ["blue"])
    assert same.left.tolist() == plain.left.tolist()
    swapped = ["yellow"] * XS.size + ["blue"] * XS.size + ["blue"]
    lane = solve_lane(pts, CAR, method="nearest", colors=swapped)
    assert k not in lane.left and lane.left.tolist()[:3] == [0, 1, 2]


def test_notes_only_where_colour_is_ignored():
    pts = np.vstack([LEFT, RIGHT])
    codes = ["blue"] * XS.size + ["yellow"] * XS.size
    for method in ("rld", "rld-sided", "rld-incremental", "nearest", "clc"):
        lane = solve_lane(pts, CAR, method=method, colors=codes, time_limit_s=5)
        assert "note" not in lane.stats, method
    assert "colors" in solve_lane(pts, CAR, method="huang", colors=codes).stats["note"]
    # CLC with its three colour uses off says so, and not without colours.
    from clc.refine import Refinement
    off = LaneSolver("clc", LaneParams(rank_color_weight=0.0),
                     options={"refine": Refinement(judge_color=False)})
    assert "colors unused" in off.solve(pts, CAR, colors=codes).stats["note"]
    assert "note" not in off.solve(pts, CAR).stats

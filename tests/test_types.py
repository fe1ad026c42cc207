import math

import numpy as np
import pytest
from shapely.geometry import Polygon

from rld import Lane, LaneParams, LaneStatus, Pose
from rld.types import as_cones, as_pose


def test_as_cones_accepts_array_likes():
    arr = as_cones([[0, 0], [1, 0], [2, 0], [3, 0]])
    assert arr.dtype == np.float64 and arr.flags.c_contiguous and arr.shape == (4, 2)


@pytest.mark.parametrize(
    "cones, match",
    [
        ([[0, 0], [1, 1], [2, 2]], "at least 4"),
        (np.zeros((5, 3)), r"shape \(N, 2\)"),
        (np.zeros(8), r"shape \(N, 2\)"),
        ([[0, 0], [1, np.nan], [2, 2], [3, 3]], "NaN or inf at rows \\[1\\]"),
        ([[0, 0], [1, 1], [np.inf, 2], [3, 3]], "NaN or inf"),
        ([["a", "b"]] * 4, "numeric"),
    ],
)
def test_as_cones_rejects(cones, match):
    with pytest.raises(ValueError, match=match):
        as_cones(cones)


def test_as_pose():
    assert as_pose((1, 2, 0.5)) == Pose(1.0, 2.0, 0.5)
    assert as_pose(Pose(1, 2, 3)) == Pose(1, 2, 3)
    with pytest.raises(ValueError, match="3 values"):
        as_pose((1, 2))
    with pytest.raises(ValueError, match="non-finite"):
        as_pose((1, math.nan, 0))
    with pytest.raises(ValueError, match="non-finite"):
        as_pose(Pose(1, 2, math.inf))


def test_pose_frames():
    pose = Pose(1.0, 1.0, math.pi / 2)
    np.testing.assert_allclose(pose.heading, [0, 1], atol=1e-12)
    # A point 2 m ahead and 1 m to the left in the car frame.
    np.testing.assert_allclose(pose.to_local(np.array([[0.0, 3.0]])), [[2.0, 1.0]], atol=1e-12)


def test_lane_params_validation():
    p = LaneParams()
    assert p.max_cone_spacing_m == 5.5 and p.min_width_m == 2.5 and p.max_width_m == 6.5
    assert p.max_iterations == 250  # measured better than the paper's 2500 (see LaneParams)
    assert p.angle_tolerance_rad == 0.7  # tuned (see LaneParams)
    assert p.max_angle_cost == pytest.approx((math.pi / 2 / 0.7) ** 4)
    with pytest.raises(ValueError, match="min_width_m"):
        LaneParams(min_width_m=7.0)
    with pytest.raises(ValueError, match="positive"):
        LaneParams(max_cone_spacing_m=-1)
    with pytest.raises(ValueError, match="finite"):
        LaneParams(w_angle=math.nan)
    with pytest.raises(ValueError, match="max_turn_angle_rad"):
        LaneParams(max_turn_angle_rad=4.0)
    with pytest.raises(AttributeError):
        p.min_width_m = 3.0  # frozen


CONES = np.array([[0, 2], [4, 2], [8, 2], [0, -2], [4, -2], [8, -2], [20, 20]], float)


def test_lane_derives_everything_from_indices():
    lane = Lane(CONES, [0, 1, 2], [3, 4, 5], LaneStatus.OPTIMAL, cost=-1.0)
    assert lane.ok and not lane.closed
    np.testing.assert_array_equal(lane.left_xy, CONES[:3])
    np.testing.assert_array_equal(lane.right_xy, CONES[3:6])
    assert isinstance(lane.polygon, Polygon) and lane.polygon.area == pytest.approx(32.0)
    c = lane.centerline
    np.testing.assert_allclose(c[:, 1], 0.0)
    assert c[0, 0] == 0 and c[-1, 0] == 8


def test_lane_never_holds_a_made_up_lane():
    lost = Lane.not_found(CONES, "no cones near the car")
    assert not lost.ok and lost.status is LaneStatus.NOT_FOUND
    assert lost.left.size == 0 and lost.right.size == 0 and lost.centerline.shape == (0, 2)
    with pytest.raises(ValueError, match="must be empty"):
        Lane(CONES, [0, 1], [3, 4], LaneStatus.NOT_FOUND)
    with pytest.raises(ValueError, match="needs both boundaries"):
        Lane(CONES, [0, 1], [], LaneStatus.FEASIBLE)
    with pytest.raises(ValueError, match="outside"):
        Lane(CONES, [0, 9], [3, 4], LaneStatus.FEASIBLE)
    with pytest.raises(ValueError, match="share a cone"):
        Lane(CONES, [0, 1], [1, 4], LaneStatus.FEASIBLE)
    with pytest.raises(ValueError, match="twice"):
        Lane(CONES, [0, 1, 0], [3, 4], LaneStatus.FEASIBLE)
    with pytest.raises(ValueError, match="right visits a cone twice"):
        Lane(CONES, [0, 1], [3, 4, 3], LaneStatus.FEASIBLE)
    # Twice on one side and shared: the side's own repeat is named first.
    with pytest.raises(ValueError, match="left visits a cone twice"):
        Lane(CONES, [0, 1, 0], [0, 4], LaneStatus.FEASIBLE)


def test_pose_arrays_are_read_only_and_right():
    pose = Pose(1.0, 2.0, math.pi / 2)
    np.testing.assert_allclose(pose.xy, [1.0, 2.0])
    np.testing.assert_allclose(pose.heading, [0.0, 1.0], atol=1e-15)
    with pytest.raises(ValueError):
        pose.xy[0] = 5.0  # shared between reads: never written
    assert pose.xy[0] == 1.0
    assert pose == Pose(1.0, 2.0, math.pi / 2) and hash(pose) == hash(Pose(1.0, 2.0,
                                                                            math.pi / 2))
    import copy
    import pickle

    for other in (pickle.loads(pickle.dumps(pose)), copy.deepcopy(pose)):
        assert other == pose and not other.xy.flags.writeable
        np.testing.assert_allclose(other.heading, pose.heading)


def test_status_ok():
    assert [s.ok for s in LaneStatus] == [True, True, False, False, False]


def test_lane_params_from_overrides():
    p = LaneParams.from_overrides(["max_cone_spacing_m=6", " max_iterations = 500 "])
    assert p.max_cone_spacing_m == 6.0 and isinstance(p.max_cone_spacing_m, float)
    assert p.max_iterations == 500 and isinstance(p.max_iterations, int)
    assert p.min_width_m == LaneParams().min_width_m  # the rest stay the defaults
    assert LaneParams.from_overrides({"w_benefit": 3}).w_benefit == 3.0
    assert LaneParams.from_overrides([]) == LaneParams()


@pytest.mark.parametrize("items, message", [
    (["nope=1"], "no field 'nope'"),
    (["max_iterations=1.5"], "takes an integer"),
    (["w_benefit=abc"], "takes a number"),
    (["w_benefit"], "give a value"),
    (["min_width_m=9"], "must be below max_width_m"),  # __post_init__'s checks still apply
    (["w_benefit=nan"], "finite"),
])
def test_lane_params_from_overrides_refuses(items, message):
    with pytest.raises(ValueError, match=message):
        LaneParams.from_overrides(items)

"""rld.ros without a ROS installation: message conversion, ``rld replay`` on bags these tests
write themselves (a generated lap with false positives and colours, as MCAP and as sqlite3),
its lanes against a ``LaneSolver`` run directly on the same maps, bad input, a truncated bag,
and the live node's callbacks with rclpy stubbed."""

from __future__ import annotations

import math
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
from click.testing import CliRunner

from rld import LaneSolver
from rld.cli import main
from rld.ros import convert as cv
from rld.ros.bag import BagReader, BagWriter
from rld.ros.core import LOG_FIRST
from rld.ros.replay import replay
from rld.ros.sample import POSE_LEAD_NS, lap_maps, write_lap_bag
from rld.ros.typestore import MSG_DIR, default_typestore
from rld.types import Pose

STORE = default_typestore()
F = cv.RosbagsFactory(STORE)
SEED = 7


def _assert_user_error(result, *words):
    """One user error: exit code 2, no traceback, the problem on the last line."""
    assert result.exit_code == 2, result.output
    assert isinstance(result.exception, SystemExit), result.exception
    assert "Traceback" not in result.output
    last = result.output.strip().splitlines()[-1]
    assert last.startswith("Error: "), result.output
    for word in words:
        assert word in last, (word, result.output)


def _roundtrip(msg, msgtype):
    return STORE.deserialize_cdr(STORE.serialize_cdr(msg, msgtype), msgtype)


# --- fixtures ------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def lap():
    """A generated lap, every 4th pose (the whole lap, 1 m poses 4 m apart)."""
    return lap_maps(seed=SEED, every=4)


@pytest.fixture(scope="module")
def lap_mcap(lap, tmp_path_factory):
    return write_lap_bag(tmp_path_factory.mktemp("bags") / "lap.mcap", lap)


def _read(path, topics=()):
    """{topic: [(log time, message)]} of a bag, decoded with rosbags directly."""
    from rosbags.rosbag2 import Reader

    out: dict[str, list] = {}
    with Reader(Path(path)) as r:
        for c, t, raw in r.messages():
            if not topics or c.topic in topics:
                try:
                    msg = STORE.deserialize_cdr(raw, c.msgtype)
                except Exception:  # noqa: BLE001 - the bad-input bag's garbage message
                    msg = None
                out.setdefault(c.topic, []).append((t, msg))
    return out


def _read_pose(msg) -> Pose:
    """The car pose a replay reads from an Odometry or PoseStamped message."""
    p = msg.pose.pose if hasattr(msg.pose, "pose") else msg.pose
    q = p.orientation
    return Pose(p.position.x, p.position.y, cv.yaw_from_quaternion(q.x, q.y, q.z, q.w))


def _direct(maps_and_poses, method, coloured=True, **kw):
    """The lanes of one LaneSolver called on (cones, classes, pose) in order."""
    solver = LaneSolver(method=method, **kw.pop("solver", {}))
    lanes = []
    for cones, classes, pose in maps_and_poses:
        colors = [cv.package_colour(c) for c in classes] if coloured else None
        lanes.append(solver.solve(cones, pose, colors=colors, **kw))
    return lanes


def _path_xy(msg) -> np.ndarray:
    return np.array([(p.pose.position.x, p.pose.position.y) for p in msg.poses]).reshape(-1, 2)


def _assert_lanes_equal(out, lanes, ns="/rld", spacing_m=0.5):
    """The output's lane topics hold exactly ``lanes``, in order."""
    centre = [m for _, m in out.get(f"{ns}/centerline", [])]
    left = [m for _, m in out.get(f"{ns}/left", [])]
    right = [m for _, m in out.get(f"{ns}/right", [])]
    markers = [m for _, m in out.get(f"{ns}/markers", [])]
    assert len(centre) == len(left) == len(right) == len(markers) == len(lanes)
    for k, lane in enumerate(lanes):
        if lane.ok:
            path = lane.path(spacing_m)
            np.testing.assert_array_equal(_path_xy(centre[k]), path.xy, err_msg=f"map {k}")
            yaw = [cv.yaw_from_quaternion(p.pose.orientation.x, p.pose.orientation.y,
                                          p.pose.orientation.z, p.pose.orientation.w)
                   for p in centre[k].poses]
            np.testing.assert_allclose(np.cos(yaw), np.cos(path.heading), atol=1e-12)
            np.testing.assert_array_equal(_path_xy(left[k]), lane.left_xy)
            np.testing.assert_array_equal(_path_xy(right[k]), lane.right_xy)
        else:
            assert not centre[k].poses and not left[k].poses and not right[k].poses
        by_ns = {m.ns: m for m in markers[k].markers}
        assert markers[k].markers[0].action == 3  # DELETEALL first
        assert lane.status.name in by_ns["status"].text
        n_used = lane.left.size + lane.right.size
        assert len(by_ns["ignored"].points) == lane.cones.shape[0] - n_used
        if lane.ok:
            assert len(by_ns["chosen"].points) == n_used


# --- conversion ----------------------------------------------------------------------------


def test_package_colour_follows_the_packages_colour_classes():
    from rld.colors import CLASSES, parse_colors

    assert {cv.package_colour(c) for c in cv.FS_CLASSES} == set(CLASSES)
    labels = [cv.package_colour(c) for c in cv.FS_CLASSES]
    assert parse_colors(labels, 5).tolist() == [CLASSES.index(c) for c in cv.FS_CLASSES]


@pytest.mark.parametrize("msgtype", cv.CONE_TYPES)
def test_cone_messages_round_trip_through_cdr(msgtype):
    rng = np.random.default_rng(1)
    xy = rng.uniform(-50, 50, size=(23, 2))
    classes = np.array([cv.FS_CLASSES[k % 5] for k in range(23)], dtype=object)
    msg = _roundtrip(cv.cones_to_msg(xy, classes, "map", 1_500_000_123, F, msgtype), msgtype)
    cones = cv.cones_from_msg(msg, msgtype)
    assert cones.frame_id == "map" and cones.stamp_ns == 1_500_000_123
    assert cones.msgtype == msgtype and cv.msgtype_of(msg) == msgtype
    if msgtype.startswith("eufs_msgs"):
        order = np.concatenate([np.flatnonzero(classes == c) for c in cv.FS_CLASSES])
        np.testing.assert_array_equal(cones.xy, xy[order])  # grouped by class, exact
        assert cones.classes.tolist() == classes[order].tolist()
        assert cones.colors == [cv.package_colour(c) for c in classes[order]]
    else:
        tol = 1e-5 if msgtype == cv.POLYGON else 0  # Point32 holds float32
        np.testing.assert_allclose(cones.xy, xy, atol=tol * 50, rtol=0)
        assert cones.colors is None and set(cones.classes) == {"unknown"}


@pytest.mark.parametrize("msgtype", cv.POSE_TYPES)
def test_pose_messages_give_the_yaw_of_their_quaternion(msgtype):
    for yaw in (0.0, 0.3, -1.2, 3.0, -3.1, math.pi):
        msg = _roundtrip(cv.pose_to_msg(Pose(4.5, -2.0, yaw), "odom", 7, F, msgtype), msgtype)
        got = cv.pose_from_msg(msg, msgtype)
        assert (got.pose.x, got.pose.y, got.frame_id, got.stamp_ns) == (4.5, -2.0, "odom", 7)
        assert abs(math.remainder(got.pose.yaw - yaw, 2 * math.pi)) < 1e-12


def test_yaw_of_a_quaternion_that_is_not_unit_and_of_a_tilted_one():
    s, c = math.sin(0.35), math.cos(0.35)
    assert cv.yaw_from_quaternion(0, 0, 3 * s, 3 * c) == pytest.approx(0.7)
    # Yaw 0.7 after a roll of pi about x (the car upside down): x still points along 0.7.
    assert cv.yaw_from_quaternion(c, s, 0.0, 0.0) == pytest.approx(0.7)


def test_other_message_types_are_refused_by_name():
    string = F.new("std_msgs/msg/String", data="x")
    with pytest.raises(cv.UnsupportedMessage, match="std_msgs/msg/String"):
        cv.cones_from_msg(string)
    with pytest.raises(cv.UnsupportedMessage, match="std_msgs/msg/String"):
        cv.pose_from_msg(string)


def test_frames_same_frame_a_fixed_transform_either_way_or_a_clear_error():
    p = cv.StampedPose(Pose(1.0, 2.0, 0.5), "odom", 0)
    assert cv.pose_in_frame(cv.StampedPose(p.pose, "map", 0), "map") == p.pose
    t = cv.FrameTransform.parse("map, odom, 10, -5, 1.5707963267948966")
    q = cv.pose_in_frame(p, "map", t)  # odom -> map
    assert (q.x, q.y, q.yaw) == pytest.approx((10 - 2.0, -5 + 1.0, 0.5 + math.pi / 2))
    back = cv.pose_in_frame(cv.StampedPose(q, "map", 0), "odom", t)  # map -> odom
    assert (back.x, back.y, back.yaw) == pytest.approx((1.0, 2.0, 0.5))
    with pytest.raises(cv.FrameMismatch, match="'map'.*'odom'"):
        cv.pose_in_frame(p, "map")
    with pytest.raises(cv.FrameMismatch, match="joins 'world' and 'odom'"):
        cv.pose_in_frame(p, "map", cv.FrameTransform("world", "odom"))
    for bad in ("map,odom,1,2", "map,odom,a,0,0", ",odom,0,0,0", "map,map,0,0,0",
                "map,odom,nan,0,0"):
        with pytest.raises(ValueError):
            cv.FrameTransform.parse(bad)


def test_the_shipped_eufs_definitions_parse_and_match_the_schema():
    names = sorted(p.stem for p in MSG_DIR.glob("eufs_msgs/*.msg"))
    assert names == ["ConeArray", "ConeArrayWithCovariance", "ConeWithCovariance"]
    fields = [n for n, _ in STORE.fielddefs["eufs_msgs/msg/ConeArrayWithCovariance"][1]]
    assert fields == ["header"] + [f for f, _ in cv.EUFS_FIELDS]
    assert [n for n, _ in STORE.fielddefs["eufs_msgs/msg/ConeWithCovariance"][1]] == [
        "point", "covariance"]


def test_importing_rld_ros_needs_neither_rclpy_nor_the_bag_libraries():
    code = ("import sys, rld, rld.ros, rld.ros.node, rld.ros.replay, rld.ros.core;"
            "bad = [m for m in ('rclpy', 'rosbags', 'mcap') if m in sys.modules];"
            "assert not bad, bad")
    subprocess.run([sys.executable, "-c", code], check=True)


# --- replay ------------------------------------------------------------------------------


def test_rld_replay_of_a_full_lap_equals_the_direct_solver(lap, lap_mcap, tmp_path):
    out, png = tmp_path / "lanes.mcap", tmp_path / "lap.png"
    result = CliRunner().invoke(main, ["replay", str(lap_mcap), "--cones", "/cones", "--pose",
                                       "/odometry", "--out", str(out), "--method", "clc",
                                       "--plot", str(png)])
    assert result.exit_code == 0, result.output
    n = len(lap)
    text = result.output
    assert f"messages    {n} maps, {n} poses" in text
    assert "skipped     0" in text and "latency     median" in text and "p95" in text
    assert "solve       median" in text
    assert png.stat().st_size > 10_000
    # Foxglove's own reader: an indexed MCAP of ROS 2 schemas, every message readable.
    from mcap.reader import make_reader

    with open(out, "rb") as fh:
        reader = make_reader(fh)
        summary = reader.get_summary()
        assert {s.encoding for s in summary.schemas.values()} == {"ros2msg"}
        assert {c.message_encoding for c in summary.channels.values()} == {"cdr"}
        assert summary.chunk_indexes and summary.statistics.message_count == 6 * n
        assert sum(1 for _ in reader.iter_messages()) == 6 * n
    got = _read(out)
    # The input topics as recorded, and a lane at every map, at the map's log time.
    assert [t for t, _ in got["/cones"]] == [m.log_time_ns for m in lap]
    assert len(got["/odometry"]) == n
    assert [t for t, _ in got["/rld/centerline"]] == [m.log_time_ns for m in lap]
    assert all(msg.header.frame_id == "map" for _, msg in got["/rld/left"])
    poses = [_read_pose(msg) for _, msg in got["/odometry"]]
    lanes = _direct([(m.cones, m.classes, p) for m, p in zip(lap, poses, strict=True)], "clc")
    assert sum(lane.ok for lane in lanes) >= 0.8 * n
    assert f"lanes       {sum(lane.ok for lane in lanes)} found" in text
    _assert_lanes_equal(got, lanes)
    # The lap has every colour class, false positives of blue and yellow among them.
    assert any(set(m.classes) >= set(cv.FS_CLASSES) for m in lap)


def test_the_solver_gets_each_cones_class(lap):
    from rld.ros.core import LaneProcessor

    proc = LaneProcessor(F, method="clc")
    seen = []
    solve = proc.solver.solve

    def spy(cones, pose, colors=None, **kw):
        seen.append((np.array(cones), colors))
        return solve(cones, pose, colors=colors, **kw)

    proc.solver.solve = spy
    m = lap[10]
    assert proc.on_pose(_roundtrip(cv.pose_to_msg(m.pose, "map", 0, F), cv.ODOMETRY)) is None
    out = proc.on_cones(_roundtrip(cv.cones_to_msg(m.cones, m.classes, "map", 1, F),
                                   cv.EUFS_CONES))
    assert out.lane is not None and out.skipped is None and set(out.messages) == set(
        cv.OUTPUT_TYPES)
    np.testing.assert_array_equal(seen[0][0], m.cones)
    assert seen[0][1] == list(m.classes)


def test_replay_of_a_sqlite3_bag_folder_equals_the_direct_solver(lap, tmp_path):
    maps = lap[::3]
    bag = write_lap_bag(tmp_path / "drive", maps, pose_topic="/pose", storage="sqlite3",
                        pose_type=cv.POSE_STAMPED)
    assert (bag / "metadata.yaml").exists() and list(bag.glob("*.db3"))
    out = tmp_path / "lanes.mcap"
    result = replay(bag, out, "/cones", "/pose", method="clc", out_ns="/car/lane",
                    spacing_m=1.0)
    assert result.stats.maps == len(maps) and not result.stats.skipped
    got = _read(out)
    poses = [_read_pose(msg) for _, msg in got["/pose"]]
    lanes = _direct([(m.cones, m.classes, p) for m, p in zip(maps, poses, strict=True)], "clc")
    _assert_lanes_equal(got, lanes, ns="/car/lane", spacing_m=1.0)


def test_replay_of_colourless_cones_in_a_bare_db3_file(lap, tmp_path):
    maps = lap[::6]
    bag = write_lap_bag(tmp_path / "drive.db3", maps, cones_type=cv.POSE_ARRAY,
                        pose_type=cv.POSE_COV)
    out = tmp_path / "lanes.mcap"
    result = replay(bag, out, "/cones", "/odometry", method="clc")
    assert result.stats.maps == len(maps) and not result.stats.skipped
    got = _read(out)
    poses = [_read_pose(msg) for _, msg in got["/odometry"]]
    lanes = _direct([(m.cones, m.classes, p) for m, p in zip(maps, poses, strict=True)], "clc",
                    coloured=False)
    _assert_lanes_equal(got, lanes)


def test_replay_with_rld_equals_the_direct_solver(lap, lap_mcap, tmp_path):
    maps = lap[::4]
    bag = write_lap_bag(tmp_path / "few.mcap", maps)
    out = tmp_path / "lanes.mcap"
    kw = {"backend": "highs", "time_limit_s": 30.0}
    result = replay(bag, out, "/cones", "/odometry", method="rld", **kw)
    got = _read(out)
    poses = [_read_pose(msg) for _, msg in got["/odometry"]]
    lanes = _direct([(m.cones, m.classes, p) for m, p in zip(maps, poses, strict=True)], "rld",
                    solver={"backend": "highs"}, time_limit_s=30.0)
    assert result.stats.found == sum(lane.ok for lane in lanes) > 0
    _assert_lanes_equal(got, lanes)


def _bad_input_bag(path, lap):
    """A drive with every kind of bad input: the bag, and each solved map with the index of
    the /odometry message whose pose it is solved at."""
    m0, m1, m2, m3 = lap[2], lap[3], lap[4], lap[5]
    t = m0.log_time_ns
    far = Pose(m1.pose.x + 1000.0, m1.pose.y, m1.pose.yaw)
    with BagWriter(path) as w:
        def cones(m, k, xy=None, classes=None):
            xy = m.cones if xy is None else xy
            classes = m.classes if classes is None else classes
            w.write("/cones", cv.cones_to_msg(xy, classes, "map", t + k, F), t + k,
                    cv.EUFS_CONES)

        def pose(p, k):
            w.write("/odometry", cv.pose_to_msg(p, "map", t + k, F), t + k, cv.ODOMETRY)

        cones(m0, 0)                                   # a map before any pose
        pose(m0.pose, 1)                               # pose 0
        cones(m0, 2)                                   # solved at pose 0
        cones(m0, 3, np.zeros((0, 2)), [])             # a map with no cones
        cones(m0, 4, m0.cones[:3], m0.classes[:3])     # three cones
        w.write("/cones", F.new("std_msgs/msg/String", data="hello"), t + 5)  # unknown type
        w.write_raw(w.connection("/cones", cv.EUFS_CONES), t + 6, b"\x00\x01\x00\x00\x07")
        w.write("/odometry", F.new("geometry_msgs/msg/Point", x=1.0, y=2.0, z=0.0), t + 7)
        pose(Pose(math.nan, 0.0, 0.0), 8)              # non-finite: the last pose stays
        pose(far, 9)                                   # pose 3
        cones(m1, 10)                                  # far from the car: NOT_FOUND
        cones(m2, 11)                                  # a tie of log times with pose 4,
        pose(m2.pose, 11)                              # written after it: the pose counts
        pose(m3.pose, 12)                              # pose 5
        cones(m3, 13)
    return path, [(m0, 0), (m1, 3), (m2, 4), (m3, 5)]


def test_bad_input_is_logged_counted_and_skipped_and_no_lane_is_lost(lap, tmp_path):
    bag, solved = _bad_input_bag(tmp_path / "bad.mcap", lap)
    out = tmp_path / "lanes.mcap"
    result = CliRunner().invoke(main, ["replay", str(bag), "--cones", "/cones", "--pose",
                                       "/odometry", "--out", str(out), "--method", "clc"])
    assert result.exit_code == 0, result.output
    text = result.output
    for line in ("skipped: map before any pose", "skipped: map with no cones",
                 "skipped: map with fewer than 4 cones: at 0.000 s: 3 cones",
                 "skipped: unsupported map message type", "std_msgs/msg/String",
                 "skipped: undecodable map message", "skipped: unsupported pose message type",
                 "skipped: non-finite pose"):
        assert line in text, (line, text)
    assert "messages    9 maps, 6 poses" in text
    assert ("skipped     7: 1 map before any pose, 1 map with fewer than 4 cones, 1 map with "
            "no cones, 1 non-finite pose, 1 undecodable map message, 1 unsupported map message "
            "type, 1 unsupported pose message type") in text
    assert "lanes       3 found, not found: 1 NOT_FOUND" in text
    got = _read(out)
    assert len(got["/cones"]) == 9 and len(got["/odometry"]) == 6  # copied, bad ones too
    odometry = [msg for _, msg in got["/odometry"]]
    lanes = _direct([(m.cones, m.classes, _read_pose(odometry[k])) for m, k in solved], "clc")
    assert [lane.ok for lane in lanes] == [True, False, True, True]
    _assert_lanes_equal(got, lanes)


def test_a_truncated_mcap_keeps_every_lane_before_the_cut(lap, tmp_path):
    maps = lap[:24]
    bag = tmp_path / "long.mcap"
    image = F.new("sensor_msgs/msg/CompressedImage", format="jpeg",
                  data=np.zeros(300_000, dtype=np.uint8))
    with BagWriter(bag) as w:  # a camera topic fills rosbags' 1 MiB chunks
        for k, m in enumerate(maps):
            t = m.log_time_ns - POSE_LEAD_NS
            w.write("/odometry", cv.pose_to_msg(m.pose, "map", t, F), t, cv.ODOMETRY)
            w.write("/cones", cv.cones_to_msg(m.cones, m.classes, "map", m.log_time_ns, F),
                    m.log_time_ns, cv.EUFS_CONES)
            if k % 4 == 3:
                w.write("/camera", image, m.log_time_ns + 1)
    data = bag.read_bytes()
    cut = tmp_path / "cut.mcap"
    cut.write_bytes(data[: int(1.3 * 2**20)])  # in the second chunk
    out = tmp_path / "lanes.mcap"
    result = CliRunner().invoke(main, ["replay", str(cut), "--cones", "/cones", "--pose",
                                       "/odometry", "--out", str(out), "--method", "nearest"])
    assert result.exit_code == 0, result.output
    assert "1 truncated bag" in result.output and "ended early" in result.output
    got = _read(out)
    assert "/camera" not in got  # only the replayed topics are copied
    k = len(got["/cones"])
    assert 4 <= k < len(maps)
    assert [t for t, _ in got["/cones"]] == [m.log_time_ns for m in maps[:k]]
    poses = [_read_pose(msg) for _, msg in got["/odometry"]][:k]
    lanes = _direct([(m.cones, m.classes, p) for m, p in zip(maps[:k], poses, strict=True)],
                    "nearest")
    _assert_lanes_equal(got, lanes)
    assert f"messages    {k} maps" in result.output


def test_a_frame_mismatch_is_a_clear_error_and_a_transform_joins_the_frames(lap, tmp_path):
    maps = lap[:6]
    t = cv.FrameTransform("map", "odom", 3.0, -1.0, 0.4)
    bag = tmp_path / "frames.mcap"
    with BagWriter(bag) as w:
        for m in maps:
            odom = t.parent_to_child(m.pose)
            w.write("/odometry", cv.pose_to_msg(odom, "odom", m.log_time_ns - POSE_LEAD_NS, F),
                    m.log_time_ns - POSE_LEAD_NS, cv.ODOMETRY)
            w.write("/cones", cv.cones_to_msg(m.cones, m.classes, "map", m.log_time_ns, F),
                    m.log_time_ns, cv.EUFS_CONES)
    out = tmp_path / "lanes.mcap"
    args = ["replay", str(bag), "--cones", "/cones", "--pose", "/odometry", "--out", str(out),
            "--method", "clc"]
    _assert_user_error(CliRunner().invoke(main, args), "'map'", "'odom'", "--transform")
    assert not out.exists()
    result = CliRunner().invoke(main, args + ["--transform", "map,odom,3,-1,0.4"])
    assert result.exit_code == 0, result.output
    got = _read(out)
    poses = [t.child_to_parent(_read_pose(msg)) for _, msg in got["/odometry"]]
    lanes = _direct([(m.cones, m.classes, p) for m, p in zip(maps, poses, strict=True)], "clc")
    assert sum(lane.ok for lane in lanes) >= 4
    _assert_lanes_equal(got, lanes)
    # The same transform given the other way round (map's pose in odom) gives the same lanes.
    inv = t.parent_to_child(Pose(0.0, 0.0, 0.0))
    out2 = tmp_path / "lanes2.mcap"
    result = CliRunner().invoke(main, args[:-3] + [str(out2), "--method", "clc", "--transform",
                                                   f"odom,map,{inv.x!r},{inv.y!r},{inv.yaw!r}"])
    assert result.exit_code == 0, result.output
    again = _read(out2)
    for side in ("/rld/left", "/rld/right"):
        for (_, a), (_, b) in zip(got[side], again[side], strict=True):
            np.testing.assert_allclose(_path_xy(a), _path_xy(b), atol=1e-9)


def test_replay_user_errors_are_one_line(lap_mcap, tmp_path):
    base = ["replay", str(lap_mcap), "--cones", "/cones", "--pose", "/odometry"]
    run = CliRunner().invoke
    _assert_user_error(run(main, base + ["--out", str(tmp_path / "x.bag")]), ".mcap")
    _assert_user_error(run(main, base[:3] + ["/nope", "--pose", "/odometry", "--out",
                                             str(tmp_path / "a.mcap")]),
                       "no cone topic '/nope'", "/odometry")
    _assert_user_error(run(main, base + ["--out", str(tmp_path / "a.mcap"), "--transform",
                                         "map,odom,1"]), "PARENT,CHILD,X,Y,YAW")
    _assert_user_error(run(main, base + ["--out", str(tmp_path / "a.mcap"), "--out-ns",
                                         "rld"]), "absolute ROS name")
    _assert_user_error(run(main, base + ["--out", str(lap_mcap)]), "input bag")
    junk = tmp_path / "junk.mcap"
    junk.write_text("not a bag")
    _assert_user_error(run(main, ["replay", str(junk), "--cones", "/c", "--pose", "/p",
                                  "--out", str(tmp_path / "b.mcap")]), "junk.mcap")
    _assert_user_error(run(main, base + ["--out", str(tmp_path / "c.mcap"), "--param",
                                         "nope=1"]), "nope")


def test_skips_beyond_the_first_few_are_counted_not_logged(lap, tmp_path):
    bag = tmp_path / "early.mcap"
    with BagWriter(bag) as w:
        for k, m in enumerate(lap[:8]):
            w.write("/cones", cv.cones_to_msg(m.cones, m.classes, "map", k, F), k, cv.EUFS_CONES)
        w.write("/odometry", cv.pose_to_msg(lap[0].pose, "map", 100, F), 100, cv.ODOMETRY)
    lines: list[str] = []
    result = replay(bag, tmp_path / "o.mcap", "/cones", "/odometry", method="nearest",
                    log=lines.append)
    assert result.stats.skipped == {"map before any pose": 8}
    assert len(lines) == LOG_FIRST and "further ones are counted" in lines[-1]


def test_a_bag_reader_lists_topics_and_reads_a_bag_folder(lap, tmp_path):
    bag = write_lap_bag(tmp_path / "folder", lap[:3])
    with BagReader(bag, {"/cones"}) as r:
        assert {c.topic for c in r.connections} == {"/cones", "/odometry"}
        msgs = list(r.messages())
    assert r.problem is None and r.total == 3 and len(msgs) == 3
    assert all(m.connection.msgtype == cv.EUFS_CONES for m in msgs)


# --- the node, rclpy stubbed -----------------------------------------------------------------


class _Publisher:
    def __init__(self, cls, topic):
        self.cls, self.topic, self.sent = cls, topic, []

    def publish(self, msg):
        self.sent.append(msg)


class _Logger:
    def __init__(self, lines):
        self.lines = lines

    def info(self, text):
        self.lines.append(("info", text))

    def warning(self, text):
        self.lines.append(("warning", text))

    def error(self, text):
        self.lines.append(("error", text))


class _Node:
    """rclpy.node.Node as the node uses it; ``overrides`` plays ``-p NAME:=VALUE``."""

    overrides: dict = {}
    made: list = []

    def __init__(self, name, **kwargs):
        self.name, self.params, self.pubs, self.subs, self.logs = name, {}, {}, {}, []
        self.destroyed = False
        _Node.made.append(self)

    def declare_parameter(self, name, value):
        self.params[name] = self.overrides.get(name, value)

    def get_parameter(self, name):
        return types.SimpleNamespace(value=self.params[name])

    def create_publisher(self, cls, topic, depth):
        self.pubs[topic] = _Publisher(cls, topic)
        return self.pubs[topic]

    def create_subscription(self, cls, topic, callback, depth):
        self.subs[topic] = (cls, callback)

    def get_logger(self):
        return _Logger(self.logs)

    def destroy_node(self):
        self.destroyed = True


def _message_class(msgtype):
    """A stand-in for an rclpy message class: keyword fields, made as rosbags messages."""
    fields = {name: "" for name, _ in STORE.fielddefs[msgtype][1]}

    class Msg:
        def __new__(cls, **kw):
            unknown = set(kw) - set(fields)
            assert not unknown, unknown
            return F.new(msgtype, **kw)

        @staticmethod
        def get_fields_and_field_types():
            return fields

    Msg.__name__ = msgtype.rsplit("/", 1)[1]
    return Msg


@pytest.fixture
def rclpy_stub(monkeypatch):
    """rclpy, rclpy.node, rclpy.executors and the message packages the node imports."""
    _Node.overrides, _Node.made = {}, []
    rclpy = types.ModuleType("rclpy")
    state = {"ok": False, "spun": []}

    def spin(node):
        state["spun"].append(node)
        raise KeyboardInterrupt

    rclpy.init = lambda args=None: state.update(ok=True, args=args)
    rclpy.spin = spin
    rclpy.ok = lambda: state["ok"]
    rclpy.shutdown = lambda: state.update(ok=False)
    node_mod = types.ModuleType("rclpy.node")
    node_mod.Node = _Node
    executors = types.ModuleType("rclpy.executors")
    executors.ExternalShutdownException = type("ExternalShutdownException", (Exception,), {})
    for name, mod in (("rclpy", rclpy), ("rclpy.node", node_mod),
                      ("rclpy.executors", executors)):
        monkeypatch.setitem(sys.modules, name, mod)
    for msgtype in list(STORE.types):
        pkg, _, name = msgtype.split("/")
        if pkg not in ("std_msgs", "geometry_msgs", "nav_msgs", "visualization_msgs",
                       "builtin_interfaces", "eufs_msgs"):
            continue
        if f"{pkg}.msg" not in sys.modules or not hasattr(sys.modules[f"{pkg}.msg"], "_stub"):
            monkeypatch.setitem(sys.modules, pkg, types.ModuleType(pkg))
            msg_mod = types.ModuleType(f"{pkg}.msg")
            msg_mod._stub = True
            monkeypatch.setitem(sys.modules, f"{pkg}.msg", msg_mod)
        setattr(sys.modules[f"{pkg}.msg"], name, _message_class(msgtype))
    return state


def test_the_node_publishes_what_the_replay_writes(lap, rclpy_stub):
    from rld.ros.node import make_node

    _Node.overrides = {"method": "clc", "cones_topic": "/slam/map", "pose_topic": "/odom",
                       "out_ns": "/planning/lane", "lane.max_cone_spacing_m": 6.0}
    node = make_node()
    logic = node.rld_logic
    assert logic.processor.solver.method == "clc"
    assert logic.processor.solver.params.max_cone_spacing_m == 6.0
    assert set(node.pubs) == {f"/planning/lane/{s}" for s in cv.OUTPUT_TYPES}
    assert node.subs["/slam/map"][0].__name__ == "ConeArrayWithCovariance"
    assert node.subs["/odom"][0].__name__ == "Odometry"
    on_cones, on_pose = node.subs["/slam/map"][1], node.subs["/odom"][1]
    maps = lap[:10]
    on_cones(cv.cones_to_msg(maps[0].cones, maps[0].classes, "map", 1, F))  # before any pose
    feed = []
    for m in maps:
        pose_msg = _roundtrip(cv.pose_to_msg(m.pose, "map", m.log_time_ns - 1, F), cv.ODOMETRY)
        on_pose(pose_msg)
        on_cones(cv.cones_to_msg(m.cones, m.classes, "map", m.log_time_ns, F))
        feed.append((m.cones, m.classes, _read_pose(pose_msg)))
    from rld.types import LaneParams

    lanes = _direct(feed, "clc", solver={"params": LaneParams(max_cone_spacing_m=6.0)})
    sent = {topic: [(0, msg) for msg in pub.sent] for topic, pub in node.pubs.items()}
    _assert_lanes_equal(sent, lanes, ns="/planning/lane")
    for topic, pub in node.pubs.items():  # valid messages of their types
        for msg in pub.sent:
            STORE.serialize_cdr(msg, cv.OUTPUT_TYPES[topic.rsplit("/", 1)[1]])
    assert logic.stats.skipped == {"map before any pose": 1}
    assert ("warning", "skipped: map before any pose") in node.logs
    # A pose in another frame: an error logged once, counted each time, nothing published.
    n = len(node.pubs["/planning/lane/centerline"].sent)
    on_pose(cv.pose_to_msg(maps[0].pose, "odom", 5, F))
    for _ in range(2):
        on_cones(cv.cones_to_msg(maps[0].cones, maps[0].classes, "map", 6, F))
    assert len(node.pubs["/planning/lane/centerline"].sent) == n
    errors = [text for level, text in node.logs if level == "error"]
    assert len(errors) == 1 and "'odom'" in errors[0] and "parameter transform" in errors[0]
    assert logic.stats.skipped["frame mismatch"] == 2


def test_node_parameters_are_checked_and_main_spins_and_summarises(rclpy_stub):
    from rld.ros import node as node_mod

    for bad, word in (({"method": "nope"}, "method"), ({"cones_type": "std_msgs/msg/String"},
                                                       "cones_type"),
                      ({"transform": "map,odom"}, "transform"), ({"out_ns": "x"}, "out_ns"),
                      ({"lane.min_width_m": 9.0}, "lane.*"), ({"time_limit_s": -1.0},
                                                             "time_limit_s")):
        _Node.overrides = bad
        with pytest.raises(ValueError, match=word.replace("*", r"\*")):
            node_mod.make_node()
        assert _Node.made[-1].destroyed
    _Node.overrides = {"transform": "map,odom,1,2,0.5", "time_limit_s": 0.2,
                       "pose_type": cv.POSE_STAMPED}
    node_mod.main(["--ros-args"])
    node = _Node.made[-1]
    assert rclpy_stub["spun"] == [node] and node.destroyed and not rclpy_stub["ok"]
    assert node.rld_logic.config.transform == cv.FrameTransform("map", "odom", 1, 2, 0.5)
    assert node.rld_logic.config.time_limit_s == 0.2
    assert node.subs["/odometry"][0].__name__ == "PoseStamped"
    assert any("rld summary" in text and "messages    0 maps" in text
               for _, text in node.logs)
    _Node.overrides = {"method": "nope"}
    with pytest.raises(SystemExit) as exc:
        node_mod.main([])
    assert exc.value.code == 2

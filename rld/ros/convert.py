"""Message conversion between ROS 2 messages and the package's arrays (no ROS needed).

In: a cone map (``cones_from_msg``: eufs_msgs/ConeArrayWithCovariance, eufs_msgs/ConeArray,
geometry_msgs/PoseArray or geometry_msgs/PolygonStamped) and the car's pose (``pose_from_msg``:
nav_msgs/Odometry, geometry_msgs/PoseStamped or geometry_msgs/PoseWithCovarianceStamped), read
by attribute, so the same functions take rclpy's messages on the car and rosbags' in a replay.
The pose is brought into the cones' frame by ``pose_in_frame`` (the same frame, or a fixed
``FrameTransform``; else ``FrameMismatch``).

Out: ``lane_messages`` builds the centreline (nav_msgs/Path, the planner-ready path of
``Lane.path``), the two boundaries (nav_msgs/Path through their cones) and a
visualization_msgs/MarkerArray (boundaries, chosen cones, ignored cones, a status text) through
a message factory: ``RosbagsFactory`` (a rosbags typestore, for bags) or ``RclpyFactory`` (the
installed ROS message packages, for the live node).

Units: metres and radians; stamps are integer nanoseconds.
"""

from __future__ import annotations

import importlib
import math
from dataclasses import dataclass
from typing import Any

import numpy as np

from rld.types import Lane, Pose

__all__ = [
    "CONE_TYPES", "POSE_TYPES", "OUTPUT_TYPES", "EUFS_FIELDS", "FS_CLASSES",
    "UnsupportedMessage", "FrameMismatch",
    "package_colour", "ConeMap", "StampedPose", "FrameTransform",
    "msgtype_of", "cones_from_msg", "pose_from_msg", "pose_in_frame",
    "yaw_from_quaternion", "quaternion_from_yaw", "stamp_ns", "time_fields",
    "RosbagsFactory", "RclpyFactory", "lane_messages", "cones_to_msg", "pose_to_msg",
]

EUFS_CONES = "eufs_msgs/msg/ConeArrayWithCovariance"
EUFS_CONES_PLAIN = "eufs_msgs/msg/ConeArray"
POSE_ARRAY = "geometry_msgs/msg/PoseArray"
POLYGON = "geometry_msgs/msg/PolygonStamped"
ODOMETRY = "nav_msgs/msg/Odometry"
POSE_STAMPED = "geometry_msgs/msg/PoseStamped"
POSE_COV = "geometry_msgs/msg/PoseWithCovarianceStamped"
PATH = "nav_msgs/msg/Path"
MARKERS = "visualization_msgs/msg/MarkerArray"

#: Message types ``cones_from_msg`` reads; the first is the default and carries colours.
CONE_TYPES = (EUFS_CONES, EUFS_CONES_PLAIN, POSE_ARRAY, POLYGON)
#: Message types ``pose_from_msg`` reads; the first is the default.
POSE_TYPES = (ODOMETRY, POSE_STAMPED, POSE_COV)
#: The lane's output topics, as suffixes of the output namespace, and their message types.
OUTPUT_TYPES = {"centerline": PATH, "left": PATH, "right": PATH, "markers": MARKERS}

#: eufs_msgs' cone fields in message order and the Formula Student colour class of each.
EUFS_FIELDS = (("blue_cones", "blue"), ("yellow_cones", "yellow"), ("orange_cones", "orange"),
               ("big_orange_cones", "big_orange"), ("unknown_color_cones", "unknown"))
#: The Formula Student cone colour classes, in eufs_msgs' order.
FS_CLASSES = tuple(c for _, c in EUFS_FIELDS)


class UnsupportedMessage(ValueError):
    """A message of a type this module does not read (its type is in the message)."""


class FrameMismatch(ValueError):
    """The cones and the pose are in different frames and no transform joins them."""


def package_colour(fs_class: str) -> str:
    """The package's colour class (``rld.colors.CLASSES``) of an eufs_msgs colour class
    (``FS_CLASSES``), as the solvers' ``colors`` take it.

    This follows the package's colour classes and is the one place the mapping lives. The
    package's classes are the Formula Student ones, named as here (blue, yellow, orange,
    big_orange, unknown), so it is the identity; with side labels it was blue -> left, yellow
    -> right, the others unknown."""
    return fs_class


def msgtype_of(msg: Any) -> str:
    """``pkg/msg/Name`` of a message: rosbags' ``__msgtype__``, or from an rclpy message's
    class (module ``pkg.msg._name``)."""
    name = getattr(msg, "__msgtype__", None)
    if isinstance(name, str):
        return name
    cls = type(msg)
    pkg = cls.__module__.split(".")[0]
    return f"{pkg}/msg/{cls.__name__}"


def stamp_ns(stamp: Any) -> int:
    """A builtin_interfaces/Time as integer nanoseconds."""
    return int(stamp.sec) * 1_000_000_000 + int(stamp.nanosec)


def time_fields(ns: int) -> dict:
    """``sec`` and ``nanosec`` of a builtin_interfaces/Time for ``ns`` nanoseconds."""
    sec, nanosec = divmod(int(ns), 1_000_000_000)
    return {"sec": int(sec), "nanosec": int(nanosec)}


def yaw_from_quaternion(x: float, y: float, z: float, w: float) -> float:
    """Yaw (rotation about z, radians, in [-pi, pi]) of a quaternion; it need not be unit."""
    return math.atan2(2.0 * (w * z + x * y), w * w + x * x - y * y - z * z)


def quaternion_from_yaw(yaw: float) -> tuple[float, float, float, float]:
    """(x, y, z, w) of a rotation by ``yaw`` radians about z."""
    return 0.0, 0.0, math.sin(yaw / 2.0), math.cos(yaw / 2.0)


# --- in ----------------------------------------------------------------------------------


@dataclass(frozen=True, eq=False)
class ConeMap:
    """A cone message as arrays: ``xy`` (N, 2) metres in ``frame_id``, ``classes`` (N,) the
    Formula Student colour class of each cone (``FS_CLASSES``; ``unknown`` for a colourless
    message), ``coloured`` whether the message carries colours at all, ``stamp_ns`` its header
    stamp and ``msgtype`` its type."""

    xy: np.ndarray
    classes: np.ndarray
    frame_id: str
    stamp_ns: int
    msgtype: str
    coloured: bool

    @property
    def colors(self) -> list[str] | None:
        """The solvers' ``colors`` (``package_colour`` of each class), or None for a colourless
        message."""
        return [package_colour(c) for c in self.classes.tolist()] if self.coloured else None


@dataclass(frozen=True)
class StampedPose:
    """A pose message as ``pose`` (x, y metres, yaw radians) in ``frame_id``, at ``stamp_ns``."""

    pose: Pose
    frame_id: str
    stamp_ns: int


def _xy(points) -> list[tuple[float, float]]:
    return [(float(p.x), float(p.y)) for p in points]


def cones_from_msg(msg: Any, msgtype: str | None = None) -> ConeMap:
    """The cones of a message of a type in ``CONE_TYPES`` (``msgtype`` names it; by default
    ``msgtype_of``). eufs_msgs' arrays are read in their field order (blue, yellow, orange, big
    orange, unknown), each cone with its class; a PoseArray's positions and a PolygonStamped's
    points have no colour. ``UnsupportedMessage`` for any other type."""
    msgtype = msgtype or msgtype_of(msg)
    coloured = msgtype in (EUFS_CONES, EUFS_CONES_PLAIN)
    if coloured:
        xy: list[tuple[float, float]] = []
        classes: list[str] = []
        for name, fs_class in EUFS_FIELDS:
            items = getattr(msg, name)
            pts = _xy(c.point for c in items) if msgtype == EUFS_CONES else _xy(items)
            xy += pts
            classes += [fs_class] * len(pts)
    elif msgtype == POSE_ARRAY:
        xy = _xy(p.position for p in msg.poses)
        classes = ["unknown"] * len(xy)
    elif msgtype == POLYGON:
        xy = _xy(msg.polygon.points)
        classes = ["unknown"] * len(xy)
    else:
        raise UnsupportedMessage(f"cannot read cones from a {msgtype}; use one of "
                                 f"{', '.join(CONE_TYPES)}")
    arr = np.array(xy, dtype=np.float64).reshape(-1, 2)
    return ConeMap(xy=arr, classes=np.array(classes, dtype=object), frame_id=str(
        msg.header.frame_id), stamp_ns=stamp_ns(msg.header.stamp), msgtype=msgtype,
        coloured=coloured)


def pose_from_msg(msg: Any, msgtype: str | None = None) -> StampedPose:
    """The car's pose of a message of a type in ``POSE_TYPES``: position x, y and the yaw of
    its orientation, in ``header.frame_id`` (for Odometry, the pose of ``child_frame_id``
    there). ``UnsupportedMessage`` for any other type."""
    msgtype = msgtype or msgtype_of(msg)
    if msgtype in (ODOMETRY, POSE_COV):
        p = msg.pose.pose
    elif msgtype == POSE_STAMPED:
        p = msg.pose
    else:
        raise UnsupportedMessage(f"cannot read a pose from a {msgtype}; use one of "
                                 f"{', '.join(POSE_TYPES)}")
    q = p.orientation
    yaw = yaw_from_quaternion(float(q.x), float(q.y), float(q.z), float(q.w))
    pose = Pose(float(p.position.x), float(p.position.y), yaw)
    return StampedPose(pose=pose, frame_id=str(msg.header.frame_id),
                       stamp_ns=stamp_ns(msg.header.stamp))


@dataclass(frozen=True)
class FrameTransform:
    """A fixed transform: the pose of frame ``child`` in frame ``parent`` (``x``, ``y`` metres,
    ``yaw`` radians), as a static tf from ``parent`` to ``child`` would give it."""

    parent: str
    child: str
    x: float = 0.0
    y: float = 0.0
    yaw: float = 0.0

    @classmethod
    def parse(cls, text: str) -> FrameTransform:
        """``"PARENT,CHILD,X,Y,YAW"`` -> ``FrameTransform``; ValueError otherwise."""
        parts = [p.strip() for p in str(text).split(",")]
        if len(parts) != 5 or not parts[0] or not parts[1]:
            raise ValueError(f"expected PARENT,CHILD,X,Y,YAW (frames, metres, radians), got "
                             f"{text!r}")
        try:
            x, y, yaw = (float(v) for v in parts[2:])
        except ValueError as exc:
            raise ValueError(f"X,Y,YAW must be numbers (metres, radians), got {text!r}") from exc
        if not all(math.isfinite(v) for v in (x, y, yaw)):
            raise ValueError(f"X,Y,YAW must be finite, got {text!r}")
        if parts[0] == parts[1]:
            raise ValueError(f"the transform joins {parts[0]!r} to itself")
        return cls(parts[0], parts[1], x, y, yaw)

    def child_to_parent(self, pose: Pose) -> Pose:
        """A pose given in ``child`` as a pose in ``parent``."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return Pose(self.x + c * pose.x - s * pose.y, self.y + s * pose.x + c * pose.y,
                    _wrap(self.yaw + pose.yaw))

    def parent_to_child(self, pose: Pose) -> Pose:
        """A pose given in ``parent`` as a pose in ``child``."""
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        dx, dy = pose.x - self.x, pose.y - self.y
        return Pose(c * dx + s * dy, -s * dx + c * dy, _wrap(pose.yaw - self.yaw))


def _wrap(angle: float) -> float:
    return math.atan2(math.sin(angle), math.cos(angle))


def pose_in_frame(pose: StampedPose, frame_id: str,
                  transform: FrameTransform | None = None) -> Pose:
    """``pose`` in the cones' frame ``frame_id``: itself when the frames are the same (an empty
    frame id is a frame like any other), else through ``transform`` in whichever direction
    joins them. ``FrameMismatch`` naming both frames when none does."""
    if pose.frame_id == frame_id:
        return pose.pose
    if transform is not None:
        if (transform.parent, transform.child) == (frame_id, pose.frame_id):
            return transform.child_to_parent(pose.pose)
        if (transform.parent, transform.child) == (pose.frame_id, frame_id):
            return transform.parent_to_child(pose.pose)
    given = (f"; the transform given joins {transform.parent!r} and {transform.child!r}"
             if transform is not None else "")
    raise FrameMismatch(
        f"the cones are in frame {frame_id!r} and the pose in {pose.frame_id!r}{given}: "
        f"publish both in one frame or give the fixed transform between them "
        f"(PARENT,CHILD,X,Y,YAW, e.g. {frame_id or 'map'},{pose.frame_id or 'odom'},0,0,0)")


# --- message factories --------------------------------------------------------------------


_NUMPY = {"bool": np.bool_, "byte": np.uint8, "char": np.uint8, "uint8": np.uint8,
          "int8": np.int8, "uint16": np.uint16, "int16": np.int16, "uint32": np.uint32,
          "int32": np.int32, "uint64": np.uint64, "int64": np.int64, "float32": np.float32,
          "float64": np.float64}


class RosbagsFactory:
    """Builds messages of a rosbags typestore: ``new(msgtype, **fields)``, every field not
    given at its zero value (rosbags' message classes take every field)."""

    def __init__(self, typestore: Any) -> None:
        self.typestore = typestore
        self._kinds: dict[str, tuple[Any, list]] = {}

    def _default(self, desc) -> Any:
        from rosbags.typesys.base import Nodetype

        kind, rest = desc
        if kind == Nodetype.BASE:
            name = rest[0]
            return "" if name in ("string", "wstring") else (
                False if name == "bool" else _NUMPY.get(name, np.float64)(0).item())
        if kind == Nodetype.NAME:
            return self.new(rest)
        (inner_kind, inner), size = rest
        if inner_kind == Nodetype.BASE and inner[0] in _NUMPY:
            return np.zeros(size if kind == Nodetype.ARRAY else 0, dtype=_NUMPY[inner[0]])
        if kind == Nodetype.ARRAY:
            return [self._default((inner_kind, inner)) for _ in range(size)]
        return []

    def new(self, msgtype: str, **fields) -> Any:
        kind = self._kinds.get(msgtype)
        if kind is None:
            kind = self._kinds[msgtype] = (self.typestore.types[msgtype],
                                           self.typestore.fielddefs[msgtype][1])
        cls, fdefs = kind
        if len(fields) < len(fdefs):
            for name, desc in fdefs:
                if name not in fields:
                    fields[name] = self._default(desc)
        return cls(**fields)


class RclpyFactory:
    """Builds messages of the installed ROS 2 message packages (``pkg.msg.Name``), for the
    live node: ``new(msgtype, **fields)``; fields the installed definition lacks are
    dropped (a distribution without ``Marker.texture``, say)."""

    def __init__(self) -> None:
        self._classes: dict[str, Any] = {}

    def message_class(self, msgtype: str) -> Any:
        if msgtype not in self._classes:
            pkg, _, name = msgtype.split("/")
            self._classes[msgtype] = getattr(importlib.import_module(f"{pkg}.msg"), name)
        return self._classes[msgtype]

    def new(self, msgtype: str, **fields) -> Any:
        cls = self.message_class(msgtype)
        known = cls.get_fields_and_field_types()
        return cls(**{k: v for k, v in fields.items() if k in known})


# --- out ---------------------------------------------------------------------------------


def _header(f, frame_id: str, ns: int) -> Any:
    return f.new("std_msgs/msg/Header", stamp=f.new("builtin_interfaces/msg/Time",
                                                    **time_fields(ns)), frame_id=frame_id)


def _pose(f, x: float, y: float, yaw: float) -> Any:
    qx, qy, qz, qw = quaternion_from_yaw(yaw)
    return f.new("geometry_msgs/msg/Pose",
                 position=f.new("geometry_msgs/msg/Point", x=float(x), y=float(y), z=0.0),
                 orientation=f.new("geometry_msgs/msg/Quaternion", x=qx, y=qy, z=qz, w=qw))


def _path(f, header, xy: np.ndarray, yaw: np.ndarray) -> Any:
    poses = [f.new("geometry_msgs/msg/PoseStamped", header=header, pose=_pose(f, x, y, h))
             for (x, y), h in zip(xy.tolist(), yaw.tolist(), strict=True)]
    return f.new(PATH, header=header, poses=poses)


def _chord_yaw(xy: np.ndarray, closed: bool) -> np.ndarray:
    """Heading of each point of a boundary towards the next (the last: from the one before;
    closed: towards the first)."""
    if xy.shape[0] < 2:
        return np.zeros(xy.shape[0])
    nxt = np.roll(xy, -1, axis=0) if closed else np.vstack([xy[1:], 2 * xy[-1] - xy[-2]])
    d = nxt - xy
    return np.arctan2(d[:, 1], d[:, 0])


#: Marker colours (r, g, b): the FS classes, the centreline and ignored cones.
_RGB = {"blue": (0.1, 0.3, 1.0), "yellow": (1.0, 0.85, 0.0), "orange": (1.0, 0.5, 0.0),
        "big_orange": (0.9, 0.3, 0.0), "unknown": (0.6, 0.6, 0.6), "centerline": (0.1, 0.8, 0.2),
        "ignored": (0.45, 0.45, 0.45), "text": (1.0, 1.0, 1.0)}


def _rgba(f, key: str, a: float = 1.0) -> Any:
    r, g, b = _RGB[key]
    return f.new("std_msgs/msg/ColorRGBA", r=r, g=g, b=b, a=a)


def _point(f, x: float, y: float) -> Any:
    return f.new("geometry_msgs/msg/Point", x=float(x), y=float(y), z=0.0)


def _marker(f, header, ns: str, kind: int, points=(), colors=(), scale=0.1, colour=None,
            text: str = "", at=(0.0, 0.0)) -> Any:
    return f.new(
        "visualization_msgs/msg/Marker", header=header, ns=ns, id=0, type=kind, action=0,
        pose=_pose(f, at[0], at[1], 0.0),
        scale=f.new("geometry_msgs/msg/Vector3", x=scale, y=scale, z=scale),
        color=colour if colour is not None else _rgba(f, "ignored"),
        points=list(points), colors=list(colors), text=text, frame_locked=False)


_LINE_STRIP, _SPHERE_LIST, _TEXT, _DELETEALL = 4, 7, 9, 3


def lane_messages(lane: Lane, cones: ConeMap, pose: Pose | None, factory: Any,
                  spacing_m: float = 0.5) -> dict[str, Any]:
    """The messages of one lane, by output topic suffix (``OUTPUT_TYPES``), all stamped with
    the cone message's stamp and frame: ``centerline`` (``lane.path(spacing_m)``: a pose every
    ``spacing_m`` metres, oriented along the heading), ``left`` and ``right`` (the boundary
    cones in order from the car, oriented to the next cone; a closed lane's first cone is not
    repeated) and ``markers``: first a DELETEALL, then the boundaries as line strips (closed
    when the lane is), the centreline, the chosen cones (``chosen``, coloured by side), the
    ignored ones (``ignored``) and a ``status`` text at the car. A lane that was not found
    gives empty paths and markers of all cones as ignored with the status."""
    f = factory
    header = _header(f, cones.frame_id, cones.stamp_ns)
    empty = np.zeros((0, 2))
    if lane.ok:
        path = lane.path(spacing_m)
        centre = _path(f, header, path.xy, path.heading)
        left = _path(f, header, lane.left_xy, _chord_yaw(lane.left_xy, lane.closed))
        right = _path(f, header, lane.right_xy, _chord_yaw(lane.right_xy, lane.closed))
    else:
        path = None
        centre = left = right = _path(f, header, empty, np.zeros(0))
    markers = [f.new("visualization_msgs/msg/Marker", header=header, ns="", id=0, type=0,
                     action=_DELETEALL)]
    used = np.zeros(cones.xy.shape[0], dtype=bool)
    if lane.ok:
        for ns, idx, key in (("left", lane.left, "blue"), ("right", lane.right, "yellow")):
            ring = np.concatenate([idx, idx[:1]]) if lane.closed and idx.size > 2 else idx
            markers.append(_marker(f, header, ns, _LINE_STRIP, scale=0.12,
                                   points=[_point(f, *p) for p in cones.xy[ring].tolist()],
                                   colour=_rgba(f, key)))
            used[idx] = True
        xy = path.xy if not path.closed or len(path) < 3 else np.vstack([path.xy, path.xy[:1]])
        markers.append(_marker(f, header, "centerline", _LINE_STRIP, scale=0.06,
                               points=[_point(f, *p) for p in xy.tolist()],
                               colour=_rgba(f, "centerline", 0.8)))
        chosen = np.concatenate([lane.left, lane.right])
        keys = ["blue"] * lane.left.size + ["yellow"] * lane.right.size
        markers.append(_marker(f, header, "chosen", _SPHERE_LIST, scale=0.35,
                               points=[_point(f, *p) for p in cones.xy[chosen].tolist()],
                               colors=[_rgba(f, k) for k in keys], colour=_rgba(f, "blue")))
    markers.append(_marker(f, header, "ignored", _SPHERE_LIST, scale=0.2,
                           points=[_point(f, *p) for p in cones.xy[~used].tolist()],
                           colour=_rgba(f, "ignored", 0.7)))
    if lane.ok:
        status = (f"{lane.status.name}: {lane.left.size} left + {lane.right.size} right cones"
                  + (", closed" if lane.closed else ""))
    else:
        status = f"{lane.status.name}: {lane.message}"
    at = (pose.x, pose.y) if pose is not None else (0.0, 0.0)
    markers.append(_marker(f, header, "status", _TEXT, scale=0.6, text=status, at=at,
                           colour=_rgba(f, "text")))
    return {"centerline": centre, "left": left, "right": right,
            "markers": f.new(MARKERS, markers=markers)}


def cones_to_msg(xy, classes, frame_id: str, ns: int, factory: Any,
                 msgtype: str = EUFS_CONES, covariance: float = 0.0) -> Any:
    """A cone message of ``msgtype`` (``CONE_TYPES``) for cones ``xy`` ((N, 2) metres) of
    Formula Student classes ``classes`` ((N,), ``FS_CLASSES``; a colourless type ignores them),
    stamped ``ns`` in ``frame_id``; eufs_msgs' covariance is ``covariance`` on the diagonal.
    For simulations and tests: ``cones_from_msg`` inverts it, cones grouped by class."""
    f = factory
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    classes = np.asarray(classes, dtype=object).reshape(-1)
    if classes.shape[0] != xy.shape[0]:
        raise ValueError(f"one class per cone: {xy.shape[0]} cones, {classes.shape[0]} classes")
    bad = set(classes.tolist()) - set(FS_CLASSES)
    if bad:
        raise ValueError(f"unknown cone classes {sorted(bad)}; use {', '.join(FS_CLASSES)}")
    header = _header(f, frame_id, ns)
    if msgtype in (EUFS_CONES, EUFS_CONES_PLAIN):
        fields = {}
        cov = np.array([covariance, 0.0, 0.0, covariance])
        for name, fs_class in EUFS_FIELDS:
            pts = [_point(f, *p) for p in xy[classes == fs_class].tolist()]
            fields[name] = (pts if msgtype == EUFS_CONES_PLAIN else [
                f.new("eufs_msgs/msg/ConeWithCovariance", point=p, covariance=cov.copy())
                for p in pts])
        return f.new(msgtype, header=header, **fields)
    if msgtype == POSE_ARRAY:
        return f.new(POSE_ARRAY, header=header,
                     poses=[_pose(f, x, y, 0.0) for x, y in xy.tolist()])
    if msgtype == POLYGON:
        pts = [f.new("geometry_msgs/msg/Point32", x=x, y=y, z=0.0) for x, y in xy.tolist()]
        return f.new(POLYGON, header=header, polygon=f.new("geometry_msgs/msg/Polygon",
                                                           points=pts))
    raise UnsupportedMessage(f"cannot write cones as a {msgtype}; use one of "
                             f"{', '.join(CONE_TYPES)}")


def pose_to_msg(pose: Pose, frame_id: str, ns: int, factory: Any, msgtype: str = ODOMETRY,
                child_frame_id: str = "base_link") -> Any:
    """A pose message of ``msgtype`` (``POSE_TYPES``) for ``pose`` in ``frame_id``, stamped
    ``ns``; ``pose_from_msg`` inverts it. For simulations and tests."""
    f = factory
    header = _header(f, frame_id, ns)
    p = _pose(f, pose.x, pose.y, pose.yaw)
    if msgtype == POSE_STAMPED:
        return f.new(msgtype, header=header, pose=p)
    if msgtype in (ODOMETRY, POSE_COV):
        with_cov = f.new("geometry_msgs/msg/PoseWithCovariance", pose=p)
        extra = {"child_frame_id": child_frame_id} if msgtype == ODOMETRY else {}
        return f.new(msgtype, header=header, pose=with_cov, **extra)
    raise UnsupportedMessage(f"cannot write a pose as a {msgtype}; use one of "
                             f"{', '.join(POSE_TYPES)}")


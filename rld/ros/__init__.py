"""ROS 2 without a ROS installation: message conversion, bag replay and a live node.

- ``rld.ros.convert``: cone maps (eufs_msgs/ConeArrayWithCovariance and ConeArray,
  geometry_msgs/PoseArray, geometry_msgs/PolygonStamped) and poses (nav_msgs/Odometry,
  geometry_msgs/PoseStamped, PoseWithCovarianceStamped) to arrays; frames checked; the lane to
  nav_msgs/Path (centreline and boundaries) and visualization_msgs/MarkerArray.
- ``rld.ros.core``: ``LaneProcessor``, the logic the replay and the node share.
- ``rld.ros.replay``: ``replay``, behind ``rld replay``; ``rld.ros.bag`` reads and writes bags.
- ``rld.ros.node``: the live rclpy node (``python -m rld.ros.node``), imported only when used.
- ``rld.ros.sample``: a generated lap written as a bag.

The bag libraries (rosbags, mcap) come with ``pip install 'rld-lanes[ros]'`` and are imported
only when a bag is read or written; rclpy only by the node. docs/ros.md tells how to use it.
"""

from rld.ros.convert import (
    CONE_TYPES,
    FS_CLASSES,
    OUTPUT_TYPES,
    POSE_TYPES,
    ConeMap,
    FrameMismatch,
    FrameTransform,
    StampedPose,
    UnsupportedMessage,
    cones_from_msg,
    lane_messages,
    package_colour,
    pose_from_msg,
    pose_in_frame,
)
from rld.ros.core import LaneProcessor, ReplayStats

__all__ = [
    "CONE_TYPES", "POSE_TYPES", "OUTPUT_TYPES", "FS_CLASSES", "ConeMap", "StampedPose",
    "FrameTransform", "FrameMismatch", "UnsupportedMessage", "cones_from_msg", "pose_from_msg",
    "pose_in_frame", "package_colour", "lane_messages", "LaneProcessor", "ReplayStats",
]

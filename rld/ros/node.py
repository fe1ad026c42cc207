"""The live ROS 2 node: subscribes to the cone map and the car's pose, publishes the lane.

    python -m rld.ros.node --ros-args -p method:=clc -p cones_topic:=/slam/map \\
        -p pose_topic:=/odometry/filtered -p lane.max_cone_spacing_m:=6.0

Its callbacks run the same ``LaneProcessor`` as ``rld replay`` (``rld.ros.core``), building
rclpy messages of the installed message packages (``RclpyFactory``); rclpy and the message
packages are imported only here, when the node is made, so ``rld`` and ``rld.ros`` install and
import without ROS. The cone type's package (eufs_msgs for the default) must be built in the
ROS workspace the node runs in.

Parameters (``NODE_PARAMETERS``, set with ``-p NAME:=VALUE`` or a parameter file): ``method``,
``backend`` (empty: the method's default), ``time_limit_s`` (0: the method's budget),
``cones_topic`` and ``cones_type``, ``pose_topic`` and ``pose_type``, ``out_ns`` (the lane
topics: OUT_NS/centerline, /left, /right, /markers), ``spacing_m``, ``transform``
(``PARENT,CHILD,X,Y,YAW``, empty: the pose and the cones in one frame), ``qos_depth``, and
``lane.NAME`` for every ``LaneParams`` field (its default is the package's).
"""

from __future__ import annotations

import dataclasses
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from rld.api import DEFAULT_METHOD, METHODS
from rld.ros.convert import (
    CONE_TYPES,
    OUTPUT_TYPES,
    POSE_TYPES,
    FrameMismatch,
    FrameTransform,
    RclpyFactory,
)
from rld.ros.core import LaneProcessor
from rld.types import LaneParams

__all__ = ["NODE_PARAMETERS", "NodeConfig", "node_config", "LaneNodeLogic", "make_node", "main"]

#: The node's own parameters and their defaults; ``lane.NAME`` adds every LaneParams field.
NODE_PARAMETERS: dict[str, Any] = {
    "method": DEFAULT_METHOD,
    "backend": "",
    "time_limit_s": 0.0,
    "cones_topic": "/cones",
    "cones_type": CONE_TYPES[0],
    "pose_topic": "/odometry",
    "pose_type": POSE_TYPES[0],
    "out_ns": "/rld",
    "spacing_m": 0.5,
    "transform": "",
    "qos_depth": 10,
}


def all_parameters() -> dict[str, Any]:
    """``NODE_PARAMETERS`` and ``lane.NAME`` with each LaneParams field's default."""
    out = dict(NODE_PARAMETERS)
    defaults = LaneParams()
    for f in dataclasses.fields(LaneParams):
        out[f"lane.{f.name}"] = getattr(defaults, f.name)
    return out


@dataclass(frozen=True)
class NodeConfig:
    """The node's checked parameters."""

    method: str
    backend: str | None
    time_limit_s: float | None
    cones_topic: str
    cones_type: str
    pose_topic: str
    pose_type: str
    topics: dict[str, str]
    spacing_m: float
    transform: FrameTransform | None
    qos_depth: int
    params: LaneParams


def node_config(get: Callable[[str], Any]) -> NodeConfig:
    """Check the parameters read by ``get(name)``; ValueError naming the one that is wrong."""
    from rld.ros.replay import output_topics

    method = str(get("method"))
    if method not in METHODS:
        raise ValueError(f"parameter method: unknown method {method!r}; available: "
                         f"{', '.join(sorted(METHODS))}")
    cones_type, pose_type = str(get("cones_type")), str(get("pose_type"))
    if cones_type not in CONE_TYPES:
        raise ValueError(f"parameter cones_type: {cones_type!r} is not one of "
                         f"{', '.join(CONE_TYPES)}")
    if pose_type not in POSE_TYPES:
        raise ValueError(f"parameter pose_type: {pose_type!r} is not one of "
                         f"{', '.join(POSE_TYPES)}")
    limit = float(get("time_limit_s"))
    if limit < 0:
        raise ValueError(f"parameter time_limit_s must be >= 0 seconds (0: the method's "
                         f"budget), got {limit}")
    text = str(get("transform")).strip()
    try:
        transform = FrameTransform.parse(text) if text else None
    except ValueError as exc:
        raise ValueError(f"parameter transform: {exc}") from exc
    try:
        topics = output_topics(str(get("out_ns")))
    except ValueError as exc:
        raise ValueError(f"parameter out_ns: {exc}") from exc
    defaults = LaneParams()
    overrides = {f.name: get(f"lane.{f.name}") for f in dataclasses.fields(LaneParams)}
    overrides = {k: v for k, v in overrides.items() if v != getattr(defaults, k)}
    try:
        params = LaneParams.from_overrides(overrides)
    except ValueError as exc:
        raise ValueError(f"parameter lane.*: {exc}") from exc
    depth = int(get("qos_depth"))
    if depth < 1:
        raise ValueError(f"parameter qos_depth must be at least 1, got {depth}")
    spacing = float(get("spacing_m"))
    if not spacing > 0:
        raise ValueError(f"parameter spacing_m must be > 0 metres, got {spacing}")
    return NodeConfig(method=method, backend=str(get("backend")) or None,
                      time_limit_s=limit or None, cones_topic=str(get("cones_topic")),
                      cones_type=cones_type, pose_topic=str(get("pose_topic")),
                      pose_type=pose_type, topics=topics, spacing_m=spacing,
                      transform=transform, qos_depth=depth, params=params)


class LaneNodeLogic:
    """What the node does, without rclpy: ``on_pose`` and ``on_cones`` are its subscription
    callbacks; ``publish(topic, msg)`` sends; ``logger`` has ``info``, ``warning`` and
    ``error``. A frame mismatch is logged as an error once per pair of frames (and counted)."""

    def __init__(self, config: NodeConfig, publish: Callable[[str, Any], None], logger: Any,
                 factory: Any = None) -> None:
        self.config = config
        self.publish = publish
        self.logger = logger
        self.processor = LaneProcessor(
            factory or RclpyFactory(), method=config.method, params=config.params,
            backend=config.backend, spacing_m=config.spacing_m,
            time_limit_s=config.time_limit_s, transform=config.transform,
            log=logger.warning)
        self._mismatches: set[str] = set()

    @property
    def stats(self):
        return self.processor.stats

    def on_pose(self, msg: Any) -> None:
        self.processor.on_pose(msg, self.config.pose_type)

    def on_cones(self, msg: Any) -> None:
        try:
            out = self.processor.on_cones(msg, self.config.cones_type)
        except FrameMismatch as exc:
            if str(exc) not in self._mismatches:
                self._mismatches.add(str(exc))
                self.logger.error(f"{exc} (parameter transform)")
            return
        for suffix, message in out.messages.items():
            self.publish(self.config.topics[suffix], message)

    def summary(self) -> str:
        return self.processor.stats.summary()


def make_node(node_name: str = "rld_lane", **kwargs) -> Any:
    """The node (an ``rclpy.node.Node``) with its parameters declared, its publishers and its
    subscriptions; ``rclpy.init`` must have run. ValueError for a bad parameter."""
    from rclpy.node import Node

    factory = RclpyFactory()
    node = Node(node_name, **kwargs)
    for name, default in all_parameters().items():
        node.declare_parameter(name, default)
    try:
        config = node_config(lambda name: node.get_parameter(name).value)
    except ValueError:
        node.destroy_node()
        raise
    pubs = {topic: node.create_publisher(factory.message_class(OUTPUT_TYPES[suffix]), topic,
                                         config.qos_depth)
            for suffix, topic in config.topics.items()}
    logic = LaneNodeLogic(config, lambda topic, msg: pubs[topic].publish(msg),
                          node.get_logger(), factory)
    node.create_subscription(factory.message_class(config.pose_type), config.pose_topic,
                             logic.on_pose, config.qos_depth)
    node.create_subscription(factory.message_class(config.cones_type), config.cones_topic,
                             logic.on_cones, config.qos_depth)
    node.rld_logic = logic
    node.get_logger().info(
        f"rld {config.method}: lanes of {config.cones_topic} ({config.cones_type}) ahead of "
        f"{config.pose_topic} ({config.pose_type}) on {', '.join(config.topics.values())}")
    return node


def main(args: list[str] | None = None) -> None:
    """``python -m rld.ros.node [--ros-args ...]``: spin the node until interrupted, then log
    its summary."""
    import sys

    import rclpy

    try:
        from rclpy.executors import ExternalShutdownException
    except ImportError:  # pragma: no cover - older rclpy
        ExternalShutdownException = KeyboardInterrupt  # noqa: N806
    rclpy.init(args=args)
    node = None
    try:
        node = make_node()
        rclpy.spin(node)
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    except ValueError as exc:
        print(f"rld node: {exc}", file=sys.stderr)
        sys.exit(2)
    finally:
        if node is not None:
            node.get_logger().info("rld summary:\n" + node.rld_logic.summary())
            node.destroy_node()
        if rclpy.ok():
            rclpy.shutdown()


if __name__ == "__main__":  # pragma: no cover
    main()

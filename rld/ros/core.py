"""The logic the replay and the live node share: ``LaneProcessor`` keeps the latest pose, runs
one ``LaneSolver`` at every cone map and builds the output messages; ``ReplayStats`` counts
what happened (maps, lanes found and not found, skipped messages by reason, latency).

A map message is skipped (logged, counted, no output) when it holds no cones, comes before
any pose, holds fewer than ``MIN_CONES`` cones, is of a type ``rld.ros.convert`` does not read,
cannot be decoded, or the solver refuses it (``ValueError``: a NaN coordinate, say). A pose
message is skipped when it cannot be read or is not finite. A valid map in which the solver
finds no lane is not skipped: its empty lane is published and counted by status.
"""

from __future__ import annotations

import math
import time
from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from rld.api import DEFAULT_METHOD, LaneSolver
from rld.ros.convert import (
    ConeMap,
    FrameMismatch,
    FrameTransform,
    StampedPose,
    UnsupportedMessage,
    cones_from_msg,
    lane_messages,
    pose_from_msg,
    pose_in_frame,
)
from rld.types import MIN_CONES, Lane, LaneParams, Pose

__all__ = ["LaneProcessor", "Outcome", "ReplayStats", "SKIP_REASONS", "LOG_FIRST"]

SKIP_NO_CONES = "map with no cones"
SKIP_NO_POSE = "map before any pose"
SKIP_FEW_CONES = f"map with fewer than {MIN_CONES} cones"
SKIP_MAP_TYPE = "unsupported map message type"
SKIP_MAP_DECODE = "undecodable map message"
SKIP_INVALID = "map the solver refuses"
SKIP_FRAME = "frame mismatch"
SKIP_POSE_TYPE = "unsupported pose message type"
SKIP_POSE_DECODE = "undecodable pose message"
SKIP_BAD_POSE = "non-finite pose"
SKIP_TRUNCATED = "truncated bag"
#: Every reason a message is skipped for.
SKIP_REASONS = (SKIP_NO_CONES, SKIP_NO_POSE, SKIP_FEW_CONES, SKIP_MAP_TYPE, SKIP_MAP_DECODE,
                SKIP_INVALID, SKIP_FRAME, SKIP_POSE_TYPE, SKIP_POSE_DECODE, SKIP_BAD_POSE,
                SKIP_TRUNCATED)
#: Skips logged per reason; later ones are only counted.
LOG_FIRST = 5


@dataclass
class ReplayStats:
    """What a replay or a node saw: map and pose messages, lanes found, lanes not found by
    status, skipped messages by reason and the latency of every solved map (seconds: from the
    raw or received message to the output messages built)."""

    maps: int = 0
    poses: int = 0
    found: int = 0
    not_found: Counter = field(default_factory=Counter)
    skipped: Counter = field(default_factory=Counter)
    latencies_s: list[float] = field(default_factory=list)
    solve_s: list[float] = field(default_factory=list)
    """The solver's own time of every solved map (``lane.stats["solve_time_s"]``), seconds."""

    @property
    def lanes(self) -> int:
        """Maps solved: lanes found and not found (each was published)."""
        return self.found + sum(self.not_found.values())

    def latency_ms(self, solve_only: bool = False) -> dict[str, float] | None:
        """Median, 95th percentile and maximum latency in milliseconds (None before any); with
        ``solve_only``, of the solver's own time."""
        values = self.solve_s if solve_only else self.latencies_s
        if not values:
            return None
        a = 1000.0 * np.asarray(values)
        return {"median": float(np.median(a)), "p95": float(np.percentile(a, 95)),
                "max": float(a.max())}

    def to_dict(self) -> dict:
        return {"maps": self.maps, "poses": self.poses, "lanes": self.lanes,
                "found": self.found, "not_found": dict(self.not_found),
                "skipped": dict(self.skipped), "latency_ms": self.latency_ms(),
                "solve_ms": self.latency_ms(solve_only=True)}

    def summary(self) -> str:
        """The counts as aligned lines, as ``rld replay`` prints them."""
        nf = ", ".join(f"{n} {s}" for s, n in sorted(self.not_found.items())) or "none"
        sk = sum(self.skipped.values())
        lines = [f"messages    {self.maps} maps, {self.poses} poses",
                 f"lanes       {self.found} found, not found: {nf}",
                 f"skipped     {sk}" + (": " + ", ".join(
                     f"{n} {r}" for r, n in sorted(self.skipped.items())) if sk else "")]
        for name, lat, what in (("latency", self.latency_ms(), "per map: decode, solve, messages"),
                                ("solve", self.latency_ms(True), "the solver alone")):
            lines.append(f"{name:<12}" + (
                f"median {lat['median']:.2f} ms, p95 {lat['p95']:.2f} ms, max {lat['max']:.2f} "
                f"ms ({what})" if lat else "none: no map solved"))
        return "\n".join(lines)


@dataclass(frozen=True, eq=False)
class Outcome:
    """One map message's result: the ``lane`` and its output ``messages`` by topic suffix, or
    the ``skipped`` reason; the ``cones`` and the car ``pose`` (in the cones' frame) when they
    were read; ``latency_s`` for a solved map."""

    lane: Lane | None = None
    messages: dict[str, Any] = field(default_factory=dict)
    skipped: str | None = None
    cones: ConeMap | None = None
    pose: Pose | None = None
    latency_s: float | None = None


class LaneProcessor:
    """Pose and cone messages in, lane messages out: the one implementation behind
    ``rld replay`` and the node (``rld.ros.node``).

    ``method``, ``params``, ``backend``, ``time_limit_s``: the ``LaneSolver`` and its budget.
    ``spacing_m``: the centreline's spacing (``Lane.path``), metres. ``transform``: a
    ``FrameTransform`` when the pose and the cones are in different frames. ``factory`` builds
    the output messages (``rld.ros.convert.RosbagsFactory`` or ``RclpyFactory``). ``log``
    receives a line for each of the first ``LOG_FIRST`` skips of each reason."""

    def __init__(self, factory: Any, method: str = DEFAULT_METHOD,
                 params: LaneParams | None = None, backend: str | None = None,
                 spacing_m: float = 0.5, time_limit_s: float | None = None,
                 transform: FrameTransform | None = None,
                 log: Callable[[str], None] | None = None) -> None:
        from rld.path import check_spacing

        self.solver = LaneSolver(method=method, params=params, backend=backend)
        self.spacing_m = check_spacing(spacing_m)
        if time_limit_s is not None and not (time_limit_s > 0):
            raise ValueError(f"time_limit_s must be positive, got {time_limit_s}")
        self.time_limit_s = time_limit_s
        self.transform = transform
        self.factory = factory
        self.log = log or (lambda line: None)
        self.pose: StampedPose | None = None
        self.stats = ReplayStats()

    def skip(self, reason: str, detail: str = "") -> Outcome:
        """Count (and for the first few, log) a skipped message."""
        self.stats.skipped[reason] += 1
        n = self.stats.skipped[reason]
        if n <= LOG_FIRST:
            more = " (further ones are counted, not logged)" if n == LOG_FIRST else ""
            self.log(f"skipped: {reason}" + (f": {detail}" if detail else "") + more)
        return Outcome(skipped=reason)

    def on_pose(self, msg: Any, msgtype: str | None = None, where: str = "") -> str | None:
        """Take a pose message as the latest pose; the skip reason when it is not one."""
        self.stats.poses += 1
        try:
            pose = pose_from_msg(msg, msgtype)
        except UnsupportedMessage as exc:
            return self.skip(SKIP_POSE_TYPE, f"{where}{exc}").skipped
        except (AttributeError, TypeError, ValueError) as exc:
            return self.skip(SKIP_POSE_DECODE, f"{where}{exc}").skipped
        if not all(math.isfinite(v) for v in (pose.pose.x, pose.pose.y, pose.pose.yaw)):
            return self.skip(SKIP_BAD_POSE, f"{where}{pose.pose}").skipped
        self.pose = pose
        return None

    def on_cones(self, msg: Any, msgtype: str | None = None, where: str = "",
                 started: float | None = None) -> Outcome:
        """Solve the lane in a cone message ahead of the latest pose and build its messages.
        ``started``: the ``time.perf_counter()`` the latency counts from (default: now).
        ``FrameMismatch`` (counted) when the pose cannot be brought into the cones' frame."""
        t0 = time.perf_counter() if started is None else started
        self.stats.maps += 1
        try:
            cones = cones_from_msg(msg, msgtype)
        except UnsupportedMessage as exc:
            return self.skip(SKIP_MAP_TYPE, f"{where}{exc}")
        except (AttributeError, TypeError, ValueError) as exc:
            return self.skip(SKIP_MAP_DECODE, f"{where}{exc}")
        n = cones.xy.shape[0]
        if n == 0:
            return self.skip(SKIP_NO_CONES, where.rstrip(": "))
        if self.pose is None:
            return self.skip(SKIP_NO_POSE, where.rstrip(": "))
        if n < MIN_CONES:
            return self.skip(SKIP_FEW_CONES, f"{where}{n} cones")
        try:
            pose = pose_in_frame(self.pose, cones.frame_id, self.transform)
        except FrameMismatch:
            self.stats.skipped[SKIP_FRAME] += 1  # counted; the caller reports it
            raise
        try:
            lane = self.solver.solve(cones.xy, pose, colors=cones.colors,
                                     time_limit_s=self.time_limit_s)
        except ValueError as exc:
            return self.skip(SKIP_INVALID, f"{where}{exc}")
        messages = lane_messages(lane, cones, pose, self.factory, self.spacing_m)
        latency = time.perf_counter() - t0
        self.stats.latencies_s.append(latency)
        self.stats.solve_s.append(float(lane.stats.get("solve_time_s", math.nan)))
        if lane.ok:
            self.stats.found += 1
        else:
            self.stats.not_found[lane.status.name] += 1
        return Outcome(lane=lane, messages=messages, cones=cones, pose=pose, latency_s=latency)

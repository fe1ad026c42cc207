"""``rld replay``: a recorded drive through one ``LaneSolver``, the lanes written to a new MCAP.

``replay`` reads the cone topic and the pose topic of a bag (``rld.ros.bag.BagReader``) in
log-time order; at every map message it solves the lane ahead of the latest pose logged at or
before it (on a tie of log times the pose counts first), through the same ``LaneProcessor`` as
the live node. The output MCAP holds the two input topics as recorded and, at each solved map's
log time and stamped with its header, the lane topics under ``out_ns`` (``OUTPUT_TYPES``:
``centerline``, ``left``, ``right``, ``markers``). Skipped messages, lanes not found and a
truncated bag are counted in ``ReplayResult.stats``; a frame mismatch stops the replay
(``FrameMismatch``), as it would stop every map.
"""

from __future__ import annotations

import itertools
import os
import re
import time
from collections.abc import Callable
from dataclasses import dataclass, field
from pathlib import Path

from rld.api import DEFAULT_METHOD
from rld.ros.bag import BagError, BagReader, BagWriter
from rld.ros.convert import (
    CONE_TYPES,
    OUTPUT_TYPES,
    POSE_TYPES,
    ConeMap,
    FrameTransform,
    RosbagsFactory,
)
from rld.ros.core import (
    SKIP_MAP_DECODE,
    SKIP_MAP_TYPE,
    SKIP_POSE_DECODE,
    SKIP_POSE_TYPE,
    SKIP_TRUNCATED,
    LaneProcessor,
    ReplayStats,
)
from rld.ros.typestore import default_typestore
from rld.types import Lane, LaneParams, Pose

__all__ = ["replay", "ReplayResult", "ReplayFrame", "output_topics", "check_namespace"]

_NAME = re.compile(r"^(/[A-Za-z_][A-Za-z0-9_]*)+$|^/$")


def check_namespace(ns: str) -> str:
    """``ns`` as an absolute ROS namespace without a trailing slash; ValueError otherwise."""
    ns = str(ns)
    if not _NAME.match(ns):
        raise ValueError(f"the output namespace must be an absolute ROS name such as /rld, "
                         f"got {ns!r}")
    return ns.rstrip("/")


def output_topics(out_ns: str = "/rld") -> dict[str, str]:
    """The output topic of each suffix of ``OUTPUT_TYPES`` under ``out_ns``."""
    ns = check_namespace(out_ns)
    return {suffix: f"{ns}/{suffix}" for suffix in OUTPUT_TYPES}


@dataclass(frozen=True, eq=False)
class ReplayFrame:
    """One map message of the replay: its log time, the car pose used (the cones' frame), the
    lane (None when skipped) and the skip reason."""

    log_time_ns: int
    pose: Pose | None
    lane: Lane | None
    skipped: str | None


@dataclass
class ReplayResult:
    """A replay's counts (``stats``), its map messages in order (``frames``), why the bag ended
    early (``problem``, or None), the output file and the messages written to it."""

    stats: ReplayStats
    frames: list[ReplayFrame] = field(default_factory=list)
    problem: str | None = None
    out_path: Path | None = None
    written: int = 0
    topics: dict[str, str] = field(default_factory=dict)
    last_cones: ConeMap | None = None
    """The last map solved, for a picture."""


def replay(in_path: str | os.PathLike, out_path: str | os.PathLike, cones_topic: str,
           pose_topic: str, method: str = DEFAULT_METHOD, params: LaneParams | None = None,
           backend: str | None = None, spacing_m: float = 0.5,
           time_limit_s: float | None = None, transform: FrameTransform | None = None,
           out_ns: str = "/rld", progress: bool = False,
           log: Callable[[str], None] | None = None) -> ReplayResult:
    """Replay the bag at ``in_path`` (a rosbag2 folder or a bare ``.mcap``/``.db3`` file) into
    the MCAP ``out_path`` (see the module docstring). ``method``, ``params``, ``backend``,
    ``time_limit_s``, ``spacing_m`` (metres) and ``transform``: as for ``LaneProcessor``.
    ``progress`` shows a progress bar on stderr when it is a terminal; ``log`` gets a line per
    logged skip and for a truncated bag. ``BagError`` for a bag that cannot be read or lacks a
    topic, ``FrameMismatch`` when the pose cannot be brought into the cones' frame; the output
    is then not written."""
    from tqdm import tqdm

    topics = output_topics(out_ns)
    if cones_topic == pose_topic:
        raise ValueError(f"the cone and the pose topic are both {cones_topic!r}")
    store = default_typestore()
    processor = LaneProcessor(RosbagsFactory(store), method=method, params=params,
                              backend=backend, spacing_m=spacing_m, time_limit_s=time_limit_s,
                              transform=transform, log=log)
    stats = processor.stats
    result = ReplayResult(stats=stats, topics=topics)
    with BagReader(in_path, {cones_topic, pose_topic}) as reader:
        have = {c.topic for c in reader.connections}
        for name, topic in (("cone", cones_topic), ("pose", pose_topic)):
            if topic not in have:
                raise BagError(f"{in_path}: no {name} topic {topic!r}; its topics: "
                               f"{', '.join(sorted(have)) or 'none'}")
        if reader.salvaged and log is not None:
            log(f"{in_path}: {reader.problem}; salvaging what it holds")
        with BagWriter(out_path) as writer, tqdm(total=reader.total, unit="msg",
                                                 desc="replay", disable=None if progress else True,
                                                 leave=False) as bar:
            t_first: int | None = None
            uncopied: set = set()
            for t, group in itertools.groupby(reader.messages(), key=lambda m: m.log_time_ns):
                # Poses first at a tie of log times: "the latest pose at or before the map".
                batch = sorted(group, key=lambda m: m.connection.topic != pose_topic)
                t_first = t if t_first is None else t_first
                where = f"at {(t - t_first) / 1e9:.3f} s: "
                for m in batch:
                    c = m.connection
                    out = _copy_connection(writer, c, uncopied, log)
                    if out is not None:
                        writer.write_raw(out, t, m.raw)
                    bar.update(1)
                    if c.topic == pose_topic:
                        _pose(processor, m, where)
                    else:
                        frame, cones = _map(processor, m, where, writer, topics, t)
                        result.frames.append(frame)
                        if cones is not None:
                            result.last_cones = cones
            if reader.problem:
                processor.skip(SKIP_TRUNCATED, f"{in_path}: {reader.problem}")
        result.problem = reader.problem
    result.out_path = Path(out_path)
    result.written = writer.count
    return result


def _copy_connection(writer: BagWriter, c, uncopied: set, log) -> object | None:
    """The output connection that copies input connection ``c``, or None (logged once) when
    its type has no definition to record: no definition in the bag, and none we know."""
    if c in uncopied:
        return None
    try:
        return writer.connection(c.topic, c.msgtype, c.msgdef, c.digest, c.typestore())
    except Exception as exc:  # noqa: BLE001 - a type nobody defines: not copied, still read
        uncopied.add(c)
        if log is not None:
            log(f"{c.topic} ({c.msgtype}) is not copied to the output: its type has no "
                f"definition in the bag or in rld ({type(exc).__name__}: {exc})")
        return None


def _pose(processor: LaneProcessor, m, where: str) -> None:
    c = m.connection
    if c.msgtype not in POSE_TYPES:
        processor.stats.poses += 1
        processor.skip(SKIP_POSE_TYPE, f"{where}{c.topic} carries {c.msgtype}")
        return
    try:
        msg = c.typestore().deserialize_cdr(m.raw, c.msgtype)
    except Exception as exc:  # noqa: BLE001 - any decoding failure is a skipped message
        processor.stats.poses += 1
        processor.skip(SKIP_POSE_DECODE, f"{where}{type(exc).__name__}: {exc}")
        return
    processor.on_pose(msg, c.msgtype, where=where)


def _map(processor: LaneProcessor, m, where: str, writer: BagWriter, topics: dict[str, str],
         t: int) -> tuple[ReplayFrame, ConeMap | None]:
    c = m.connection
    started = time.perf_counter()
    pose = processor.pose.pose if processor.pose is not None else None
    if c.msgtype not in CONE_TYPES:
        processor.stats.maps += 1
        processor.skip(SKIP_MAP_TYPE, f"{where}{c.topic} carries {c.msgtype}")
        return ReplayFrame(t, pose, None, SKIP_MAP_TYPE), None
    try:
        msg = c.typestore().deserialize_cdr(m.raw, c.msgtype)
    except Exception as exc:  # noqa: BLE001 - any decoding failure is a skipped message
        processor.stats.maps += 1
        processor.skip(SKIP_MAP_DECODE, f"{where}{type(exc).__name__}: {exc}")
        return ReplayFrame(t, pose, None, SKIP_MAP_DECODE), None
    out = processor.on_cones(msg, c.msgtype, where=where, started=started)
    for suffix, message in out.messages.items():
        writer.write(topics[suffix], message, t, OUTPUT_TYPES[suffix])
    return ReplayFrame(t, out.pose or pose, out.lane, out.skipped), out.cones

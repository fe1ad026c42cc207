"""A recorded drive without a car: a generated lap (``rld.generator``, ``rld.simulation``)
written as a ROS 2 bag, the cone map on one topic and the car's pose on another, as a team's
SLAM would publish them. For trying ``rld replay`` and for the tests.

``python -m rld.ros.sample lap.mcap [--seed 7] [--every 1]`` writes one; ``lap_maps`` gives the
maps as arrays in message order (what a ``LaneSolver`` is to get) and ``write_lap_bag`` writes
them. The true left boundary's cones are blue and the right's yellow, a share of the real
cones is unknown-coloured (unclassified), and the false positives get a seeded mix of classes.
"""

from __future__ import annotations

import os
from collections.abc import Iterable
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from rld.ros.convert import (
    EUFS_CONES,
    FS_CLASSES,
    ODOMETRY,
    RosbagsFactory,
    cones_to_msg,
    pose_to_msg,
)
from rld.types import Pose

__all__ = ["SampleMap", "lap_maps", "write_lap_bag", "START_NS", "POSE_LEAD_NS"]

#: The log time of a sample bag's first map: 2024-01-01 00:00:00 UTC, in nanoseconds.
START_NS = 1_704_067_200 * 1_000_000_000
#: How long before each map its pose is logged, nanoseconds.
POSE_LEAD_NS = 20_000_000


@dataclass(frozen=True, eq=False)
class SampleMap:
    """One map update of a sample lap: its log time (ns), the cones (N, 2) metres and their
    Formula Student classes (N,) in message order (grouped by class), the car's pose, and the
    lap's pose index."""

    log_time_ns: int
    cones: np.ndarray
    classes: np.ndarray
    pose: Pose
    index: int


def lap_maps(seed: int = 7, every: int = 1, range_m: float = 30.0, fp_rate: float = 0.2,
             unknown_rate: float = 0.1, period_s: float = 0.1) -> list[SampleMap]:
    """The map updates of a generated lap (track ``seed``; ``range_m`` metres of perception,
    ``fp_rate`` false positives, as ``rld.simulation``): every ``every``-th pose, one every
    ``period_s`` seconds of log time; ``unknown_rate`` of the real cones unclassified."""
    from rld.generator import generate_track
    from rld.simulation import simulate_lap

    if every < 1:
        raise ValueError(f"every must be at least 1, got {every}")
    track = generate_track(seed)
    lap = simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed)
    rng = np.random.default_rng([seed, 43])
    n_real = track.cones.shape[0]
    real = np.full(n_real, "unknown", dtype=object)
    real[track.left] = "blue"
    real[track.right] = "yellow"
    real[rng.random(n_real) < unknown_rate] = "unknown"
    false = rng.choice(np.array(["unknown", "orange", "big_orange", "blue", "yellow"],
                                dtype=object),
                       p=[0.6, 0.15, 0.05, 0.1, 0.1], size=lap.false_positives.shape[0])
    out = []
    for j, k in enumerate(range(0, len(lap), every)):
        f = lap.frame(k)
        classes = np.where(f.source >= 0, real[np.maximum(f.source, 0)],
                           false[np.maximum(-1 - f.source, 0)]) if f.source.size else real[:0]
        order = np.concatenate([np.flatnonzero(classes == c) for c in FS_CLASSES]).astype(int)
        out.append(SampleMap(START_NS + int(round(j * period_s * 1e9)), f.cones[order],
                             classes[order], f.pose, k))
    return out


def write_lap_bag(path: str | os.PathLike, maps: Iterable[SampleMap], cones_topic: str = "/cones",
                  pose_topic: str = "/odometry", frame_id: str = "map",
                  cones_type: str = EUFS_CONES, pose_type: str = ODOMETRY,
                  storage: str = "mcap") -> Path:
    """Write ``maps`` as a bag at ``path`` (``rld.ros.bag.BagWriter``: a bare ``.mcap`` or
    ``.db3`` file, else a bag folder of ``storage``): each map's pose on ``pose_topic``
    ``POSE_LEAD_NS`` before it, its cones on ``cones_topic``, both in ``frame_id`` and stamped
    with their log time."""
    from rld.ros.bag import BagWriter
    from rld.ros.typestore import default_typestore

    factory = RosbagsFactory(default_typestore())
    with BagWriter(path, storage=storage) as writer:
        for m in maps:
            t_pose = m.log_time_ns - POSE_LEAD_NS
            writer.write(pose_topic, pose_to_msg(m.pose, frame_id, t_pose, factory, pose_type),
                         t_pose, pose_type)
            writer.write(cones_topic, cones_to_msg(m.cones, m.classes, frame_id,
                                                   m.log_time_ns, factory, cones_type),
                         m.log_time_ns, cones_type)
    return Path(path)


def main(argv: list[str] | None = None) -> None:
    """``python -m rld.ros.sample OUT [--seed N] [--every K] ...``."""
    import click

    @click.command()
    @click.argument("out", metavar="OUT")
    @click.option("--seed", default=7, show_default=True, type=click.IntRange(min=0),
                  help="Seed of the generated track, its false positives and colours.")
    @click.option("--every", default=1, show_default=True, type=click.IntRange(min=1),
                  help="Every k-th pose of the lap (poses lie 1 m apart), a count.")
    @click.option("--range-m", default=30.0, show_default=True,
                  type=click.FloatRange(0, min_open=True), help="Perception range, metres.")
    @click.option("--fp-rate", default=0.2, show_default=True,
                  type=click.FloatRange(0, 1, max_open=True),
                  help="False-positive rate: the share of the map's cones that are false.")
    @click.option("--storage", type=click.Choice(["mcap", "sqlite3"]), default="mcap",
                  show_default=True, help="Storage of a bag folder (OUT without a suffix).")
    def cli(out: str, seed: int, every: int, range_m: float, fp_rate: float,
            storage: str) -> None:
        """Write a generated lap as a ROS 2 bag: OUT.mcap, OUT.db3 or a bag folder OUT, with
        eufs_msgs/ConeArrayWithCovariance on /cones and nav_msgs/Odometry on /odometry."""
        maps = lap_maps(seed=seed, every=every, range_m=range_m, fp_rate=fp_rate)
        try:
            write_lap_bag(out, maps, storage=storage)
        except (OSError, ValueError) as exc:
            raise click.ClickException(str(exc)) from exc
        click.echo(f"wrote {out}: {len(maps)} maps on /cones, poses on /odometry")

    cli.main(args=argv, prog_name="python -m rld.ros.sample")


if __name__ == "__main__":  # pragma: no cover
    main()

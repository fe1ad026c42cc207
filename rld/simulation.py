"""The evaluation protocol's simulation (DESIGN.md, after CLC section VIII-B).

Along one lap of a track with annotated boundaries:

1. poses every ``step_m`` (1 m) along the ground-truth centreline, heading along its tangent;
2. a perception field: the half-disc of radius ``range_m`` ahead of the car;
3. the partial map at pose k: every cone that was inside the field at any pose 0..k (the SLAM
   map growing during the first lap), unlabelled real cones included;
4. false positives at rate r: a persistent, seeded set of round(r / (1 - r) * real cones) points,
   uniform over the union of the fields along the lap; each joins the map once it has been in
   the field;
5. the ground-truth lane at pose k: per side, the labelled cones from the one nearest the car
   (not behind it) forward, up to the first cone not yet in the map;
6. the method sees the partial map shuffled (seeded per pose), without labels.

Colour perception (issue 41; off unless ``color_accuracy`` is given): one class per point for
the whole lap (``rld.colors`` codes): each real labelled cone reports unknown with probability
``color_unknown``, else its true class (left boundary blue, right yellow) with probability
``color_accuracy`` and the other side's class otherwise; unlabelled real cones and false
positives report blue, yellow or unknown at random. Seeded from the lap's seed on a stream of
its own, so the false positives are the same draw with and without colours.

``fp_clearance_m`` (0 in the protocol) is an analysis knob, not part of the protocol: false
positives are then drawn only at least that far from both true boundary lines
(``Track.boundary_distance``), the same number of them. Sweeping it says how much of a method's
failures come from false positives near the true boundaries (``rld bench fp-clearance``).
"""

from __future__ import annotations

from collections.abc import Iterator
from dataclasses import dataclass

import numpy as np

from rld.tracks import Track
from rld.types import Pose

__all__ = ["Frame", "Lap", "simulate_lap", "in_field"]


def in_field(points: np.ndarray, xy: np.ndarray, heading: np.ndarray, range_m: float) -> np.ndarray:
    """Points inside the half-disc of radius ``range_m`` ahead of the car: (P,) for one pose, or
    (K, P) for (K, 2) positions and headings."""
    xy = np.atleast_2d(xy)
    heading = np.atleast_2d(heading)
    d = points[None, :, :] - xy[:, None, :]
    ahead = np.einsum("kpi,ki->kp", d, heading) >= 0.0
    near = np.einsum("kpi,kpi->kp", d, d) <= range_m**2
    out = ahead & near
    return out[0] if out.shape[0] == 1 else out


@dataclass(frozen=True, eq=False)
class Frame:
    """What a method sees at one pose, and the truth to score it against.

    ``cones`` (M, 2) is the partial map, shuffled. ``source`` (M,) tells, for each frame cone,
    its index in the track's cones, or ``-1 - k`` for false positive k. ``gt_left`` and
    ``gt_right`` are the ground-truth lane as frame indices; ``left_seq`` and ``right_seq`` are
    the track's whole boundaries as frame indices (-1 where a cone is not yet in the map), for
    metrics that need the boundary order beyond the visible lane.
    """

    index: int
    pose: Pose
    cones: np.ndarray
    source: np.ndarray
    gt_left: np.ndarray
    gt_right: np.ndarray
    left_seq: np.ndarray
    right_seq: np.ndarray
    closed: bool
    colors: np.ndarray | None = None
    """Each frame cone's perceived class code (``rld.colors``), or None without colour."""

    @property
    def is_false_positive(self) -> np.ndarray:
        return self.source < 0

    @property
    def gt_closed(self) -> bool:
        """The ground-truth lane is the whole loop on both sides."""
        return bool(
            self.closed
            and self.gt_left.size == self.left_seq.size
            and self.gt_right.size == self.right_seq.size
        )


class Lap:
    """One simulated lap (see the module docstring); iterate it for its ``Frame``\\ s."""

    def __init__(
        self,
        track: Track,
        range_m: float = 50.0,
        fp_rate: float = 0.0,
        seed: int = 0,
        step_m: float = 1.0,
        fp_clearance_m: float = 0.0,
        color_accuracy: float | None = None,
        color_unknown: float = 0.0,
    ) -> None:
        if not 0.0 <= fp_rate < 1.0:
            raise ValueError(f"fp_rate must be in [0, 1), got {fp_rate}")
        if not range_m > 0 or not np.isfinite(range_m):
            raise ValueError(f"range_m must be a positive number, got {range_m}")
        if not (np.isfinite(fp_clearance_m) and fp_clearance_m >= 0):
            raise ValueError(f"fp_clearance_m must be a number >= 0, got {fp_clearance_m}")
        self.track = track
        self.fp_clearance_m = float(fp_clearance_m)
        self.range_m = float(range_m)
        self.fp_rate = float(fp_rate)
        self.seed = int(seed)
        self.centerline = track.centerline(step_m)
        c = self.centerline
        if track.closed:
            tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
        else:
            tangent = np.gradient(c, axis=0)
        self.yaw = np.arctan2(tangent[:, 1], tangent[:, 0])
        self.headings = np.column_stack([np.cos(self.yaw), np.sin(self.yaw)])
        n_real = track.cones.shape[0]
        rng = np.random.default_rng(self.seed)
        self.false_positives = self._sample_false_positives(
            int(round(fp_rate / (1.0 - fp_rate) * n_real)), rng
        )
        self.all_points = np.vstack([track.cones, self.false_positives])
        seen = in_field(self.all_points, c, self.headings, self.range_m)  # (K, P)
        first = np.where(seen.any(axis=0), seen.argmax(axis=0), np.iinfo(np.int64).max)
        self.first_seen = first.astype(np.int64)
        self.color_accuracy = color_accuracy
        self.color_unknown = float(color_unknown)
        self.point_colors = (None if color_accuracy is None
                             else self._perceive_colors(float(color_accuracy), self.color_unknown))

    def _perceive_colors(self, accuracy: float, unknown: float) -> np.ndarray:
        """One class code per point of ``all_points`` (the module docstring's colour model)."""
        from rld.colors import CLASSES

        for name, v in (("color_accuracy", accuracy), ("color_unknown", unknown)):
            if not (np.isfinite(v) and 0.0 <= v <= 1.0):
                raise ValueError(f"{name} must be a probability in [0, 1], got {v}")
        blue, yellow, unk = (CLASSES.index(c) for c in ("blue", "yellow", "unknown"))
        rng = np.random.default_rng([self.seed, 41])
        n = self.all_points.shape[0]
        out = rng.choice(np.array([blue, yellow, unk]), size=n)  # unlabelled and false positives
        for side, true, other in ((self.track.left, blue, yellow),
                                  (self.track.right, yellow, blue)):
            u, v = rng.random(side.size), rng.random(side.size)
            out[side] = np.where(u < unknown, unk, np.where(v < accuracy, true, other))
        return out.astype(np.int64)

    def _sample_false_positives(self, count: int, rng: np.random.Generator) -> np.ndarray:
        if count == 0:
            return np.zeros((0, 2))
        lo = self.centerline.min(axis=0) - self.range_m
        hi = self.centerline.max(axis=0) + self.range_m
        out: list[np.ndarray] = []
        have = 0
        empty = 0  # draws in a row that kept nothing: a clearance that leaves no room
        while have < count:
            cand = rng.uniform(lo, hi, size=(max(4 * count, 256), 2))
            ok = in_field(cand, self.centerline, self.headings, self.range_m).any(axis=0)
            if self.fp_clearance_m > 0:
                ok[ok] = self.track.boundary_distance(cand[ok]) >= self.fp_clearance_m
            out.append(cand[ok])
            have += int(ok.sum())
            empty = 0 if ok.any() else empty + 1
            if empty >= 100:
                raise ValueError(f"no room for false positives {self.fp_clearance_m:g} m from "
                                 "the boundaries within the perception field")
        return np.vstack(out)[:count]

    def __len__(self) -> int:
        return self.centerline.shape[0]

    def __iter__(self) -> Iterator[Frame]:
        for k in range(len(self)):
            yield self.frame(k)

    def pose(self, k: int) -> Pose:
        return Pose(float(self.centerline[k, 0]), float(self.centerline[k, 1]), float(self.yaw[k]))

    def _gt_side(self, side: np.ndarray, in_map: np.ndarray, pose: Pose) -> np.ndarray:
        """Ground-truth boundary (track indices) at this pose (protocol step 5)."""
        if side.size == 0:
            return side
        xy = self.track.cones[side]
        d = xy - pose.xy
        ok = in_map[side] & (d @ pose.heading >= 0.0)
        if not ok.any():
            return side[:0]
        dist = np.where(ok, np.hypot(d[:, 0], d[:, 1]), np.inf)
        start = int(np.argmin(dist))
        n = side.size
        out = []
        for step in range(n if self.track.closed else n - start):
            k = (start + step) % n
            if not in_map[side[k]]:
                break
            out.append(side[k])
        return np.array(out, dtype=np.int64)

    def frame(self, k: int) -> Frame:
        """The frame at pose ``k``."""
        pose = self.pose(k)
        in_map = self.first_seen <= k
        n_real = self.track.cones.shape[0]
        gt_l = self._gt_side(self.track.left, in_map[:n_real], pose)
        gt_r = self._gt_side(self.track.right, in_map[:n_real], pose)
        members = np.flatnonzero(in_map)
        rng = np.random.default_rng([self.seed, k])
        members = members[rng.permutation(members.size)]
        to_frame = np.full(self.all_points.shape[0], -1, dtype=np.int64)
        to_frame[members] = np.arange(members.size)
        source = np.where(members < n_real, members, -1 - (members - n_real))
        return Frame(
            index=k,
            pose=pose,
            cones=np.ascontiguousarray(self.all_points[members]),
            source=source,
            gt_left=to_frame[gt_l],
            gt_right=to_frame[gt_r],
            left_seq=to_frame[self.track.left],
            right_seq=to_frame[self.track.right],
            closed=self.track.closed,
            colors=None if self.point_colors is None else self.point_colors[members],
        )


def simulate_lap(
    track: Track, range_m: float = 50.0, fp_rate: float = 0.0, seed: int = 0, step_m: float = 1.0,
    fp_clearance_m: float = 0.0, color_accuracy: float | None = None, color_unknown: float = 0.0,
) -> Lap:
    """Set up the protocol's lap over ``track`` (see ``Lap``; ``fp_clearance_m`` and the colour
    model: the module docstring; no colours unless ``color_accuracy`` is given)."""
    return Lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed, step_m=step_m,
               fp_clearance_m=fp_clearance_m, color_accuracy=color_accuracy,
               color_unknown=color_unknown)

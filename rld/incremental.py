"""Incremental RLD on a growing map (``method="rld-incremental"``).

On the car the map is a SLAM map: cones keep their positions between updates and new ones
appear at the frontier. So the lane found so far is kept, as positions, and each call
re-optimises only its frontier:

1. Match. Every kept lane cone is looked up in the new map (nearest cone within 0.5 m). A pose
   jump (more than 5 m or 45 degrees since the last call), a map with fewer cones than before,
   or a kept cone with no map cone within 0.5 m (it moved or vanished) restarts from scratch.
2. Frontier. The last ``frontier_cones`` cones of each boundary are released; the cone before
   them (the anchor) and the one before that (its predecessor) stay. The frontier program is
   the ordinary RLD program (``rld.program`` through ``rld.solver.RldModel``, the shared
   constraints and costs) over the map cones not in the kept lane, seen from a virtual pose
   between the two anchors heading along the lane: its cone window (the ``max_cones`` nearest
   ahead of that pose), its near endpoints fixed to the two predecessors and the edges
   predecessor-anchor fixed to 1, so the turn limit and the angle cost hold at the junction.
3. Rollback. When the frontier program has no lane, the kept part is cut back two more cones
   per side and the frontier solved again, up to ``max_rollbacks`` times; then the solver
   restarts from scratch (the windowed RLD from the car). It restarts too when the car has
   reached the end of the kept lane (fewer than ``MIN_AHEAD`` cones ahead on a side: the
   frontier could not pass a gap wider than ``max_cone_spacing_m`` in the map).
4. Closing (CLC section IV-E). When both boundaries end within ``max_cone_spacing_m`` of their
   own first cone and the closed lane meets the CLC lane predicates, the lane is closed and
   frozen.

The returned ``Lane`` starts at the boundary cone nearest the car on each side (the one before
it when that one is ahead of the car) and runs forward to the end of the lane (around the loop
when closed). ``lane.stats`` counts ``restarts`` and ``rollbacks`` (over the solver's life),
says ``mode`` (``start``, ``extend``, ``closed``) and reports the frontier program's cones.

Guarantees: between two calls without a counted rollback or restart, the kept lane (everything
but the released frontier) is unchanged, cone for cone; each frontier satisfies every RLD
constraint among its own cones and at the junction. Not guaranteed: constraints between the
frontier and kept cones other than the junction (a frontier edge could cross, or come closer
than the minimum width to, an older part of the lane in a hairpin), and optimality of the whole
lane (each frontier is optimal given the kept part).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from rld.constraints import lane_is_feasible
from rld.solver import MATCH_TOLERANCE_M, RldModel
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["IncrementalRld", "POSE_JUMP_M", "POSE_JUMP_RAD"]

POSE_JUMP_M = 5.0
POSE_JUMP_RAD = math.radians(45.0)
#: Fewer cones than this ahead of the car on a side: the car has reached the lane's end.
MIN_AHEAD = 3


class IncrementalRld:
    """RLD that keeps its lane between calls and re-optimises only the frontier (module
    docstring). ``backend``: as ``RldModel``; ``frontier_cones``: cones per side released and
    re-optimised at each call; ``max_rollbacks``: how often the kept part may be cut back by
    two more cones before a restart."""

    def __init__(self, params: LaneParams, backend: str | None = None, frontier_cones: int = 3,
                 max_rollbacks: int = 3) -> None:
        if frontier_cones < 1 or max_rollbacks < 0:
            raise ValueError("frontier_cones must be >= 1 and max_rollbacks >= 0")
        self.params = params
        self.frontier_cones = int(frontier_cones)
        self.max_rollbacks = int(max_rollbacks)
        self.window = RldModel(params, backend=backend)  # from the car: starts
        self.frontier = RldModel(params, backend=backend)  # from the virtual pose
        self.restarts = 0
        self.rollbacks = 0
        self.reset()

    def reset(self) -> None:
        self.left_xy: np.ndarray | None = None
        self.right_xy: np.ndarray | None = None
        self.closed = False
        self.prev_pose: Pose | None = None
        self.n_map = 0
        self.window.reset()
        self.frontier.reset()

    # -- helpers -------------------------------------------------------------------------

    def _jumped(self, pose: Pose) -> bool:
        if self.prev_pose is None:
            return False
        d = math.hypot(pose.x - self.prev_pose.x, pose.y - self.prev_pose.y)
        dyaw = abs((pose.yaw - self.prev_pose.yaw + math.pi) % (2 * math.pi) - math.pi)
        return d > POSE_JUMP_M or dyaw > POSE_JUMP_RAD

    def _match(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray] | None:
        tree = cKDTree(points)
        out = []
        for xy in (self.left_xy, self.right_xy):
            dist, idx = tree.query(xy, distance_upper_bound=MATCH_TOLERANCE_M)
            if not np.all(np.isfinite(dist)) or np.unique(idx).size != idx.size:
                return None
            out.append(idx.astype(np.int64))
        if np.intersect1d(out[0], out[1]).size:
            return None
        return out[0], out[1]

    def _closable(self, points, L, R) -> bool:
        p = self.params
        if L.size < 4 or R.size < 4:
            return False
        for side in (L, R):
            if np.hypot(*(points[side[-1]] - points[side[0]])) > p.max_cone_spacing_m:
                return False
        return lane_is_feasible(points[L], points[R], p, closed=True)

    def _extend(self, points, L, R, time_limit_s):
        """One frontier solve with ``back`` cones released per side; the new (L, R) or None."""
        for attempt in range(self.max_rollbacks + 1):
            back = self.frontier_cones + 2 * attempt
            kl, kr = L[: max(L.size - back, 0)], R[: max(R.size - back, 0)]
            if kl.size < 2 or kr.size < 2:
                return None, attempt
            ql, al, qr, ar = int(kl[-2]), int(kl[-1]), int(kr[-2]), int(kr[-1])
            # Cones the frontier may use: the map minus the kept lane, plus the junction cones.
            kept = np.union1d(kl[:-2], kr[:-2])
            free = np.setdiff1d(np.arange(points.shape[0]), kept)
            mid = 0.5 * (points[al] + points[ar])
            d = (points[al] - points[ql]) / max(np.hypot(*(points[al] - points[ql])), 1e-9) + \
                (points[ar] - points[qr]) / max(np.hypot(*(points[ar] - points[qr])), 1e-9)
            vpose = Pose(float(mid[0]), float(mid[1]), float(math.atan2(d[1], d[0])))
            loc = {int(v): k for k, v in enumerate(free)}
            lane = self.frontier.solve(
                points[free], vpose, time_limit_s=time_limit_s, start=(loc[ql], loc[qr]),
                fixed_edges=[(loc[ql], loc[al]), (loc[qr], loc[ar])])
            if lane.ok:
                fl, fr = free[lane.left], free[lane.right]
                if fl[0] == ql and fr[0] == qr and fl.size >= 2 and fr.size >= 2 \
                        and fl[1] == al and fr[1] == ar:
                    self._last_frontier = lane.stats
                    return (np.concatenate([kl[:-2], fl]), np.concatenate([kr[:-2], fr])), \
                        attempt
        return None, self.max_rollbacks + 1

    def _start_index(self, points, pose, side) -> int:
        xy = points[side]
        j = int(np.argmin(np.hypot(*(xy - pose.xy).T)))
        if j > 0 and (xy[j] - pose.xy) @ pose.heading > 0:
            j -= 1
        return j

    def _ahead(self, points, pose, side) -> int:
        """Cones of a boundary from the one nearest the car onward (all of them when closed)."""
        return side.size if self.closed else side.size - self._start_index(points, pose, side)

    def _view(self, points, pose, L, R, status, mode, stats) -> Lane:
        """The lane from the car forward (module docstring)."""
        out = []
        for side in (L, R):
            j = self._start_index(points, pose, side)
            out.append(np.r_[side[j:], side[:j]] if self.closed else side[j:])
        stats.update(mode=mode, restarts=self.restarts, rollbacks=self.rollbacks,
                     lane_cones=int(L.size + R.size))
        if out[0].size < 1 or out[1].size < 1:
            return Lane.not_found(points, "the kept lane lies behind the car", stats=stats)
        return Lane(cones=points, left=out[0], right=out[1], status=status,
                    closed=self.closed, message="incremental RLD", stats=stats)

    # -- the call ------------------------------------------------------------------------

    def solve(self, points: np.ndarray, pose: Pose, time_limit_s: float | None = None,
              colors=None, confidence=None) -> Lane:
        stats: dict = {}
        if colors is not None or confidence is not None:
            stats["note"] = "the incremental solver ignores colors and confidence"
        matched = None
        if self.left_xy is not None:
            reason = None
            if self._jumped(pose):
                reason = "pose jump"
            elif points.shape[0] < self.n_map:
                reason = "the map lost cones"
            else:
                matched = self._match(points)
                if matched is None:
                    reason = "a lane cone moved or vanished"
            if reason is not None:
                self.restarts += 1
                stats["restart_reason"] = reason
                self.reset()
        self.prev_pose = pose
        self.n_map = points.shape[0]
        if matched is None:
            lane = self.window.solve(points, pose, time_limit_s=time_limit_s)
            stats.update({k: lane.stats[k] for k in ("n_cones_used", "horizon_m")
                          if k in lane.stats})
            if not lane.ok:
                lane.stats.update(stats, mode="start", restarts=self.restarts,
                                  rollbacks=self.rollbacks)
                return lane
            self.left_xy, self.right_xy = points[lane.left], points[lane.right]
            return self._view(points, pose, lane.left, lane.right, lane.status, "start", stats)
        L, R = matched
        if self.closed:
            return self._view(points, pose, L, R, LaneStatus.FEASIBLE, "closed", stats)
        self._last_frontier = {}
        new, attempts = self._extend(points, L, R, time_limit_s)
        if new is None:
            # No consistent frontier even after the rollbacks: start over from the car.
            self.restarts += 1
            stats["restart_reason"] = "no frontier after rollbacks"
            self.reset()
            self.prev_pose, self.n_map = pose, points.shape[0]
            lane = self.window.solve(points, pose, time_limit_s=time_limit_s)
            if not lane.ok:
                lane.stats.update(stats, mode="start", restarts=self.restarts,
                                  rollbacks=self.rollbacks)
                return lane
            self.left_xy, self.right_xy = points[lane.left], points[lane.right]
            return self._view(points, pose, lane.left, lane.right, lane.status, "start", stats)
        self.rollbacks += attempts
        L, R = new
        if min(self._ahead(points, pose, L), self._ahead(points, pose, R)) < MIN_AHEAD:
            # The car has reached the end of the kept lane (the frontier cannot pass a gap in
            # the map): start over from the car, as the windowed solver would.
            self.restarts += 1
            stats["restart_reason"] = "the car reached the end of the lane"
            self.reset()
            self.prev_pose, self.n_map = pose, points.shape[0]
            lane = self.window.solve(points, pose, time_limit_s=time_limit_s)
            if not lane.ok:
                lane.stats.update(stats, mode="start", restarts=self.restarts,
                                  rollbacks=self.rollbacks)
                return lane
            self.left_xy, self.right_xy = points[lane.left], points[lane.right]
            return self._view(points, pose, lane.left, lane.right, lane.status, "start", stats)
        stats["n_cones_used"] = int(self._last_frontier.get("n_cones_used", 0))
        stats["frontier_status"] = "ok"
        if self._closable(points, L, R):
            self.closed = True
        self.left_xy, self.right_xy = points[L], points[R]
        return self._view(points, pose, L, R, LaneStatus.FEASIBLE,
                          "closed" if self.closed else "extend", stats)

"""Incremental RLD on a growing map (``method="rld-incremental"``): the lane found so far is kept
by position and each call re-optimises only its frontier with the RLD program (match, frontier,
rollback, closing); the steps, what is guaranteed and what is not: docs/incremental.md."""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from rld.constraints import (
    blocked_by_fixed,
    candidate_edges,
    crossing_edge_pairs,
    lane_is_feasible,
    width_conflicts,
)
from rld.costs import REACH_M, lane_cost
from rld.insertion import boundary_edges as _edges
from rld.insertion import extend_ends, insert_cones
from rld.solver import MATCH_TOLERANCE_M, RldModel
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["IncrementalRld", "KeptChain", "pose_jumped", "POSE_JUMP_M", "POSE_JUMP_RAD",
           "KEPT_GROWTH_S"]

#: A pose more than this far (metres) from the last call's is a jump: the lane restarts from
#: scratch. Source: our choice.
POSE_JUMP_M = 5.0
#: A heading change larger than this (radians, 45 degrees) since the last call is a jump too.
#: Source: our choice.
POSE_JUMP_RAD = math.radians(45.0)
#: Fewer cones than this ahead of the car on a side after an extension: the car has nearly
#: reached the lane's end, so the solver restarts from the car. Chosen by measurement:
#: docs/tuning.md#min_ahead.
MIN_AHEAD = 6
#: Why ``IncrementalRld.chain`` stops growing a lane inside one call: the next window would
#: overrun the call's budget, ``LaneParams.max_windows`` windows solved, no consistent
#: frontier after the rollbacks, a step added no cone, the lane closed, or the grown lane fails
#: the shared predicate (``lane_is_feasible`` less w_max, as ``rld.solver`` checks a window's).
CHAIN_STOPS = ("time budget", "window limit", "no frontier", "no growth", "closed",
               "infeasible step")
#: A reused ``rld`` solver's call that re-attaches the last call's chain grows it only while
#: the call has run less than this, seconds (the kept chain carries the rest; 20 Hz).
#: Chosen by measurement: docs/tuning.md#kept_growth_s.
KEPT_GROWTH_S = 0.05
#: A returned lane with a side whose cones all lie nearer the car than this (metres; the
#: geometric rule's 20 m) is short: ``rld`` solves again from a wider window (``RETRY_MAX_CONES``).
#: Chosen by measurement: docs/tuning.md#short_lane_retry.
SHORT_LANE_M = 20.0
#: The car's window of that retry, cones (``max_cones`` is 20). Chosen by measurement:
#: docs/tuning.md#short_lane_retry.
RETRY_MAX_CONES = 30
#: The frontier program's stats an extend call passes on in ``lane.stats["frontier"]``.
FRONTIER_STATS = ("n_cones_used", "n_cols", "n_rows", "solve_time_s", "backend", "objective")


def pose_jumped(pose: Pose, previous: Pose | None) -> bool:
    """Whether ``pose`` lies more than ``POSE_JUMP_M`` or ``POSE_JUMP_RAD`` from ``previous``
    (never when there is none)."""
    if previous is None:
        return False
    d = math.hypot(pose.x - previous.x, pose.y - previous.y)
    dyaw = abs((pose.yaw - previous.yaw + math.pi) % (2 * math.pi) - math.pi)
    return d > POSE_JUMP_M or dyaw > POSE_JUMP_RAD


@dataclass
class KeptChain:
    """The lane a chained ``rld`` call returned, kept for the solver's next call: each side's
    cone positions (metres, from the car on), the map it was found on, the car's pose, and
    whether it closed, every window was proven optimal, and why the chain stopped."""

    left_xy: np.ndarray
    right_xy: np.ndarray
    map_xy: np.ndarray
    pose: Pose
    closed: bool
    optimal: bool
    stop: str


def _unit(v: np.ndarray) -> np.ndarray:
    return v / max(float(np.hypot(v[0], v[1])), 1e-9)


class IncrementalRld:
    """RLD that keeps its lane between calls and re-optimises only the frontier
    (docs/incremental.md). ``backend``: as ``RldModel``; ``frontier_cones``: cones per side
    released and re-optimised at each call; ``max_rollbacks``: how often the kept part may be
    cut back by two more cones before a restart."""

    @staticmethod
    def least_frontier_cones(frontier_cones: int = 3) -> int:
        """The smallest frontier window: the 4 junction cones and room for more free cones
        than the 2 x ``frontier_cones`` released, or the lane cannot grow."""
        return 2 * int(frontier_cones) + 5

    def __init__(self, params: LaneParams, backend: str | None = None, frontier_cones: int = 3,
                 max_rollbacks: int = 3, frontier_max_cones: int | None = None) -> None:
        if frontier_cones < 1 or max_rollbacks < 0:
            raise ValueError("frontier_cones must be >= 1 and max_rollbacks >= 0")
        self.params = params
        self.frontier_cones = int(frontier_cones)
        self.frontier_max_cones = int(params.max_cones if frontier_max_cones is None
                                      else frontier_max_cones)
        least = self.least_frontier_cones(self.frontier_cones)
        if self.frontier_max_cones < least:
            raise ValueError(f"frontier_max_cones must be at least 2 * frontier_cones + 5 = "
                             f"{least}")
        self.max_rollbacks = int(max_rollbacks)
        self.window = RldModel(params, backend=backend)  # from the car: (re)starts
        self.frontier = RldModel(params, backend=backend)  # from the virtual pose
        self.restarts = 0
        self.rollbacks = 0
        self.insertions = 0
        self.prev_map: np.ndarray | None = None  # the last call's map, to tell new cones
        self._colors: np.ndarray | None = None  # this call's side labels (``solve``)
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
        return pose_jumped(pose, self.prev_pose)

    def _match(self, points: np.ndarray, sides=None,
               tree: cKDTree | None = None) -> tuple[np.ndarray, np.ndarray] | None:
        """Each side's cones (positions; default the kept lane's) as indices into ``points``
        (``tree``: its k-d tree, if built), each within ``MATCH_TOLERANCE_M``; ``None`` when
        one is missing or two share a cone."""
        tree = cKDTree(points) if tree is None else tree
        out = []
        for xy in (self.left_xy, self.right_xy) if sides is None else sides:
            dist, idx = tree.query(xy, distance_upper_bound=MATCH_TOLERANCE_M)
            if not np.all(np.isfinite(dist)) or np.unique(idx).size != idx.size:
                return None
            out.append(idx.astype(np.int64))
        if np.intersect1d(out[0], out[1]).size:
            return None
        return out[0], out[1]

    def _extend(self, points, L, R, time_limit_s, deadline=None, keep_junction=False):
        """One frontier solve with ``back`` cones released per side, rolled back as
        docs/incremental.md (step 3) says. Returns ((L, R) or None, rollbacks, closes):
        ``closes`` when both frontier paths ended on their own boundary's first cone.
        ``deadline`` (a ``time.perf_counter()`` value): no attempt starts after it, and each
        solve's budget ends at it. ``keep_junction``: a side too short to release ``back``
        cones keeps its first two (``chain``: the car's window lane may be 4 cones a side)."""
        tried = set()
        for attempt in range(self.max_rollbacks + 1):
            if deadline is not None:
                left_s = deadline - time.perf_counter()
                if left_s <= 0:
                    return None, attempt, False
                time_limit_s = left_s if time_limit_s is None else min(time_limit_s, left_s)
            back = self.frontier_cones + 2 * attempt
            floor = 2 if keep_junction else 0
            kl = L[: max(L.size - back, min(floor, L.size))]
            kr = R[: max(R.size - back, min(floor, R.size))]
            if kl.size < 2 or kr.size < 2 or (kl.size, kr.size) in tried:
                return None, attempt, False
            tried.add((kl.size, kr.size))
            ql, al, qr, ar = int(kl[-2]), int(kl[-1]), int(kr[-2]), int(kr[-1])
            # Cones the frontier may use: the map minus the kept lane, plus the junction cones
            # and, for closing the loop (CLC IV-E), each boundary's first cone.
            kept = np.union1d(kl[:-2], kr[:-2])
            firsts = (int(L[0]), int(R[0])) if kl.size >= 4 and kr.size >= 4 else None
            if firsts is not None:
                kept = np.setdiff1d(kept, firsts)
            free = np.setdiff1d(np.arange(points.shape[0]), kept)
            mid = 0.5 * (points[al] + points[ar])
            dl, dr = _unit(points[al] - points[ql]), _unit(points[ar] - points[qr])
            d = dl + dr
            vpose = Pose(float(mid[0]), float(mid[1]), float(math.atan2(d[1], d[0])))
            released = np.concatenate([L[kl.size:], R[kr.size:]])
            window = self._frontier_window(points, free, (ql, al, dl), (qr, ar, dr),
                                           released)
            lane = self.frontier.solve(
                points, vpose, time_limit_s=time_limit_s, start=(ql, qr),
                fixed_edges=[(ql, al), (qr, ar)], window=window, heading=False,
                fixed_lane=self._kept_edges(points, kl[:-1], kr[:-1], window),
                colors=self._colors)
            if not lane.ok:
                continue
            fl, fr = lane.left, lane.right
            if fl[0] == qr and fr[0] == ql:  # named by the program's pose: ours by the start
                fl, fr = fr, fl
            if not (fl[0] == ql and fr[0] == qr and fl.size >= 2 and fr.size >= 2
                    and fl[1] == al and fr[1] == ar):
                continue
            ends = [False, False]
            if firsts is not None:
                paths = [fl, fr]
                for side in (0, 1):
                    if firsts[1 - side] in paths[side]:  # ran into the other side's start
                        paths = None
                        break
                    hit = np.flatnonzero(paths[side] == firsts[side])
                    if hit.size:  # reached its own start: the boundary ends before it
                        paths[side] = paths[side][: hit[0]]
                        ends[side] = True
                if paths is None:
                    continue
                fl, fr = paths
            newL, newR = np.concatenate([kl[:-2], fl]), np.concatenate([kr[:-2], fr])
            if not self._consistent(points, newL, newR, kl.size - 1, kr.size - 1, ends):
                continue
            self._last_frontier = dict(lane.stats, status=lane.status)
            closes = all(ends) and lane_is_feasible(points[newL], points[newR], self.params,
                                                    closed=True)
            return (newL, newR), attempt, closes
        return None, self.max_rollbacks + 1, False

    def _insert_new_cones(self, points, L, R, prev_map) -> tuple[np.ndarray, np.ndarray, int]:
        """Late insertion: each cone that entered the map since the last call joins a kept
        edge when that lowers the RLD objective (``rld.insertion.insert_cones``, the shared
        rule), so a cone the perception saw late (in a hairpin, say) is not skipped for good
        once the frontier has moved on. Returns (L, R, insertions)."""
        if prev_map is None or prev_map.shape[0] == 0:
            return L, R, 0
        lane = np.union1d(L, R)
        d, _ = cKDTree(prev_map).query(points, distance_upper_bound=MATCH_TOLERANCE_M)
        new = np.setdiff1d(np.flatnonzero(~np.isfinite(d)), lane)
        if new.size == 0:
            return L, R, 0
        (L, R), count = insert_cones(points, (L, R), new, self.params, self.closed,
                                     self._colors)
        return L, R, count

    def _kept_edges(self, points, kl, kr, window) -> np.ndarray:
        """The kept lane's edges (both sides, up to the junctions) that come near the frontier
        window: the frontier may not cross them or pinch the lane against them."""
        e = np.vstack([_edges(kl), _edges(kr)])
        if e.shape[0] == 0:
            return e
        lo, hi = points[window].min(axis=0), points[window].max(axis=0)
        pad = self.params.max_cone_spacing_m + self.params.min_width_m
        a, b = points[e[:, 0]], points[e[:, 1]]
        near = np.all((np.minimum(a, b) <= hi + pad) & (np.maximum(a, b) >= lo - pad), axis=1)
        return e[near]

    def _consistent(self, points, L, R, fl0, fr0, ends) -> bool:
        """The frontier against the whole lane: no frontier edge (from index ``fl0`` / ``fr0``
        of each side on, with the closing edge of a side that reached its start) crosses or
        comes closer than ``min_width_m`` to any other lane edge, by the shared constraint
        families of RLD (eqs 6-8 and the no-crossing rows of section V, ``rld.constraints``),
        which the frontier program itself applies only among its own cones."""
        edges, new = [], []
        for side, f0, closes in ((L, fl0, ends[0]), (R, fr0, ends[1])):
            e = _edges(side, closes)
            edges.append(e)
            new.append(np.arange(e.shape[0]) >= f0)
        edges, new = np.vstack(edges), np.concatenate(new)
        fresh, kept = edges[new], edges[~new]
        w = self.params.min_width_m
        return not (crossing_edge_pairs(points, fresh).shape[0]
                    or width_conflicts(points, fresh, w).shape[0]
                    or blocked_by_fixed(points, fresh, kept, w).any())

    def _frontier_window(self, points, free, left, right, released=()) -> np.ndarray:
        """The frontier program's cones (indices into ``points``): the two junctions
        (predecessor and anchor per side) and the free cones nearest to the anchors along the
        map, ``frontier_max_cones`` in all. Nearest by path length over the candidate edges
        (cone pairs within ``max_cone_spacing_m``, Dijkstra from both anchors), so a window
        follows the lane on from its end instead of filling with another part of the track
        that lies close as the crow flies; a cone more than ``window_behind_m`` behind both
        anchors, along their own sides' last edges, is left out."""
        p = self.params
        junction = np.array([left[0], left[1], right[0], right[1]], dtype=np.int64)
        anchors = np.array([left[1], right[1]], dtype=np.int64)
        # Only cones that a few edges could reach matter: a disc around the anchors.
        reach = p.max_cone_spacing_m * self.frontier_max_cones / 2.0
        near = np.hypot(*(points[free][:, None, :] - points[anchors][None, :, :]).transpose(
            2, 0, 1)).min(axis=1) <= reach
        cand = free[near]
        ahead = np.zeros(cand.size, dtype=bool)
        for _, anchor, direction in (left, right):
            ahead |= (points[cand] - points[anchor]) @ direction >= -p.window_behind_m
        cand = np.union1d(cand[ahead], junction)
        xy = points[cand]
        pairs = candidate_edges(xy, p.max_cone_spacing_m)  # the edges the program may use
        if pairs.size == 0:
            return junction
        w = np.hypot(*(xy[pairs[:, 0]] - xy[pairs[:, 1]]).T)
        graph = coo_matrix((w, (pairs[:, 0], pairs[:, 1])), shape=(cand.size, cand.size))
        # From the anchors and from the released cones (the last frontier, which the new one
        # will usually keep and extend): the window reaches past the lane's current end.
        seeds = np.union1d(anchors, np.intersect1d(np.asarray(released, dtype=np.int64), cand))
        src = np.searchsorted(cand, seeds)
        dist = dijkstra(graph, directed=False, indices=src, min_only=True)
        others = np.flatnonzero(np.isfinite(dist) & ~np.isin(cand, junction))
        order = others[np.lexsort((cand[others], np.round(dist[others], 9)))]
        n = max(int(self.frontier_max_cones) - junction.size, 0)
        return np.union1d(junction, cand[order[:n]])

    def _start_index(self, points, pose, side, closed: bool | None = None) -> int:
        """Where the returned boundary starts: the cone nearest the car, or the next one (at
        most two steps on) while that lies behind the car, the protocol's convention for the
        ground truth (docs/protocol.md, step 5). ``closed``: default the kept lane's."""
        closed = self.closed if closed is None else closed
        xy = points[side]
        j = int(np.argmin(np.hypot(*(xy - pose.xy).T)))
        for _ in range(2):
            if (xy[j] - pose.xy) @ pose.heading >= 0:
                break
            if j + 1 < side.size:
                j += 1
            elif closed:
                j = 0
            else:
                break
        return j

    def _from_car(self, points, pose, sides, closed: bool) -> tuple[np.ndarray, ...]:
        """Each side from its ``_start_index`` on: a closed lane's rolled there, an open one's
        cut there."""
        js = [self._start_index(points, pose, S, closed=closed) for S in sides]
        if closed:
            return tuple(np.roll(S, -j) for S, j in zip(sides, js, strict=True))
        return tuple(S[j:] for S, j in zip(sides, js, strict=True))

    def _ahead(self, points, pose, side) -> int:
        """Cones of a boundary from the one nearest the car onward (all of them when closed)."""
        return side.size if self.closed else side.size - self._start_index(points, pose, side)

    def _view(self, points, pose, L, R, status, mode, stats) -> Lane:
        """The lane from the car forward (docs/incremental.md, the returned lane)."""
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

    # -- chained windows inside one call (method "rld") ---------------------------------

    def reattach(self, points: np.ndarray, pose: Pose, lane: Lane, kept: KeptChain):
        """The car's window lane ``lane`` joined to ``kept``, the chain of the solver's last
        call: each side runs on along its kept side from the last edge the two share (along
        the window's where the kept side ends there), up to its first cone near a cone new or
        gone since then (the windows past the car's saw another map). Returns (L, R, closed, kept
        cones, whether a side was cut), or why not (a string): the pose jumped, a kept cone is
        gone, a side does not join, or the joined lane fails a chain step's checks."""
        if pose_jumped(pose, kept.pose):
            return "pose jump"
        tree = cKDTree(points)
        matched = self._match(points, (kept.left_xy, kept.right_xy), tree)
        if matched is None:
            return "a kept cone is gone"
        if kept.closed:
            on_loop = True  # the window's sides run along the loop: the loop stands
            for W, K in zip((lane.left, lane.right), matched, strict=True):
                pos = {int(c): j for j, c in enumerate(K)}
                js = np.array([pos.get(int(c), -1) for c in W])
                on_loop &= bool(np.all(js >= 0) and np.all(np.diff(js) % K.size == 1))
            matched = self._from_car(points, pose, matched, closed=True)
            if on_loop:
                return matched[0], matched[1], True, int(matched[0].size + matched[1].size), \
                    False
            # Else the loop, opened at the car, is joined as an open chain, which grows on.
        # Cones new since then, and cones gone since then: the map changed there.
        d, _ = cKDTree(kept.map_xy).query(points, distance_upper_bound=MATCH_TOLERANCE_M)
        g, _ = tree.query(kept.map_xy, distance_upper_bound=MATCH_TOLERANCE_M)
        changed = np.vstack([points[~np.isfinite(d)], kept.map_xy[~np.isfinite(g)]])
        near_new = cKDTree(changed) if changed.shape[0] else None
        sides, cut = [], bool(kept.closed)  # an opened loop's end is tried again
        for W, K in zip((lane.left, lane.right), matched, strict=True):
            pos = {int(c): j for j, c in enumerate(K)}
            join = None
            for i in range(W.size - 1, 0, -1):
                j = pos.get(int(W[i]))
                if j is not None and j >= 1 and K[j - 1] == W[i - 1]:
                    join = (i, j)
                    break
            if join is None:
                return "a side does not join"
            i, j = join
            tail = K[j + 1:]
            back = np.flatnonzero(np.isin(tail, W[: i + 1]))  # an opened loop comes back
            tail = tail[: back[0]] if back.size else tail
            if near_new is not None and tail.size:
                dn, _ = near_new.query(points[tail],
                                       distance_upper_bound=self.params.max_cone_spacing_m)
                hit = np.flatnonzero(np.isfinite(dn))
                if hit.size:
                    tail, cut = tail[: hit[0]], True
            # On along the kept side; where that ends first, on along the window's.
            sides.append((np.concatenate([W[: i + 1], tail]) if tail.size else W, i))
        (L, il), (R, ir) = sides
        if (np.unique(L).size != L.size or np.unique(R).size != R.size
                or np.intersect1d(L, R).size):
            return "the joined sides share a cone"
        if not (self._consistent(points, L, R, il, ir, (False, False))
                and lane_is_feasible(points[L], points[R], self.params, max_width=False)):
            return "the joined lane fails the checks"
        return L, R, False, int(L.size - il - 1 + R.size - ir - 1), cut

    def hold(self, points: np.ndarray, pose: Pose, failed: Lane, kept: KeptChain | None,
             colors: np.ndarray | None = None) -> Lane | None:
        """The last call's chain ``kept``, every cone matched on this map and from the car
        forward, for a call whose car window gave no lane (``failed``); ``None`` when the pose
        jumped, a cone is gone, a side keeps fewer than two cones or the lane fails the checks."""
        if kept is None or pose_jumped(pose, kept.pose):
            return None
        matched = self._match(points, (kept.left_xy, kept.right_xy))
        if matched is None:
            return None
        L, R = self._from_car(points, pose, matched, kept.closed)
        if min(L.size, R.size) < 2 or not lane_is_feasible(
                points[L], points[R], self.params, closed=kept.closed, max_width=False):
            return None
        stats = dict(failed.stats, held=failed.message)
        stats["chain"] = {"windows": 0, "steps": 0, "stop": kept.stop, "kept_cones":
                          int(L.size + R.size), "not_kept": None, "cut": False,
                          "added_cones": int(L.size + R.size)}
        return Lane(cones=points, left=L, right=R, status=LaneStatus.FEASIBLE,
                    closed=kept.closed,
                    message=f"the last call's lane, held: the car's window gave none "
                            f"({failed.message})",
                    cost=lane_cost(points, L, R, pose, self.params, closed=kept.closed,
                                   colors=colors),
                    stats=stats)

    @staticmethod
    def keep(points: np.ndarray, pose: Pose, lane: Lane) -> KeptChain | None:
        """What the next call of a reused ``rld`` solver needs of the chained ``lane``."""
        if not lane.ok or "chain" not in lane.stats:
            return None
        return KeptChain(points[lane.left], points[lane.right], np.array(points, dtype=float),
                         pose, bool(lane.closed), lane.status is LaneStatus.OPTIMAL,
                         lane.stats["chain"]["stop"])

    def forward(self, points: np.ndarray, pose: Pose, lane: Lane,
                colors: np.ndarray | None = None) -> Lane:
        """``lane`` from the car forward: each side of an open lane from ``_start_index`` (the
        protocol's convention for the truth, as ``rld-incremental`` returns its lane), its
        cost recomputed; a closed lane, or one a side of which would keep fewer than two
        cones, as it is. ``stats["chain"]["behind"]`` counts the cones dropped."""
        if not lane.ok or lane.closed:
            return lane
        L, R = self._from_car(points, pose, (lane.left, lane.right), closed=False)
        behind = lane.left.size - L.size + lane.right.size - R.size
        if not behind or min(L.size, R.size) < 2:
            return lane
        stats = dict(lane.stats)
        stats["chain"] = dict(stats.get("chain", {}), behind=int(behind))
        return Lane(cones=points, left=L, right=R, status=lane.status, message=lane.message,
                    cost=lane_cost(points, L, R, pose, self.params, colors=colors),
                    stats=stats)

    @staticmethod
    def short(points: np.ndarray, pose: Pose, lane: Lane) -> bool:
        """Whether an open ``lane`` has a side within ``SHORT_LANE_M`` of the car while the map
        holds a cone beyond (no lane: short; a closed lane: not)."""
        far = float(np.hypot(*(points - pose.xy).T).max()) > SHORT_LANE_M
        if not lane.ok:
            return far
        if lane.closed:
            return False
        ends = [float(np.hypot(*(points[s] - pose.xy).T).max()) for s in (lane.left, lane.right)]
        return far and min(ends) < SHORT_LANE_M

    def extend_ends(self, points: np.ndarray, pose: Pose, lane: Lane,
                    colors: np.ndarray | None = None) -> Lane:
        """An open ``lane``'s boundaries extended at their far ends, beyond ``REACH_M``
        from the car, where RLD's objective prefers it (``rld.insertion.extend_ends``), its
        cost recomputed; ``stats["chain"]["extended"]`` counts the cones added."""
        if not lane.ok or lane.closed:
            return lane
        (L, R), n = extend_ends(points, pose, (lane.left, lane.right), self.params,
                                REACH_M, colors)
        if not n:
            return lane
        stats = dict(lane.stats)
        stats["chain"] = dict(stats.get("chain", {}), extended=int(n))
        return Lane(cones=points, left=L, right=R, status=lane.status, message=lane.message,
                    cost=lane_cost(points, L, R, pose, self.params, colors=colors),
                    stats=stats)

    def chain(self, points: np.ndarray, pose: Pose, lane: Lane, t0: float, budget_s: float,
              max_windows: int, colors: np.ndarray | None = None,
              kept: KeptChain | None = None, grow_s: float | None = None) -> Lane:
        """The car's window lane ``lane`` grown by frontier steps (``_extend``) on this map
        until a stop of ``CHAIN_STOPS``; the call began at ``t0`` (``time.perf_counter``) with
        ``budget_s`` seconds. ``kept``: the last call's chain, re-attached first (``reattach``);
        once it is, the chain grows only for the call's first ``grow_s`` seconds. Without it
        the chain is stateless (``solve``'s kept lane is never touched)."""
        L, R = lane.left, lane.right
        self._colors = colors
        deadline = t0 + budget_s
        step_s = time.perf_counter() - t0  # the car's window: the first step estimate
        windows, grown, closed = 1, 0, False
        optimal = lane.status is LaneStatus.OPTIMAL
        attached = self.reattach(points, pose, lane, kept) if kept is not None else None
        why = attached if isinstance(attached, str) else None
        attached = None if why else attached
        n_kept, stop = 0, None
        grow_until = deadline
        if attached is not None:
            if grow_s is not None:
                grow_until = min(deadline, t0 + grow_s)
            L, R, closed, n_kept, cut = attached
            optimal &= kept.optimal
            if closed:
                stop = "closed"
            elif not cut and kept.stop not in ("time budget", "window limit"):
                stop = kept.stop  # the same end on the same map: the same step would stop
        stepped = stop is None
        while stop is None:
            if windows >= max_windows:
                stop = "window limit"
                break
            now = time.perf_counter()
            if now + step_s > grow_until:  # the next step would likely end after the budget
                stop = "time budget"
                break
            self._last_frontier = {}
            new, _, closes = self._extend(points, L, R, None, deadline, keep_junction=True)
            windows += 1
            step_s = max(step_s, time.perf_counter() - now)
            if new is None:
                stop = "time budget" if time.perf_counter() >= deadline else "no frontier"
                break
            if not closes and new[0].size + new[1].size <= L.size + R.size:
                stop = "no growth"
                break
            if not lane_is_feasible(points[new[0]], points[new[1]], self.params,
                                    closed=closes, max_width=False):
                stop = "infeasible step"  # the lane so far stands: rld returns no lane the
                break  # shared predicate rejects
            L, R = new
            grown += 1
            optimal &= self._last_frontier.get("status") is LaneStatus.OPTIMAL
            if closes:
                closed, stop = True, "closed"
                break
        if attached is not None and not grown and stop in ("no growth", "no frontier",
                                                           "infeasible step") and stepped:
            # The kept chain's end does not extend on this map: the chain from the car's
            # window, as a stateless call would find it, when it is longer.
            fresh = self.chain(points, pose, lane, t0, budget_s, max_windows, colors)
            if fresh.left.size + fresh.right.size > L.size + R.size or fresh.closed:
                fresh.stats["chain"]["not_kept"] = "the kept end does not extend"
                return fresh
        stats = dict(lane.stats)
        stats["chain"] = {"windows": windows, "steps": grown, "stop": stop,
                          "kept_cones": n_kept, "not_kept": why,
                          "cut": bool(attached is not None and attached[4]),
                          "added_cones": int(L.size + R.size - lane.left.size
                                             - lane.right.size)}
        if not grown and attached is None:
            return Lane(cones=points, left=L, right=R, status=lane.status,
                        message=lane.message, cost=lane.cost, stats=stats)
        if closed and grown:  # a loop: each side from the car, as rld-incremental returns it
            L, R = self._from_car(points, pose, (L, R), closed=True)
        # OPTIMAL: every window's program proven optimal (not the chained lane as a whole).
        return Lane(cones=points, left=L, right=R,
                    status=LaneStatus.OPTIMAL if optimal else LaneStatus.FEASIBLE,
                    closed=closed, message=lane.message,
                    cost=lane_cost(points, L, R, pose, self.params, closed=closed, colors=colors),
                    stats=stats)

    # -- the call ------------------------------------------------------------------------

    def _start(self, points, pose, time_limit_s, stats, reason=None) -> Lane:
        """Start (or, with a ``reason``, restart) from the car: the windowed RLD."""
        if reason is not None:
            self.restarts += 1
            stats["restart_reason"] = reason
            self.reset()
        self.prev_pose, self.n_map = pose, points.shape[0]
        lane = self.window.solve(points, pose, time_limit_s=time_limit_s, colors=self._colors)
        stats.update({k: lane.stats[k] for k in ("n_cones_used", "horizon_m")
                      if k in lane.stats})
        if not lane.ok:
            lane.stats.update(stats, mode="start", restarts=self.restarts,
                              rollbacks=self.rollbacks)
            return lane
        self.left_xy, self.right_xy = points[lane.left], points[lane.right]
        return self._view(points, pose, lane.left, lane.right, lane.status, "start", stats)

    def solve(self, points: np.ndarray, pose: Pose, time_limit_s: float | None = None,
              colors=None, confidence=None) -> Lane:
        """One map update: ``points`` (N, 2) metres, validated; ``pose`` the car's. The
        budget ``time_limit_s`` bounds each program solve (a call with rollbacks makes up to
        ``max_rollbacks + 2`` of them). ``colors`` (side labels): the colour cost
        (``rld.costs.boundary_color_cost``, weight ``w_color``) in every program and
        insertion."""
        stats: dict = {}
        self._colors = colors
        if confidence is not None:
            stats["note"] = "the incremental solver ignores confidence"
        prev_map, self.prev_map = self.prev_map, np.array(points, dtype=np.float64)
        if self.left_xy is None:
            return self._start(points, pose, time_limit_s, stats)
        if self._jumped(pose):
            return self._start(points, pose, time_limit_s, stats, "pose jump")
        if points.shape[0] < self.n_map:
            return self._start(points, pose, time_limit_s, stats, "the map lost cones")
        matched = self._match(points)
        if matched is None:
            return self._start(points, pose, time_limit_s, stats,
                               "a lane cone moved or vanished")
        self.prev_pose, self.n_map = pose, points.shape[0]
        L, R, inserted = self._insert_new_cones(points, *matched, prev_map)
        if inserted:
            self.insertions += inserted
            self.left_xy, self.right_xy = points[L], points[R]
        stats["insertions"] = self.insertions
        if self.closed:
            stats["n_cones_used"] = 0  # the loop is frozen: no program runs
            return self._view(points, pose, L, R, LaneStatus.FEASIBLE, "closed", stats)
        self._last_frontier = {}
        new, attempts, closes = self._extend(points, L, R, time_limit_s)
        self.rollbacks += min(attempts, self.max_rollbacks)
        if new is None:
            # No consistent frontier even after the rollbacks: start over from the car.
            return self._start(points, pose, time_limit_s, stats, "no frontier after rollbacks")
        L, R = new
        if min(self._ahead(points, pose, L), self._ahead(points, pose, R)) < MIN_AHEAD:
            # The car has nearly reached the end of the lane: the frontier has not kept up (a
            # gap in the map, or a wrong turn it cannot leave): start over from the car.
            return self._start(points, pose, time_limit_s, stats,
                               "the car reached the end of the lane")
        stats["n_cones_used"] = int(self._last_frontier.get("n_cones_used", 0))
        stats["frontier"] = {k: self._last_frontier[k] for k in FRONTIER_STATS
                             if k in self._last_frontier}
        if closes:
            self.closed = True
        self.left_xy, self.right_xy = points[L], points[R]
        return self._view(points, pose, L, R, LaneStatus.FEASIBLE,
                          "closed" if self.closed else "extend", stats)

"""Simple baselines that every method must beat.

``nearest_chain``: the naive greedy of PEERS.md. From the starting cones (CLC IV-C), each
boundary steps to the nearest unused cone ahead (turn below 90 degrees) within the maximum cone
spacing, until none is left. No lane-level constraint is checked: it is the floor.
"""

from __future__ import annotations

import numpy as np

from rld import constraints as cons
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["nearest_chain"]


def _chain(points: np.ndarray, start: int, heading: np.ndarray, adj: list[np.ndarray],
           used: np.ndarray) -> list[int]:
    path = [start]
    used[start] = True
    direction = heading
    while True:
        here = path[-1]
        nbrs = adj[here]
        nbrs = nbrs[~used[nbrs]]
        if nbrs.size == 0:
            break
        step = points[nbrs] - points[here]
        ahead = step @ direction > 0.0
        if not ahead.any():
            break
        nbrs, step = nbrs[ahead], step[ahead]
        k = int(np.argmin(np.hypot(step[:, 0], step[:, 1])))
        nxt = int(nbrs[k])
        path.append(nxt)
        used[nxt] = True
        direction = step[k]
    return path


def nearest_chain(points: np.ndarray, pose: Pose, params: LaneParams) -> Lane:
    """The nearest-neighbour chain baseline on validated ``points`` (see the module docstring).
    Its ``cost`` is the number of cones it took (it optimises nothing)."""
    start = cons.find_starting_vertices(points, pose, params.near_radius_m, params.start_reach_m)
    if start is None:
        return Lane.not_found(
            points,
            f"no cone on each side of the car within near_radius_m = {params.near_radius_m} m",
        )
    edges = cons.candidate_edges(points, params.max_cone_spacing_m)
    adj: list[list[int]] = [[] for _ in range(points.shape[0])]
    for i, j in edges:
        adj[i].append(int(j))
        adj[j].append(int(i))
    adj_arr = [np.array(sorted(a), dtype=np.int64) for a in adj]
    used = np.zeros(points.shape[0], dtype=bool)
    used[list(start)] = True
    left = _chain(points, start[0], pose.heading, adj_arr, used)
    right = _chain(points, start[1], pose.heading, adj_arr, used)
    return Lane(
        cones=points,
        left=np.array(left),
        right=np.array(right),
        status=LaneStatus.FEASIBLE,
        message="nearest-neighbour chain (a baseline: no optimality, no lane constraints)",
        cost=float(len(left) + len(right)),
    )

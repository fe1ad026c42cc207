"""Simple baselines that every method must beat.

``nearest_chain``: the naive greedy of PEERS.md. From the starting cones (CLC IV-C), each
boundary steps to the nearest unused cone ahead (turn below 90 degrees) within the maximum cone
spacing, until none is left. No lane-level constraint is checked: it is the floor. With colours,
a cone whose class names the other side than the chain's counts ``COLOR_PENALTY_M`` farther than
it is: the chain prefers its own side's class and still takes another cone when nothing else is
ahead. The chain's side, as its classes tell it: the side most of its labelled cones so far name,
else the side it starts on (a class that most of a boundary contradicts is taken for the
boundary's: one wrong label does not turn the chain, nor do labels swapped throughout).
"""

from __future__ import annotations

import numpy as np

from rld import constraints as cons
from rld.colors import SIDE_LEFT, SIDE_RIGHT
from rld.costs import color_cost
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["nearest_chain", "COLOR_PENALTY_M"]

#: Metres added to a successor's distance when its class names the other side than the chain's
#: (module docstring). Chosen by measurement: docs/tuning.md#color_penalty_m.
COLOR_PENALTY_M = 1.0


def _chain(points: np.ndarray, start: int, heading: np.ndarray, adj: list[np.ndarray],
           used: np.ndarray, colors: np.ndarray | None = None, side: int = SIDE_LEFT
           ) -> list[int]:
    path = [start]
    used[start] = True
    direction = heading
    votes = {SIDE_LEFT: 0, SIDE_RIGHT: 0}  # the chain's labelled cones, per side they name
    if colors is not None and colors[start] in votes:
        votes[int(colors[start])] += 1
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
        dist = np.hypot(step[:, 0], step[:, 1])
        if colors is not None:
            own = side if votes[SIDE_LEFT] == votes[SIDE_RIGHT] else max(votes, key=votes.get)
            dist = dist + COLOR_PENALTY_M * color_cost(colors[nbrs], own)
        k = int(np.argmin(dist))
        nxt = int(nbrs[k])
        path.append(nxt)
        used[nxt] = True
        if colors is not None and colors[nxt] in votes:
            votes[int(colors[nxt])] += 1
        direction = step[k]
    return path


def nearest_chain(points: np.ndarray, pose: Pose, params: LaneParams,
                  colors: np.ndarray | None = None) -> Lane:
    """The nearest-neighbour chain baseline on validated ``points`` (see the module docstring),
    ``colors`` optional side labels. Its ``cost`` is the number of cones it took (it optimises
    nothing)."""
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
    left = _chain(points, start[0], pose.heading, adj_arr, used, colors, SIDE_LEFT)
    right = _chain(points, start[1], pose.heading, adj_arr, used, colors, SIDE_RIGHT)
    return Lane(
        cones=points,
        left=np.array(left),
        right=np.array(right),
        status=LaneStatus.FEASIBLE,
        message="nearest-neighbour chain (a baseline: no optimality, no lane constraints)",
        cost=float(len(left) + len(right)),
    )

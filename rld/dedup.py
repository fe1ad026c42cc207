"""Duplicate cones: detections closer than ``LaneParams.duplicate_radius_m`` are one cone.

A perception stack or a SLAM map can report one cone twice (two detections that were not
associated, or the same cone from two sensors). Neither method is made for that: RLD's spacing
cost excludes edges shorter than 0.39 m (``LaneParams.max_spacing_cost``), so a doubled cone
takes two places of its 20-cone window and the lane found is about half as long; CLC may
zigzag through both copies. ``LaneSolver.solve`` (``rld.api``) therefore merges duplicates
before any method runs (``merge_duplicates``), solves on the merged cones and maps the lane back
to the caller's indices; ``lane.stats["duplicates_merged"]`` counts the cones merged away.

Groups are the connected components of the "at most ``radius_m`` apart" relation, so a chain of
detections each within the radius of the next is one cone even where its ends lie farther
apart. Each group is represented by its lowest-index member (see ``merge_duplicates``).
"""

from __future__ import annotations

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

__all__ = ["merge_duplicates", "DUPLICATE_RADIUS_M"]

from rld.types import LaneParams

#: ``LaneParams.duplicate_radius_m``'s default (m): the rules' small cone has a 0.228 m base, the
#: dataset's closest distinct cones lie 0.63 m apart (track 6), generated ones 0.99 m (60 seeds).
DUPLICATE_RADIUS_M: float = LaneParams.duplicate_radius_m


def merge_duplicates(
    points: np.ndarray,
    radius_m: float = DUPLICATE_RADIUS_M,
    colors: np.ndarray | None = None,
    confidence: np.ndarray | None = None,
) -> tuple[np.ndarray, np.ndarray, np.ndarray | None, np.ndarray | None]:
    """Merge the cones of ``points`` ((N, 2) metres) that lie at most ``radius_m`` apart.

    Returns ``(kept_points, kept_index, colors, confidence)``:

    - ``kept_index`` (K,) int64, increasing: for each merged cone, the lowest index of its group
      in ``points`` (the caller's array); ``kept_points = points[kept_index]``.
    - Position: the lowest-index member's, not the group's mean. A lane solved on the merged
      cones is then, mapped back through ``kept_index``, a lane of the caller's own cones at
      exactly the positions it was solved on (widths, turns and crossings checked by the
      method hold for the lane returned), and in a growing map, where a later duplicate gets a
      higher index, a cone's position does not move when a duplicate joins it (the warm starts
      and ``rld-incremental`` match kept cones by position). The mean would be a better
      estimate of the cone, but it moves by at most ``radius_m``, well within the 0.5 m
      tolerance of those matches, and is no cone of the caller's.
    - ``colors`` (labels, 0 = unknown; ``None`` in, ``None`` out): a known label beats unknown.
      When members carry different known labels, the one most of them carry wins, and a tie
      gives unknown (0): a cone seen once blue and once yellow is no evidence for either
      side (the methods charge it as unknown, ``LaneParams.color_unknown``). The
      rule does not depend on the members' order.
    - ``confidence`` (``None`` in, ``None`` out): the largest of the members' (a cone detected
      twice is at least as certain as its best detection).

    ``radius_m`` 0 merges only coincident points. Nothing is merged (``kept_index`` is
    ``arange(N)``) when no two points are that close.
    """
    points = np.asarray(points, dtype=np.float64)
    n = points.shape[0]
    if not radius_m >= 0:
        raise ValueError(f"radius_m must be >= 0, got {radius_m}")
    for name, arr in (("colors", colors), ("confidence", confidence)):
        if arr is not None and np.shape(arr) != (n,):
            raise ValueError(f"{name} must have one value per point ({n}), got {np.shape(arr)}")
    pairs = (cKDTree(points).query_pairs(float(radius_m), output_type="ndarray") if n > 1
             else np.zeros((0, 2), dtype=np.int64))
    if pairs.shape[0] == 0:
        keep = np.arange(n, dtype=np.int64)
        return (points.copy(), keep,
                None if colors is None else np.array(colors, copy=True),
                None if confidence is None else np.array(confidence, dtype=np.float64))
    graph = coo_matrix((np.ones(pairs.shape[0]), (pairs[:, 0], pairs[:, 1])), shape=(n, n))
    k, comp = connected_components(graph, directed=False)
    # Each group's lowest member; groups numbered in the order of that member.
    lowest = np.full(k, n, dtype=np.int64)
    np.minimum.at(lowest, comp, np.arange(n, dtype=np.int64))
    order = np.argsort(lowest)
    rank = np.empty(k, dtype=np.int64)
    rank[order] = np.arange(k)
    group = rank[comp]  # (N,) the merged cone each point belongs to
    keep = lowest[order]
    out_colors = None if colors is None else _merge_labels(np.asarray(colors), group, k)
    out_conf = None
    if confidence is not None:
        out_conf = np.full(k, -np.inf)
        np.maximum.at(out_conf, group, np.asarray(confidence, dtype=np.float64))
    return points[keep], keep, out_colors, out_conf


def _merge_labels(labels: np.ndarray, group: np.ndarray, k: int) -> np.ndarray:
    """Per group: the known (non-zero) label most members carry; 0 when none is known or the
    most frequent known labels tie."""
    out = np.zeros(k, dtype=labels.dtype)
    known = labels != 0
    if not known.any():
        return out
    values, code = np.unique(labels[known], return_inverse=True)
    m = values.size
    # One key per (group, label) that occurs; its count is that label's votes in the group.
    key, counts = np.unique(group[known] * m + code.reshape(-1), return_counts=True)
    g, lab = key // m, values[key % m]
    top = np.zeros(k, dtype=np.int64)
    np.maximum.at(top, g, counts)
    best = counts == top[g]
    ties = np.bincount(g[best], minlength=k)
    sole = best & (ties[g] == 1)
    out[g[sole]] = lab[sole]
    return out

"""Every constraint family that RLD and CLC share, written once as pure functions of arrays.

RLD (Brandes et al. 2020) uses them to build its binary program; CLC (Ivanov & Markgraf 2024)
uses the same families as predicates on path pairs. Conventions:

- ``points``: (N, 2) float64 cone positions, metres.
- ``edges``: (E, 2) int64 cone-index pairs with ``i < j``, sorted lexicographically
  (``candidate_edges`` makes them).
- Boundaries: (k, 2) float arrays ordered from the car forward.

Where a paper's inequality is strict, or printed the wrong way round, we state our reading:

- RLD eq. 7 prints ``MinDist > d_min``; a *minimum* width needs ``MinDist < d_min`` (two edges
  closer than the narrowest lane cannot both be boundary edges), as its text says.
- The limits are closed sets everywhere (``|turn| <= phi_max``, ``w_min <= w <= w_max``,
  ``MinDist >= d_min`` allowed), so that RLD's program (which cannot take strict inequalities) and
  CLC's predicates (which the paper prints strict, eqs 13 and 15) accept exactly the same lanes.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.spatial import cKDTree

from rld import geometry as geo
from rld import geometry_kernels as gk
from rld.types import Pose

__all__ = [
    "candidate_edges",
    "edge_lengths",
    "width_conflicts",
    "crossing_edge_pairs",
    "blocked_by_fixed",
    "heading_mask",
    "near_car_mask",
    "start_mask",
    "angle_triples",
    "turn_within_limit",
    "c_seg",
    "first_edges_ahead",
    "c_poly",
    "lane_widths",
    "overlap_widths",
    "c_width",
    "lane_is_feasible",
    "find_starting_vertices",
    "starting_vertex_pairs",
]


def candidate_edges(points: np.ndarray, max_spacing_m: float) -> np.ndarray:
    """Cone pairs that may be consecutive on one boundary: distance <= ``max_spacing_m``
    (CLC eq. 2, the search graph; RLD eq. 35's D <= d_max on edges). Returns (E, 2) int64 with
    ``i < j``, sorted."""
    return geo.pairs_within(points, max_spacing_m)


def edge_lengths(points: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """Length of every edge (RLD D_ij), metres."""
    d = points[edges[:, 1]] - points[edges[:, 0]]
    return np.hypot(d[:, 0], d[:, 1])


def _nearby_edge_pairs(points: np.ndarray, edges: np.ndarray, reach_m: float,
                       other: np.ndarray | None = None) -> np.ndarray:
    """Pairs of edges that share no cone and whose segments may come within ``reach_m`` of
    each other (a superset: midpoints within reach + the longest edge). Without ``other``:
    pairs (e, f), e < f, within ``edges``; with it: pairs (e, f), e into ``edges``, f into
    ``other``. Sorted by (e, f)."""
    if other is None and edges.shape[0] < 2:
        return np.zeros((0, 2), dtype=np.int64)
    if other is not None and (edges.shape[0] == 0 or other.shape[0] == 0):
        return np.zeros((0, 2), dtype=np.int64)
    mid = (points[edges[:, 0]] + points[edges[:, 1]]) / 2
    longest = float(edge_lengths(points, edges).max())
    if other is None:
        pairs = cKDTree(mid).query_pairs(reach_m + longest + 1e-9, output_type="ndarray")
        pairs = np.sort(pairs.astype(np.int64), axis=1)
        b = edges[pairs[:, 1]]
    else:
        omid = (points[other[:, 0]] + points[other[:, 1]]) / 2
        reach = reach_m + (longest + float(edge_lengths(points, other).max())) / 2 + 1e-9
        near = cKDTree(mid).sparse_distance_matrix(cKDTree(omid), reach, output_type="ndarray")
        pairs = np.column_stack([near["i"], near["j"]]).astype(np.int64).reshape(-1, 2)
        b = other[pairs[:, 1]]
    a = edges[pairs[:, 0]]
    disjoint = (
        (a[:, 0] != b[:, 0]) & (a[:, 0] != b[:, 1]) & (a[:, 1] != b[:, 0]) & (a[:, 1] != b[:, 1])
    )
    pairs = pairs[disjoint]
    order = np.lexsort((pairs[:, 1], pairs[:, 0]))
    return np.ascontiguousarray(pairs[order])


def width_conflicts(points: np.ndarray, edges: np.ndarray, min_width_m: float,
                    other: np.ndarray | None = None) -> np.ndarray:
    """Edge pairs that cannot both be in a lane because the lane would be narrower than
    ``min_width_m`` (RLD eqs 6-8).

    A pair (e, f) of edges with four distinct cones conflicts when
    ``MinDist(e, f) < d_min`` and ``End(e, f) = 0`` (our reading of eq. 7, see the module
    docstring): the segments come closer than the narrowest lane somewhere other than
    end to end. Consecutive edges of one boundary are closest end to end and stay allowed.
    Returns (K, 2) int64 edge indices, sorted: pairs ``e < f`` within ``edges``, or, given
    ``other`` (an (F, 2) edge array), pairs of an edge of ``edges`` and one of ``other``.
    """
    pairs = _nearby_edge_pairs(points, edges, min_width_m, other)
    if pairs.shape[0] == 0:
        return pairs
    e, f = edges[pairs[:, 0]], (edges if other is None else other)[pairs[:, 1]]
    d, end = geo.segment_distance_end(points[e[:, 0]], points[e[:, 1]], points[f[:, 0]],
                                      points[f[:, 1]])
    return pairs[(d < min_width_m) & ~end]


def crossing_edge_pairs(points: np.ndarray, edges: np.ndarray,
                        other: np.ndarray | None = None) -> np.ndarray:
    """Edge pairs with four distinct cones whose segments share a point (cross, touch or
    overlap): no lane may hold both (the no-crossing constraint of RLD section V; CLC C_poly
    implies it). Returns (K, 2) int64 edge indices, sorted: pairs ``e < f`` within
    ``edges``, or, given ``other``, pairs of an edge of ``edges`` and one of ``other``."""
    pairs = _nearby_edge_pairs(points, edges, 0.0, other)
    if pairs.shape[0] == 0:
        return pairs
    e, f = edges[pairs[:, 0]], (edges if other is None else other)[pairs[:, 1]]
    hit = geo.segments_intersect(points[e[:, 0]], points[e[:, 1]], points[f[:, 0]],
                                 points[f[:, 1]])
    return pairs[hit]


def blocked_by_fixed(points: np.ndarray, edges: np.ndarray, fixed: np.ndarray,
                     min_width_m: float) -> np.ndarray:
    """Which ``edges`` can no longer be in a lane that already holds the ``fixed`` edges:
    those that cross one of them or come closer than ``min_width_m`` to one (other than end
    to end), by exactly the families of ``crossing_edge_pairs`` and ``width_conflicts`` (RLD
    eqs 6-8 and section V), taken across the two sets. ``edges`` and ``fixed``: (E, 2)
    and (F, 2) int64 indices into ``points``; returns (E,) bool. The incremental solver
    (``rld.incremental``) blocks its frontier's candidate edges against the kept lane so."""
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    fixed = np.asarray(fixed, dtype=np.int64).reshape(-1, 2)
    out = np.zeros(edges.shape[0], dtype=bool)
    if edges.shape[0] == 0 or fixed.shape[0] == 0:
        return out
    edges, fixed = np.sort(edges, axis=1), np.sort(fixed, axis=1)
    out[crossing_edge_pairs(points, edges, fixed)[:, 0]] = True
    out[width_conflicts(points, edges, min_width_m, fixed)[:, 0]] = True
    return out


def heading_mask(
    points: np.ndarray, edges: np.ndarray, pose: Pose, radius_m: float, tolerance_rad: float,
    first: np.ndarray | None = None,
) -> np.ndarray:
    """RLD h (eq. 9): edges whose nearest point is within ``radius_m`` of the car and whose line
    is within ``tolerance_rad`` of the car's heading (undirected: an edge and its reverse
    agree). Boolean (E,). Edges at a cone of ``first`` (indices: a side's first cone farther
    than the near radius, ``start_mask``) count as near whatever their distance (ours)."""
    a, b = points[edges[:, 0]], points[edges[:, 1]]
    near = geo.point_segment_distance(pose.xy, a, b) <= radius_m
    if first is not None and len(first):
        near |= np.isin(edges[:, 0], first) | np.isin(edges[:, 1], first)
    u = b - a
    length = np.hypot(u[:, 0], u[:, 1])
    cos = np.abs(u @ pose.heading) / np.where(length > 0, length, 1.0)
    angle = np.arccos(np.clip(cos, 0.0, 1.0))
    return near & (angle <= tolerance_rad) & (length > 0)


def near_car_mask(points: np.ndarray, pose: Pose, radius_m: float) -> np.ndarray:
    """RLD r (eq. 11): cones within ``radius_m`` of the car, the ones that may start a boundary
    (also CLC's start-vertex search radius, IV-C). Boolean (N,)."""
    d = points - pose.xy
    return np.hypot(d[:, 0], d[:, 1]) <= radius_m


def start_mask(points: np.ndarray, pose: Pose, radius_m: float, reach_m: float) -> np.ndarray:
    """Cones that may start a boundary, boolean (N,): ``near_car_mask``, and for a side (car frame
    y > 0 left, y < 0 right) with no cone there, its nearest cone ahead (x > 0) within ``reach_m``
    metres (ours, a start line: ``LaneParams.start_reach_m``; ``reach_m <= radius_m`` adds none)."""
    near = near_car_mask(points, pose, radius_m)
    if reach_m <= radius_m or points.shape[0] == 0:
        return near
    local = pose.to_local(points)
    dist = np.hypot(local[:, 0], local[:, 1])
    for side in (local[:, 1] > 0, local[:, 1] < 0):
        if (near & side).any():
            continue
        cand = np.flatnonzero(side & (local[:, 0] > 0) & (dist <= reach_m))
        if cand.size:
            near[cand[np.argmin(dist[cand])]] = True
    return near


def angle_triples(points: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Every pair of candidate edges that meet at a cone, as RLD's f variables (eq. 21).

    Returns ``(triples, turns)``: ``triples`` (T, 5) int64 rows ``(i, j, k, e_ij, e_jk)``
    with the shared cone ``j`` in the middle, ``i < k``, and the indices of the two edges; and
    ``turns`` (T,), the signed turn from i->j to j->k in radians (its absolute value is the same
    read in either direction).
    """
    E = edges.shape[0]
    if E < 2:
        return np.zeros((0, 5), dtype=np.int64), np.zeros(0)
    # Incidence: for every (cone, edge, other end) sorted by cone.
    cone = np.concatenate([edges[:, 0], edges[:, 1]])
    other = np.concatenate([edges[:, 1], edges[:, 0]])
    eid = np.concatenate([np.arange(E), np.arange(E)])
    order = np.lexsort((other, cone))
    cone, other, eid = cone[order], other[order], eid[order]
    starts = np.searchsorted(cone, np.arange(points.shape[0]))
    ends = np.searchsorted(cone, np.arange(points.shape[0]), side="right")
    rows = []
    for j in np.flatnonzero(ends - starts >= 2):
        s, t = starts[j], ends[j]
        o, e = other[s:t], eid[s:t]
        ia, ib = np.triu_indices(t - s, k=1)
        rows.append(np.column_stack([o[ia], np.full(ia.size, j), o[ib], e[ia], e[ib]]))
    if not rows:
        return np.zeros((0, 5), dtype=np.int64), np.zeros(0)
    triples = np.ascontiguousarray(np.vstack(rows).astype(np.int64))
    turns = geo.turn_angles(points[triples[:, 0]], points[triples[:, 1]], points[triples[:, 2]])
    return triples, turns


def turn_within_limit(turns: np.ndarray, max_turn_rad: float) -> np.ndarray:
    """``|turn| <= phi_max`` (CLC C_seg, eq. 15; with theta_e = pi the complement of RLD's
    high angle-cost mask t^c, eq. 28)."""
    return np.abs(turns) <= max_turn_rad


def _closed(xy: np.ndarray, closed: bool) -> np.ndarray:
    return np.vstack([xy, xy[:1]]) if closed and xy.shape[0] > 1 else xy


def c_seg(left: np.ndarray, right: np.ndarray, max_turn_rad: float, closed: bool = False) -> bool:
    """CLC C_seg (eq. 15): no turn between consecutive segments of either boundary exceeds
    ``max_turn_rad`` (wrapping around for closed boundaries)."""
    for xy in (left, right):
        turns = geo.polyline_turn_angles(xy, closed=closed and len(xy) >= 3)
        if not np.all(turn_within_limit(turns, max_turn_rad)):
            return False
    return True


def first_edges_ahead(left: np.ndarray, right: np.ndarray, pose: Pose,
                      max_turn_rad: float) -> bool:
    """Each boundary's first edge ((k, 2) metres, from the car) turns at most ``max_turn_rad``
    from the car's heading: C_seg with the heading for the missing segment (ours; CLC's
    candidates, ``clc.search_kernels.enumerate_pairs``). A boundary of one cone passes."""
    h = pose.heading
    for xy in (left, right):
        if len(xy) >= 2:
            dx, dy = float(xy[1][0] - xy[0][0]), float(xy[1][1] - xy[0][1])
            turn = abs(math.atan2(h[0] * dy - h[1] * dx, h[0] * dx + h[1] * dy)) \
                if (dx or dy) else math.pi
            if turn > max_turn_rad:
                return False
    return True


def c_poly(left: np.ndarray, right: np.ndarray, closed: bool = False) -> bool:
    """CLC C_poly (section VI): the lane polygon is simple.

    Open lane: the ring left + reversed right does not touch or cross itself. Closed lane: each
    boundary ring is simple and the two rings share no point.
    """
    left = np.asarray(left, dtype=np.float64)
    right = np.asarray(right, dtype=np.float64)
    if not closed:
        return geo.ring_is_simple(geo.lane_ring(left, right))
    if not (geo.ring_is_simple(left) and geo.ring_is_simple(right)):
        return False
    return not geo.polylines_touch(_closed(left, True), _closed(right, True))


def lane_widths(left: np.ndarray, right: np.ndarray, closed: bool = False) -> np.ndarray:
    """CLC lane width W(L, R) (eqs 8-12): the lengths of all matching lines.

    For each vertex and each segment of one boundary (the query, eq. 8), the nearest point pair
    to the whole other boundary (the target) gives a matching line (eq. 9); both boundaries take
    both roles (eq. 11). Returned in the order: left vertices, left segments, right vertices,
    right segments. Metres.
    """
    L = _closed(np.asarray(left, dtype=np.float64), closed)
    R = _closed(np.asarray(right, dtype=np.float64), closed)
    if L.shape[0] == 0 or R.shape[0] == 0:
        return np.zeros(0)
    out = []
    for Q, T in ((L, R), (R, L)):
        # k = 0: vertices as queries.
        out.append(geo.point_polyline_distance(Q, T))
        # k = 1: segments as queries, against every target segment (or the single point).
        if Q.shape[0] >= 2:
            out.append(geo.polyline_segments_distance(Q, T))
    return np.concatenate(out)


def overlap_widths(left: np.ndarray, right: np.ndarray) -> np.ndarray:
    """Distance from every cone of each boundary to the other boundary (metres), for the cones
    whose nearest point on the other boundary lies inside it, not at one of its two ends.

    The width check of a finished lane in RLD's quality checks (section IV-B: "the distance
    between boundaries falling within the minimum and maximum width"). It differs from CLC's
    ``lane_widths`` only at the lane's ends: where one boundary runs on past the other's last
    cone, ``lane_widths`` measures the diagonal to that last cone (up to 7.4 m on a 4 m lane in
    a bend), which the true lane fails too; here those cones are not paired. Left cones first,
    then right. A boundary of fewer than two cones pairs nothing.
    """
    out = []
    for Q, T in ((left, right), (right, left)):
        Q = np.asarray(Q, dtype=np.float64).reshape(-1, 2)
        T = np.asarray(T, dtype=np.float64).reshape(-1, 2)
        if T.shape[0] < 2 or Q.shape[0] == 0:
            continue
        _, d, k, t = geo.nearest_on_polyline(Q, T)
        # Beyond an end: the foot before the first cone or past the last (a cone abreast of
        # an end cone, t = 0 or 1 exactly, is paired).
        at_end = ((k == 0) & (t < -1e-12)) | ((k == T.shape[0] - 2) & (t > 1.0 + 1e-12))
        out.append(d[~at_end])
    return np.concatenate(out) if out else np.zeros(0)


def c_width(
    left: np.ndarray,
    right: np.ndarray,
    min_width_m: float,
    max_width_m: float,
    closed: bool = False,
) -> bool:
    """CLC C_width (eq. 13): every matching line is within [w_min, w_max] (closed bounds, see
    the module docstring)."""
    w = lane_widths(left, right, closed)
    return bool(np.all((w >= min_width_m) & (w <= max_width_m)))


def lane_is_feasible(left: np.ndarray, right: np.ndarray, params, closed: bool = False,
                     max_width: bool = True) -> bool:
    """CLC CD(P) (eq. 6) on a whole path pair: C_seg, C_width and C_poly, plus the spacing limit
    the search graph enforces (CLC constraint 1, ``max_cone_spacing_m``). ``max_width=False``
    leaves out C_width's upper bound: RLD's cone window can cut one boundary short of the other,
    and the matching lines past the shorter one's end (diagonals to its last cone) then exceed
    w_max on the true lane (``rld.solver``)."""
    for xy in (left, right):
        if len(xy) >= 2:
            seg = np.diff(_closed(np.asarray(xy, float), closed), axis=0)
            if np.any(np.hypot(seg[:, 0], seg[:, 1]) > params.max_cone_spacing_m):
                return False
    return (
        c_seg(left, right, params.max_turn_angle_rad, closed)
        and c_width(left, right, params.min_width_m,
                    params.max_width_m if max_width else math.inf, closed)
        and c_poly(left, right, closed)
    )


def starting_vertex_pairs(
    points: np.ndarray, pose: Pose, radius_m: float, k: int = 1, min_width_m: float = 0.0,
    reach_m: float = 0.0,
) -> list[tuple[int, int]]:
    """The ``k`` best (left, right) start pairs of CLC's ``find_starting_vertices`` (IV-C),
    best first (see there); fewer when fewer pairs exist, none when a side has no candidate.
    Pairs whose two cones are less than ``min_width_m`` apart (metres) come after every wider
    pair, in the same order among themselves (our addition, ``LaneParams.start_min_width_m``;
    0, the default, is the paper's order).
    A side with no cone within ``radius_m`` takes its candidate from ``start_mask`` with
    ``reach_m`` (our addition, ``LaneParams.start_reach_m``; 0, the default, is the paper's)."""
    # One compiled loop (geometry_kernels.start_pairs_ranked; 0.1 ms of numpy calls before,
    # twice per CLC call): the order of the numpy form, which tests/test_constraints.py keeps.
    pts = np.ascontiguousarray(points, dtype=np.float64)
    out = gk.start_pairs_ranked(pts, float(pose.x), float(pose.y), math.cos(pose.yaw),
                                math.sin(pose.yaw), float(radius_m), max(int(k), 1),
                                float(min_width_m))
    if out.shape[0] == 0 and reach_m > radius_m:
        # A side without a cone within the radius: the same order over start_mask's cones.
        sel = np.flatnonzero(start_mask(pts, pose, radius_m, reach_m))
        out = sel[gk.start_pairs_ranked(pts[sel], float(pose.x), float(pose.y),
                                        math.cos(pose.yaw), math.sin(pose.yaw), math.inf,
                                        max(int(k), 1), float(min_width_m))]
    return [(int(a), int(b)) for a, b in out]


def find_starting_vertices(
    points: np.ndarray, pose: Pose, radius_m: float, reach_m: float = 0.0
) -> tuple[int, int] | None:
    """CLC ``find_starting_vertices`` (IV-C): the first left and right cone.

    Candidates lie within ``radius_m`` of the car (RLD's near-car mask r, eq. 11); the left one
    at a positive angle from the heading, the right one at a negative angle. Of all pairs, the
    one most symmetric about the car's line wins: the mirror image of the left cone across that
    line is nearest the right cone. Ties go to the pair nearest the car, then to the lower
    indices. ``None`` when a side has no candidate. ``starting_vertex_pairs`` gives the
    runners-up too, and the meaning of ``reach_m``.
    """
    pairs = starting_vertex_pairs(points, pose, radius_m, 1, reach_m=reach_m)
    return pairs[0] if pairs else None

"""The cost terms of RLD (Brandes et al. 2020, section II-G/H), written once.

RLD's program uses them as objective coefficients; CLC's ``rld_cost`` ranker evaluates the same
objective on whole path pairs through ``lane_cost``, so the two methods can be compared on one
definition.
"""

from __future__ import annotations

import math

import numpy as np

from rld import costs_kernels as ck
from rld import geometry as geo
from rld.colors import SIDE_LEFT, SIDE_RIGHT, SIDE_UNKNOWN
from rld.constraints import lane_widths
from rld.types import LaneParams, Pose

__all__ = [
    "spacing_cost",
    "angle_cost",
    "heading_cost",
    "regularity_cost",
    "width_roughness",
    "width_second_differences",
    "high_cost_mask",
    "edge_objective",
    "lane_cost",
    "within_radius",
    "reach_costs",
    "jog_positions",
    "JOG_THRESHOLD_M",
    "REACH_M",
    "open_path_costs",
    "color_cost",
    "boundary_color_cost",
    "color_edge_cost",
    "color_skip_cost",
    "color_start_cost",
    "color_unknown_cost",
    "lane_color_costs",
    "confidence_cost",
    "ranking_features",
    "FEATURE_NAMES",
]

#: Metres from the car, past the geometric rule's 20 m, within which a lane is judged by RLD's
#: objective (``reach_costs``): CLC's refinement (``Refinement.reach_m``) and ``rld``'s
#: short-lane retry; beyond it both extend a lane's far ends (``rld.insertion.extend_ends``).
#: Source: our choice.
REACH_M = 25.0

#: A width jog: a boundary cone whose matching line's second difference
#: (``width_second_differences``, ``jog_positions``) exceeds this, metres; where CLC's
#: refinement dives (``Refinement.jog_threshold_m``) and where a swap may happen
#: (``rld.insertion.swap_cones``).
#: Chosen by measurement: docs/tuning.md#jog_threshold_m.
JOG_THRESHOLD_M = 1.0

#: The CLC ranking features (section VII), in the order of ``ranking_features``.
FEATURE_NAMES = (
    "length_m",
    "n_left",
    "n_right",
    "width_var",
    "left_spacing_var",
    "right_spacing_var",
    "left_turn_var",
    "right_turn_var",
)


def spacing_cost(lengths_m: np.ndarray, expected_m: float, tolerance_m: float) -> np.ndarray:
    """RLD eq. 18: s_ij = ((D_ij - d_e) / d_t)^4, dimensionless (``costs_kernels.spacing_term``).
    """
    d = np.asarray(lengths_m, dtype=np.float64)
    out = np.empty(d.size)
    ck.spacing_costs(np.ascontiguousarray(d.ravel()), float(expected_m), float(tolerance_m), out)
    return out.reshape(d.shape)


def angle_cost(turns_rad: np.ndarray, tolerance_rad: float) -> np.ndarray:
    """RLD eq. 20: t_ijk = ((angle(a_ij, a_jk) - theta_e) / theta_t)^4 with theta_e = pi.

    ``angle`` is the angle at the shared cone between the two edges, pi for a straight line, so
    ``angle - pi = -|turn|`` and the cost is (|turn| / theta_t)^4 (``costs_kernels.angle_term``).
    """
    t = np.asarray(turns_rad, dtype=np.float64)
    out = np.empty(t.size)
    ck.angle_costs(np.ascontiguousarray(t.ravel()), float(tolerance_rad), out)
    return out.reshape(t.shape)


def regularity_cost(len_a: np.ndarray, len_b: np.ndarray, tolerance: float) -> np.ndarray:
    """Spacing regularity, our extension (not in either paper): (ln(D_a / D_b) / ln(rho_t))^2
    for two consecutive edges of one boundary, of lengths ``len_a`` and ``len_b`` (metres, > 0),
    with ``tolerance`` = rho_t > 1: 0 for equal edges, 1 when one is rho_t times the other,
    the same read in either direction. A false positive inserted into a boundary splits one
    edge beside whole ones; the paper's spacing cost (eq. 18) scores each edge alone. RLD pays
    it on the angle variables f_ijk (eq. 29 gets ``w_regularity`` times it beside w_t t_ijk).
    The square, not the fourth power of eqs 18 and 20: measured better in the paper's
    experiment (docs/benchmarks.md). ``costs_kernels.regularity_term``."""
    a, b = np.broadcast_arrays(np.asarray(len_a, dtype=np.float64),
                               np.asarray(len_b, dtype=np.float64))
    out = np.empty(a.size)
    ck.regularity_costs(np.ascontiguousarray(a.ravel()), np.ascontiguousarray(b.ravel()),
                        math.log(tolerance), out)
    return out.reshape(a.shape)


def width_roughness(left_xy: np.ndarray, right_xy: np.ndarray) -> float:
    """How unevenly the lane's width changes from cone to cone, m^2 (ours, not in either
    paper): for each boundary, the lengths of its cones' matching lines (CLC eq. 9 with the
    vertices as queries: each cone's distance to the other boundary's polyline, the diagonal
    to its end cone for a cone past its end), in order, and the sum of the squared second
    differences of that sequence; both boundaries summed. 0 for parallel boundaries of equal
    extent, small where the width changes smoothly along the lane; a cone 1 m off an otherwise
    straight boundary of a 4 m lane adds 1 + 4 + 1 = 6 m^2 on its own side, plus the change it
    makes to the other side's lengths. A side of fewer than 3 cones, or facing fewer than 2,
    adds 0. Measured against counting only the cones beside the other boundary
    (``overlap_widths``' pairing), this form did better on the shared tracks (docs/clc.md at commit
    933288e).
    ``left_xy``, ``right_xy``: (n, 2) and (m, 2), metres, each ordered from the car forward.
    CLC's dive judge (``clc.refine.dive_cost``) adds ``LaneParams.w_width_roughness`` times it
    to RLD's objective: a false positive 0.6-1.5 m beside a true cone makes a line as smooth
    as the true one, but jogs the width."""
    return float(ck.width_roughness(
        np.ascontiguousarray(left_xy, dtype=np.float64).reshape(-1, 2),
        np.ascontiguousarray(right_xy, dtype=np.float64).reshape(-1, 2)))


def width_second_differences(query_xy: np.ndarray, target_xy: np.ndarray) -> np.ndarray:
    """The second differences (metres) of the matching-line lengths of the boundary
    ``query_xy`` to the boundary ``target_xy`` (each cone's distance to the target polyline,
    CLC eq. 9), in order: entry k belongs to query cone k + 1. Empty for fewer than 3 query
    cones or fewer than 2 target cones. ``width_roughness`` sums their squares;
    ``jog_positions`` finds the large ones."""
    Q = np.asarray(query_xy, dtype=np.float64).reshape(-1, 2)
    T = np.asarray(target_xy, dtype=np.float64).reshape(-1, 2)
    if Q.shape[0] < 3 or T.shape[0] < 2:
        return np.zeros(0)
    out = np.empty(Q.shape[0] - 2)
    ck.width_second_differences(np.ascontiguousarray(Q), np.ascontiguousarray(T), out)
    return out


def heading_cost(
    points: np.ndarray, edges: np.ndarray, pose: Pose, min_distance_m: float
) -> np.ndarray:
    """RLD eq. 25: p_ij = (|v_ij x h_c| / d_car(a_ij))^4.

    ``v_ij`` is the edge vector (metres, not normalised, as printed), ``h_c`` the unit heading,
    ``d_car`` the distance from the car to the edge's midpoint, floored at ``min_distance_m``
    (our addition: the paper divides by zero for an edge whose midpoint is under the car).
    ``costs_kernels.heading_term``.
    """
    points = np.asarray(points, dtype=np.float64)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    out = np.empty(edges.shape[0])
    h = pose.heading
    ck.heading_costs(np.ascontiguousarray(points[edges[:, 0]]),
                     np.ascontiguousarray(points[edges[:, 1]]), float(pose.xy[0]),
                     float(pose.xy[1]), float(h[0]), float(h[1]), float(min_distance_m), out)
    return out


def high_cost_mask(costs: np.ndarray, critical: float) -> np.ndarray:
    """RLD eqs 27-28: the entries whose cost exceeds the critical value s_crit or t_crit; the
    program forbids them (and ours never creates their variables)."""
    return np.asarray(costs) > critical


def edge_objective(
    points: np.ndarray,
    edges: np.ndarray,
    pose: Pose,
    params: LaneParams,
    heading: bool = True,
) -> np.ndarray:
    """Coefficient of every edge variable in RLD's objective (eq. 29):
    ``w_s s_ij + w_p p_ij - w_b``. ``heading=False`` leaves out the heading cost ``w_p p_ij``
    (the incremental solver's frontier, whose direction is fixed by its junction edges
    instead). The colour cost is per cone, not per edge (``color_cost``)."""
    lengths = np.hypot(*(points[edges[:, 1]] - points[edges[:, 0]]).T)
    s = spacing_cost(lengths, params.expected_spacing_m, params.spacing_tolerance_m)
    out = params.w_spacing * s - params.w_benefit
    if heading:
        out = out + params.w_heading * heading_cost(points, edges, pose,
                                                    params.heading_min_distance_m)
    return out


def color_cost(colors: np.ndarray, side: int) -> np.ndarray:
    """Whether each cone's side label (``colors``, ``rld.colors``) contradicts ``side``
    (``SIDE_LEFT`` or ``SIDE_RIGHT``), (N,) floats 1 or 0; unknown and either (orange, big
    orange) never do. The indicator the colour costs are made of: ``boundary_color_cost`` (RLD's
    objective, CLC's judge and ranking), CLC's next-vertex decider
    (``clc.search.color_penalties``), the nearest-neighbour chain."""
    if side not in (SIDE_LEFT, SIDE_RIGHT):
        raise ValueError(f"side must be SIDE_LEFT ({SIDE_LEFT}) or SIDE_RIGHT ({SIDE_RIGHT})")
    other = SIDE_RIGHT if side == SIDE_LEFT else SIDE_LEFT
    return (np.asarray(colors) == other).astype(np.float64)


def boundary_color_cost(points: np.ndarray, colors: np.ndarray, idx: np.ndarray, pose: Pose,
                        near_radius_m: float, closed: bool = False,
                        unknown: float = 0.0) -> float:
    """The colour cost of one boundary ``idx`` (side labels ``colors``; ours, RLD section V),
    unweighted: 1/2 per edge joining the two sides' labels, per unlabelled cone between them
    and per near end on the car's other side, plus ``unknown`` per unknown cone
    (docs/formulation.md, "Colour"; ``costs_kernels.boundary_color``)."""
    h = pose.heading
    return float(ck.boundary_color(np.ascontiguousarray(points, dtype=np.float64),
                                   np.ascontiguousarray(colors, dtype=np.int64),
                                   np.ascontiguousarray(idx, dtype=np.int64), bool(closed),
                                   float(pose.xy[0]), float(pose.xy[1]), float(h[0]),
                                   float(h[1]), float(near_radius_m), float(unknown)))


def color_edge_cost(colors: np.ndarray, edges: np.ndarray) -> np.ndarray:
    """``boundary_color_cost``'s edge term for each edge (E, 2): 1/2 where its two cones'
    labels name different sides, else 0 (RLD's program puts it on the edge variables)."""
    a, b = np.asarray(colors)[edges[:, 0]], np.asarray(colors)[edges[:, 1]]
    return 0.5 * (_names_side(a) & _names_side(b) & (a != b))


def _names_side(labels: np.ndarray) -> np.ndarray:
    """Which side labels name a side (``SIDE_LEFT`` or ``SIDE_RIGHT``)."""
    return (labels == SIDE_LEFT) | (labels == SIDE_RIGHT)


def color_skip_cost(colors: np.ndarray, triples: np.ndarray) -> np.ndarray:
    """``boundary_color_cost``'s term for each triple (i, j, k, ...) of consecutive cones: 1/2
    where j names no side and the labels of i and k name different sides (RLD's program puts
    it on the angle variables f_ijk)."""
    c = np.asarray(colors)
    a, m, b = c[triples[:, 0]], c[triples[:, 1]], c[triples[:, 2]]
    return 0.5 * (~_names_side(m) & _names_side(a) & _names_side(b) & (a != b))


def color_start_cost(points: np.ndarray, colors: np.ndarray, pose: Pose) -> np.ndarray:
    """``boundary_color_cost``'s end term for each cone were it an end near the car: 1/2 where
    its label contradicts the side of the car it lies on (RLD's program puts it on the
    endpoint variables m_i of the near cones)."""
    y = pose.to_local(np.asarray(points, dtype=np.float64))[:, 1]
    side = np.where(y > 0, SIDE_LEFT, np.where(y < 0, SIDE_RIGHT, 0))
    c = np.asarray(colors)
    return 0.5 * (_names_side(c) & (side > 0) & (c != side))


def color_unknown_cost(colors: np.ndarray) -> np.ndarray:
    """``boundary_color_cost``'s per-cone term over its weight ``unknown``: 1 for each cone
    labelled unknown, else 0, (N,) floats (RLD's program puts it on the cone variables g_i)."""
    return (np.asarray(colors) == SIDE_UNKNOWN).astype(np.float64)


def lane_color_costs(points: np.ndarray, colors: np.ndarray, lanes, pose: Pose,
                     radius_m: float | None = None, share: bool = False,
                     near_radius_m: float | None = None,
                     unknown: float | None = None) -> np.ndarray:
    """``boundary_color_cost`` of each open lane's two boundaries, unweighted, (K,) floats (the
    start radius and unknown charge ``LaneParams``' defaults unless ``near_radius_m``,
    ``unknown``);
    ``share=True``: that over the cones counted (those of sides of two cones or more; 0 for
    none), which does not grow with the lane's length. ``lanes``: a CLC ``CandidateList``
    (``flat()``) or a sequence of ``(left, right, ...)`` index arrays into ``points``; with
    ``radius_m``, each boundary cut there first (``within_radius``). One compiled
    loop (``costs_kernels.lane_color_counts``): CLC ranks hundreds of candidates per call."""
    if hasattr(lanes, "flat"):
        lf, lp, rf, rp, _ = lanes.flat()
    else:
        lanes = list(lanes)
        if not lanes:
            return np.zeros(0)
        paths = [[np.asarray(lane[s], dtype=np.int64).reshape(-1) for lane in lanes]
                 for s in (0, 1)]
        lf, rf = (np.concatenate(q) for q in paths)
        lp, rp = (np.concatenate([[0], np.cumsum([q.size for q in qs])]) for qs in paths)
    out = np.zeros(len(lp) - 1)
    counted = np.zeros(len(lp) - 1)
    h = pose.heading
    near = LaneParams().near_radius_m if near_radius_m is None else float(near_radius_m)
    unknown = LaneParams().color_unknown if unknown is None else float(unknown)
    ck.lane_color_counts(np.ascontiguousarray(points, dtype=np.float64),
                         np.ascontiguousarray(colors, dtype=np.int64),
                         np.ascontiguousarray(lf, dtype=np.int64),
                         np.ascontiguousarray(lp, dtype=np.int64),
                         np.ascontiguousarray(rf, dtype=np.int64),
                         np.ascontiguousarray(rp, dtype=np.int64),
                         float(pose.xy[0]), float(pose.xy[1]), float(h[0]), float(h[1]), near,
                         unknown, 0.0 if radius_m is None else float(radius_m), out,
                         counted)
    return out / np.maximum(counted, 1.0) if share else out


def confidence_cost(confidence: np.ndarray) -> np.ndarray:
    """1 - confidence per cone: what using a doubtful detection costs. Our extension."""
    return 1.0 - np.asarray(confidence, dtype=np.float64)


def lane_cost(
    points: np.ndarray,
    left: np.ndarray,
    right: np.ndarray,
    pose: Pose,
    params: LaneParams,
    closed: bool = False,
    colors: np.ndarray | None = None,
    confidence: np.ndarray | None = None,
    sided: bool = False,
    heading: bool = True,
    radius_m: float | None = None,
) -> float:
    """RLD's objective (eq. 29) of the lane graph made by two index sequences: the sum of the
    edge coefficients of its edges plus ``w_t`` times the angle cost at every interior cone,
    plus the confidence cost and ``w_color`` times the colour cost of each boundary
    (``boundary_color_cost``, start radius ``near_radius_m``, ``color_unknown``) when given;
    every RLD form pays the same (``sided`` is kept for callers and changes nothing).
    ``heading=False`` leaves out the heading cost, as the incremental solver's frontier
    program does (``edge_objective``).

    ``radius_m`` (open lanes only; None: the whole lane): each boundary counts only up to and
    with its first cone farther than this from the car (``within_radius``), so two lanes that
    agree near the car but end differently far from it cost the same near part (CLC's dive
    judge, ``clc.solver``). Closed lanes always count whole."""
    total = 0.0
    open_paths = []  # the open boundaries, costed in one batch (half the numpy overhead)
    wrong = 0.0  # the colour cost, added once (the same float as ``reach_costs``)
    for idx in (left, right):
        idx = np.asarray(idx, dtype=np.int64)
        if radius_m is not None and not closed:
            idx = within_radius(points, idx, pose, radius_m)
        if confidence is not None and idx.size >= 2:
            total += params.w_confidence * float(confidence_cost(confidence[idx]).sum())
        if colors is not None and idx.size >= 2:
            wrong += boundary_color_cost(points, colors, idx, pose, params.near_radius_m, closed,
                                         params.color_unknown)
        if idx.size < 2:
            continue
        if not closed:
            open_paths.append(idx)
            continue
        seq = np.concatenate([idx, idx[:1]])
        edges = np.column_stack([seq[:-1], seq[1:]])
        total += float(edge_objective(points, edges, pose, params, heading).sum())
        turns = geo.polyline_turn_angles(points[idx], closed=True)
        total += params.w_angle * float(angle_cost(turns, params.angle_tolerance_rad).sum())
        if params.w_regularity:
            lens = np.hypot(*np.diff(points[seq], axis=0).T)
            total += params.w_regularity * float(regularity_cost(
                lens, np.roll(lens, 1), params.regularity_tolerance).sum())
    if wrong:
        total += params.w_color * wrong
    if open_paths:
        ptr = np.concatenate([[0], np.cumsum([q.size for q in open_paths])])
        total += float(open_path_costs(points, np.concatenate(open_paths), ptr, pose, params,
                                       heading=heading).sum())
    return total


def within_radius(points: np.ndarray, idx: np.ndarray, pose: Pose,
                  radius_m: float) -> np.ndarray:
    """The start of the boundary ``idx`` (indices into ``points``, metres) up to and with its
    first cone farther than ``radius_m`` from the car's position, at least two cones (the
    whole boundary when no cone is that far). The edge that leaves the disc stays, so a
    boundary that ends just outside it is not cut short of the edge that reaches it."""
    if not (isinstance(radius_m, int | float) and math.isfinite(radius_m) and radius_m > 0):
        raise ValueError(f"radius_m must be a positive number of metres, got {radius_m!r}")
    idx = np.ascontiguousarray(idx, dtype=np.int64)
    if idx.size <= 2:
        return idx
    # near_car_mask's test (distance <= radius_m is near), in one compiled loop.
    return idx[:ck.radius_cut(np.ascontiguousarray(points, dtype=np.float64), idx,
                              float(pose.xy[0]), float(pose.xy[1]), float(radius_m))]


def jog_positions(points: np.ndarray, pose: Pose, left: np.ndarray, right: np.ndarray,
                  threshold_m: float, reach_m: float) -> list[tuple[int, int]]:
    """(side, j) of every cone of ``left`` (0) or ``right`` (1) within ``reach_m`` of the car
    whose matching line (CLC eq. 9) has an absolute second difference above ``threshold_m``
    (metres; ``width_second_differences``), largest first: where the lane's width jogs."""
    out = []
    for side, path, other in ((0, left, right), (1, right, left)):
        idx = within_radius(points, path, pose, reach_m)
        d2 = np.abs(width_second_differences(points[idx], points[other]))
        out += [(-float(d2[k]), side, int(k) + 1) for k in np.flatnonzero(d2 > threshold_m)]
    return [(side, j) for _, side, j in sorted(out)]


def reach_costs(points: np.ndarray, pose: Pose, params: LaneParams, lanes, radius_m: float,
                colors: np.ndarray | None = None) -> np.ndarray:
    """(K,) for each open lane ``(left, right)`` of ``lanes``, cut at ``radius_m`` of the car
    (``within_radius``): ``lane_cost`` (eq. 29, with ``colors``) plus ``params.w_width_roughness``
    times the ``width_roughness`` (ours), in one compiled loop (CLC's judge, ``clc.refine``)."""
    if not (isinstance(radius_m, int | float) and math.isfinite(radius_m) and radius_m > 0):
        raise ValueError(f"radius_m must be a positive number of metres, got {radius_m!r}")
    lanes = list(lanes)
    out = np.zeros(len(lanes))
    if not lanes:
        return out
    sides = [[np.asarray(lane[s], dtype=np.int64).reshape(-1) for lane in lanes] for s in (0, 1)]
    flats, ptrs = [], []
    for paths in sides:
        flats.append(np.ascontiguousarray(np.concatenate(paths), dtype=np.int64))
        ptrs.append(np.concatenate([[0], np.cumsum([q.size for q in paths])]).astype(np.int64))
    pts = np.ascontiguousarray(points, dtype=np.float64)
    h = pose.heading
    ck.reach_costs(pts, flats[0], ptrs[0], flats[1], ptrs[1], float(pose.xy[0]),
                   float(pose.xy[1]), float(h[0]), float(h[1]), float(radius_m),
                   float(params.expected_spacing_m), float(params.spacing_tolerance_m),
                   float(params.w_spacing), float(params.w_benefit), float(params.w_heading),
                   float(params.heading_min_distance_m), float(params.w_angle),
                   float(params.angle_tolerance_rad), float(params.w_regularity),
                   math.log(params.regularity_tolerance) if params.w_regularity else 1.0,
                   float(params.w_width_roughness),
                   np.zeros(0, dtype=np.int64) if colors is None
                   else np.ascontiguousarray(colors, dtype=np.int64),
                   float(params.w_color), float(params.near_radius_m),
                   float(params.color_unknown), out)
    return out


def open_path_costs(points: np.ndarray, flat: np.ndarray, ptr: np.ndarray, pose: Pose,
                    params: LaneParams, heading: bool = True) -> np.ndarray:
    """The edge and turn terms of RLD's objective for many open paths at once: path k is
    ``flat[ptr[k]:ptr[k + 1]]`` (indices into ``points``); returns (K,) the sum of its edge
    coefficients (eq. 29, ``edge_objective`` with ``heading``) plus ``w_t`` times the angle
    cost (eq. 20) at its interior cones, 0 for a path of fewer than two cones. ``lane_cost``
    sums it over the sides of an open lane (and adds the per-cone costs, which need the side);
    CLC's ``rld_cost`` ranker scores a whole candidate list with it. One compiled loop
    (``costs_kernels.open_path_costs``) over the same terms as ``edge_objective`` and
    ``angle_cost``."""
    flat = np.ascontiguousarray(flat, dtype=np.int64)
    ptr = np.ascontiguousarray(ptr, dtype=np.int64)
    out = np.zeros(ptr.size - 1)
    if flat.size < 2:
        return out
    pts = np.ascontiguousarray(points, dtype=np.float64)
    h = pose.heading
    ck.open_path_costs(pts, flat, ptr, float(pose.xy[0]), float(pose.xy[1]), float(h[0]),
                       float(h[1]), float(params.expected_spacing_m),
                       float(params.spacing_tolerance_m), float(params.w_spacing),
                       float(params.w_benefit), float(params.w_heading) if heading else 0.0,
                       float(params.heading_min_distance_m), float(params.w_angle),
                       float(params.angle_tolerance_rad), float(params.w_regularity),
                       math.log(params.regularity_tolerance) if params.w_regularity else 1.0,
                       out)
    return out


def ranking_features(left_xy: np.ndarray, right_xy: np.ndarray, closed: bool = False) -> np.ndarray:
    """The 8 features of CLC section VII for one lane, (8,) float64 in ``FEATURE_NAMES`` order:
    lane length (mean of the two boundary lengths, CLC eq. 7, m), cones on the left and on the
    right, the variance of the lane width (of all matching-line lengths W(L, R), CLC eq. 12,
    m^2), the variance of the segment lengths of each boundary (m^2) and of the signed turn
    angles between consecutive segments of each boundary (rad^2). Variances are population
    variances, 0 for fewer than two values. A closed lane counts its closing segments and the
    turns at the wrap. ``left_xy`` and ``right_xy``: (n, 2) and (m, 2) boundary points ordered
    from the car forward, metres. The numbers come from the kernels of ``rld.costs_kernels``;
    the CLC search keeps the same numbers incrementally (``clc.search_kernels``)."""
    L = np.ascontiguousarray(np.asarray(left_xy, dtype=np.float64).reshape(-1, 2))
    R = np.ascontiguousarray(np.asarray(right_xy, dtype=np.float64).reshape(-1, 2))
    widths = np.ascontiguousarray(lane_widths(L, R, closed), dtype=np.float64)
    out = np.zeros(ck.N_FEATURES)
    if closed:
        ck.closed_lane_features(L, R, widths, out)
    else:
        ck.lane_features(L, R, widths, out)
    return out

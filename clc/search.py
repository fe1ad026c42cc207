"""The CLC search (Ivanov & Markgraf 2024, sections IV-VI) in plain Python over numba kernels.

``search_graph`` builds the graph of IV-A (every cone pair within ``max_cone_spacing_m``, CLC
eq. 2, the shared ``candidate_edges``) or of IV-B (a Delaunay triangulation, filtered by the same
distance); ``enumerate_candidates`` finds the start vertices (IV-C, the shared
``find_starting_vertices``), enumerates the feasible path pairs (Alg. 2, ``clc.search_kernels``)
and, on request, their closings (IV-E).

What the search guarantees: every candidate satisfies the shared whole-path predicate
``rld.constraints.lane_is_feasible`` (C_seg, C_width, C_poly and the spacing limit); with
``max_iterations=0`` (no limit) the candidates are exactly all feasible path pairs from the two
start vertices (theorem 4). Under a limit the search is a heuristic, depth-first walk led by the
next-vertex and left-right deciders (section V) and, when warm-started, by the previous lane.
"""

from __future__ import annotations

import math
import time
from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import Delaunay

from clc import search_kernels as sk
from rld import geometry as geo
from rld.colors import SIDE_LEFT, SIDE_RIGHT
from rld.constraints import candidate_edges, find_starting_vertices, hook_position, lane_is_feasible
from rld.costs import color_cost, open_path_costs, ranking_features, within_radius
from rld.types import LaneParams, Pose

__all__ = ["SearchGraph", "SearchResult", "CandidateList", "closable", "merge_results",
           "search_graph", "color_penalties", "enumerate_candidates", "contested_dives",
           "claim_dive", "dive_at",
           "pair_drops", "outward_drops", "skip_inserts", "start_replacements", "trim_behind",
           "unhook", "GRAPHS"]

#: Search-graph constructions: ``radius`` (IV-A, the paper's choice) and ``delaunay`` (IV-B).
GRAPHS = ("radius", "delaunay")
#: Two detections nearer than this (metres) are one cone seen twice or a cone and a false
#: positive beside it, which RLD's objective cannot tell apart (``pair_drops``' default; the
#: solver passes ``clc.solver.PAIR_DROP_M``). Measured against 1.5 m: docs/tuning.md#pair_drop_m.
DUPLICATE_M = 1.0


@dataclass(frozen=True)
class SearchGraph:
    """The undirected search graph in CSR form: the neighbours of cone v are
    ``indices[indptr[v]:indptr[v + 1]]``, sorted by index. ``longest_m``: its longest edge
    (metres), which sets the next-vertex decider's dead-end score. ``side_penalty``: (2, N)
    the decider's colour penalty of each cone on the left (row 0) and on the right (row 1),
    radians (``color_penalties``), or None without colours; every search on the graph uses it."""

    edges: np.ndarray
    indptr: np.ndarray
    indices: np.ndarray
    longest_m: float = 0.0
    side_penalty: np.ndarray | None = None

    def dead_end(self, params: LaneParams) -> float:
        """The look-ahead's score of a cone with no step onward (``search_kernels.
        dead_end_score``): phi_max + the decider's distance weight times the longest edge."""
        return float(params.max_turn_angle_rad) + float(params.nvd_distance_weight) * \
            self.longest_m

    def neighbours(self, v: int) -> np.ndarray:
        return self.indices[self.indptr[v]: self.indptr[v + 1]]

    def has_edge(self, a: int, b: int) -> bool:
        nb = self.neighbours(a)
        k = np.searchsorted(nb, b)
        return bool(k < nb.size and nb[k] == b)


def color_penalties(colors: np.ndarray | None, params: LaneParams) -> np.ndarray | None:
    """The next-vertex decider's colour penalty (ours), (2, N) radians: row 0 for taking each
    cone into the left boundary, row 1 into the right, ``params.nvd_color_weight`` times the
    shared ``rld.costs.color_cost`` (a cone whose label names the other side); None without
    labels or with the weight 0. It orders the search, it forbids nothing."""
    if colors is None or params.nvd_color_weight == 0:
        return None
    w = float(params.nvd_color_weight)
    return np.ascontiguousarray(np.vstack([w * color_cost(colors, SIDE_LEFT),
                                           w * color_cost(colors, SIDE_RIGHT)]))


def search_graph(points: np.ndarray, params: LaneParams, kind: str = "radius",
                 colors: np.ndarray | None = None) -> SearchGraph:
    """CLC IV-A (``radius``: every pair within ``max_cone_spacing_m``) or IV-B (``delaunay``:
    the Delaunay edges no longer than it); ``colors`` (side labels) give it the decider's
    ``color_penalties``."""
    points = np.ascontiguousarray(points, dtype=np.float64)
    n = points.shape[0]
    if kind == "radius":
        edges = candidate_edges(points, params.max_cone_spacing_m)
    elif kind == "delaunay":
        edges = _delaunay_edges(points, params.max_cone_spacing_m)
    else:
        raise ValueError(f"unknown search graph {kind!r}; use one of {GRAPHS}")
    indptr, indices = sk.csr_from_edges(np.ascontiguousarray(edges, dtype=np.int64), n)
    return SearchGraph(edges=edges, indptr=indptr, indices=indices,
                       longest_m=float(sk.dead_end_score(points, indptr, indices, 0.0, 1.0)),
                       side_penalty=color_penalties(colors, params))


def _delaunay_edges(points: np.ndarray, max_len: float) -> np.ndarray:
    if points.shape[0] < 3:
        return candidate_edges(points, max_len)
    try:
        tri = Delaunay(points)
    except Exception:  # collinear or degenerate input: no triangulation
        return candidate_edges(points, max_len)
    s = tri.simplices
    e = np.concatenate([s[:, [0, 1]], s[:, [1, 2]], s[:, [0, 2]]]).astype(np.int64)
    e.sort(axis=1)
    e = np.unique(e, axis=0)
    d = points[e[:, 1]] - points[e[:, 0]]
    return np.ascontiguousarray(e[np.hypot(d[:, 0], d[:, 1]) <= max_len])


class CandidateList(Sequence):
    """The candidates of one search as a read-only sequence of ``(left, right, closed)``
    (cone index arrays from the car forward), backed by the kernel's flat arrays: a candidate
    becomes Python objects only when it is read."""

    def __init__(self, lf: np.ndarray, lp: np.ndarray, rf: np.ndarray, rp: np.ndarray,
                 closed: np.ndarray | None = None) -> None:
        self._lf, self._lp, self._rf, self._rp = lf, lp, rf, rp
        n = lp.size - 1
        self._closed = np.zeros(n, dtype=bool) if closed is None else closed

    def __len__(self) -> int:
        return self._lp.size - 1

    def __getitem__(self, k):
        if isinstance(k, slice):
            return [self[i] for i in range(*k.indices(len(self)))]
        n = len(self)
        if k < 0:
            k += n
        if not 0 <= k < n:
            raise IndexError(k)
        return (self._lf[self._lp[k]: self._lp[k + 1]], self._rf[self._rp[k]: self._rp[k + 1]],
                bool(self._closed[k]))

    def sizes(self) -> tuple[np.ndarray, np.ndarray]:
        """Cones per left and per right boundary, (K,) each."""
        return np.diff(self._lp), np.diff(self._rp)

    def flat(self) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
        """The backing arrays, read-only by convention: ``(left_flat, left_ptr, right_flat,
        right_ptr, closed)``; candidate k's left boundary is
        ``left_flat[left_ptr[k]:left_ptr[k + 1]]`` (likewise right)."""
        return self._lf, self._lp, self._rf, self._rp, self._closed


@dataclass
class SearchResult:
    """What one enumeration found.

    ``candidates``: ``(left, right, closed)`` per feasible path pair, cone indices from the car
    forward, in the order found (with ``close_loops``, the closings of IV-E follow);
    ``features``: (K, 8) ranking features (``rld.costs.FEATURE_NAMES``); ``iterations``: the
    extensions made (Alg. 2's counter); ``complete``: the search ran out of options before
    ``max_iterations`` (every feasible pair was enumerated); ``start``: the start vertices, or
    None when a side has no cone near the car.
    """

    candidates: Sequence = field(default_factory=list)
    features: np.ndarray = field(default_factory=lambda: np.zeros((0, 8)))
    iterations: int = 0
    complete: bool = True
    start: tuple[int, int] | None = None
    graph: SearchGraph | None = None


def enumerate_candidates(
    points: np.ndarray,
    pose: Pose,
    params: LaneParams,
    max_iterations: int | None = None,
    graph: str | SearchGraph = "radius",
    start: tuple[int, int] | None = None,
    guide: tuple[np.ndarray, np.ndarray] | None = None,
    close_loops: bool = False,
    banned: np.ndarray | None = None,
    forbid: tuple[int, int] = (-1, -1),
    stale: int = 0,
    colors: np.ndarray | None = None,
) -> SearchResult:
    """CLC Alg. 1 up to the ranking: graph, start vertices, Alg. 2, closings.

    ``points`` (N, 2) metres (validated by the caller); ``max_iterations``: it_max (None:
    ``params.max_iterations``; 0: no limit); ``start``: force the start vertices;
    ``guide``: the warm-start lane (left, right index arrays in ``points``), followed first.
    ``close_loops``: add the closing of every closable candidate (IV-E) as a further candidate;
    ``clc.solver`` closes only the ranked winner instead (see there). ``banned``: cones no path
    may take (indices into ``points``); ``forbid``: a cone per side (-1: none) that may not
    come right after that side's whole guide, only later (``contested_dives``). ``stale``
    (0: off; only under a limit): abandon the subtree of an extension after which this many
    extensions in a row left the pair infeasible (``clc.solver``'s trapped searches).
    ``colors`` (side labels): the next-vertex decider's colour penalties, for a graph built
    here (``search_graph``); a ``SearchGraph`` given brings its own.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    g = graph if isinstance(graph, SearchGraph) else search_graph(points, params, graph, colors)
    if start is None:
        start = find_starting_vertices(points, pose, params.near_radius_m, params.start_reach_m)
    if start is None:
        return SearchResult(start=None, graph=g)
    it_max = params.max_iterations if max_iterations is None else int(max_iterations)
    gl, gr = (np.zeros(0, np.int64), np.zeros(0, np.int64)) if guide is None else guide
    lf, lp, rf, rp, feats, iterations, complete = sk.enumerate_pairs(
        points, g.indptr, g.indices, int(start[0]), int(start[1]),
        float(np.cos(pose.yaw)), float(np.sin(pose.yaw)), float(params.max_turn_angle_rad),
        float(params.min_width_m), float(params.max_width_m), float(params.nvd_distance_weight),
        float(params.nvd_lookahead_weight), int(it_max), np.ascontiguousarray(gl, dtype=np.int64),
        np.ascontiguousarray(gr, dtype=np.int64),
        np.zeros(0, np.int64) if banned is None else np.ascontiguousarray(banned, dtype=np.int64),
        int(forbid[0]), int(forbid[1]), g.dead_end(params), int(stale), True,
        *((None, None) if g.side_penalty is None else g.side_penalty))
    cands = CandidateList(lf, lp, rf, rp)
    features = feats
    if close_loops:
        extra = [(left, right) for left, right, _ in cands if closable(g, left, right)
                 and lane_is_feasible(points[left], points[right], params, closed=True)]
        if extra:
            lf2 = np.concatenate([lf] + [e[0] for e in extra])
            rf2 = np.concatenate([rf] + [e[1] for e in extra])
            lp2 = np.concatenate([lp, lp[-1] + np.cumsum([e[0].size for e in extra])])
            rp2 = np.concatenate([rp, rp[-1] + np.cumsum([e[1].size for e in extra])])
            closed = np.r_[np.zeros(len(cands), bool), np.ones(len(extra), bool)]
            cands = CandidateList(lf2, lp2, rf2, rp2, closed)
            features = np.vstack([feats] + [ranking_features(points[a], points[b], closed=True)
                                            for a, b in extra])
    return SearchResult(candidates=cands, features=features, iterations=int(iterations),
                        complete=bool(complete), start=(int(start[0]), int(start[1])), graph=g)


def _arc_behind(points: np.ndarray, path: np.ndarray, pose: Pose) -> float:
    """Path length (metres) of ``path`` behind the car: from its start to where it crosses
    the line through the car across its heading (the whole path when it never does; 0 when
    it starts on or past the line; ``search_kernels.arc_behind``). The part of a dive's reach
    that does not count."""
    path = np.ascontiguousarray(path, dtype=np.int64)
    if path.size == 0:
        return 0.0
    return float(sk.arc_behind(points, path, float(pose.x), float(pose.y),
                               math.cos(pose.yaw), math.sin(pose.yaw)))


def path_ahead(points: np.ndarray, path: np.ndarray, pose: Pose) -> float:
    """Path length (metres) of ``path`` ahead of the car: its whole length less ``_arc_behind``
    (0 for a path of one cone, or one wholly behind the car)."""
    path = np.ascontiguousarray(path, dtype=np.int64)
    if path.size < 2:
        return 0.0
    return max(geo.polyline_length(points[path]) - _arc_behind(points, path, pose), 0.0)


def contested_dives(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
                    start: tuple[int, int], left: np.ndarray, right: np.ndarray,
                    margin: float, reach_m: float, iterations: int,
                    skip: set | None = None, cut_other: bool = False,
                   deadline: float = math.inf,
                   stopped: list | None = None) -> list[SearchResult]:
    """Searches that revisit the close calls of a lane found under the iteration limit (our
    addition, docs/clc.md). The depth-first search changes a choice near the car only after it
    has exhausted everything beyond it, which under it_max it never does. For every position j
    of ``left`` or ``right`` within ``reach_m`` of path ahead of the car (the part of the path
    behind the car does not count, ``_arc_behind``) where the next-vertex decider's runner-up
    scored at most ``margin`` above the cone taken (``search_kernels.contested_positions``), or
    whose edge passes a skipped cone within ``params.skipped_cone_m``
    (``search_kernels.skipped_positions``), one more search of ``iterations`` follows the lane
    up to j (the guide) and may not take that cone next (``forbid``), so it takes the runner-up
    there and continues on its own; the cone may come later, which mends a skipped cone (the
    runner-up is the cone skipped, the one taken comes after it). When that search did take the
    cone again somewhere, a second one bans it outright (``banned``), so it cannot find its way
    back to the same lane. Returns one result per search, in order (left first). ``skip``: the
    close calls already revisited, as (side, path up to and with the cone, other boundary,
    ``cut_other``) keys (``claim_dive``); the ones revisited here are added to it and not run again.

    ``cut_other``: the guide keeps of the other boundary only its cones up to and with the one
    nearest path[j - 1] (the last cone kept on this side), so the dive rebuilds both boundaries
    from beside the choice. For a lane that stops short (``clc.solver.SHORT_LANE_M``): when a
    wrong choice on one side has taken a cone of the other boundary, that side was bent to
    match, and a dive that kept it whole could not reach the true lane.

    ``deadline`` (``time.perf_counter()``): no search starts after it (the caller's time
    budget); the close calls not revisited are not added to ``skip``, and ``True`` is appended
    to ``stopped`` (when given)."""
    out = []
    hx, hy = float(np.cos(pose.yaw)), float(np.sin(pose.yaw))
    left = np.ascontiguousarray(left, dtype=np.int64)
    right = np.ascontiguousarray(right, dtype=np.int64)
    for side, path, other in ((0, left, right), (1, right, left)):
        reach = float(reach_m) + _arc_behind(points, path, pose)
        pos = sk.contested_positions(points, graph.indptr, graph.indices, path, other, hx, hy,
                                     float(params.max_turn_angle_rad),
                                     float(params.nvd_distance_weight),
                                     float(params.nvd_lookahead_weight), float(margin), reach,
                                     graph.dead_end(params),
                                     None if graph.side_penalty is None
                                     else graph.side_penalty[side])
        if params.skipped_cone_m > 0:
            pos = np.union1d(pos, sk.skipped_positions(points, graph.indptr, graph.indices, path,
                                                       other, float(params.skipped_cone_m),
                                                       reach))
        for j in pos:
            if time.perf_counter() > deadline:
                if stopped is not None:
                    stopped.append(True)
                return out
            if skip is not None and not claim_dive(skip, side, path, int(j), other, cut_other):
                continue
            res, guide = dive_at(points, pose, params, graph, start, left, right, side, int(j),
                                 iterations, cut_other)
            out.append(res)
            cone = int(path[j])
            lf, _, rf, _, _ = res.candidates.flat()
            if np.any(lf == cone) or np.any(rf == cone):
                out.append(enumerate_candidates(points, pose, params,
                                                max_iterations=iterations, graph=graph,
                                                start=start, guide=guide,
                                                banned=path[j:j + 1]))
    return out


def claim_dive(done: set, side: int, path: np.ndarray, j: int, other: np.ndarray,
               cut_other: bool = False) -> bool:
    """Whether the dive at position ``j`` of boundary ``path`` (``side`` 0 left, 1 right;
    ``other`` the other boundary) is still to be made, recording it in ``done`` when it is.
    A dive is identified by the path up to and with its cone, the other boundary and
    ``cut_other``: the key ``contested_dives`` and ``clc.solver``'s jog dives share, so that
    neither revisits a close call the other has."""
    key = (side, path[:j + 1].tobytes(), other.tobytes(), bool(cut_other))
    if key in done:
        return False
    done.add(key)
    return True


def dive_at(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
            start: tuple[int, int], left: np.ndarray, right: np.ndarray, side: int, j: int,
            iterations: int, cut_other: bool = False) -> tuple[SearchResult, tuple]:
    """One dive (``contested_dives``; ``clc.solver``'s jog dives): a search of ``iterations``
    that follows the lane up to position ``j`` of boundary ``side`` (0 left, 1 right) and may
    not take that boundary's cone there, so it continues on its own. ``cut_other``: the guide
    keeps of the other boundary only its cones up to and with the one nearest the cone before
    (see ``contested_dives``). Returns the search and the guide it followed."""
    path, other = (left, right) if side == 0 else (right, left)
    kept = other
    if cut_other and other.size > 1:
        d = points[other] - points[path[j - 1]]
        kept = other[: int(np.argmin(np.hypot(d[:, 0], d[:, 1]))) + 1]
    guide = (left[:j], kept) if side == 0 else (kept, right[:j])
    cone = int(path[j])
    res = enumerate_candidates(points, pose, params, max_iterations=iterations, graph=graph,
                               start=start, guide=guide,
                               forbid=(cone, -1) if side == 0 else (-1, cone))
    return res, guide


def merge_results(a: SearchResult, b: SearchResult) -> SearchResult:
    """The candidates of two searches from the same start vertices, ``a``'s first; iterations
    add up and the result is complete when either search was."""
    ca, cb = a.candidates, b.candidates
    if not isinstance(ca, CandidateList) or not isinstance(cb, CandidateList):
        raise TypeError("merge_results takes the results of enumerate_candidates")
    lf = np.concatenate([ca._lf, cb._lf])
    rf = np.concatenate([ca._rf, cb._rf])
    lp = np.concatenate([ca._lp, ca._lp[-1] + cb._lp[1:]])
    rp = np.concatenate([ca._rp, ca._rp[-1] + cb._rp[1:]])
    closed = np.concatenate([ca._closed, cb._closed])
    return SearchResult(candidates=CandidateList(lf, lp, rf, rp, closed),
                        features=np.vstack([a.features, b.features]),
                        iterations=a.iterations + b.iterations,
                        complete=a.complete or b.complete, start=a.start, graph=a.graph)


def closable(g: SearchGraph, left: np.ndarray, right: np.ndarray) -> bool:
    """CLC IV-E: both paths have at least three cones and an edge joins each one's last cone
    to its first."""
    return (left.size >= 3 and right.size >= 3 and g.has_edge(int(left[-1]), int(left[0]))
            and g.has_edge(int(right[-1]), int(right[0])))


def pair_drops(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
               left: np.ndarray, right: np.ndarray, reach_m: float,
               pair_m: float = DUPLICATE_M,
               check: bool = True) -> list[tuple[np.ndarray, np.ndarray]]:
    """The lanes made from ``left``, ``right`` by dropping one cone of a close pair: for every
    two consecutive cones of a boundary nearer than ``pair_m`` (metres), the first of them in
    the dive judge's window of ``reach_m`` (``rld.costs.within_radius``: up to and with the
    first cone farther from the car), the lane without the first and the lane without the
    second. A start vertex is never dropped; an interior cone only
    when an edge of the search graph joins its two neighbours; and only lanes that satisfy the
    shared predicates (``lane_is_feasible``) are returned (``check=False``: left to the caller).
    Our addition, docs/clc.md.

    Such a pair is one cone and a false positive beside it (or one cone seen twice), which RLD's
    objective cannot tell apart, and neither cone need bend the boundary away from the lane
    (``outward_drops``). But a lane that keeps both pays for the short edge between them, and
    a dive that drops a *true* cone elsewhere to avoid it can then win the judge. Offered to
    the judge beside the dives (``clc.solver.PAIR_DROPS``), the lane with one of the pair is
    compared with them."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    out = []
    for side, p in enumerate(paths):
        if p.size < 3:
            continue
        head = within_radius(points, p, pose, reach_m).size
        for j in range(min(head, p.size - 1)):
            d = points[p[j + 1]] - points[p[j]]
            if math.hypot(d[0], d[1]) >= pair_m:
                continue
            for k in (j, j + 1):
                if k > 0:
                    out += _drop(points, params, graph, paths, side, k, check)
    return out


def _drop(points: np.ndarray, params: LaneParams, graph: SearchGraph, paths: list,
          side: int, k: int, check: bool = True) -> list[tuple[np.ndarray, np.ndarray]]:
    """The lane ``paths`` without cone ``k`` of side ``side``, as a one-element list, when an
    interior cone's two neighbours are joined by a search-graph edge and (``check``) the lane
    satisfies the shared predicates (``lane_is_feasible``); else an empty list."""
    p = paths[side]
    if k < p.size - 1 and not graph.has_edge(int(p[k - 1]), int(p[k + 1])):
        return []
    trial = list(paths)
    trial[side] = np.delete(p, k)
    if not check or lane_is_feasible(points[trial[0]], points[trial[1]], params):
        return [(trial[0], trial[1])]
    return []


def outward_drops(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
                  left: np.ndarray, right: np.ndarray, reach_m: float,
                  check: bool = True) -> list[tuple[np.ndarray, np.ndarray]]:
    """The lanes made from ``left``, ``right`` by dropping one cone that bends its boundary
    away from the lane: an interior cone path[k] of the dive judge's window of ``reach_m``
    (``rld.costs.within_radius``) without which the lane polygon (``geometry.lane_ring``) has
    less area. Removing it takes off the triangle path[k-1], path[k], path[k+1] (shoelace,
    ``geometry.signed_area``); the polygon shrinks when that triangle turns the way the whole
    polygon does: the cone lies outside the chord path[k-1] -> path[k+1], and the lane without
    it is narrower there, never wider. For a lane whose left boundary lies to the left (a
    clockwise polygon), the boundary turns toward the lane at such a cone
    (``geometry.turn_angles``: right on the left boundary, left on the right one). Only when an
    edge of the search graph joins the two neighbours and the lane satisfies the shared
    predicates (``lane_is_feasible``; ``check=False`` leaves that to the caller, who may need
    it for one lane only). Our addition, docs/clc.md.

    A false positive inserted between two true cones of a boundary, or taken in their place
    a little off the line, earns the edge benefit of RLD's objective, and the dives, which
    change one choice of the search at a time, often do not return the lane without it. A
    cone bending the boundary *into* the lane is never dropped: true cones do that at a
    hairpin's apex, where the judge would rather cut the corner (and a lane without such a
    cone would lead the car over it)."""
    paths = [np.ascontiguousarray(left, dtype=np.int64),
             np.ascontiguousarray(right, dtype=np.int64)]
    orient = np.sign(geo.signed_area(geo.lane_ring(points[paths[0]], points[paths[1]])))
    out = []
    if orient == 0:
        return out
    pts = np.ascontiguousarray(points, dtype=np.float64)
    for side, p in enumerate(paths):
        head = within_radius(points, p, pose, reach_m).size
        # The right boundary runs backwards in the ring, so its triangles turn the other way.
        ks = sk.outward_positions(pts, graph.indptr, graph.indices, p, head,
                                  1.0 if side == 0 else -1.0, float(orient))
        for k in ks.tolist():  # the neighbours are joined (the kernel checked the edge)
            out += _drop(points, params, graph, paths, side, k, check)
    return out


def skip_inserts(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
                 left: np.ndarray, right: np.ndarray, reach_m: float,
                 check: bool = True) -> list[tuple[np.ndarray, np.ndarray]]:
    """The lanes made from ``left``, ``right`` by taking in a skipped cone: for every edge
    path[j-1] -> path[j] of a boundary within ``reach_m`` of path ahead of the car that passes
    a cone in neither boundary, a search-graph neighbour of path[j-1] and of path[j] whose
    closest point on the edge is inside it and at most ``params.skipped_cone_m`` away
    (``search_kernels.skipped_cones``, which also gives the skipped-cone trigger of
    ``contested_dives``), the lane with the nearest such cone between the two. Only lanes
    that satisfy the shared predicates (``lane_is_feasible``) are returned. Our addition,
    docs/clc.md.

    A skipped-cone dive forbids path[j] after path[j-1], but the search then takes the
    decider's best option there, which need not be the skipped cone; this offers the judge
    the lane with it directly, as ``pair_drops`` offers the lane without one cone of a close
    pair."""
    if params.skipped_cone_m <= 0:
        return []
    paths = [np.ascontiguousarray(left, dtype=np.int64),
             np.ascontiguousarray(right, dtype=np.int64)]
    out = []
    for side, p in enumerate(paths):
        reach = float(reach_m) + _arc_behind(points, p, pose)
        pos, cones = sk.skipped_cones(points, graph.indptr, graph.indices, p, paths[1 - side],
                                      float(params.skipped_cone_m), reach)
        for j, v in zip(pos, cones, strict=True):
            if v < 0:
                continue
            trial = list(paths)
            trial[side] = np.insert(p, j, v)
            if not check or lane_is_feasible(points[trial[0]], points[trial[1]], params):
                out.append((trial[0], trial[1]))
    return out


def start_replacements(points: np.ndarray, pose: Pose, params: LaneParams,
                       graph: SearchGraph, left: np.ndarray, right: np.ndarray,
                       inside_m: float, pair_m: float = 0.0, check: bool = True
                       ) -> list[tuple[np.ndarray, np.ndarray]]:
    """The lanes made from ``left``, ``right`` by replacing a boundary's first cone with a cone
    inside the lane beside its first edge: a search-graph neighbour of the boundary's second
    cone, in neither boundary, on the car's side of that boundary (left of the car for the
    left one, by the car's heading, as ``find_starting_vertices`` takes them), whose closest
    point on the first edge lies inside the edge and which lies on the lane's side of it, at
    most ``inside_m`` metres from it, and more than ``pair_m`` metres from the second cone (a
    cone that close to it is one of a close pair, ``pair_drops``' business). Only lanes that
    satisfy the shared predicates (``lane_is_feasible``) are returned. Our addition,
    docs/clc.md.

    The start pair is the most symmetric about the car (IV-C), so when the car is off the
    lane's centre a cone outside the boundary on the far side can pair better than the true
    first cone, which the lane then leaves inside it (track 3 of the shared dataset, pose 38,
    an unlabelled cone 1.5 m outside the right boundary). A true boundary leaves no cone
    inside the lane beside it; this offers the judge the lane that starts at that cone."""
    if inside_m <= 0:
        return []
    paths = [np.ascontiguousarray(left, dtype=np.int64),
             np.ascontiguousarray(right, dtype=np.int64)]
    pts = np.ascontiguousarray(points, dtype=np.float64)
    h = pose.heading
    out = []
    for side, p in enumerate(paths):
        if p.size < 2:
            continue
        # The rule in one compiled loop over the second cone's neighbours.
        cones = sk.start_replacement_cones(
            pts, graph.indptr, graph.indices, p, paths[1 - side], side == 0,
            float(pose.x), float(pose.y), float(h[0]), float(h[1]), float(inside_m),
            float(pair_m))
        for v in cones.tolist():
            trial = list(paths)
            trial[side] = np.concatenate([[v], p[1:]])
            if not check or lane_is_feasible(points[trial[0]], points[trial[1]], params):
                out.append((trial[0], trial[1]))
    return out


def trim_behind(points: np.ndarray, pose: Pose, params: LaneParams, left: np.ndarray,
                right: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """An open lane without the cones that begin a boundary behind the car
    (``geometry.leading_behind``: up to its first cone not behind the car, keeping at least
    two cones a side), when the lane without them still satisfies the shared predicates
    (``lane_is_feasible``): both sides trimmed, else the left alone, else the right alone,
    else the lane unchanged. Returns (left, right, cones trimmed). Our addition, docs/clc.md.

    The search starts each boundary at a start vertex (IV-C), which may lie up to
    ``LaneParams.start_behind_m`` behind the car, and the judge (RLD's objective, which pays a
    benefit for every edge) prefers a lane with one more edge there, whether its cone is the
    true one before the car or a false positive beside it. A cone behind the car tells a
    planner nothing about the lane ahead; the protocol's true lane begins at the first cone not
    behind the car (DESIGN.md step 5), and a false positive behind it is a lane that leaves
    the truth at the car. The lane ahead of the car is unchanged."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    cut = [geo.leading_behind(points[p], pose.xy, pose.heading) for p in paths]
    for take in ((True, True), (True, False), (False, True)):
        k = [c if t else 0 for c, t in zip(cut, take, strict=True)]
        if sum(k) == 0:
            continue
        trial = [p[j:] for p, j in zip(paths, k, strict=True)]
        if lane_is_feasible(points[trial[0]], points[trial[1]], params):
            return trial[0], trial[1], sum(k)
    return paths[0], paths[1], 0


def unhook(points: np.ndarray, params: LaneParams, left: np.ndarray,
           right: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """An open lane with a boundary's hook (``rld.constraints.hook_position``) undone: the hooked
    cones given to the other boundary, as the shared predicates allow; returns (left, right,
    cones moved or cut). Our addition: docs/clc.md, "Hooks undone (unhook)"."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    for a in (0, 1):
        own, other = paths[a], paths[1 - a]
        j = hook_position(points[own], points[other], params.max_cone_spacing_m)
        if j < 0:
            continue
        tail = own[j:]
        for give in (tail.size, 1, 0):
            trial = [None, None]
            trial[a], trial[1 - a] = own[:j], np.concatenate([other, tail[:give]])
            if lane_is_feasible(points[trial[0]], points[trial[1]], params):
                return trial[0], trial[1], int(tail.size)
    return paths[0], paths[1], 0


def drop_ring_join(points: np.ndarray, pose: Pose, params: LaneParams, graph: SearchGraph,
                   left: np.ndarray, right: np.ndarray) -> tuple[np.ndarray, np.ndarray, int]:
    """Drop the first cone of a boundary of a *closed* lane when RLD's objective of the closed
    lane (eq. 29, ``rld.costs.lane_cost(closed=True)``) is lower without it and the ring
    without it is still a lane (an edge of the search graph joins the ring's last cone to its
    second, and ``lane_is_feasible(closed=True)`` holds). Our addition, docs/clc.md.

    The search starts each boundary at a start vertex (IV-C). When a false positive beside the
    car pairs better with the other side than the true cone next to it, the closed lane keeps
    it as a detour between the boundary's last true cone and its first one: the ring's join,
    which the open-lane ``outward_drops`` does not see. Only the terms around the join change
    (the edges into and out of the cone, the turns at it and at its two neighbours), so the
    objective's change is computed on the five cones around it (``open_path_costs``); rings of
    fewer than five cones are left alone. Each side once, left first; returns (left, right,
    cones dropped)."""
    paths = [np.asarray(left, dtype=np.int64), np.asarray(right, dtype=np.int64)]
    dropped = 0
    for side in (0, 1):
        p = paths[side]
        if p.size < 5 or not graph.has_edge(int(p[-1]), int(p[1])):
            continue
        if ring_join_change(points, pose, params, p) >= -1e-9:
            continue
        trial = list(paths)
        trial[side] = p[1:]
        if lane_is_feasible(points[trial[0]], points[trial[1]], params, closed=True):
            paths, dropped = trial, dropped + 1
    return paths[0], paths[1], dropped


def ring_join_change(points: np.ndarray, pose: Pose, params: LaneParams,
                     ring: np.ndarray) -> float:
    """The change of RLD's objective (eq. 29) of a closed boundary ``ring`` (five cones or
    more) when its first cone is dropped: the terms around it, the edges into and out of it,
    the turns at it and at its two neighbours, against the edge and turns that replace them
    (``open_path_costs`` over the five cones around it and the four without it). Equal to
    the change of ``lane_cost(closed=True)``, which sums the same terms over the whole ring."""
    p = np.asarray(ring, dtype=np.int64)
    if p.size < 5:
        raise ValueError(f"a ring of at least five cones is needed, got {p.size}")
    seqs = np.array([p[-2], p[-1], p[0], p[1], p[2], p[-2], p[-1], p[1], p[2]])
    cost = open_path_costs(points, seqs, np.array([0, 5, 9]), pose, params)
    return float(cost[1] - cost[0])

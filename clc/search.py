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

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import Delaunay

from clc import search_kernels as sk
from rld.colors import SIDE_LEFT, SIDE_RIGHT
from rld.constraints import candidate_edges, find_starting_vertices, lane_is_feasible
from rld.costs import color_cost, ranking_features
from rld.types import LaneParams, Pose

__all__ = ["SearchGraph", "SearchResult", "CandidateList", "closable", "merge_results",
           "search_graph", "color_penalties", "enumerate_candidates", "GRAPHS"]

#: Search-graph constructions: ``radius`` (IV-A, the paper's choice) and ``delaunay`` (IV-B).
GRAPHS = ("radius", "delaunay")
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
    colors: np.ndarray | None = None,
) -> SearchResult:
    """CLC Alg. 1 up to the ranking: graph, start vertices, Alg. 2, closings.

    ``points`` (N, 2) metres (validated by the caller); ``max_iterations``: it_max (None:
    ``params.max_iterations``; 0: no limit); ``start``: force the start vertices;
    ``guide``: the warm-start lane (left, right index arrays in ``points``), followed first.
    ``close_loops``: add the closing of every closable candidate (IV-E) as a further candidate;
    ``clc.solver`` closes only the ranked winner instead (see there). ``banned``: cones no path
    may take (indices into ``points``); ``forbid``: a cone per side (-1: none) that may not
    come right after that side's whole guide, only later (``clc.refine.dive_at``).
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
        int(forbid[0]), int(forbid[1]), g.dead_end(params), True,
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

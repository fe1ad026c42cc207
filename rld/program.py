"""The RLD binary integer program (Brandes et al. 2020, section II) as solver-neutral arrays.

``build_program`` turns cones and a pose into a ``LaneProgram``: an objective vector, a sparse
constraint matrix with row bounds, and 0/1 column bounds, every column binary. Backends
(``rld.backends``) only load these arrays, solve, and hand back a 0/1 vector; ``extract_paths``
turns that into two boundaries.

Columns, in this order (each block may be empty):

- ``a`` (E): edge variables a_ij for the candidate edges (eqs 1-9, 29);
- ``f`` (T): angle variables f_ijk for pairs of candidate edges meeting at a cone (eq. 21);
- ``g`` (N): inlier-cone variables (eqs 1-2);
- ``m`` (N): endpoint variables, the paper's m_i = 2 g_i - A_i (eq. 10), kept as columns so
  the endpoint constraints are short rows.

Every family of rows comes from the shared constraint and cost modules; docs/formulation.md maps
each row family to its equation and states where we deviate. In short: eq. 7 is read with ``<``;
eq. 9 as ``h^T a >= 2`` (eq. 33); eq. 4 is implied by eq. 3 and left out; eqs 12-17 (the far
endpoints at most d_max apart) become pairwise rows m_i + m_j <= 1; eqs 27-28 and the spacing
limit are applied by not creating the variables ("exact pruning"), with a row a_ij + a_jk <= 1
wherever a pruned angle variable would have had to be 0; eq. 5 is added lazily, for the cycles
a solution actually contains.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import scipy.sparse as sp

from rld import constraints as cons
from rld import costs
from rld.types import LaneParams, Pose

__all__ = ["LaneProgram", "build_program", "cycle_cut", "lane_cut", "extract_paths",
           "ROW_FAMILIES"]

ROW_FAMILIES = (
    "inlier_lower",  # eq. 1: g_i - A_i <= 0
    "inlier_upper",  # eq. 2: A_i - 2 g_i <= 0 (degree <= 2)
    "endpoint_def",  # eq. 10: m_i - 2 g_i + A_i = 0
    "four_endpoints",  # eq. 3: sum m_i = 4
    "near_endpoints",  # eq. 11: sum r_i m_i = 2
    "far_endpoints",  # eqs 12-17: m_i + m_j <= 1 for far cones more than d_max apart
    "heading",  # eq. 9 / 33: h^T a >= 2
    "width_conflict",  # eqs 6-8: a_e + a_f <= 1
    "crossing",  # section V: a_e + a_f <= 1 for crossing edges
    "turn_limit",  # eq. 28 on pruned f: a_ij + a_jk <= 1
    "angle_link",  # eqs 22-23: 2 f - a_ij - a_jk <= 0 and f - a_ij - a_jk >= -1
    "cycle_cut",  # eq. 5, lazily
    "lane_cut",  # our addition, lazily: exactly a lane the shared predicate rejects
    "fixed_start",  # optional: the near endpoints are given (cross-check with CLC)
    "angle_cover",  # valid equalities tying f to g, m and a (our strengthening)
    # The sided formulation (our extension):
    "two_endpoints",  # per side: sum m = 2
    "one_side",  # g_L + g_R <= 1
    "vertex_min_width",  # g_L_i + g_R_j <= 1 for cones closer than w_min
    "vertex_max_width",  # g_s_i <= sum of g_other_j within w_max
)


@dataclass(eq=False)
class LaneProgram:
    """One instance of the RLD program over ``points`` (the cones it was built from).

    ``c`` is the objective (minimised); ``A`` (rows x columns, CSR) with ``row_lo <= A x <=
    row_hi``; columns are binary with bounds ``col_lo``, ``col_hi``. ``family`` names each row's
    family (see ``ROW_FAMILIES``). ``edges``, ``triples``, ``turns`` describe the ``a`` and ``f``
    columns; ``near`` is the mask r of eq. 11.
    """

    points: np.ndarray
    pose: Pose
    params: LaneParams
    edges: np.ndarray
    triples: np.ndarray
    turns: np.ndarray
    near: np.ndarray
    c: np.ndarray
    A: sp.csr_matrix
    row_lo: np.ndarray
    row_hi: np.ndarray
    col_lo: np.ndarray
    col_hi: np.ndarray
    family: np.ndarray
    sided: bool = False
    stats: dict = field(default_factory=dict)

    @property
    def n_edges(self) -> int:
        return int(self.edges.shape[0])

    @property
    def n_cones(self) -> int:
        return int(self.points.shape[0])

    @property
    def n_cols(self) -> int:
        return int(self.c.shape[0])

    @property
    def n_rows(self) -> int:
        return int(self.A.shape[0])

    def block(self, name: str, side: int = 0) -> slice:
        """The column slice of block ``a``, ``f``, ``g`` or ``m``; of side 0 (left) or 1
        (right) in the sided formulation."""
        E, T, N = self.n_edges, int(self.triples.shape[0]), self.n_cones
        starts = {"a": 0, "f": E, "g": E + T, "m": E + T + N}
        sizes = {"a": E, "f": T, "g": N, "m": N}
        base = side * (E + T + 2 * N)
        return slice(base + starts[name], base + starts[name] + sizes[name])

    def edge_ids(self, a, b) -> np.ndarray:
        """Index (within block ``a``) of the candidate edge joining cone ``a[i]`` and cone
        ``b[i]`` (program indices, either order), -1 where the program has no such edge."""
        a, b = np.asarray(a, dtype=np.int64), np.asarray(b, dtype=np.int64)
        out = np.full(a.shape, -1, dtype=np.int64)
        if self.n_edges == 0 or a.size == 0:
            return out
        n = self.n_cones
        keys = self.edges[:, 0] * n + self.edges[:, 1]
        order = np.argsort(keys, kind="stable")
        sorted_keys = keys[order]
        q = np.minimum(a, b) * n + np.maximum(a, b)
        pos = np.minimum(np.searchsorted(sorted_keys, q), sorted_keys.size - 1)
        hit = sorted_keys[pos] == q
        out[hit] = order[pos[hit]]
        return out

    def objective(self, x: np.ndarray) -> float:
        return float(self.c @ x)

    def is_feasible(self, x: np.ndarray, tol: float = 1e-6) -> bool:
        """Whether the 0/1 vector ``x`` satisfies every row and column bound."""
        ax = self.A @ x
        return bool(
            np.all(ax >= self.row_lo - tol)
            and np.all(ax <= self.row_hi + tol)
            and np.all(x >= self.col_lo - tol)
            and np.all(x <= self.col_hi + tol)
        )

    def add_rows(self, A: sp.spmatrix, lo: np.ndarray, hi: np.ndarray, family: str) -> None:
        """Append rows (used for the lazy cycle cuts)."""
        self.A = sp.vstack([self.A, sp.csr_matrix(A)], format="csr")
        self.row_lo = np.concatenate([self.row_lo, lo])
        self.row_hi = np.concatenate([self.row_hi, hi])
        self.family = np.concatenate([self.family, np.full(len(lo), family, dtype=object)])

    def solution_from_edges(self, chosen: np.ndarray, right: np.ndarray | None = None
                            ) -> np.ndarray:
        """The full 0/1 column vector implied by chosen edge indices (for hints and tests):
        a, then f, g and m derived from them. In the sided formulation ``chosen`` are the left
        edges and ``right`` the right ones."""
        x = np.zeros(self.n_cols)
        sets = [chosen] if not self.sided else [chosen, [] if right is None else right]
        for side, ids in enumerate(sets):
            a = np.zeros(self.n_edges)
            a[np.asarray(ids, dtype=np.int64)] = 1.0
            x[self.block("a", side)] = a
            if self.triples.shape[0]:
                x[self.block("f", side)] = a[self.triples[:, 3]] * a[self.triples[:, 4]]
            deg = np.bincount(self.edges[a > 0].ravel(), minlength=self.n_cones)
            x[self.block("g", side)] = deg > 0
            x[self.block("m", side)] = deg == 1
        return x


class _Rows:
    """Accumulates sparse rows as COO triplets."""

    def __init__(self) -> None:
        self.r: list[np.ndarray] = []
        self.c: list[np.ndarray] = []
        self.v: list[np.ndarray] = []
        self.lo: list[np.ndarray] = []
        self.hi: list[np.ndarray] = []
        self.fam: list[np.ndarray] = []
        self.n = 0

    def add(self, rows, cols, vals, lo, hi, family: str) -> None:
        """``rows`` are local row numbers 0..k-1 of this batch; scalar bounds apply to all k
        (k counts the row numbers too, so a scalar bound never drops a row)."""
        lo = np.atleast_1d(np.asarray(lo, dtype=np.float64))
        hi = np.atleast_1d(np.asarray(hi, dtype=np.float64))
        rows = np.asarray(rows, dtype=np.int64)
        k = max(lo.size, hi.size, int(rows.max()) + 1 if rows.size else 0)
        if k == 0:
            return
        self.r.append(rows + self.n)
        self.c.append(np.asarray(cols, dtype=np.int64))
        self.v.append(np.asarray(vals, dtype=np.float64))
        self.lo.append(np.broadcast_to(lo, (k,)).copy())
        self.hi.append(np.broadcast_to(hi, (k,)).copy())
        self.fam.append(np.full(k, family, dtype=object))
        self.n += k

    def add_pairs(self, cols_a, cols_b, hi: float, family: str) -> None:
        """Rows x_a + x_b <= hi."""
        k = len(cols_a)
        if k == 0:
            return
        rows = np.repeat(np.arange(k), 2)
        cols = np.column_stack([cols_a, cols_b]).ravel()
        self.add(rows, cols, np.ones(2 * k), -np.inf, np.full(k, hi), family)

    def build(self, n_cols: int):
        if self.n == 0:
            return (sp.csr_matrix((0, n_cols)), np.zeros(0), np.zeros(0),
                    np.zeros(0, dtype=object))
        A = sp.csr_matrix(
            (np.concatenate(self.v), (np.concatenate(self.r), np.concatenate(self.c))),
            shape=(self.n, n_cols),
        )
        A.sum_duplicates()
        return A, np.concatenate(self.lo), np.concatenate(self.hi), np.concatenate(self.fam)


def build_program(
    points: np.ndarray,
    pose: Pose,
    params: LaneParams,
    *,
    no_crossing: bool = True,
    start: tuple[int, int] | None = None,
    prune: bool = True,
    strengthen: bool = True,
    sided: bool = False,
    colors: np.ndarray | None = None,
    confidence: np.ndarray | None = None,
    heading: bool = True,
) -> LaneProgram:
    """Build the RLD program over ``points`` (N, 2) for the car at ``pose``.

    ``no_crossing`` adds the pairwise no-crossing rows (the paper's section V extension).
    ``start`` fixes the two near endpoints (cone indices), as CLC's starting vertices.
    ``prune=False`` builds the paper's dense model instead (all cone pairs as edge variables,
    all edge pairs at a cone as angle variables, the spacing limit and eqs 27-28 as rows); it
    exists to test that pruning is exact. ``strengthen`` adds valid equalities that tie the
    angle variables to the cones (``angle_cover``; they cut no lane graph off, and make the
    relaxation pay the angle costs). ``sided`` builds our side-aware formulation: a set of
    columns per side, each side one path starting near the car on its own side, and the lane
    width bounded at the cones (see docs/formulation.md). ``colors`` (``rld.colors`` side
    labels) and ``confidence`` (0..1) per cone add the colour cost (``costs.boundary_color_cost``:
    its terms on the edge, angle, cone and near endpoint columns) and the confidence cost.
    ``heading=False`` drops the heading row (eq. 9 / 33) and the heading cost (eq. 25): for a
    program whose start is fixed together with its first edges (``rld.incremental``'s
    frontier), which give the direction that the heading terms stand in for.
    """
    points = np.ascontiguousarray(points, dtype=np.float64)
    N = points.shape[0]
    p = params
    if prune:
        edges = cons.candidate_edges(points, p.max_cone_spacing_m)
    else:
        ii, jj = np.triu_indices(N, k=1)
        edges = np.column_stack([ii, jj]).astype(np.int64)
    lengths = cons.edge_lengths(points, edges)
    s_cost = costs.spacing_cost(lengths, p.expected_spacing_m, p.spacing_tolerance_m)
    edge_bad = (lengths > p.max_cone_spacing_m) | costs.high_cost_mask(s_cost, p.max_spacing_cost)
    if start is not None:  # a fixed start's first edges run ahead (cons.first_edges_ahead)
        edge_bad |= _backward_from(points, edges, start, pose, p.max_turn_angle_rad)
    if prune:
        edges, lengths, s_cost = edges[~edge_bad], lengths[~edge_bad], s_cost[~edge_bad]
        edge_bad = edge_bad[~edge_bad]
    E = edges.shape[0]
    all_triples, all_turns = cons.angle_triples(points, edges)
    t_cost = costs.angle_cost(all_turns, p.angle_tolerance_rad)
    turn_bad = ~cons.turn_within_limit(all_turns, p.max_turn_angle_rad) | costs.high_cost_mask(
        t_cost, p.max_angle_cost
    )
    if prune:
        keep = ~turn_bad
        triples, turns, t_cost_kept = all_triples[keep], all_turns[keep], t_cost[keep]
        forbidden_pairs = all_triples[turn_bad]
    else:
        triples, turns, t_cost_kept = all_triples, all_turns, t_cost
        forbidden_pairs = all_triples[:0]
    T = triples.shape[0]
    near = cons.start_mask(points, pose, p.near_radius_m, p.start_reach_m)
    if start is not None:
        near = np.zeros(N, dtype=bool)
        near[list(start)] = True
    # A side's first cone beyond the near radius (start_mask): its edges count for eq. 9.
    first = np.flatnonzero(near & ~cons.near_car_mask(points, pose, p.near_radius_m))
    edge_cost = costs.edge_objective(points, edges, pose, p, heading=heading)
    if colors is not None:
        edge_cost = edge_cost + p.w_color * costs.color_edge_cost(colors, edges)
    cone_cost = np.zeros(N)
    if colors is not None and p.color_unknown:
        cone_cost += p.w_color * p.color_unknown * costs.color_unknown_cost(colors)
    if confidence is not None:
        cone_cost += p.w_confidence * costs.confidence_cost(confidence)
    h = np.flatnonzero(cons.heading_mask(points, edges, pose, p.heading_radius_m,
                                         p.heading_tolerance_rad, first)) if heading else None
    wc = cons.width_conflicts(points, edges, p.min_width_m)
    cr = cons.crossing_edge_pairs(points, edges) if no_crossing else np.zeros((0, 2), int)
    # Far cone pairs that may not both be far endpoints (eqs 12-17).
    far = np.flatnonzero(~near)
    fi, fj = np.triu_indices(far.size, k=1)
    fi, fj = far[fi], far[fj]
    apart = np.hypot(*(points[fi] - points[fj]).T) > p.far_endpoint_max_m
    fi, fj = fi[apart], fj[apart]

    n_sets = 2 if sided else 1
    size = E + T + 2 * N
    n_cols = n_sets * size
    c = np.zeros(n_cols)
    rows = _Rows()
    blocks = []
    for k in range(n_sets):
        a0 = k * size
        f0, g0, m0 = a0 + E, a0 + E + T, a0 + E + T + N
        blocks.append((a0, f0, g0, m0))
        c[a0:f0] = edge_cost
        c[f0:g0] = p.w_angle * t_cost_kept
        if p.w_regularity:
            c[f0:g0] += p.w_regularity * costs.regularity_cost(
                lengths[triples[:, 3]], lengths[triples[:, 4]], p.regularity_tolerance)
        c[g0:m0] = cone_cost
        if colors is not None:
            c[f0:g0] += p.w_color * costs.color_skip_cost(colors, triples)
            c[m0:m0 + N] += p.w_color * near * costs.color_start_cost(points, colors, pose)
        _path_rows(rows, edges, triples, forbidden_pairs, N, a0, f0, g0, m0, strengthen)
    if not sided:
        a0, f0, g0, m0 = blocks[0]
        # eq. 3: sum_i (A_i - 2 g_i) = -4, i.e. sum_i m_i = 4 (eq. 4 is the same sum as an
        # inequality and is implied).
        rows.add(np.zeros(N), m0 + np.arange(N), np.ones(N), 4.0, 4.0, "four_endpoints")
        # eq. 11: r^T m = 2
        nz = np.flatnonzero(near)
        rows.add(np.zeros(nz.size), m0 + nz, np.ones(nz.size), 2.0, 2.0, "near_endpoints")
        if start is not None:
            rows.add(np.arange(2), m0 + np.array(start), np.ones(2), np.ones(2), np.ones(2),
                     "fixed_start")
        # eqs 12-17: the two far endpoints are at most far_endpoint_max_m apart.
        rows.add_pairs(m0 + fi, m0 + fj, 1.0, "far_endpoints")
        # eq. 9 / 33: at least two edges near the car along the heading.
        if h is not None:
            rows.add(np.zeros(h.size), a0 + h, np.ones(h.size), 2.0, np.inf, "heading")
        # eqs 6-8: minimum width.
        rows.add_pairs(a0 + wc[:, 0], a0 + wc[:, 1], 1.0, "width_conflict")
        rows.add_pairs(a0 + cr[:, 0], a0 + cr[:, 1], 1.0, "crossing")
    else:
        _sided_rows(rows, points, pose, p, blocks, near, start, h, wc, cr, fi, fj)
    A, lo, hi, fam = rows.build(n_cols)
    col_lo = np.zeros(n_cols)
    col_hi = np.ones(n_cols)
    if not prune:
        # The dense model states the spacing limit, eq. 27 and eq. 28 as constraints.
        for a0, f0, g0, _ in blocks:
            col_hi[a0:f0][edge_bad] = 0.0
            col_hi[f0:g0][turn_bad] = 0.0
    return LaneProgram(
        points=points, pose=pose, params=p, edges=edges, triples=triples, turns=turns,
        near=near, c=c, A=A, row_lo=lo, row_hi=hi, col_lo=col_lo, col_hi=col_hi, family=fam,
        sided=sided,
        stats={"n_cols": n_cols, "n_rows": int(A.shape[0]), "n_edges": E, "n_angles": T},
    )


def _path_rows(rows: _Rows, edges, triples, forbidden_pairs, N, a0, f0, g0, m0,
               strengthen: bool) -> None:
    """The rows that make one set of edge columns a set of paths with consistent inlier,
    endpoint and angle columns (eqs 1, 2, 10, 22, 23, 28 and the angle-cover rows)."""
    E, T = edges.shape[0], triples.shape[0]
    # Incidence of edges on cones: A_i = sum of a_e over e containing i.
    inc_r = edges.ravel()  # cone of each (edge, end)
    inc_c = np.repeat(np.arange(E), 2) + a0
    # eq. 1: g_i - A_i <= 0
    rows.add(np.concatenate([np.arange(N), inc_r]), np.concatenate([g0 + np.arange(N), inc_c]),
             np.concatenate([np.ones(N), -np.ones(2 * E)]), -np.inf, np.zeros(N), "inlier_lower")
    # eq. 2 (times 2): A_i - 2 g_i <= 0
    rows.add(np.concatenate([np.arange(N), inc_r]), np.concatenate([g0 + np.arange(N), inc_c]),
             np.concatenate([-2 * np.ones(N), np.ones(2 * E)]), -np.inf, np.zeros(N),
             "inlier_upper")
    # eq. 10: m_i - 2 g_i + A_i = 0
    rows.add(np.concatenate([np.arange(N), np.arange(N), inc_r]),
             np.concatenate([m0 + np.arange(N), g0 + np.arange(N), inc_c]),
             np.concatenate([np.ones(N), -2 * np.ones(N), np.ones(2 * E)]),
             np.zeros(N), np.zeros(N), "endpoint_def")
    # eq. 28 on pruned angle variables: the two edges cannot both be chosen.
    rows.add_pairs(a0 + forbidden_pairs[:, 3], a0 + forbidden_pairs[:, 4], 1.0, "turn_limit")
    if T == 0:
        return
    # eqs 22-23: f = a_ij * a_jk.
    k = np.arange(T)
    r3 = np.repeat(k, 3)
    cols = np.column_stack([f0 + k, a0 + triples[:, 3], a0 + triples[:, 4]]).ravel()
    rows.add(r3, cols, np.tile([2.0, -1.0, -1.0], T), -np.inf, np.zeros(T), "angle_link")
    rows.add(r3, cols, np.tile([1.0, -1.0, -1.0], T), -np.ones(T), np.inf, "angle_link")
    if not strengthen:
        return
    # Valid equalities that tie f to the cones (our addition; the LP relaxation of eqs 22-23
    # alone lets f = 0 with both edges at 1/2, so the angle costs vanish from the bound). An
    # interior cone (g = 1, m = 0) has exactly one chosen pair of edges, an endpoint or unused
    # cone none: sum_{t at j} f_t = g_j - m_j. A chosen edge e at a cone j that is not an
    # endpoint is in exactly one chosen pair there, and never in two:
    # a_e - m_j <= sum_{t at j, e in t} f_t <= a_e.
    centre = triples[:, 1]
    rows.add(np.concatenate([centre, np.arange(N), np.arange(N)]),
             np.concatenate([f0 + np.arange(T), g0 + np.arange(N), m0 + np.arange(N)]),
             np.concatenate([np.ones(T), -np.ones(N), np.ones(N)]),
             np.zeros(N), np.zeros(N), "angle_cover")
    inc_edge = np.concatenate([triples[:, 3], triples[:, 4]])
    inc_cone = np.concatenate([centre, centre])
    inc_f = np.concatenate([np.arange(T), np.arange(T)])
    pairs, row_of = np.unique(np.column_stack([inc_cone, inc_edge]), axis=0,
                              return_inverse=True)
    row_of = row_of.ravel()
    K = pairs.shape[0]
    kk = np.arange(K)
    rows.add(np.concatenate([row_of, kk]), np.concatenate([f0 + inc_f, a0 + pairs[:, 1]]),
             np.concatenate([np.ones(row_of.size), -np.ones(K)]), -np.inf, np.zeros(K),
             "angle_cover")
    rows.add(np.concatenate([row_of, kk, kk]),
             np.concatenate([f0 + inc_f, a0 + pairs[:, 1], m0 + pairs[:, 0]]),
             np.concatenate([np.ones(row_of.size), -np.ones(K), np.ones(K)]),
             np.zeros(K), np.inf, "angle_cover")


def _backward_from(points, edges, start, pose: Pose, max_turn_rad: float) -> np.ndarray:
    """Edges at a start cone leaving it more than ``max_turn_rad`` off the car's heading,
    boolean (E,): CLC's first-edge rule (``cons.first_edges_ahead``) as columns (ours)."""
    bad = np.zeros(edges.shape[0], dtype=bool)
    h = pose.heading
    for s in start:
        for a, b in ((0, 1), (1, 0)):
            at = edges[:, a] == s
            d = points[edges[at, b]] - points[s]
            turn = np.abs(np.arctan2(h[0] * d[:, 1] - h[1] * d[:, 0], d @ h))
            bad[np.flatnonzero(at)[turn > max_turn_rad]] = True
    return bad


def _sided_rows(rows: _Rows, points, pose, p, blocks, near, start, h, wc, cr, fi, fj) -> None:
    """The side-aware formulation (our extension): one path per side, each starting near the
    car on its own side, the lane width bounded at the cones. See docs/formulation.md."""
    N = points.shape[0]
    (aL, _, gL, mL), (aR, _, gR, mR) = blocks
    lateral = pose.to_local(points)[:, 1]
    if start is not None:
        near_sides = [np.array([start[0]]), np.array([start[1]])]
    else:
        near_sides = [np.flatnonzero(near & (lateral > 0)), np.flatnonzero(near & (lateral < 0))]
    for (a0, _, _, m0), nz in zip(blocks, near_sides, strict=True):
        # Each side is one path: two endpoints (eq. 3 per side), one of them near the car on
        # its own side (eq. 11 per side), with an edge along the heading near the car (eq. 9).
        rows.add(np.zeros(N), m0 + np.arange(N), np.ones(N), 2.0, 2.0, "two_endpoints")
        rows.add(np.zeros(nz.size), m0 + nz, np.ones(nz.size), 1.0, 1.0, "near_endpoints")
        if h is not None:
            rows.add(np.zeros(h.size), a0 + h, np.ones(h.size), 1.0, np.inf, "heading")
    # A cone belongs to one side at most.
    rows.add_pairs(gL + np.arange(N), gR + np.arange(N), 1.0, "one_side")
    # eqs 12-17: the far endpoints (one per side) at most d_max apart.
    rows.add_pairs(mL + fi, mR + fj, 1.0, "far_endpoints")
    rows.add_pairs(mR + fi, mL + fj, 1.0, "far_endpoints")
    # eqs 6-8 across the sides.
    rows.add_pairs(aL + wc[:, 0], aR + wc[:, 1], 1.0, "width_conflict")
    rows.add_pairs(aR + wc[:, 0], aL + wc[:, 1], 1.0, "width_conflict")
    # No crossing, whatever the sides: the two edges' four columns sum to at most 1.
    if cr.shape[0]:
        k = cr.shape[0]
        cols = np.column_stack([aL + cr[:, 0], aR + cr[:, 0], aL + cr[:, 1], aR + cr[:, 1]])
        rows.add(np.repeat(np.arange(k), 4), cols.ravel(), np.ones(4 * k), -np.inf,
                 np.ones(k), "crossing")
    # The width at the cones: a left and a right cone closer than w_min cannot both be used;
    # every used cone has a cone of the other side within w_max.
    d = np.hypot(*(points[:, None, :] - points[None, :, :]).transpose(2, 0, 1))
    np.fill_diagonal(d, np.inf)
    ci, cj = np.nonzero(d < p.min_width_m)
    rows.add_pairs(gL + ci, gR + cj, 1.0, "vertex_min_width")
    wi, wj = np.nonzero(d <= p.max_width_m)
    for g_self, g_other in ((gL, gR), (gR, gL)):
        rows.add(np.concatenate([np.arange(N), wi]),
                 np.concatenate([g_self + np.arange(N), g_other + wj]),
                 np.concatenate([np.ones(N), -np.ones(wi.size)]), -np.inf, np.zeros(N),
                 "vertex_max_width")


def _components(n: int, edges: np.ndarray) -> list[list[int]]:
    """Connected components (lists of cones) of the graph of ``edges`` with at least one edge."""
    adj: list[list[int]] = [[] for _ in range(n)]
    for i, j in edges:
        adj[i].append(int(j))
        adj[j].append(int(i))
    seen = np.zeros(n, dtype=bool)
    comps = []
    for s in range(n):
        if seen[s] or not adj[s]:
            continue
        stack, comp = [s], []
        seen[s] = True
        while stack:
            v = stack.pop()
            comp.append(v)
            for w in adj[v]:
                if not seen[w]:
                    seen[w] = True
                    stack.append(w)
        comps.append(sorted(comp))
    return comps


def cycle_cut(program: LaneProgram, cones: list[int]) -> None:
    """Add RLD eq. 5 for the cone set ``cones``: at most |S| - 1 edges inside S."""
    S = np.zeros(program.n_cones, dtype=bool)
    S[cones] = True
    inside = np.flatnonzero(S[program.edges[:, 0]] & S[program.edges[:, 1]])
    # In the sided formulation both sides' edges inside S count: two paths have even fewer.
    cols = np.concatenate([program.block("a", k).start + inside
                           for k in range(2 if program.sided else 1)])
    _add_lazy_row(program, cols, np.ones(cols.size), len(cones) - 1.0, "cycle_cut")


def _add_lazy_row(program: LaneProgram, cols: np.ndarray, coef: np.ndarray, hi: float,
                  family: str) -> None:
    """Append one row ``coef . x[cols] <= hi`` (the lazy cuts)."""
    A = sp.csr_matrix((coef, (np.zeros(cols.size, dtype=np.int64), cols)),
                      shape=(1, program.n_cols))
    program.add_rows(A, np.array([-np.inf]), np.array([hi]), family)


def lane_cut(program: LaneProgram, left: Sequence[int], right: Sequence[int]) -> None:
    """Cut off exactly one lane, the boundaries ``left`` and ``right`` (cone indices of the
    program, each in path order): sum of a_e over its edges E minus the sum over every other
    edge column <= abs(E) - 1, which every other 0/1 vector of edges satisfies (a lane that
    extends it too). In the sided formulation each side's edges are taken in that side's
    block. Our addition: ``rld.solver.RldModel.solve`` adds it, lazily like the cycle cuts,
    for an optimum that the shared lane predicate rejects."""
    sides = 2 if program.sided else 1
    coef = np.full(sides * program.n_edges, -1.0)
    n_in = 0
    for side, path in enumerate((left, right)):
        path = np.asarray(path, dtype=np.int64)
        if path.size < 2:
            continue
        k = np.asarray(program.edge_ids(path[:-1], path[1:]), dtype=np.int64)
        if np.any(k < 0):
            raise ValueError("lane_cut: an edge of the lane is not a candidate edge")
        coef[(side if program.sided else 0) * program.n_edges + k] = 1.0
        n_in += k.size
    if n_in == 0:
        raise ValueError("lane_cut: the lane has no edge")
    cols = np.concatenate([np.arange(program.block("a", s).start, program.block("a", s).stop)
                           for s in range(sides)])
    _add_lazy_row(program, cols, coef, n_in - 1.0, "lane_cut")


def extract_paths(
    program: LaneProgram, x: np.ndarray, side: int = 0
) -> tuple[list[list[int]], list[list[int]]]:
    """Split a solution (the edges of ``side`` in the sided formulation) into its simple paths
    and its cycles (lists of cones).

    Each path is ordered from its end nearer the car (an end in the near mask first).
    """
    chosen = program.edges[x[program.block("a", side)] > 0.5]
    n = program.n_cones
    deg = np.bincount(chosen.ravel(), minlength=n)
    adj: list[list[int]] = [[] for _ in range(n)]
    for i, j in chosen:
        adj[i].append(int(j))
        adj[j].append(int(i))
    paths, cycles = [], []
    for comp in _components(n, chosen):
        ends = [v for v in comp if deg[v] == 1]
        if len(ends) != 2 or any(deg[v] > 2 for v in comp):
            cycles.append(comp)
            continue
        d = np.hypot(*(program.points[ends] - program.pose.xy).T)
        key = [(not program.near[v], d[k], v) for k, v in enumerate(ends)]
        first = min(key)[2]
        path, prev = [first], -1
        while len(path) < len(comp):
            nxt = [w for w in adj[path[-1]] if w != prev]
            prev = path[-1]
            path.append(nxt[0])
        paths.append(path)
    return paths, cycles

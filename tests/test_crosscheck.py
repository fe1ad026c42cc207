"""RLD against CLC on identical inputs (issue 5, item 1): the exact cross-check.

Both sides take the same cones, the same car pose, the same start vertices (CLC's
``find_starting_vertices``; RLD's near endpoints fixed to them, ``build_program(start=...)``)
and the same objective (RLD eq. 29 through ``rld.costs.lane_cost``, which is CLC's ``rld_cost``
ranker). CLC enumerates every feasible path pair (``max_iterations=0``, theorem 4); RLD solves
its program to optimality with lazy cycle cuts.

The two feasible sets do not coincide, by construction of the two papers (docs/formulation.md,
"RLD-CLC cross-check"): RLD alone has the heading row (eq. 9), the far-endpoint distance rows
(eqs 12-17), the spacing-cost cut s_crit (eq. 27), pairwise minimum width only between edges
that are not end to end (eqs 6-8), and paths of at least one edge; CLC alone has the maximum
width and the minimum width between whole chains (eq. 13), and first edges within phi_max of
the heading (ours, ``first_edges_ahead``). So the tests assert the strongest statements that
hold:

(a) every CLC candidate maps to a column vector of the RLD program with the same objective
    (``lane_cost`` == ``LaneProgram.objective``): one home for the costs;
(b) every CLC candidate that satisfies the RLD program costs at least RLD's optimum (RLD is
    optimal over a superset), and when there is none, RLD's optimum is a lane CLC rejects or
    the program is infeasible;
(c) whenever RLD's optimal lane satisfies CLC's predicates, it is one of CLC's candidates and
    RLD's optimal cost equals the minimum over the RLD-feasible candidates;
(d) where that minimum is attained once, the two lanes are identical.
Each branch must fire on a minimum share of the instances (counted below), so none is vacuous.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from clc.search import enumerate_candidates
from rld.backends import make_backend
from rld.constraints import find_starting_vertices, first_edges_ahead, lane_is_feasible
from rld.costs import lane_cost
from rld.program import build_program, cycle_cut, extract_paths
from rld.types import LaneParams, Pose

P = LaneParams()
TIE = 1e-6  # objective tolerance (CP-SAT and HiGHS agree with numpy to about 1e-9)
# How far from the true optimum a backend's "optimal" may be. HiGHS closes the gap to 1e-7
# (rld.backends.highs). CP-SAT stops at its default absolute_gap_limit of 1e-4, in an
# objective it scales to integers, so its bound is not exact either: seed 103527, n = 10 gave
# an incumbent of -9.995247, a "proven" bound of -9.995315 and a CLC candidate at -9.995330
# (the backends' own agreement test, tests/test_rld.py, allows 1e-4).
OPT_TOL = {"cpsat": 2e-4, "highs": TIE}


def track_instance(seed: int, n: int, curvy: bool = False) -> tuple[np.ndarray, Pose]:
    """Two noisy boundary rows (3.5-4.5 m apart, 2.5-4.5 m spacing, a random constant bend of
    curvature up to 0.06 1/m, or 0.12-0.2 1/m when ``curvy``: a hairpin) with 1-5 false positives
    (at most n - 4), ``n`` cones in all, rotated and shifted at random; the car between the
    first cones, heading along the lane."""
    rng = np.random.default_rng(seed)
    fp = int(rng.integers(1, min(5, n - 4) + 1))  # at least two cones per boundary
    k_left = (n - fp) // 2
    k_right = n - fp - k_left
    width = rng.uniform(3.5, 4.5)
    if curvy:
        kappa = float(rng.choice([-1, 1]) * rng.uniform(0.12, 0.2))
    else:
        kappa = rng.uniform(-0.06, 0.06) or 1e-6

    def row(k: int, offset: float) -> np.ndarray:
        s = np.cumsum(np.r_[0.0, rng.uniform(2.5, 4.5, size=k - 1)])
        centre = np.column_stack([np.sin(kappa * s) / kappa, (1 - np.cos(kappa * s)) / kappa])
        normal = np.column_stack([-np.sin(kappa * s), np.cos(kappa * s)])
        return centre + offset * normal + rng.normal(0, 0.2, size=centre.shape)

    pts = np.vstack([row(k_left, width / 2), row(k_right, -width / 2),
                     rng.uniform([-2, -7], [16, 7], size=(fp, 2))])
    theta = rng.uniform(-math.pi, math.pi)
    rot = np.array([[math.cos(theta), -math.sin(theta)], [math.sin(theta), math.cos(theta)]])
    shift = rng.uniform(-50, 50, size=2)
    pts = pts @ rot.T + shift
    x0, y0 = np.array([0.5, 0.0]) @ rot.T + shift
    order = rng.permutation(n)  # no method may rely on the input order
    return np.ascontiguousarray(pts[order]), Pose(float(x0), float(y0), float(theta))


def rld_optimum(points, pose, start, backend="cpsat"):
    """RLD's optimal cost and lane (left, right from the start cones) with the near endpoints
    fixed to ``start``; (inf, None) when the program is infeasible. The program is returned
    too, for mapping CLC's candidates onto its columns."""
    be = make_backend(backend)
    prog = build_program(points, pose, P, start=start, strengthen=be.strengthen)
    for _ in range(30):
        res = be.solve(prog, 30.0)
        if res.x is None:
            assert res.status == "infeasible", res
            return math.inf, None, prog
        assert res.status == "optimal", res
        paths, cycles = extract_paths(prog, res.x)
        if not cycles:
            break
        for comp in cycles:
            cycle_cut(prog, comp)
    else:
        raise AssertionError("too many cycle rounds")
    assert len(paths) == 2
    lane = None
    ends = {int(p[0]) for p in paths} | {int(p[-1]) for p in paths}
    # The program fixes the near endpoints to the start cones (build_program(start=...)).
    assert set(start) <= ends, (start, paths)
    by_start = {}
    for path in paths:
        path = list(path)
        for s in start:
            if path[-1] == s:
                path = path[::-1]
            if path[0] == s:
                by_start[s] = np.array(path)
    if len(by_start) == 2:
        lane = (by_start[start[0]], by_start[start[1]])
    return res.objective, lane, prog


def candidate_columns(prog, left, right) -> np.ndarray | None:
    """The program's column vector for a CLC candidate, None when it uses an edge the program
    has no column for (pruned by the spacing limit or s_crit, eq. 27)."""
    eid = {(int(i), int(j)): k for k, (i, j) in enumerate(prog.edges)}
    chosen = []
    for path in (left, right):
        for a, b in zip(path[:-1], path[1:], strict=True):
            key = (min(int(a), int(b)), max(int(a), int(b)))
            if key not in eid:
                return None
            chosen.append(eid[key])
    return prog.solution_from_edges(np.array(chosen, dtype=np.int64))


def cross_check(seed: int, n: int, backend: str = "cpsat", curvy: bool = False) -> dict:
    """Run (a)-(d) on one instance; returns which branches fired."""
    points, pose = track_instance(seed, n, curvy)
    start = find_starting_vertices(points, pose, P.near_radius_m)
    if start is None:
        return {"no_start": True}
    res = enumerate_candidates(points, pose, P, max_iterations=0, start=start)
    assert res.complete
    opt, lane, prog = rld_optimum(points, pose, start, backend)
    tol = OPT_TOL[backend]
    fired = {"candidates": len(res.candidates)}
    rld_feasible_costs = []
    for left, right, closed in res.candidates:
        assert not closed
        x = candidate_columns(prog, left, right)
        cost = lane_cost(points, left, right, pose, P)
        if x is None:
            continue
        # (a) one objective: the shared lane cost is the program's objective of the lane.
        assert prog.objective(x) == pytest.approx(cost, abs=1e-9)
        if prog.is_feasible(x):
            rld_feasible_costs.append((cost, left, right))
    # (b) RLD is optimal (to the backend's tolerance) over a superset of the RLD-feasible
    # candidates.
    for cost, left, right in rld_feasible_costs:
        assert cost >= opt - tol, (seed, n, left, right, cost, opt)
    fired["rld_feasible_candidates"] = len(rld_feasible_costs)
    if math.isinf(opt):
        # Infeasible: then no CLC candidate satisfies the program either.
        fired["rld_infeasible"] = True
        assert not rld_feasible_costs
        return fired
    if lane is None:
        # One path joins the two start cones (a U through the lane's far end) and the other
        # runs elsewhere: every RLD-feasible CLC candidate costs more, by (b), strictly.
        fired["rld_lane_not_a_pair"] = True
        assert all(cost > opt - tol for cost, _, _ in rld_feasible_costs)
        return fired
    left, right = lane
    if not (lane_is_feasible(points[left], points[right], P)
            and first_edges_ahead(points[left], points[right], pose, P.max_turn_angle_rad)):
        fired["rld_lane_rejected_by_clc"] = True
        return fired
    # (c) RLD's optimal lane is a CLC candidate and the minimum over the feasible ones.
    fired["equal_optimum"] = True
    keys = {(tuple(a.tolist()), tuple(b.tolist())) for _, a, b in rld_feasible_costs}
    assert (tuple(left.tolist()), tuple(right.tolist())) in keys
    best = min(c for c, _, _ in rld_feasible_costs)
    assert best == pytest.approx(opt, abs=tol)
    # (d) a unique minimum (no other candidate within the tolerance) is the same lane on both
    # sides.
    at_best = [(a, b) for c, a, b in rld_feasible_costs if c <= best + tol]
    if len(at_best) == 1:
        fired["identical_lane"] = True
        assert np.array_equal(at_best[0][0], left) and np.array_equal(at_best[0][1], right)
    return fired


N_INSTANCES = 200
N_CURVY = 50


@pytest.fixture(scope="module")
def tally():
    return {"gentle": [], "curvy": []}


@pytest.mark.parametrize("seed", range(N_INSTANCES))
def test_rld_and_clc_cross_check(seed, tally):
    n = 8 + seed % 7  # 8..14 cones
    tally["gentle"].append(cross_check(seed, n))


@pytest.mark.parametrize("seed", range(N_CURVY))
def test_rld_and_clc_cross_check_in_hairpins(seed, tally):
    tally["curvy"].append(cross_check(5000 + seed, 8 + seed % 7, curvy=True))


def test_every_branch_of_the_cross_check_fires(tally):
    """Guards within 2 points of the shares measured on 2026-12-07 (gentle: 189 of 200
    instances have a lane both ways, 11 have none both ways (the start pair's boundaries would
    run backwards), 186 of the 189 equal optima and identical lanes; hairpins of 5-8 m radius,
    turns up to 0.9 rad a cone: 46, 45 and 45 of 50, 4 infeasible)."""
    # Runs after the parametrized tests in this module (pytest keeps the file order).
    gentle, curvy = tally["gentle"], tally["curvy"]
    if len(gentle) < N_INSTANCES or len(curvy) < N_CURVY:
        pytest.skip("run with the whole cross-check")
    share = lambda rows, key: sum(bool(t.get(key)) for t in rows) / len(rows)  # noqa: E731
    assert share(gentle, "no_start") == 0
    assert share(gentle, "rld_feasible_candidates") >= 0.925
    assert share(gentle, "rld_infeasible") <= 0.075
    with_lane = [t for t in gentle if t.get("rld_feasible_candidates")]
    assert share(with_lane, "equal_optimum") >= 0.965
    assert share(with_lane, "identical_lane") >= 0.965
    assert share(gentle, "rld_lane_not_a_pair") <= 0.02
    assert share(curvy, "rld_feasible_candidates") >= 0.9
    assert share(curvy, "equal_optimum") >= 0.88
    assert share(curvy, "identical_lane") >= 0.88
    assert share(curvy, "rld_lane_not_a_pair") <= 0.02
    assert share(curvy, "rld_infeasible") <= 0.1


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 10**6), st.integers(6, 12))
def test_cross_check_property(seed, n):
    cross_check(seed, n)


@pytest.mark.parametrize("seed", range(20))
def test_cross_check_with_highs(seed):
    # The same statements with another backend on a subset.
    cross_check(1000 + seed, 8 + seed % 5, backend="highs")



def test_public_methods_agree_on_30_cone_windows(dataset_dir):
    """Through the public methods (issue 40, item 4; benchmarks/bench_crosscheck.py): RLD's
    program over a whole window of at most 30 cones against CLC on the same cones with no
    iteration limit in effect and RLD's objective as its ranker, both otherwise at their
    defaults; six shared tracks, R = 30 m, no false positives, every 15th pose (94 windows).
    Measured 2026-12-08: 93 identical; the other differs in one side's first cone, beside the
    car (track 1 pose 45), none unexplained (docs/formulation.md)."""
    from benchmarks.bench_crosscheck import run

    recs = run(dataset_dir)
    assert len(recs) == 94
    assert all(r["optimal"] and r["complete"] for r in recs)
    causes = [r["cause"] for r in recs if not r["same"]]
    assert sum(r["same"] for r in recs) >= 92  # measured 93; the floor within 2 points
    assert "unexplained" not in causes, causes
    assert causes.count("RLD lane not CLC-feasible") + causes.count("first cone") <= 2


def test_first_cone_only_hand_worked():
    """The public cross-check's ``first cone`` cause: one side differs, by one cone at its
    start; not two sides, not a cone elsewhere, not two cones, not a closed lane."""
    from benchmarks.bench_crosscheck import first_cone_only

    a = ((1, 2, 3), (7, 8))
    assert first_cone_only(a, ((0, 1, 2, 3), (7, 8)))
    assert first_cone_only(((0, 1, 2, 3), (7, 8)), a)
    assert first_cone_only(a, ((1, 2, 3), (6, 7, 8)))
    assert not first_cone_only(a, a)
    assert not first_cone_only(a, ((0, 1, 2, 3), (6, 7, 8)))
    assert not first_cone_only(a, ((1, 2, 9, 3), (7, 8)))
    assert not first_cone_only(a, ((5, 0, 1, 2, 3), (7, 8)))
    assert not first_cone_only(a, ((4, 2, 3), (7, 8)))
    assert not first_cone_only((frozenset({(1, 2)}), frozenset({(7, 8)})), a)

"""cvxpy backend: the program as a cvxpy Problem over a boolean vector, solved by any installed
MILP solver (HiGHS by default, ``cvxpy:NAME`` for another). cvxpy passes ``warm_start`` on to
solvers that take one; HiGHS through cvxpy does not, so the hint is set but may go unused."""

from __future__ import annotations

import time

import numpy as np

from rld.backends.base import Backend, BackendResult
from rld.backends.highs import presolve_option
from rld.program import LaneProgram

# cvxpy's solver names and how each takes a time limit.
_TIME_OPTION = {"HIGHS": "time_limit", "SCIPY": None, "GLPK_MI": None, "CBC": "maximumSeconds",
                "SCIP": None, "GUROBI": "TimeLimit", "MOSEK": None, "CPLEX": None}


class CvxpyBackend(Backend):
    name = "cvxpy"

    def __init__(self, solver: str = "HIGHS") -> None:
        import cvxpy as cp

        self.solver = solver.upper()
        if self.solver not in cp.installed_solvers():
            raise ValueError(
                f"cvxpy solver {self.solver!r} is not installed; installed: "
                f"{', '.join(cp.installed_solvers())}"
            )

    def solve(self, program: LaneProgram, time_limit_s: float, hint=None) -> BackendResult:
        import cvxpy as cp

        t0 = time.perf_counter()
        n = program.n_cols
        x = cp.Variable(n, boolean=True)
        A = program.A
        cons = []
        up = np.isfinite(program.row_hi)
        lo = np.isfinite(program.row_lo)
        eq = up & lo & (program.row_hi == program.row_lo)
        if (up & ~eq).any():
            cons.append(A[up & ~eq] @ x <= program.row_hi[up & ~eq])
        if (lo & ~eq).any():
            cons.append(A[lo & ~eq] @ x >= program.row_lo[lo & ~eq])
        if eq.any():
            cons.append(A[eq] @ x == program.row_lo[eq])
        zero = program.col_hi < 0.5
        if zero.any():
            cons.append(x[np.flatnonzero(zero)] == 0)
        prob = cp.Problem(cp.Minimize(program.c @ x), cons)
        options = {}
        key = _TIME_OPTION.get(self.solver)
        if key:
            options[key] = max(float(time_limit_s), 1e-3)
        if self.solver == "HIGHS":
            options.update(mip_rel_gap=0.0, mip_abs_gap=1e-7, threads=1,
                           presolve=presolve_option(program.n_cones, time_limit_s))
        if hint is not None:
            x.value = np.asarray(hint, dtype=np.float64)
        try:
            prob.solve(solver=self.solver, warm_start=hint is not None, **options)
        except cp.error.SolverError as exc:
            return BackendResult("error", None, time_s=time.perf_counter() - t0, message=str(exc))
        elapsed = time.perf_counter() - t0
        status = prob.status
        if status in (cp.INFEASIBLE, cp.INFEASIBLE_INACCURATE):
            return BackendResult("infeasible", None, time_s=elapsed)
        if x.value is None:
            return BackendResult("timeout", None, time_s=elapsed, message=str(status))
        sol = np.round(np.asarray(x.value, dtype=np.float64))
        kind = "optimal" if status == cp.OPTIMAL else "feasible"
        return BackendResult(kind, sol, float(program.c @ sol), float("nan"), elapsed,
                             message=str(status))

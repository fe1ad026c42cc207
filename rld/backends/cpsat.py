"""OR-Tools CP-SAT backend: Boolean variables, linear rows (pairs as at-most-one), the float
objective as given (CP-SAT scales it internally), the warm start as solution hints."""

from __future__ import annotations

import time

import numpy as np

from rld.backends.base import Backend, BackendResult
from rld.program import LaneProgram


class CpSatBackend(Backend):
    name = "cpsat"

    #: The valid angle-cover rows slow CP-SAT down (measured on 60 generated frames, n = 12:
    #: median 19.6 -> 14.9 ms without them); it gets the paper's rows only.
    strengthen = False

    #: CP-SAT's presolve costs more than it saves on small programs: measured on 48 generated
    #: frames (20 % false positives), n = 12: median 13 -> 9 ms with it off, p95 23 -> 21 ms;
    #: but at n = 16 the p95 rose 47 -> 79 ms and at n = 30 159 -> 377 ms. So it is off up to
    #: this many cones.
    presolve_off_max_cones = 12

    def __init__(self, workers: int = 1, **parameters) -> None:
        from ortools.sat.python import cp_model  # noqa: F401 (fail early if missing)

        self.workers = int(workers)
        self.parameters = parameters  # any CpSolver parameter by name

    def solve(self, program: LaneProgram, time_limit_s: float, hint=None) -> BackendResult:
        from ortools.sat.python import cp_model

        t0 = time.perf_counter()
        model = cp_model.CpModel()
        n = program.n_cols
        x = [model.new_bool_var(f"x{j}") for j in range(n)]
        for j in np.flatnonzero(program.col_hi < 0.5):
            model.add(x[j] == 0)
        for j in np.flatnonzero(program.col_lo > 0.5):
            model.add(x[j] == 1)
        A = program.A
        indptr, indices, data = A.indptr, A.indices, A.data
        lo, hi = program.row_lo, program.row_hi
        for r in range(A.shape[0]):
            cols = indices[indptr[r]:indptr[r + 1]]
            vals = data[indptr[r]:indptr[r + 1]]
            if cols.size == 2 and hi[r] == 1 and vals[0] == 1 and vals[1] == 1 and lo[r] < -1:
                model.add_at_most_one(x[cols[0]], x[cols[1]])
                continue
            expr = cp_model.LinearExpr.weighted_sum([x[c] for c in cols],
                                                    [int(v) for v in vals])
            lb = int(np.ceil(lo[r] - 1e-9)) if np.isfinite(lo[r]) else -(2**40)
            ub = int(np.floor(hi[r] + 1e-9)) if np.isfinite(hi[r]) else 2**40
            model.add_linear_constraint(expr, lb, ub)
        model.minimize(cp_model.LinearExpr.weighted_sum(x, [float(v) for v in program.c]))
        if hint is not None:
            for j in range(n):
                model.add_hint(x[j], bool(hint[j] > 0.5))
        solver = cp_model.CpSolver()
        # The budget covers building the CP-SAT model too.
        solver.parameters.max_time_in_seconds = max(
            float(time_limit_s) - (time.perf_counter() - t0), 1e-3)
        solver.parameters.num_workers = self.workers
        if program.n_cones <= self.presolve_off_max_cones:
            solver.parameters.cp_model_presolve = False
        for key, value in self.parameters.items():
            setattr(solver.parameters, key, value)
        status = solver.solve(model)
        elapsed = time.perf_counter() - t0
        if status in (cp_model.OPTIMAL, cp_model.FEASIBLE):
            sol = np.array([solver.value(v) for v in x], dtype=np.float64)
            return BackendResult(
                "optimal" if status == cp_model.OPTIMAL else "feasible",
                sol,
                float(program.c @ sol),
                float(solver.best_objective_bound),
                elapsed,
            )
        if status == cp_model.INFEASIBLE:
            return BackendResult("infeasible", None, time_s=elapsed)
        if status == cp_model.UNKNOWN:
            return BackendResult("timeout", None, time_s=elapsed)
        return BackendResult("error", None, time_s=elapsed, message=solver.status_name(status))

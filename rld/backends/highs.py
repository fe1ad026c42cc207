"""HiGHS backend through highspy: the program passed as one HighsLp, its LP relaxation solved
first (``LP_FIRST``); only when that optimum is fractional, the program with integrality and
the warm start as a MIP start (``setSolution``)."""

from __future__ import annotations

import time

import numpy as np

from rld.backends.base import Backend, BackendResult
from rld.program import LaneProgram

#: HiGHS's presolve is not interrupted by its time limit, and on our programs it costs more
#: than it saves up to this many cones. Measured 2026-12-01 on the 48 frames of
#: ``rld bench rld`` (20 % false positives), solve alone, 1 s limit, median / p95 ms with
#: presolve on -> off: n = 12 12.6 / 32.5 -> 7.9 / 12.8, n = 20 25.3 / 119.5 -> 10.5 / 22.5,
#: n = 30 52.2 / 150.5 -> 16.0 / 37.2 (the same optima); n = 40 104.7 / 357.3 -> 24.1 / 710.5
#: with 4 of 44 no longer optimal within the limit. With a 20 ms limit at n = 40 presolve ran
#: over it by a median 26 and at most 123 ms, without it by at most 19 ms.
PRESOLVE_OFF_MAX_CONES = 30
#: Below this budget presolve is off at any size: it would not stop at the limit.
PRESOLVE_MIN_BUDGET_S = 0.25
#: Solve the LP relaxation first: an integral LP optimum is an optimum of the program (the LP
#: bound is met by a 0/1 point), proven without the MIP's root work. Chosen by measurement:
#: docs/tuning.md#lp_first.
LP_FIRST = True
#: A relaxation value this close to 0 or 1 counts as integral.
INTEGRAL_TOL = 1e-6


def presolve_option(n_cones: int, time_limit_s: float) -> str:
    """HiGHS's ``presolve`` option for a program of ``n_cones`` cones and this budget (s)."""
    if n_cones <= PRESOLVE_OFF_MAX_CONES or time_limit_s < PRESOLVE_MIN_BUDGET_S:
        return "off"
    return "choose"


class HighsBackend(Backend):
    name = "highs"

    def __init__(self, threads: int = 1, lp_first: bool | None = None) -> None:
        import highspy  # noqa: F401

        self.threads = int(threads)
        self.lp_first = LP_FIRST if lp_first is None else bool(lp_first)

    def _model(self, program: LaneProgram, time_limit_s: float, integer: bool):
        """A silent ``Highs`` holding ``program`` (with integrality when ``integer``)."""
        import highspy

        inf = highspy.kHighsInf
        h = highspy.Highs()
        h.silent()
        h.setOptionValue("presolve", presolve_option(program.n_cones, time_limit_s))
        h.setOptionValue("threads", self.threads)
        h.setOptionValue("mip_rel_gap", 0.0)
        h.setOptionValue("mip_abs_gap", 1e-7)
        lp = highspy.HighsLp()
        n, m = program.n_cols, program.n_rows
        lp.num_col_ = n
        lp.num_row_ = m
        lp.col_cost_ = program.c.astype(np.float64)
        lp.col_lower_ = program.col_lo.astype(np.float64)
        lp.col_upper_ = program.col_hi.astype(np.float64)
        lp.row_lower_ = np.where(np.isfinite(program.row_lo), program.row_lo, -inf)
        lp.row_upper_ = np.where(np.isfinite(program.row_hi), program.row_hi, inf)
        csc = program.A.tocsc()
        csc.sort_indices()
        lp.a_matrix_.format_ = highspy.MatrixFormat.kColwise
        lp.a_matrix_.start_ = csc.indptr.astype(np.int32)
        lp.a_matrix_.index_ = csc.indices.astype(np.int32)
        lp.a_matrix_.value_ = csc.data.astype(np.float64)
        lp.a_matrix_.num_col_ = n
        lp.a_matrix_.num_row_ = m
        if integer:
            lp.integrality_ = [highspy.HighsVarType.kInteger] * n
        h.passModel(lp)
        return h

    @staticmethod
    def _relaxed(h, program: LaneProgram, t0: float, time_limit_s: float):
        """Solve the LP relaxation held by ``h``: ``optimal`` when its optimum is a 0/1 point
        (then an optimum of the program), ``infeasible`` when it has none (nor has the
        program), else ``None``."""
        import highspy

        h.setOptionValue("time_limit", max(float(time_limit_s) - (time.perf_counter() - t0),
                                           1e-3))
        h.run()
        status = h.getModelStatus()
        if status == highspy.HighsModelStatus.kInfeasible:
            return BackendResult("infeasible", None, time_s=time.perf_counter() - t0)
        if status == highspy.HighsModelStatus.kOptimal:
            x = np.asarray(h.getSolution().col_value)
            if np.all(np.abs(x - np.round(x)) <= INTEGRAL_TOL):
                x = np.round(x)
                obj = float(program.c @ x)
                return BackendResult("optimal", x, obj, obj, time.perf_counter() - t0)
        return None

    def relaxation(self, program: LaneProgram, time_limit_s: float) -> BackendResult | None:
        """The program's LP relaxation alone (``_relaxed``): a result when it settles the
        program, else ``None``."""
        t0 = time.perf_counter()
        return self._relaxed(self._model(program, time_limit_s, False), program, t0,
                             time_limit_s)

    def solve(self, program: LaneProgram, time_limit_s: float, hint=None) -> BackendResult:
        import highspy

        t0 = time.perf_counter()
        n = program.n_cols
        h = self._model(program, time_limit_s, not self.lp_first)
        if self.lp_first:
            settled = self._relaxed(h, program, t0, time_limit_s)
            if settled is not None:
                return settled
            h.changeColsIntegrality(n, np.arange(n, dtype=np.int32),
                                    np.full(n, highspy.HighsVarType.kInteger.value, np.uint8))
        if hint is not None:
            sol = highspy.HighsSolution()
            sol.col_value = [float(v) for v in hint]
            sol.value_valid = True
            h.setSolution(sol)
        # The budget covers handing the model over too.
        h.setOptionValue("time_limit", max(float(time_limit_s) - (time.perf_counter() - t0),
                                           1e-3))
        h.run()
        elapsed = time.perf_counter() - t0
        status = h.getModelStatus()
        info = h.getInfo()
        S = highspy.HighsModelStatus
        has_sol = info.primal_solution_status == highspy.SolutionStatus.kSolutionStatusFeasible
        x = np.round(np.array(h.getSolution().col_value)) if has_sol else None
        bound = float(info.mip_dual_bound)
        if status == S.kOptimal and x is not None:
            return BackendResult("optimal", x, float(program.c @ x), bound, elapsed)
        if status == S.kInfeasible:
            return BackendResult("infeasible", None, time_s=elapsed)
        if x is not None:
            return BackendResult("feasible", x, float(program.c @ x), bound, elapsed)
        if status in (S.kTimeLimit, S.kInterrupt, S.kIterationLimit, S.kSolutionLimit):
            return BackendResult("timeout", None, time_s=elapsed)
        return BackendResult("error", None, time_s=elapsed, message=h.modelStatusToString(status))

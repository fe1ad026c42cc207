"""OR-Tools CP-SAT backend: Boolean variables, linear rows (pairs as at-most-one), the float
objective as given (CP-SAT scales it internally), the warm start as solution hints."""

from __future__ import annotations

import time

import numpy as np

from rld.backends.base import Backend, BackendResult
from rld.program import LaneProgram

_BIG = 2**40  # an infinite row bound, as a CP-SAT domain end


def _ints(values) -> str:
    return ", ".join(map(str, values))


def model_text(program: LaneProgram, hint=None) -> str | None:
    """The CP-SAT model of ``program`` in protobuf text format (``CpModelProto``).

    Written as one string and parsed in C++ because building it through ``cp_model``'s Python
    objects cost about 2 ms of a 5 ms call at n = 12 (one Python object per variable, term and
    row). Columns are Boolean variables, fixed ones by their domain; a row ``a + b <= 1``
    becomes ``at_most_one``, any other a linear row with integer coefficients and its bounds
    rounded inwards (the variables are integers); the objective is the float ``c`` as given
    (CP-SAT scales it internally); ``hint`` (0/1 per column) becomes the solution hint.
    ``None`` when a column's or a row's bounds admit no integer (CP-SAT would call such a model
    invalid, not infeasible).
    """
    n = program.n_cols
    lo_fixed = program.col_lo > 0.5
    hi_fixed = program.col_hi < 0.5
    if np.any(lo_fixed & hi_fixed):
        return None
    dom = np.where(hi_fixed, "variables { domain: [0, 0] }",
                   np.where(lo_fixed, "variables { domain: [1, 1] }",
                            "variables { domain: [0, 1] }"))
    parts = dom.tolist()
    A = program.A
    indptr, indices, data = A.indptr, A.indices, A.data
    lo, hi = program.row_lo, program.row_hi
    length = np.diff(indptr)
    pair = (length == 2) & (hi == 1) & (lo < -1)
    first = indptr[:-1][pair]
    pair[pair] = (data[first] == 1) & (data[first + 1] == 1)
    starts = indptr[:-1][pair]
    for a, b in zip(indices[starts].tolist(), indices[starts + 1].tolist(), strict=True):
        parts.append(f"constraints {{ at_most_one {{ literals: [{a}, {b}] }} }}")
    with np.errstate(invalid="ignore"):
        lbs = np.where(np.isfinite(lo), np.ceil(lo - 1e-9), -_BIG).astype(np.int64)
        ubs = np.where(np.isfinite(hi), np.floor(hi + 1e-9), _BIG).astype(np.int64)
    if np.any(lbs > ubs):
        return None
    lbs, ubs = lbs.tolist(), ubs.tolist()
    ints = data.astype(np.int64)
    if np.any(ints != data):
        raise ValueError("CP-SAT takes integer row coefficients only")
    for r in np.flatnonzero(~pair).tolist():
        s, e = indptr[r], indptr[r + 1]
        parts.append(f"constraints {{ linear {{ vars: [{_ints(indices[s:e].tolist())}] "
                     f"coeffs: [{_ints(ints[s:e].tolist())}] domain: [{lbs[r]}, {ubs[r]}] }} }}")
    parts.append(f"floating_point_objective {{ vars: [{_ints(range(n))}] "
                 f"coeffs: [{_ints(np.asarray(program.c, dtype=np.float64).tolist())}] }}")
    if hint is not None:
        values = (np.asarray(hint) > 0.5).astype(int)
        parts.append(f"solution_hint {{ vars: [{_ints(range(n))}] "
                     f"values: [{_ints(values.tolist())}] }}")
    return "\n".join(parts)


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
        text = model_text(program, hint)
        if text is None:
            return BackendResult("infeasible", None, time_s=time.perf_counter() - t0)
        model = cp_model.CpModel()
        model.proto.parse_text_format(text)
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
            sol = np.array(solver.response_proto.solution, dtype=np.float64)
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

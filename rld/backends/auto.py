"""The ``auto`` backend: per program, the backend measured fastest at its size.

``rld bench rld`` (2026-12-01, 48 generated frames with 20 % false positives, 1 s limit, cold,
median / p95 ms) after HiGHS lost its presolve up to 30 cones (``rld.backends.highs``):

| n | CP-SAT | HiGHS |
|---|---|---|
| 12 | 6.0-7.2 / 16.6-20.7 | 13.4 / 21.0 |
| 16 | 12.1-15.1 / 28.0-31.6 | 13.9 / 26.1 |
| 20 | 17.3-21.6 / 43.5-56.4 | 15.1 / 29.6 |
| 30 | 29.8-32.8 / 87.8-113.9 | 22.8 / 52.3 |
| 40 | 49.4-52.0 / 226.7-285.2 | 102.1 / 382.7 |

(CP-SAT over four runs, HiGHS one.) So CP-SAT up to 16 cones and above 30, HiGHS in between.
Both return an optimum of the same program; only ties between equal-cost lanes may differ.
"""

from __future__ import annotations

import numpy as np

from rld.backends.base import Backend, BackendResult
from rld.backends.cpsat import CpSatBackend
from rld.backends.highs import PRESOLVE_OFF_MAX_CONES, HighsBackend
from rld.program import LaneProgram

#: Programs with more cones than this and at most ``PRESOLVE_OFF_MAX_CONES`` go to HiGHS.
CPSAT_MAX_CONES = 16


class AutoBackend(Backend):
    name = "auto"

    def __init__(self) -> None:
        self._cpsat = CpSatBackend()
        self._highs = HighsBackend()
        self.last_name = ""
        """The backend that solved the last program."""

    def pick(self, n_cones: int) -> Backend:
        """The backend for a program of ``n_cones`` cones."""
        if CPSAT_MAX_CONES < n_cones <= PRESOLVE_OFF_MAX_CONES:
            return self._highs
        return self._cpsat

    def strengthen_for(self, n_cones: int) -> bool:
        return self.pick(n_cones).strengthen

    def solve(self, program: LaneProgram, time_limit_s: float,
              hint: np.ndarray | None = None) -> BackendResult:
        backend = self.pick(program.n_cones)
        self.last_name = backend.name
        return backend.solve(program, time_limit_s, hint)

"""The ``auto`` backend: per program, the backend measured fastest at its size: CP-SAT up to
``CPSAT_MAX_CONES`` cones and above ``PRESOLVE_OFF_MAX_CONES``, HiGHS in between; both return
an optimum of the same program (docs/tuning.md#cpsat_max_cones)."""

from __future__ import annotations

import numpy as np

from rld.backends.base import Backend, BackendResult
from rld.backends.cpsat import CpSatBackend
from rld.backends.highs import PRESOLVE_OFF_MAX_CONES, HighsBackend
from rld.program import LaneProgram

#: Programs with more cones than this and at most ``PRESOLVE_OFF_MAX_CONES`` go to HiGHS.
#: Chosen by measurement: docs/tuning.md#cpsat_max_cones.
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

"""The ``auto`` backend: HiGHS's LP relaxation first (an integral optimum settles the program,
``rld.backends.highs.LP_FIRST``), CP-SAT on the program when the relaxation's optimum is
fractional; both answers are optima of the same program (docs/tuning.md#auto_backend)."""

from __future__ import annotations

import time

import numpy as np

from rld.backends import highs
from rld.backends.base import Backend, BackendResult
from rld.backends.cpsat import CpSatBackend
from rld.backends.highs import HighsBackend
from rld.program import LaneProgram


class AutoBackend(Backend):
    name = "auto"

    def __init__(self) -> None:
        self._cpsat = CpSatBackend()
        self._highs = HighsBackend()
        self.last_name = ""
        """What settled the last program: ``highs-lp`` (its relaxation) or ``cpsat``."""

    def strengthen_for(self, n_cones: int) -> bool:
        # The angle-cover rows tighten the relaxation solved first.
        return highs.LP_FIRST or self._cpsat.strengthen

    def solve(self, program: LaneProgram, time_limit_s: float,
              hint: np.ndarray | None = None) -> BackendResult:
        t0 = time.perf_counter()
        if highs.LP_FIRST:
            settled = self._highs.relaxation(program, time_limit_s)
            if settled is not None:
                self.last_name = "highs-lp"
                return settled
        self.last_name = "cpsat"
        result = self._cpsat.solve(
            program, max(time_limit_s - (time.perf_counter() - t0), 1e-3), hint)
        result.time_s = time.perf_counter() - t0
        return result

"""The backend interface and its result."""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from rld.program import LaneProgram


@dataclass
class BackendResult:
    """``status``: ``optimal``, ``feasible`` (budget hit, incumbent returned), ``infeasible``,
    ``timeout`` (budget hit, nothing found) or ``error``. ``x``: the 0/1 solution or ``None``.
    ``objective``/``bound``: the incumbent's value and the proven lower bound (NaN when
    unknown)."""

    status: str
    x: np.ndarray | None
    objective: float = float("nan")
    bound: float = float("nan")
    time_s: float = 0.0
    message: str = ""

    @property
    def gap(self) -> float:
        return float(self.objective - self.bound)


class Backend:
    """Solve a ``LaneProgram``: minimise ``c x`` s.t. ``row_lo <= A x <= row_hi``, x binary
    within ``col_lo..col_hi``. ``hint`` is a full 0/1 vector from a previous solution."""

    name = "base"
    #: Whether the program should carry the valid angle-cover rows (``build_program``'s
    #: ``strengthen``): they tighten an LP relaxation, which helps LP-based MIP solvers.
    strengthen = True

    def strengthen_for(self, n_cones: int) -> bool:
        """``strengthen`` for a program of ``n_cones`` cones."""
        return self.strengthen

    def solve(
        self, program: LaneProgram, time_limit_s: float, hint: np.ndarray | None = None
    ) -> BackendResult:  # pragma: no cover - interface
        raise NotImplementedError

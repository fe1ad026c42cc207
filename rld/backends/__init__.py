"""Solver backends for the RLD program: each is a thin adapter with the same three steps (load
the program's arrays, solve under a time budget with an optional warm start, map the solution
back to a 0/1 vector). Add one by registering a ``Backend`` subclass in ``BACKENDS``."""

from __future__ import annotations

from rld.backends.auto import AutoBackend
from rld.backends.base import Backend, BackendResult
from rld.backends.cpsat import CpSatBackend
from rld.backends.cvxpy_backend import CvxpyBackend
from rld.backends.highs import HighsBackend

BACKENDS: dict[str, type[Backend]] = {
    "cpsat": CpSatBackend,
    "highs": HighsBackend,
    "cvxpy": CvxpyBackend,
    "auto": AutoBackend,
}
DEFAULT_BACKEND = "auto"

__all__ = ["Backend", "BackendResult", "BACKENDS", "DEFAULT_BACKEND", "make_backend"]


def make_backend(name: str | None, **options) -> Backend:
    """The backend called ``name`` (``cpsat``, ``highs``, ``cvxpy``, ``cvxpy:SOLVER`` or
    ``auto``: HiGHS's LP relaxation, then CP-SAT when it is fractional, ``rld.backends.auto``)."""
    name = DEFAULT_BACKEND if name is None else name
    base, _, solver = name.partition(":")
    if base not in BACKENDS:
        raise ValueError(f"unknown backend {name!r}; available: {', '.join(BACKENDS)}")
    if solver:
        if base != "cvxpy":
            raise ValueError(f"only the cvxpy backend takes a solver name, got {name!r}")
        options["solver"] = solver
    return BACKENDS[base](**options)

"""Rankers that pick the most likely lane among CLC's candidates (Ivanov & Markgraf 2024,
section VII). numpy only: training lives in ``clc.train`` (torch, the ``train`` extra).

Every ranker has ``name`` and ``score(points, pose, params, candidates, features)`` returning
one score per candidate, higher is better:

- ``learned``: the RankNet-style 8-100-1 ReLU network of section VII on the features of
  ``rld.costs.ranking_features``, its weights in ``models/clc_ranker.npz`` (installed as
  ``clc/models``; made by ``rld train-ranker``; its JSON card lies beside it).
- ``rld_cost``: minus the RLD objective (eq. 29) of each candidate, from the shared cost module,
  so CLC's enumeration and RLD's program can be compared on one objective.
- ``longest``: the lane length (the paper's "simple but effective heuristic"), ties broken by
  the number of cones.
"""

from __future__ import annotations

import importlib.resources
import math
import os
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from rld.costs import FEATURE_NAMES, lane_cost, open_path_costs
from rld.types import LaneParams, Pose

__all__ = ["Ranker", "LongestRanker", "RldCostRanker", "LearnedRanker", "get_ranker",
           "RANKERS", "DEFAULT_MODEL"]

#: Where ``rld train-ranker`` writes the learned ranker and ``LearnedRanker.load`` reads it.
DEFAULT_MODEL = Path(str(importlib.resources.files("clc.models") / "clc_ranker.npz"))
RANKERS = ("learned", "rld_cost", "longest")
#: The arrays of a learned ranker's ``.npz`` (``clc.train.save_ranker`` writes them).
_ARRAYS = ("W1", "b1", "w2", "b2", "mean", "std", "feature_names")
#: The ranker ``LearnedRanker.load`` last read from each file (by resolved path), with the
#: file's size and modification time then: a stateless ``solve_lane`` builds a new solver on
#: every call, and reading the ``.npz`` took 0.31 ms of it (median; 0.03 ms with this cache, a
#: median CLC call at R = 50 m, 30 % false positives is about 2 ms). A rewritten file is read
#: again.
_LOADED: dict[str, tuple[int, int, LearnedRanker]] = {}


class Ranker(Protocol):
    """What CLC needs of a ranker: a ``name`` and ``score``.

    ``score(points, pose, params, candidates, features)``: ``points`` (N, 2) cone positions (m),
    ``pose`` the car's ``Pose``, ``params`` the ``LaneParams`` of the search, ``candidates`` a
    sequence of ``(left_idx, right_idx, closed)`` (int64 index arrays into ``points``) and
    ``features`` (K, 8) float64, row k the ``rld.costs.ranking_features`` of candidate k.
    Returns (K,) float64 scores, higher is better (CLC section VII picks the argmax).
    """

    name: str

    def score(self, points: np.ndarray | None, pose: Pose | None, params: LaneParams | None,
              candidates: Sequence, features: np.ndarray) -> np.ndarray: ...


class LongestRanker:
    """The longest lane wins (mean boundary length, m); more cones break ties."""

    name = "longest"

    def score(self, points: np.ndarray | None, pose: Pose | None, params: LaneParams | None,
              candidates: Sequence, features: np.ndarray) -> np.ndarray:
        f = np.asarray(features, dtype=np.float64).reshape(-1, len(FEATURE_NAMES))
        return f[:, 0] + 1e-6 * (f[:, 1] + f[:, 2])


class RldCostRanker:
    """Minus RLD's objective (eq. 29, ``rld.costs.lane_cost``): the cheapest lane wins."""

    name = "rld_cost"

    def score(self, points: np.ndarray | None, pose: Pose | None, params: LaneParams | None,
              candidates: Sequence, features: np.ndarray) -> np.ndarray:
        if not hasattr(candidates, "flat"):
            return np.array([-lane_cost(points, a, b, pose, params, closed=c)
                             for a, b, c in candidates], dtype=np.float64)
        # A search's candidate list: all open candidates at once (``open_path_costs``), the
        # closed ones (if any) one by one.
        lf, lp, rf, rp, closed = candidates.flat()
        out = -(open_path_costs(points, lf, lp, pose, params)
                + open_path_costs(points, rf, rp, pose, params))
        for k in np.flatnonzero(closed):
            a, b, c = candidates[int(k)]
            out[k] = -lane_cost(points, a, b, pose, params, closed=c)
        return out


class LearnedRanker:
    """Net(x) = w2 . relu(W1^T z + b1) + b2 with z the standardised features (section VII)."""

    name = "learned"

    def __init__(self, W1: np.ndarray, b1: np.ndarray, w2: np.ndarray, b2: float,
                 mean: np.ndarray, std: np.ndarray) -> None:
        # Copies, made read-only below: ``load`` shares one instance between solvers.
        self.W1 = np.array(W1, dtype=np.float64)
        self.b1 = np.array(b1, dtype=np.float64)
        self.w2 = np.array(w2, dtype=np.float64)
        self.b2 = float(b2)
        self.mean = np.array(mean, dtype=np.float64)
        self.std = np.array(std, dtype=np.float64)
        nf = len(FEATURE_NAMES)
        if self.b1.ndim != 1 or self.b1.shape[0] < 1:
            raise ValueError(f"ranker weights: b1 has shape {self.b1.shape}, expected (hidden,)")
        h = self.b1.shape[0]
        shapes = {"W1": (self.W1.shape, (nf, h)), "w2": (self.w2.shape, (h,)),
                  "mean": (self.mean.shape, (nf,)), "std": (self.std.shape, (nf,))}
        for name, (got, want) in shapes.items():
            if got != want:
                raise ValueError(f"ranker weights: {name} has shape {got}, expected {want}")
        if not np.all(self.std > 0):
            raise ValueError("ranker weights: std must be positive")
        for name in ("W1", "b1", "w2", "mean", "std"):
            if not np.all(np.isfinite(getattr(self, name))):
                raise ValueError(f"ranker weights: {name} is not finite")
            getattr(self, name).flags.writeable = False
        if not math.isfinite(self.b2):
            raise ValueError("ranker weights: b2 is not finite")

    @classmethod
    def load(cls, path: str | Path | None = None) -> LearnedRanker:
        """Read weights written by ``clc.train.save_ranker`` (default ``DEFAULT_MODEL``).

        A file already read, unchanged since (same size and modification time), gives the
        instance read then (its arrays are read-only)."""
        path = Path(path) if path is not None else DEFAULT_MODEL
        try:
            st = path.stat()
        except FileNotFoundError:
            raise FileNotFoundError(
                f"no learned CLC ranker at {path}: train one with `rld train-ranker` "
                "(needs the train extra), or use ranker='longest'") from None
        # The absolute path, not resolve(): resolving symlinks took 0.14 ms of every stateless
        # call; a file reached by two names is merely read twice.
        key = os.path.abspath(path)
        size, mtime, ranker = _LOADED.get(key, (-1, -1, None))
        if ranker is None or (size, mtime) != (st.st_size, st.st_mtime_ns):
            ranker = cls._read(path)
            _LOADED[key] = (st.st_size, st.st_mtime_ns, ranker)
        return ranker

    @classmethod
    def _read(cls, path: Path) -> LearnedRanker:
        with np.load(path, allow_pickle=False) as z:
            missing = [k for k in _ARRAYS if k not in z.files]
            if missing:
                raise ValueError(f"ranker weights {path}: missing arrays {missing}")
            names = tuple(str(v) for v in np.atleast_1d(z["feature_names"]))
            if names != FEATURE_NAMES:
                raise ValueError(f"ranker features {names} differ from {FEATURE_NAMES}")
            b2 = np.asarray(z["b2"], dtype=np.float64)
            if b2.shape != ():
                raise ValueError(f"ranker weights: b2 has shape {b2.shape}, expected ()")
            return cls(z["W1"], z["b1"], z["w2"], float(b2), z["mean"], z["std"])

    def net(self, features: np.ndarray) -> np.ndarray:
        """Net(x) of section VII for every row of ``features`` (K, 8): (K,) float64."""
        z = (np.asarray(features, dtype=np.float64) - self.mean) / self.std
        return np.maximum(z @ self.W1 + self.b1, 0.0) @ self.w2 + self.b2

    def score(self, points: np.ndarray | None, pose: Pose | None, params: LaneParams | None,
              candidates: Sequence, features: np.ndarray) -> np.ndarray:
        return self.net(np.asarray(features).reshape(-1, len(FEATURE_NAMES)))


def get_ranker(ranker: Any = "learned") -> Ranker:
    """A ranker by name (``RANKERS``), or any object with ``score`` as it is."""
    if hasattr(ranker, "score"):
        return ranker
    if ranker == "learned":
        return LearnedRanker.load()
    if ranker == "rld_cost":
        return RldCostRanker()
    if ranker == "longest":
        return LongestRanker()
    raise ValueError(f"unknown ranker {ranker!r}; use one of {RANKERS} or an object with score()")

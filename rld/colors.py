"""Cone colour classes as Formula Student perception reports them: the one home of their names,
integer codes and meaning for the lane (issue 41).

The rules (FS Driverless handbook, track marking): blue cones mark the left boundary, yellow
the right, small orange the exit and entry lanes, big orange the start, finish and timekeeping
lines, on both sides. So blue is evidence for the left boundary and yellow for the right;
orange and big orange belong to either boundary and, like ``unknown``, say nothing about the
side. The integer codes are those of the public planner teams use (0 unknown, 1 yellow, 2 blue,
3 orange, 4 big orange); ``left`` and ``right`` are kept as aliases of blue and yellow.

The methods receive side labels (``side_labels``): ``SIDE_LEFT`` (blue), ``SIDE_RIGHT``
(yellow), ``SIDE_EITHER`` (orange, big orange: a cone of either boundary) and ``SIDE_UNKNOWN``
(perception could not tell). Colour is evidence, a cost, never a hard rule: a boundary pays for
joining the two sides' classes and for every cone perception could not classify
(``rld.costs.boundary_color_cost``); an orange cone pays for neither.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["CLASSES", "ALIASES", "SIDE_UNKNOWN", "SIDE_LEFT", "SIDE_RIGHT", "SIDE_EITHER",
           "parse_colors",
           "parse_class_probs", "side_labels", "side_labels_from_probs", "PROB_SUM_TOLERANCE"]

#: Class names by integer code (the public planner's numbering), the columns of ``class_probs``.
CLASSES = ("unknown", "yellow", "blue", "orange", "big_orange")
#: Other accepted names: the package's earlier side labels.
ALIASES = {"left": "blue", "right": "yellow"}
SIDE_UNKNOWN, SIDE_LEFT, SIDE_RIGHT, SIDE_EITHER = 0, 1, 2, 3
#: The side each class speaks for, by class code: blue left, yellow right, orange either.
_SIDE_OF_CLASS = np.array([SIDE_UNKNOWN, SIDE_RIGHT, SIDE_LEFT, SIDE_EITHER, SIDE_EITHER])
#: How far (absolute) a row of ``class_probs`` may sum from 1.
PROB_SUM_TOLERANCE = 1e-6
_CODES = {name: k for k, name in enumerate(CLASSES)} | {a: CLASSES.index(c)
                                                        for a, c in ALIASES.items()}


def parse_colors(colors: Any, n: int) -> np.ndarray:
    """Class codes (int64, (n,), see ``CLASSES``) of ``colors``: one name (case-insensitive,
    ``left``/``right`` aliases) or integer code per cone; ValueError naming what is wrong."""
    arr = np.asarray(colors)
    if arr.shape != (n,):
        raise ValueError(f"colors must have one class per cone ({n}), got shape {arr.shape}")
    if arr.dtype.kind in "USO":
        names = [str(c).strip().lower() for c in arr.tolist()]
        bad = sorted(set(names) - set(_CODES))
        if bad:
            raise ValueError(f"unknown colour classes {bad}; use {', '.join(CLASSES)} (or "
                             f"left / right for blue / yellow)")
        return np.array([_CODES[c] for c in names], dtype=np.int64)
    if arr.dtype.kind == "b" or arr.dtype.kind not in "iuf" or (
            arr.size and not np.all(np.isfinite(arr))) or not np.all(arr == np.round(arr)):
        raise ValueError("integer colours must be class codes 0 (unknown), 1 (yellow), 2 (blue), "
                         "3 (orange) or 4 (big orange)")
    codes = arr.astype(np.int64)
    if codes.size and (codes.min() < 0 or codes.max() >= len(CLASSES)):
        raise ValueError(f"colour codes must be 0..{len(CLASSES) - 1} (0 unknown, 1 yellow, "
                         f"2 blue, 3 orange, 4 big orange), got {sorted(set(codes.tolist()))}")
    return codes


def parse_class_probs(probs: Any, n: int) -> np.ndarray:
    """``probs`` as an (n, 5) float array of class probabilities in ``CLASSES``' column order;
    ValueError unless finite, in [0, 1] and each row summing to 1 within ``PROB_SUM_TOLERANCE``."""
    try:
        arr = np.asarray(probs, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"class_probs must be numbers: {exc}") from exc
    if arr.shape != (n, len(CLASSES)):
        raise ValueError(f"class_probs must have shape ({n}, {len(CLASSES)}) (columns "
                         f"{', '.join(CLASSES)}), got {arr.shape}")
    if not np.all(np.isfinite(arr)) or (arr.size and (arr.min() < 0 or arr.max() > 1)):
        raise ValueError("class_probs must be finite probabilities in [0, 1]")
    off = np.abs(arr.sum(axis=1) - 1.0)
    if off.size and off.max() > PROB_SUM_TOLERANCE:
        row = int(np.argmax(off))
        raise ValueError(f"class_probs rows must sum to 1 (within {PROB_SUM_TOLERANCE:g}); row "
                         f"{row} sums to {arr[row].sum():.9g}")
    return arr


def side_labels(codes: np.ndarray) -> np.ndarray:
    """The side each class code speaks for (``SIDE_*``, int64): blue left, yellow right,
    orange and big orange either, unknown unknown."""
    return _SIDE_OF_CLASS[np.asarray(codes, dtype=np.int64)]


def side_labels_from_probs(probs: np.ndarray) -> np.ndarray:
    """Side labels from class probabilities: left where blue has more than half the mass, right
    where yellow has, either where the two oranges together have, else unknown (until the
    methods weigh probabilities themselves)."""
    probs = np.asarray(probs, dtype=np.float64)
    out = np.full(probs.shape[0], SIDE_UNKNOWN, dtype=np.int64)
    out[probs[:, CLASSES.index("blue")] > 0.5] = SIDE_LEFT
    out[probs[:, CLASSES.index("yellow")] > 0.5] = SIDE_RIGHT
    out[probs[:, CLASSES.index("orange")] + probs[:, CLASSES.index("big_orange")] > 0.5] = \
        SIDE_EITHER
    return out

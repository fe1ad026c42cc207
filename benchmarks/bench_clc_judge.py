"""How often CLC's dive judge picks a right lane when it has one (``rld bench clc-judge``).

The dive judge (``clc.solver.dive_cost``, ``ClcModel._cheapest``) keeps the winner unless a
contender (a dive's lane, a local edit, an outward drop) is strictly cheaper; the cheapest
then wins. Its cost is a weighted sum of seven terms within ``DIVE_REACH_M`` of the car
(``TERMS``): the spacing cost, the edge count (times -1: RLD's benefit), the heading cost, the
angle cost and the regularity cost of RLD's objective (eq. 29), the width roughness and the
turn roughness (ours). ``judge_weights`` gives today's weights of those terms, so that
``terms(...) @ judge_weights(params)`` is the judge's cost.

``collect`` runs CLC over a lap of the evaluation protocol (a fresh ``LaneSolver`` per pose,
as ``rld bench clc-failures``) and keeps every *mixed* decision: one where among the winner
and the feasible contenders at least one lane is right and one is wrong, by the protocol's
tolerant rule (``rld.metrics.diverges_early``). ``accuracy`` is the share of those where a
set of weights picks a right lane, by the judge's own rule. ``fit`` searches the weights
(coordinate steps on each, from today's) for the highest accuracy on the decisions given.

The lanes are labelled as the judge sees them: before the winner is trimmed to its first cone
not behind the car (``clc.search.trim_behind``) and unhooked (``clc.search.unhook``); the
protocol allows a lane to begin with true cones behind the car, so the trim rarely changes a
label. The decisions are on-policy for today's judge: a judge with other weights makes other
decisions later in the same call. So a fitted accuracy says where to look, not what the
protocol will measure; the protocol (``rld eval --param``) says that
(docs/clc.md, "A judge fitted to its own decisions").
"""

from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

TERMS = ("spacing", "minus_edges", "heading", "angle", "regularity", "width_roughness",
         "turn_roughness")
#: The LaneParams field that weighs each of ``TERMS`` in the judge.
WEIGHT_FIELDS = ("w_spacing", "w_benefit", "w_heading", "w_angle", "w_regularity",
                 "w_width_roughness", "w_turn_roughness")
#: The multiplicative steps ``fit`` tries on each weight (0 drops the term).
STEPS = (0.0, 0.25, 0.5, 0.8, 1.25, 2.0, 4.0, 8.0, 16.0)


def judge_weights(params) -> np.ndarray:
    """Today's weight of each of ``TERMS`` (the LaneParams fields of ``WEIGHT_FIELDS``)."""
    return np.array([float(getattr(params, f)) for f in WEIGHT_FIELDS])


def terms(points: np.ndarray, pose, params, lanes) -> np.ndarray:
    """(K, 7) the judge's terms (``TERMS``) of each open lane ``(left, right)`` of ``lanes``,
    within ``clc.solver.DIVE_REACH_M`` of the car: ``rld.costs.reach_costs`` with one unit
    weight at a time (its other parameters, the tolerances, are ``params``')."""
    from dataclasses import replace

    from clc.solver import DIVE_REACH_M
    from rld.costs import reach_costs

    lanes = [(np.asarray(a), np.asarray(b)) for a, b in lanes]
    out = np.zeros((len(lanes), len(TERMS)))
    # reach_costs takes its weights from LaneParams, which must be positive where RLD needs
    # them: each term is the difference of two calls, the term's weight 1 and 2, the others
    # at their smallest allowed value 1e-12 (contributing below 1e-9 of any term).
    tiny = {f: 1e-12 for f in WEIGHT_FIELDS}
    for j, field in enumerate(WEIGHT_FIELDS):
        one = reach_costs(points, pose, replace(params, **{**tiny, field: 1.0}), lanes,
                          DIVE_REACH_M)
        two = reach_costs(points, pose, replace(params, **{**tiny, field: 2.0}), lanes,
                          DIVE_REACH_M)
        out[:, j] = two - one
    return out


@dataclass
class Decision:
    """One mixed decision of the judge: ``terms`` (K, 7) of the winner (row 0) and the feasible
    open contenders, in the judge's order; ``right`` (K,) whether each is right."""

    track: int
    seed: int
    pose: int
    terms: np.ndarray
    right: np.ndarray


def pick(terms_k: np.ndarray, w: np.ndarray) -> int:
    """The judge's rule: row 0 (the winner) unless another row is strictly cheaper under the
    weights ``w``; then the first cheapest."""
    c = terms_k @ w
    k = int(np.argmin(c))
    return k if c[k] < c[0] else 0


def accuracy(decisions: Sequence[Decision], w: np.ndarray) -> float:
    """The share of ``decisions`` where ``pick`` chooses a right lane (nan for none)."""
    if not decisions:
        return math.nan
    return float(np.mean([bool(d.right[pick(d.terms, w)]) for d in decisions]))


def fit(decisions: Sequence[Decision], w0: np.ndarray, sweeps: int = 4,
        steps: Sequence[float] = STEPS) -> np.ndarray:
    """Coordinate search from ``w0`` for the weights of the highest ``accuracy``: each weight
    but the edge count's (it fixes the scale) in turn times each of ``steps`` (a weight at 0
    restarts from 1 / its term's spread), kept when the accuracy rises; up to ``sweeps``
    rounds, fewer when one changes nothing."""
    w = np.asarray(w0, dtype=np.float64).copy()
    if not decisions:
        return w
    spread = np.concatenate([d.terms for d in decisions]).std(axis=0)
    best = accuracy(decisions, w)
    for _ in range(sweeps):
        moved = False
        for j in range(w.size):
            if j == 1:
                continue
            base = w[j] if w[j] > 0 else 1.0 / max(float(spread[j]), 1e-9)
            for s in steps:
                v = w.copy()
                v[j] = base * s
                a = accuracy(decisions, v)
                if a > best + 1e-9:
                    best, w, moved = a, v, True
        if not moved:
            break
    return w


def collect(track, track_id: int, range_m: float, fp_rate: float, seed: int = 0,
            every: int = 1, params=None) -> list[Decision]:
    """Every mixed decision of the judge over the protocol's lap of ``track`` (see the
    module docstring)."""
    from rld.api import LaneSolver
    from rld.constraints import lane_is_feasible
    from rld.metrics import diverges_early, tolerant_skips
    from rld.simulation import simulate_lap
    from rld.types import LaneParams

    params = params or LaneParams()
    lap = simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed)
    out: list[Decision] = []
    for k in range(0, len(lap), every):
        frame = lap.frame(k)
        skips = tolerant_skips(frame)

        def hook(points, pose, winner, contenders, frame=frame, skips=skips, k=k):
            if winner[2]:
                return
            lanes = [(winner[0], winner[1])]
            for a, b, closed, score in contenders:
                if closed or (score is None
                              and not lane_is_feasible(points[a], points[b], params)):
                    continue
                lanes.append((a, b))
            if len(lanes) < 2:
                return
            right = np.array([not diverges_early(frame, a, b, skips) for a, b in lanes])
            if right.any() and not right.all():
                out.append(Decision(track_id, seed, k, terms(points, pose, params, lanes),
                                    right))

        # Through LaneSolver, as the protocol solves (its input checks and cone handling);
        # the hook sits on the CLC model it wraps.
        solver = LaneSolver("clc", params)
        solver._impl.model.judge_hook = hook
        solver.solve(frame.cones, frame.pose)
    return out


def _job(args) -> list[Decision]:
    from rld.generator import generate_track
    from rld.tracks import find_dataset_dir, load_dataset_track

    source, tid, seed, range_m, fp_rate, every = args
    track = (generate_track(tid) if source == "generated"
             else load_dataset_track(find_dataset_dir(), tid))
    return collect(track, tid, range_m, fp_rate, seed, every)


def run(source: str = "shared", tracks: Sequence[int] | None = None,
        cells: Sequence[tuple[float, float]] = ((30.0, 0.1), (30.0, 0.3), (50.0, 0.3)),
        seeds: Sequence[int] = (5,), every: int = 1, fit_weights: bool = False,
        processes: int = 2, progress: bool = True) -> dict:
    """Collect the mixed decisions on ``source`` ("shared": the dataset tracks, default all;
    "generated": ``rld.generator`` seeds ``tracks``) at every (range m, false-positive rate) of
    ``cells``, the ``seeds`` pooled; today's accuracy per track and pooled. With
    ``fit_weights``, also leave-one-track-out: the weights fitted on the other tracks and
    their accuracy on the track left out, and the weights fitted on all."""
    from multiprocessing import get_context

    from tqdm import tqdm

    from rld.tracks import DATASET_TRACKS, find_dataset_dir
    from rld.types import LaneParams

    if source == "shared":
        if find_dataset_dir() is None:
            raise FileNotFoundError("racetrack dataset not found (../shared/data/...)")
        tracks = list(tracks or DATASET_TRACKS)
    elif source == "generated":
        if not tracks:
            raise ValueError("give the generated tracks' seeds")
        tracks = list(tracks)
    else:
        raise ValueError(f"unknown source {source!r}; use 'shared' or 'generated'")
    jobs = [(source, t, s, r, f, every) for t in tracks for s in seeds for r, f in cells]
    decisions: list[Decision] = []
    with get_context("spawn").Pool(max(1, int(processes))) as pool:
        for part in tqdm(pool.imap_unordered(_job, jobs), total=len(jobs),
                         desc=f"clc judge ({source})", unit="lap", disable=not progress):
            decisions.extend(part)
    w0 = judge_weights(LaneParams())
    per_track = {}
    for t in tracks:
        mine = [d for d in decisions if d.track == t]
        row = {"decisions": len(mine), "today": accuracy(mine, w0)}
        if fit_weights:
            w = fit([d for d in decisions if d.track != t], w0)
            row.update(fitted=w.tolist(), held_out=accuracy(mine, w))
        per_track[t] = row
    out = {"source": source, "cells": [list(c) for c in cells], "seeds": list(seeds),
           "every": every, "decisions": len(decisions), "today": accuracy(decisions, w0),
           "weights_today": w0.tolist(), "per_track": per_track}
    if fit_weights and decisions:
        w = fit(decisions, w0)
        out.update(fitted=w.tolist(), fitted_accuracy=accuracy(decisions, w))
    return out


def to_markdown(result: dict) -> str:
    """One row per track (decisions, today's accuracy, and with a fit the held-out one), a
    pooled row, and the weights."""
    fitted = "fitted" in result
    head = "| track | mixed decisions | today's judge right |"
    rule = "|---|---|---|"
    if fitted:
        head += " fitted on the other tracks, right on this one |"
        rule += "---|"
    lines = [head, rule]
    for t, row in result["per_track"].items():
        line = f"| {t} | {row['decisions']} | {100 * row['today']:.1f} % |"
        if fitted:
            line += f" {100 * row['held_out']:.1f} % |"
        lines.append(line)
    pooled = f"| all | {result['decisions']} | {100 * result['today']:.1f} % |"
    if fitted:
        pooled += f" {100 * result['fitted_accuracy']:.1f} % (fitted on all) |"
    lines.append(pooled)
    text = (f"\nWeights of {', '.join(TERMS)}: today "
            f"{np.round(result['weights_today'], 4).tolist()}")
    if fitted:
        text += f"; fitted on all {np.round(result['fitted'], 4).tolist()}"
    return "\n".join(lines) + "\n" + text + "."

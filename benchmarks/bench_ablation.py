"""Ablation of CLC's additions beyond the paper, each switched off alone (issue 39, item 3).

``python -m benchmarks.bench_ablation --set choosing --out /tmp/ablation/results`` runs the
baseline (today's defaults) and every variant of ``VARIANTS`` ("without X": one addition
switched off, everything else as today) through the evaluation protocol as ``rld eval`` drives
a method (``rld.evaluation.run_protocol``: one ``LaneSolver`` per lap, ``score_lane``; here all
variants on one simulated lap, pose by pose, see ``run_lap``), on one of two sets (DESIGN.md,
"Choosing and reporting"):

- ``choosing``: the six shared tracks with false-positive seeds 0-4, plus the generated set
  ``rld.generator.generated_set("choosing")`` (false-positive seed 0);
- ``reporting``: the shared tracks with seeds 5-9, plus ``generated_set("reporting")`` (seed 5);

at ranges 30 and 50 m and false-positive rates 0, 10, 30 and 50 %, every ``--every``-th pose.
A variant is switched through ``LaneParams`` fields or through the fields of CLC's refinement
stage (``clc.refine.Refinement``, given to the model's constructor); nothing in the package
changes. The additions the ablation removed (docs/ablation.md) are no longer variants: the table
there reran at commit 0cfe2c5. RLD's two additions (``RLD_VARIANTS``, against ``rld_baseline``:
``--variants rld_baseline,rld_no_lane_cuts,rld_no_heading_fallback --against rld_baseline``)
are switched in ``rld.solver`` around each solve (``patched``).

Results: one JSON-lines file per set and variant (``OUT/SET/VARIANT.jsonl``), a line per lap
with its per-pose records (the geometric deviation, predicted and true lane length, latency).
A run resumes: laps already in a file are not run again. Laps run in an order that covers every
cell early, each lap for every variant before the next lap and each pose for every variant
before the next pose (so load on a shared machine falls on all variants alike, and a run cut
short still holds the same laps for each).

The statistic (``compare``): per variant, the paired difference to the baseline (variant minus
baseline, on the same poses) of the geometric critical % at 1 m and at 0.5 m (pooled over the
cells, and per false-positive rate), of the mean lane length ratio (mean predicted / mean true,
%, points) and of the median latency (ms; steady calls, not a lap's first), each with a 95 %
percentile bootstrap interval over laps (``ratio_interval``, ``median_interval``): a lap (a
track, seed, range and rate) is the unit, resampled with replacement within its cell (part of
the set, range, rate), ``RESAMPLES`` times from a fixed seed; both variants of a pair keep the
same draws. The decision rule (``verdict``): an addition is kept only when switching it off
raises a geometric rate with the interval above zero and lowers none with the interval below
zero; decided on ``choosing``, confirmed on ``reporting``.
"""

from __future__ import annotations

import argparse
import importlib
import json
import math
import subprocess
import sys
import time
from collections.abc import Iterator, Sequence
from contextlib import contextmanager
from dataclasses import dataclass, field, replace
from pathlib import Path

import numpy as np

#: Resamples of the bootstrap intervals.
RESAMPLES = 2000
#: The interval's two-sided level.
LEVEL = 0.95
#: The geometric rule's distances (m) the statistic compares (``rld.metrics``).
GEO_M = (1.0, 0.5)


@dataclass(frozen=True)
class Variant:
    """One arm of the ablation: ``params`` (``LaneParams`` fields) and ``refine``
    (``clc.refine.Refinement`` fields) switch one addition off; empty for the baseline."""

    name: str
    addition: str
    params: dict = field(default_factory=dict)
    refine: dict = field(default_factory=dict)
    tuning: str = ""  # its docs/tuning.md anchor
    method: str = "clc"
    #: RLD only: ``"module.NAME"``: value, set around each solve (``patched``).
    patches: dict = field(default_factory=dict)

    @property
    def switch(self) -> str:
        items = {**self.params, **{f"Refinement.{k}": v for k, v in self.refine.items()},
                 **{k.rsplit(".", 1)[1]: v for k, v in self.patches.items()}}
        parts = [f"{k}={v:g}" if isinstance(v, float) else f"{k}={v}" for k, v in items.items()]
        return ", ".join(parts) or "(defaults)"


BASELINE = Variant("baseline", "today's CLC, every addition on")

#: The variants, one addition switched off in each (docs/clc.md, "Additions beyond the paper").
VARIANTS: tuple[Variant, ...] = (
    Variant("no_nvd_distance", "next-vertex decider: distance term",
            {"nvd_distance_weight": 0.0}, tuning="nvd_distance_weight"),
    Variant("no_nvd_lookahead", "next-vertex decider: look-ahead",
            {"nvd_lookahead_weight": 0.0}, tuning="nvd_lookahead_weight"),
    Variant("no_contested_dives", "contested (close-call) dives",
            refine={"contested": False}, tuning="contested_margin"),
    Variant("no_jog_dives", "jog dives", refine={"jog_dives": 0}, tuning="jog_dives"),
    Variant("no_short_lane_dives", "short-lane dives", refine={"short_lane_m": 0.0},
            tuning="short_lane_m"),
    Variant("one_dive_round", "dive rounds (3; one round without them)",
            refine={"rounds": 1}, tuning="dive_rounds"),
    Variant("no_dive_stage", "dive judge with everything it judges (dives, pair drops)",
            {"contested_margin": 0.0}, tuning="contested_margin"),
    Variant("no_width_roughness", "dive judge: width roughness",
            {"w_width_roughness": 0.0}, tuning="w_width_roughness"),
    Variant("no_pair_drops", "pair drops", refine={"pair_drops": False}, tuning="pair_drops"),
    Variant("no_ring_join", "ring-join drop", refine={"ring_join": False}, tuning="ring_join"),
    Variant("no_trim_behind", "trim-behind", refine={"trim_behind": False},
            tuning="trim_behind"),
    Variant("no_start_lookback", "start look-back", {"start_lookback_m": 0.0},
            tuning="start_lookback_m"),
    Variant("no_narrow_last", "narrow start pairs last", {"start_min_width_m": 0.0},
            tuning="start_min_width_m"),
    Variant("no_runner_up_starts", "runner-up start pairs", {"start_pairs": 1},
            tuning="start_pairs"),
    Variant("it_max_2500", "it_max 250 (the paper's 2500 instead)",
            {"max_iterations": 2500}, tuning="max_iterations"),
)

#: RLD's two additions (issue 39, item 3), switched in ``rld.solver`` around each solve: the lane
#: cuts (its optimum checked by the shared predicate, cut off and solved again; off: every lane
#: accepted, as the paper's RLD returns its optimum) and the heading fallback.
ACCEPT_ALL = "accept-all"
RLD_BASELINE = Variant("rld_baseline", "today's RLD, its additions on", method="rld")
RLD_VARIANTS: tuple[Variant, ...] = (
    Variant("rld_no_lane_cuts", "RLD: lane cuts (the optimum checked, cut off, solved again)",
            tuning="max_cone_spacing_m", method="rld",
            patches={"rld.solver.lane_is_feasible": ACCEPT_ALL}),
    Variant("rld_no_heading_fallback", "RLD: heading fallback (solved again without eq. 9's "
            "row when no lane)", tuning="heading_fallback", method="rld",
            patches={"rld.solver.HEADING_FALLBACK": False}),
)

#: Each set: the shared tracks' false-positive seeds, the generated set, its false-positive seed.
SETS = {"choosing": ((0, 1, 2, 3, 4), "choosing", 0),
        "reporting": ((5, 6, 7, 8, 9), "reporting", 5)}


def combined(variants: Sequence[Variant], name: str = "combined") -> Variant:
    """One variant with every switch of ``variants`` at once (a check that additions judged
    one at a time do not matter together)."""
    params, refine = {}, {}
    for v in variants:
        params.update(v.params)
        refine.update(v.refine)
    return Variant(name, "together: " + ", ".join(v.name for v in variants), params, refine)


def variants_by_name(names: Sequence[str] | None = None) -> list[Variant]:
    """The baseline and the named variants (all when ``names`` is None), baseline first."""
    known = {v.name: v for v in (*VARIANTS, *RLD_VARIANTS, RLD_BASELINE)}
    if names is None:
        return [BASELINE, *VARIANTS]
    bad = [n for n in names if n not in known and n != BASELINE.name]
    if bad:
        raise ValueError(f"unknown variant(s) {bad}; known: {', '.join(known)}")
    return [BASELINE] + [known[n] for n in names if n != BASELINE.name]


@contextmanager
def patched(variant: Variant) -> Iterator[None]:
    """``variant.patches`` set in their modules for the duration (``ACCEPT_ALL``: a predicate
    that accepts every lane), then restored."""
    old = []
    try:
        for key, value in variant.patches.items():
            mod = importlib.import_module(key.rsplit(".", 1)[0])
            attr = key.rsplit(".", 1)[1]
            if not hasattr(mod, attr):
                raise AttributeError(f"{key} does not exist")
            old.append((mod, attr, getattr(mod, attr)))
            setattr(mod, attr, (lambda *a, **k: True) if value == ACCEPT_ALL else value)
        yield
    finally:
        for mod, attr, value in reversed(old):
            setattr(mod, attr, value)


def configured(variant: Variant) -> tuple:
    """The ``LaneParams`` and the ``clc.refine.Refinement`` of ``variant``."""
    from clc.refine import Refinement
    from rld.types import LaneParams

    return replace(LaneParams(), **variant.params), Refinement(**variant.refine)


# ----------------------------------------------------------------------------- the laps

@dataclass(frozen=True)
class Unit:
    """A lap of the protocol: the bootstrap's unit."""

    part: str  # "shared" or "generated"
    track: str
    seed: int
    range_m: float
    fp_rate: float

    @property
    def key(self) -> str:
        return f"{self.part}|{self.track}|{self.seed}|{self.range_m:g}|{self.fp_rate:g}"

    @property
    def cell(self) -> tuple:
        return (self.part, self.range_m, self.fp_rate)


def load_tracks(set_name: str, dataset: str | None = None, shared: Sequence[int] | None = None,
                n_generated: int | None = None) -> dict:
    """{(part, track name): Track} of the set; ``shared``: dataset track numbers (default all),
    ``n_generated``: the first this many of the generated set (default all)."""
    from rld.generator import generated_set
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    folder = Path(dataset) if dataset else find_dataset_dir()
    if folder is None:
        raise SystemExit("the racetrack dataset was not found: give --dataset")
    out = {}
    for n in (DATASET_TRACKS if shared is None else shared):
        t = load_dataset_track(folder, int(n))
        out[("shared", t.name)] = t
    gen = generated_set(SETS[set_name][1])
    for t in gen[: len(gen) if n_generated is None else n_generated]:
        out[("generated", t.name)] = t
    return out


def units(set_name: str, tracks: dict, ranges: Sequence[float],
          fp_rates: Sequence[float]) -> list[Unit]:
    """The set's laps, ordered so that every prefix spreads over the cells: the i-th lap of
    every cell (part, range, rate) before the (i+1)-th of any; within a cell, every track of
    one seed before the next seed."""
    seeds, _, gen_seed = SETS[set_name]
    per_cell = []
    for part in ("shared", "generated"):
        names = [name for p, name in tracks if p == part]
        part_seeds = seeds if part == "shared" else (gen_seed,)
        for r in ranges:
            for fp in fp_rates:
                per_cell.append([Unit(part, name, sd, float(r), float(fp))
                                 for sd in part_seeds for name in names])
    out = []
    for i in range(max((len(c) for c in per_cell), default=0)):
        out += [c[i] for c in per_cell if i < len(c)]
    return out


def run_lap(variants: Sequence[Variant], track, unit: Unit, every: int) -> dict[str, list]:
    """The compact per-pose records of every variant on one lap, driven as ``rld eval`` drives
    a method (``rld.evaluation.run_protocol``, stateful: one ``LaneSolver`` per lap and
    variant, every ``every``-th pose of ``simulate_lap``, scored by ``score_lane``, latency the
    ``solve`` call, a lap's first call marked): one simulated lap for all variants, each pose
    solved by every variant in a seeded random order (so load on a shared machine falls on the
    variants alike) and each distinct lane scored once. ``run_protocol``'s lane tracker, which
    only feeds stability ratios the ablation does not use, is left out; the records agree with
    ``run_protocol``'s (tests/test_bench_ablation.py)."""
    from rld.api import LaneSolver
    from rld.metrics import score_lane
    from rld.simulation import simulate_lap

    lap = simulate_lap(track, range_m=unit.range_m, fp_rate=unit.fp_rate, seed=unit.seed)
    solvers = {}
    for v in variants:
        params, refine = configured(v)
        solvers[v.name] = LaneSolver(method=v.method, params=params,
                                     options={"refine": refine} if v.method == "clc" else None)
    out: dict[str, list] = {v.name: [] for v in variants}
    rng = np.random.default_rng(_key_seed(unit.key))
    for k in range(0, len(lap), every):
        frame = lap.frame(k)
        scores: dict[tuple, object] = {}
        for i in rng.permutation(len(variants)):
            v = variants[int(i)]
            with patched(v):
                t0 = time.perf_counter()
                lane = solvers[v.name].solve(frame.cones, frame.pose, time_limit_s=None,
                                             colors=frame.colors)
                latency = time.perf_counter() - t0
            key = (lane.ok, lane.closed, lane.left.tobytes(), lane.right.tobytes())
            if key not in scores:
                scores[key] = score_lane(frame, lane.left, lane.right, lane.ok, lane.closed)
            sc = scores[key]
            out[v.name].append({
                "pose": k, "deviation_m": sc.deviation_m, "pred_length_m": sc.pred_length_m,
                "true_length_m": sc.true_length_m, "latency_s": latency,
                "first_call": k == 0, "status": lane.status.name,
                "iterations": int(lane.stats.get("iterations", -1)),
                "complete": lane.stats.get("complete"), "too_short": sc.too_short,
                "category_tolerant": sc.category_tolerant})
    return out


def _key_seed(text: str) -> int:
    """A seed from a lap's key, the same in every process (``hash`` of a str is not)."""
    return int.from_bytes(text.encode(), "little") % 2**32


def _commit() -> str:
    root = Path(__file__).resolve().parents[1]
    try:
        head = subprocess.run(["git", "rev-parse", "--short", "HEAD"], cwd=root, check=True,
                              capture_output=True, text=True).stdout.strip()
        dirty = subprocess.run(["git", "status", "--porcelain", "--", "clc", "rld"], cwd=root,
                               check=True, capture_output=True, text=True).stdout.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"
    return head + ("+dirty" if dirty else "")


def result_path(out: str | Path, set_name: str, variant: str) -> Path:
    return Path(out) / set_name / f"{variant}.jsonl"


def read_results(path: Path, every: int | None = None,
                 switch: str | None = None) -> dict[str, dict]:
    """{lap key: line} of a result file (the last line of a key wins), only the lines of
    ``every`` and ``switch`` when given; {} when missing."""
    done = {}
    if path.exists():
        with path.open() as f:
            for line in f:
                line = line.strip()
                if line:
                    try:
                        d = json.loads(line)
                    except json.JSONDecodeError:  # a line cut by an interrupted run
                        continue
                    if ((every is None or d.get("every") == every)
                            and (switch is None or d.get("switch") == switch)):
                        done[d["unit"]] = d
    return done


def run(set_name: str, variants: Sequence[Variant], out: str | Path, every: int = 4,
        ranges: Sequence[float] = (30.0, 50.0), fp_rates: Sequence[float] = (0.0, 0.1, 0.3, 0.5),
        dataset: str | None = None, shared: Sequence[int] | None = None,
        n_generated: int | None = None, progress: bool = True) -> None:
    """Run every lap of the set for every variant whose file lacks it (resumable)."""
    from tqdm import tqdm

    tracks = load_tracks(set_name, dataset, shared, n_generated)
    laps = units(set_name, tracks, ranges, fp_rates)
    paths = {v.name: result_path(out, set_name, v.name) for v in variants}
    for p in paths.values():
        p.parent.mkdir(parents=True, exist_ok=True)
    done = {v.name: set(read_results(paths[v.name], every, v.switch)) for v in variants}
    todo = [(u, [v for v in variants if u.key not in done[v.name]]) for u in laps]
    todo = [(u, vs) for u, vs in todo if vs]
    commit = _commit()
    bar = tqdm(total=sum(len(vs) for _, vs in todo), desc=f"ablation {set_name}",
               unit="lap", disable=not progress)
    for u, vs in todo:
        t0 = time.perf_counter()
        recs = run_lap(vs, tracks[(u.part, u.track)], u, every)
        wall = time.perf_counter() - t0
        for v in vs:
            line = {"unit": u.key, "part": u.part, "track": u.track, "seed": u.seed,
                    "range_m": u.range_m, "fp_rate": u.fp_rate, "every": every,
                    "variant": v.name, "switch": v.switch, "commit": commit,
                    "lap_wall_s": wall, "n_variants": len(vs), "records": recs[v.name]}
            with paths[v.name].open("a") as f:
                f.write(json.dumps(line) + "\n")
        bar.set_postfix_str(u.key, refresh=False)
        bar.update(len(vs))
    bar.close()


# ----------------------------------------------------------------------------- the statistic

def ratio_interval(num: np.ndarray, den: np.ndarray, strata: Sequence, resamples: int = RESAMPLES,
                   seed: int = 0, level: float = LEVEL) -> tuple[float, float, float]:
    """(point, low, high) of sum(num) / sum(den), the interval a percentile bootstrap over the
    units (one entry of ``num``, ``den`` each), resampled with replacement within each stratum
    (``strata``, one label per unit; each stratum keeps its number of units). A paired
    difference of rates is this with ``num`` the per-unit sum of the per-pose differences and
    ``den`` the poses."""
    num = np.asarray(num, dtype=np.float64)
    den = np.asarray(den, dtype=np.float64)
    w = _weights(strata, resamples, seed)
    stat = (w @ num) / (w @ den)
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(stat, [tail, 100.0 - tail])
    return float(num.sum() / den.sum()), float(lo), float(hi)


def _weights(strata: Sequence, resamples: int, seed: int) -> np.ndarray:
    """(resamples, units) how often each unit is drawn: per stratum (in sorted order of its
    label, for determinism), as many draws with replacement as it has units."""
    labels = [str(s) for s in strata]
    rng = np.random.default_rng(seed)
    w = np.zeros((resamples, len(labels)))
    for s in sorted(set(labels)):
        idx = np.array([i for i, x in enumerate(labels) if x == s])
        k = idx.size
        draws = rng.integers(0, k, size=(resamples, k)) + k * np.arange(resamples)[:, None]
        w[:, idx] = np.bincount(draws.ravel(), minlength=resamples * k).reshape(resamples, k)
    return w


def _weighted_lower_median(values_sorted: np.ndarray, w: np.ndarray) -> np.ndarray:
    """Per row of ``w`` (weights of ``values_sorted``'s entries), the lower weighted median."""
    cw = np.cumsum(w, axis=1)
    k = np.argmax(cw >= cw[:, -1:] / 2.0, axis=1)
    return values_sorted[k]


def median_interval(a: np.ndarray, b: np.ndarray, unit_of: np.ndarray, strata: Sequence,
                    resamples: int = RESAMPLES, seed: int = 0,
                    level: float = LEVEL) -> tuple[float, float, float]:
    """(point, low, high) of median(b) - median(a) (lower medians; ``a``, ``b`` per pose,
    ``unit_of`` each pose's unit index into ``strata``), the interval as ``ratio_interval``'s
    (the same draws for the same ``strata`` and ``seed``)."""
    a = np.asarray(a, dtype=np.float64)
    b = np.asarray(b, dtype=np.float64)
    unit_of = np.asarray(unit_of)
    w_units = _weights(strata, resamples, seed)
    oa, ob = np.argsort(a, kind="stable"), np.argsort(b, kind="stable")
    ones = np.ones((1, a.size))
    point = float(_weighted_lower_median(b[ob], ones)[0] - _weighted_lower_median(a[oa], ones)[0])
    stat = np.empty(resamples)
    for s in range(0, resamples, 100):
        w = w_units[s:s + 100][:, unit_of]
        stat[s:s + 100] = (_weighted_lower_median(b[ob], w[:, ob])
                           - _weighted_lower_median(a[oa], w[:, oa]))
    tail = 100.0 * (1.0 - level) / 2.0
    lo, hi = np.percentile(stat, [tail, 100.0 - tail])
    return point, float(lo), float(hi)


def verdict(geo_diffs: Sequence[tuple[float, float, float]]) -> str:
    """The issue's rule on the (point, low, high) differences without - with of the geometric
    rates: ``keep`` when one interval lies above zero (the addition lowers that rate) and none
    below zero (it raises none); else ``remove``."""
    raises = any(lo > 0.0 for _, lo, _ in geo_diffs)
    lowers = any(hi < 0.0 for _, _, hi in geo_diffs)
    return "keep" if raises and not lowers else "remove"


def _paired(base: dict, var: dict) -> tuple[list[str], dict[str, tuple[list, list]]]:
    """The laps both hold, and per lap the two record lists on the poses both hold."""
    keys = [k for k in base if k in var]
    pairs = {}
    for k in keys:
        a = {r["pose"]: r for r in base[k]["records"]}
        b = {r["pose"]: r for r in var[k]["records"]}
        poses = [p for p in a if p in b]
        pairs[k] = ([a[p] for p in poses], [b[p] for p in poses])
    return keys, pairs


def compare(base: dict, var: dict, resamples: int = RESAMPLES, seed: int = 0,
            fp_rates: Sequence[float] | None = None) -> dict:
    """The paired statistic of one variant against the baseline (result files read by
    ``read_results``): ``geo_<d>m`` (pooled) and ``geo_<d>m_fp<rate>`` as (point, low, high)
    in % points, ``length`` (points of the length ratio), ``latency_ms`` (median difference),
    the baseline's own rates and the counts. Only laps and poses both hold count."""
    keys, pairs = _paired(base, var)
    if not keys:
        return {"laps": 0, "poses": 0}
    out: dict = {"laps": len(keys), "poses": sum(len(pairs[k][0]) for k in keys)}
    fps = sorted({base[k]["fp_rate"] for k in keys}) if fp_rates is None else list(fp_rates)

    def cell(k):
        d = base[k]
        return f"{d['part']}|{d['range_m']:g}|{d['fp_rate']:g}"

    def sums(sel, fn):
        return np.array([sum(fn(a, b) for a, b in zip(*pairs[k], strict=True)) for k in sel])

    n_all = sums(keys, lambda a, b: 1.0)
    for d in GEO_M:
        diff = sums(keys, lambda a, b, d=d: 100.0 * ((b["deviation_m"] > d)
                                                     - (a["deviation_m"] > d)))
        out[f"geo_{d:g}m"] = ratio_interval(diff, n_all, [cell(k) for k in keys], resamples,
                                            seed)
        out[f"base_geo_{d:g}m"] = float(
            100.0 * sums(keys, lambda a, b, d=d: a["deviation_m"] > d).sum() / n_all.sum())
        for fp in fps:
            sel = [k for k in keys if base[k]["fp_rate"] == fp]
            if not sel:
                continue
            idx = [keys.index(k) for k in sel]
            out[f"geo_{d:g}m_fp{fp:g}"] = ratio_interval(diff[idx], n_all[idx],
                                                         [cell(k) for k in sel], resamples, seed)
        for part in ("shared", "generated"):
            idx = [i for i, k in enumerate(keys) if base[k]["part"] == part]
            if idx:
                out[f"geo_{d:g}m_{part}"] = ratio_interval(
                    diff[idx], n_all[idx], [cell(keys[i]) for i in idx], resamples, seed)
    dlen = sums(keys, lambda a, b: 100.0 * (_len(b["pred_length_m"]) - _len(a["pred_length_m"])))
    true = sums(keys, lambda a, b: _len(a["true_length_m"]))
    out["length"] = ratio_interval(dlen, true, [cell(k) for k in keys], resamples, seed)
    out["base_length"] = float(100.0 * sums(keys, lambda a, b: _len(a["pred_length_m"])).sum()
                               / true.sum())
    # Latency: steady calls only (a lap's first call compiles and sets up).
    la, lb, unit_of = [], [], []
    for i, k in enumerate(keys):
        for a, b in zip(*pairs[k], strict=True):
            if not (a["first_call"] or b["first_call"]):
                la.append(1000.0 * a["latency_s"])
                lb.append(1000.0 * b["latency_s"])
                unit_of.append(i)
    out["latency_ms"] = median_interval(np.array(la), np.array(lb), np.array(unit_of),
                                        [cell(k) for k in keys], resamples, seed)
    out["base_latency_ms"] = float(np.median(la))
    out["verdict"] = verdict([out[f"geo_{d:g}m"] for d in GEO_M])
    # A cell of one lap is always drawn whole: its interval is a point, not evidence.
    cells = [cell(k) for k in keys]
    out["fewest_laps_per_cell"] = min(cells.count(c) for c in set(cells))
    # Sensitivity: whole tracks as the unit (all laps of a drawn track, within its part), for
    # laps of one track are not independent across seeds, ranges and rates.
    tracks = sorted({(base[k]["part"], base[k]["track"]) for k in keys})
    of = np.array([tracks.index((base[k]["part"], base[k]["track"])) for k in keys])
    t_n = np.bincount(of, weights=n_all, minlength=len(tracks))
    for d in GEO_M:
        diff = sums(keys, lambda a, b, d=d: 100.0 * ((b["deviation_m"] > d)
                                                     - (a["deviation_m"] > d)))
        out[f"geo_{d:g}m_by_track"] = ratio_interval(
            np.bincount(of, weights=diff, minlength=len(tracks)), t_n,
            [p for p, _ in tracks], resamples, seed)
    out["verdict_by_track"] = verdict([out[f"geo_{d:g}m_by_track"] for d in GEO_M])
    if out["fewest_laps_per_cell"] < 2:
        out["verdict"] = out["verdict_by_track"] = "too few laps"
    return out


def _len(v) -> float:
    return 0.0 if v is None or not math.isfinite(v) else float(v)


# ----------------------------------------------------------------------------- the tables

def _ci(t, digits: int = 2) -> str:
    if t is None:
        return "-"
    p, lo, hi = t
    return f"{p:+.{digits}f} ({lo:+.{digits}f}, {hi:+.{digits}f})"


def analyse(out: str | Path, set_name: str, variants: Sequence[Variant],
            resamples: int = RESAMPLES, seed: int = 0, every: int = 4,
            reference: str = BASELINE.name) -> dict[str, dict]:
    """``compare`` of every variant with results (at ``every``) against the baseline on
    ``set_name``, or against the variant named ``reference`` (its file as written)."""
    base = read_results(result_path(out, set_name, reference), every,
                        BASELINE.switch if reference == BASELINE.name else None)
    res = {}
    for v in variants:
        if v.name in (BASELINE.name, reference):
            continue
        var = read_results(result_path(out, set_name, v.name), every, v.switch)
        if base and var:
            res[v.name] = compare(base, var, resamples, seed)
    return res


def cell_table(laps: dict) -> str:
    """Markdown, one row per (range, false-positive rate) of result lines ``laps``: poses,
    geometric critical % at 1 m and 0.5 m, mean predicted / mean true length %, too-short %,
    median / p95 latency ms (a lap's first call left out); the issue targets' figures."""
    cells: dict = {}
    for d in laps.values():
        c = cells.setdefault((d["range_m"], d["fp_rate"]), [])
        c += d["records"]
    rows = ["| R (m) | FP | poses | geometric > 1 m % | > 0.5 m % | length ratio % | "
            "too short % | median / p95 latency (ms) |", "|---|---|---|---|---|---|---|---|"]
    for (r, fp), recs in sorted(cells.items()):
        dev = np.array([x["deviation_m"] for x in recs])
        pred = sum(x["pred_length_m"] for x in recs)
        true = sum(x["true_length_m"] for x in recs)
        short = np.mean([bool(x.get("too_short")) for x in recs])
        lat = 1000.0 * np.array([x["latency_s"] for x in recs if not x["first_call"]])
        times = (f"{np.median(lat):.2f} / {np.percentile(lat, 95):.2f}" if lat.size else "-")
        rows.append(f"| {r:g} | {fp:.0%} | {dev.size} | {100 * np.mean(dev > 1.0):.2f} | "
                    f"{100 * np.mean(dev > 0.5):.2f} | {100 * pred / max(true, 1e-12):.1f} | "
                    f"{100 * short:.2f} | {times} |")
    return "\n".join(rows)


def commits(out: str | Path, set_name: str, variants: Sequence[Variant]) -> set[str]:
    """The commits the result files of ``set_name`` were written at."""
    found = set()
    for v in variants:
        found |= {d.get("commit", "?") for d in
                  read_results(result_path(out, set_name, v.name)).values()}
    return found


def markdown(results: dict[str, dict[str, dict]], variants: Sequence[Variant]) -> str:
    """The table: a row per variant, each set's differences (without - with, % points and
    ms, with 95 % intervals), each set's verdict and the final one (keep only when the
    choosing verdict is keep and the reporting set confirms it)."""
    sets = [s for s in ("choosing", "reporting") if s in results]
    head = "| addition switched off | switch |"
    rule = "|---|---|"
    for s in sets:
        head += (f" {s}: Δ geo 1 m | Δ geo 0.5 m | Δ length ratio | Δ median latency (ms)* |"
                 f" {s} verdict |")
        rule += "---|---|---|---|---|"
    head += " verdict |"
    rule += "---|"
    lines = [head, rule]
    for v in variants:
        if v.name == BASELINE.name:
            continue
        row = f"| {v.addition} (`{v.name}`) | `{v.switch}` |"
        verdicts = {}
        for s in sets:
            r = results[s].get(v.name)
            if not r or not r.get("laps"):
                row += " not run | | | | |"
                continue
            verdicts[s] = r["verdict"]
            row += (f" {_ci(r['geo_1m'])} | {_ci(r['geo_0.5m'])} | {_ci(r['length'], 1)} | "
                    f"{_ci(r['latency_ms'])} | {r['verdict']} |")
        if "choosing" in verdicts and "reporting" in verdicts:
            final = ("keep" if verdicts["choosing"] == verdicts["reporting"] == "keep"
                     else "remove")
            if verdicts["choosing"] != verdicts["reporting"]:
                final += " (sets disagree)"
        elif verdicts.get("choosing") == "remove":
            final = "remove (choosing only)"
        else:
            final = "open (not confirmed)"
        lines.append(row + f" **{final}** |")
    return "\n".join(lines)


def fp_markdown(results: dict[str, dict], variants: Sequence[Variant], set_name: str,
                fp_rates: Sequence[float]) -> str:
    """Per false-positive rate (pooled over ranges and parts): the differences of the
    geometric rates at 1 m and 0.5 m, with 95 % intervals, on ``set_name``."""
    head = "| variant |" + "".join(f" 1 m, {fp:.0%} FP | 0.5 m, {fp:.0%} FP |" for fp in fp_rates)
    lines = [head, "|---|" + "---|---|" * len(fp_rates)]
    for v in variants:
        r = results.get(v.name)
        if not r or not r.get("laps"):
            continue
        lines.append(f"| `{v.name}` |" + "".join(
            f" {_ci(r.get(f'geo_1m_fp{fp:g}'))} | {_ci(r.get(f'geo_0.5m_fp{fp:g}'))} |"
            for fp in fp_rates))
    return "\n".join(lines)


def part_markdown(results: dict[str, dict], variants: Sequence[Variant]) -> str:
    """Per part of the set (the shared tracks, the generated set): the differences of the
    geometric rates at 1 m and 0.5 m, with 95 % intervals."""
    parts = ("shared", "generated")
    lines = ["| variant |" + "".join(f" 1 m, {p} | 0.5 m, {p} |" for p in parts),
             "|---|" + "---|---|" * len(parts)]
    for v in variants:
        r = results.get(v.name)
        if not r or not r.get("laps"):
            continue
        lines.append(f"| `{v.name}` |" + "".join(
            f" {_ci(r.get(f'geo_1m_{p}'))} | {_ci(r.get(f'geo_0.5m_{p}'))} |" for p in parts))
    return "\n".join(lines)


def track_markdown(results: dict[str, dict], variants: Sequence[Variant]) -> str:
    """The sensitivity of the verdict to the bootstrap's unit: whole tracks (within each part
    of the set) instead of laps."""
    lines = ["| variant | 1 m, tracks resampled | 0.5 m, tracks resampled | verdict (laps) | "
             "verdict (tracks) |", "|---|---|---|---|---|"]
    for v in variants:
        r = results.get(v.name)
        if not r or not r.get("laps"):
            continue
        lines.append(f"| `{v.name}` | {_ci(r.get('geo_1m_by_track'))} | "
                     f"{_ci(r.get('geo_0.5m_by_track'))} | {r['verdict']} | "
                     f"{r['verdict_by_track']} |")
    return "\n".join(lines)


def baseline_line(results: dict[str, dict], set_name: str,
                  reference: str = BASELINE.name) -> str:
    r = next((x for x in results.values() if x.get("laps")), None)
    if r is None:
        return f"{set_name}: no results"
    return (f"{set_name}: {r['laps']} laps, {r['poses']} poses; {reference} geometric critical "
            f"{r['base_geo_1m']:.2f} % (1 m) and {r['base_geo_0.5m']:.2f} % (0.5 m), length "
            f"ratio {r['base_length']:.1f} %, median latency {r['base_latency_ms']:.2f} ms")


# ----------------------------------------------------------------------------- the command

def _floats(text: str) -> list[float]:
    return [float(x) for x in text.split(",") if x.strip()]


def main(argv: Sequence[str] | None = None) -> None:
    ap = argparse.ArgumentParser(
        prog="python -m benchmarks.bench_ablation",
        description="Ablation of CLC's additions beyond the paper, each switched off alone, "
                    "on the choosing or reporting set (DESIGN.md 'Choosing and reporting'). "
                    "Runs the missing laps (resumable), then prints the paired differences to "
                    "the baseline with 95 %% lap-bootstrap intervals and the verdicts.")
    ap.add_argument("--set", dest="sets", default="choosing",
                    help="Comma-separated sets to run: choosing, reporting (default: choosing).")
    ap.add_argument("--variants", default=None,
                    help="Comma-separated variant names (default: all); the baseline always "
                         "runs. --list shows them.")
    ap.add_argument("--list", action="store_true", help="List the variants and exit.")
    ap.add_argument("--combine", default=None, metavar="NAMES",
                    help="Comma-separated variant names: also run (and compare) one variant "
                         "with all their switches at once, named by --combine-name.")
    ap.add_argument("--combine-name", default="combined",
                    help="The combined variant's name and file (default: combined).")
    ap.add_argument("--out", default="ablation_out",
                    help="Results folder: OUT/SET/VARIANT.jsonl (default: ablation_out).")
    ap.add_argument("--every", type=int, default=4, help="Every n-th pose (default: 4).")
    ap.add_argument("--ranges", default="30,50", help="Ranges R in m (default: 30,50).")
    ap.add_argument("--fp-rates", default="0,0.1,0.3,0.5",
                    help="False-positive rates (default: 0,0.1,0.3,0.5).")
    ap.add_argument("--dataset", default=None, help="The racetrack dataset folder (default: "
                    "found as rld eval finds it).")
    ap.add_argument("--tracks", default=None,
                    help="Comma-separated shared track numbers (default: all six).")
    ap.add_argument("--generated", type=int, default=None,
                    help="Only the first N tracks of the generated set (default: all 32).")
    ap.add_argument("--processes", type=int, default=1,
                    help="Processes; only 1 is supported (the laps of a shared machine).")
    ap.add_argument("--against", default=BASELINE.name, metavar="NAME",
                    help="Compare with the results of this variant (OUT/SET/NAME.jsonl) "
                         "instead of the baseline's, e.g. a --combine-name (default: baseline).")
    ap.add_argument("--no-run", action="store_true",
                    help="Only analyse the results already in OUT.")
    ap.add_argument("--resamples", type=int, default=RESAMPLES,
                    help=f"Bootstrap resamples (default: {RESAMPLES}).")
    ap.add_argument("--boot-seed", type=int, default=0, help="Bootstrap seed (default: 0).")
    ap.add_argument("--markdown", default=None, help="Also write the tables to this file.")
    args = ap.parse_args(argv)

    if args.list:
        for v in [BASELINE, *VARIANTS, RLD_BASELINE, *RLD_VARIANTS]:
            print(f"{v.name:24s} {v.switch:40s} {v.addition}")
        return
    if args.processes != 1:
        ap.error("--processes: only 1 is supported")
    sets = [s.strip() for s in args.sets.split(",") if s.strip()]
    for s in sets:
        if s not in SETS:
            ap.error(f"--set: unknown set {s!r}; use choosing or reporting")
    try:
        variants = variants_by_name(None if args.variants is None else
                                    [x.strip() for x in args.variants.split(",") if x.strip()])
    except ValueError as exc:
        ap.error(str(exc))
    if args.combine:
        try:
            members = variants_by_name([x.strip() for x in args.combine.split(",")
                                        if x.strip()])
        except ValueError as exc:
            ap.error(str(exc))
        if args.combine_name in {v.name for v in [BASELINE, *VARIANTS]}:
            ap.error("--combine-name: that is the name of a variant")
        variants.append(combined(members[1:], args.combine_name))
    fp_rates = _floats(args.fp_rates)
    if not args.no_run:
        for s in sets:
            run(s, variants, args.out, every=args.every, ranges=_floats(args.ranges),
                fp_rates=fp_rates, dataset=args.dataset,
                shared=None if args.tracks is None else [int(x) for x in args.tracks.split(",")],
                n_generated=args.generated)
    ref = args.against
    results = {s: analyse(args.out, s, variants, args.resamples, args.boot_seed, args.every, ref)
               for s in ("choosing", "reporting") if result_path(args.out, s, ref).exists()}
    variants = [v for v in variants if v.name != ref]  # the reference is no row of its own
    parts = [f"Every {args.every}th pose; differences are variant minus {ref} (without - "
             "with), % points (latency: ms), 95 % paired bootstrap intervals over laps.",
             *(baseline_line(results[s], s, ref)
               + f"; commits {sorted(commits(args.out, s, variants))}" for s in results),
             "", markdown(results, variants)]
    for s in results:
        parts += ["", f"Per false-positive rate, {s}:", "",
                  fp_markdown(results[s], variants, s, fp_rates),
                  "", f"Per part of the set, {s}:", "", part_markdown(results[s], variants),
                  "", f"Whole tracks as the bootstrap's unit, {s}:", "",
                  track_markdown(results[s], variants)]
    for s in sets or results:
        laps = read_results(result_path(args.out, s, ref), args.every)
        if laps:
            parts += ["", f"Per cell, {ref}, {s}:", "", cell_table(laps)]
    text = "\n".join(parts)
    print(text)
    if args.markdown:
        Path(args.markdown).write_text(text + "\n")


if __name__ == "__main__":
    main(sys.argv[1:])

"""The ablation benchmark (benchmarks/bench_ablation.py): its paired lap bootstrap on hand-made
examples whose answers are known, the keep/remove rule, the variants' switches, and its driver
against ``run_protocol``."""

import math

import numpy as np
import pytest

from rld.cli import _benchmark_module
from rld.types import LaneParams

B = _benchmark_module("bench_ablation")  # benchmarks/ is not an installed package


def test_ratio_interval_two_units_is_the_bootstrap_of_two_draws():
    # Units +1 and -1 (one pose each): a resample of two draws has mean -1, 0 or +1 with
    # probabilities 1/4, 1/2, 1/4, so the 2.5 and 97.5 percentiles are -1 and +1.
    point, lo, hi = B.ratio_interval([1.0, -1.0], [1.0, 1.0], ["a", "a"], resamples=4000)
    assert point == 0.0
    assert (lo, hi) == (-1.0, 1.0)


def test_ratio_interval_keeps_each_stratum_whole():
    # A stratum of one unit is drawn in every resample; a stratum of equal units gives the same
    # sums whichever are drawn: the interval is the point, 5 / 30.
    point, lo, hi = B.ratio_interval([5.0, 0.0, 0.0], [10.0, 10.0, 10.0], ["x", "y", "y"])
    assert point == pytest.approx(1 / 6)
    assert lo == pytest.approx(1 / 6) and hi == pytest.approx(1 / 6)


def test_ratio_interval_is_seeded():
    num, den, strata = [3.0, 0.0, 1.0, 7.0], [10.0, 12.0, 9.0, 11.0], ["a", "a", "b", "b"]
    assert B.ratio_interval(num, den, strata, seed=3) == B.ratio_interval(num, den, strata,
                                                                           seed=3)


def test_median_interval_of_a_shift_is_the_shift():
    rng = np.random.default_rng(0)
    a = rng.exponential(3.0, size=60)
    unit_of = np.repeat(np.arange(6), 10)
    point, lo, hi = B.median_interval(a, a + 2.0, unit_of, ["s"] * 6, resamples=300)
    assert point == pytest.approx(2.0) and lo == pytest.approx(2.0) and hi == pytest.approx(2.0)


def _results(critical: dict[str, list[bool]], fp=0.3, latency=0.005, length=10.0) -> dict:
    """Result-file lines as ``read_results`` returns them: one lap per key, a pose per flag
    (critical: deviation 2 m, else 0.1 m)."""
    out = {}
    for key, flags in critical.items():
        out[key] = {"unit": key, "part": "shared", "track": key, "range_m": 50.0, "fp_rate": fp,
                    "records": [{"pose": 4 * i, "deviation_m": 2.0 if c else 0.1,
                                 "pred_length_m": length, "true_length_m": 10.0,
                                 "latency_s": latency, "first_call": i == 0}
                                for i, c in enumerate(flags)]}
    return out


def test_compare_pairs_the_poses():
    # The baseline's laps differ widely (0 to 7 critical poses of 10); switching the addition
    # off makes exactly one more pose critical in every lap. Paired, the difference is exactly
    # +10 points whichever laps are drawn, so the interval is the point: a keep. Unpaired,
    # the spread between laps would swamp it.
    base = {f"lap{j}": [i < j for i in range(10)] for j in (0, 2, 5, 7)}
    var = {k: [i < j + 1 for i in range(10)] for k, j in zip(base, (0, 2, 5, 7), strict=True)}
    r = B.compare(_results(base), _results(var, latency=0.007, length=9.0), resamples=500)
    assert r["laps"] == 4 and r["poses"] == 40
    for d in ("1m", "0.5m"):
        assert r[f"geo_{d}"] == pytest.approx((10.0, 10.0, 10.0))
        assert r[f"geo_{d}_fp0.3"] == pytest.approx((10.0, 10.0, 10.0))
    assert r["base_geo_1m"] == pytest.approx(100.0 * 14 / 40)
    assert r["length"] == pytest.approx((-10.0, -10.0, -10.0))  # 9 m of 10, from 10 m of 10
    assert r["latency_ms"] == pytest.approx((2.0, 2.0, 2.0))  # first calls left out
    assert r["verdict"] == "keep"
    # Each lap its own track here: whole tracks resampled give the same answer.
    assert r["geo_1m_by_track"] == pytest.approx((10.0, 10.0, 10.0))
    assert r["verdict_by_track"] == "keep"


def test_compare_identical_runs_remove():
    base = {f"lap{j}": [i < j for i in range(8)] for j in (0, 3)}
    r = B.compare(_results(base), _results(base), resamples=200)
    assert r["geo_1m"] == (0.0, 0.0, 0.0)
    assert r["verdict"] == "remove"


def test_compare_counts_only_poses_both_hold():
    base = _results({"a": [True, False, False], "b": [False, False]})
    var = _results({"a": [True, True]})  # lap b missing, lap a one pose short
    r = B.compare(base, var, resamples=100)
    assert r["laps"] == 1 and r["poses"] == 2
    assert r["geo_1m"][0] == pytest.approx(50.0)


@pytest.mark.parametrize(("diffs", "want"), [
    ([(0.5, 0.1, 0.9), (0.2, -0.1, 0.5)], "keep"),     # raises one rate, lowers none
    ([(0.5, 0.1, 0.9), (-0.5, -0.9, -0.1)], "remove"),  # raises one, lowers the other
    ([(0.5, -0.1, 0.9), (0.2, -0.1, 0.5)], "remove"),  # no interval above zero
    ([(0.0, 0.0, 0.0), (0.0, 0.0, 0.0)], "remove"),    # changes nothing
    ([(-0.3, -0.6, -0.1), (0.0, 0.0, 0.0)], "remove"),  # the addition raises a rate
])
def test_verdict(diffs, want):
    assert B.verdict(diffs) == want


def test_variants_switch_existing_knobs():
    from dataclasses import fields

    from clc.refine import Refinement

    names = [v.name for v in B.VARIANTS]
    assert len(set(names)) == len(names)
    for v in B.VARIANTS:
        assert v.params or v.refine, v.name
        params, refine = B.configured(v)
        assert isinstance(params, LaneParams) and isinstance(refine, Refinement)
        for k, value in v.params.items():
            assert getattr(params, k) == value != getattr(LaneParams(), k)
        assert set(v.refine) <= {f.name for f in fields(Refinement)}
        for k, value in v.refine.items():
            assert getattr(refine, k) == value != getattr(Refinement(), k)


def test_units_spread_over_the_cells():
    tracks = {("shared", "t1"): None, ("shared", "t2"): None, ("generated", "g1"): None}
    laps = B.units("choosing", tracks, (30.0, 50.0), (0.0, 0.5))
    assert len(laps) == 2 * 5 * 4 + 1 * 1 * 4
    assert len({u.key for u in laps}) == len(laps)
    assert {u.cell for u in laps[:8]} == {(p, r, f) for p in ("shared", "generated")
                                          for r in (30.0, 50.0) for f in (0.0, 0.5)}
    assert {u.seed for u in laps if u.part == "shared"} == {0, 1, 2, 3, 4}
    assert {u.seed for u in B.units("reporting", tracks, (30.0,), (0.0,))
            if u.part == "shared"} == {5, 6, 7, 8, 9}


def test_run_lap_records_agree_with_run_protocol():
    from rld.evaluation import run_protocol
    from rld.generator import generate_track

    track = generate_track(7)
    unit = B.Unit("generated", track.name, 1, 30.0, 0.3)
    variants = [B.BASELINE, next(v for v in B.VARIANTS if v.name == "no_start_lookback")]
    mine = B.run_lap(variants, track, unit, every=15)
    for v in variants:
        params, _ = B.configured(v)
        ref = run_protocol([track], method="clc", params=params, range_m=30.0, fp_rate=0.3,
                           seed=1, every=15, stateful=True)
        got = mine[v.name]
        assert [r.pose for r in ref] == [g["pose"] for g in got]
        for r, g in zip(ref, got, strict=True):
            assert r.status == g["status"] and r.first_call == g["first_call"]
            assert r.pred_length_m == g["pred_length_m"]
            assert r.true_length_m == g["true_length_m"]
            assert (r.deviation_m == g["deviation_m"]
                    or (math.isinf(r.deviation_m) and math.isinf(g["deviation_m"])))


def test_compare_gives_no_verdict_on_one_lap_a_cell():
    base = _results({"a": [False] * 5})
    var = _results({"a": [True] + [False] * 4})
    r = B.compare(base, var, resamples=50)
    assert r["geo_1m"] == pytest.approx((20.0, 20.0, 20.0))  # a point: one lap, always drawn
    assert r["verdict"] == "too few laps"


def test_combined_variant_has_every_switch():
    a = next(v for v in B.VARIANTS if v.name == "no_trim_behind")
    b = next(v for v in B.VARIANTS if v.name == "no_width_roughness")
    c = B.combined([a, b], "both")
    assert c.refine == a.refine and c.params == b.params
    params, refine = B.configured(c)
    assert refine.trim_behind is False and params.w_width_roughness == 0.0


def test_cell_table_hand_worked():
    # Two laps of one cell: 10 poses, 3 beyond 1 m (2 m), 1 between 0.5 and 1 m, the rest
    # 0.1 m; lengths 9 of 10 m each (90 %); one pose too short; latencies 1..10 ms with the
    # first call of each lap left out.
    laps = _results({"a": [True, True, False, False, False], "b": [True, False, False, False,
                                                                    False]}, length=9.0)
    laps["b"]["records"][1]["deviation_m"] = 0.7
    laps["a"]["records"][2]["too_short"] = True
    for k, rec in enumerate(laps["a"]["records"] + laps["b"]["records"]):
        rec["latency_s"] = (k + 1) / 1000.0
    row = B.cell_table(laps).splitlines()[2]
    lat = np.array([2, 3, 4, 5, 7, 8, 9, 10], float)
    assert row == (f"| 50 | 30% | 10 | 30.00 | 40.00 | 90.0 | 10.00 | {np.median(lat):.2f} / "
                   f"{np.percentile(lat, 95):.2f} |")


def test_rld_variants_patch_and_restore():
    import rld.solver

    before = (rld.solver.lane_is_feasible, rld.solver.HEADING_FALLBACK)
    for v in B.RLD_VARIANTS:
        assert v.method == "rld" and v.patches
        with B.patched(v):
            if "HEADING_FALLBACK" in v.switch:
                assert rld.solver.HEADING_FALLBACK is False
            else:
                assert rld.solver.lane_is_feasible(None, None, None) is True
        assert (rld.solver.lane_is_feasible, rld.solver.HEADING_FALLBACK) == before
    assert [v.name for v in B.variants_by_name(["rld_baseline", "rld_no_lane_cuts"])] == [
        "baseline", "rld_baseline", "rld_no_lane_cuts"]

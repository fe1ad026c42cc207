"""``rld eval``: method specs, the parallel protocol run, its files and the CLI."""

from __future__ import annotations

import dataclasses
import json
import math

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from rld.cli import main
from rld.evaluation import PoseRecord, lap_interval, run_protocol, summarize
from rld.generator import generate_track
from rld.report import (
    MethodSpec,
    evaluate,
    headline_markdown,
    parse_method,
    seeds_markdown,
    summaries,
    write_outputs,
)


def test_parse_method():
    assert parse_method("rld") == MethodSpec("rld")
    assert parse_method("rld:highs").kwargs() == {"backend": "highs"}
    assert parse_method("clc:longest").kwargs() == {"ranker": "longest"}
    assert parse_method("clc:longest").label == "clc:longest"
    for bad, msg in (("rldx", "unknown method"), ("rld:gurobi", "no option"),
                     ("clc:best", "unknown ranker"), ("nearest:cpsat", "no option")):
        with pytest.raises(ValueError, match=msg):
            parse_method(bad)


def test_parallel_run_equals_the_serial_protocol(tmp_path):
    track = generate_track(3)
    specs = [parse_method("nearest"), parse_method("clc:longest")]
    recs = evaluate([track], specs, ranges=(30.0,), fp_rates=(0.0, 0.3), every=40,
                    processes=2, progress=False)
    serial = run_protocol([track], method="clc", ranker="longest", range_m=30.0, fp_rate=0.3,
                          every=40, stateful=True, label="clc:longest")
    got = [r for r in recs if r.method == "clc:longest" and r.fp_rate == 0.3]
    assert [(r.pose, r.category, r.iou) for r in got] == \
        [(r.pose, r.category, r.iou) for r in serial]
    rows = summaries(recs)
    assert [(r["method"], r["fp_rate"]) for r in rows] == [
        ("nearest", 0.0), ("nearest", 0.3), ("clc:longest", 0.0), ("clc:longest", 0.3)]
    paths = write_outputs(recs, tmp_path / "out", header="test")
    lines = (tmp_path / "out" / "poses.jsonl").read_text().splitlines()
    assert len(lines) == len(recs) and json.loads(lines[0])["method"] == "nearest"
    md = paths["results"].read_text()
    assert "**clc:longest, R = 30 m**" in md and md.startswith("test")
    assert all(p.exists() and p.stat().st_size > 0 for p in paths["plots"])


def test_eval_command_on_a_generated_track(tmp_path):
    out = tmp_path / "ev"
    page = out / "page" / "results.md"  # its folder is made, as --out's is
    res = CliRunner().invoke(main, [
        "eval", str(tmp_path / "no-such-dataset"), "--generated", "1", "--methods",
        "nearest", "--ranges", "30", "--fp-rates", "0", "--every", "50", "--processes", "1",
        "--out", str(out), "--results", str(page), "--plot-failures"])
    assert res.exit_code == 0, res.output
    assert (out / "summary.json").exists() and (out / "categories.png").exists()
    text = page.read_text()
    assert "CLC paper, Table I" in text and "nearest, R = 30 m" in text
    summary = json.loads((out / "summary.json").read_text())
    if summary[0]["critical"] > 0:
        assert any((out / "failures").iterdir())


def test_several_seeds_are_pooled_and_each_kept(tmp_path):
    track = generate_track(3)
    spec = [parse_method("nearest")]
    recs = evaluate([track], spec, ranges=(30.0,), fp_rates=(0.3,), every=20, seed=(0, 5),
                    processes=1, progress=False)
    by_seed = {sd: [r for r in recs if r.seed == sd] for sd in (0, 5)}
    # Each seed's lap is the protocol's lap with that seed.
    for sd, got in by_seed.items():
        serial = run_protocol([track], method="nearest", range_m=30.0, fp_rate=0.3, every=20,
                              seed=sd, stateful=True)
        assert [(r.pose, r.category, r.n_cones) for r in got] == \
            [(r.pose, r.category, r.n_cones) for r in serial]
    # Different seeds put different false positives in the map.
    assert [r.n_cones for r in by_seed[0]] != [r.n_cones for r in by_seed[5]]
    (row,) = summaries(recs)
    assert row["poses"] == len(recs) == sum(len(v) for v in by_seed.values())
    assert row["seeds"] == [0, 5]
    for key in ("critical", "critical_tolerant"):
        assert row[f"{key}_by_seed"] == [summarize(by_seed[sd])[key] for sd in (0, 5)]
        assert math.isclose(row[key], float(np.mean(row[f"{key}_by_seed"])))  # equal laps
    md = seeds_markdown([row])
    assert "| nearest | 30 | 30% | 0, 5 |" in md
    # One seed: no seed table.
    assert seeds_markdown(summaries(by_seed[0])) == ""
    with pytest.raises(ValueError, match="distinct"):
        evaluate([track], spec, ranges=(30.0,), fp_rates=(0.3,), every=20, seed=(1, 1),
                 processes=1, progress=False)
    text = write_outputs(recs, tmp_path / "out")["results"].read_text()
    assert "**Seeds**" in text


def test_eval_command_takes_several_seeds(tmp_path):
    out = tmp_path / "ev"
    res = CliRunner().invoke(main, [
        "eval", str(tmp_path / "no-such-dataset"), "--generated", "1", "--methods", "nearest",
        "--ranges", "30", "--fp-rates", "0.3", "--every", "50", "--processes", "1",
        "--seed", "0,1", "--out", str(out)])
    assert res.exit_code == 0, res.output
    assert json.loads((out / "summary.json").read_text())[0]["seeds"] == [0, 1]
    res = CliRunner().invoke(main, ["eval", "--generated", "1", "--seed", "0,x"])
    assert res.exit_code != 0 and "seeds are integers" in res.output


def test_eval_command_refuses_unknown_methods(tmp_path):
    res = CliRunner().invoke(main, ["eval", "--methods", "rld,foo", "--generated", "1"])
    assert res.exit_code != 0 and "unknown method" in res.output


def test_stability_is_recorded_and_tabulated(tmp_path):
    from rld.evaluation import _stability
    from rld.metrics import stability_ratio
    from rld.types import Pose

    # Hand-worked: the car drives 1 m along x; the previous lane runs along y = 0, the new one
    # along y = 0.5: at every radius the crossing moved 0.5 m sideways per metre driven.
    prev_line = np.column_stack([np.linspace(0, 40, 41), np.zeros(41)])
    new_line = prev_line + [0.0, 0.5]
    prev = (Pose(0.0, 0.0, 0.0), prev_line, prev_line)
    got = _stability(prev, Pose(1.0, 0.0, 0.0), new_line, prev_line)
    for r in (5, 10, 20):
        # The crossings of y = 0 and y = 0.5 with the circle of radius r about the origin.
        expect = math.hypot(r - math.sqrt(r * r - 0.25), 0.5)
        assert got[f"stability_{r}"] == pytest.approx(expect)
        assert got[f"stability_{r}"] == stability_ratio(prev_line, new_line, (0, 0), r, 1.0)
        assert got[f"tracked_stability_{r}"] == 0.0  # the tracked lane did not move
    assert all(math.isnan(v) for v in _stability(None, Pose(0, 0, 0), new_line, None).values())

    # Driven along a lap, a method's records carry the ratios and the summary their means.
    recs = run_protocol([generate_track(3)], method="clc", range_m=30.0, every=1,
                        stateful=True)[:40]
    vals = [r.stability_10 for r in recs if not math.isnan(r.stability_10)]
    assert len(vals) >= 30 and all(v >= 0 for v in vals)
    rows = summaries(recs)
    assert rows[0]["stability_10"] == pytest.approx(np.mean(vals))
    assert not math.isnan(rows[0]["tracked_stability_10"])
    paths = write_outputs(recs, tmp_path / "out")
    md = paths["results"].read_text()
    assert "**Stability**" in md and "tracked 20 m" in md
    assert (tmp_path / "out" / "stability.png").stat().st_size > 0


def test_failure_pictures_of_several_seeds_do_not_overwrite_each_other(tmp_path):
    """Every critical failure of every seed gets its own picture (the seed is in the name)."""
    track = generate_track(3)
    folder = tmp_path / "fails"
    crit = 0
    for sd in (0, 5):
        recs = run_protocol([track], method="nearest", range_m=30.0, fp_rate=0.3, every=20,
                            seed=sd, plot_failures=str(folder))
        crit += sum(r.deviation_m > 0.5 for r in recs)  # geometric critical at 0.5 m
    assert crit > 0  # the nearest-cone baseline fails here; else the test proves nothing
    pictures = list(folder.iterdir())
    assert len(pictures) == crit
    assert {p.name.split("_seed")[1].split("_")[0] for p in pictures} <= {"0", "5"}


def _lap(track: str, seed: int, n: int, hits: int, strict_hits: int | None = None):
    """A lap of ``n`` poses, the first ``hits`` critical under the tolerant rule (and the first
    ``strict_hits``, default ``hits``, under the strict one)."""
    strict_hits = hits if strict_hits is None else strict_hits
    return [PoseRecord(track=track, pose=k, range_m=30.0, fp_rate=0.3, method="m", status="x",
                       category="diverging_lt20" if k < strict_hits else "near_gt",
                       category_tolerant="failed" if k < hits else "gt", iou=1.0,
                       iou20=1.0, divergence_m=math.inf, pred_length_m=1.0, true_length_m=1.0,
                       latency_s=0.001, n_cones=10, seed=seed) for k in range(n)]


def test_lap_interval_by_hand():
    # Two equal laps at 20 % and 60 %: a resample of two laps pools to 20, 40 or 60 % with
    # probabilities 1/4, 1/2, 1/4, so the 95 % interval is 20 - 60 and a 40 % one is 40 - 40.
    recs = _lap("a", 0, 10, 2) + _lap("b", 0, 10, 6)
    assert lap_interval(recs) == (20.0, 60.0)
    assert lap_interval(recs, level=0.4) == (40.0, 40.0)
    # Laps are (track, seed): the same track with two seeds is two laps.
    assert lap_interval(_lap("a", 0, 10, 2) + _lap("a", 1, 10, 6)) == (20.0, 60.0)
    # Seeds that repeat a track's lap (0 % false positives) do not narrow the interval: the
    # tracks are drawn first (resampling the ten laps alone would give about 30 - 50).
    same = [r for sd in range(5) for t, h in (("a", 2), ("b", 6)) for r in _lap(t, sd, 10, h)]
    assert lap_interval(same) == (20.0, 60.0)
    # The strict rule counts the strict categories.
    assert lap_interval(_lap("a", 0, 10, 2, 5) + _lap("b", 0, 10, 2, 5), tolerant=False) == \
        (50.0, 50.0)
    # Deterministic for a seed.
    many = [r for k in range(6) for r in _lap(f"t{k}", 0, 20, 3 * k)]
    assert lap_interval(many, seed=3) == lap_interval(many, seed=3)
    for bad in ({"level": 1.0}, {"level": 0.0}, {"resamples": 0}):
        with pytest.raises(ValueError):
            lap_interval(recs, **bad)
    with pytest.raises(ValueError, match="no records"):
        lap_interval([])


@given(st.lists(st.tuples(st.integers(1, 30), st.floats(0, 1)), min_size=1, max_size=8),
       st.floats(0.5, 0.99))
@settings(max_examples=60, deadline=None)
def test_lap_interval_lies_between_the_laps(laps, level):
    recs = [r for k, (n, f) in enumerate(laps) for r in _lap(f"t{k % 3}", k, n, int(f * n))]
    rates = [100.0 * int(f * n) / n for n, f in laps]
    lo, hi = lap_interval(recs, level=level, resamples=300)
    assert min(rates) - 1e-9 <= lo <= hi <= max(rates) + 1e-9
    if len(set(rates)) == 1:
        assert lo == hi == pytest.approx(rates[0])


def test_seed_table_gives_the_lap_interval():
    recs = _lap("a", 0, 10, 2) + _lap("b", 0, 10, 6) + _lap("a", 1, 10, 2) + _lap("b", 1, 10, 6)
    (row,) = summaries(recs)
    assert row["critical_tolerant_interval"] == list(lap_interval(recs))
    assert seeds_markdown([row]).rstrip().endswith("| 40.00 (20.00 - 60.00) |")


def _geo(recs, devs):
    return [dataclasses.replace(r, deviation_m=d) for r, d in zip(recs, devs, strict=True)]


def test_geometric_rates_by_hand():
    # Ten poses 0.3, 0.7, 1.5 m and inf (no lane) off, six on the line: critical at 0.5 m
    # 3 of 10, at 1 m 2 of 10, whatever the index rule says (here 3 tolerant-critical poses).
    recs = _geo(_lap("a", 0, 10, 3), (0.3, 0.7, 1.5, math.inf) + (0.0,) * 6)
    out = summarize(recs)
    assert out["geo_critical_1m"] == pytest.approx(20.0)
    assert out["geo_critical_0.5m"] == pytest.approx(30.0)
    assert out["critical_tolerant"] == pytest.approx(30.0)
    # Pooled with a clean lap of the next seed: 2 and 3 of 20; each seed's rate and the
    # pooled one with its lap interval (two laps of one track: 0 % or 20 / 30 %, each drawn).
    clean = _geo(_lap("a", 1, 10, 0), (0.0,) * 10)
    (row,) = summaries(recs + clean)
    assert row["geo_critical_1m_by_seed"] == [20.0, 0.0]
    assert row["geo_critical_0.5m"] == pytest.approx(15.0)
    assert row["geo_critical_1m_interval"] == list(lap_interval(recs + clean, geometric_m=1.0))
    lo, hi = row["geo_critical_0.5m_interval"]
    assert lo == pytest.approx(0.0) and hi == pytest.approx(30.0)
    md = seeds_markdown([row])
    assert "| 20.00 / 0.00 | 30.00 / 0.00 | 10.00 (0.00 - 20.00) | 15.00 (0.00 - 30.00) |" in md
    # Records written before the rule (NaN) make the rate NaN, not a silent 0.
    assert math.isnan(summarize(_lap("a", 0, 10, 3))["geo_critical_1m"])
    assert "| - | - |" in headline_markdown(summaries(_lap("a", 0, 10, 3)))


def test_headline_table_by_hand():
    # Lengths: predicted 1 m (from _lap) of 4 m true: 25 %; two of ten poses too short; the
    # first call is start-up (250 ms), the others' latency 1 ms.
    recs = _geo(_lap("a", 0, 10, 0), (0.7,) + (0.0,) * 9)
    recs = [dataclasses.replace(r, true_length_m=4.0, too_short=k < 2, first_call=k == 0,
                                latency_s=0.25 if k == 0 else 0.001)
            for k, r in enumerate(recs)]
    (row,) = summaries(recs)
    assert row["length_ratio"] == pytest.approx(25.0)
    assert row["short"] == pytest.approx(20.0)
    assert row["startup_calls"] == 1 and row["startup_median_ms"] == pytest.approx(250.0)
    assert row["latency_max_ms"] == pytest.approx(1.0)  # the first call is not latency
    line = headline_markdown([row]).splitlines()[2]
    assert line == ("| m | 30 | 30% | 10 | 0.00 | 10.00 | 1 / 4 (25) | 20.00 | 100.0 | "
                    "1.0 / 1.0 / 1.0 | 250 |")


def test_protocol_records_the_geometric_rule():
    recs = run_protocol([generate_track(3)], method="nearest", range_m=30.0, fp_rate=0.3,
                        every=25)
    dev = np.array([r.deviation_m for r in recs])
    assert not np.isnan(dev).any() and (dev >= 0).all()
    assert (dev[[r.category == "failed" for r in recs]] == math.inf).all()
    out = summarize(recs)
    for d in (1.0, 0.5):
        assert out[f"geo_critical_{d:g}m"] == pytest.approx(100.0 * np.mean(dev > d))
    # Stateless: only the run's first call is start-up.
    assert [r.first_call for r in recs] == [True] + [False] * (len(recs) - 1)
    stateful = run_protocol([generate_track(3)], method="nearest", range_m=30.0, every=100,
                            stateful=True)
    assert stateful[0].first_call and not any(r.first_call for r in stateful[1:])

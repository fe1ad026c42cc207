"""``rld eval``: method specs, the parallel protocol run, its files and the CLI."""

from __future__ import annotations

import json

import pytest
from click.testing import CliRunner

from rld.cli import main
from rld.evaluation import run_protocol
from rld.generator import generate_track
from rld.report import MethodSpec, evaluate, parse_method, summaries, write_outputs


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
    page = tmp_path / "results.md"
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


def test_eval_command_refuses_unknown_methods(tmp_path):
    res = CliRunner().invoke(main, ["eval", "--methods", "rld,foo", "--generated", "1"])
    assert res.exit_code != 0 and "unknown method" in res.output

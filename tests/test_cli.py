import csv
import json

import click
import numpy as np
import pytest
import yaml
from click.testing import CliRunner

from rld import LaneParams
from rld.cli import main
from rld.tracks import Track, write_csv


def _straight(n: int = 10, spacing_m: float = 3.0) -> np.ndarray:
    """Two straight rows of cones 4 m apart along +x: left (y = 2) then right (y = -2)."""
    xs = np.arange(n) * spacing_m
    return np.vstack([np.column_stack([xs, np.full(n, 2.0)]),
                      np.column_stack([xs, np.full(n, -2.0)])])


#: Cone ids of ``_straight()`` in the test maps: not row positions, so that a row index
#: printed for an id shows.
_LEFT_IDS = list(range(110, 120))
_RIGHT_IDS = list(range(140, 150))


def _colour_csv(path, labels=("left", "right"), column="color"):
    """A CSV map of ``_straight()`` with ids and a colour column (left cones ``labels[0]``)."""
    cones = _straight()
    rows = [f"{i},{x:g},{y:g},{labels[0] if k < 10 else labels[1]}"
            for k, (i, (x, y)) in enumerate(zip(_LEFT_IDS + _RIGHT_IDS, cones, strict=True))]
    path.write_text(f"# closed=0\nid,x,y,{column}\n" + "\n".join(rows) + "\n")
    return path


def _yaml_map(path):
    """``_straight()`` in the dataset's format (``id: [x, y]``), ids as in ``_colour_csv``."""
    cones = _straight()
    path.write_text(yaml.safe_dump({i: [float(x), float(y)] for i, (x, y)
                                    in zip(_LEFT_IDS + _RIGHT_IDS, cones, strict=True)}))
    return path


def _assert_user_error(result, *words):
    """One user error: exit code 2, no traceback, and the problem on one line starting with
    "Error" (alone, or after click's usage lines when an option's value is wrong)."""
    assert result.exit_code == 2, result.output
    assert isinstance(result.exception, SystemExit), result.exception
    assert "Traceback" not in result.output
    lines = result.output.strip().splitlines()
    assert lines[-1].startswith("Error: "), result.output
    assert sum(line.startswith("Error") for line in lines) == 1, result.output
    if len(lines) > 1:  # click's usage format
        assert len(lines) == 4 and lines[0].startswith("Usage: "), result.output
        assert lines[1].startswith("Try '") and lines[2] == "", result.output
    for word in words:
        assert word in lines[-1], (word, result.output)


def test_demo_prints_a_summary_and_writes_a_plot(tmp_path):
    out = tmp_path / "lane.png"
    result = CliRunner().invoke(main, ["demo", "--out", str(out)])
    assert result.exit_code == 0, result.output
    for word in ("track", "frame", "status", "solve time", "again", "off line", "length",
                 "index rule", "IoU"):
        assert word in result.output
    # The index-rule category is printed with what it means.
    from rld.metrics import CATEGORY_MEANING
    line = next(x for x in result.output.splitlines() if x.startswith("index rule"))
    assert any(f"{c}: {m}" in line for c, m in CATEGORY_MEANING.items())
    assert out.exists() and out.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_solve_reads_a_csv_map(tmp_path):
    xs = np.arange(0, 30, 3.0)
    cones = np.vstack([np.column_stack([xs, np.full(10, 2.0)]),
                       np.column_stack([xs, np.full(10, -2.0)])])
    path = tmp_path / "map.csv"
    write_csv(Track(cones, np.arange(20), np.arange(10), np.arange(10, 20), closed=False), path)
    plot = tmp_path / "s.png"
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "1,0,0", "--plot", str(plot)])
    assert result.exit_code == 0, result.output
    assert ("OPTIMAL" in result.output or "FEASIBLE" in result.output) and plot.exists()


def test_solve_reads_a_dataset_map(dataset_dir):
    result = CliRunner().invoke(
        main, ["solve", str(dataset_dir / "cone_map_1.yaml"), "--pose", "5,-2,0"]
    )
    assert result.exit_code in (0, 1), result.output
    assert "136 cones" in result.output
    ids = {int(k) for k in yaml.safe_load((dataset_dir / "cone_map_1.yaml").read_text())}
    for line in result.output.splitlines():
        if line.startswith(("left ", "right ")):  # the boundaries as the map's cone ids
            assert set(json.loads(line.split("ids: ", 1)[1])) <= ids, line


def test_solve_reports_bad_input(tmp_path):
    path = tmp_path / "few.csv"
    path.write_text("x,y\n0,0\n1,1\n")
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "0,0,0"])
    _assert_user_error(result, "at least 4")  # the library's ValueError, as one line
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "0,0"])
    _assert_user_error(result, "--pose", "x,y,yaw")


@pytest.mark.parametrize("args, words", [
    (["demo", "--fp-rate", "2"], ["--fp-rate", "0.0<=x<1.0"]),
    (["demo", "--fp-rate", "-0.1"], ["--fp-rate"]),
    (["demo", "--range-m", "0"], ["--range-m", "x>0"]),
    (["demo", "--seed", "-1"], ["--seed"]),
    (["demo", "--out", "/nonexistent/dir/lane.png"], ["--out", "/nonexistent/dir does not exist"]),
    (["demo", "--out", "lane.nope"], ["--out", ".nope"]),
    (["eval", "--every", "0"], ["--every", "x>=1"]),
    (["eval", "--processes", "0"], ["--processes"]),
    (["eval", "--generated", "-1"], ["--generated"]),
    (["eval", "--fp-rates", "0,1"], ["--fp-rates", "1 is not in the range 0<=x<1"]),
    (["eval", "--fp-rates", "0,x"], ["--fp-rates", "'x' is not one"]),
    (["eval", "--ranges", "30,0"], ["--ranges", "x>0"]),
    (["eval", "--ranges", "30,inf"], ["--ranges", "finite"]),
    (["eval", "--seed", "0,-1"], ["--seed"]),
    (["eval", "--seed", ","], ["--seed", "expected comma-separated seeds"]),
    (["eval", "--tracks", "1,a"], ["--tracks"]),
    (["eval", "--methods", ","], ["--methods", "no method"]),
    (["eval", "--methods", "nope"], ["--methods", "unknown method"]),
    (["eval", "--param", "nope=1"], ["--param", "no field 'nope'"]),
    (["train-ranker", "--epochs", "0"], ["--epochs"]),
    (["train-ranker", "--fp-rates", "0.1,1.5"], ["--fp-rates"]),
    (["bench", "rld", "--backends", "cpsat,nope"], ["--backends", "unknown backend 'nope'"]),
    (["bench", "rld", "--sizes", "12,3"], ["--sizes", "x>=4"]),
    (["bench", "rld", "--stride", "0"], ["--stride"]),
    (["bench", "rld", "--time-limit", "0"], ["--time-limit"]),
    (["bench", "budget", "--budgets", "0.02,0"], ["--budgets"]),
    (["bench", "rld-paper", "--cones", "3"], ["--cones"]),
    (["bench", "rld-paper", "--poses", "0"], ["--poses"]),
    (["bench", "rld-paper", "--seeds", "0,1.5"], ["--seeds", "seeds are integers"]),
    (["bench", "rld-paper", "--backend", "cpsat,highs"], ["--backend", "one backend"]),
    (["bench", "protocol", "--range-m", "-5"], ["--range-m"]),
    (["bench", "protocol", "--every", "0"], ["--every"]),
    (["bench", "incremental", "--every", "0"], ["--every"]),
    (["bench", "incremental", "--fp-rates", "2"], ["--fp-rates"]),
    (["bench", "clc", "--ranker", "nope"], ["--ranker"]),
    (["bench", "clc", "--out", "/nonexistent/dir/clc.md"], ["--out", "does not exist"]),
    (["bench", "clc-failures", "--processes", "0"], ["--processes"]),
    (["bench", "clc-failures", "--ranges", "-30"], ["--ranges"]),
    (["bench", "fp-clearance", "--cells", "30:1"], ["--cells", "0 <= rate < 1"]),
    (["bench", "fp-clearance", "--cells", "0:0.1"], ["--cells"]),
    (["bench", "fp-clearance", "--plot", "/nonexistent/dir/p.png"], ["--plot"]),
])
def test_bad_option_values_are_one_line_usage_errors(args, words):
    _assert_user_error(CliRunner().invoke(main, args), *words)


def test_eval_file_errors_are_one_line(tmp_path):
    a_file = tmp_path / "file.txt"
    a_file.write_text("")
    _assert_user_error(CliRunner().invoke(main, ["eval", "--generated", "1", "--out",
                                                 str(a_file / "out")]), "--out", "not a folder")
    _assert_user_error(CliRunner().invoke(main, ["eval", str(tmp_path / "nope")]),
                       "dataset folder", "does not exist")
    # A dataset folder without the track asked for: the missing file is named.
    _assert_user_error(CliRunner().invoke(main, ["eval", str(tmp_path), "--tracks", "9"]),
                       "cone_map_9.yaml", "no such file")
    (tmp_path / "cone_map_9.yaml").write_text("a: [1, 2]\n")
    (tmp_path / "boundaries_9.yaml").write_text("left: [1]\nright: [2]\n")
    _assert_user_error(CliRunner().invoke(main, ["eval", str(tmp_path), "--tracks", "9"]),
                       "cone_map_9.yaml", "cone id 'a' is not an integer")


@pytest.mark.parametrize("name, text, words", [
    ("map.yaml", "1: [0, 0]\na: [1, 2]\n", ["map.yaml", "cone id 'a' is not an integer"]),
    ("map.yaml", "1: [0, 0]\n1.5: [1, 2]\n", ["map.yaml", "cone id 1.5 is not an integer"]),
    ("map.yaml", "1: [0, 0]\n2: [1]\n", ["map.yaml", "cone 2: expected [x, y]"]),
    ("map.yaml", "1: [0, 0]\n2: [1, x]\n", ["map.yaml", "cone 2: expected [x, y]"]),
    ("map.yaml", "1: [0, 0\n", ["map.yaml", "not valid YAML"]),
    ("map.yaml", "- [0, 0]\n- [1, 1]\n", ["map.yaml", "expected a mapping"]),
    ("map.csv", "x,y\n0,0\n1,abc\n", ["map.csv", "line 3", "bad x,y"]),
    ("map.csv", "id,x,y\n1,0,0\nb,1,1\n", ["map.csv", "line 3", "cone id 'b'"]),
    ("map.csv", "id,x,y\n1,0,0\n2,1\n", ["map.csv", "line 3", "no 'y' column"]),
    ("map.csv", "id,x,y\n1,0,0\n1,1,1\n", ["map.csv", "cone id 1 appears twice"]),
    ("map.csv", "id,x,y,side,order\n1,0,0,left,first\n", ["map.csv", "order 'first'"]),
    ("map.csv", "x,y\n", ["map.csv", "no rows"]),
    ("map.txt", "0,0\n", ["map.txt", "unknown map format"]),
])
def test_solve_names_the_file_of_a_malformed_map(tmp_path, name, text, words):
    path = tmp_path / name
    path.write_text(text)
    _assert_user_error(CliRunner().invoke(main, ["solve", str(path), "--pose", "0,0,0"]),
                       *words)


def test_solve_user_errors_are_one_line(tmp_path):
    good = _colour_csv(tmp_path / "map.csv")

    def solve(*args):
        return CliRunner().invoke(main, ["solve", *args])

    _assert_user_error(solve(str(tmp_path / "missing.yaml"), "--pose", "0,0,0"),
                       "MAP", "does not exist")
    _assert_user_error(solve(str(tmp_path), "--pose", "0,0,0"), "MAP", "is a directory")
    for pose in ("0,0", "a,b,c", "1,2,3,4", ""):
        _assert_user_error(solve(str(good), "--pose", pose), "--pose", "x,y,yaw")
    _assert_user_error(solve(str(good), "--pose", "1,0,nan"), "--pose", "finite")
    _assert_user_error(solve(str(good)), "--pose")  # missing
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--out", str(tmp_path / "l.txt")),
                       "--out", ".json or .csv")
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--out", "/nonexistent/dir/l.json"),
                       "--out", "/nonexistent/dir")
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--plot", str(tmp_path)),
                       "--plot", "is a folder")
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--backend", "nope"),
                       "--backend", "unknown backend 'nope'")
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--time-limit", "0"),
                       "--time-limit")
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--param", "nope=1"),
                       "--param", "no field 'nope'")
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--param", "max_iterations=2.5"),
                       "--param", "takes an integer")
    # Refused by the library (a ValueError of LaneSolver), reported as one line.
    _assert_user_error(solve(str(good), "--pose", "1,0,0", "--method", "nearest", "--backend",
                             "highs"), "has no solver backends")
    bad = _colour_csv(tmp_path / "purple.csv", labels=("purple", "yellow"), column="colour")
    _assert_user_error(solve(str(bad), "--pose", "1,0,0"),
                       "purple.csv", "cone 110", "unknown colour 'purple'", "blue, orange")
    assert not (tmp_path / "l.txt").exists()


def test_solve_prints_the_maps_ids_and_writes_json(tmp_path):
    path = _yaml_map(tmp_path / "map.yaml")
    out = tmp_path / "lane.json"
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "1,0,0", "--out", str(out)])
    assert result.exit_code == 0, result.output
    # The lane from the car forward: the first cone a side (x = 0) is behind the car at x = 1.
    assert "ids: [111, 112, 113" in result.output and "ids: [141, 142, 143" in result.output
    doc = json.loads(out.read_text())
    ids = {int(k): v for k, v in yaml.safe_load(path.read_text()).items()}
    assert doc["method"] == "rld" and doc["status"] in ("OPTIMAL", "FEASIBLE") and doc["ok"]
    assert doc["closed"] is False and doc["message"] == "" and doc["pose"] == [1.0, 0.0, 0.0]
    for side, expected in (("left", _LEFT_IDS), ("right", _RIGHT_IDS)):
        assert doc[side]["ids"] and set(doc[side]["ids"]) <= set(ids)
        assert doc[side]["ids"] == expected[1:1 + len(doc[side]["ids"])]
        assert doc[side]["xy"] == [ids[i] for i in doc[side]["ids"]]


def test_solve_writes_csv(tmp_path):
    path = _colour_csv(tmp_path / "map.csv")
    out = tmp_path / "lane.csv"
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "1,0,0", "--out", str(out),
                                       "--method", "nearest"])
    assert result.exit_code == 0, result.output
    rows = list(csv.DictReader(out.open()))
    assert rows and list(rows[0]) == ["side", "order", "id", "x", "y"]
    cones = dict(zip(_LEFT_IDS + _RIGHT_IDS, _straight().tolist(), strict=True))
    for side in ("left", "right"):
        mine = [r for r in rows if r["side"] == side]
        assert [int(r["order"]) for r in mine] == list(range(len(mine))) and mine
        for r in mine:
            assert [float(r["x"]), float(r["y"])] == cones[int(r["id"])]
        assert {int(r["id"]) for r in mine} <= set(_LEFT_IDS if side == "left" else _RIGHT_IDS)


def test_solve_honours_backend_time_limit_and_param(tmp_path):
    path = _colour_csv(tmp_path / "map.csv")
    for backend in ("highs", "cpsat"):
        out = tmp_path / f"{backend}.json"
        result = CliRunner().invoke(main, ["solve", str(path), "--pose", "1,0,0", "--backend",
                                           backend, "--time-limit", "5", "--out", str(out)])
        assert result.exit_code == 0, result.output
        assert f"(backend {backend})" in result.output
        doc = json.loads(out.read_text())
        assert doc["backend"] == backend and doc["time_limit_s"] == 5.0
    # No cone lies within 0.1 m of the car, and no reach beyond: the nearest-neighbour chain
    # finds no start.
    out = tmp_path / "none.json"
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "1,0,0", "--method",
                                       "nearest", "--param", "near_radius_m=0.1", "--param",
                                       "start_reach_m=0", "--out", str(out)])
    assert result.exit_code == 1 and "NOT_FOUND" in result.output, result.output
    doc = json.loads(out.read_text())
    assert doc["params"] == {"near_radius_m": 0.1, "start_reach_m": 0.0} and not doc["ok"]
    assert doc["left"] == {"ids": [], "xy": []} and doc["cost"] is None


def test_solve_reads_colours(tmp_path):
    """The RLD programs charge w_color times the colour cost (``rld.costs.boundary_color_cost``):
    labels swapped throughout leave the lane and cost its two starts on the wrong class,
    1/2 each, more than the right ones."""
    right = _colour_csv(tmp_path / "right.csv")
    swapped = _colour_csv(tmp_path / "swapped.csv", labels=("right", "left"), column="Colour")

    def cost(path, *args):
        out = tmp_path / "lane.json"
        result = CliRunner().invoke(main, ["solve", str(path), "--pose", "1,0,0", "--method",
                                           "rld-sided", "--out", str(out), *args])
        assert result.exit_code == 0, result.output
        assert "20 with a colour label" in result.output
        doc = json.loads(out.read_text())
        assert doc["left"]["ids"] == _LEFT_IDS and doc["right"]["ids"] == _RIGHT_IDS
        return doc["cost"]

    base = cost(right)
    w = LaneParams().w_color
    assert cost(swapped) - base == pytest.approx(2 * 0.5 * w)
    assert cost(swapped, "--param", "w_color=0.5") - base == pytest.approx(2 * 0.5 * 0.5)
    # An empty cell is unknown: no label, no colour cost.
    text = right.read_text().replace(",left\n", ",\n").replace(",right\n", ",\n")
    right.write_text(text)
    result = CliRunner().invoke(main, ["solve", str(right), "--pose", "1,0,0"])
    assert result.exit_code == 0 and "0 with a colour label" in result.output, result.output


def _options(group, path=("rld",)):
    for name, cmd in group.commands.items():
        if isinstance(cmd, click.Group):
            yield from _options(cmd, (*path, name))
        else:
            for p in cmd.params:
                if isinstance(p, click.Option) and p.name not in ("help", "version"):
                    yield " ".join((*path, name)), p


def test_every_option_documents_itself_and_its_default():
    for command, opt in _options(main):
        where = f"{command} {opt.opts[0]}"
        assert opt.help, where
        assert (opt.show_default or opt.is_flag and "default" in opt.help
                or opt.required or opt.multiple), where


def test_bench_incremental_quick(dataset_dir):
    result = CliRunner().invoke(main, ["bench", "incremental", "--quick", "--fp-rates", "0"])
    assert result.exit_code == 0, result.output
    assert "| 0% | all |" in result.output and "lane cones" in result.output


def test_bench_latency_quick(dataset_dir):
    result = CliRunner().invoke(main, ["bench", "latency", "--quick", "--methods",
                                       "rld,rld-incremental"])
    assert result.exit_code == 0, result.output
    rows = {r.split("|")[1].strip(): [c.strip() for c in r.strip("|").split("|")]
            for r in result.output.splitlines() if r.startswith("| rld")}
    assert set(rows) == {"rld", "rld-incremental"}
    for cells in rows.values():
        assert cells[1] == "19"  # 20 poses, the first call left out
        median, p95, top = (float(c) for c in cells[2:5])
        assert 0 < median <= p95 <= top
    assert int(rows["rld"][7].split(" / ")[1]) >= 2  # the chain solved windows past the car's
    assert rows["rld-incremental"][7] == "-"
    bad = CliRunner().invoke(main, ["bench", "latency", "--methods", "rld,foo"])
    assert bad.exit_code != 0 and "foo" in bad.output


def test_bench_clc_failures_quick(dataset_dir):
    result = CliRunner().invoke(main, ["bench", "clc-failures", "--ranges", "30", "--fp-rates",
                                       "0.3", "--every", "25", "--processes", "1"])
    assert result.exit_code == 0, result.output
    row = result.output.strip().splitlines()[-1]
    assert row.startswith("| 30 m | 30% | ")
    cells = [c.strip() for c in row.strip("|").split("|")]
    critical = int(cells[3].split()[0])
    assert sum(int(c) for c in cells[4:7]) == critical  # every critical pose has one class

def test_bench_budget_quick():
    result = CliRunner().invoke(main, ["bench", "budget", "--backends", "cpsat", "--sizes",
                                       "12", "--budgets", "0.05", "--tracks", "1",
                                       "--stride", "100"])
    assert result.exit_code == 0, result.output
    assert "| cpsat | 12 | 50 |" in result.output


def test_bench_rld_paper_quick():
    result = CliRunner().invoke(main, ["bench", "rld-paper", "--poses", "3", "--seeds", "0"])
    assert result.exit_code == 0, result.output
    assert "| all | 1:1 | 9 |" in result.output and "tolerant (%)" in result.output
    assert "Per seed" not in result.output


def test_bench_rld_paper_pools_seeds_and_tallies_each():
    result = CliRunner().invoke(main, ["bench", "rld-paper", "--poses", "2", "--seeds", "0,1"])
    assert result.exit_code == 0, result.output
    assert "| all | 1:5 | 12 |" in result.output  # 2 seeds x 3 topologies x 2 poses
    assert "| false : real | seed 0 | seed 1 |" in result.output


def test_eval_refuses_a_stride_that_restarts_the_incremental_solver():
    result = CliRunner().invoke(main, ["eval", "--generated", "1", "--methods",
                                       "rld-incremental", "--every", "5"])
    assert result.exit_code != 0 and "pose by pose" in result.output


def test_eval_generated_tracks_start_at_the_seed_given(tmp_path):
    result = CliRunner().invoke(main, ["eval", "--generated", "1", "--generated-seed", "105",
                                       "--methods", "nearest", "--ranges", "30", "--fp-rates",
                                       "0", "--every", "40", "--processes", "1",
                                       "--out", str(tmp_path)])
    assert result.exit_code == 0, result.output
    assert "Tracks: generated seed 105." in result.output


def test_eval_param_overrides_reach_the_solver(tmp_path):
    args = ["eval", "--generated", "1", "--methods", "nearest", "--ranges", "30",
            "--fp-rates", "0", "--every", "40", "--processes", "1"]
    plain = CliRunner().invoke(main, args + ["--out", str(tmp_path / "a")])
    # No cone lies within 0.1 m of the car, and no reach beyond: the baseline finds no start
    # and fails everywhere.
    none = CliRunner().invoke(main, args + ["--out", str(tmp_path / "b"),
                                            "--param", "near_radius_m=0.1",
                                            "--param", "start_reach_m=0"])
    assert plain.exit_code == 0 and none.exit_code == 0, plain.output + none.output
    records = [json.loads(line) for line in (tmp_path / "b" / "poses.jsonl").open()]
    assert records and all(r["category"] == "failed" for r in records)
    records = [json.loads(line) for line in (tmp_path / "a" / "poses.jsonl").open()]
    assert any(r["category"] != "failed" for r in records)


def test_bench_rld_paper_param_overrides():
    result = CliRunner().invoke(main, ["bench", "rld-paper", "--poses", "2", "--seeds", "0",
                                       "--param", "near_radius_m=0.1",
                                       "--param", "start_reach_m=0"])
    assert result.exit_code == 0, result.output
    assert "| all | 1:5 | 6 | 100.0 | 100.0 |" in result.output


@pytest.mark.parametrize("item, message", [
    ("no_such_field=1", "no field 'no_such_field'"),
    ("max_iterations=2.5", "takes an integer"),
    ("w_benefit", "give a value"),
    ("max_cones=30", "the window size is --cones"),
])
def test_bench_rld_paper_refuses_bad_params(item, message):
    result = CliRunner().invoke(main, ["bench", "rld-paper", "--poses", "1", "--seeds", "0",
                                       "--param", item])
    assert result.exit_code != 0 and message in result.output, result.output


def test_warmup_compiles_a_method_and_reports_it():
    # nearest and huang: the two methods whose kernels compile in seconds.
    result = CliRunner().invoke(main, ["warmup", "--methods", "nearest,huang", "--quiet"])
    assert result.exit_code == 0, result.output
    assert "nearest" in result.output and "huang" in result.output
    assert "kernel cache" in result.output


def test_warmup_rejects_an_unknown_method():
    result = CliRunner().invoke(main, ["warmup", "--methods", "rld,bogus"])
    assert result.exit_code != 0 and "bogus" in result.output
    from rld.warmup import warmup

    with pytest.raises(ValueError, match="bogus"):
        warmup(["bogus"])

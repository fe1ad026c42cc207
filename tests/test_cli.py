import json

import numpy as np
import pytest
from click.testing import CliRunner

from rld.cli import main
from rld.tracks import Track, write_csv


def test_demo_prints_a_summary_and_writes_a_plot(tmp_path):
    out = tmp_path / "lane.png"
    result = CliRunner().invoke(main, ["demo", "--out", str(out)])
    assert result.exit_code == 0, result.output
    for word in ("track", "frame", "status", "solve time", "again", "score", "IoU"):
        assert word in result.output
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


def test_solve_reports_bad_input(tmp_path):
    path = tmp_path / "few.csv"
    path.write_text("x,y\n0,0\n1,1\n")
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "0,0,0"])
    assert result.exit_code == 1 and "at least 4" in result.output
    result = CliRunner().invoke(main, ["solve", str(path), "--pose", "0,0"])
    assert result.exit_code == 2 and "x,y,yaw" in result.output


def test_bench_incremental_quick(dataset_dir):
    result = CliRunner().invoke(main, ["bench", "incremental", "--quick", "--fp-rates", "0"])
    assert result.exit_code == 0, result.output
    assert "| 0% | all |" in result.output and "lane cones" in result.output


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
    # No cone lies within 0.1 m of the car: the baseline finds no start and fails everywhere.
    none = CliRunner().invoke(main, args + ["--out", str(tmp_path / "b"),
                                            "--param", "near_radius_m=0.1"])
    assert plain.exit_code == 0 and none.exit_code == 0, plain.output + none.output
    records = [json.loads(line) for line in (tmp_path / "b" / "poses.jsonl").open()]
    assert records and all(r["category"] == "failed" for r in records)
    records = [json.loads(line) for line in (tmp_path / "a" / "poses.jsonl").open()]
    assert any(r["category"] != "failed" for r in records)


def test_bench_rld_paper_param_overrides():
    result = CliRunner().invoke(main, ["bench", "rld-paper", "--poses", "2", "--seeds", "0",
                                       "--param", "near_radius_m=0.1"])
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

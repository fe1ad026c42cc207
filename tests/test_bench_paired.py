"""``rld bench paired``: two evaluation runs compared pose by pose (benchmarks/bench_paired.py)."""

from __future__ import annotations

import json
import math

import pytest

from benchmarks import bench_paired as bp


def _rec(pose, dev, method="rld", fp=0.3, pred=20.0, seed=1):
    return dict(track="track 1", pose=pose, range_m=50.0, fp_rate=fp, seed=seed, method=method,
                deviation_m=dev, pred_length_m=pred, true_length_m=40.0)


def _write(folder, recs):
    folder.mkdir()
    (folder / "poses.jsonl").write_text("".join(json.dumps(r) + "\n" for r in recs))
    return folder


def test_records_load_one_method_with_no_lane_as_infinite(tmp_path):
    run = _write(tmp_path / "a", [_rec(0, None), _rec(0, 0.2, method="clc"), _rec(2, 0.7)])
    recs = bp.load_records(run, "rld")
    assert [r["pose"] for r in recs] == [0, 2]
    assert recs[0]["deviation_m"] == math.inf
    with pytest.raises(ValueError, match="no records of method 'huang'"):
        bp.load_records(run, "huang")
    with pytest.raises(FileNotFoundError, match="poses.jsonl not found"):
        bp.load_records(tmp_path, "rld")


def test_table_pairs_the_poses_both_runs_scored():
    # Hand-worked: poses 0, 2, 4 in both runs (6 only in base, left out). At 1 m: base
    # critical at 0 (inf: no lane), other at 4 -> 33.33 -> 33.33, one fixed, one broken, +0.
    # At 0.5 m: base at 0 and 2, other at 2 and 4 -> 66.67 -> 66.67, pose 0 fixed, 4 broken.
    # Lengths: base 0, 20, 20 -> 13.3 m; other 10, 20, 30 -> 20.0 m.
    base = [_rec(0, math.inf, pred=0.0), _rec(2, 0.7), _rec(4, 0.1), _rec(6, 3.0)]
    other = [_rec(4, 1.5, pred=30.0), _rec(2, 0.6), _rec(0, 0.2, pred=10.0)]
    lines = bp.table(base, other).splitlines()
    assert len(lines) == 4  # header, rule, all, one cell
    assert lines[2] == ("| all | 3 | 33.33 -> 33.33 (+0.00 [+0.00, +0.00]; 1 fixed, 1 broken) | "
                        "66.67 -> 66.67 (+0.00 [+0.00, +0.00]; 1 fixed, 1 broken) | "
                        "13.3 -> 20.0 / 40.0 |")
    assert lines[3].startswith("| 50 m 30% | 3 | 33.33 -> 33.33")


def test_a_change_on_one_pose_moves_the_difference_by_its_share():
    base = [_rec(k, 0.1) for k in range(4)] + [_rec(k, 0.1, fp=0.5) for k in range(4)]
    other = [_rec(0, 2.0)] + [_rec(k, 0.1) for k in range(1, 4)] + [
        _rec(k, 0.1, fp=0.5) for k in range(4)]
    lines = bp.table(base, other).splitlines()
    # One of 8 poses broken: +12.50 points pooled, +25.00 in its cell, 0 in the other.
    assert "0.00 -> 12.50 (+12.50 [+12.50, +12.50]; 0 fixed, 1 broken)" in lines[2]
    assert lines[3].startswith("| 50 m 30% | 4 | 0.00 -> 25.00 (+25.00")
    assert lines[4].startswith("| 50 m 50% | 4 | 0.00 -> 0.00 (+0.00")


def test_runs_without_a_common_pose_are_an_error():
    with pytest.raises(ValueError, match="share no pose"):
        bp.table([_rec(0, 0.1)], [_rec(0, 0.1, seed=2)])


def test_the_command_prints_the_table_and_names_a_wrong_folder(tmp_path):
    from click.testing import CliRunner

    from rld.cli import main

    a = _write(tmp_path / "a", [_rec(0, 0.1), _rec(2, 1.2)])
    b = _write(tmp_path / "b", [_rec(0, 0.1), _rec(2, 0.3)])
    result = CliRunner().invoke(main, ["bench", "paired", str(a), str(b)])
    assert result.exit_code == 0, result.output
    assert "| all | 2 | 50.00 -> 0.00 (-50.00 [-50.00, -50.00]; 1 fixed, 0 broken)" in result.output
    result = CliRunner().invoke(main, ["bench", "paired", str(a), str(tmp_path)])
    assert result.exit_code == 2 and "poses.jsonl not found" in result.output

"""benchmarks/bench_color.py's figures on hand-made records (issue 41, item 4)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from benchmarks import bench_color as bc


def _rec(base, acc, dev, pred=10.0, true=20.0, range_m=30.0, fp=0.1):
    return {"base": base, "accuracy": math.nan if acc is None else acc, "deviation_m": dev,
            "pred_length_m": pred, "true_length_m": true, "range_m": range_m, "fp_rate": fp}


def test_rates_lengths_and_the_table_row():
    recs = [_rec("clc", None, d) for d in (0.2, 0.7, 1.2, 0.0)]
    recs += [_rec("clc", 0.95, d, pred=15.0) for d in (0.2, 0.2, 0.7, 0.0)]
    # deviations > 1 m: 1 of 4; > 0.5 m: 2 of 4; length 10 of 20 m.
    assert bc._rate(bc._select(recs, "clc", None), 1.0) == 25.0
    assert bc._rate(bc._select(recs, "clc", None), 0.5) == 50.0
    assert bc._length(bc._select(recs, "clc", None)) == 50.0
    assert bc._rate(bc._select(recs, "clc", 0.95), 0.5) == 25.0
    assert bc._select(recs, "clc", 0.8) == []
    row = bc.tables(recs).splitlines()[2]
    assert row == "| clc | 30 | 10% | 4 | 25.00 / 50.00, 50 | 0.00 / 25.00, 75 | - |"


def _pose(track, pose, dev, seed=0, range_m=30.0, fp=0.1):
    return {"track": track, "pose": pose, "range_m": range_m, "fp_rate": fp, "seed": seed,
            "deviation_m": dev}


def test_weights_compare_pairs_poses_and_counts_both_ways():
    from benchmarks import bench_color_weights as bw

    base = [_pose("track 1", k, d) for k, d in enumerate((0.2, 0.7, 0.9, 0.0))]
    other = [_pose("track 1", k, d) for k, d in enumerate((0.7, 0.2, 0.9, 0.0))]
    other.append(_pose("track 2", 0, 3.0))  # no partner in base: not counted
    assert bw.compare(base, other) == (1, 1)
    assert bw.compare(base, other, d=0.8) == (0, 0)
    point, low, high = bw.paired_interval(base, other[:4])
    assert point == 0.0 and low <= 0.0 <= high
    # Every pose critical: 2 of the 4 were not, +50 % points.
    worse = [_pose("track 1", k, 2.0) for k in range(4)]
    assert bw.paired_interval(base, worse)[0] == 50.0
    assert bw.parse_setting("0.25:0:2") == (0.25, 0.0, 2.0, None)
    assert bw.parse_setting("0:0:0.35:1") == (0.0, 0.0, 0.35, 1.0)
    assert bw.setting_name(0, 0, 0.35, 1.0) == "n0_r0_j0.35_u1"
    for bad in ("0.25:1", "0:0:1:1:1", "0:0:-1"):
        with pytest.raises(ValueError, match="weights >= 0"):
            bw.parse_setting(bad)


def test_latency_table_reports_the_paired_ratio():
    import numpy as np

    from benchmarks import bench_color_latency as bl

    lat = {"clc": np.array([[0.010, 0.011], [0.020, 0.020], [0.030, 0.033]])}
    row = bl.table(lat).splitlines()[2]
    assert row.startswith("| clc | 3 | 20.0 / ")
    assert row.endswith("| 1.100 (1.000) |")


def test_kept_chain_table_pairs_each_variant_with_the_stateless_chain():
    from benchmarks import bench_kept as bk

    def rec(method, k, dev, pred, latency, first=False, range_m=50.0):
        return dict(_pose("track 1", k, dev, range_m=range_m), method=method,
                    pred_length_m=pred, true_length_m=20.0, latency_s=latency,
                    first_call=first)

    base = [rec(bk.STATELESS, k, d, 20.0, 0.1, k == 0) for k, d in enumerate((0.2, 0.7, 1.5, 0))]
    kept = [rec("kept 0.05 s", k, d, 10.0, 0.01, k == 0)
            for k, d in enumerate((0.2, 0.2, 1.5, 0.7))]
    lines = bk.table(base + kept).splitlines()
    assert lines[2].startswith("| stateless | 4 | 25.00 | 50.00 | 20.0 / 20.0 | 100 / 100 / 100 |")
    # > 1 m: the same pose; > 0.5 m: pose 1 no longer, pose 3 now: 2 of 4 both ways, +0.
    assert lines[3].startswith("| kept 0.05 s | 4 | 25.00 (+0.00 [+0.00, +0.00]) | 50.00 (+0.00")
    assert "| 10.0 / 20.0 | 10 / 10 / 10 | 50 m 10%: 25.00 / 50.00, 10 |" in lines[3]


def test_forward_table_counts_the_poses_the_view_fixed_and_broke():
    from benchmarks import bench_forward as bf

    def rec(pose, whole, forward):
        return dict(seed=1, range_m=50.0, fp_rate=0.3, track=1, pose=pose, whole_m=whole,
                    forward_m=forward, whole_length_m=30.0, forward_length_m=28.0)

    recs = [rec(0, 1.5, 0.2), rec(2, 0.7, 0.7), rec(4, 0.1, 0.6)]
    assert bf.lap_interval(recs, 1.0) == pytest.approx((-100 / 3, -100 / 3, -100 / 3))
    assert bf.lap_interval(recs, 0.5) == pytest.approx((0.0, 0.0, 0.0))
    lines = bf.table(recs).splitlines()
    # > 1 m: one pose fixed, none broken; > 0.5 m: one fixed (1.5), one broken (0.1 -> 0.6).
    assert lines[2] == ("| all | 3 | 33.33 / 66.67 | 0.00 / 66.67 | 1 / 0; 1 / 1 | -33.33 "
                        "[-33.33, -33.33], +0.00 [+0.00, +0.00] | 30.0 / 28.0 |")
    assert lines[3].startswith("| 50 m 30% | 3 | 33.33 / 66.67 |")


def test_ends_table_counts_the_poses_the_extension_fixed_and_broke():
    from benchmarks import bench_ends as be

    def rec(pose, off, on, off_gt, on_gt):
        return dict(seed=1, range_m=30.0, fp_rate=0.5, track=1, pose=pose, off_m=off, on_m=on,
                    off_length_m=40.0, on_length_m=42.0, off_gt=off_gt, on_gt=on_gt)

    recs = [rec(0, 0.2, 1.5, False, False), rec(2, 0.7, 0.7, False, True),
            rec(4, 0.6, 0.1, True, True), rec(6, 0.0, 0.0, False, False)]
    assert be.lap_interval(recs, 1.0) == pytest.approx((25.0, 25.0, 25.0))
    assert be.lap_interval(recs, 0.5) == pytest.approx((0.0, 0.0, 0.0))
    lines = be.table(recs).splitlines()
    # > 1 m: one broken (0.2 -> 1.5); > 0.5 m: one broken, one fixed (0.6 -> 0.1).
    assert lines[2] == ("| all | 4 | 0.00 / 50.00 | 25.00 / 50.00 | 0 / 1; 1 / 1 | +25.00 "
                        "[+25.00, +25.00], +0.00 [+0.00, +0.00] | 40.0 / 42.0 | 25.0 / 50.0 |")
    assert lines[3].startswith("| 30 m 50% | 4 | 0.00 / 50.00 |")


def test_agreement_names_the_first_difference():
    from benchmarks import bench_agreement as ba
    from rld.types import Lane, LaneStatus, Pose

    cones = np.array([[0.0, 2.0], [4.0, 2.0], [8.0, 2.0], [0.0, -2.0], [4.0, -2.0],
                      [8.0, -2.0], [12.0, -2.0]])
    pose = Pose(-1.0, 0.0, 0.0)

    def lane(left, right):
        return Lane(cones=cones, left=np.array(left), right=np.array(right),
                    status=LaneStatus.OPTIMAL)

    a, b = lane([0, 1, 2], [3, 4, 5, 6]), lane([0, 1, 2], [3, 4, 5])
    assert ba._first_difference(a, a, pose, False) is None
    side, k, xy = ba._first_difference(a, b, pose, False)
    assert (side, k) == ("right", 3) and xy.tolist() == [12.0, -2.0]
    side, k, _ = ba._first_difference(lane([1, 2], [3, 4, 5]), b, pose, False)
    assert (side, k) == ("left", 0)

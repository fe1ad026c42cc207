"""benchmarks/bench_color.py's figures on hand-made records (issue 41, item 4)."""

from __future__ import annotations

import math

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

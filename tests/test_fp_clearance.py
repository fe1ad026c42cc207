"""False positives kept a distance from the true boundaries (``fp_clearance_m``, an analysis
knob of the protocol's simulation and of the RLD paper's experiment) and the benchmark that
sweeps it (benchmarks/bench_fp_clearance.py)."""

import numpy as np
import pytest
from click.testing import CliRunner
from hypothesis import given, settings
from hypothesis import strategies as st

from rld.cli import _benchmark_module, main
from rld.generator import generate_track
from rld.simulation import in_field, simulate_lap
from rld.tracks import Track

B = _benchmark_module("bench_fp_clearance")  # benchmarks/ is not an installed package
PAPER = _benchmark_module("bench_rld_paper")


def _square(closed: bool) -> Track:
    """Left boundary: the square (0,0)-(10,0)-(10,10)-(0,10); right: the square 2 m outside."""
    inner = np.array([[0, 0], [10, 0], [10, 10], [0, 10]], float)
    outer = np.array([[-2, -2], [12, -2], [12, 12], [-2, 12]], float)
    return Track(np.vstack([inner, outer]), np.arange(8), np.arange(4), np.arange(4, 8),
                 closed=closed)


def test_boundary_distance_by_hand():
    closed, open_ = _square(True), _square(False)
    p = np.array([[5.0, 5.0],    # the square's centre: 5 m from every inner side
                  [-1.0, 5.0],   # between the two left sides: 1 m from each
                  [5.0, 11.0],   # 1 m from both top sides
                  [-1.0, 5.0]])
    np.testing.assert_allclose(closed.boundary_distance(p), [5.0, 1.0, 1.0, 1.0])
    # Open: the segment (0,10)-(0,0) is not a side of the inner line, nor (-2,12)-(-2,-2) of
    # the outer; the centre is still 5 m from the bottom, right and top sides.
    np.testing.assert_allclose(open_.boundary_distance(p[:2]), [5.0, np.hypot(1.0, 5.0)])
    lines = closed.boundary_lines()
    assert lines[0].shape == (5, 2) and np.array_equal(lines[0][0], lines[0][-1])
    assert open_.boundary_lines()[0].shape == (4, 2)


@settings(max_examples=40, deadline=None)
@given(st.integers(0, 30), st.floats(-20, 60), st.floats(-20, 60))
def test_boundary_distance_matches_dense_sampling(seed, x, y):
    """Against brute force: the least distance to points sampled every 1 cm along both
    lines, which is within 1 cm of the exact distance."""
    track = generate_track(seed)
    got = track.boundary_distance(np.array([[x, y]]))[0]
    best = np.inf
    for line in track.boundary_lines():
        a, b = line[:-1], line[1:]
        for i in range(a.shape[0]):
            n = max(2, int(np.ceil(np.hypot(*(b[i] - a[i])) / 0.01)) + 1)
            t = np.linspace(0, 1, n)[:, None]
            pts = a[i] + t * (b[i] - a[i])
            best = min(best, float(np.min(np.hypot(pts[:, 0] - x, pts[:, 1] - y))))
    assert got <= best + 1e-9 and best - got <= 0.01


@pytest.mark.parametrize("clearance", [1.0, 2.0])
def test_lap_clearance_keeps_count_field_and_distance(clearance):
    track = generate_track(4)
    base = simulate_lap(track, range_m=30.0, fp_rate=0.5, seed=1)
    lap = simulate_lap(track, range_m=30.0, fp_rate=0.5, seed=1, fp_clearance_m=clearance)
    fp = lap.false_positives
    assert fp.shape == base.false_positives.shape and fp.shape[0] > 50
    assert np.all(track.boundary_distance(fp) >= clearance)
    assert np.all(in_field(fp, lap.centerline, lap.headings, lap.range_m).any(axis=0))
    # Without the clearance some false positives do fall that near: the knob moves them.
    assert np.any(track.boundary_distance(base.false_positives) < clearance)


def test_lap_clearance_zero_is_the_protocol():
    track = generate_track(4)
    a = simulate_lap(track, range_m=30.0, fp_rate=0.3, seed=2)
    b = simulate_lap(track, range_m=30.0, fp_rate=0.3, seed=2, fp_clearance_m=0.0)
    assert np.array_equal(a.false_positives, b.false_positives)


@pytest.mark.parametrize("bad", [-0.5, float("nan"), float("inf")])
def test_lap_clearance_rejects_bad_values(bad):
    with pytest.raises(ValueError, match="fp_clearance_m"):
        simulate_lap(generate_track(4), range_m=30.0, fp_rate=0.3, fp_clearance_m=bad)


def test_lap_clearance_with_no_room_raises_instead_of_hanging():
    with pytest.raises(ValueError, match="no room"):
        simulate_lap(generate_track(4), range_m=30.0, fp_rate=0.3, fp_clearance_m=1000.0)


def test_paper_frames_clearance_keeps_truth_and_count():
    plain = list(PAPER.frames(0, poses=4))
    kept = list(PAPER.frames(0, poses=4, fp_clearance_m=1.5))
    tracks = PAPER.topologies(0)
    assert len(plain) == len(kept) == 3 * 2 * 4
    near_before = 0
    for a, b in zip(plain, kept, strict=True):
        assert (a.topology, a.ratio) == (b.topology, b.ratio)
        assert a.points.shape == b.points.shape
        track = tracks[a.topology]
        # The frame holds the real cones first, then the false positives.
        n_real = int(sum(np.any(np.all(track.cones == p, axis=1)) for p in a.points))
        assert 0 < n_real < a.points.shape[0]
        np.testing.assert_array_equal(a.points[:n_real], b.points[:n_real])
        assert np.all(track.boundary_distance(b.points[n_real:]) >= 1.5)
        near_before += int(np.sum(track.boundary_distance(a.points[n_real:]) < 1.5))
        assert not b.on_line  # none within the tolerant 0.5 m of a line
    assert near_before > 0


def test_parse_clearances():
    assert B.parse_clearances("0, 0.5,2") == [0.0, 0.5, 2.0]
    for bad in ("", "-1", "nan", "1,inf"):
        with pytest.raises(ValueError):
            B.parse_clearances(bad)


def test_to_markdown_by_hand():
    clc = [{"clearance_m": 1.0, "range_m": 30.0, "fp_rate": 0.3, "poses": 200,
            "critical_tolerant": 3, "critical_strict": 10, "mean_iou_pct": 97.125,
            "fp_near_pct": 12.5}]
    rld = [{"clearance_m": 0.0, "ratio": "1:1", "solves": 90, "inaccurate_pct": 20.0,
            "inaccurate_tolerant_pct": 10.0}]
    text = B.to_markdown(clc, rld)
    assert "| 1 | 30 m | 30% | 200 | 12.5 | 3 | 1.50 | 10 | 5.00 | 97.12 |" in text
    assert "| 0 | 1:1 | 90 | 20.0 | 10.0 |" in text
    assert B.to_markdown([], rld).startswith("RLD")


def test_run_rld_small():
    rows = B.run_rld([0.0, 2.0], seeds=(0,), poses=2, progress=False)
    assert [(r["clearance_m"], r["ratio"]) for r in rows] == [
        (0.0, "1:5"), (0.0, "1:1"), (2.0, "1:5"), (2.0, "1:1")]
    for r in rows:
        assert r["solves"] == 3 * 2
        assert 0.0 <= r["inaccurate_tolerant_pct"] <= r["inaccurate_pct"] <= 100.0


def test_run_clc_small(dataset_dir):
    rows = B.run_clc([0.0, 2.0], seeds=(0,), cells=[(30.0, 0.3)], every=100, processes=1,
                     tracks=[1], progress=False)
    assert [r["clearance_m"] for r in rows] == [0.0, 2.0]
    assert rows[0]["poses"] == rows[1]["poses"] > 0
    assert rows[0]["fp_near_pct"] == 0.0 and 0.0 < rows[1]["fp_near_pct"] < 100.0
    for r in rows:
        assert 0 <= r["critical_tolerant"] <= r["critical_strict"] <= r["poses"]


def test_cli_rejects_bad_options():
    runner = CliRunner()
    for args in (["--methods", "foo"], ["--clearances", "-1"], ["--cells", "30"]):
        res = runner.invoke(main, ["bench", "fp-clearance", *args])
        assert res.exit_code == 2, (args, res.output)


def test_plot_writes_png(tmp_path):
    clc = [{"clearance_m": c, "range_m": 30.0, "fp_rate": 0.3, "poses": 100,
            "critical_tolerant": k, "critical_strict": k, "mean_iou_pct": 99.0,
            "fp_near_pct": 0.0} for c, k in ((0.0, 3), (1.0, 1))]
    rld = [{"clearance_m": c, "ratio": r, "solves": 10, "inaccurate_pct": 5.0,
            "inaccurate_tolerant_pct": 4.0} for c in (0.0, 1.0) for r in ("1:5", "1:1")]
    for args in ((clc, rld), (clc, []), ([], rld)):
        path = tmp_path / f"p{len(args[0])}{len(args[1])}.png"
        B.plot(*args, str(path))
        assert path.stat().st_size > 1000

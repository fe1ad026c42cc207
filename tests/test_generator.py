import math

import numpy as np
import pytest

from rld import geometry as geo
from rld.constraints import c_poly, lane_widths
from rld.generator import (
    CHORD_TOL_M,
    MAX_SPACING_M,
    MAX_WIDTH_M,
    MIN_RADIUS_M,
    MIN_SPACING_M,
    MIN_WIDTH_M,
    generate_track,
)

SEEDS = range(12)


@pytest.fixture(scope="module", params=SEEDS)
def clean(request):
    return generate_track(request.param, noise_m=0.0)


def _gaps(xy):
    return np.hypot(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T)


def test_spacing_rule(clean):
    for xy in (clean.left_xy, clean.right_xy):
        g = _gaps(xy)
        assert MIN_SPACING_M <= g.min() and g.max() <= MAX_SPACING_M


def test_spacing_is_tighter_in_corners(clean):
    # Gaps next to a sharp vertex (turn > 15 degrees) are shorter than the longest gaps.
    xy = clean.left_xy
    turns = np.abs(geo.polyline_turn_angles(xy, closed=True))
    g = _gaps(xy)
    if (turns > math.radians(15)).any():
        assert g[turns > math.radians(15)].mean() < g.max() - 0.5


def test_width_rule(clean):
    w = lane_widths(clean.left_xy, clean.right_xy, closed=True)
    assert w.min() >= MIN_WIDTH_M - CHORD_TOL_M
    assert w.max() <= MAX_WIDTH_M + CHORD_TOL_M


def test_closed_simple_and_separated(clean):
    assert clean.closed
    assert c_poly(clean.left_xy, clean.right_xy, closed=True)
    # The left boundary is the inner ring of a counter-clockwise loop.
    assert geo.lane_polygon(clean.left_xy, clean.right_xy, closed=True).area > 0
    assert abs(geo.polyline_length(clean.left_xy, True) - geo.polyline_length(
        clean.right_xy, True)) < 0.5 * geo.polyline_length(clean.right_xy, True)


def test_turn_radius_rule(clean):
    # Three consecutive points of the design centreline, a metre apart: circumradius >=
    # MIN_RADIUS_M (within the sampling error).
    c = clean.meta["design_centerline"][::4]
    a, b, d = np.roll(c, 1, axis=0), c, np.roll(c, -1, axis=0)
    ab, bd, ad = (np.hypot(*(x - y).T) for x, y in ((a, b), (b, d), (a, d)))
    area2 = np.abs((b - a)[:, 0] * (d - a)[:, 1] - (b - a)[:, 1] * (d - a)[:, 0])
    radius = ab * bd * ad / np.maximum(2 * area2, 1e-12)
    assert radius.min() >= MIN_RADIUS_M * 0.9


def test_features_appear_across_seeds():
    """Hairpins (>= 150 degrees within 25 m) and chicanes (a left then right turn, or the
    reverse, of >= 20 degrees each within 30 m) appear among the seeds."""
    hairpins = chicanes = 0
    for seed in SEEDS:
        c = generate_track(seed, noise_m=0.0).centerline(1.0)
        t = np.diff(np.vstack([c, c[:1]]), axis=0)
        h = np.unwrap(np.arctan2(t[:, 1], t[:, 0]))
        h = np.concatenate([h, h + 2 * math.pi])
        n = c.shape[0]
        turn25 = np.array([h[i + 25] - h[i] for i in range(n)])
        hairpins += bool((np.abs(turn25) >= math.radians(150)).any())
        t15 = np.array([h[i + 15] - h[i] for i in range(n)])
        s = np.radians(20)
        found = any(
            (t15[i] > s and (t15[i + 15 : i + 30] < -s).any())
            or (t15[i] < -s and (t15[i + 15 : i + 30] > s).any())
            for i in range(n - 30)
        )
        chicanes += found
    assert hairpins >= 4 and chicanes >= 2


def test_seeded_and_noisy():
    a, b = generate_track(5), generate_track(5)
    np.testing.assert_array_equal(a.cones, b.cones)
    assert not np.array_equal(generate_track(6).cones[:5], a.cones[:5])
    assert 0.1 <= a.meta["noise_m"] <= 0.3
    noisy = generate_track(5, noise_m=0.2)
    err = noisy.cones - noisy.meta["clean_cones"]
    assert err.std() == pytest.approx(0.2, rel=0.2)
    np.testing.assert_array_equal(generate_track(5, noise_m=0.0).cones,
                                  noisy.meta["clean_cones"])

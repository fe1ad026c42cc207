"""Tests for rld.geometry (and through it the numba kernels of rld.geometry_kernels).

Every formula is checked against a hand-worked answer and, with hypothesis, against an
independent reference: dense sampling of the segments, shapely, or exact rational arithmetic
(``fractions.Fraction``) on integer coordinates, where the degenerate cases (collinear,
touching, parallel, zero-length) are frequent.
"""

from __future__ import annotations

import math
from fractions import Fraction

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from shapely.geometry import LinearRing, LineString, Point, Polygon

from rld import geometry as geo

PI = math.pi

# --- strategies and helpers -------------------------------------------------------------------

int_pt = st.tuples(st.integers(-4, 4), st.integers(-4, 4))
float_coord = st.floats(-10.0, 10.0, allow_nan=False, allow_infinity=False, allow_subnormal=False)
float_pt = st.tuples(float_coord, float_coord)
any_pt = st.one_of(int_pt.map(lambda p: (float(p[0]), float(p[1]))), float_pt)
# Powers of two keep integer geometry exact in floating point (collinear stays collinear).
exact_scale = st.sampled_from([1.0, 0.5, 0.25, 2.0])

N_SAMPLES = 201  # parameter samples per segment: spacing 1/200 of its length
TS = np.linspace(0.0, 1.0, N_SAMPLES)
INTERIOR = (TS > 0.0) & (TS < 1.0)


def _arr(p):
    return np.asarray(p, dtype=np.float64)


def _seg_geom(a, b):
    """shapely geometry of the closed segment ab (a Point when it has zero length).

    GEOS mishandles lines far shorter than a micron (a 1e-165 m LineString is at infinite
    distance from everything), so those are Points too: an error of at most 1e-12 m."""
    a, b = tuple(map(float, a)), tuple(map(float, b))
    return Point(a) if math.dist(a, b) <= 1e-12 else LineString([a, b])


def _samples(a, b):
    a, b = _arr(a), _arr(b)
    return a + TS[:, None] * (b - a)


def _sampled_pair_distances(a0, a1, b0, b1):
    """(201, 201) distances between the sampled points of both segments."""
    pa, pb = _samples(a0, a1), _samples(b0, b1)
    return np.hypot(pa[:, None, 0] - pb[None, :, 0], pa[:, None, 1] - pb[None, :, 1])


def _seg_len(a, b):
    return math.dist(tuple(map(float, a)), tuple(map(float, b)))


def _wrap(x):
    """Angle wrapped to (-pi, pi]."""
    y = math.remainder(x, 2 * PI)  # in [-pi, pi]
    return PI if y <= -PI else y


def _angdiff(x, y):
    """|x - y| modulo 2 pi (pi and -pi are the same direction)."""
    return abs(math.remainder(x - y, 2 * PI))


# Exact rational references on integer (or dyadic) coordinates.


def _sub(p, q):
    return (Fraction(p[0]) - Fraction(q[0]), Fraction(p[1]) - Fraction(q[1]))


def _cross(u, v):
    return u[0] * v[1] - u[1] * v[0]


def _dot(u, v):
    return u[0] * v[0] + u[1] * v[1]


def _exact_point_segment(p, a, b):
    """Exact squared distance from p to segment ab and the foot parameter (None when ab is a
    point)."""
    u = _sub(b, a)
    w = _sub(p, a)
    ll = _dot(u, u)
    if ll == 0:
        return _dot(w, w), None
    t = min(max(_dot(w, u) / ll, Fraction(0)), Fraction(1))
    q = (Fraction(a[0]) + t * u[0] - Fraction(p[0]), Fraction(a[1]) + t * u[1] - Fraction(p[1]))
    return _dot(q, q), t


def _exact_cross(a0, a1, b0, b1):
    """Proper crossing by Cramer's rule: the lines meet at one point with both parameters strictly
    inside (0, 1). Parallel, collinear and zero-length segments have no such point."""
    u, v, w = _sub(a1, a0), _sub(b1, b0), _sub(b0, a0)
    den = _cross(u, v)
    if den == 0:
        return False
    s = _cross(w, v) / den
    t = _cross(w, u) / den
    return 0 < s < 1 and 0 < t < 1


def _exact_distance_end(a0, a1, b0, b1):
    """Exact squared distance and End() by the convexity of the closest-pair set.

    With D > 0 the set of closest pairs is convex in parameter space, so End is True iff exactly
    one endpoint-endpoint pair (as points in the plane) attains D and no foot of an endpoint on
    the interior of the other (non-degenerate) segment attains it. With D = 0, End is True iff
    the segments meet only at a shared endpoint.
    """
    pts = [tuple(Fraction(c) for c in p) for p in (a0, a1, b0, b1)]
    a0, a1, b0, b1 = pts
    if _seg_geom(a0, a1).intersects(_seg_geom(b0, b1)):
        if not ({a0, a1} & {b0, b1}):
            return Fraction(0), False
        u, v = _sub(a1, a0), _sub(b1, b0)
        if _dot(u, u) > 0 and _dot(v, v) > 0 and _cross(u, v) == 0 and _cross(u, _sub(b0, a0)) == 0:
            pa = sorted([_dot(a0, u), _dot(a1, u)])
            pb = sorted([_dot(b0, u), _dot(b1, u)])
            if min(pa[1], pb[1]) - max(pa[0], pb[0]) > 0:
                return Fraction(0), False  # collinear overlap of positive length
        return Fraction(0), True
    feet = [
        _exact_point_segment(a0, b0, b1),
        _exact_point_segment(a1, b0, b1),
        _exact_point_segment(b0, a0, a1),
        _exact_point_segment(b1, a0, a1),
    ]
    d2 = min(f[0] for f in feet)
    interior = any(f[0] == d2 and f[1] is not None and 0 < f[1] < 1 for f in feet)
    pairs = {(p, q) for p in (a0, a1) for q in (b0, b1) if _dot(_sub(p, q), _sub(p, q)) == d2}
    return d2, (not interior) and len(pairs) == 1


def _dist_end(a0, a1, b0, b1):
    d, e = geo.segment_distance_end(_arr(a0), _arr(a1), _arr(b0), _arr(b1))
    return float(d), bool(e)


def _scaled(pts, k):
    return [(p[0] * k, p[1] * k) for p in pts]


# --- point-segment distance -------------------------------------------------------------------


def test_point_segment_distance_hand_worked():
    a, b = (0, 0), (6, 0)
    assert geo.point_segment_distance((3, 4), a, b) == pytest.approx(4.0, abs=1e-12)  # foot inside
    assert geo.point_segment_distance((-3, 4), a, b) == pytest.approx(5.0, abs=1e-12)  # beyond a
    assert geo.point_segment_distance((9, -4), a, b) == pytest.approx(5.0, abs=1e-12)  # beyond b
    assert geo.point_segment_distance((2, 0), a, b) == 0.0  # on the segment
    assert geo.point_segment_distance((4, 5), (1, 1), (1, 1)) == pytest.approx(5.0, abs=1e-12)
    # Oblique segment (0,0)-(4,4); p=(4,0) has its foot at (2,2): distance sqrt(8).
    assert geo.point_segment_distance((4, 0), (0, 0), (4, 4)) == pytest.approx(math.sqrt(8))
    # Broadcasting: three points against one segment.
    out = geo.point_segment_distance([[3, 4], [-3, 4], [2, 0]], a, b)
    assert out.shape == (3,)
    np.testing.assert_allclose(out, [4.0, 5.0, 0.0], atol=1e-12)


@given(seed=st.integers(0, 2**32 - 1), scale=st.sampled_from([1e-3, 1.0, 1e4]))
def test_segment_parameter_is_its_numpy_formula_bit_for_bit(seed, scale):
    # The compiled form (geometry_kernels.segment_parameter) against the numpy one it replaced,
    # broadcast (k, 1, 2) against (1, m, 2), zero-length segments among them.
    rng = np.random.default_rng(seed)
    p = rng.normal(0, scale, (int(rng.integers(1, 9)), 1, 2))
    a = rng.normal(0, scale, (1, int(rng.integers(1, 9)), 2))
    b = a + rng.normal(0, scale, a.shape) * (rng.random(a.shape[:2])[..., None] > 0.2)
    ab = b - a
    want = ((p - a) * ab).sum(axis=-1) / np.maximum((ab * ab).sum(axis=-1), 1e-18)
    assert np.array_equal(geo.segment_parameter(p, a, b), want)


def test_segment_parameter_and_nearest_on_polyline_hand_worked():
    a, b = np.array([0.0, 0.0]), np.array([4.0, 0.0])
    p = np.array([[1.0, 3.0], [-2.0, 1.0], [6.0, -1.0], [4.0, 2.0]])
    np.testing.assert_allclose(geo.segment_parameter(p, a, b), [0.25, -0.5, 1.5, 1.0])
    poly = np.array([[0.0, 0.0], [4.0, 0.0], [4.0, 4.0]])
    q, d, k, t = geo.nearest_on_polyline(p, poly)
    # (1, 3): 3 m above the first segment at t = 0.25; (-2, 1): before the start;
    # (6, -1): past the corner, nearest the corner itself (first segment at t = 1.5);
    # (4, 2): on the second segment, halfway.
    np.testing.assert_allclose(q, [[1, 0], [0, 0], [4, 0], [4, 2]])
    np.testing.assert_allclose(d, [3, math.sqrt(5), math.sqrt(5), 0])
    assert k.tolist() == [0, 0, 0, 1]
    np.testing.assert_allclose(t, [0.25, -0.5, 1.5, 0.5])


@settings(max_examples=60)
@given(st.integers(0, 10_000), st.integers(2, 6))
def test_nearest_on_polyline_matches_shapely(seed, m):
    rng = np.random.default_rng(seed)
    poly = np.cumsum(rng.uniform(0.5, 3, size=(m, 2)), axis=0)
    pts = rng.uniform(-2, 12, size=(8, 2))
    q, d, _, _ = geo.nearest_on_polyline(pts, poly)
    line = LineString(poly)
    np.testing.assert_allclose(d, [line.distance(Point(x)) for x in pts], atol=1e-9)
    np.testing.assert_allclose(np.hypot(*(q - pts).T), d, atol=1e-9)


def test_bad_shape_is_rejected():
    with pytest.raises(ValueError):
        geo.point_segment_distance([1.0, 2.0, 3.0], (0, 0), (1, 0))


@settings(max_examples=250, deadline=None)
@given(any_pt, any_pt, any_pt)
def test_point_segment_distance_matches_sampling_and_shapely(p, a, b):
    d = float(geo.point_segment_distance(p, a, b))
    sampled = np.hypot(*(_samples(a, b) - _arr(p)).T).min()
    assert d <= sampled + 1e-9
    assert d >= sampled - _seg_len(a, b) / 200 - 1e-9
    assert d == pytest.approx(Point(p).distance(_seg_geom(a, b)), abs=1e-9)


# --- segment distance and End() ---------------------------------------------------------------

S5 = math.sqrt(5.0)
HAND_DIST_END = [
    # (a0, a1, b0, b1, distance, End, what)
    ((0, 0), (4, 0), (0, 3), (4, 3), 3.0, False, "parallel, facing over their whole length"),
    ((0, 0), (1, 0), (3, 1), (3, 5), S5, True, "closest pair (1,0)-(3,1): sqrt(2^2+1^2)"),
    ((0, 0), (2, 0), (3, 1), (5, 4), math.sqrt(2), True, "skew, (2,0)-(3,1)"),
    ((0, 0), (4, 0), (2, 1), (2, 3), 1.0, False, "perpendicular foot (2,0) inside ab"),
    ((0, 0), (4, 0), (1, 2), (-1, 5), 2.0, False, "foot of (1,2) at (1,0), not sqrt(5) at ends"),
    ((0, 0), (4, 0), (2, 0), (2, 3), 0.0, False, "T-touch: endpoint on an interior point"),
    ((0, 0), (2, 2), (0, 2), (2, 0), 0.0, False, "proper crossing at (1,1)"),
    ((0, 0), (2, 0), (0, 0), (0, 2), 0.0, True, "L-shape, shared endpoint"),
    ((2, 0), (0, 0), (0, 2), (0, 0), 0.0, True, "L-shape, both reversed"),
    ((0, 0), (3, 0), (1, 0), (5, 0), 0.0, False, "collinear overlap [1,3]"),
    ((0, 0), (1, 0), (1, 0), (2, 0), 0.0, True, "collinear end to end"),
    ((0, 0), (2, 0), (2, 0), (1, 0), 0.0, False, "collinear, shared endpoint, folding back"),
    ((0, 0), (1, 0), (0, 0), (1, 0), 0.0, False, "identical segments"),
    ((0, 0), (1, 0), (1, 0), (0, 0), 0.0, False, "identical segments, reversed"),
    ((0, 0), (1, 0), (3, 0), (5, 0), 2.0, True, "collinear with a gap"),
    ((0, 0), (1, 0), (1, 3), (2, 3), 3.0, True, "parallel, projections touch at x=1 only"),
    ((0, 0), (4, 0), (2, 3), (6, 3), 3.0, False, "parallel, projections overlap on [2,4]"),
    ((0, 0), (4, 0), (6, 3), (2, 3), 3.0, False, "same, antiparallel"),
    ((2, 1), (2, 1), (0, 0), (4, 0), 1.0, False, "point above the interior of a segment"),
    ((6, 3), (6, 3), (0, 0), (2, 0), 5.0, True, "point beyond an end: (6,3)-(2,0) = 5"),
    ((2, 0), (2, 0), (0, 0), (4, 0), 0.0, False, "point on the interior of a segment"),
    ((0, 0), (0, 0), (0, 0), (4, 0), 0.0, True, "point on an end of a segment"),
    ((0, 0), (0, 0), (3, 4), (3, 4), 5.0, True, "two points 3-4-5 apart"),
    ((1, 1), (1, 1), (1, 1), (1, 1), 0.0, True, "two coincident points"),
]


@pytest.mark.parametrize(
    "a0, a1, b0, b1, dist, end", [c[:6] for c in HAND_DIST_END], ids=[c[6] for c in HAND_DIST_END]
)
def test_segment_distance_end_hand_worked(a0, a1, b0, b1, dist, end):
    d, e = _dist_end(a0, a1, b0, b1)
    assert d == pytest.approx(dist, abs=1e-12)
    assert e is end
    assert float(geo.segment_distance(a0, a1, b0, b1)) == pytest.approx(dist, abs=1e-12)
    # Same answers with the segments swapped.
    d2, e2 = _dist_end(b0, b1, a0, a1)
    assert d2 == pytest.approx(dist, abs=1e-12)
    assert e2 is end


def test_segment_distance_end_vectorized_matches_scalar():
    cases = np.array([c[:4] for c in HAND_DIST_END], dtype=np.float64)  # (n, 4, 2)
    d, e = geo.segment_distance_end(cases[:, 0], cases[:, 1], cases[:, 2], cases[:, 3])
    assert d.shape == e.shape == (len(HAND_DIST_END),)
    assert e.dtype == np.bool_
    np.testing.assert_allclose(d, [c[4] for c in HAND_DIST_END], atol=1e-12)
    assert e.tolist() == [c[5] for c in HAND_DIST_END]
    # Broadcasting one segment against many, with a 2-D leading shape.
    b0 = cases[:, 2].reshape(2, -1, 2)
    b1 = cases[:, 3].reshape(2, -1, 2)
    d, e = geo.segment_distance_end((0, 0), (4, 0), b0, b1)
    assert d.shape == e.shape == b0.shape[:-1]
    for idx in np.ndindex(d.shape):
        ds, es = _dist_end((0, 0), (4, 0), b0[idx], b1[idx])
        assert d[idx] == ds and bool(e[idx]) is es


@settings(max_examples=300, deadline=None)
@given(any_pt, any_pt, any_pt, any_pt)
def test_segment_distance_matches_sampling_and_shapely(a0, a1, b0, b1):
    d = float(geo.segment_distance(a0, a1, b0, b1))
    sampled = _sampled_pair_distances(a0, a1, b0, b1).min()
    err = (_seg_len(a0, a1) + _seg_len(b0, b1)) / 200
    assert d <= sampled + 1e-9
    assert d >= sampled - err - 1e-9
    # Shapely and we decide "the segments touch" each in its own rounding: for segments that
    # pass within ~1e-9 m of each other one may say 0 and the other 1.4e-9 (seen).
    assert d == pytest.approx(_seg_geom(a0, a1).distance(_seg_geom(b0, b1)), abs=1e-8)
    assert d == pytest.approx(float(geo.segment_distance(b0, b1, a0, a1)), abs=1e-12)
    assert d == pytest.approx(float(geo.segment_distance_end(a0, a1, b0, b1)[0]), abs=0)


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt, int_pt, exact_scale)
def test_segment_distance_end_matches_exact_reference(a0, a1, b0, b1, k):
    a0, a1, b0, b1 = _scaled([a0, a1, b0, b1], k)
    d2, end = _exact_distance_end(a0, a1, b0, b1)
    d, e = _dist_end(a0, a1, b0, b1)
    assert d == pytest.approx(math.sqrt(d2), abs=1e-12)
    assert e is end


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt, int_pt)
def test_end_true_means_an_endpoint_pair_attains_the_distance(a0, a1, b0, b1):
    d, e = _dist_end(a0, a1, b0, b1)
    assume(e)
    ends = min(math.dist(p, q) for p in (a0, a1) for q in (b0, b1))
    assert abs(ends - d) <= 1e-9


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt, int_pt)
def test_end_false_means_an_interior_point_attains_the_distance(a0, a1, b0, b1):
    d, e = _dist_end(a0, a1, b0, b1)
    assume(not e)
    la, lb = _seg_len(a0, a1), _seg_len(b0, b1)
    # Two points are each their own endpoint: End cannot be False for them.
    assert la > 0 or lb > 0
    pair = _sampled_pair_distances(a0, a1, b0, b1)
    # Pairs with a parameter strictly inside a segment of positive length.
    mask = np.zeros_like(pair, dtype=bool)
    if la > 0:
        mask |= INTERIOR[:, None]
    if lb > 0:
        mask |= INTERIOR[None, :]
    interior_min = pair[mask].min()
    assert interior_min <= d + (la + lb) / 200 + 1e-9
    assert interior_min >= d - 1e-9


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt, int_pt, exact_scale)
def test_end_is_symmetric_under_swap_and_reversal(a0, a1, b0, b1, k):
    a0, a1, b0, b1 = _scaled([a0, a1, b0, b1], k)
    d, e = _dist_end(a0, a1, b0, b1)
    for args in [
        (a1, a0, b0, b1),
        (a0, a1, b1, b0),
        (a1, a0, b1, b0),
        (b0, b1, a0, a1),
        (b1, b0, a0, a1),
        (b0, b1, a1, a0),
        (b1, b0, a1, a0),
    ]:
        d2, e2 = _dist_end(*args)
        assert d2 == pytest.approx(d, abs=1e-12)
        assert e2 is e


@settings(max_examples=200, deadline=None)
@given(st.lists(st.tuples(int_pt, int_pt, int_pt, int_pt), min_size=1, max_size=30))
def test_segment_distance_end_batch_equals_elementwise(segs):
    arr = np.array(segs, dtype=np.float64)  # (n, 4, 2)
    d, e = geo.segment_distance_end(arr[:, 0], arr[:, 1], arr[:, 2], arr[:, 3])
    for i, s in enumerate(segs):
        ds, es = _dist_end(*s)
        assert d[i] == ds
        assert bool(e[i]) is es


# --- intersection predicates ------------------------------------------------------------------

HAND_INTERSECT = [
    # (a0, a1, b0, b1, intersect, cross, what)
    ((0, 0), (2, 2), (0, 2), (2, 0), True, True, "X crossing"),
    ((0, 0), (4, 0), (2, 0), (2, 3), True, False, "T-touch"),
    ((0, 0), (2, 0), (0, 0), (0, 2), True, False, "shared endpoint"),
    ((0, 0), (3, 0), (1, 0), (5, 0), True, False, "collinear overlap"),
    ((0, 0), (1, 0), (1, 0), (2, 0), True, False, "collinear end to end"),
    ((0, 0), (1, 0), (2, 0), (3, 0), False, False, "collinear, disjoint"),
    ((0, 0), (4, 0), (0, 1), (4, 1), False, False, "parallel"),
    ((0, 0), (2, 0), (3, -1), (3, 1), False, False, "the lines cross beyond ab"),
    ((2, 0), (2, 0), (0, 0), (4, 0), True, False, "point on a segment"),
    ((2, 1), (2, 1), (0, 0), (4, 0), False, False, "point off a segment"),
    ((5, 0), (5, 0), (0, 0), (4, 0), False, False, "point on the line, beyond the segment"),
    ((1, 1), (1, 1), (1, 1), (1, 1), True, False, "coincident points"),
]


@pytest.mark.parametrize(
    "a0, a1, b0, b1, inter, cross",
    [c[:6] for c in HAND_INTERSECT],
    ids=[c[6] for c in HAND_INTERSECT],
)
def test_intersect_and_cross_hand_worked(a0, a1, b0, b1, inter, cross):
    for args in [(a0, a1, b0, b1), (b0, b1, a0, a1), (a1, a0, b1, b0)]:
        assert bool(geo.segments_intersect(*args)) is inter
        assert bool(geo.segments_cross(*args)) is cross


def test_distant_segments_on_one_line_do_not_meet():
    # Two segments of a generated straight, 37 m apart on one line (rld.generator, seed 103):
    # their orientations are rounding noise of either sign, and before the bounding-box test
    # segments_intersect and segments_cross reported a crossing (ring_is_simple then rejected a
    # simple ring).
    a0, a1 = (-25.531440777696847, 54.26752450441628), (-25.751177244794352, 53.29185851998294)
    b0, b1 = (-33.8814265274021, 17.192217095949008), (-34.1011629944996, 16.216551111515667)
    for args in [(a0, a1, b0, b1), (b0, b1, a0, a1), (a1, a0, b1, b0)]:
        assert not bool(geo.segments_intersect(*args))
        assert not bool(geo.segments_cross(*args))
        assert float(geo.segment_distance(*args)) > 30.0
    # The same along a whole noise-free straight: a long thin ring is simple.
    xs = np.linspace(0.0, 60.0, 31)
    t = np.column_stack([-25.5 - 0.2197 * xs, 54.27 - 0.9757 * xs])
    n = np.array([0.9757, -0.2197])
    ring = np.vstack([t, (t + 3.0 * n)[::-1]])
    assert geo.ring_is_simple(ring)
    assert geo.ring_is_simple(ring) is Polygon(ring).is_valid


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt, int_pt, exact_scale)
def test_segments_intersect_matches_shapely(a0, a1, b0, b1, k):
    a0, a1, b0, b1 = _scaled([a0, a1, b0, b1], k)
    expected = _seg_geom(a0, a1).intersects(_seg_geom(b0, b1))
    assert bool(geo.segments_intersect(a0, a1, b0, b1)) is expected
    # Intersecting means distance 0, and conversely.
    assert (float(geo.segment_distance(a0, a1, b0, b1)) == 0.0) is expected


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt, int_pt, exact_scale)
def test_segments_cross_matches_exact_reference(a0, a1, b0, b1, k):
    a0, a1, b0, b1 = _scaled([a0, a1, b0, b1], k)
    got = bool(geo.segments_cross(a0, a1, b0, b1))
    assert got is _exact_cross(a0, a1, b0, b1)
    if a0 != a1 and b0 != b1:
        assert got is LineString([a0, a1]).crosses(LineString([b0, b1]))
    if got:  # a proper crossing is an intersection with an interior contact
        assert bool(geo.segments_intersect(a0, a1, b0, b1))
        assert _dist_end(a0, a1, b0, b1) == (0.0, False)


# --- turn angles ------------------------------------------------------------------------------

HAND_TURNS = [
    ((0, 0), (1, 0), (2, 0), 0.0, "straight on"),
    ((0, 0), (1, 0), (1, 1), PI / 2, "left 90"),
    ((0, 0), (1, 0), (1, -1), -PI / 2, "right 90"),
    ((0, 0), (1, 0), (2, 1), PI / 4, "left 45"),
    ((0, 0), (1, 0), (0, 1), 3 * PI / 4, "left 135"),
    ((0, 0), (1, 0), (0, -1), -3 * PI / 4, "right 135"),
    ((0, 0), (0, 2), (-3, 2 + 3 * math.sqrt(3)), PI / 6, "left 30, unequal lengths"),
    ((1, 1), (0, 0), (1, 1), PI, "diagonal reversal"),
    ((0, 0), (1, 1), (0, 0), PI, "diagonal reversal, other way"),
    ((0, 0), (0, 0), (1, 0), PI, "zero-length first segment"),
    ((0, 0), (1, 0), (1, 0), PI, "zero-length second segment"),
    ((2, 2), (2, 2), (2, 2), PI, "all three equal"),
]


@pytest.mark.parametrize(
    "p0, p1, p2, turn", [c[:4] for c in HAND_TURNS], ids=[c[4] for c in HAND_TURNS]
)
def test_turn_angles_hand_worked(p0, p1, p2, turn):
    assert float(geo.turn_angles(p0, p1, p2)) == pytest.approx(turn, abs=1e-12)


AXIS_REVERSALS = [
    pytest.param((-1, 0), (0, 0), (-1, 0), id="east-west-east"),
    pytest.param((0, 1), (0, 0), (0, 1), id="south-north-south"),
    pytest.param((1, 0), (0, 0), (1, 0), id="west-east-west"),
    pytest.param((0, -1), (0, 0), (0, -1), id="north-south-north"),
]


@pytest.mark.parametrize("p0, p1, p2", AXIS_REVERSALS)
def test_turn_angle_of_an_axis_aligned_reversal_is_plus_pi(p0, p1, p2):
    # An exact reversal is +pi whichever way round (a cross product of -0.0 once gave -pi).
    assert float(geo.turn_angles(p0, p1, p2)) == PI
    assert float(geo.turn_angles(p2, p1, p0)) == PI


def test_polyline_turn_angles_hand_worked():
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    np.testing.assert_allclose(geo.polyline_turn_angles(sq), [PI / 2, PI / 2], atol=1e-12)
    np.testing.assert_allclose(geo.polyline_turn_angles(sq, closed=True), [PI / 2] * 4, atol=1e-12)
    np.testing.assert_allclose(
        geo.polyline_turn_angles(sq[::-1], closed=True), [-PI / 2] * 4, atol=1e-12
    )
    assert geo.polyline_turn_angles(sq[:2]).shape == (0,)
    assert geo.polyline_turn_angles(np.zeros((0, 2))).shape == (0,)
    zig = np.array([[0, 0], [1, 0], [2, 1], [3, 1], [3, 0]], float)
    np.testing.assert_allclose(
        geo.polyline_turn_angles(zig), [PI / 4, -PI / 4, -PI / 2], atol=1e-12
    )


def _reference_turn(p0, p1, p2):
    u = (p1[0] - p0[0], p1[1] - p0[1])
    v = (p2[0] - p1[0], p2[1] - p1[1])
    if u == (0, 0) or v == (0, 0):
        return PI
    return _wrap(math.atan2(v[1], v[0]) - math.atan2(u[1], u[0]))


@settings(max_examples=300, deadline=None)
@given(int_pt, int_pt, int_pt)
def test_turn_angles_match_heading_difference(p0, p1, p2):
    got = float(geo.turn_angles(p0, p1, p2))
    assert _angdiff(got, _reference_turn(p0, p1, p2)) <= 1e-12
    u = (p1[0] - p0[0], p1[1] - p0[1])
    v = (p2[0] - p1[0], p2[1] - p1[1])
    reversal = u[0] * v[1] - u[1] * v[0] == 0 and u[0] * v[0] + u[1] * v[1] < 0
    if u == (0, 0) or v == (0, 0):
        assert got == PI
    elif reversal:
        assert got == PI  # an exact reversal is +pi (the range is (-pi, pi])
    else:
        assert -PI < got <= PI
        assert got == pytest.approx(_reference_turn(p0, p1, p2), abs=1e-12)
        # Sign: positive is a left turn (counter-clockwise), exactly by orientation.
        c = u[0] * v[1] - u[1] * v[0]
        assert (got > 0) == (c > 0) and (got < 0) == (c < 0)


@settings(max_examples=250, deadline=None)
@given(
    int_pt,
    int_pt,
    int_pt,
    st.floats(-PI, PI, allow_nan=False),
    float_pt,
)
def test_turn_angles_invariant_under_rotation_and_translation(p0, p1, p2, theta, shift):
    assume(p0 != p1 and p1 != p2)
    c, s = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -s], [s, c]])
    pts = np.array([p0, p1, p2], float) @ rot.T + np.array(shift)
    got = float(geo.turn_angles(pts[0], pts[1], pts[2]))
    assert _angdiff(got, float(geo.turn_angles(p0, p1, p2))) <= 1e-9


@settings(max_examples=250, deadline=None)
@given(st.lists(int_pt, min_size=3, max_size=9), st.booleans())
def test_reversing_a_polyline_negates_its_turns(pts, closed):
    xy = np.array(pts, float)
    fwd = geo.polyline_turn_angles(xy, closed=closed)
    rev = geo.polyline_turn_angles(xy[::-1], closed=closed)
    k = len(pts)
    assert fwd.shape == (k if closed else k - 2,)
    for x, y in zip(rev, -fwd[::-1], strict=True):
        assert _angdiff(x, y) <= 1e-12
    # The polyline helper is turn_angles on consecutive (wrapped) triples.
    idx = range(k) if closed else range(1, k - 1)
    expect = [_reference_turn(pts[i - 1], pts[i], pts[(i + 1) % k]) for i in idx]
    for x, y in zip(fwd, expect, strict=True):
        assert _angdiff(x, y) <= 1e-12


@settings(max_examples=200, deadline=None)
@given(st.lists(st.floats(0, 2 * PI, exclude_max=True), min_size=3, max_size=12, unique=True))
def test_turns_of_a_convex_polygon_sum_to_two_pi(angles):
    angles = sorted(angles)
    assume(min(np.diff(angles + [angles[0] + 2 * PI])) > 1e-3)
    assume(max(np.diff(angles + [angles[0] + 2 * PI])) < PI - 1e-3)  # strictly convex
    ring = 5.0 * np.column_stack([np.cos(angles), np.sin(angles)])
    turns = geo.polyline_turn_angles(ring, closed=True)
    assert np.all(turns > 0)
    assert turns.sum() == pytest.approx(2 * PI, abs=1e-9)
    assert geo.polyline_turn_angles(ring[::-1], closed=True).sum() == pytest.approx(
        -2 * PI, abs=1e-9
    )


# --- lengths and resampling -------------------------------------------------------------------


def test_cumulative_length_hand_worked():
    xy = np.array([[0, 0], [3, 4], [3, 10]], float)
    np.testing.assert_allclose(geo.cumulative_length(xy), [0, 5, 11], atol=1e-12)
    assert geo.polyline_length(xy) == pytest.approx(11.0)
    closing = math.sqrt(3**2 + 10**2)
    np.testing.assert_allclose(
        geo.cumulative_length(xy, closed=True), [0, 5, 11, 11 + closing], atol=1e-12
    )
    assert geo.polyline_length(xy, closed=True) == pytest.approx(11 + closing)
    # A unit square ring: perimeter 4.
    sq = np.array([[0, 0], [1, 0], [1, 1], [0, 1]], float)
    assert geo.polyline_length(sq, closed=True) == pytest.approx(4.0)
    assert geo.polyline_length(sq) == pytest.approx(3.0)
    # Degenerate inputs.
    assert geo.cumulative_length(np.zeros((0, 2))).shape == (0,)
    assert geo.polyline_length(np.zeros((0, 2))) == 0.0
    assert geo.polyline_length(np.zeros((0, 2)), closed=True) == 0.0
    np.testing.assert_array_equal(geo.cumulative_length(np.array([[2.0, 3.0]])), [0.0])
    assert geo.polyline_length(np.array([[2.0, 3.0]]), closed=True) == 0.0


polyline_st = st.lists(float_pt, min_size=2, max_size=8)


@settings(max_examples=250, deadline=None)
@given(polyline_st, st.booleans())
def test_cumulative_length_matches_shapely(pts, closed):
    xy = np.array(pts, float)
    c = geo.cumulative_length(xy, closed=closed)
    assert c.shape == (len(pts) + (1 if closed else 0),)
    assert c[0] == 0.0
    assert np.all(np.diff(c) >= 0)
    ring = pts + [pts[0]] if closed else pts
    for i in range(1, len(ring)):
        assert c[i] - c[i - 1] == pytest.approx(math.dist(ring[i - 1], ring[i]), abs=1e-12)
    seglens = [math.dist(p, q) for p, q in zip(ring[:-1], ring[1:], strict=True)]
    if all(x == 0 or x > 1e-9 for x in seglens) and any(seglens):  # GEOS-safe lengths
        assert geo.polyline_length(xy, closed) == pytest.approx(LineString(ring).length, abs=1e-9)


def test_resample_polyline_hand_worked():
    line = np.array([[0, 0], [10, 0]], float)
    r = geo.resample_polyline(line, 1.0)
    np.testing.assert_allclose(r, np.column_stack([np.arange(11.0), np.zeros(11)]), atol=1e-12)
    # 10 m at step 3: floor(10/3) = 3 intervals of 10/3 m, 4 points.
    r = geo.resample_polyline(line, 3.0)
    np.testing.assert_allclose(r[:, 0], [0, 10 / 3, 20 / 3, 10], atol=1e-12)
    # Step longer than the line: just the two ends.
    np.testing.assert_allclose(geo.resample_polyline(line, 25.0), line, atol=1e-12)
    # An L of 4 + 2 m at step 2: the corner (4,0) is a sample.
    ell = np.array([[0, 0], [4, 0], [4, 2]], float)
    np.testing.assert_allclose(
        geo.resample_polyline(ell, 2.0), [[0, 0], [2, 0], [4, 0], [4, 2]], atol=1e-12
    )
    # A closed 4 x 4 square at step 1: 16 points, the first not repeated at the end.
    sq = np.array([[0, 0], [4, 0], [4, 4], [0, 4]], float)
    r = geo.resample_polyline(sq, 1.0, closed=True)
    assert r.shape == (16, 2)
    np.testing.assert_allclose(r[0], [0, 0])
    np.testing.assert_allclose(r[4], [4, 0], atol=1e-12)
    np.testing.assert_allclose(r[15], [0, 1], atol=1e-12)
    np.testing.assert_allclose(np.hypot(*np.diff(r, axis=0).T), 1.0, atol=1e-12)
    # Degenerate inputs.
    one = np.array([[1.0, 2.0]])
    np.testing.assert_array_equal(geo.resample_polyline(one, 1.0), one)
    same = np.array([[1.0, 2.0], [1.0, 2.0], [1.0, 2.0]])
    np.testing.assert_array_equal(geo.resample_polyline(same, 1.0), one)


def _reference_point_at(pts, s):
    """The point at arc length s along the polyline, by walking its segments."""
    acc = 0.0
    for p, q in zip(pts[:-1], pts[1:], strict=True):
        seg = math.dist(p, q)
        if seg > 0 and s <= acc + seg:
            t = (s - acc) / seg
            return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))
        acc += seg
    return pts[-1]


@settings(max_examples=250, deadline=None)
@given(polyline_st, st.floats(0.1, 5.0), st.booleans())
def test_resample_polyline_spacing_and_positions(pts, step, closed):
    xy = np.array(pts, float)
    ring = pts + [pts[0]] if closed else pts
    total = sum(math.dist(p, q) for p, q in zip(ring[:-1], ring[1:], strict=True))
    assume(total > 1e-6)
    r = geo.resample_polyline(xy, step, closed=closed)
    n = max(int(math.floor(total / step)), 1)
    assert r.shape == (n if closed else n + 1, 2)
    spacing = total / n
    assert spacing >= step * (1 - 1e-12) or n == 1
    assert spacing < 2 * step or n == 1
    # Every sample is at arc length k * spacing along the original.
    for k, q in enumerate(r):
        ref = _reference_point_at(ring, k * spacing) if (closed or k < n) else ring[-1]
        assert math.dist(q, ref) <= 1e-9 * (1 + total)
    np.testing.assert_allclose(r[0], xy[0], atol=1e-12)
    if not closed:
        np.testing.assert_array_equal(r[-1], xy[-1])
    # Chords are never longer than the arc between them; the length can only shrink.
    chords = np.hypot(*np.diff(r, axis=0).T)
    assert np.all(chords <= spacing + 1e-9)
    assert geo.polyline_length(r, closed) <= total + 1e-9


@settings(max_examples=50, deadline=None)
@given(st.floats(2.0, 30.0), st.floats(0.05, 1.0))
def test_resample_polyline_keeps_the_length_of_a_smooth_curve(radius, step):
    t = np.linspace(0, 1.5 * PI, 600)
    arc = radius * np.column_stack([np.cos(t), np.sin(t)])
    length = geo.polyline_length(arc)
    r = geo.resample_polyline(arc, step)
    assert abs(geo.polyline_length(r) - length) <= step
    # Samples are on the arc (chord sagitta of the 600-gon is tiny) and evenly spaced.
    np.testing.assert_allclose(np.hypot(*r.T), radius, atol=radius * 1e-4)
    chords = np.hypot(*np.diff(r, axis=0).T)
    assert chords.max() - chords.min() <= 1e-3 * step + 1e-9


# --- point-polyline distance ------------------------------------------------------------------


def test_point_polyline_distance_hand_worked():
    ell = np.array([[0, 0], [4, 0], [4, 3]], float)
    got = geo.point_polyline_distance([[2, 1], [6, 1], [7, 7], [-3, -4], [4, 0]], ell)
    np.testing.assert_allclose(got, [1, 2, 5, 5, 0], atol=1e-12)
    # A single point as the polyline, a single point as the query.
    np.testing.assert_allclose(geo.point_polyline_distance((3, 4), np.array([[0.0, 0.0]])), [5.0])
    assert geo.point_polyline_distance((3, 4), ell).shape == (1,)
    # No polyline at all: infinitely far.
    assert np.all(np.isinf(geo.point_polyline_distance([[0, 0], [1, 1]], np.zeros((0, 2)))))


def test_polyline_segments_distance_hand_worked():
    ell = np.array([[0, 0], [4, 0], [4, 3]], float)
    q = np.array([[1, 2], [3, 2], [6, 5], [8, 1]], float)
    # (1,2)-(3,2): 1 from x = 4, 2 from y = 0 -> 1. (3,2)-(6,5) passes through (4, 3) -> 0.
    # (6,5)-(8,1): the corner (4, 3) is nearest, its foot at t = 0.2, (6.4, 4.2) -> sqrt(7.2).
    got = geo.polyline_segments_distance(q, ell)
    np.testing.assert_allclose(got, [1.0, 0.0, math.sqrt(7.2)], atol=1e-12)
    # A single point as the target polyline; no target at all.
    np.testing.assert_allclose(geo.polyline_segments_distance(q[:2], np.array([[2.0, 5.0]])),
                               [3.0])
    assert np.all(np.isinf(geo.polyline_segments_distance(q, np.zeros((0, 2)))))
    assert geo.polyline_segments_distance(q[:1], ell).shape == (0,)


@settings(max_examples=200, deadline=None)
@given(st.lists(any_pt, min_size=2, max_size=6), st.lists(any_pt, min_size=1, max_size=6))
def test_polyline_segments_distance_matches_pairwise_and_shapely(q, poly):
    q, poly = np.array(q, float), np.array(poly, float)
    got = geo.polyline_segments_distance(q, poly)
    assert got.shape == (len(q) - 1,)
    for i in range(len(q) - 1):
        if len(poly) == 1:
            want = float(geo.point_segment_distance(poly[0], q[i], q[i + 1]))
        else:
            want = float(geo.segment_distance(q[i], q[i + 1], poly[:-1], poly[1:]).min())
            shp = min(_seg_geom(a, b).distance(_seg_geom(q[i], q[i + 1]))
                      for a, b in zip(poly[:-1], poly[1:], strict=True))
            assert got[i] == pytest.approx(shp, abs=1e-8)
        assert got[i] == pytest.approx(want, abs=1e-12)


@settings(max_examples=200, deadline=None)
@given(st.lists(any_pt, min_size=1, max_size=12), st.lists(any_pt, min_size=1, max_size=12))
def test_point_polyline_distance_matches_pairwise(p, poly):
    # The kernel tries the previous point's nearest segment first and skips segments whose
    # bounding box is already farther: the minimum over every segment must not change.
    p, poly = np.array(p, float), np.array(poly, float)
    got = geo.point_polyline_distance(p, poly)
    for i in range(len(p)):
        if len(poly) == 1:
            want = float(np.hypot(*(p[i] - poly[0])))
        else:
            want = float(geo.point_segment_distance(p[i], poly[:-1], poly[1:]).min())
        assert got[i] == pytest.approx(want, abs=1e-12)


@settings(max_examples=300, deadline=None)
@given(st.lists(any_pt, min_size=0, max_size=8), st.lists(any_pt, min_size=0, max_size=8))
def test_polylines_touch_matches_every_segment_pair(p, q):
    # Integer points make touching, overlapping and collinear pairs common.
    p, q = np.array(p, float).reshape(-1, 2), np.array(q, float).reshape(-1, 2)
    want = any(bool(geo.segments_intersect(p[i], p[i + 1], q[j], q[j + 1]))
               for i in range(len(p) - 1) for j in range(len(q) - 1))
    assert geo.polylines_touch(p, q) is want
    assert geo.polylines_touch(q, p) is want


def test_polylines_touch_hand_worked():
    a = np.array([[0, 0], [4, 0], [4, 4]], float)
    assert geo.polylines_touch(a, np.array([[2, -1], [2, 1]], float))  # crossing
    assert geo.polylines_touch(a, np.array([[4, 4], [6, 6]], float))  # sharing an end point
    assert geo.polylines_touch(a, np.array([[1, 0], [3, 0]], float))  # overlapping
    assert not geo.polylines_touch(a, np.array([[1, 1], [3, 1], [3, 3]], float))
    assert not geo.polylines_touch(a, np.array([[2, 0]], float))  # one point: no segment
    assert not geo.polylines_touch(a, np.zeros((0, 2)))


@settings(max_examples=250, deadline=None)
@given(st.lists(any_pt, min_size=1, max_size=7), st.lists(any_pt, min_size=1, max_size=5))
def test_point_polyline_distance_matches_shapely(poly, pts):
    got = geo.point_polyline_distance(np.array(pts, float), np.array(poly, float))
    if len(poly) == 1:
        parts = [Point(poly[0])]
    else:  # segment by segment, so that sub-micron segments are shapely Points
        parts = [_seg_geom(p, q) for p, q in zip(poly[:-1], poly[1:], strict=True)]
    assert got.shape == (len(pts),)
    for q, d in zip(pts, got, strict=True):
        assert d == pytest.approx(min(g.distance(Point(q)) for g in parts), abs=1e-9)
    if len(poly) >= 2 and all(
        math.dist(p, q) > 1e-9 for p, q in zip(poly[:-1], poly[1:], strict=True)
    ):
        line = LineString(poly)
        for q, d in zip(pts, got, strict=True):
            assert d == pytest.approx(line.distance(Point(q)), abs=1e-9)


# --- simple rings -----------------------------------------------------------------------------

HAND_RINGS = [
    ([(0, 0), (1, 0), (0, 1)], True, "triangle"),
    ([(0, 0), (4, 0), (4, 4), (0, 4)], True, "square"),
    ([(0, 0), (4, 0), (4, 4), (2, 1), (0, 4)], True, "concave"),
    ([(0, 0), (2, 0), (4, 0), (4, 4), (0, 4)], True, "collinear vertex on an edge"),
    ([(0, 0), (4, 4), (4, 0), (0, 4)], False, "bow-tie"),
    ([(0, 0), (2, 0), (2, 2), (4, 2), (4, 4), (2, 4), (2, 2), (0, 2)], False, "figure 8 at (2,2)"),
    ([(0, 0), (4, 0), (4, 4), (2, 0), (0, 4)], False, "vertex touching an edge"),
    ([(0, 0), (4, 0), (2, 0), (2, 3)], False, "spike folding back along an edge"),
    ([(0, 0), (1, 0), (2, 0)], False, "collinear triangle"),
    ([(0, 0), (4, 0), (4, 0), (4, 4)], False, "repeated consecutive vertex"),
    ([(0, 0), (4, 0), (4, 4), (0, 4), (0, 0)], False, "explicitly closed (zero-length edge)"),
]


@pytest.mark.parametrize(
    "ring, simple", [c[:2] for c in HAND_RINGS], ids=[c[2] for c in HAND_RINGS]
)
def test_ring_is_simple_hand_worked(ring, simple):
    xy = np.array(ring, float)
    assert geo.ring_is_simple(xy) is simple
    assert geo.ring_is_simple(xy[::-1]) is simple
    assert geo.ring_is_simple(np.roll(xy, 2, axis=0)) is simple


@settings(max_examples=300, deadline=None)
@given(st.lists(int_pt, min_size=3, max_size=8), exact_scale)
def test_ring_is_simple_matches_shapely(pts, k):
    n = len(pts)
    assume(all(pts[i] != pts[(i + 1) % n] for i in range(n)))
    assume(len(set(pts)) >= 3)
    pts = _scaled(pts, k)
    expected = LinearRing(pts).is_simple
    assert geo.ring_is_simple(np.array(pts, float)) is expected
    if expected:
        # A simple ring turns exactly once around: +2 pi counter-clockwise, -2 pi clockwise.
        total = geo.polyline_turn_angles(np.array(pts, float), closed=True).sum()
        assert total == pytest.approx(2 * PI if LinearRing(pts).is_ccw else -2 * PI, abs=1e-9)


# --- centreline -------------------------------------------------------------------------------


def _straight(y, x0=0.0, x1=10.0, n=11):
    return np.column_stack([np.linspace(x0, x1, n), np.full(n, float(y))])


def test_centerline_of_parallel_straight_boundaries():
    left, right = _straight(2.0), _straight(-2.0)
    c = geo.centerline(left, right)
    # Equal rungs alternate the two sides: midpoints every 0.5 m along y = 0.
    np.testing.assert_allclose(
        c, np.column_stack([np.arange(0, 10.5, 0.5), np.zeros(21)]), atol=1e-12
    )
    # With a resolution both sides and the result are resampled every metre.
    c = geo.centerline(left, right, resolution_m=1.0)
    np.testing.assert_allclose(c, np.column_stack([np.arange(11.0), np.zeros(11)]), atol=1e-12)
    # Different vertex counts on the two sides: still on y = 0, from x = 0 to x = 10.
    c = geo.centerline(_straight(2.0, n=3), _straight(-2.0, n=17))
    np.testing.assert_allclose(c[:, 1], 0.0, atol=1e-12)
    assert c[0, 0] == 0.0 and c[-1, 0] == 10.0
    assert np.all(np.diff(c[:, 0]) >= 0)
    assert len(c) == 3 + 17 - 1  # every step advances one side
    # An empty boundary gives no centreline.
    assert geo.centerline(np.zeros((0, 2)), right).shape == (0, 2)


def test_centerline_of_concentric_squares():
    outer = np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], float)
    inner = 0.6 * outer
    c = geo.centerline(outer, inner, closed=True)
    # Worked by hand: ties advance the left side, then the short rung advances the right one.
    expected = [[-4, -4], [1, -4], [4, -4], [4, 1], [4, 4], [-1, 4], [-4, 4], [-4, -1]]
    np.testing.assert_allclose(c, expected, atol=1e-12)
    assert np.all(np.max(np.abs(c), axis=1) == 4.0)  # half-way between half-sides 5 and 3


def test_centerline_of_concentric_circles():
    t1 = np.linspace(0, 2 * PI, 100, endpoint=False)
    t2 = np.linspace(0, 2 * PI, 60, endpoint=False) + 0.3
    outer = 10 * np.column_stack([np.cos(t1), np.sin(t1)])
    inner = 6 * np.column_stack([np.cos(t2), np.sin(t2)])
    for left, right in [(outer, inner), (inner, outer)]:
        c = geo.centerline(left, right, closed=True, resolution_m=0.5)
        r = np.hypot(*c.T)
        assert np.all(r <= 8.0 + 1e-9)  # mid-radius of 10 and 6 (the disc is convex)
        assert np.all(r >= 7.5)
        # It goes once around: every heading gap small, and about 2 pi 8 / 0.5 points.
        ang = np.sort(np.arctan2(c[:, 1], c[:, 0]))
        assert np.max(np.diff(np.r_[ang, ang[0] + 2 * PI])) < 0.1
        assert abs(len(c) - 2 * PI * 8 / 0.5) <= 3
        # Closed: the first point is not repeated at the end.
        assert not np.allclose(c[0], c[-1])


# --- lane polygon -----------------------------------------------------------------------------


def test_lane_ring_is_left_then_right_reversed():
    left = np.array([[0, 2], [10, 2]], float)
    right = np.array([[0, -2], [10, -2]], float)
    np.testing.assert_array_equal(geo.lane_ring(left, right), [[0, 2], [10, 2], [10, -2], [0, -2]])


def test_lane_polygon_of_a_straight_lane():
    for left, right in [
        (_straight(2.0), _straight(-2.0)),
        (_straight(2.0, n=2), _straight(-2.0, n=7)),
        (_straight(-2.0), _straight(2.0)),  # sides swapped: same region
    ]:
        poly = geo.lane_polygon(left, right)
        assert poly.is_valid
        assert poly.area == pytest.approx(40.0, abs=1e-9)
        assert poly.bounds == pytest.approx((0.0, -2.0, 10.0, 2.0))


def test_lane_polygon_of_a_closed_lane_is_the_annulus():
    outer = np.array([[-5, -5], [5, -5], [5, 5], [-5, 5]], float)
    inner = 0.6 * outer
    for left, right in [(outer, inner), (inner, outer), (outer[::-1], inner)]:
        poly = geo.lane_polygon(left, right, closed=True)
        assert poly.is_valid
        assert poly.area == pytest.approx(100.0 - 36.0, abs=1e-9)
        assert not poly.contains(Point(0, 0)) and poly.contains(Point(4, 0))
    t = np.linspace(0, 2 * PI, 200, endpoint=False)
    circ = np.column_stack([np.cos(t), np.sin(t)])
    poly = geo.lane_polygon(10 * circ, 6 * circ, closed=True)
    expected = Polygon(10 * circ).area - Polygon(6 * circ).area
    assert poly.area == pytest.approx(expected, abs=1e-9)
    assert poly.area == pytest.approx(PI * (100 - 36), rel=1e-3)
    # Fewer than three points on a loop: no lane.
    assert geo.lane_polygon(outer[:2], inner, closed=True).is_empty


def test_lane_polygon_repairs_a_crossing_lane():
    # The boundaries cross at (5, 0): a bow-tie of two triangles of area 4 * 5 / 2 = 10.
    left = np.array([[0, 2], [10, -2]], float)
    right = np.array([[0, -2], [10, 2]], float)
    assert not Polygon(geo.lane_ring(left, right)).is_valid
    poly = geo.lane_polygon(left, right)
    assert poly.is_valid
    assert poly.geom_type == "MultiPolygon"
    assert poly.area == pytest.approx(20.0, abs=1e-9)
    # Without repair the raw (invalid) polygon comes back.
    raw = geo.lane_polygon(left, right, repair=False)
    assert not raw.is_valid


def test_lane_polygon_repairs_a_self_crossing_loop():
    # A bow-tie outer loop, crossing itself at (2, 2): two triangles of area 4 * 2 / 2 = 4.
    bowtie = np.array([[0, 0], [4, 4], [4, 0], [0, 4]], float)
    tiny = np.array([[100, 100], [100.5, 100], [100, 100.5]], float)
    poly = geo.lane_polygon(bowtie, tiny, closed=True)
    assert poly.is_valid
    assert poly.area == pytest.approx(8.0, abs=1e-9)
    assert poly.contains(Point(0.5, 2)) and poly.contains(Point(3.5, 2))
    assert not poly.contains(Point(2, 0.5))


def test_lane_polygon_degenerate():
    assert geo.lane_polygon(np.array([[0.0, 0.0]]), np.array([[1.0, 1.0]])).is_empty
    # A lane with no width is an empty polygon after repair.
    line = _straight(0.0)
    assert geo.lane_polygon(line, line).area == pytest.approx(0.0)


# --- pairs within a radius --------------------------------------------------------------------


def test_pairs_within_hand_worked_and_bad_input():
    pts = np.array([[0, 0], [3, 4], [10, 0], [6, 8], [3, 4.0000001]], float)
    # 0-1 and 1-3 and 3-4 are exactly 5 apart (inclusive); 1-4 are 1e-7 apart; 0-4 just past 5.
    assert geo.pairs_within(pts, 5.0).tolist() == [[0, 1], [1, 3], [1, 4], [3, 4]]
    assert geo.pairs_within(pts, np.float32(5.0)).shape == (4, 2)
    assert geo.pairs_within(pts[:1], 5.0).shape == (0, 2)
    assert geo.pairs_within(np.zeros((0, 2)), 5.0).shape == (0, 2)
    for bad in (0.0, -1.0, math.nan, math.inf, "5"):
        with pytest.raises(ValueError, match="radius"):
            geo.pairs_within(pts, bad)
    with pytest.raises(ValueError, match="finite"):
        geo.pairs_within(np.array([[0.0, 0.0], [math.nan, 1.0]]), 5.0)


def test_pairs_within_finds_pairs_across_cell_edges():
    # Points on and either side of the grid's cell edges (multiples of r), in pairs exactly r
    # apart or a rounding error less: none may be lost to a cell boundary.
    r = 0.1  # not exact in binary: x / r rounds
    xs = np.array([k * r for k in range(-5, 6)] + [np.nextafter(k * r, -1.0) for k in range(-5, 6)])
    pts = np.column_stack([xs, np.zeros_like(xs)])
    got = {tuple(p) for p in geo.pairs_within(pts, r).tolist()}
    want = {(i, j) for i in range(len(xs)) for j in range(i + 1, len(xs))
            if math.hypot(*(pts[j] - pts[i])) <= r}
    assert got == want


def test_signed_area_hand_worked():
    square = np.array([[0.0, 0.0], [2.0, 0.0], [2.0, 3.0], [0.0, 3.0]])
    assert geo.signed_area(square) == pytest.approx(6.0)
    assert geo.signed_area(square[::-1]) == pytest.approx(-6.0)
    assert geo.signed_area(square[:2]) == 0.0
    # A lane along +x, left boundary at y = 2 and right at y = -2: clockwise.
    left = np.array([[0.0, 2.0], [5.0, 2.0]])
    right = np.array([[0.0, -2.0], [5.0, -2.0]])
    assert geo.signed_area(geo.lane_ring(left, right)) == pytest.approx(-20.0)


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.floats(-50, 50), st.floats(-50, 50)), min_size=3, max_size=12))
def test_signed_area_matches_shapely_on_simple_rings(pts):
    ring = np.array(pts, dtype=np.float64)
    r = LinearRing(ring)
    assume(r.is_valid and r.is_simple)
    a = geo.signed_area(ring)
    assert abs(a) == pytest.approx(Polygon(ring).area, rel=1e-9, abs=1e-9)
    assume(abs(a) > 1e-6)
    assert (a > 0) == r.is_ccw


def test_leading_behind_hand_worked():
    # The car at (1, 0) heading +x: x < 1 is behind it.
    xy = np.array([[-2.0, 2.0], [0.5, 2.0], [1.0, 2.0], [-3.0, 2.0], [6.0, 2.0]])
    h = np.array([1.0, 0.0])
    assert geo.leading_behind(xy, (1.0, 0.0), h) == 2  # abreast (x = 1) is not behind
    assert geo.leading_behind(xy[2:], (1.0, 0.0), h) == 0  # a later cone behind is not leading
    assert geo.leading_behind(xy[:2], (1.0, 0.0), h) == 0  # two cones are kept
    assert geo.leading_behind(xy[:2], (1.0, 0.0), h, keep=1) == 1
    assert geo.leading_behind(xy[:2], (1.0, 0.0), h, keep=0) == 2
    # Heading -y: behind is y > 0 from the car at the origin.
    assert geo.leading_behind(xy, (0.0, 0.0), np.array([0.0, -1.0])) == 3
    assert geo.leading_behind(np.zeros((0, 2)), (0.0, 0.0), h) == 0


@settings(max_examples=100, deadline=None)
@given(st.lists(st.tuples(st.floats(-20, 20), st.floats(-20, 20)), min_size=0, max_size=8),
       st.floats(-math.pi, math.pi), st.integers(0, 3))
def test_leading_behind_matches_brute_force(pts, yaw, keep):
    xy = np.array(pts, dtype=np.float64).reshape(-1, 2)
    h = np.array([math.cos(yaw), math.sin(yaw)])
    k = geo.leading_behind(xy, (0.0, 0.0), h, keep=keep)
    want = 0
    while want < len(pts) - keep and float(xy[want] @ h) < 0.0:
        want += 1
    assert k == want

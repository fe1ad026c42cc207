"""A seeded generator of closed, rules-compliant Formula Student circuits.

The centreline is a periodic cubic spline through control points on a jittered stadium (two
long straights joined by turns), with hairpins (a control point pulled deep into the infield)
and chicanes (alternating lateral offsets on a straight) inserted at random. A candidate is
kept only when it satisfies every rule below, on the noise-free cone positions:

- the centreline is closed and simple, and distinct parts of the track keep at least
  ``GAP_M`` metres of infield between their boundaries;
- the centreline's turn radius is at least ``MIN_RADIUS_M`` (FS hairpins: outer diameter
  of at least 9 m);
- the lane width is within [3, 5] m everywhere (it varies smoothly along the lap); measured on
  the cones with the CLC matching lines, within ``CHORD_TOL_M`` of that range;
- consecutive cones of one boundary are 1-5 m apart, tighter in corners;
- both boundaries are simple and do not touch each other.

Cone positions then get isotropic Gaussian noise (0.1-0.3 m standard deviation, drawn per track
unless given).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.interpolate import splev, splprep

from rld import geometry as geo
from rld.tracks import Track

__all__ = [
    "generate_track",
    "MIN_WIDTH_M",
    "MAX_WIDTH_M",
    "MIN_SPACING_M",
    "MAX_SPACING_M",
    "CHORD_TOL_M",
]

MIN_WIDTH_M, MAX_WIDTH_M = 3.0, 5.0
MIN_SPACING_M, MAX_SPACING_M = 1.0, 5.0
MIN_RADIUS_M = 5.0
GAP_M = 3.0
#: Cones stand on the boundary lines; the chords between them cut corners, so the width
#: measured on the cones (CLC matching lines) may differ from the nominal one by this much.
CHORD_TOL_M = 0.25


def _candidate_centerline(rng: np.random.Generator) -> np.ndarray:
    """Control points of one candidate circuit, counter-clockwise."""
    straight = rng.uniform(40.0, 110.0)
    radius = rng.uniform(14.0, 30.0)
    n_arc, n_straight = 6, max(3, int(straight / 15))
    pts = []
    for k in range(n_straight):  # bottom straight, left to right
        pts.append((-straight / 2 + straight * k / n_straight, -radius))
    for k in range(n_arc):  # right turn-around
        a = -math.pi / 2 + math.pi * k / n_arc
        pts.append((straight / 2 + radius * math.cos(a), radius * math.sin(a)))
    for k in range(n_straight):  # top straight, right to left
        pts.append((straight / 2 - straight * k / n_straight, radius))
    for k in range(n_arc):  # left turn-around
        a = math.pi / 2 + math.pi * k / n_arc
        pts.append((-straight / 2 + radius * math.cos(a), radius * math.sin(a)))
    pts = np.array(pts)
    # Radial jitter gives curvy sections.
    centre_dir = pts / np.linalg.norm(pts, axis=1, keepdims=True)
    pts = pts + centre_dir * rng.normal(0.0, 0.12 * radius, size=(len(pts), 1))
    m = len(pts)
    # Hairpin: pull one control point deep towards the middle.
    if rng.random() < 0.7:
        k = int(rng.integers(m))
        pts[k] = pts[k] * rng.uniform(0.15, 0.45)
    # Chicane: alternate lateral offsets on one straight.
    if rng.random() < 0.7:
        k = int(rng.integers(1, max(2, n_straight - 2)))
        amp = rng.uniform(3.0, 6.0)
        pts[k, 1] += amp
        if k + 1 < n_straight:
            pts[k + 1, 1] -= amp
    return pts


def _boundary_cones(line: np.ndarray, curvature: np.ndarray) -> np.ndarray:
    """Indices into a densely sampled closed boundary ``line`` where cones stand: the spacing
    shrinks with curvature, from 4.8 m on straights to 1.5 m in tight corners, and is spread
    evenly so the loop closes without a short or long last gap."""
    seg = np.hypot(*np.diff(np.vstack([line, line[:1]]), axis=0).T)
    spacing = np.clip(4.8 / (1.0 + 9.0 * np.abs(curvature)), 1.5, 4.8)
    count = np.concatenate([[0.0], np.cumsum(seg / spacing)])  # cones "due" along the line
    n = max(int(round(count[-1])), 3)
    targets = np.arange(n) * (count[-1] / n)
    return np.minimum(np.searchsorted(count, targets), line.shape[0] - 1)


def _signed_curvature(xy: np.ndarray) -> np.ndarray:
    d1 = (np.roll(xy, -1, axis=0) - np.roll(xy, 1, axis=0)) / 2
    d2 = np.roll(xy, -1, axis=0) - 2 * xy + np.roll(xy, 1, axis=0)
    num = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    return num / np.maximum(np.hypot(d1[:, 0], d1[:, 1]) ** 3, 1e-12)


def _try_build(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray] | None:
    ctrl = _candidate_centerline(rng)
    try:
        tck, _ = splprep([ctrl[:, 0], ctrl[:, 1]], s=0.0, per=True, k=3)
    except Exception:  # noqa: BLE001 (scipy raises plain errors on degenerate input)
        return None
    u = np.linspace(0, 1, 4000, endpoint=False)
    c = np.column_stack(splev(u, tck))
    c = geo.resample_polyline(c, 0.25, closed=True)
    if not geo.ring_is_simple(c[::4]):
        return None
    kappa = _signed_curvature(c)
    if np.max(np.abs(kappa)) > 1.0 / MIN_RADIUS_M:
        return None
    # Smoothly varying width within [3, 5] m.
    t = np.linspace(0, 2 * math.pi, c.shape[0], endpoint=False)
    phase, mean = rng.uniform(0, 2 * math.pi), rng.uniform(3.4, 4.6)
    width = np.clip(mean + 0.4 * np.sin(3 * t + phase), MIN_WIDTH_M, MAX_WIDTH_M)
    tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])  # to the left
    left_line = c + normal * (width[:, None] / 2)
    right_line = c - normal * (width[:, None] / 2)
    # Distinct parts of the track must stay apart: any two centreline points further than
    # a quarter lap along the track must be at least width + gap apart.
    step = 8
    sub = c[::step]
    d = np.hypot(*(sub[:, None, :] - sub[None, :, :]).transpose(2, 0, 1))
    k = np.arange(sub.shape[0])
    sep = np.abs(k[:, None] - k[None, :])
    sep = np.minimum(sep, sub.shape[0] - sep) * step * 0.25
    far = sep > 15.0
    if np.any(d[far] < MAX_WIDTH_M + GAP_M):
        return None
    li = _boundary_cones(left_line, kappa)
    ri = _boundary_cones(right_line, kappa)
    return left_line[li], right_line[ri]


def generate_track(
    seed: int = 0,
    noise_m: float | None = None,
    max_tries: int = 500,
) -> Track:
    """A closed circuit that satisfies the module's rules, reproducibly from ``seed``.

    ``noise_m`` is the standard deviation of the Gaussian noise on every cone position, metres;
    ``None`` draws it uniformly from [0.1, 0.3]; 0 gives the noise-free layout. The car starts
    at the first cones of both boundaries and drives in list order (counter-clockwise).
    ``meta`` holds the noise, the noise-free cone positions and the seed.
    """
    rng = np.random.default_rng(seed)
    for _ in range(max_tries):
        built = _try_build(rng)
        if built is None:
            continue
        left, right = built
        if not _rules_hold(left, right):
            continue
        sigma = rng.uniform(0.1, 0.3) if noise_m is None else float(noise_m)
        clean = np.vstack([left, right])
        cones = clean + rng.normal(0.0, 1.0, size=clean.shape) * sigma
        nl = left.shape[0]
        ids = np.arange(clean.shape[0])
        return Track(
            cones,
            ids,
            np.arange(nl),
            np.arange(nl, clean.shape[0]),
            closed=True,
            name=f"generated seed {seed}",
            meta={"seed": seed, "noise_m": sigma, "clean_cones": clean},
        )
    raise RuntimeError(f"no valid track after {max_tries} tries (seed {seed})")


def _rules_hold(left: np.ndarray, right: np.ndarray) -> bool:
    """Spacing, width and simplicity on the noise-free cones (the rules the module claims)."""
    from rld.constraints import c_poly, lane_widths

    for xy in (left, right):
        seg = np.hypot(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T)
        if seg.min() < MIN_SPACING_M or seg.max() > MAX_SPACING_M:
            return False
    if not c_poly(left, right, closed=True):
        return False
    # Width measured from every cone to the other boundary line (the CLC vertex matching).
    w = lane_widths(left, right, closed=True)
    return bool(w.min() >= MIN_WIDTH_M - CHORD_TOL_M and w.max() <= MAX_WIDTH_M + CHORD_TOL_M)

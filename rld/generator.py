"""A seeded generator of closed, rules-compliant Formula Student circuits.

The centreline is a loop of circular corners joined by straights: ordinary corners (6.5-15 m
radius, log-uniform), hairpins (160-190 degrees on a 6.5-9 m radius), chicanes (a left-right
pair), and one to three corners against the loop's sense, in random order; the straights'
lengths (drawn 2-15 m) are adjusted by the least absolute change (a small linear program) so
the loop closes. Cones stand every 2.4-4.2 m (drawn per gap, a little tighter in corners); the
lane is 3.2-3.6 m wide at its narrowest, wider in places. These shapes were chosen (issue 39,
docs/generator.md) so that cone spacing, lane width, turn per cone and position noise are
distributed as on the shared dataset tracks, on the fixed ``CHOOSING_SEEDS``; they are reported
on ``REPORTING_SEEDS`` (``generated_set``). A candidate is kept only when it satisfies every rule
below, on the noise-free cone positions:

- the centreline is closed and simple, and distinct parts of the track keep at least
  ``GAP_M`` metres of infield between their boundaries;
- the centreline's turn radius is at least ``MIN_RADIUS_M`` (FS hairpins: outer diameter
  of at least 9 m, so 4.5 m plus half the width);
- the lane width is within [3, 5] m everywhere (it varies smoothly along the lap); measured on
  the cones with the CLC matching lines, within ``CHORD_TOL_M`` of that range;
- consecutive cones of one boundary are 1-5 m apart, tighter in corners;
- both boundaries are simple and do not touch each other.

Cone positions then get isotropic Gaussian noise (standard deviation drawn per track from
``NOISE_RANGE_M``, 0.05-0.25 m, unless given).
"""

from __future__ import annotations

import math

import numpy as np
from scipy.optimize import linprog

from rld import geometry as geo
from rld.tracks import Track

__all__ = [
    "generate_track",
    "generated_set",
    "CHOOSING_SEEDS",
    "REPORTING_SEEDS",
    "NOISE_RANGE_M",
    "MIN_WIDTH_M",
    "MAX_WIDTH_M",
    "MIN_SPACING_M",
    "MAX_SPACING_M",
    "CHORD_TOL_M",
]

MIN_WIDTH_M, MAX_WIDTH_M = 3.0, 5.0
MIN_SPACING_M, MAX_SPACING_M = 1.0, 5.0
MIN_RADIUS_M = 6.0
GAP_M = 3.0
#: Cones stand on the boundary lines; the chords between them cut corners, so the width
#: measured on the cones (CLC matching lines) may differ from the nominal one by this much.
CHORD_TOL_M = 0.25
#: Issue 39's two fixed sets of generated tracks (DESIGN.md, "Choosing and reporting"): defaults
#: are chosen on ``CHOOSING_SEEDS`` and reported on ``REPORTING_SEEDS``. Neither overlaps the
#: seeds used elsewhere: the tests (0-49), ``rld bench rld-paper`` (11-15), ``rld eval
#: --generated 12 --generated-seed 100`` (100-111) and the ranker's training (1000-1007,
#: ``rld train-ranker``).
CHOOSING_SEEDS = tuple(range(2000, 2032))
REPORTING_SEEDS = tuple(range(3000, 3032))
#: The standard deviation of the cones' position noise is drawn from this range, metres.
NOISE_RANGE_M = (0.05, 0.25)
#: The centreline's shape: counts are [low, high) integer ranges, angles in degrees, radii and
#: straights in metres (issue 39 chose them on ``CHOOSING_SEEDS``: docs/generator.md).
_SHAPE = {
    "chicanes": (0, 3), "chicane_deg": (30, 60), "chicane_radius": (6.5, 11.0),
    "against": (1, 4), "against_deg": (40, 120), "against_radius": (6.5, 12.0),
    "hairpin_p": 0.7, "hairpin_radius": (6.5, 9.0),
    "corners": (4, 9), "corner_radius": (6.5, 15.0),
    "straight": (2.0, 15.0), "straight_bounds": (2.0, 90.0),
}
#: Cone spacing: each gap drawn from ``gap`` (metres), divided by 1 + ``corner`` |curvature|,
#: at least ``min``.
_SPACING = {"gap": (2.4, 4.2), "corner": 1.0, "min": 1.5}
#: Lane width: a per-track least width drawn from ``low`` plus a rise drawn from ``rise`` times
#: ((1 + sin) / 2) ** ``power`` along the lap (narrow most of the way, wider in places), metres.
_WIDTH = {"low": (3.2, 3.6), "rise": (0.6, 1.4), "power": 2.0}


def _corners(rng: np.random.Generator) -> list[tuple[float, float]]:
    """The circuit's corners as (signed turn in radians, centreline radius in metres), in driving
    order, turning 2 pi in all (counter-clockwise): hairpins, chicanes (a left-right pair),
    corners against the loop's sense and ordinary corners (``_SHAPE``), in random order."""
    P = _SHAPE
    groups: list[list[tuple[float, float]]] = []
    negative = 0.0
    for _ in range(int(rng.integers(*P["chicanes"]))):
        a = math.radians(rng.uniform(*P["chicane_deg"]))
        r = rng.uniform(*P["chicane_radius"])
        pair = [(a, r), (-a, r)] if rng.random() < 0.5 else [(-a, r), (a, r)]
        groups.append(pair)
    for _ in range(int(rng.integers(*P["against"]))):
        a = math.radians(rng.uniform(*P["against_deg"]))
        negative += a
        groups.append([(-a, _log_uniform(rng, *P["against_radius"]))])
    budget = 2 * math.pi + negative
    if rng.random() < P["hairpin_p"]:
        a = math.radians(rng.uniform(160, 190))
        budget -= a
        groups.append([(a, rng.uniform(*P["hairpin_radius"]))])
    m = int(rng.integers(*P["corners"]))
    for a in rng.dirichlet(np.full(m, 2.0)) * budget:
        r = (_log_uniform(rng, *P["corner_radius"]) if a < math.radians(150)
             else P["hairpin_radius"][1])
        groups.append([(float(a), r)])
    order = rng.permutation(len(groups))
    return [c for k in order for c in groups[k]]


def _log_uniform(rng: np.random.Generator, lo: float, hi: float) -> float:
    return float(math.exp(rng.uniform(math.log(lo), math.log(hi))))


def _centerline_from_corners(corners, rng) -> np.ndarray | None:
    """Arcs for the corners joined by straights whose lengths are adjusted (least change) so the
    loop closes; ``None`` when no straights within ``_SHAPE["straight_bounds"]`` close it."""
    heading = 0.0
    arcs = []  # displacement of each arc
    dirs = []  # unit direction of each straight (one before every corner)
    for turn, radius in corners:
        dirs.append((math.cos(heading), math.sin(heading)))
        # Chord of the arc: length 2 r sin(|turn| / 2) along the mean heading.
        mean = heading + turn / 2
        chord = 2 * radius * math.sin(abs(turn) / 2)
        arcs.append((chord * math.cos(mean), chord * math.sin(mean)))
        heading += turn
    U = np.array(dirs).T  # (2, k)
    A = np.sum(arcs, axis=0)
    k = U.shape[1]
    L0 = rng.uniform(*_SHAPE["straight"], size=k)
    # Least absolute change of the straights (within their bounds) that closes the loop: U L = -A.
    # Variables [L, t] with t >= |L - L0|; minimise sum(t).
    res = linprog(
        c=np.concatenate([np.zeros(k), np.ones(k)]),
        A_ub=np.block([[np.eye(k), -np.eye(k)], [-np.eye(k), -np.eye(k)]]),
        b_ub=np.concatenate([L0, -L0]),
        A_eq=np.hstack([U, np.zeros((2, k))]),
        b_eq=-A,
        bounds=[_SHAPE["straight_bounds"]] * k + [(0, None)] * k,
        method="highs",
    )
    if res.status != 0:
        return None
    L = res.x[:k]
    pts = [np.zeros(2)]
    heading = 0.0
    for (turn, radius), length in zip(corners, L, strict=True):
        d = np.array([math.cos(heading), math.sin(heading)])
        n = max(int(length / 0.25), 1)
        pts.extend(pts[-1] + d * length * np.arange(1, n + 1)[:, None] / n)
        side = 1.0 if turn > 0 else -1.0
        centre = pts[-1] + side * radius * np.array([-d[1], d[0]])
        start = math.atan2(*(pts[-1] - centre)[::-1])
        k = max(int(abs(turn) * radius / 0.25), 2)
        ang = start + turn * np.arange(1, k + 1) / k
        pts.extend(centre + radius * np.column_stack([np.cos(ang), np.sin(ang)]))
        heading += turn
    c = np.array(pts[:-1])
    return c - c.mean(axis=0)


def _boundary_cones(line: np.ndarray, curvature: np.ndarray,
                    rng: np.random.Generator) -> np.ndarray:
    """Where cones stand ((k, 2) metres) on a densely sampled closed boundary ``line``, walking
    along it: each gap is drawn uniformly from ``_SPACING["gap"]`` (metres), shrunk in
    corners by ``1 / (1 + _SPACING["corner"] |curvature|)`` to no less than
    ``_SPACING["min"]``; all gaps are then scaled alike so the loop closes without a short or
    long last gap."""
    P = _SPACING
    s = geo.cumulative_length(line, closed=True)
    total = s[-1]
    kappa = np.abs(curvature)

    def gap(at: float) -> float:
        j = min(int(np.searchsorted(s, at)), line.shape[0] - 1)
        return max(float(rng.uniform(*P["gap"]) / (1.0 + P["corner"] * kappa[j])), P["min"])

    pos = [0.0]
    while True:
        g = gap(pos[-1])
        if pos[-1] + 1.5 * g > total:
            break
        pos.append(pos[-1] + g)
    pos = np.array(pos) * (total / (pos[-1] + g))
    ring = np.vstack([line, line[:1]])
    return np.column_stack([np.interp(pos, s, ring[:, 0]), np.interp(pos, s, ring[:, 1])])


def _signed_curvature(xy: np.ndarray) -> np.ndarray:
    d1 = (np.roll(xy, -1, axis=0) - np.roll(xy, 1, axis=0)) / 2
    d2 = np.roll(xy, -1, axis=0) - 2 * xy + np.roll(xy, 1, axis=0)
    num = d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]
    return num / np.maximum(np.hypot(d1[:, 0], d1[:, 1]) ** 3, 1e-12)


def _try_build(rng: np.random.Generator) -> tuple[np.ndarray, np.ndarray, np.ndarray] | None:
    c = _centerline_from_corners(_corners(rng), rng)
    if c is None:
        return None
    c = geo.resample_polyline(c, 0.25, closed=True)
    if not geo.ring_is_simple(c[::4]):
        return None
    kappa = _signed_curvature(c)
    if np.max(np.abs(kappa)) > 1.0 / MIN_RADIUS_M:
        return None
    # Smoothly varying width within [3, 5] m.
    t = np.linspace(0, 2 * math.pi, c.shape[0], endpoint=False)
    phase, low = rng.uniform(0, 2 * math.pi), rng.uniform(*_WIDTH["low"])
    rise = rng.uniform(*_WIDTH["rise"]) * ((1 + np.sin(3 * t + phase)) / 2) ** _WIDTH["power"]
    width = np.clip(low + rise, MIN_WIDTH_M, MAX_WIDTH_M)
    tangent = np.roll(c, -1, axis=0) - np.roll(c, 1, axis=0)
    tangent /= np.linalg.norm(tangent, axis=1, keepdims=True)
    normal = np.column_stack([-tangent[:, 1], tangent[:, 0]])  # to the left
    left_line = c + normal * (width[:, None] / 2)
    right_line = c - normal * (width[:, None] / 2)
    # Distinct parts of the track must stay apart: any two centreline points further than
    # 15 m apart along the track must be at least the widest lane plus GAP_M apart.
    step = 8
    sub = c[::step]
    d = np.hypot(*(sub[:, None, :] - sub[None, :, :]).transpose(2, 0, 1))
    k = np.arange(sub.shape[0])
    sep = np.abs(k[:, None] - k[None, :])
    sep = np.minimum(sep, sub.shape[0] - sep) * step * 0.25
    far = sep > 15.0
    if np.any(d[far] < MAX_WIDTH_M + GAP_M):
        return None
    return (_boundary_cones(left_line, kappa, rng), _boundary_cones(right_line, kappa, rng),
            c)


def generate_track(
    seed: int = 0,
    noise_m: float | None = None,
    max_tries: int = 500,
) -> Track:
    """A closed circuit that satisfies the module's rules, reproducibly from ``seed``.

    ``noise_m`` is the standard deviation of the Gaussian noise on every cone position, metres;
    ``None`` draws it uniformly from [0.1, 0.3]; 0 gives the noise-free layout. The car starts
    at the first cones of both boundaries and drives in list order (counter-clockwise).
    ``meta`` holds the seed, the noise, the noise-free cone positions and the design centreline
    (every 0.25 m).
    """
    rng = np.random.default_rng(seed)
    for _ in range(max_tries):
        built = _try_build(rng)
        if built is None:
            continue
        left, right, design = built
        if not _rules_hold(left, right):
            continue
        sigma = rng.uniform(*NOISE_RANGE_M) if noise_m is None else float(noise_m)
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
            meta={
                "seed": seed,
                "noise_m": sigma,
                "clean_cones": clean,
                "design_centerline": design,
            },
        )
    raise RuntimeError(f"no valid track after {max_tries} tries (seed {seed})")


def generated_set(name: str) -> list[Track]:
    """The fixed set of generated tracks ``name``: ``"choosing"`` (``CHOOSING_SEEDS``) or
    ``"reporting"`` (``REPORTING_SEEDS``), in seed order."""
    seeds = {"choosing": CHOOSING_SEEDS, "reporting": REPORTING_SEEDS}.get(name)
    if seeds is None:
        raise ValueError(f"unknown generated set {name!r}: use 'choosing' or 'reporting'")
    return [generate_track(s) for s in seeds]


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

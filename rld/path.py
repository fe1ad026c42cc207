"""A lane's centreline for planners: ``LanePath`` (evenly spaced s, x, y, heading, curvature,
widths; metres, radians) built by ``lane_path`` from the two boundaries' cones (construction:
the comment below; docs/api.md)."""

# Construction (``lane_path``), all in metres:
# 1. Each boundary becomes an interpolating cubic spline through its cones by chord length
#    (periodic for a closed lane, not-a-knot for an open one), sampled every 0.1 m or less.
#    (A polyline would not do for curvature: its chords lie a sagitta, several cm at 3-5 m cone
#    spacing, inside a curve, a ripple whose curvature dwarfs a 15 m radius's.)
# 2. The samples are zipped into rungs as ``rld.geometry.centerline`` zips cones (the shorter
#    next rung first), which orders the correspondence between the sides, monotone on both.
# 3. The zipper's staircase of spline parameters is smoothed (Gaussian, 0.5 m, about its
#    straight trend; wrapped when closed), so no zig-zag of a rung's ends (up to one sample
#    apart) reaches the curvature; the midpoints of the smoothed rungs are the centreline.
# 4. A cubic spline through those midpoints (periodic when closed) is sampled every
#    ``spacing_m`` of its arc length (Gauss-Legendre quadrature): heading and curvature are its
#    first and second derivatives, the widths ``rld.geometry.point_polyline_distance`` to each
#    boundary's polyline through its cones (``rld.geometry.boundary_line``).

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np
from scipy.interpolate import CubicSpline
from scipy.ndimage import gaussian_filter1d

from rld import geometry as geo

__all__ = ["LanePath", "lane_path", "check_spacing", "PATH_COLUMNS"]

#: The columns of ``LanePath.as_array``, in order.
PATH_COLUMNS = ("s", "x", "y", "heading", "curvature", "width_left", "width_right")

_DENSE_STEP_M = 0.1  # at most this between the dense samples of steps 1-3
_SMOOTH_M = 0.5  # the Gaussian smoothing of the correspondence in step 3, metres
_GAUSS = np.polynomial.legendre.leggauss(5)  # arc-length quadrature nodes and weights


def _ro(a) -> np.ndarray:
    a = np.array(a, dtype=np.float64).reshape(-1)
    a.flags.writeable = False
    return a


@dataclass(frozen=True, eq=False)
class LanePath:
    """A lane's centreline sampled every ``spacing_m`` of arc length ``s`` (m): position ``x``,
    ``y`` (m), ``heading`` (rad), signed ``curvature`` (1/m, positive turning left) and the
    distance ``width_left`` / ``width_right`` (m) to each boundary's polyline; read-only arrays."""

    s: np.ndarray = field(default_factory=lambda: np.zeros(0))
    x: np.ndarray = field(default_factory=lambda: np.zeros(0))
    y: np.ndarray = field(default_factory=lambda: np.zeros(0))
    heading: np.ndarray = field(default_factory=lambda: np.zeros(0))
    curvature: np.ndarray = field(default_factory=lambda: np.zeros(0))
    width_left: np.ndarray = field(default_factory=lambda: np.zeros(0))
    width_right: np.ndarray = field(default_factory=lambda: np.zeros(0))
    closed: bool = False
    length: float | None = None
    """Centreline length, m: to the last sample, or back to the first when ``closed`` (the
    closing step is ``length - s[-1]``); ``None`` gives ``s[-1]`` (0 when empty)."""

    def __post_init__(self) -> None:
        for name in PATH_COLUMNS:
            object.__setattr__(self, name, _ro(getattr(self, name)))
        sizes = {getattr(self, name).size for name in PATH_COLUMNS}
        if len(sizes) > 1:
            raise ValueError(f"LanePath arrays differ in length: {sorted(sizes)}")
        object.__setattr__(self, "closed", bool(self.closed))
        if self.length is None:
            object.__setattr__(self, "length", float(self.s[-1]) if self.s.size else 0.0)
        object.__setattr__(self, "length", float(self.length))

    def __len__(self) -> int:
        return int(self.s.size)

    @property
    def xy(self) -> np.ndarray:
        """(N, 2) centreline positions, metres."""
        return np.column_stack([self.x, self.y])

    def as_array(self) -> np.ndarray:
        """(N, 7) float array with the columns of ``PATH_COLUMNS``: s, x, y, heading,
        curvature, width_left, width_right."""
        return np.column_stack([getattr(self, name) for name in PATH_COLUMNS]).reshape(-1, 7)

    def to_dict(self) -> dict:
        """JSON-ready dict: each column of ``PATH_COLUMNS`` as a list of floats, ``closed`` and
        ``length`` (m)."""
        out: dict = {name: getattr(self, name).tolist() for name in PATH_COLUMNS}
        out["closed"] = self.closed
        out["length"] = self.length
        return out


def _side_spline(xy: np.ndarray, closed: bool, name: str) -> tuple[CubicSpline, float]:
    """Interpolating cubic spline through a boundary's cones by chord length, and its parameter
    range (m). Periodic when ``closed``; repeated consecutive cones are dropped."""
    xy = np.asarray(xy, dtype=np.float64)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"the {name} boundary must have shape (k, 2), got {xy.shape}")
    if not np.all(np.isfinite(xy)):
        raise ValueError(f"the {name} boundary has a non-finite point")
    if xy.shape[0]:
        keep = np.concatenate([[True], np.hypot(*np.diff(xy, axis=0).T) > 1e-9])
        xy = xy[keep]
    if closed and xy.shape[0] > 1 and math.hypot(*(xy[-1] - xy[0])) <= 1e-9:
        xy = xy[:-1]  # a ring given with its first point repeated
    need = 3 if closed else 2
    if xy.shape[0] < need:
        raise ValueError(f"the {name} boundary of {'a closed' if closed else 'an open'} lane needs "
                         f"at least {need} distinct points, got {xy.shape[0]}")
    pts = np.vstack([xy, xy[:1]]) if closed else xy
    t = geo.cumulative_length(pts)
    if closed:
        bc = "periodic"
    else:
        bc = "not-a-knot" if pts.shape[0] > 2 else "natural"  # two points: a straight line
    return CubicSpline(t, pts, bc_type=bc), float(t[-1])


def _zip(L: np.ndarray, R: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Rungs of the zipper of ``rld.geometry.centerline`` between the polylines ``L`` and ``R``:
    index pairs (i, j), each step advancing the side whose next vertex makes the shorter rung."""
    lx, ly = L[:, 0].tolist(), L[:, 1].tolist()
    rx, ry = R[:, 0].tolist(), R[:, 1].tolist()
    nl, nr = len(lx) - 1, len(rx) - 1
    i = j = 0
    out_i, out_j = [0], [0]
    while i < nl or j < nr:
        if i == nl:
            j += 1
        elif j == nr:
            i += 1
        elif (lx[i + 1] - rx[j]) ** 2 + (ly[i + 1] - ry[j]) ** 2 <= \
                (lx[i] - rx[j + 1]) ** 2 + (ly[i] - ry[j + 1]) ** 2:
            i += 1
        else:
            j += 1
        out_i.append(i)
        out_j.append(j)
    return np.array(out_i), np.array(out_j)


def _smooth_params(p: np.ndarray, period: float | None, sigma: float) -> np.ndarray:
    """Gaussian smoothing (``sigma`` samples) of the nondecreasing sequence ``p``: about its
    straight trend, wrapped when ``period`` is given (``p[-1] == p[0] + period``), else padded
    by reflection through the end points, so a straight trend comes through exactly."""
    if p.size < 3 or sigma <= 0:
        return p
    if period is not None:
        q = p[:-1]
        trend = p[0] + period * np.arange(q.size) / q.size
        out = gaussian_filter1d(q - trend, sigma, mode="wrap") + trend
        return np.append(out, out[0] + period)
    pad = min(p.size - 1, int(math.ceil(4 * sigma)))
    ext = np.concatenate([2 * p[0] - p[pad:0:-1], p, 2 * p[-1] - p[-2:-pad - 2:-1]])
    out = gaussian_filter1d(ext, sigma, mode="nearest")[pad:pad + p.size]
    return np.clip(out, p[0], p[-1])


def _arc_length(spline: CubicSpline, t: np.ndarray) -> np.ndarray:
    """Arc length (m) of ``spline`` at its breakpoints ``t``, from ``t[0]``."""
    nodes, weights = _GAUSS
    a, b = t[:-1, None], t[1:, None]
    tt = (a + b) / 2 + (b - a) / 2 * nodes[None, :]
    speed = np.hypot(*np.moveaxis(spline.derivative(1)(tt), -1, 0))
    seg = (speed * weights[None, :]).sum(axis=1) * (t[1:] - t[:-1]) / 2
    return np.concatenate([[0.0], np.cumsum(seg)])


def _midline(left_xy, right_xy, closed: bool, step: float) -> np.ndarray:
    """Steps 1-3 of the construction (the comment atop): centreline points in order, (k, 2)."""
    bl, tl = _side_spline(left_xy, closed, "left")
    br, tr = _side_spline(right_xy, closed, "right")
    ul = np.linspace(0.0, tl, max(int(math.ceil(tl / step)), 1) + 1)
    ur = np.linspace(0.0, tr, max(int(math.ceil(tr / step)), 1) + 1)
    L = bl(ul)
    if closed:  # start the right ring at its dense sample nearest to the left's first point
        k = int(np.argmin(np.hypot(*(bl(0.0)[None] - br(ur[:-1])).T)))
        ur = ur + ur[k]
    i, j = _zip(L, br(ur))
    # Every rung moves one side on by a dense step, the midpoint by about half of one.
    sigma = _SMOOTH_M / (step / 2)
    u = _smooth_params(ul[i], tl if closed else None, sigma)
    v = _smooth_params(ur[j], tr if closed else None, sigma)
    c = (bl(u) + br(v)) / 2
    if closed:
        c = c[:-1]  # the last rung is the first again
    # Drop points that do not move on by a quarter step (where both sides' tangents nearly
    # oppose, as they may at a degenerate end).
    xs, ys = c[:, 0].tolist(), c[:, 1].tolist()
    keep = [0]
    for k in range(1, len(xs)):
        if math.hypot(xs[k] - xs[keep[-1]], ys[k] - ys[keep[-1]]) >= step / 4:
            keep.append(k)
    c = c[keep]
    if closed and c.shape[0] > 1 and math.hypot(*(c[-1] - c[0])) < step / 4:
        c = c[:-1]
    return c


def check_spacing(spacing_m) -> float:
    """``spacing_m`` as a float; ValueError unless it is a positive finite number (metres)."""
    if isinstance(spacing_m, bool) or not isinstance(spacing_m, int | float | np.integer |
                                                      np.floating):
        raise ValueError(f"spacing_m must be a number of metres, got {spacing_m!r}")
    if not (math.isfinite(spacing_m) and spacing_m > 0):
        raise ValueError(f"spacing_m must be a positive finite number of metres, got {spacing_m!r}")
    return float(spacing_m)


def lane_path(left_xy, right_xy, closed: bool, spacing_m: float = 0.5) -> LanePath:
    """The centreline between boundaries ``left_xy`` and ``right_xy`` ((k, 2) cones, metres, from
    the car forward) every ``spacing_m`` m, with heading, curvature and widths (construction:
    the comment atop this module). ValueError for a bad spacing, shape or too few points."""
    spacing = check_spacing(spacing_m)
    closed = bool(closed)
    step = min(_DENSE_STEP_M, spacing / 2)
    c = _midline(left_xy, right_xy, closed, step)
    if c.shape[0] < 2:  # both boundaries end where they begin (or shrink to a point)
        raise ValueError("the boundaries leave no centreline of positive length")
    pts = np.vstack([c, c[:1]]) if closed else c
    t = geo.cumulative_length(pts)
    bc = "periodic" if closed else ("not-a-knot" if pts.shape[0] > 2 else "natural")
    spline = CubicSpline(t, pts, bc_type=bc)
    arc = _arc_length(spline, t)
    total = float(arc[-1])
    s = np.arange(0.0, total, spacing) if total > 0 else np.zeros(1)
    if not closed and total - s[-1] > 1e-9:
        s = np.append(s, total)  # an open path ends at the lane's end: a shorter last step
    u = np.interp(s, arc, t)  # |B'| is constant to ~1e-6 within a dense step
    xy, d1, d2 = spline(u), spline(u, 1), spline(u, 2)
    speed = np.hypot(d1[:, 0], d1[:, 1])
    curvature = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(speed, 1e-12) ** 3
    left_line = geo.boundary_line(np.asarray(left_xy, dtype=np.float64).reshape(-1, 2), closed)
    right_line = geo.boundary_line(np.asarray(right_xy, dtype=np.float64).reshape(-1, 2), closed)
    return LanePath(
        s=s, x=xy[:, 0], y=xy[:, 1], heading=np.arctan2(d1[:, 1], d1[:, 0]), curvature=curvature,
        width_left=geo.point_polyline_distance(xy, left_line),
        width_right=geo.point_polyline_distance(xy, right_line), closed=closed, length=total)

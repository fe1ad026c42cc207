"""A lane tracker over time after Huang et al. (2009), section 2.3, for any method's lanes.

The tracked lane is a centreline of control points about every ``spacing_m`` (2 m) metres, each
with a confidence in [0, 1]. Each new centreline (a candidate) is matched to the tracked one by
the match score of section 2.3,

    m(c, l) = integral over s_c of 1 + (tau - d(s_c(x), l)) / tau dx,

where s_c is the longest stretch of the candidate that stays within ``tau_m`` of the tracked
lane. A candidate scoring at least ``min_match_m`` updates the lane: every control point within
``tau_m`` of the candidate moves toward its nearest candidate point by an exponential moving
average (weight ``alpha``) and gains ``confidence_gain``; the others lose ``confidence_decay``,
except those before the candidate's start (on the backward extension of its first segment,
within ``tau_m``), which it does not see (kept as they are); the candidate's part beyond the
tracked lane's far end (when it passes that end within ``tau_m``) extends it with new control
points at ``initial_confidence``. A candidate that does not match (an outlier frame) moves
nothing and every confidence decays. Control points whose confidence falls below
``min_confidence`` are recomputed by linear interpolation between their nearest confident
neighbours (section 2.3), or dropped at the ends. After ``max_misses`` unmatched candidates
in a row the tracker starts over from the next candidate (the paper re-instantiates lanes
from its road map, which cone tracks do not have).

Deviations: the paper runs one tracker per lane of a road network with a map prior; here there
is one lane, no prior, and the control points behind the car (more than ``keep_behind_m``) are
dropped as it drives on. Units: metres.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rld import geometry as geo

__all__ = ["TrackerParams", "TrackedLane", "LaneTracker", "project_onto", "match_score"]


@dataclass(frozen=True)
class TrackerParams:
    """Tunables of the tracker (metres and unitless confidences)."""

    spacing_m: float = 2.0
    tau_m: float = 1.0
    min_match_m: float = 6.0
    alpha: float = 0.5
    initial_confidence: float = 0.3
    confidence_gain: float = 0.2
    confidence_decay: float = 0.1
    min_confidence: float = 0.05
    max_misses: int = 3
    keep_behind_m: float = 4.0
    sample_step_m: float = 0.25

    def __post_init__(self) -> None:
        for name, v in self.__dict__.items():
            if not np.isfinite(v) or v < 0:
                raise ValueError(f"TrackerParams.{name} must be a finite non-negative number")
        if not 0 < self.alpha <= 1:
            raise ValueError("TrackerParams.alpha must be in (0, 1]")
        if self.spacing_m <= 0 or self.tau_m <= 0 or self.sample_step_m <= 0:
            raise ValueError("TrackerParams spacings and tau_m must be positive")


@dataclass(frozen=True)
class TrackedLane:
    """The tracker's lane after an update: ``centerline`` (K, 2) control points from the car
    forward, metres; ``confidence`` (K,) in [0, 1]; ``matched``: the last candidate updated it;
    ``score_m``: that candidate's match score (metres, section 2.3)."""

    centerline: np.ndarray
    confidence: np.ndarray
    matched: bool
    score_m: float = 0.0
    restarted: bool = False

    def confident(self, threshold: float = 0.5) -> np.ndarray:
        """The control points from the start up to the first one below ``threshold``."""
        low = np.flatnonzero(self.confidence < threshold)
        return self.centerline[: low[0] if low.size else self.centerline.shape[0]]


def project_onto(points: np.ndarray, poly: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Nearest points of the polyline ``poly`` (m, 2) to ``points`` (k, 2): ``(closest (k, 2),
    distance (k,), arc length along poly of the closest point (k,))``, metres."""
    points = np.atleast_2d(np.asarray(points, dtype=np.float64))
    poly = np.asarray(poly, dtype=np.float64)
    if poly.shape[0] == 1:
        d = np.hypot(*(points - poly[0]).T)
        return np.repeat(poly[:1], points.shape[0], axis=0), d, np.zeros(points.shape[0])
    q, d, k, t = geo.nearest_on_polyline(points, poly)
    seg = np.hypot(*(poly[1:] - poly[:-1]).T)
    arc = geo.cumulative_length(poly)[k] + np.clip(t, 0.0, 1.0) * seg[k]
    return q, d, arc


def match_score(candidate: np.ndarray, lane: np.ndarray, tau_m: float,
                step_m: float = 0.25) -> float:
    """The match score m(c, l) of section 2.3, metres: the candidate sampled every ``step_m``
    along its arc; the longest run of samples within ``tau_m`` of ``lane``; the integral of
    1 + (tau - d) / tau over that run (trapezoid rule on the samples). 0 when no sample is
    within ``tau_m``."""
    cand = np.asarray(candidate, dtype=np.float64)
    if cand.shape[0] < 2 or np.asarray(lane).shape[0] < 1:
        return 0.0
    pts = geo.resample_polyline(cand, step_m)
    _, d, _ = project_onto(pts, lane)
    s = geo.cumulative_length(pts)
    inside = d <= tau_m
    best, k = 0.0, 0
    n = pts.shape[0]
    while k < n:
        if not inside[k]:
            k += 1
            continue
        j = k
        while j + 1 < n and inside[j + 1]:
            j += 1
        if j > k:
            f = 1.0 + (tau_m - d[k: j + 1]) / tau_m
            best = max(best, float(np.sum(0.5 * (f[1:] + f[:-1]) * np.diff(s[k: j + 1]))))
        k = j + 1
    return best


@dataclass
class LaneTracker:
    """Section 2.3's tracker for one lane; ``update`` once per new centreline."""

    params: TrackerParams = field(default_factory=TrackerParams)
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    confidence: np.ndarray = field(default_factory=lambda: np.zeros(0))
    misses: int = 0

    def reset(self) -> None:
        self.points = np.zeros((0, 2))
        self.confidence = np.zeros(0)
        self.misses = 0

    def _start(self, candidate: np.ndarray) -> TrackedLane:
        self.points = geo.resample_polyline(candidate, self.params.spacing_m)
        self.confidence = np.full(self.points.shape[0], self.params.initial_confidence)
        self.misses = 0
        return TrackedLane(self.points.copy(), self.confidence.copy(), True, 0.0, True)

    def update(self, candidate: np.ndarray | None, car_xy: np.ndarray | None = None,
               heading: np.ndarray | None = None) -> TrackedLane:
        """Fold a new centreline (k, 2), from the car forward, into the tracked lane; ``None``
        (no lane this frame) counts as an unmatched candidate. ``car_xy`` and ``heading``
        (unit vector) drop control points more than ``keep_behind_m`` behind the car."""
        p = self.params
        cand = None if candidate is None else np.asarray(candidate, dtype=np.float64)
        if cand is not None and (cand.ndim != 2 or cand.shape[1] != 2
                                 or not np.all(np.isfinite(cand))):
            raise ValueError("candidate must be a finite (k, 2) array of points")
        if cand is not None and cand.shape[0] < 2:
            cand = None
        if self.points.shape[0] < 2:
            if cand is None:
                return TrackedLane(self.points.copy(), self.confidence.copy(), False)
            return self._start(cand)
        score = 0.0 if cand is None else match_score(cand, self.points, p.tau_m,
                                                     p.sample_step_m)
        if score < p.min_match_m:
            self.misses += 1
            self.confidence = np.maximum(self.confidence - p.confidence_decay, 0.0)
            if self.misses > p.max_misses and cand is not None:
                return self._start(cand)
            self._clean(car_xy, heading)
            return TrackedLane(self.points.copy(), self.confidence.copy(), False, score)
        self.misses = 0
        q, d, arc = project_onto(self.points, cand)
        hit = d <= p.tau_m
        # A control point before the candidate's start is not seen by it: neither a hit nor a
        # miss. A lane that begins at its first cone ahead of the car (CLC's, since
        # 2026-12-04) would else wear down the points behind it, and ``confident`` (from the
        # start) would return none. "Before" is on the backward extension of its first
        # segment: behind the start and within ``tau_m`` of that line. A point whose nearest
        # candidate point is the start but that lies off to the side (a stale fold of the
        # tracked lane, say) is a miss as before.
        unseen = ~hit & (arc <= 0.0) & _behind_start(self.points, cand, p.tau_m)
        self.points[hit] = (1 - p.alpha) * self.points[hit] + p.alpha * q[hit]
        self.confidence = np.where(
            hit, self.confidence + p.confidence_gain,
            np.where(unseen, self.confidence, self.confidence - p.confidence_decay)
        ).clip(0.0, 1.0)
        # Extend with the candidate's part beyond the tracked lane's far end, when the
        # candidate passes that end (within tau): a candidate that stops short of it, or
        # turns away before it, has no part beyond it (before 2026-12-05 the part after
        # the nearest point was appended even when that point was metres off, which folded
        # the tracked lane back on itself in hairpins).
        _, dend, arc = project_onto(self.points[-1:], cand)
        rest = cand_after(cand, float(arc[0]))
        if dend[0] <= p.tau_m and rest.shape[0] >= 2 \
                and geo.polyline_length(rest) >= p.spacing_m:
            new = geo.resample_polyline(rest, p.spacing_m)[1:]
            self.points = np.vstack([self.points, new])
            self.confidence = np.r_[self.confidence, np.full(new.shape[0], p.initial_confidence)]
        self._clean(car_xy, heading)
        return TrackedLane(self.points.copy(), self.confidence.copy(), True, score)

    def _clean(self, car_xy, heading) -> None:
        p = self.params
        if car_xy is not None and heading is not None and self.points.shape[0]:
            along = (self.points - np.asarray(car_xy, float)) @ np.asarray(heading, float)
            first = np.flatnonzero(along >= -p.keep_behind_m)
            k = int(first[0]) if first.size else self.points.shape[0]
            self.points, self.confidence = self.points[k:], self.confidence[k:]
        ok = self.confidence >= p.min_confidence
        if ok.all() or not ok.any():
            if not ok.any():
                self.reset()
            return
        idx = np.flatnonzero(ok)
        lo, hi = idx[0], idx[-1] + 1  # drop unconfident ends
        pts, conf, ok = self.points[lo:hi].copy(), self.confidence[lo:hi].copy(), ok[lo:hi]
        s = np.arange(pts.shape[0], dtype=float)
        for c in range(2):  # interior ones: interpolate between confident neighbours
            pts[~ok, c] = np.interp(s[~ok], s[ok], pts[ok, c])
        self.points, self.confidence = pts, conf


def _behind_start(points: np.ndarray, cand: np.ndarray, tau_m: float) -> np.ndarray:
    """Which ``points`` (k, 2) lie behind the polyline ``cand``'s first point, along its first
    segment, within ``tau_m`` metres of the line through that segment."""
    step = np.hypot(*(cand[1:] - cand[0]).T)
    far = np.flatnonzero(step > 0.0)
    if far.size == 0:
        return np.zeros(points.shape[0], dtype=bool)
    u = (cand[far[0] + 1] - cand[0]) / step[far[0]]
    rel = points - cand[0]
    along = rel @ u
    across = np.abs(rel[:, 0] * u[1] - rel[:, 1] * u[0])
    return (along <= 0.0) & (across <= tau_m)


def cand_after(cand: np.ndarray, arc_m: float) -> np.ndarray:
    """The part of the polyline ``cand`` beyond arc length ``arc_m`` (starting at that point)."""
    s = geo.cumulative_length(cand)
    if arc_m >= s[-1]:
        return cand[-1:].copy()
    k = int(np.searchsorted(s, arc_m, side="right"))
    t = (arc_m - s[k - 1]) / max(s[k] - s[k - 1], 1e-12)
    start = cand[k - 1] + t * (cand[k] - cand[k - 1])
    return np.vstack([start, cand[k:]])

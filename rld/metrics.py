"""Per-pose metrics of the evaluation protocol (DESIGN.md) and the stability ratio of Huang et
al. (2009, section 3.5, eq. 5).

Every method is scored by the same functions. The headline is the geometric rule
(``geometric_deviation``: how far a boundary strays from the true one within 20 m of the car,
critical beyond 1 m or 0.5 m), beside the lane's length and IoU20. The paper-compatible index
rule follows: exact match, per-side divergence (strict, and tolerant of off-boundary points on
the true boundary line, also where they stand in for a true cone) and the six categories, in
this order of precedence: ``failed``, ``gt``, ``diverging_lt20`` (critical), ``near_gt``,
``diverging_ge20``, ``too_short``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon

from rld import geometry as geo
from rld.simulation import Frame
from rld.types import Pose

__all__ = [
    "CATEGORIES",
    "CATEGORY_MEANING",
    "CRITICAL",
    "CRITICAL_DISTANCE_M",
    "TOLERANT_DISTANCE_M",
    "SideDivergence",
    "PoseScore",
    "TRUE_LANE_REACH_M",
    "true_lane_extent",
    "true_sides",
    "true_polygon",
    "true_lines",
    "tolerant_skips",
    "diverges_early",
    "lane_iou",
    "candidate_ious",
    "lane_iou20",
    "truncate_polyline",
    "side_divergence",
    "categorize",
    "score_lane",
    "GEOMETRIC_DISTANCES_M",
    "GEOMETRIC_STEP_M",
    "reference_line",
    "kept_part",
    "densify",
    "side_deviation",
    "geometric_deviation",
    "too_short_sides",
    "circle_crossing",
    "stability_ratio",
    "side_agreement",
    "lanes_agree",
    "lanes_identical",
]

CATEGORIES = ("gt", "near_gt", "too_short", "diverging_ge20", "diverging_lt20", "failed")
#: What each index-rule category means (DESIGN.md step 7), for printing beside it.
CATEGORY_MEANING = {
    "gt": "both sides exactly the true cone sequences",
    "near_gt": "follows the true cones; may leave them beyond 20 m with IoU >= 0.9",
    "too_short": "follows the true cones but a side stops under half its true length",
    "diverging_ge20": "leaves the true cone order beyond 20 m (IoU < 0.9)",
    "diverging_lt20": "leaves the true cone order within 20 m of the car (critical)",
    "failed": "no lane (critical)",
}
#: The categories that count as critical failures (DESIGN.md): diverging below 20 m, no lane.
CRITICAL = frozenset({"diverging_lt20", "failed"})
CRITICAL_DISTANCE_M = 20.0
TOLERANT_DISTANCE_M = 0.5
IOU20_HORIZON_M = 20.0
#: The geometric rule's distances (m, DESIGN.md "Geometric critical"): a boundary more than 1 m
#: off may lead the car off the track; 0.5 m is more than the clearance the rules leave.
GEOMETRIC_DISTANCES_M = (1.0, 0.5)
#: Largest gap (m) between the samples of a predicted boundary (DESIGN.md, geometric rule step 3).
GEOMETRIC_STEP_M = 0.25
#: A true boundary's cone farther than this (m) from the other true boundary lies past the
#: lane's known end (``true_lane_extent``). It is ``LaneParams.max_width_m``'s default; no cone of
#: the shared tracks' whole boundaries is farther than 5.75 m from the other boundary.
TRUE_LANE_REACH_M = 6.5
_PREFIX_WINDOW = 5  # how many boundary cones before the first true one a lane may start with


def _iou(a, b) -> float:
    union = a.union(b).area
    if union <= 0.0:
        return math.nan
    return float(a.intersection(b).area / union)


def true_lane_extent(
    gt_left: np.ndarray, gt_right: np.ndarray, reach_m: float = TRUE_LANE_REACH_M
) -> tuple[int, int]:
    """How many cones of each true boundary (positions, in order) the true lane polygon keeps.

    The protocol's truth (DESIGN.md step 5) follows each side up to its first cone not yet in
    the map, so one side can run on far past the other's end (on track 2, 100 m past it: the
    outside of a bend is seen first). Its polygon then closes with a diagonal across the
    infield, crosses itself, and is no lane any method may return (C_width). Each side is cut
    before its first cone farther than ``reach_m`` from the other side's polyline, keeping at
    least its first cone; both sides are measured against the other's uncut polyline, so the
    rule does not depend on an order. Deviation from DESIGN.md, which takes the sides as they
    are: see docs/protocol.md.
    """
    L = np.asarray(gt_left, dtype=np.float64).reshape(-1, 2)
    R = np.asarray(gt_right, dtype=np.float64).reshape(-1, 2)
    if L.shape[0] == 0 or R.shape[0] == 0:
        return L.shape[0], R.shape[0]

    def keep(a: np.ndarray, b: np.ndarray) -> int:
        far = np.flatnonzero(geo.point_polyline_distance(a, b) > reach_m)
        return a.shape[0] if far.size == 0 else max(int(far[0]), 1)

    return keep(L, R), keep(R, L)


def _ahead_of_first_cones(gt_left: np.ndarray, gt_right: np.ndarray, heading: np.ndarray):
    """The line through the first true cones as ``(a0, n)`` (a point on it and its unit normal
    pointing the way the car faces), or None when the two cones coincide."""
    a0, b0 = np.asarray(gt_left[0], float), np.asarray(gt_right[0], float)
    u = b0 - a0
    norm = np.hypot(*u)
    if norm == 0:
        return None
    u = u / norm
    n = np.array([-u[1], u[0]])
    if n @ np.asarray(heading, float) < 0:
        n = -n
    return a0, n


def _half_plane(a0: np.ndarray, n: np.ndarray) -> Polygon:
    u = np.array([n[1], -n[0]])
    big = 1e4
    return Polygon([a0 - big * u, a0 + big * u, a0 + big * u + big * n, a0 - big * u + big * n])


def _from_line(xy: np.ndarray, a0: np.ndarray, n: np.ndarray) -> np.ndarray:
    """``xy`` from where it first reaches the half-plane ahead of the line (a0, n): the points
    before are dropped and the crossing point is interpolated; empty when it never does."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    side = (xy - a0) @ n
    ahead = np.flatnonzero(side >= 0.0)
    if ahead.size == 0:
        return xy[:0]
    k = int(ahead[0])
    if k == 0:
        return xy.copy()
    s0, s1 = float(side[k - 1]), float(side[k])  # s0 < 0 <= s1, from the same products
    t = s0 / (s0 - s1)
    return np.vstack([xy[k - 1] + t * (xy[k] - xy[k - 1]), xy[k:]])


def lane_iou(
    pred_left: np.ndarray,
    pred_right: np.ndarray,
    gt_left: np.ndarray,
    gt_right: np.ndarray,
    pred_closed: bool = False,
    gt_closed: bool = False,
    heading: np.ndarray | None = None,
) -> float:
    """IoU of the predicted and true lane polygons (left points, then right reversed; invalid
    polygons repaired with ``shapely.make_valid``). NaN when both have no area.

    With ``heading`` (the car's unit heading) and an open truth, both polygons are first clipped
    to the half-plane ahead of the line through the first true cones, as IoU20 is: the truth
    starts there, and a lane that begins with the cones just passed is not wrong (the
    divergence rule lets it), so what lies behind counts neither way.
    """
    a = geo.lane_polygon(pred_left, pred_right, closed=pred_closed)
    b = geo.lane_polygon(gt_left, gt_right, closed=gt_closed)
    a, b = _ahead_only(a, b, gt_left, gt_right, heading, gt_closed)
    return _iou(a, b)


def _ahead_only(pred, truth, gt_left, gt_right, heading, gt_closed):
    """``pred`` (one polygon or an array of them) and ``truth`` clipped to the half-plane ahead
    of the line through the first true cones (``lane_iou``); unchanged without a heading, for
    a closed truth, or when that line is undefined."""
    if heading is None or gt_closed or not len(gt_left) or not len(gt_right):
        return pred, truth
    return _clip_ahead(pred, truth, _ahead_of_first_cones(gt_left, gt_right, heading))


def _clip_ahead(pred, truth, line):
    """``pred`` (one polygon or an array of them) and ``truth`` clipped to the half-plane ahead
    of ``line`` (``_ahead_of_first_cones``), unchanged when it is None."""
    if line is None:
        return pred, truth
    half = _half_plane(*line)
    return shapely.intersection(pred, half), truth.intersection(half)


def true_polygon(frame: Frame, sides: tuple[np.ndarray, np.ndarray] | None = None) -> Polygon:
    """The true lane polygon that the protocol's IoU compares with, before the clip ahead of
    the first true cones: ``true_sides`` (or ``sides``, when already computed) as one polygon,
    closed for a closed truth."""
    gl, gr = true_sides(frame) if sides is None else sides
    return geo.lane_polygon(gl, gr, closed=frame.gt_closed)


def true_sides(frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """The true boundaries (positions, metres) that the protocol's IoU and IoU20 compare with:
    ``frame``'s truth, cut to both sides' common extent (``true_lane_extent``) unless closed."""
    gl, gr = frame.cones[frame.gt_left], frame.cones[frame.gt_right]
    if not frame.gt_closed:
        kl, kr = true_lane_extent(gl, gr)
        gl, gr = gl[:kl], gr[:kr]
    return gl, gr


def candidate_ious(frame: Frame, candidates) -> np.ndarray:
    """The protocol's IoU (as ``score_lane`` gives it, 0 where it is undefined) of many lanes
    at once: ``candidates`` are ``(left, right, closed)`` with frame indices. Vectorized over
    the candidates with shapely; CLC's ranker trains on it (``clc.train``)."""
    cones = frame.cones
    gl, gr = true_sides(frame)
    truth = true_polygon(frame, (gl, gr))
    polys = np.array([geo.lane_polygon(cones[np.asarray(a, dtype=np.int64)],
                                       cones[np.asarray(b, dtype=np.int64)], closed=c)
                      for a, b, c in candidates], dtype=object)
    if polys.size == 0:
        return np.zeros(0)
    polys, truth = _ahead_only(polys, truth, gl, gr, frame.pose.heading, frame.gt_closed)
    inter = shapely.area(shapely.intersection(polys, truth))
    union = shapely.area(shapely.union(polys, truth))
    return np.where(union > 0, inter / np.where(union > 0, union, 1.0), 0.0)


def truncate_polyline(xy: np.ndarray, length_m: float) -> np.ndarray:
    """The first ``length_m`` metres of arc length of ``xy``, ending on an interpolated point."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if xy.shape[0] < 2:
        return xy.copy()
    s = geo.cumulative_length(xy)
    if s[-1] <= length_m:
        return xy.copy()
    k = int(np.searchsorted(s, length_m))  # s[k-1] < length <= s[k]
    t = (length_m - s[k - 1]) / (s[k] - s[k - 1])
    end = xy[k - 1] + t * (xy[k] - xy[k - 1])
    return np.vstack([xy[:k], end])


def lane_iou20(
    pred_left: np.ndarray,
    pred_right: np.ndarray,
    gt_left: np.ndarray,
    gt_right: np.ndarray,
    heading: np.ndarray,
) -> float:
    """IoU20: every boundary cut to the first 20 m of its arc length ahead of the line through
    the first true cones (a boundary that begins behind it is measured from where it crosses
    it), both polygons clipped to the half-plane ahead of that line, then IoU. NaN without a
    true lane."""
    if len(gt_left) == 0 or len(gt_right) == 0:
        return math.nan
    line = _ahead_of_first_cones(gt_left, gt_right, heading)
    if line is None:
        return math.nan
    pl, pr, gl, gr = (truncate_polyline(_from_line(x, *line), IOU20_HORIZON_M)
                      for x in (pred_left, pred_right, gt_left, gt_right))
    return _iou(*_clip_ahead(geo.lane_polygon(pl, pr), geo.lane_polygon(gl, gr), line))


@dataclass(frozen=True)
class SideDivergence:
    """How one predicted boundary follows the true one.

    ``diverged``: it takes a cone that is not the next true cone (or one past the truth's end).
    ``distance_m``: arc length along the truth from the car to the last matched true cone
    (``inf`` when it does not diverge). ``stopped_early``: no divergence, but it ends before the
    truth does.
    """

    diverged: bool
    distance_m: float
    stopped_early: bool
    matched: int


def side_divergence(
    pred: np.ndarray,
    gt: np.ndarray,
    boundary: np.ndarray,
    cones: np.ndarray,
    car_xy: np.ndarray,
    closed: bool,
    skippable: np.ndarray | None = None,
) -> SideDivergence:
    """Divergence of one predicted side ``pred`` from the truth ``gt`` (index arrays into
    ``cones``), following DESIGN.md.

    ``boundary`` is the side's whole boundary in order (indices, -1 for cones not in the map),
    cyclic when ``closed``: ``pred`` may begin with up to five boundary cones that precede
    ``gt[0]`` (beside or behind the car); its next cone must be ``gt[0]`` or ``gt[1]``; then it
    must take the next true cone each step. ``skippable`` (bool per cone) marks cones that the
    tolerant rule passes over instead of diverging.

    With ``skippable``, a passed-over point may also stand in for true cones: when the side goes
    from a matched true cone over one or more passed-over points to a later true cone, the true
    cones between count as matched if each lies within ``TOLERANT_DISTANCE_M`` of the side's
    polyline through those points. A false positive that falls on the line beside a true cone
    is then forgiven whether the lane takes it besides the true cone or instead of it. Both
    lanes are the same line within 0.5 m; the second one was a divergence until 2026-12-02
    (deviation from DESIGN.md's letter, docs/protocol.md). A true cone skipped with no
    passed-over point in its place is still a divergence.
    """
    raw = np.asarray(pred, dtype=np.int64)
    gt = np.asarray(gt, dtype=np.int64)
    skip = np.zeros(cones.shape[0], dtype=bool) if skippable is None else skippable
    kept = np.flatnonzero(~skip[raw]) if raw.size else np.zeros(0, dtype=np.int64)
    pred = raw[kept]
    gt_pos = {int(c): k for k, c in enumerate(gt)} if skippable is not None else {}

    def stood_in(i: int, j: int) -> int:
        """The position in ``gt`` reached when pred[i] follows gt[j] over passed-over points
        that stand in for the true cones between, else -1."""
        k = gt_pos.get(int(pred[i]), -1)
        lo, hi = int(kept[i - 1]), int(kept[i])
        if skippable is None or k <= j + 1 or hi - lo < 2:
            return -1
        line = cones[raw[lo : hi + 1]]
        d = geo.point_polyline_distance(cones[gt[j + 1 : k]], line)
        return k if bool(np.all(d <= TOLERANT_DISTANCE_M)) else -1

    def arc_to(j: int) -> float:
        if j < 0:
            return 0.0
        first = float(np.hypot(*(cones[gt[0]] - car_xy)))
        return first + geo.polyline_length(cones[gt[: j + 1]])

    if pred.size == 0:
        return SideDivergence(False, math.inf, gt.size > 0, 0)
    if gt.size == 0:
        return SideDivergence(True, 0.0, False, 0)
    pos = {int(c): k for k, c in enumerate(boundary) if c >= 0}
    n = len(boundary)
    g0 = pos.get(int(gt[0]))
    t = 0
    last = -1
    while t < pred.size and g0 is not None and int(pred[t]) in pos:
        back = (g0 - pos[int(pred[t])]) % n if closed else g0 - pos[int(pred[t])]
        if not 1 <= back <= _PREFIX_WINDOW or (last >= 0 and back >= last):
            break
        last = back
        t += 1
    if t == pred.size:
        return SideDivergence(False, math.inf, True, 0)
    if pred[t] == gt[0]:
        j = 0
    elif gt.size > 1 and pred[t] == gt[1]:
        j = 1
    else:
        return SideDivergence(True, 0.0, False, 0)
    for i in range(t + 1, pred.size):
        if j + 1 < gt.size and pred[i] == gt[j + 1]:
            j += 1
        elif (k := stood_in(i, j)) >= 0:
            j = k
        else:
            return SideDivergence(True, arc_to(j), False, j + 1)
    return SideDivergence(False, math.inf, j + 1 < gt.size, j + 1)


def categorize(
    ok: bool,
    exact: bool,
    sides: tuple[SideDivergence, SideDivergence],
    iou: float,
    pred_lengths: tuple[float, float],
    true_lengths: tuple[float, float],
) -> str:
    """The protocol's category of one prediction (see the module docstring)."""
    if not ok:
        return "failed"
    if exact:
        return "gt"
    diverged = [s for s in sides if s.diverged]
    if diverged:
        d = min(s.distance_m for s in diverged)
        if d < CRITICAL_DISTANCE_M:
            return "diverging_lt20"
        return "near_gt" if (not math.isnan(iou) and iou >= 0.9) else "diverging_ge20"
    for s, lp, lt in zip(sides, pred_lengths, true_lengths, strict=True):
        if s.stopped_early and lp < 0.5 * lt:
            return "too_short"
    return "near_gt"


@dataclass(frozen=True)
class PoseScore:
    """Every metric of one prediction at one pose."""

    category: str
    category_tolerant: str
    iou: float
    iou20: float
    exact: bool
    divergence_m: float
    divergence_tolerant_m: float
    pred_length_m: float
    true_length_m: float
    deviation_m: float = math.nan
    """The geometric rule's deviation (``geometric_deviation``, m; inf: critical at every
    distance)."""
    too_short: bool = False
    """A lane found with a side under half its true length (``too_short_sides``)."""

    @property
    def critical(self) -> bool:
        return self.category in CRITICAL

    @property
    def critical_tolerant(self) -> bool:
        return self.category_tolerant in CRITICAL

    def critical_at(self, distance_m: float) -> bool:
        """Critical by the geometric rule at ``distance_m`` (DESIGN.md "Geometric critical")."""
        return self.deviation_m > distance_m


def true_lines(frame: Frame) -> tuple[np.ndarray, np.ndarray]:
    """Each side's true boundary line through its mapped cones ((k, 2) metres, left and
    right; a closed boundary's line returns to its first cone)."""
    left, right = (geo.boundary_line(frame.cones[seq[seq >= 0]], frame.closed)
                   for seq in (frame.left_seq, frame.right_seq))
    return left, right


def tolerant_skips(frame: Frame, lines: tuple[np.ndarray, np.ndarray] | None = None
                   ) -> tuple[np.ndarray, np.ndarray]:
    """The tolerant rule's passed-over points per side (bool per cone of ``frame``): on no
    boundary, and within ``TOLERANT_DISTANCE_M`` of that side's true line (``true_lines``)."""
    lines = true_lines(frame) if lines is None else lines
    on_boundary = np.zeros(frame.cones.shape[0], dtype=bool)
    for seq in (frame.left_seq, frame.right_seq):
        on_boundary[seq[seq >= 0]] = True
    return tuple(~on_boundary & (geo.point_polyline_distance(frame.cones, line)
                                 <= TOLERANT_DISTANCE_M) for line in lines)


def diverges_early(frame: Frame, left: np.ndarray, right: np.ndarray,
                   skips: tuple[np.ndarray, np.ndarray] | None = None) -> bool:
    """Whether the lane ``left``, ``right`` (frame indices, a lane that was found) is critical
    by the tolerant rule: a side diverges below ``CRITICAL_DISTANCE_M``, or both sides are
    empty. The same answer as
    ``score_lane(...).critical_tolerant`` for a lane found, without the IoU and lengths
    (``skips``: ``tolerant_skips(frame)``, computed once per frame by a caller that asks for
    many lanes)."""
    skips = tolerant_skips(frame) if skips is None else skips
    sides = tuple(
        side_divergence(np.asarray(p, dtype=np.int64), gt, seq, frame.cones, frame.pose.xy,
                        frame.closed, skip)
        for p, gt, seq, skip in ((left, frame.gt_left, frame.left_seq, skips[0]),
                                 (right, frame.gt_right, frame.right_seq, skips[1])))
    # categorize is the one home of the categories: a lane that diverges is critical or not
    # by its divergence alone, so the IoU and lengths it would read otherwise are not needed
    # (nan and 0: only near_gt / too_short / diverging_ge20 would depend on them). Not exact:
    # an exact lane does not diverge, and is no more critical as "gt" than as near_gt.
    ok = len(left) > 0 or len(right) > 0  # both sides empty: score_lane's "failed"
    return categorize(ok, False, sides, math.nan, (0.0, 0.0), (0.0, 0.0)) in CRITICAL


def score_lane(
    frame: Frame, left: np.ndarray, right: np.ndarray, ok: bool = True, closed: bool = False
) -> PoseScore:
    """Score a predicted lane (frame indices ``left``, ``right``) against ``frame``'s truth."""
    cones = frame.cones
    left = np.asarray(left, dtype=np.int64)
    right = np.asarray(right, dtype=np.int64)
    ok = bool(ok) and (left.size > 0 or right.size > 0)
    gt_closed = frame.gt_closed
    true_len = (
        geo.polyline_length(cones[frame.gt_left], gt_closed),
        geo.polyline_length(cones[frame.gt_right], gt_closed),
    )
    pred_len = (
        geo.polyline_length(cones[left], closed),
        geo.polyline_length(cones[right], closed),
    )
    if not ok:
        mean_true = float(np.mean(true_len))
        return PoseScore("failed", "failed", 0.0, 0.0, False, 0.0, 0.0, 0.0, mean_true,
                         math.inf, False)
    gl, gr = true_sides(frame)
    iou = lane_iou(cones[left], cones[right], gl, gr, closed, gt_closed, frame.pose.heading)
    iou = 0.0 if math.isnan(iou) else iou
    iou20 = lane_iou20(cones[left], cones[right], gl, gr, frame.pose.heading)
    exact = (
        np.array_equal(left, frame.gt_left) and np.array_equal(right, frame.gt_right)
    )
    deviation = geometric_deviation(frame, left, right, True, closed)
    skips = tolerant_skips(frame)
    results = []
    for tolerant in (False, True):
        sides = []
        for pred, gt, seq, skip in ((left, frame.gt_left, frame.left_seq, skips[0]),
                                    (right, frame.gt_right, frame.right_seq, skips[1])):
            sides.append(side_divergence(pred, gt, seq, cones, frame.pose.xy, frame.closed,
                                         skip if tolerant else None))
        cat = categorize(True, exact, (sides[0], sides[1]), iou, pred_len, true_len)
        results.append((cat, min(s.distance_m for s in sides)))
    return PoseScore(
        category=results[0][0],
        category_tolerant=results[1][0],
        iou=iou,
        iou20=iou20,
        exact=exact,
        divergence_m=results[0][1],
        divergence_tolerant_m=results[1][1],
        pred_length_m=float(np.mean(pred_len)),
        true_length_m=float(np.mean(true_len)),
        deviation_m=deviation,
        too_short=too_short_sides(pred_len, true_len),
    )


def too_short_sides(pred_lengths: tuple[float, float], true_lengths: tuple[float, float]) -> bool:
    """A found lane is too short when a side is under half its true length (m), the length rule
    of the ``too_short`` category without its divergence test: reported beside the geometric
    rule, which never counts a short lane."""
    return any(p < 0.5 * t for p, t in zip(pred_lengths, true_lengths, strict=True))


def reference_line(frame: Frame, side: str) -> np.ndarray:
    """The geometric rule's reference for ``side`` ("left" / "right"), DESIGN.md step 1: the
    side's mapped boundary cones in list order from two before its truth's first cone to the
    truth's last ((k, 2) m; wraps on a closed boundary; empty when the truth is)."""
    seq, gt = ((frame.left_seq, frame.gt_left) if side == "left"
               else (frame.right_seq, frame.gt_right))
    if gt.size == 0:
        return np.zeros((0, 2))
    n = seq.size
    pos = {int(c): k for k, c in enumerate(seq) if c >= 0}
    p0, p1 = pos[int(gt[0])], pos[int(gt[-1])]
    if frame.closed:
        ks = (p0 + np.arange(-2, (p1 - p0) % n + 1 if gt.size < n else n)) % n
    else:
        ks = np.arange(max(p0 - 2, 0), p1 + 1)
    idx = seq[ks]
    return frame.cones[idx[idx >= 0]]


def kept_part(pred: np.ndarray, car_xy: np.ndarray,
              horizon_m: float = CRITICAL_DISTANCE_M) -> np.ndarray:
    """The predicted boundary ``pred`` ((k, 2) m, k >= 1) from its first cone to arc length
    s0 + ``horizon_m``, cut by interpolation; s0: the car's nearest point on the first three
    segments, the first one's line extended backwards (DESIGN.md, geometric rule step 2)."""
    pred = np.asarray(pred, dtype=np.float64).reshape(-1, 2)
    if pred.shape[0] < 2:
        return pred
    seg = pred[1:] - pred[:-1]
    length = np.hypot(seg[:, 0], seg[:, 1])
    cum = np.concatenate([[0.0], np.cumsum(length)])
    best, s0 = math.inf, 0.0
    for i in range(min(3, seg.shape[0])):
        ll = float(length[i])
        t = 0.0 if ll == 0.0 else float((car_xy - pred[i]) @ seg[i]) / (ll * ll)
        t = min(t, 1.0) if i == 0 else min(max(t, 0.0), 1.0)
        d = float(np.hypot(*(car_xy - pred[i] - t * seg[i])))
        if d < best - 1e-9:  # a tie keeps the earlier segment
            best, s0 = d, float(cum[i]) + t * ll
    end = s0 + horizon_m
    if end <= 0.0:
        return pred[:1]
    if end >= cum[-1]:
        return pred
    i = int(np.searchsorted(cum, end, side="right")) - 1  # cum[i] <= end < cum[i + 1]
    t = (end - cum[i]) / length[i]
    return np.vstack([pred[: i + 1], pred[i] + t * seg[i]])


def densify(xy: np.ndarray, step_m: float = GEOMETRIC_STEP_M) -> np.ndarray:
    """Every vertex of the polyline ``xy`` and points at most ``step_m`` apart along each of its
    segments (DESIGN.md, geometric rule step 3), in order."""
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if xy.shape[0] < 2:
        return xy
    seg = xy[1:] - xy[:-1]
    counts = np.maximum(np.ceil(np.hypot(seg[:, 0], seg[:, 1]) / step_m).astype(np.int64), 1)
    owner = np.repeat(np.arange(seg.shape[0]), counts)
    t = (np.arange(int(counts.sum())) - (np.cumsum(counts) - counts)[owner]) / counts[owner]
    return np.vstack([xy[:-1][owner] + seg[owner] * t[:, None], xy[-1:]])


def side_deviation(pred: np.ndarray, reference: np.ndarray, car_xy: np.ndarray,
                   closed: bool = False, n_true: int = 2) -> float:
    """One side's geometric deviation (m): the largest distance of ``kept_part(pred)``'s
    samples to ``reference``; inf when the side has under two cones or starts more than 20 m
    from the car while its truth has ``n_true`` >= 2 cones (DESIGN.md steps 2-4)."""
    pred = np.asarray(pred, dtype=np.float64).reshape(-1, 2)
    car_xy = np.asarray(car_xy, dtype=np.float64)
    if n_true >= 2 and (pred.shape[0] < 2
                        or np.hypot(*(pred[0] - car_xy)) > CRITICAL_DISTANCE_M):
        return math.inf
    if pred.shape[0] == 0 or reference.shape[0] == 0:
        return 0.0  # nothing predicted, or no truth to measure against: not measured
    if closed and pred.shape[0] > 2:
        pred = np.vstack([pred, pred[:1]])
    samples = densify(kept_part(pred, car_xy))
    return float(geo.point_polyline_distance(samples, reference).max())


def geometric_deviation(frame: Frame, left: np.ndarray, right: np.ndarray, ok: bool = True,
                        closed: bool = False) -> float:
    """The lane's geometric deviation (m), the larger side's ``side_deviation``; inf when no
    lane is found. Critical at d metres when it exceeds d (``GEOMETRIC_DISTANCES_M``)."""
    if not ok:
        return math.inf
    return max(side_deviation(frame.cones[np.asarray(pred, dtype=np.int64)],
                              reference_line(frame, side), frame.pose.xy, closed, gt.size)
               for pred, side, gt in ((left, "left", frame.gt_left),
                                      (right, "right", frame.gt_right)))


def circle_crossing(line: np.ndarray, center: np.ndarray, radius_m: float) -> np.ndarray | None:
    """The first point where the polyline ``line``, walked from its start, leaves the circle of
    ``radius_m`` around ``center`` (Huang et al. 3.5: the lane estimate ahead meets the
    circle). A segment may start outside, pass through the circle and leave it; a tangent
    touch does not count. ``None`` when it never leaves the circle."""
    line = np.asarray(line, dtype=np.float64)
    exit_ = _first_exit(line, np.asarray(center, dtype=np.float64), radius_m)
    if exit_ is None:
        return None
    i, t = exit_
    return line[i] + t * (line[i + 1] - line[i])


def _circle_roots(p: np.ndarray, u: np.ndarray, radius_m: float):
    """Where the segments ``p + t u`` (p relative to the circle's centre, (k, 2) each) meet the
    circle of ``radius_m``: ``ok`` (the line through the segment cuts it in two points) and the
    two roots ``t1 < t2`` of |p + t u|^2 = r^2 (inside for t in (t1, t2))."""
    qa, qb, qc = (u * u).sum(1), 2.0 * (p * u).sum(1), (p * p).sum(1) - radius_m**2
    disc = qb * qb - 4.0 * qa * qc
    ok = (qa > 0) & (disc > 0)
    root, den = np.sqrt(np.where(ok, disc, 0.0)), np.where(ok, 2.0 * qa, 1.0)
    return ok, (-qb - root) / den, (-qb + root) / den


def _first_exit(line: np.ndarray, center: np.ndarray, radius_m: float
                ) -> tuple[int, float] | None:
    """The segment ``i`` and parameter ``t`` in (0, 1] where the polyline ``line``, walked from
    its start, first leaves the circle (``circle_crossing``), or None."""
    if line.shape[0] < 2:
        return None
    u = np.diff(line, axis=0)
    ok, t1, t2 = _circle_roots(line[:-1] - center, u, radius_m)
    # A segment leaves at t2 if that is on the segment and some part of it before is inside
    # (t2 may exceed 1 by a rounding error when the segment ends on the circle).
    leave = ok & (t2 > 0.0) & (t2 <= 1.0 + 1e-12) & (np.maximum(t1, 0.0) < t2)
    if not leave.any():
        return None
    i = int(np.argmax(leave))
    return i, min(float(t2[i]), 1.0)


def stability_ratio(
    line0: np.ndarray,
    line1: np.ndarray,
    center: np.ndarray,
    radius_m: float,
    travelled_m: float,
) -> float:
    """Huang et al. eq. 5: R = ||p0 - p1|| / d_v, where p0 and p1 are where the previous and the
    new lane estimate (centrelines, from the car forward) cross the circle of ``radius_m``
    around the car's position ``center`` at the previous step, and d_v the distance the car
    travelled between the two estimates. NaN when either estimate does not reach the circle or
    the car did not move."""
    if travelled_m <= 0:
        return math.nan
    p0 = circle_crossing(line0, np.asarray(center, float), radius_m)
    p1 = circle_crossing(line1, np.asarray(center, float), radius_m)
    if p0 is None or p1 is None:
        return math.nan
    return float(np.hypot(*(p0 - p1)) / travelled_m)


def side_agreement(a: np.ndarray, b: np.ndarray) -> int:
    """How many cones two boundaries (index sequences into the same map, from the car forward)
    share over their common horizon, or -1 where they contradict each other there.

    The common horizon starts where the later of the two starts: when ``b[0]`` lies in ``a``,
    ``a`` is cut to begin there, else when ``a[0]`` lies in ``b``, ``b`` is (methods differ in
    where a boundary starts: RLD may keep a cone up to ``window_behind_m`` behind the car, CLC
    starts at the cones nearest the car). It ends where the shorter of the two ends: a lane that
    stops earlier (RLD's cone window) does not contradict one that goes on. Within it the two
    sequences must be equal. Returns the length of the common part (>= 1), or -1 when neither
    start lies in the other boundary or the common parts differ."""
    a = [int(v) for v in np.asarray(a).ravel()]
    b = [int(v) for v in np.asarray(b).ravel()]
    if not a or not b:
        return -1
    if b[0] in a:
        a = a[a.index(b[0]):]
    elif a[0] in b:
        b = b[b.index(a[0]):]
    else:
        return -1
    n = min(len(a), len(b))
    return n if a[:n] == b[:n] else -1


def lanes_identical(lane_a, lane_b, pose: Pose) -> bool:
    """Whether two ``Lane``\\ s on the same map are the same lane cone for cone: both found,
    both open or both closed; open sides equal from each side's first cone not behind the car
    (``geometry.leading_behind``) to its end, closed sides as sets of edges. Stricter than
    ``lanes_agree``: a lane cut short, or no lane against no lane, is not the same lane."""
    if not (lane_a.ok and lane_b.ok) or bool(lane_a.closed) != bool(lane_b.closed):
        return False
    for x, y in ((lane_a.left, lane_b.left), (lane_a.right, lane_b.right)):
        x, y = np.asarray(x, dtype=np.int64), np.asarray(y, dtype=np.int64)
        if lane_a.closed:
            if _edge_set(x) != _edge_set(y):
                return False
            continue
        jx = geo.leading_behind(lane_a.cones[x], pose.xy, pose.heading, keep=0)
        jy = geo.leading_behind(lane_b.cones[y], pose.xy, pose.heading, keep=0)
        if not np.array_equal(x[jx:], y[jy:]):
            return False
    return True


def _edge_set(loop: np.ndarray) -> set[tuple[int, int]]:
    s = [int(v) for v in loop]
    return {tuple(sorted(e)) for e in zip(s, s[1:] + s[:1], strict=True)}


def lanes_agree(lane_a, lane_b, min_common: int = 2) -> bool:
    """Whether two ``Lane``\\ s (or ``(left, right)`` index pairs; ``None`` for no lane) on the
    same map give the same boundaries over their common horizon (``side_agreement``; a closed
    lane's boundaries as loops, ``_closed_agreement``), with at least ``min_common`` shared
    cones on each side. Two methods that both find no lane agree; one lane against none does
    not."""
    def sides(lane):
        if lane is None or (hasattr(lane, "ok") and not lane.ok):
            return None
        if hasattr(lane, "left"):
            return lane.left, lane.right
        return lane

    sa, sb = sides(lane_a), sides(lane_b)
    if sa is None or sb is None:
        return sa is None and sb is None
    ca, cb = (bool(getattr(lane, "closed", False)) for lane in (lane_a, lane_b))
    return all(_closed_agreement(x, y, ca, cb) >= min_common
               for x, y in zip(sa, sb, strict=True))


def _closed_agreement(a: np.ndarray, b: np.ndarray, closed_a: bool, closed_b: bool) -> int:
    """``side_agreement`` where a boundary may be a loop: two loops agree (their length) when
    their edge sets are equal; a loop against an open boundary is read from the open one's
    first cone (where it starts is the method's convention, not a disagreement)."""
    a = [int(v) for v in np.asarray(a).ravel()]
    b = [int(v) for v in np.asarray(b).ravel()]
    if closed_a and closed_b:
        return len(a) if a and _edge_set(a) == _edge_set(b) else -1
    if closed_a and b and b[0] in a:
        i = a.index(b[0])
        a = a[i:] + a[:i]
    elif closed_b and a and a[0] in b:
        i = b.index(a[0])
        b = b[i:] + b[:i]
    return side_agreement(np.array(a, dtype=np.int64), np.array(b, dtype=np.int64))

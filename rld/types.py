"""Value types of the public API: ``Pose``, ``LaneParams``, ``LaneStatus``, ``Lane``.

Validation of user input happens once, here, at the API edge (``as_cones``, ``as_pose``): a
malformed input raises ``ValueError`` naming the problem; everything behind the edge may assume
clean ``float64`` arrays.
"""

from __future__ import annotations

import enum
import math
from collections.abc import Sequence
from dataclasses import dataclass, field, fields, is_dataclass, replace
from typing import TYPE_CHECKING, Any

import numpy as np

if TYPE_CHECKING:
    from rld.path import LanePath

__all__ = [
    "Pose",
    "LaneParams",
    "LaneStatus",
    "Lane",
    "as_cones",
    "as_pose",
    "MIN_CONES",
]

#: Fewest cones that can form a lane: two boundaries of at least two cones each.
MIN_CONES = 4


@dataclass(frozen=True)
class Pose:
    """The car's pose in the map frame: position ``x``, ``y`` in metres, ``yaw`` in radians
    (counter-clockwise from the map's x axis)."""

    x: float
    y: float
    yaw: float

    def __post_init__(self) -> None:
        # Made once, read-only: the solvers read them tens of thousands of times per lap
        # (a new array per read cost about 0.1 ms of a 3 ms CLC call).
        xy = np.array([self.x, self.y], dtype=np.float64)
        yaw = float(self.yaw)  # not validated here (as_pose does): a non-finite one gives NaNs
        h = (np.array([math.cos(yaw), math.sin(yaw)], dtype=np.float64) if math.isfinite(yaw)
             else np.full(2, math.nan))
        xy.flags.writeable = h.flags.writeable = False
        object.__setattr__(self, "_xy", xy)
        object.__setattr__(self, "_heading", h)

    def __reduce__(self):
        # Rebuilt through __init__, so a copy or an unpickled pose has read-only arrays too.
        return (type(self), (self.x, self.y, self.yaw))

    @property
    def xy(self) -> np.ndarray:
        """Position as a (2,) float array, metres (read-only)."""
        return self._xy

    @property
    def heading(self) -> np.ndarray:
        """Unit heading vector h_c (RLD eq. 25), as a (2,) float array (read-only)."""
        return self._heading

    def to_local(self, points: np.ndarray) -> np.ndarray:
        """Map-frame points (k, 2) to the car frame: x forward, y to the left, metres."""
        d = np.asarray(points, dtype=np.float64) - self.xy
        c, s = math.cos(self.yaw), math.sin(self.yaw)
        return np.column_stack([c * d[:, 0] + s * d[:, 1], -s * d[:, 0] + c * d[:, 1]])


def as_pose(pose: Pose | Sequence[float] | np.ndarray) -> Pose:
    """Validate ``pose`` (a ``Pose`` or three numbers ``x, y, yaw``) and return a ``Pose``.

    Raises ``ValueError`` when it has the wrong length or a non-finite value.
    """
    if isinstance(pose, Pose):
        values = (pose.x, pose.y, pose.yaw)
    else:
        try:
            arr = np.asarray(pose, dtype=np.float64).reshape(-1)
        except (TypeError, ValueError) as exc:
            raise ValueError(f"pose must be (x, y, yaw) numbers, got {pose!r}") from exc
        if arr.shape != (3,):
            raise ValueError(f"pose must have 3 values (x, y, yaw), got {arr.size}")
        values = tuple(float(v) for v in arr)
    if not all(math.isfinite(v) for v in values):
        raise ValueError(f"pose has a non-finite value: {values}")
    return Pose(*values)


def as_cones(cones: Any, min_cones: int = MIN_CONES) -> np.ndarray:
    """Validate ``cones`` (array-like of shape (N, 2), metres) and return a C-contiguous
    ``float64`` copy.

    Raises ``ValueError`` on a wrong shape, a non-numeric or non-finite entry, or fewer than
    ``min_cones`` cones (a lane needs two cones per boundary).
    """
    try:
        arr = np.array(cones, dtype=np.float64)
    except (TypeError, ValueError) as exc:
        raise ValueError(f"cones must be numeric with shape (N, 2): {exc}") from exc
    if arr.ndim != 2 or arr.shape[1] != 2:
        raise ValueError(f"cones must have shape (N, 2), got {arr.shape}")
    if not np.all(np.isfinite(arr)):
        bad = np.flatnonzero(~np.all(np.isfinite(arr), axis=1))
        raise ValueError(
            f"cones contain NaN or inf at rows {bad[:10].tolist()}"
            + (" ..." if bad.size > 10 else "")
        )
    if arr.shape[0] < min_cones:
        raise ValueError(
            f"need at least {min_cones} cones for a lane (two per boundary), got {arr.shape[0]}"
        )
    return np.ascontiguousarray(arr)


#: LaneParams fields for which 0 is meaningful.
_MAY_BE_ZERO = ("window_behind_m", "nvd_distance_weight", "nvd_lookahead_weight",
                "contested_margin", "start_min_width_m", "start_lookback_m", "start_reach_m",
                "duplicate_radius_m", "w_regularity", "w_width_roughness", "w_color",
                "color_unknown", "nvd_color_weight", "rank_color_weight")


@dataclass(frozen=True)
class LaneParams:
    """Every tunable of both methods, in one frozen object. Units are in the names.

    Defaults come from the Formula Student rules, the CLC paper (Ivanov & Markgraf 2024,
    section VIII-C) and the RLD paper (Brandes et al. 2020, section II); the RLD weights
    and tolerances are not printed in that paper and are our choice (see docs/formulation.md).
    """

    max_cone_spacing_m: float = 5.5
    """Longest edge between consecutive cones of one boundary, metres (CLC d_max, eq. 2; RLD's
    candidate edges). Source: CLC section VIII-C (the rules space a side's cones at most 5 m
    apart); larger values measured, not kept: docs/tuning.md#max_cone_spacing_m."""
    min_width_m: float = 2.5
    """Narrowest lane, metres (CLC w_min, eq. 13; RLD d_min, eq. 7). Source: CLC section VIII-C;
    the rules guarantee a 3 m track."""
    max_width_m: float = 6.5
    """Widest lane, metres (CLC w_max, eq. 13). Source: CLC section VIII-C."""
    max_turn_angle_rad: float = math.pi / 2
    """Largest absolute turn between consecutive segments of a boundary, radians (CLC phi_max,
    eq. 15); with theta_e = pi it also sets RLD's t_crit (eq. 28, ``max_angle_cost``). Source:
    CLC section VIII-C (90 degrees)."""
    expected_spacing_m: float = 3.5
    """RLD d_e (eq. 18): the expected distance between consecutive cones of one side, metres.
    Source: our first choice; the paper prints no value (docs/formulation.md)."""
    spacing_tolerance_m: float = 2.2
    """RLD d_t (eq. 18): the spacing deviation that costs 1, metres; the paper prints no value.
    2.2 so that a 1 m edge between two cones of one boundary line earns more than it costs.
    Chosen by measurement: docs/tuning.md#spacing_tolerance_m."""
    angle_tolerance_rad: float = 0.7
    """RLD theta_t (eq. 20): the turn angle that costs 1, radians (theta_e = pi, a straight
    line); the paper prints no value. Smaller values cut lanes short in hairpins. Chosen by
    measurement: docs/tuning.md#angle_tolerance_rad."""
    max_spacing_cost: float = 4.0
    """RLD s_crit (eq. 27), dimensionless: edges with a larger spacing cost are excluded; with
    the defaults, edges shorter than 0.39 m (3.5 - 2.2 * 4^(1/4)). Source: our first choice;
    the paper prints no value."""
    w_spacing: float = 1.0
    """RLD w_s (eq. 29), dimensionless. Source: our first choice; the paper prints no weights."""
    w_angle: float = 1.0
    """RLD w_t (eq. 29), dimensionless. Source: our first choice; the paper prints no weights."""
    w_heading: float = 1.0
    """RLD w_p (eq. 29), dimensionless. Source: our first choice; the paper prints no weights."""
    w_benefit: float = 2.5
    """RLD w_b (eq. 29): the reward for every chosen edge, dimensionless; the paper prints no
    value. Chosen by measurement (a grid with theta_t and d_t): docs/tuning.md#w_benefit."""
    w_regularity: float = 0.5
    """Weight of the spacing-regularity cost (``rld.costs.regularity_cost``; ours, dimensionless)
    in RLD's objective and ``lane_cost`` (so CLC's judge too); 0 turns it off. Chosen by
    measurement: docs/tuning.md#w_regularity."""
    w_width_roughness: float = 0.2
    """Weight of the width roughness (``rld.costs.width_roughness``, per m^2; ours) in CLC's dive
    judge (``clc.refine.dive_cost``); 0 turns it off. The roughness of true lanes in hairpins
    caps it. Chosen by measurement: docs/tuning.md#w_width_roughness."""
    regularity_tolerance: float = 2.0
    """rho_t of the regularity cost (``w_regularity``; ours): the ratio of consecutive edge
    lengths that costs 1, dimensionless, above 1. Chosen by measurement of the true edges:
    docs/tuning.md#regularity_tolerance."""
    w_color: float = 0.35
    """Weight of the colour cost (``rld.costs.boundary_color_cost``, 1 per contradicting cone), RLD
    units (eq. 29); the RLD forms, and CLC's dive judge with ``Refinement.judge_color`` (off);
    0 turns it off. Chosen by measurement: docs/tuning.md#w_color."""
    color_unknown: float = 1.0
    """What the colour cost charges each cone of a boundary labelled unknown, in contradicting
    cones (``rld.costs.boundary_color_cost``; ours): perception leaves false positives
    unclassified more often than true cones. Chosen by measurement: docs/tuning.md#w_color."""
    w_confidence: float = 1.0
    """Weight of the confidence cost (ours; RLD section V): w (1 - confidence) for every cone the
    lane uses; only with ``confidence``. Source: our first choice."""
    heading_radius_m: float = 4.0
    """RLD d_h (eq. 9), metres: edges whose nearest point is this close to the car count for h.
    Source: our first choice (the paper prints no value); 4.5 m measured, not kept:
    docs/tuning.md#heading_radius_m."""
    heading_tolerance_rad: float = math.pi / 4
    """RLD theta_heading (eq. 9), radians: the most an edge near the car may deviate from the
    heading. Source: our first choice (the paper prints no value)."""
    heading_min_distance_m: float = 1.0
    """Floor on d_car in RLD's heading cost (eq. 25), metres, so that an edge passing under the
    car does not divide by zero. Source: ours (eq. 25 has no floor)."""
    near_radius_m: float = 4.5
    """RLD d_near (eqs 11-12) and CLC's start-vertex search radius (IV-C), metres: the first cone
    of each boundary lies within it. Source: the rules (a side's cones up to 5 m apart need more
    than CLC IV-C's "such as 2 m")."""
    start_reach_m: float = 10.0
    """A side with no cone within ``near_radius_m`` starts at its nearest cone ahead of the car
    within this, metres (ours, a start line; ``rld.constraints.start_mask``): ``near_radius_m``
    plus one ``max_cone_spacing_m``; 0 turns it off. Chosen: docs/tuning.md#start_reach_m."""
    far_endpoint_max_m: float = 6.5
    """RLD d_max (eq. 17), metres: the most the two far endpoints may be apart. The paper prints
    no value but calls it "the maximum reasonable lane width", so ``max_width_m``. Chosen by
    measurement: docs/tuning.md#far_endpoint_max_m."""
    max_iterations: int = 250
    """CLC it_max (Alg. 2): the most extensions one enumeration makes. The paper's 2500 (VIII-C)
    adds near-car alternatives that the ranker then sometimes prefers, in more time. Chosen by
    measurement: docs/tuning.md#max_iterations."""
    nvd_distance_weight: float = 0.15
    """Distance term of CLC's next-vertex decider, radians per metre: the search tries first the
    neighbour minimising |turn| + this * distance; 0 is eq. 3 (the turn alone), which skips cones
    near the car. Chosen by measurement: docs/tuning.md#nvd_distance_weight."""
    nvd_lookahead_weight: float = 0.75
    """Look-ahead of CLC's next-vertex decider (ours, dimensionless): an option's score adds this
    times the best score of the step after it, so a cone that only a sharp turn can leave ranks
    lower; 0 is the one-step decider. Chosen by measurement: docs/tuning.md#nvd_lookahead_weight."""
    nvd_color_weight: float = 0.0
    """Radians added to CLC's next-vertex decider score of a cone whose class contradicts the side
    being extended (``clc.search.color_penalties``); 0: off (none helped at colour accuracy 0.95
    without hurting at 0.8 or random labels). Chosen: docs/tuning.md#nvd_color_weight."""
    rank_color_weight: float = 1.0
    """Subtracted from CLC's ranker score times a lane's colour cost per cone within 25 m
    (``rld.costs.lane_color_costs``, ``share=True``; ``clc.solver.ClcModel._score``; ranker
    units); 0: off. Chosen by measurement: docs/tuning.md#rank_color_weight."""
    contested_margin: float = 0.2
    """CLC's contested-choice dives (ours; ``clc.search.contested_dives``): a choice of the lane
    whose runner-up scored at most this much higher in the next-vertex decider (its radians) is
    searched again; 0: no dives. Chosen by measurement: docs/tuning.md#contested_margin."""
    start_pairs: int = 4
    """How many start pairs CLC tries, most symmetric first (IV-C), the next only while none has
    given a lane (ours; 1 is the paper's single pair). Chosen by measurement:
    docs/tuning.md#start_pairs."""
    start_min_width_m: float = 3.0
    """CLC's start pairs (IV-C) whose two cones are closer than this, metres, come after every
    wider pair (ours; 0 is the paper's order): the rules guarantee a 3 m track. Chosen by
    measurement: docs/tuning.md#start_min_width_m."""
    start_lookback_m: float = 3.0
    """CLC seeks its start pairs (IV-C) about the point this far behind the car, metres along its
    heading, first, then about the car; the lane is returned from its first cone not behind the
    car (ours; 0 is the paper's). Chosen by measurement: docs/tuning.md#start_lookback_m."""
    max_cones: int = 20
    """How many map cones, nearest ahead of the car, RLD's program takes (the paper's n; it uses
    12, section IV-A). Source: our first choice."""
    max_windows: int = 30
    """Most cone windows one ``rld`` call solves: the car's, then frontier windows chained on
    its lane's end (``rld.incremental.IncrementalRld.chain``) while the call's time budget
    lasts; 1 is the paper's single window. Chosen by measurement: docs/tuning.md#max_windows."""
    duplicate_radius_m: float = 0.3
    """Cones at most this far apart, metres centre to centre, are one cone, merged before any
    method runs (``rld.dedup``); 0 turns merging off. Source: the rules (a small cone's base is
    0.228 m wide, so two cones cannot stand closer)."""
    window_behind_m: float = 4.0
    """How far behind the car, metres along its heading, a cone may lie and still enter RLD's
    window; the cones beside the car must stay in for the lane to start there (at 0 some drop out).
    Chosen by measurement: docs/tuning.md#window_behind_m."""

    def __post_init__(self) -> None:
        for name, value in self.__dict__.items():
            if not isinstance(value, int | float) or not math.isfinite(float(value)):
                raise ValueError(f"LaneParams.{name} must be a finite number, got {value!r}")
            if value < 0 or (value == 0 and name not in _MAY_BE_ZERO):
                raise ValueError(f"LaneParams.{name} must be positive, got {value!r}")
        if self.min_width_m >= self.max_width_m:
            raise ValueError("LaneParams.min_width_m must be below max_width_m")
        if self.max_turn_angle_rad > math.pi:
            raise ValueError("LaneParams.max_turn_angle_rad must be at most pi")
        if int(self.start_pairs) < 1:
            raise ValueError("LaneParams.start_pairs must be at least 1")
        if int(self.max_cones) < 4:
            raise ValueError("LaneParams.max_cones must be at least 4")
        if int(self.max_windows) < 1:
            raise ValueError("LaneParams.max_windows must be at least 1")
        if self.regularity_tolerance <= 1.0:
            raise ValueError("LaneParams.regularity_tolerance must be above 1 (a length ratio)")

    @classmethod
    def from_overrides(cls, items) -> LaneParams:
        """The defaults with ``items`` applied: ``"name=value"`` strings (as the CLI's
        ``--param`` takes them) or a mapping of names to values. Each value takes its field's
        type (an int field wants an integer). ValueError naming the field for an unknown name,
        a value that does not parse or one the checks of ``__post_init__`` refuse."""
        base = cls()
        known = [f.name for f in fields(cls)]
        pairs = items.items() if hasattr(items, "items") else [
            tuple(str(t).split("=", 1)) if "=" in str(t) else (str(t), None) for t in items]
        kw = {}
        for name, value in pairs:
            name = str(name).strip()
            if name not in known:  # a property such as max_angle_cost is no field
                raise ValueError(f"LaneParams has no field {name!r}; fields: "
                                 + ", ".join(known))
            if value is None:
                raise ValueError(f"give a value: {name}=VALUE")
            kind = type(getattr(base, name))
            try:
                kw[name] = kind(value) if kind is float else int(str(value).strip())
            except ValueError as exc:
                what = "a number" if kind is float else "an integer"
                raise ValueError(f"LaneParams.{name} takes {what}, got {value!r}") from exc
        return replace(base, **kw)

    @property
    def max_angle_cost(self) -> float:
        """RLD t_crit (eq. 28), derived so that eq. 28 and the turn limit C_seg coincide:
        t_crit = (phi_max / theta_t)^4."""
        return (self.max_turn_angle_rad / self.angle_tolerance_rad) ** 4


class LaneStatus(enum.Enum):
    """Outcome of one solve.

    ``OPTIMAL`` and ``FEASIBLE`` carry a lane; the others carry none and say why.
    """

    OPTIMAL = "optimal"
    """The method's own criterion is proved optimal (or, for a search, the search is complete)."""
    FEASIBLE = "feasible"
    """A valid lane, but the budget ran out before optimality (or completeness) was shown."""
    NOT_FOUND = "not_found"
    """No lane: the method found none (no start cones near the car, no feasible pair, ...)."""
    INFEASIBLE = "infeasible"
    """No lane: the program was proved to have no solution."""
    TIMEOUT = "timeout"
    """No lane: the time budget ran out before any lane was found."""

    @property
    def ok(self) -> bool:
        return self in (LaneStatus.OPTIMAL, LaneStatus.FEASIBLE)


_EMPTY = np.zeros(0, dtype=np.int64)


def _plain(value: Any) -> Any:
    """``value`` as plain JSON types, for ``Lane.to_dict``'s stats: numpy scalars and arrays to
    numbers and lists, mappings to dicts with str keys, dataclasses to dicts of their fields,
    enums to their names, non-finite floats to None, anything else to its ``repr``."""
    if value is None or isinstance(value, bool | str | int):
        return value
    if isinstance(value, float | np.floating):
        return float(value) if math.isfinite(value) else None
    if isinstance(value, np.bool_ | np.integer):
        return value.item()
    if isinstance(value, np.ndarray):
        return _plain(value.tolist())
    if isinstance(value, dict):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, list | tuple | set | frozenset):
        return [_plain(v) for v in value]
    if isinstance(value, enum.Enum):
        return value.name
    if is_dataclass(value) and not isinstance(value, type):
        return {f.name: _plain(getattr(value, f.name)) for f in fields(value)}
    return repr(value)


@dataclass(frozen=True, eq=False)
class Lane:
    """The driving lane found in ``cones``: two ordered index sequences, from the car forward.

    Everything else (``left_xy``, ``right_xy``, ``centerline``, ``polygon``) is derived from the
    indices and the cones; a ``Lane`` never holds coordinates of its own. A lane that was not
    found has empty ``left`` and ``right`` and a ``status`` and ``message`` saying why.
    """

    cones: np.ndarray
    left: np.ndarray = field(default_factory=lambda: _EMPTY.copy())
    right: np.ndarray = field(default_factory=lambda: _EMPTY.copy())
    status: LaneStatus = LaneStatus.NOT_FOUND
    message: str = ""
    cost: float = math.nan
    closed: bool = False
    stats: dict = field(default_factory=dict)

    def __post_init__(self) -> None:
        cones = np.asarray(self.cones, dtype=np.float64)
        left = np.asarray(self.left, dtype=np.int64).reshape(-1)
        right = np.asarray(self.right, dtype=np.int64).reshape(-1)
        object.__setattr__(self, "cones", cones)
        object.__setattr__(self, "left", left)
        object.__setattr__(self, "right", right)
        n = cones.shape[0]
        for name, idx in (("left", left), ("right", right)):
            if idx.size and (idx.min() < 0 or idx.max() >= n):
                raise ValueError(f"Lane.{name} has an index outside 0..{n - 1}")
        # One count of every index (cheaper than sorting each side); which rule broke is
        # found only when one did.
        if left.size + right.size > 1 and np.bincount(np.concatenate([left, right])).max() > 1:
            for name, idx in (("left", left), ("right", right)):
                if idx.size and np.bincount(idx).max() > 1:
                    raise ValueError(f"Lane.{name} visits a cone twice")
            raise ValueError("Lane.left and Lane.right share a cone")
        if not self.status.ok and (left.size or right.size):
            raise ValueError(f"a lane with status {self.status.name} must be empty")
        if self.status.ok and (left.size == 0 or right.size == 0):
            raise ValueError(f"a lane with status {self.status.name} needs both boundaries")

    @classmethod
    def not_found(
        cls,
        cones: np.ndarray,
        message: str,
        status: LaneStatus = LaneStatus.NOT_FOUND,
        stats: dict | None = None,
    ) -> Lane:
        """An empty lane saying why none was found."""
        return cls(cones=cones, status=status, message=message, stats=dict(stats or {}))

    @property
    def ok(self) -> bool:
        """True when a lane was found."""
        return self.status.ok

    @property
    def left_xy(self) -> np.ndarray:
        """(k, 2) positions of the left boundary, metres, from the car forward."""
        return self.cones[self.left]

    @property
    def right_xy(self) -> np.ndarray:
        """(k, 2) positions of the right boundary, metres, from the car forward."""
        return self.cones[self.right]

    @property
    def centerline(self) -> np.ndarray:
        """(m, 2) midpoints between the boundaries (see ``rld.geometry.centerline``)."""
        from rld.geometry import centerline

        if not self.ok:
            return np.zeros((0, 2))
        return centerline(self.left_xy, self.right_xy, closed=self.closed)

    @property
    def polygon(self):
        """The driving lane as a shapely geometry (see ``rld.geometry.lane_polygon``)."""
        from rld.geometry import lane_polygon

        return lane_polygon(self.left_xy, self.right_xy, closed=self.closed)

    def path(self, spacing_m: float = 0.5) -> LanePath:
        """The centreline every ``spacing_m`` m with heading, curvature and widths
        (``rld.path.lane_path``); an empty ``LanePath`` when no lane was found."""
        from rld.path import LanePath, check_spacing, lane_path

        if not self.ok:
            check_spacing(spacing_m)
            return LanePath(closed=self.closed)
        return lane_path(self.left_xy, self.right_xy, self.closed, spacing_m)

    def to_dict(self) -> dict:
        """The lane as plain JSON types: cones, left, right, status (its name), message, cost
        (None for NaN), closed and stats (numpy values made plain); ``from_dict`` inverts it."""
        return {
            "cones": self.cones.tolist(), "left": self.left.tolist(),
            "right": self.right.tolist(), "status": self.status.name, "message": self.message,
            "cost": float(self.cost) if math.isfinite(self.cost) else None,
            "closed": bool(self.closed), "stats": _plain(self.stats),
        }

    @classmethod
    def from_dict(cls, d: dict) -> Lane:
        """The ``Lane`` of a ``to_dict`` result (also after a JSON round trip); ValueError for a
        missing key or an unknown status."""
        missing = [k for k in ("cones", "left", "right", "status") if k not in d]
        if missing:
            raise ValueError(f"a lane dict needs the keys {missing}")
        try:
            status = LaneStatus[d["status"]]
        except KeyError as exc:
            raise ValueError(f"unknown lane status {d['status']!r}") from exc
        cost = d.get("cost")
        return cls(
            cones=np.array(d["cones"], dtype=np.float64).reshape(-1, 2),
            left=np.array(d["left"], dtype=np.int64), right=np.array(d["right"], dtype=np.int64),
            status=status, message=str(d.get("message", "")),
            cost=math.nan if cost is None else float(cost), closed=bool(d.get("closed", False)),
            stats=dict(d.get("stats") or {}),
        )

    def to_json(self, **kwargs) -> str:
        """``json.dumps`` of ``to_dict`` (strict JSON: no NaN); keyword arguments pass on."""
        import json

        return json.dumps(self.to_dict(), allow_nan=False, **kwargs)

    def __repr__(self) -> str:
        return (
            f"Lane(status={self.status.name}, left={self.left.tolist()}, "
            f"right={self.right.tolist()}, cost={self.cost:.4g}, closed={self.closed}, "
            f"message={self.message!r})"
        )

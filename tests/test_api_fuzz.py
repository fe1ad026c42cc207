"""The public API on hostile inputs, every method: duplicated cones, cones on one line, rings,
dense clusters, lanes with false positives, poses anywhere. Every call returns a ``Lane`` (or
raises ``ValueError``), never another exception; a lane found is well formed; the lanes of the
two published methods satisfy the shared lane predicate (RLD's without C_width's upper bound,
which its cone window can break on a true lane, docs/formulation.md)."""

from __future__ import annotations

import math

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from rld import LaneParams, solve_lane
from rld.api import METHODS
from rld.constraints import lane_is_feasible
from rld.types import Lane

P = LaneParams()


@st.composite
def scenes(draw):
    """(cones (n, 2), pose (x, y, yaw)): one of several hostile layouts around the origin."""
    seed = draw(st.integers(0, 2**31 - 1))
    kind = draw(st.sampled_from(["lane", "duplicates", "line", "ring", "cluster", "scatter"]))
    rng = np.random.default_rng(seed)
    if kind in ("lane", "duplicates"):
        k = int(rng.integers(2, 9))
        xs = np.cumsum(rng.uniform(2.5, 5.0, k)) - 3.0
        width = rng.uniform(2.0, 7.0)
        pts = np.vstack([np.column_stack([xs, np.full(k, width / 2)]),
                         np.column_stack([xs + rng.normal(0, 0.5, k), np.full(k, -width / 2)])])
        pts = np.vstack([pts + rng.normal(0, 0.2, pts.shape),
                         rng.uniform([-5, -8], [30, 8], (int(rng.integers(0, 8)), 2))])
        if kind == "duplicates":
            pts = np.vstack([pts, pts[rng.integers(0, len(pts), int(rng.integers(1, 8)))]])
    elif kind == "line":
        n = int(rng.integers(4, 16))
        pts = np.column_stack([np.arange(n) * rng.uniform(0.5, 4.0), np.zeros(n)])
        pts = pts + [rng.uniform(-3, 0), 0.0]
    elif kind == "ring":
        n = int(rng.integers(6, 40))
        r = rng.uniform(3.0, 15.0)
        t = np.linspace(0, 2 * math.pi, n, endpoint=False)
        pts = np.column_stack([r * np.cos(t), r * np.sin(t) + r * rng.choice([-1, 1])])
    elif kind == "cluster":
        pts = rng.uniform(-3.0, 3.0, (int(rng.integers(4, 60)), 2))
    else:
        pts = rng.uniform(-30.0, 30.0, (int(rng.integers(4, 80)), 2))
    yaw = draw(st.sampled_from([0.0, rng.uniform(-math.pi, math.pi)]))
    return pts, (float(rng.normal(0, 0.5)), float(rng.normal(0, 0.5)), float(yaw))


@settings(max_examples=25)
@given(scenes())
def test_every_method_answers_hostile_input_with_a_lane_or_no_lane(scene):
    cones, pose = scene
    for method in METHODS:
        lane = solve_lane(cones, pose, method=method, time_limit_s=0.2)
        assert isinstance(lane, Lane), method
        assert lane.ok == (lane.left.size > 0 and lane.right.size > 0), method
        if not lane.ok:
            assert lane.message, method  # a reason, not a silent empty lane
            continue
        n = cones.shape[0]
        for side in (lane.left, lane.right):
            assert side.dtype.kind == "i" and np.all((side >= 0) & (side < n)), method
            assert np.unique(side).size == side.size, method
        assert not set(lane.left.tolist()) & set(lane.right.tolist()), method
        if method == "clc":
            assert lane_is_feasible(cones[lane.left], cones[lane.right], P, closed=lane.closed)
        if method in ("rld", "rld-sided"):
            assert lane_is_feasible(cones[lane.left], cones[lane.right], P, max_width=False)

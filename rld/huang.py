"""A fitted-centreline baseline after Huang et al. (2009), section 2.2 (``method="huang"``).

1. Centreline evidence (2.2.1): every cone is boundary evidence, like a short piece of road
   paint, so the lane centre is most likely half a lane width from it: D(p) = sum of f_rp(|p -
   c|) over the cones c (eq. 3; the paper's half width is 1.83 m, ours ``half_width_m`` =
   1.9 m), on a grid in the car frame (``rld.huang_kernels``). Where a left and a right cone
   both lie half a width away the evidence doubles, so a threshold keeps the centreline and
   drops the ridges outside the track.
2. Ridge points (2.2.2): grid points above the threshold that are local maxima along their row
   or column.
3. RANSAC parabolas (2.2.2): 200 draws of three ridge points, a parabola in the frame of their
   first principal component, inliers within ``alpha_m``, two least-squares refits, the
   largest connected set of inliers (links of ``link_m`` = 1.5 m), the score sum 1 / (1 + d).
   Deviations: d is the distance along the principal-component normal, not the algebraic
   distance of the conic; one of the three points is drawn near the car, because the lane
   wanted is the car's own (the paper keeps up to five lanes and lets its tracker choose).
4. Cones to boundaries (ours): every cone is projected onto the fitted centreline; those between
   half the minimum and half the maximum lane width to its left (right) form the left (right)
   boundary, ordered by arc length and cut at the first gap wider than the maximum spacing.

It returns the same ``Lane`` as the graph methods, so it is scored by the same protocol. A
single parabola cannot follow a hairpin: that, and the false positives that lie near the fitted
curve, are what the graph methods buy (docs/huang.md).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from rld import geometry as geo
from rld import huang_kernels as hk
from rld.tracker import project_onto
from rld.types import Lane, LaneParams, LaneStatus, Pose

__all__ = ["HuangParams", "fit_centerline", "huang_lane"]


@dataclass(frozen=True)
class HuangParams:
    """Tunables of the baseline (metres unless said)."""

    half_width_m: float = 1.9
    """Where a cone's evidence peaks (eq. 3: half a lane width; the paper's 1.83 m is half a
    3.66 m road lane, Formula Student lanes are 3-5 m wide)."""
    peak_var_m2: float = 0.5
    """Spread of that peak (eq. 3 prints 0.14 m^2 for paint lines). A cone is a point: with the
    narrow peak, the rings of staggered left and right cones meet only in isolated spots;
    0.5 m^2 lets them overlap along the centre."""
    grid_res_m: float = 0.25
    horizon_m: float = 30.0
    """The grid reaches this far ahead of and beside the car."""
    ridge_threshold: float = 0.6
    """Smoothed evidence above which a ridge point counts (measured on generated tracks: 0.6
    gave 15 % critical failures at 0 % false positives, 0.9 gave 36 %, most of them no lane)."""
    smooth_m: float = 1.0
    """Gaussian smoothing of the evidence before the ridge search (ours: cones are sparse
    points, so the centre ridge between staggered cones is continuous only after smoothing)."""
    iterations: int = 200
    alpha_m: float = 0.5
    link_m: float = 1.5
    min_inliers: int = 12
    seed: int = 0


def _fit(u: np.ndarray, v: np.ndarray) -> np.ndarray | None:
    if np.ptp(u) < 1e-6:
        return None
    deg = 2 if np.unique(np.round(u, 6)).size >= 3 else 1
    coef = np.polyfit(u, v, deg)
    return np.r_[np.zeros(3 - coef.size), coef]


def fit_centerline(ridge: np.ndarray, car_xy: np.ndarray, near_m: float,
                   hp: HuangParams) -> tuple[np.ndarray, float] | None:
    """The best RANSAC parabola through the ridge points (k, 2) with a point within ``near_m``
    of ``car_xy``: its centreline (sampled every 0.5 m over its inliers, ordered from the end
    nearer the car) and its score; None when there is none."""
    if ridge.shape[0] < max(hp.min_inliers, 3):
        return None
    rng = np.random.default_rng(hp.seed)
    near = np.flatnonzero(np.hypot(*(ridge - car_xy).T) <= near_m)
    if near.size == 0:
        return None
    best = None
    for _ in range(hp.iterations):
        i = near[rng.integers(near.size)]
        j, k = rng.choice(ridge.shape[0], size=2, replace=False)
        three = ridge[[i, j, k]]
        mean = three.mean(axis=0)
        _, _, vt = np.linalg.svd(three - mean)
        e1 = vt[0]
        e2 = np.array([-e1[1], e1[0]])
        rel = ridge - mean
        u, v = rel @ e1, rel @ e2
        coef = _fit(u[[i, j, k]], v[[i, j, k]])
        if coef is None:
            continue
        for _refit in range(2):
            d = np.abs(v - np.polyval(coef, u))
            inl = np.flatnonzero(d <= hp.alpha_m)
            if inl.size < hp.min_inliers:
                break
            coef = _fit(u[inl], v[inl])
            if coef is None:
                break
        else:
            d = np.abs(v - np.polyval(coef, u))
            inl = np.flatnonzero(d <= hp.alpha_m)
            if best is not None and inl.size <= best[0]:
                continue  # the score is at most the number of inliers: cannot win
            # The largest connected set of inliers (links of link_m), which must reach the car.
            pairs = cKDTree(ridge[inl]).query_pairs(hp.link_m, output_type="ndarray")
            g = coo_matrix((np.ones(len(pairs)), (pairs[:, 0], pairs[:, 1])),
                           shape=(inl.size, inl.size)) if len(pairs) else None
            if g is None:
                continue
            _, lab = connected_components(g, directed=False)
            sizes = np.bincount(lab)
            comp = inl[lab == np.argmax(sizes)]
            if comp.size < hp.min_inliers or not np.isin(comp, near).any():
                continue
            score = float(np.sum(1.0 / (1.0 + d[comp])))
            if best is None or score > best[0]:
                best = (score, coef, mean, e1, e2, u[comp].min(), u[comp].max())
    if best is None:
        return None
    score, coef, mean, e1, e2, u0, u1 = best
    us = np.linspace(u0, u1, max(int((u1 - u0) / 0.5), 2) + 1)
    line = mean + np.outer(us, e1) + np.outer(np.polyval(coef, us), e2)
    if np.hypot(*(line[-1] - car_xy)) < np.hypot(*(line[0] - car_xy)):
        line = line[::-1]
    return line, score


def cones_beside(points: np.ndarray, line: np.ndarray,
                 params: LaneParams) -> tuple[np.ndarray, np.ndarray]:
    """Step 4 of the module docstring: the cones (indices into ``points``, metres) between
    half the minimum and half the maximum lane width to the left and to the right of the
    centreline ``line`` (m, 2), from at most 1 m before its start to at most 1 m past its end
    (measured along its end segments, so a cone beyond an end does not join a side by its
    distance to the end point), ordered along the line and cut at the first gap wider than
    ``max_cone_spacing_m``."""
    q, dist, arc = project_onto(points, line)
    # Signed side: the cross product of the centreline's direction with the cone's offset.
    seg = np.searchsorted(geo.cumulative_length(line), arc, side="right").clip(1, len(line) - 1)
    tang = line[seg] - line[seg - 1]
    off = points - q
    side = np.sign(tang[:, 0] * off[:, 1] - tang[:, 1] * off[:, 0])
    length = geo.polyline_length(line)
    along = arc.copy()
    t0 = (line[1] - line[0]) / max(float(np.hypot(*(line[1] - line[0]))), 1e-12)
    t1 = (line[-1] - line[-2]) / max(float(np.hypot(*(line[-1] - line[-2]))), 1e-12)
    first, last = arc <= 1e-9, arc >= length - 1e-9
    along[first] = np.minimum((points[first] - line[0]) @ t0, 0.0)
    along[last] = length + np.maximum((points[last] - line[-1]) @ t1, 0.0)
    ok_s = (along >= -1.0) & (along <= length + 1.0)
    band = (dist >= params.min_width_m / 2) & (dist <= params.max_width_m / 2)
    sides = []
    for sgn in (1.0, -1.0):
        idx = np.flatnonzero(ok_s & band & (side == sgn))
        idx = idx[np.argsort(arc[idx], kind="stable")]
        keep = [int(idx[0])] if idx.size else []
        for k in idx[1:]:
            if np.hypot(*(points[k] - points[keep[-1]])) > params.max_cone_spacing_m:
                break
            keep.append(int(k))
        sides.append(np.array(keep, dtype=np.int64))
    return sides[0], sides[1]


def huang_lane(points: np.ndarray, pose: Pose, params: LaneParams,
               hp: HuangParams | None = None) -> Lane:
    """The baseline's lane in ``points`` (N, 2, validated) for the car at ``pose``."""
    hp = hp or HuangParams()
    local = pose.to_local(points)
    H = hp.horizon_m
    use = (local[:, 0] >= -4.0) & (local[:, 0] <= H + 4.0) & (np.abs(local[:, 1]) <= H + 4.0)
    res = hp.grid_res_m
    x0, y0 = -2.0, -H
    nx, ny = int((H - x0) / res) + 1, int(2 * H / res) + 1
    D = hk.evidence_grid(np.ascontiguousarray(local[use]), x0, y0, res, nx, ny,
                         hp.half_width_m, hp.half_width_m + 2.5, hp.peak_var_m2)
    if hp.smooth_m > 0:
        from scipy.ndimage import gaussian_filter

        D = gaussian_filter(D, hp.smooth_m / res, mode="constant")
    ii, jj = np.nonzero(hk.ridge_mask(D, hp.ridge_threshold))
    ridge_local = np.column_stack([x0 + ii * res, y0 + jj * res])
    stats = {"ridge_points": int(ii.size)}
    fit = fit_centerline(ridge_local, np.zeros(2), params.near_radius_m, hp)
    if fit is None:
        return Lane.not_found(points, "no centreline parabola through the cone evidence near "
                              "the car", stats=stats)
    line_local, score = fit
    stats["parabola_score"] = score
    # Keep the centreline from beside the car forward.
    line_local = line_local[line_local[:, 0] >= -1.0]
    if line_local.shape[0] < 2:
        return Lane.not_found(points, "the fitted centreline does not lead ahead", stats=stats)
    c, s = np.cos(pose.yaw), np.sin(pose.yaw)
    line = pose.xy + line_local @ np.array([[c, s], [-s, c]])
    left, right = cones_beside(points, line, params)
    if left.size < 2 or right.size < 2:
        return Lane.not_found(points, "fewer than two cones beside the fitted centreline on a "
                              "side", stats=stats)
    return Lane(cones=points, left=left, right=right, status=LaneStatus.FEASIBLE,
                message="fitted baseline (Huang et al. 2009): no optimality claim",
                stats=stats)

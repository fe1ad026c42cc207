"""Numba kernels of the Huang et al. baseline (``rld.huang``): the centreline evidence grid."""

from __future__ import annotations

import math

import numpy as np

from rld._jit import njit

__all__ = ["evidence_grid", "ridge_mask"]


@njit(cache=True)
def evidence_grid(cones: np.ndarray, x0: float, y0: float, res: float, nx: int, ny: int,
                  half_width: float, cutoff: float, peak_var: float = 0.14) -> np.ndarray:
    """Centreline evidence D (Huang et al. section 2.2.1, eq. 3 with cones as point detections
    of lane-boundary paint): D(p) = sum over cones c of f(|p - c|), f(x) = -exp(-x^2 / 0.42) +
    exp(-(x - h)^2 / v), h = ``half_width`` (m), v = ``peak_var``
    (m^2; the paper's 0.14 for a paint line). Pixel (i, j) is the point (x0 + i res,
    y0 + j res) of the car frame; cones farther than ``cutoff`` from a pixel add nothing (f is
    below 1e-6 there). Returns (nx, ny) float64."""
    D = np.zeros((nx, ny))
    reach = int(math.ceil(cutoff / res))
    for k in range(cones.shape[0]):
        cx, cy = cones[k, 0], cones[k, 1]
        ci = int(round((cx - x0) / res))
        cj = int(round((cy - y0) / res))
        for i in range(max(ci - reach, 0), min(ci + reach + 1, nx)):
            px = x0 + i * res
            for j in range(max(cj - reach, 0), min(cj + reach + 1, ny)):
                py = y0 + j * res
                d = math.sqrt((px - cx) ** 2 + (py - cy) ** 2)
                if d <= cutoff:
                    peak = math.exp(-(d - half_width) ** 2 / peak_var)
                    D[i, j] += -math.exp(-d * d / 0.42) + peak
    return D


@njit(cache=True)
def ridge_mask(D: np.ndarray, threshold: float) -> np.ndarray:
    """Ridge points (section 2.2.2): pixels above ``threshold`` that are a local maximum along
    their row or their column (not below either neighbour)."""
    nx, ny = D.shape
    out = np.zeros((nx, ny), dtype=np.bool_)
    for i in range(nx):
        for j in range(ny):
            v = D[i, j]
            if v <= threshold:
                continue
            row = (j == 0 or v >= D[i, j - 1]) and (j == ny - 1 or v >= D[i, j + 1])
            col = (i == 0 or v >= D[i - 1, j]) and (i == nx - 1 or v >= D[i + 1, j])
            out[i, j] = row or col
    return out

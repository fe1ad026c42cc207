"""One plotting function for every picture of a scene: cones, false positives, the ground
truth and a lane. Used by the CLI, the notebooks and failure reports."""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["plot_scene"]


def plot_scene(
    cones: np.ndarray,
    lane: Any = None,
    pose: Any = None,
    gt_left: np.ndarray | None = None,
    gt_right: np.ndarray | None = None,
    false_positive: np.ndarray | None = None,
    title: str | None = None,
    ax: Any = None,
    path: str | None = None,
):
    """Draw a scene and return the matplotlib ``Axes``.

    ``cones`` (N, 2) metres; ``lane`` a ``Lane`` (its polygon shaded, boundaries blue/yellow as
    on a Formula Student track); ``pose`` a ``Pose`` (an arrow); ``gt_left``/``gt_right`` index
    arrays of the true lane (dashed); ``false_positive`` a boolean mask (crosses). With ``path``
    the figure is saved there (PNG at 120 dpi) and closed.
    """
    import matplotlib

    if path is not None and ax is None:
        matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    cones = np.asarray(cones, dtype=np.float64)
    if ax is None:
        _, ax = plt.subplots(figsize=(8, 8))
    fp = np.zeros(cones.shape[0], bool) if false_positive is None else np.asarray(false_positive)
    ax.scatter(cones[~fp, 0], cones[~fp, 1], s=14, c="0.35", zorder=3, label="cones")
    if fp.any():
        ax.scatter(cones[fp, 0], cones[fp, 1], s=22, c="tab:red", marker="x", zorder=3,
                   label="false positives")
    for idx, style in ((gt_left, "ground truth"), (gt_right, None)):
        if idx is not None and len(idx) > 1:
            xy = cones[np.asarray(idx)]
            ax.plot(xy[:, 0], xy[:, 1], "--", c="k", lw=1.0, zorder=6, label=style)
    if lane is not None and getattr(lane, "ok", False):
        poly = lane.polygon
        for g in getattr(poly, "geoms", [poly]):
            if not g.is_empty and g.geom_type == "Polygon":
                x, y = g.exterior.xy
                ax.fill(x, y, color="tab:green", alpha=0.18, lw=0, zorder=1)
        for xy, color, name in ((lane.left_xy, "tab:blue", "left"),
                                (lane.right_xy, "gold", "right")):
            if lane.closed and len(xy) > 2:
                xy = np.vstack([xy, xy[:1]])
            ax.plot(xy[:, 0], xy[:, 1], "-o", c=color, ms=5, lw=2, zorder=4, label=f"{name}")
    if pose is not None:
        h = pose.heading * 3.0
        ax.arrow(pose.x, pose.y, h[0], h[1], width=0.35, color="k", zorder=5,
                 length_includes_head=True)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    if title:
        ax.set_title(title)
    ax.legend(loc="best", fontsize=8)
    if path is not None:
        fig = ax.figure
        fig.tight_layout()
        fig.savefig(path, dpi=120)
        plt.close(fig)
    return ax

"""``rld replay --plot``: a lap overview of a replay. Left, the map: the last solved map's cones
by colour class, the car's path, every lane found (its centreline, thin), the last lane found
(its boundaries), and where maps were skipped or held no lane. Right, over the drive's log
time: each lane's length (the mean of its two boundaries) and each map's latency, whole and
the solver's alone."""

from __future__ import annotations

import numpy as np

__all__ = ["plot_replay"]

_CLASS_COLOURS = {"blue": "tab:blue", "yellow": "gold", "orange": "darkorange",
                  "big_orange": "orangered", "unknown": "0.55"}


def _length(lane) -> float:
    from rld import geometry as geo

    return 0.5 * (geo.polyline_length(lane.left_xy, lane.closed)
                  + geo.polyline_length(lane.right_xy, lane.closed))


def plot_replay(result, path: str, title: str | None = None) -> None:
    """Draw ``result`` (a ``rld.ros.replay.ReplayResult``) to ``path`` (PNG, or another
    format by suffix)."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    frames = result.frames
    solved = [f for f in frames if f.lane is not None]
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(12, 5.4),
                                 gridspec_kw={"width_ratios": [1.25, 1]})
    cones = result.last_cones
    if cones is not None:
        for cls, colour in _CLASS_COLOURS.items():
            xy = cones.xy[cones.classes == cls]
            if xy.size:
                ax.scatter(xy[:, 0], xy[:, 1], s=8, c=colour, zorder=3,
                           label=f"{cls.replace('_', ' ')} cones")
    poses = np.array([(f.pose.x, f.pose.y) for f in frames if f.pose is not None]).reshape(-1, 2)
    if poses.size:
        ax.plot(poses[:, 0], poses[:, 1], "--", c="k", lw=0.6, zorder=5, label="car")
    first = True
    for f in solved:
        if f.lane.ok:
            c = f.lane.centerline
            ax.plot(c[:, 0], c[:, 1], "-", c="tab:green", lw=2.5, alpha=0.15, zorder=1,
                    label="lanes found (centrelines)" if first else None)
            first = False
    last = next((f.lane for f in reversed(solved) if f.lane.ok), None)
    if last is not None:
        for xy, colour, name in ((last.left_xy, "tab:blue", "last lane"),
                                 (last.right_xy, "goldenrod", None)):
            if last.closed and len(xy) > 2:
                xy = np.vstack([xy, xy[:1]])
            ax.plot(xy[:, 0], xy[:, 1], "-", c=colour, lw=1.6, zorder=4, label=name)
    bad = [(f, "not found") for f in solved if not f.lane.ok] + [
        (f, "skipped") for f in frames if f.skipped]
    for kind, marker in (("not found", "o"), ("skipped", "x")):
        pts = np.array([(f.pose.x, f.pose.y) for f, k in bad if k == kind and f.pose is not None])
        if pts.size:
            ax.scatter(pts[:, 0], pts[:, 1], s=45, marker=marker, zorder=5, linewidths=1.5,
                       facecolors="none" if marker == "o" else "tab:red", edgecolors="tab:red",
                       label="no lane found" if kind == "not found" else "map skipped")
    ax.set_aspect("equal")
    ax.set_xlabel("x (m)")
    ax.set_ylabel("y (m)")
    ax.legend(loc="best", fontsize=7)

    t0 = frames[0].log_time_ns if frames else 0
    t = np.array([(f.log_time_ns - t0) / 1e9 for f in solved])
    if solved:
        length = np.array([_length(f.lane) if f.lane.ok else 0.0 for f in solved])
        ok = np.array([f.lane.ok for f in solved])
        bx.plot(t, length, "-", c="tab:green", lw=1.2, label="lane length (m)")
        if (~ok).any():
            bx.scatter(t[~ok], length[~ok], marker="o", facecolors="none",
                       edgecolors="tab:red", s=30, zorder=3, label="no lane found")
    skipped = np.array([(f.log_time_ns - t0) / 1e9 for f in frames if f.skipped])
    if skipped.size:
        bx.scatter(skipped, np.zeros_like(skipped), marker="x", c="tab:red", s=30, zorder=3,
                   label="map skipped")
    bx.set_ylim(bottom=0)
    bx.set_xlabel("log time (s)")
    bx.set_ylabel("lane length (m)")
    cx = bx.twinx()
    lat = 1000.0 * np.array(result.stats.latencies_s)
    if lat.size == t.size and lat.size:
        cx.plot(t, lat, "-", c="0.45", lw=0.8, label="latency (ms)")
        cx.plot(t, 1000.0 * np.array(result.stats.solve_s), ":", c="0.2", lw=0.8,
                label="the solver alone (ms)")
        top = 2.0 * float(np.percentile(lat, 95))
        cx.set_ylim(0, max(top, 1.0))  # the first call's start-up may stay off the scale
    cx.set_ylabel("latency (ms)")
    handles = bx.get_legend_handles_labels()
    more = cx.get_legend_handles_labels()
    bx.legend(handles[0] + more[0], handles[1] + more[1], loc="upper left", fontsize=7)
    s = result.stats
    fig.suptitle(title or f"replay: {s.maps} maps, {s.found} lanes found, "
                          f"{sum(s.not_found.values())} not found, "
                          f"{sum(s.skipped.values())} skipped", fontsize=10)
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)

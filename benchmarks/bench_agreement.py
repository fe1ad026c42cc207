"""Where RLD and CLC still differ on clean tracks (issue 40, item 4): the poses of
tests/test_agreement.py (R = 50 m, 0 %, four generated tracks every 10th pose, the six shared
tracks every 20th, ``solve_lane`` at its defaults with a 3 s budget) whose lanes are not
identical (``rld.metrics.lanes_identical``), each drawn around its first difference.

    python -m benchmarks.bench_agreement --out docs/agreement.png

prints one row per disagreement (the pose, each lane's index-rule category, closed or open,
the side and the cone number where the two first differ, and its distance from the car) and
the counts; ``--out`` draws them all in one figure.
"""

from __future__ import annotations

import argparse

import numpy as np


def _first_difference(a, b, pose, closed: bool):
    """(side, index, point) where two lanes' sides first differ from the car forward (a closed
    side: its first cone not shared as an edge), or None when they are identical."""
    from rld.metrics import _edge_set, lanes_identical

    if lanes_identical(a, b, pose):
        return None
    for name, x, y in (("left", a.left, b.left), ("right", a.right, b.right)):
        x, y = np.asarray(x), np.asarray(y)
        if closed or a.closed != b.closed:
            diff = sorted(_edge_set(x) ^ _edge_set(y))
            if diff:
                c = diff[0][0]
                return name, int(np.flatnonzero(x == c)[0]) if c in x else -1, a.cones[c]
            continue
        m = min(x.size, y.size)
        k = next((j for j in range(m) if x[j] != y[j]), m)
        if k < max(x.size, y.size):
            c = x[k] if k < x.size else y[k]
            return name, int(k), a.cones[c]
    return "both", -1, a.cones[a.left[0]] if a.ok else np.zeros(2)


def run() -> list[dict]:
    """One record per disagreement, with the frame and both lanes for drawing."""
    from rld.api import solve_lane
    from rld.generator import generate_track
    from rld.metrics import score_lane
    from rld.simulation import simulate_lap
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    sets = [([generate_track(100 + s) for s in range(4)], 10),
            ([load_dataset_track(find_dataset_dir(), k) for k in DATASET_TRACKS], 20)]
    out = []
    for tracks, every in sets:
        for track in tracks:
            lap = simulate_lap(track, range_m=50.0, fp_rate=0.0, seed=0)
            for k in range(0, len(lap), every):
                f = lap.frame(k)
                r = solve_lane(f.cones, f.pose, method="rld", time_limit_s=3.0)
                c = solve_lane(f.cones, f.pose, method="clc", time_limit_s=3.0)
                diff = _first_difference(r, c, f.pose, bool(r.closed and c.closed))
                if diff is None:
                    out.append(dict(track=track.name, pose=k, same=True))
                    continue
                side, idx, xy = diff
                cats = [score_lane(f, x.left, x.right, x.ok, x.closed).category for x in (r, c)]
                out.append(dict(track=track.name, pose=k, same=False, side=side, index=idx,
                                xy=np.asarray(xy, dtype=float),
                                distance_m=float(np.hypot(*(np.asarray(xy) - f.pose.xy))),
                                rld=cats[0], clc=cats[1], rld_closed=bool(r.closed),
                                clc_closed=bool(c.closed), frame=f, lanes=(r, c)))
    return out


def table(records: list[dict]) -> str:
    gen = [r for r in records if r["track"].startswith("generated")]
    shared = [r for r in records if not r["track"].startswith("generated")]
    lines = [f"identical: {sum(r['same'] for r in gen)} of {len(gen)} (generated), "
             f"{sum(r['same'] for r in shared)} of {len(shared)} (shared)", "",
             "| pose | rld | clc | closed (rld / clc) | first difference | from the car (m) |",
             "|---|---|---|---|---|---|"]
    for r in records:
        if r["same"]:
            continue
        lines.append(f"| {r['track']} pose {r['pose']} | {r['rld']} | {r['clc']} | "
                     f"{'yes' if r['rld_closed'] else 'no'} / {'yes' if r['clc_closed'] else 'no'}"
                     f" | {r['side']} cone {r['index']} | {r['distance_m']:.1f} |")
    return "\n".join(lines)


def plot(records: list[dict], path: str) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    bad = [r for r in records if not r["same"]]
    if not bad:
        return
    cols = 5
    rows = (len(bad) + cols - 1) // cols
    fig, axes = plt.subplots(rows, cols, figsize=(3.2 * cols, 3.2 * rows), squeeze=False)
    for ax in axes.ravel():
        ax.set_axis_off()
    for ax, r in zip(axes.ravel(), bad, strict=False):
        f, (a, b) = r["frame"], r["lanes"]
        ax.set_axis_on()
        ax.scatter(f.cones[:, 0], f.cones[:, 1], s=6, c="0.5")
        for lane, style, label in ((a, "-", "rld"), (b, "--", "clc")):
            if not lane.ok:
                continue
            for side, color in ((lane.left, "tab:blue"), (lane.right, "tab:orange")):
                s = np.r_[side, side[:1]] if lane.closed else side
                ax.plot(f.cones[s, 0], f.cones[s, 1], style, color=color, lw=1.2 if
                        label == "rld" else 2.0, alpha=0.9 if label == "rld" else 0.6)
        x, y = r["xy"]
        ax.scatter([x], [y], s=80, facecolors="none", edgecolors="red")
        ax.arrow(*f.pose.xy, *(2.0 * f.pose.heading), width=0.4, color="green")
        ax.set_xlim(x - 12, x + 12)
        ax.set_ylim(y - 12, y + 12)
        ax.set_aspect("equal")
        ax.set_xticks([])
        ax.set_yticks([])
        ax.set_title(f"{r['track']} p{r['pose']}: {r['rld']} / {r['clc']}", fontsize=8)
    fig.suptitle("RLD (solid) and CLC (dashed) where they differ; red: the first difference",
                 fontsize=10)
    fig.tight_layout(rect=(0, 0, 1, 0.98))
    fig.savefig(path, dpi=70)
    plt.close(fig)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--out", default="", help="draw the disagreements into this PNG")
    a = ap.parse_args()
    recs = run()
    print(table(recs))
    if a.out:
        plot(recs, a.out)


if __name__ == "__main__":
    main()

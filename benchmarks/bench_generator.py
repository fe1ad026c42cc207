"""Do the generated tracks resemble the shared ones? (``rld bench generator``, issue 39).

Four distributions, measured alike on the six shared dataset tracks and on a set of generated
tracks (``rld.generator.generated_set``), pooled over the tracks and both boundaries:

- **cone spacing**: the distance between consecutive cones of one boundary (around the loop),
  metres;
- **lane width**: the distance from each boundary cone to the other boundary's polyline
  (``geometry.boundary_line``, ``geometry.point_polyline_distance``), metres;
- **turn angle per cone**: the absolute turn at each boundary cone between its two segments
  (``geometry.polyline_turn_angles``), radians;
- **position noise**: each cone's distance from a smooth curve through its neighbours: the
  least-squares quadratic ``x(s), y(s)`` in arc length ``s`` through the ``NOISE_NEIGHBOURS``
  cones either side of it (the cone itself left out), sampled densely between its two
  neighbours; metres. A generated cone's Gaussian noise and a real cone's survey jitter are
  measured by the same rule (neither track knows its own noise-free positions).

The two-sample Kolmogorov-Smirnov statistic (``scipy.stats.ks_2samp``) compares each pair;
issue 39 asks for at most ``KS_TARGET`` on each. ``clc_rates`` measures, besides, that the
generated tracks are not easier: CLC's geometric critical rates on them against the shared
tracks'.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from rld import geometry as geo

#: The distributions, in table order: key, label, unit.
DISTRIBUTIONS = (
    ("spacing", "cone spacing", "m"),
    ("width", "lane width", "m"),
    ("turn", "turn angle per cone", "rad"),
    ("noise", "position noise", "m"),
)
#: Issue 39's bound on each two-sample KS statistic.
KS_TARGET = 0.15
#: Cones either side of a cone in its smooth curve (``position_noise``).
NOISE_NEIGHBOURS = 2
QUANTILES = (5, 50, 95)


def _ring(xy: np.ndarray) -> np.ndarray:
    xy = np.asarray(xy, dtype=np.float64).reshape(-1, 2)
    if xy.shape[0] < 3:
        raise ValueError(f"a closed boundary needs at least 3 cones, got {xy.shape[0]}")
    return xy


def cone_spacing(xy: np.ndarray) -> np.ndarray:
    """(k,) distance from each cone of the closed boundary ``xy`` (k, 2) to the next, metres
    (the last to the first)."""
    xy = _ring(xy)
    return np.hypot(*np.diff(np.vstack([xy, xy[:1]]), axis=0).T)


def lane_width(xy: np.ndarray, other: np.ndarray) -> np.ndarray:
    """(k,) distance from each cone of the closed boundary ``xy`` to the polyline of the closed
    boundary ``other``, metres."""
    return geo.point_polyline_distance(_ring(xy), geo.boundary_line(_ring(other), True))


def turn_per_cone(xy: np.ndarray) -> np.ndarray:
    """(k,) absolute turn at each cone of the closed boundary ``xy``, radians."""
    return np.abs(geo.polyline_turn_angles(_ring(xy), closed=True))


def position_noise(xy: np.ndarray, neighbours: int = NOISE_NEIGHBOURS) -> np.ndarray:
    """(k,) distance from each cone of the closed boundary ``xy`` to the smooth curve through
    its ``neighbours`` cones either side (itself left out): least-squares quadratics ``x(s)``
    and ``y(s)`` in the arc length ``s`` along the cones, sampled every 1/50 of the way between
    its two neighbours; metres. Cones on a line measure 0, on a circle nearly (2 mm for 40
    cones on a 20 m circle: a quadratic in arc length is not quite a circle). On a
    straight boundary with isotropic Gaussian noise of standard deviation sigma its median is
    about 0.94 sigma (the leave-one-out residual across the line: sigma times sqrt(1 + 17/18)).
    """
    xy = _ring(xy)
    k = xy.shape[0]
    if k < 2 * neighbours + 1:
        raise ValueError(f"position_noise needs at least {2 * neighbours + 1} cones, got {k}")
    gap = cone_spacing(xy)
    s_ring = np.concatenate([[0.0], np.cumsum(gap)])  # arc length of cone i at s_ring[i]
    total = s_ring[-1]
    offsets = np.array([o for o in range(-neighbours, neighbours + 1) if o != 0])
    u = np.linspace(-1.0, 1.0, 101)
    out = np.empty(k)
    for i in range(k):
        idx = (i + offsets) % k
        s = s_ring[idx] + total * np.floor_divide(i + offsets, k) - s_ring[i]
        A = np.column_stack([np.ones_like(s), s, s * s])
        coef, *_ = np.linalg.lstsq(A, xy[idx], rcond=None)
        s0, s1 = s[neighbours - 1], s[neighbours]  # the neighbours just before and after
        t = np.where(u < 0, -u * s0, u * s1)
        curve = np.column_stack([np.ones_like(t), t, t * t]) @ coef
        out[i] = float(np.min(np.hypot(*(curve - xy[i]).T)))
    return out


def track_distributions(track) -> dict[str, np.ndarray]:
    """The four distributions of one closed track, both boundaries pooled (module docstring)."""
    left, right = track.left_xy, track.right_xy
    return {
        "spacing": np.concatenate([cone_spacing(left), cone_spacing(right)]),
        "width": np.concatenate([lane_width(left, right), lane_width(right, left)]),
        "turn": np.concatenate([turn_per_cone(left), turn_per_cone(right)]),
        "noise": np.concatenate([position_noise(left), position_noise(right)]),
    }


def pooled(tracks: Sequence) -> dict[str, np.ndarray]:
    """``track_distributions`` pooled over ``tracks``."""
    per = [track_distributions(t) for t in tracks]
    return {key: np.concatenate([p[key] for p in per]) for key, _, _ in DISTRIBUTIONS}


def ks_statistics(a: dict[str, np.ndarray], b: dict[str, np.ndarray]) -> dict[str, float]:
    """The two-sample KS statistic of each distribution of ``a`` against ``b``."""
    from scipy.stats import ks_2samp

    return {key: float(ks_2samp(a[key], b[key]).statistic) for key, _, _ in DISTRIBUTIONS}


def shared_tracks() -> list:
    """The six shared dataset tracks; ``FileNotFoundError`` without the dataset."""
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    folder = find_dataset_dir()
    if folder is None:
        raise FileNotFoundError("racetrack dataset not found (set RLD_DATASET_DIR or put it in "
                                "../shared/data/fsd_racetrack_dataset)")
    return [load_dataset_track(folder, k) for k in DATASET_TRACKS]


def run(sets: Sequence[str] = ("choosing", "reporting")) -> dict:
    """The distributions of the shared tracks and of each generated set named in ``sets``
    (``rld.generator.generated_set``), and each set's KS statistics against the shared ones."""
    from rld.generator import generated_set

    shared = pooled(shared_tracks())
    out = {"shared": shared, "sets": {}}
    for name in sets:
        dist = pooled(generated_set(name))
        out["sets"][name] = {"dist": dist, "ks": ks_statistics(shared, dist)}
    return out


def spread(first_seed: int = 4000, blocks: int = 8, size: int = 32,
           shared: dict[str, np.ndarray] | None = None) -> dict[str, list[float]]:
    """The KS statistics of ``blocks`` further sets of ``size`` generated tracks (seeds from
    ``first_seed`` on, in blocks), each against the shared tracks: how much a set's figure
    owes to its luck. The default seeds 4000-4255 overlap neither fixed set."""
    from rld.generator import generate_track

    shared = pooled(shared_tracks()) if shared is None else shared
    out: dict[str, list[float]] = {key: [] for key, _, _ in DISTRIBUTIONS}
    for b in range(blocks):
        seeds = range(first_seed + b * size, first_seed + (b + 1) * size)
        ks = ks_statistics(shared, pooled([generate_track(s) for s in seeds]))
        for key in out:
            out[key].append(ks[key])
    return out


def spread_markdown(result: dict[str, list[float]], first_seed: int, size: int) -> str:
    """One row per distribution: the least, median and largest KS statistic of the blocks."""
    blocks = len(next(iter(result.values())))
    lines = [f"| distribution | KS over {blocks} sets of {size} (seeds {first_seed}-"
             f"{first_seed + blocks * size - 1}): least / median / largest |", "|---|---|"]
    for key, label, _ in DISTRIBUTIONS:
        v = np.array(result[key])
        lines.append(f"| {label} | {v.min():.3f} / {np.median(v):.3f} / {v.max():.3f} |")
    return "\n".join(lines)


def _q(values: np.ndarray) -> str:
    return " / ".join(f"{v:.2f}" for v in np.percentile(values, QUANTILES))


def to_markdown(result: dict) -> str:
    """One row per distribution: its 5 / 50 / 95 % quantiles on the shared tracks and on each
    generated set, and each set's KS statistic (flagged when above ``KS_TARGET``)."""
    shared, sets = result["shared"], result["sets"]
    head = ["distribution", "shared (6 tracks)"]
    for name in sets:
        head += [f"{name} set", f"KS, {name}"]
    lines = ["| " + " | ".join(head) + " |", "|" + "---|" * len(head)]
    for key, label, unit in DISTRIBUTIONS:
        row = [f"{label} ({unit}), q5 / q50 / q95", _q(shared[key])]
        for s in sets.values():
            ks = s["ks"][key]
            row += [_q(s["dist"][key]), f"{ks:.3f}" + ("" if ks <= KS_TARGET else " **> 0.15**")]
        lines.append("| " + " | ".join(row) + " |")
    counts = ", ".join(f"{name} {s['dist']['spacing'].size}" for name, s in sets.items())
    lines.append("")
    lines.append(f"Cones (each distribution has one value a boundary cone): shared "
                 f"{shared['spacing'].size}, {counts}. KS target: at most {KS_TARGET}.")
    return "\n".join(lines)


def plot(result: dict, path: str) -> None:
    """A 2 x 2 picture of the empirical CDFs, shared tracks against each generated set, each
    panel titled with its KS statistics; written to ``path``."""
    import matplotlib

    matplotlib.use("Agg", force=False)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(2, 2, figsize=(7.5, 5.6))
    styles = {"choosing": "--", "reporting": ":"}
    for ax, (key, label, unit) in zip(axes.ravel(), DISTRIBUTIONS, strict=True):
        series = [("shared", result["shared"][key], "-", "k")]
        series += [(f"{name} set", s["dist"][key], styles.get(name, "-."), None)
                   for name, s in result["sets"].items()]
        for name, values, ls, color in series:
            v = np.sort(values)
            ax.step(v, np.arange(1, v.size + 1) / v.size, where="post", ls=ls, color=color,
                    label=name, lw=1.3)
        hi = max(np.percentile(v, 99.5) for _, v, _, _ in series)
        lo = min(np.percentile(v, 0.5) for _, v, _, _ in series)
        ax.set_xlim(lo - 0.05 * (hi - lo), hi + 0.05 * (hi - lo))
        ks = ", ".join(f"{name} {s['ks'][key]:.2f}" for name, s in result["sets"].items())
        ax.set_title(f"{label} (KS {ks})", fontsize=9)
        ax.set_xlabel(unit, fontsize=8)
        ax.tick_params(labelsize=8)
        ax.grid(alpha=0.3)
    axes[0, 0].legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(path, dpi=80)
    plt.close(fig)


def clc_rates(tracks: Sequence, range_m: float = 30.0, fp_rates: Sequence[float] = (0.0, 0.3),
              every: int = 4, seed: int = 0) -> dict[float, dict]:
    """CLC's geometric critical rates (%, ``geo_critical_1m`` and ``geo_critical_0.5m``) on
    ``tracks`` under the protocol (``run_protocol``, a fresh solver per pose, every
    ``every``-th pose, false-positive seed ``seed``), per false-positive rate."""
    from rld.evaluation import run_protocol, summarize

    out = {}
    for fp in fp_rates:
        s = summarize(run_protocol(list(tracks), method="clc", range_m=range_m, fp_rate=fp,
                                   every=every, seed=seed))
        out[fp] = {"poses": s["poses"], "geo_critical_1m": s["geo_critical_1m"],
                   "geo_critical_0.5m": s["geo_critical_0.5m"]}
    return out


def clc_markdown(shared: dict[float, dict], generated: dict[float, dict], range_m: float,
                 name: str = "choosing") -> str:
    """CLC's geometric critical rates on the shared tracks and on the generated set, side by
    side, per false-positive rate, and whether the generated ones are at least the shared."""
    lines = [f"| R = {range_m:g} m, false positives | poses shared / {name} | "
             f"critical > 1 m, shared | {name} | critical > 0.5 m, shared | {name} | "
             "generated at least shared |",
             "|---|---|---|---|---|---|---|"]
    for fp in shared:
        a, b = shared[fp], generated[fp]
        harder = (b["geo_critical_1m"] >= a["geo_critical_1m"]
                  and b["geo_critical_0.5m"] >= a["geo_critical_0.5m"])
        lines.append(f"| {fp:.0%} | {a['poses']} / {b['poses']} | {a['geo_critical_1m']:.2f} % "
                     f"| {b['geo_critical_1m']:.2f} % | {a['geo_critical_0.5m']:.2f} % | "
                     f"{b['geo_critical_0.5m']:.2f} % | {'yes' if harder else 'no'} |")
    return "\n".join(lines)

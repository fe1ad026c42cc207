"""The ``rld`` command line: ``rld demo``, ``rld solve``, ``rld warmup``, ``rld eval``,
``rld replay``, ``rld bench ...``.

A user error (a value out of range, a file that cannot be read or written, a map not in its
format, input the library refuses) ends the command with one line naming the problem and exit
code 2, click's code for usage errors: click's own usage format for an option's value, and
``Error: ...`` for the rest (``UserError``). Exit code 1 is kept for ``rld solve`` finding no
lane in a valid map.
"""

from __future__ import annotations

import math
import os
import sys
import time
from pathlib import Path

import click

from rld.api import DEFAULT_METHOD, METHODS, LaneSolver, solve_lane
from rld.types import Pose


class UserError(click.ClickException):
    """A user error that is not about one option's value: ``Error: MESSAGE`` on one line (the
    message's own line breaks are folded), exit code 2."""

    exit_code = 2

    def __init__(self, message: str) -> None:
        super().__init__(" ".join(str(message).split()))


def _os_error(exc: OSError) -> str:
    """``PATH: reason`` for a file that could not be read or written."""
    if exc.filename is not None and exc.strerror:
        return f"{exc.filename}: {exc.strerror.lower()}"
    return str(exc)


# --- option types and checks -------------------------------------------------------------


class _Numbers(click.ParamType):
    """A comma-separated list of numbers (``"0,0.1,0.3"``), each checked against a range;
    converts to a list. Empty items are skipped; ``empty`` allows a list with none. ``what``
    names the items in the messages."""

    name = "list"

    def __init__(self, kind: type = float, low: float | None = None, high: float | None = None,
                 low_open: bool = False, high_open: bool = False, empty: bool = False,
                 what: str = "values") -> None:
        self.kind, self.low, self.high = kind, low, high
        self.low_open, self.high_open, self.empty = low_open, high_open, empty
        self.what = what

    def _bounds(self) -> str:
        """The range as click writes its own: ``x>=0``, ``x>0``, ``0<=x<1``."""
        lo = "<" if self.low_open else "<="
        hi = "<" if self.high_open else "<="
        if self.high is None:
            return f"x{lo.replace('<', '>')}{self.low:g}"
        if self.low is None:
            return f"x{hi}{self.high:g}"
        return f"{self.low:g}{lo}x{hi}{self.high:g}"

    def convert(self, value, param, ctx):
        if isinstance(value, (list, tuple)):
            return list(value)
        kinds = "integers" if self.kind is int else "numbers"
        out = []
        for item in (v.strip() for v in str(value).split(",")):
            if not item:
                continue
            try:
                x = self.kind(item)
            except ValueError:
                self.fail(f"{self.what} are {kinds}, comma-separated, got {value!r} ({item!r} "
                          "is not one)", param, ctx)
            if not math.isfinite(x):
                self.fail(f"{self.what} are finite {kinds}, got {value!r}", param, ctx)
            if (
                self.low is not None and (x < self.low or (self.low_open and x == self.low))
            ) or (
                self.high is not None and (x > self.high or (self.high_open and x == self.high))
            ):
                self.fail(f"{item} is not in the range {self._bounds()} (in {value!r})",
                          param, ctx)
            out.append(x)
        if not out and not self.empty:
            self.fail(f"expected comma-separated {self.what}, got {value!r}", param, ctx)
        return out


#: Rates of false positives: the share of the map's cones that are false (rld.simulation).
_RATES = _Numbers(float, 0.0, 1.0, high_open=True, what="rates")
#: Perception ranges, metres.
_RANGES = _Numbers(float, 0.0, low_open=True, what="ranges")
#: Time budgets, seconds.
_BUDGETS = _Numbers(float, 0.0, low_open=True, what="budgets")
#: Seeds (numpy's generators take integers >= 0).
_SEEDS = _Numbers(int, 0, what="seeds")
#: Track numbers of the dataset, or seeds of generated tracks.
_TRACK_IDS = _Numbers(int, 0, what="track numbers")
#: Cones per window: a lane needs at least 4.
_SIZES = _Numbers(int, 4, what="sizes")
_RATE = click.FloatRange(0.0, 1.0, max_open=True)
_METRES = click.FloatRange(0.0, min_open=True)
_SECONDS = click.FloatRange(0.0, min_open=True)
_COUNT = click.IntRange(min=1)
_SEED = click.IntRange(min=0)


def _unwritable(path: Path, folder: bool = False) -> str | None:
    """Why ``path`` (a file, or with ``folder`` a folder that may be created) cannot be
    written, or ``None``."""
    if folder:
        if path.exists() and not path.is_dir():
            return f"{path} is a file, not a folder"
        base = path
        while not base.exists() and base != base.parent:
            base = base.parent
        if not base.is_dir():
            return f"cannot create {path}: {base} is not a folder"
        if not os.access(base, os.W_OK | os.X_OK):
            return f"cannot write in {base}: permission denied"
        return None
    if path.is_dir():
        return f"{path} is a folder"
    parent = path.parent
    if not parent.is_dir():
        return f"cannot write {path}: folder {parent} does not exist"
    if not os.access(parent, os.W_OK | os.X_OK) or (path.exists()
                                                     and not os.access(path, os.W_OK)):
        return f"cannot write {path}: permission denied"
    return None


def _out_file(ctx, param, value):
    """Callback of a file option: the file can be written (checked before the work)."""
    if value is not None:
        problem = _unwritable(Path(value))
        if problem:
            raise click.BadParameter(problem, ctx=ctx, param=param)
    return value


def _out_file_anywhere(ctx, param, value):
    """Callback of a file option whose folders are created when missing."""
    if value is not None:
        path = Path(value)
        problem = (f"{path} is a folder" if path.is_dir()
                   else _unwritable(path.parent, folder=True))
        if problem:
            raise click.BadParameter(problem, ctx=ctx, param=param)
    return value


def _out_folder(ctx, param, value):
    """Callback of a folder option: the folder exists or can be created, and written in."""
    if value is not None:
        problem = _unwritable(Path(value), folder=True)
        if problem:
            raise click.BadParameter(problem, ctx=ctx, param=param)
    return value


def _image_file(ctx, param, value):
    """Callback of a picture option: writable, and a format matplotlib draws (by suffix)."""
    value = _out_file(ctx, param, value)
    suffix = Path(value).suffix.lower().lstrip(".") if value else ""
    if suffix:
        from matplotlib.backend_bases import FigureCanvasBase

        kinds = FigureCanvasBase.get_supported_filetypes()
        if suffix not in kinds:
            raise click.BadParameter(f"cannot draw a .{suffix} file; use one of "
                                     f"{', '.join('.' + k for k in sorted(kinds))}",
                                     ctx=ctx, param=param)
    return value


_LANE_FORMATS = (".json", ".csv")


def _lane_file(ctx, param, value):
    """Callback of ``rld solve --out``: writable, ``.json`` or ``.csv``."""
    value = _out_file(ctx, param, value)
    if value is not None and Path(value).suffix.lower() not in _LANE_FORMATS:
        raise click.BadParameter(f"{value}: expected a .json or .csv file", ctx=ctx,
                                 param=param)
    return value


def _parse_pose(text: str) -> Pose:
    """``"x,y,yaw"`` (metres, metres, radians) -> ``Pose``; ``click.BadParameter`` otherwise."""
    try:
        x, y, yaw = (float(v) for v in text.split(","))
    except ValueError as exc:
        msg = f"expected x,y,yaw (metres, metres, radians), got {text!r}"
        raise click.BadParameter(msg) from exc
    if not all(math.isfinite(v) for v in (x, y, yaw)):
        raise click.BadParameter(f"x,y,yaw must be finite numbers, got {text!r}")
    return Pose(x, y, yaw)


def _pose_option(ctx, param, value):
    return None if value is None else _parse_pose(value)


def _backends_option(ctx, param, value):
    """Callback: each comma-separated RLD backend name exists (``rld.backends``)."""
    if value is None:
        return None
    from rld.backends import BACKENDS

    names = [b.strip() for b in value.split(",") if b.strip()]
    several = param.name == "backends"
    if not several and len(names) != 1:
        raise click.BadParameter(f"expected one backend, got {value!r}", ctx=ctx, param=param)
    for name in names or [""]:
        base, _, solver = name.partition(":")
        if base not in BACKENDS or (solver and base != "cvxpy") or name.endswith(":"):
            raise click.BadParameter(
                f"unknown backend {name!r}; use {', '.join(BACKENDS)} or cvxpy:SOLVER",
                ctx=ctx, param=param)
    return names if several else names[0]


_PARAM_HELP = ("Override a LaneParams field, NAME=VALUE (repeatable; the field's unit is in "
               "its name, e.g. --param max_cone_spacing_m=6.0); the run's command line records "
               "it.")


def _params(items: tuple[str, ...]):
    """LaneParams from --param NAME=VALUE items (None when there are none)."""
    if not items:
        return None
    from rld.types import LaneParams

    try:
        return LaneParams.from_overrides(items)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--param'") from exc


def _write_text(path: str | Path, text: str) -> None:
    try:
        with open(path, "w", newline="") as fh:
            fh.write(text)
    except OSError as exc:
        raise UserError(_os_error(exc)) from exc


# --- output ------------------------------------------------------------------------------


def _summary(lane, ids=None) -> str:
    """The lane as text; with ``ids`` (the map's cone ids, by row) the boundaries list cone ids,
    else row indices."""
    from rld import geometry as geo

    lines = [f"status      {lane.status.name}" + (f" ({lane.message})" if lane.message else "")]
    if lane.ok:
        sides = (("left", lane.left, lane.left_xy), ("right", lane.right, lane.right_xy))
        for name, idx, xy in sides:
            names = (ids[idx] if ids is not None else idx).tolist()
            lines.append(
                f"{name:<11} {idx.size:3d} cones, {geo.polyline_length(xy, lane.closed):6.1f} m"
                f"{', ids' if ids is not None else ''}: {names}"
            )
        lines.append(f"cost        {lane.cost:.4g}")
        lines.append(f"closed      {lane.closed}")
    t = lane.stats.get("solve_time_s")
    if t is not None:
        lines.append(f"solve time  {1000 * t:.2f} ms")
    return "\n".join(lines)


def _finite(value) -> float | None:
    try:
        value = float(value)
    except (TypeError, ValueError):
        return None
    return value if math.isfinite(value) else None


def _lane_json(lane, ids, **extra) -> str:
    """The lane as JSON: method, status, message, closed, cost, each side's cone ids and x, y
    (metres), and ``extra`` (map, pose, backend, params, time limit)."""
    import json

    doc = {"method": lane.stats.get("method"), "status": lane.status.name,
           "message": lane.message, "ok": bool(lane.ok), "closed": bool(lane.closed),
           "cost": _finite(lane.cost) if lane.ok else None}
    for name, idx, xy in (("left", lane.left, lane.left_xy), ("right", lane.right,
                                                               lane.right_xy)):
        doc[name] = {"ids": [int(i) for i in ids[idx]],
                     "xy": [[float(x), float(y)] for x, y in xy]}
    doc["backend"] = lane.stats.get("backend")
    doc["solve_time_s"] = _finite(lane.stats.get("solve_time_s"))
    doc.update(extra)
    return json.dumps(doc, indent=1) + "\n"


def _lane_csv(lane, ids) -> str:
    """The lane as CSV: one row per boundary cone, ``side,order,id,x,y`` (order from the car
    forward, from 0; x, y in metres)."""
    import csv
    import io

    buf = io.StringIO()
    w = csv.writer(buf, lineterminator="\n")
    w.writerow(["side", "order", "id", "x", "y"])
    for name, idx, xy in (("left", lane.left, lane.left_xy), ("right", lane.right,
                                                               lane.right_xy)):
        for k, (i, (x, y)) in enumerate(zip(idx.tolist(), xy, strict=True)):
            w.writerow([name, k, int(ids[i]), repr(float(x)), repr(float(y))])
    return buf.getvalue()


# --- commands ----------------------------------------------------------------------------


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rld-lanes")
def main() -> None:
    """rld: find the driving lane of a race track from 2D cone positions."""


_METHOD_HELP = "Lane-finding method."


@main.command()
@click.option("--seed", default=7, show_default=True, type=_SEED,
              help="Seed of the generated track and its false positives.")
@click.option("--fp-rate", default=0.2, show_default=True, type=_RATE,
              help="False-positive rate: the share of the map's cones that are false.")
@click.option("--range-m", default=30.0, show_default=True, type=_METRES,
              help="Perception range, metres.")
@click.option("--method", type=click.Choice(sorted(METHODS)), default=DEFAULT_METHOD,
              show_default=True, help=_METHOD_HELP)
@click.option("--out", default="lane.png", show_default=True, metavar="FILE", callback=_image_file,
              help="Picture of the scene (PNG, or another format by suffix).")
def demo(seed: int, fp_rate: float, range_m: float, method: str, out: str) -> None:
    """Solve a built-in example: a generated track, partly mapped, with false positives."""
    from rld.generator import generate_track
    from rld.metrics import CATEGORY_MEANING, score_lane
    from rld.plotting import plot_scene
    from rld.simulation import simulate_lap

    track = generate_track(seed)
    lap = simulate_lap(track, range_m=range_m, fp_rate=fp_rate, seed=seed)
    frame = lap.frame(len(lap) // 3)
    click.echo(
        f"track       {track.name}: {track.left.size}+{track.right.size} boundary cones, "
        f"{track.boundary_length('left'):.0f} m lap"
    )
    click.echo(
        f"frame       pose {frame.index} of {len(lap)}: {frame.cones.shape[0]} cones in the map, "
        f"{int(frame.is_false_positive.sum())} false positives ({fp_rate:.0%} rate, "
        f"{range_m:.0f} m range)"
    )
    lane = solve_lane(frame.cones, frame.pose, method=method)
    click.echo(f"method      {method}")
    click.echo(_summary(lane))
    # The first call of a process loads the solver and, on a fresh install, compiles the numba
    # kernels into their on-disk cache (seconds); the same call again shows what a call costs.
    t0 = time.perf_counter()
    solve_lane(frame.cones, frame.pose, method=method)
    click.echo(f"again       {1000 * (time.perf_counter() - t0):.2f} ms (the first call also "
               "loads the solver, and compiles the kernels after a fresh install)")
    score = score_lane(frame, lane.left, lane.right, lane.ok, lane.closed)
    verdict = ("critical (the car may leave the track)" if score.critical_at(1.0) else
               "critical at 0.5 m, not at 1 m" if score.critical_at(0.5) else "not critical")
    click.echo(f"off line    {score.deviation_m:.2f} m: how far a boundary strays from the true "
               f"one within 20 m of the car; {verdict}")
    click.echo(f"length      {score.pred_length_m:.1f} of {score.true_length_m:.1f} m (mean of "
               "the sides)" + ("; too short: a side under half its true length"
                               if score.too_short else ""))
    click.echo(f"index rule  {score.category}: {CATEGORY_MEANING[score.category]} (tolerant: "
               f"{score.category_tolerant}); IoU {score.iou:.2f}, IoU20 {score.iou20:.2f}")
    try:
        plot_scene(
            frame.cones, lane=lane, pose=frame.pose, gt_left=frame.gt_left,
            gt_right=frame.gt_right, false_positive=frame.is_false_positive,
            title=f"{method} on {track.name}, pose {frame.index}: {score.category}", path=out,
        )
    except OSError as exc:
        raise UserError(_os_error(exc)) from exc
    click.echo(f"plot        {out}")


#: The options ``rld solve`` and ``rld replay`` share.
_BACKEND_OPTION = click.option(
    "--backend", default=None, callback=_backends_option,
    show_default="auto: CP-SAT or HiGHS by the program's size",
    help="Solver backend of the RLD methods: auto, cpsat, highs, cvxpy or cvxpy:SOLVER.")
_TIME_LIMIT_OPTION = click.option(
    "--time-limit", "time_limit_s", type=_SECONDS, default=None,
    show_default="the method's: 0.4 s for RLD; CLC is bounded by max_iterations",
    help="Time budget of each solve, seconds.")


@main.command()
@click.argument("map_path", metavar="MAP", type=click.Path(exists=True, dir_okay=False))
@click.option("--pose", required=True, callback=_pose_option, metavar="X,Y,YAW",
              help="Car pose: x and y in metres, yaw in radians (from the x axis, "
                   "counter-clockwise), e.g. -1.5,2,0.3.")
@click.option("--method", type=click.Choice(sorted(METHODS)), default=DEFAULT_METHOD,
              show_default=True, help=_METHOD_HELP)
@_BACKEND_OPTION
@_TIME_LIMIT_OPTION
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE", help=_PARAM_HELP)
@click.option("--out", default=None, metavar="FILE", callback=_lane_file, show_default="none",
              help="Write the lane to this file, by suffix: .json (method, status, message, "
                   "closed, each side's cone ids and x, y in metres) or .csv (one row per "
                   "boundary cone: side, order, id, x, y).")
@click.option("--plot", "plot_path", default=None, metavar="FILE", callback=_image_file,
              show_default="none",
              help="Draw the scene into this picture (PNG, or another format by suffix).")
def solve(map_path: str, pose: Pose, method: str, backend: str | None,
          time_limit_s: float | None, param_items: tuple[str, ...], out: str | None,
          plot_path: str | None) -> None:
    """Find the lane in MAP ahead of --pose and print it as the map's cone ids.

    MAP is a dataset cone_map_K.yaml (id: [x, y], metres) or our CSV (id,x,y[,side,order]
    [,color], or just x,y; a color column gives each cone's class: blue, yellow, orange,
    big_orange or unknown (left / right for blue / yellow), an empty cell unknown). Exit code
    0 when a lane was found, 1 when the map holds none, 2 for a user error."""
    from rld.tracks import load_map

    params = _params(param_items)
    try:
        track = load_map(map_path)
    except (ValueError, OSError) as exc:
        raise UserError(_os_error(exc) if isinstance(exc, OSError) else str(exc)) from exc
    colors = track.meta.get("colors")
    if colors is not None:
        from rld.colors import ALIASES, CLASSES

        for cid, label in zip(track.ids.tolist(), colors, strict=True):
            if label not in CLASSES and label not in ALIASES:
                raise UserError(f"{map_path}: cone {cid}: unknown colour {label!r}; use "
                                f"{', '.join(CLASSES)} or left / right (an empty cell is "
                                "unknown)")
    try:
        solver = LaneSolver(method=method, params=params, backend=backend)
        lane = solver.solve(track.cones, pose, colors=colors, time_limit_s=time_limit_s)
    except ValueError as exc:
        raise UserError(str(exc)) from exc
    labelled = sum(c != "unknown" for c in colors) if colors is not None else 0
    click.echo(f"map         {map_path}: {track.cones.shape[0]} cones"
               + (f", {labelled} with a colour label" if colors is not None else ""))
    click.echo(f"method      {method}"
               + (f" (backend {lane.stats['backend']})" if lane.stats.get("backend") else ""))
    click.echo(_summary(lane, ids=track.ids))
    if out:
        if Path(out).suffix.lower() == ".json":
            overrides = {t.split("=", 1)[0].strip(): None for t in param_items}
            text = _lane_json(lane, track.ids, map=str(map_path),
                              pose=[pose.x, pose.y, pose.yaw],
                              time_limit_s=time_limit_s,
                              params={k: getattr(params, k) for k in overrides})
        else:
            text = _lane_csv(lane, track.ids)
        _write_text(out, text)
        click.echo(f"lane        {out}")
    if plot_path:
        from rld.plotting import plot_scene

        gt = (track.left, track.right) if track.left.size else (None, None)
        try:
            plot_scene(track.cones, lane=lane, pose=pose, gt_left=gt[0], gt_right=gt[1],
                       title=f"{method}: {lane.status.name}", path=plot_path)
        except OSError as exc:
            raise UserError(_os_error(exc)) from exc
        click.echo(f"plot        {plot_path}")
    if not lane.ok:
        sys.exit(1)


@main.command()
@click.option("--methods", default=None, show_default="all methods",
              help="Comma-separated methods: " + ", ".join(sorted(METHODS)) + ".")
@click.option("--quiet", is_flag=True, help="No progress bar; off by default.")
def warmup(methods: str | None, quiet: bool) -> None:
    """Compile every kernel of the methods into the kernel cache now (a car's start-up or
    install script), so that the first solve of a later process only loads it."""
    from tqdm import tqdm

    from rld._jit import cache_dir
    from rld.warmup import FRAMES
    from rld.warmup import warmup as run_warmup

    names = [m.strip() for m in methods.split(",") if m.strip()] if methods else sorted(METHODS)
    bad = [m for m in names if m not in METHODS]
    if bad:
        raise click.BadParameter(f"unknown methods {bad}; available: {', '.join(sorted(METHODS))}",
                                 param_hint="--methods")
    steps = len(names) * sum(frame[3] for frame in FRAMES)
    t0 = time.perf_counter()
    with tqdm(total=steps, unit="frame", disable=quiet, leave=False) as bar:
        def step(method: str) -> None:
            bar.set_description(method)
            bar.update()

        seconds = run_warmup(names, progress=step)
    for m, s in seconds.items():
        click.echo(f"{m:<16} {s:6.1f} s")
    click.echo(f"kernel cache {cache_dir()} ({time.perf_counter() - t0:.1f} s in all)")


def _emit(text: str, out: str | None) -> None:
    """Print a benchmark's Markdown and, with ``--out``, also write it to that file."""
    click.echo(text)
    if out:
        _write_text(out, text + "\n")


def _benchmark_module(name: str):
    """Import ``benchmarks.NAME`` from the working directory or from this checkout."""
    import importlib

    for root in (Path.cwd(), Path(__file__).resolve().parents[1]):
        if (root / "benchmarks" / f"{name}.py").exists():
            if str(root) not in sys.path:
                sys.path.insert(0, str(root))
            return importlib.import_module(f"benchmarks.{name}")
    raise UserError("benchmarks/ not found: run `rld bench` from a checkout of the repository")


def _dataset_benchmark(name: str, command: str):
    """``benchmarks.NAME`` (``_benchmark_module``), or ``None`` after saying that ``command``
    is skipped because the racetrack dataset was not found."""
    mod = _benchmark_module(name)
    if not mod.dataset_available():
        click.echo(f"{command}: skipped, the racetrack dataset was not found (set "
                   "RLD_DATASET_DIR or put it in ../shared/data/fsd_racetrack_dataset)", err=True)
        return None
    return mod


def _load_dataset_tracks(folder, numbers) -> list:
    """The dataset's tracks ``numbers`` in ``folder``; a missing or malformed file is a
    ``UserError`` naming it."""
    from rld.tracks import load_dataset_track

    try:
        return [load_dataset_track(folder, k) for k in numbers]
    except OSError as exc:
        raise UserError(_os_error(exc)) from exc
    except ValueError as exc:
        raise UserError(str(exc)) from exc


_EVERY_HELP = "Every k-th pose of each lap (poses lie 1 m apart), a count."
_FP_RATES_HELP = ("Comma-separated false-positive rates: the share of the map's cones that are "
                  "false, each 0 <= rate < 1.")
_RANGES_HELP = "Comma-separated perception ranges, metres (each > 0)."
_SEEDS_HELP = "Comma-separated seeds of the false positives (integers >= 0), pooled."
_OUT_MD_HELP = "Also write the Markdown tables to this file."
_PROCESSES_HELP = "Worker processes, a count."


@main.command("train-ranker")
@click.option("--generated", "n_generated", default=8, show_default=True,
              type=click.IntRange(min=0),
              help="Generated tracks to train on, a count (seeds 1000, 1001, ...).")
@click.option("--train-tracks", default="1,2,3", show_default=True,
              type=_Numbers(int, 0, empty=True, what="track numbers"),
              help="Comma-separated shared dataset track numbers to train on (the others are "
                   "held out); empty for none.")
@click.option("--fp-rates", default="0,0.1,0.3", show_default=True, type=_RATES,
              help=_FP_RATES_HELP)
@click.option("--ranges", default="50", show_default=True, type=_RANGES, help=_RANGES_HELP)
@click.option("--every", default=4, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--epochs", default=200, show_default=True, type=_COUNT,
              help="Training epochs, a count.")
@click.option("--max-iterations", default=2500, show_default=True, type=_COUNT,
              help="CLC's it_max while collecting candidates, a count (the packaged model's; "
                   "the solver's default, 250, gave a worse ranker).")
@click.option("--seed", default=0, show_default=True, type=_SEED,
              help="Seed of the false positives and the training.")
@click.option("--out", default=None, metavar="FILE", callback=_out_file_anywhere,
              show_default="the packaged model, clc/models/clc_ranker.npz",
              help="Weights file (.npz; its JSON card is written beside it).")
def train_ranker(n_generated: int, train_tracks: list[int], fp_rates: list[float],
                 ranges: list[float], every: int, epochs: int, max_iterations: int, seed: int,
                 out: str | None) -> None:
    """Train CLC's learned ranker (section VII) and write its weights and JSON card."""
    import datetime

    try:
        from clc import train
    except ImportError as exc:  # pragma: no cover - torch is imported lazily inside
        raise click.ClickException(str(exc)) from exc
    try:
        import torch  # noqa: F401
    except ImportError as exc:
        raise click.ClickException(
            "training needs torch: pip install -e '.[train]'") from exc
    from clc.ranker import DEFAULT_MODEL, LearnedRanker, LongestRanker
    from rld.generator import generate_track
    from rld.tracks import DATASET_TRACKS, find_dataset_dir
    from rld.types import LaneParams

    fps, rs, wanted = fp_rates, ranges, train_tracks
    folder = find_dataset_dir()
    shared = dict(zip(DATASET_TRACKS, _load_dataset_tracks(folder, DATASET_TRACKS),
                      strict=True)) if folder else {}
    held = [shared[k] for k in DATASET_TRACKS if k not in wanted and k in shared]
    tracks = [generate_track(1000 + s) for s in range(n_generated)]
    tracks += [shared[k] for k in wanted if k in shared]
    if not tracks:
        raise UserError("no tracks to train on")
    params = LaneParams(max_iterations=max_iterations)
    lists = train.collect(tracks, fp_rates=fps, ranges=rs, every=every, seed=seed,
                          params=params)
    held_lists = train.collect(held, fp_rates=fps, ranges=rs, every=every, seed=seed,
                               params=params)
    arrays = train.train_ranker(lists, seed=seed, epochs=epochs)
    model = LearnedRanker(arrays["W1"], arrays["b1"], arrays["w2"], arrays["b2"],
                          arrays["mean"], arrays["std"])
    scores = {"training": train.top_pick_iou(model, lists),
              "held_out": train.top_pick_iou(model, held_lists) if held_lists else None}
    card = {
        "date": datetime.date.today().isoformat(),
        "training_data": {"generated_track_seeds": [1000 + s for s in range(n_generated)],
                          "dataset_tracks": [t.name for t in tracks if t.name.startswith("track")],
                          "held_out_tracks": [t.name for t in held], "fp_rates": fps,
                          "ranges_m": rs, "every_kth_pose": every, "lists": len(lists),
                          "max_iterations": max_iterations,
                          "candidates": int(sum(cl.iou.size for cl in lists))},
        "target": "the protocol's IoU (rld.metrics.candidate_ious) minus 0.03 per cone on a "
                  "side whose boundary does not hold it",
        "hyper_parameters": {"epochs": epochs, "lr": 0.008, "batch_size": 8192,
                             "wrong_cone_penalty": 0.03,
                             "lambda_iou": 20.0, "hidden": 100, "pairs_per_list": 256},
        "seed": seed,
        "scores": scores,
        "longest_lane_baseline": {"held_out": train.top_pick_iou(LongestRanker(), held_lists)
                                  if held_lists else None},
    }
    try:
        path = train.save_ranker(arrays, out or DEFAULT_MODEL, card)
    except OSError as exc:
        raise UserError(_os_error(exc)) from exc
    click.echo(f"wrote {path} and {path.with_suffix('.json')}")
    click.echo(f"mean IoU of the top pick: {scores}")


@main.command("eval")
@click.argument("dataset", required=False, type=click.Path(file_okay=False))
@click.option("--methods", default="rld,clc", show_default=True,
              help="Comma-separated method specs: name or name:option (rld:highs, clc:longest).")
@click.option("--tracks", "track_ids", default=None, type=_TRACK_IDS,
              show_default="all the dataset has",
              help="Comma-separated dataset track numbers.")
@click.option("--generated", "n_generated", default=0, show_default=True,
              type=click.IntRange(min=0),
              help="Also this many generated tracks, a count (seeds from --generated-seed on).")
@click.option("--generated-seed", "first_generated", default=0, show_default=True, type=_SEED,
              help="Seed of the first generated track (the ranker trains on "
                   "1000-1007, `rld bench rld-paper` uses 11-15).")
@click.option("--ranges", default="30,50", show_default=True, type=_RANGES, help=_RANGES_HELP)
@click.option("--fp-rates", default="0,0.1,0.3,0.5", show_default=True, type=_RATES,
              help=_FP_RATES_HELP)
@click.option("--every", default=1, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--seed", "seeds", default="0", show_default=True, type=_SEEDS,
              help="Seed of the false positives (integer >= 0), or several, comma-separated "
                   "(0,1,2): the tables pool them and a table gives each seed's critical rates.")
@click.option("--processes", default=None, type=_COUNT, show_default="the CPU count",
              help=_PROCESSES_HELP)
@click.option("--out", default="eval_out", show_default=True, metavar="FOLDER",
              callback=_out_folder,
              help="Output folder (created if missing).")
@click.option("--plot-failures", is_flag=True,
              help="Draw every pose critical by the geometric rule at 0.5 m (into "
                   "OUT/failures); off by default.")
@click.option("--results", "results_page", default=None, metavar="FILE",
              callback=_out_file_anywhere, show_default="none",
              help="Also write the results page (Markdown, as docs/results.md) to this file, "
                   "its pictures beside it (its folder created if missing).")
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE", help=_PARAM_HELP)
@click.option("--color-accuracy", type=click.FloatRange(0.0, 1.0), default=None,
              show_default="no colour",
              help="Simulate colour perception: the probability that a labelled cone reports "
                   "its true class (blue left, yellow right), 0..1; 0.5 is random.")
@click.option("--color-unknown", type=click.FloatRange(0.0, 1.0), default=0.1, show_default=True,
              help="With --color-accuracy: the probability that a labelled cone reports "
                   "unknown, 0..1.")
def eval_cmd(dataset: str | None, methods: str, track_ids: list[int] | None, n_generated: int,
             first_generated: int, ranges: list[float], fp_rates: list[float], every: int,
             seeds: list[int], processes: int | None, out: str, plot_failures: bool,
             results_page: str | None, param_items: tuple[str, ...],
             color_accuracy: float | None, color_unknown: float) -> None:
    """Run the evaluation protocol (DESIGN.md) and write records, tables and plots."""
    import datetime
    import shlex

    from rld import report
    from rld.generator import generate_track
    from rld.tracks import DATASET_TRACKS, find_dataset_dir

    params = _params(param_items)
    try:
        specs = [report.parse_method(m) for m in methods.split(",") if m.strip()]
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--methods'") from exc
    if not specs:
        raise click.BadParameter(f"no method in {methods!r}", param_hint="'--methods'")
    folder = Path(dataset) if dataset else find_dataset_dir()
    if track_ids and folder is None:
        raise click.BadParameter("the racetrack dataset was not found: give DATASET or set "
                                 "RLD_DATASET_DIR", param_hint="'--tracks'")
    tracks = []
    if folder is not None and (track_ids or n_generated == 0):
        if not folder.is_dir():
            raise UserError(f"dataset folder {folder} does not exist")
        tracks += _load_dataset_tracks(folder, track_ids or list(DATASET_TRACKS))
    tracks += [generate_track(first_generated + s) for s in range(n_generated)]
    if not tracks:
        raise UserError("no tracks: give a dataset folder (or put the dataset in "
                        "../shared/data/...) or --generated N")
    try:
        records = report.evaluate(
            tracks, specs, ranges=ranges, fp_rates=fp_rates, every=every, seed=seeds,
            processes=processes, params=params,
            plot_failures=str(Path(out) / "failures") if plot_failures else None,
            color=None if color_accuracy is None else (color_accuracy, color_unknown))
    except ValueError as exc:
        raise UserError(str(exc)) from exc
    command = "rld eval " + " ".join(shlex.quote(a) for a in sys.argv[2:])
    header = (f"Command: `{command}`. Machine: {report.machine()}. "
              f"Date: {datetime.date.today().isoformat()}. Tracks: "
              f"{', '.join(t.name for t in tracks)}.")
    try:
        paths = report.write_outputs(records, out, header=header)
    except OSError as exc:
        raise UserError(_os_error(exc)) from exc
    click.echo(paths["results"].read_text())
    click.echo(f"wrote {out}/: poses.jsonl, summary.json, results.md, "
               + ", ".join(p.name for p in paths["plots"]))
    if results_page:
        import shutil

        page = Path(results_page)
        images = []
        try:
            page.parent.mkdir(parents=True, exist_ok=True)
            for plot in paths["plots"]:
                target = page.parent / f"{page.stem}_{plot.name}"
                shutil.copyfile(plot, target)
                images.append(target.name)
            page.write_text(report.results_page(paths["rows"], header, images))
        except OSError as exc:
            raise UserError(_os_error(exc)) from exc
        click.echo(f"wrote {results_page} and its images")


@main.group()
def bench() -> None:
    """Run the benchmarks of benchmarks/ (from a checkout) and print their tables."""


_BACKENDS_HELP = "Comma-separated RLD backends: cpsat, highs, cvxpy, cvxpy:SOLVER or auto."


@bench.command("rld")
@click.option("--method", type=click.Choice(["rld", "rld-sided"]), default="rld",
              show_default=True, help=_METHOD_HELP)
@click.option("--backends", default="cpsat,highs,cvxpy", show_default=True,
              callback=_backends_option, help=_BACKENDS_HELP)
@click.option("--sizes", default="12,16,20,30,40", show_default=True, type=_SIZES,
              help="Comma-separated window sizes, cones (each >= 4).")
@click.option("--tracks", "n_tracks", default=4, show_default=True, type=_COUNT,
              help="Generated tracks, a count.")
@click.option("--stride", default=25, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--time-limit", "time_limit_s", default=1.0, show_default=True, type=_SECONDS,
              help="Budget per call, seconds.")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_rld(method: str, backends: list[str], sizes: list[int], n_tracks: int, stride: int,
              time_limit_s: float, out: str | None) -> None:
    """RLD latency per backend and window size, cold and warm-started."""
    mod = _benchmark_module("bench_rld")
    rows = mod.run(sizes=sizes, backends=backends, n_tracks=n_tracks, stride=stride,
                   time_limit_s=time_limit_s, method=method)
    table = mod.to_markdown(rows, time_limit_s)
    click.echo(f"machine: {mod.machine()}")
    _emit(table, out)


@bench.command("budget")
@click.option("--backends", default="cpsat,highs,cvxpy", show_default=True,
              callback=_backends_option, help=_BACKENDS_HELP)
@click.option("--sizes", default="30,40", show_default=True, type=_SIZES,
              help="Comma-separated window sizes, cones (each >= 4).")
@click.option("--budgets", default="0.02,0.05,0.2", show_default=True, type=_BUDGETS,
              help="Comma-separated time budgets, seconds (each > 0).")
@click.option("--tracks", "n_tracks", default=4, show_default=True, type=_COUNT,
              help="Generated tracks, a count.")
@click.option("--stride", default=25, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_budget(backends: list[str], sizes: list[int], budgets: list[float], n_tracks: int,
                 stride: int, out: str | None) -> None:
    """How far past its time budget an RLD call runs, per backend, size and budget."""
    mod = _benchmark_module("bench_rld")
    rows = mod.run_budget(sizes=sizes, budgets=budgets, backends=backends, n_tracks=n_tracks,
                          stride=stride)
    table = mod.budget_markdown(rows)
    click.echo(f"machine: {mod.machine()}")
    _emit(table, out)


@bench.command("rld-paper")
@click.option("--method", type=click.Choice(["rld", "rld-sided"]), default="rld",
              show_default=True, help=_METHOD_HELP)
@click.option("--backend", default="cpsat", show_default=True, callback=_backends_option,
              help="RLD backend: cpsat, highs, cvxpy, cvxpy:SOLVER or auto.")
@click.option("--cones", "n_cones", default=12, show_default=True, type=click.IntRange(min=4),
              help="Window size, cones.")
@click.option("--poses", default=60, show_default=True, type=_COUNT,
              help="Poses per topology and ratio, a count.")
@click.option("--seeds", default="0,1,2,3,4", show_default=True, type=_SEEDS,
              help="Comma-separated seeds (tracks, noise, false positives; integers >= 0), "
                   "pooled.")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE", help=_PARAM_HELP)
def bench_rld_paper(method: str, backend: str, n_cones: int, poses: int, seeds: list[int],
                    out: str | None, param_items: tuple[str, ...]) -> None:
    """RLD accuracy in the paper's experiment (fig. 7): topologies x false-positive ratios."""
    params = _params(param_items)  # checked here; the benchmark gets the names given
    names = {t.split("=", 1)[0].strip() for t in param_items}
    if "max_cones" in names:
        raise click.BadParameter("the window size is --cones", param_hint="'--param'")
    overrides = {k: getattr(params, k) for k in names}
    mod = _benchmark_module("bench_rld_paper")
    table = mod.to_markdown(mod.run(backend=backend, n_cones=n_cones, poses=poses,
                                    method=method, seeds=seeds, **overrides))
    _emit(table, out)


@bench.command("protocol")
@click.option("--method", type=click.Choice(sorted(METHODS)), default="rld", show_default=True,
              help=_METHOD_HELP)
@click.option("--backend", default=None, callback=_backends_option, show_default="auto",
              help="RLD backend: cpsat, highs, cvxpy, cvxpy:SOLVER or auto.")
@click.option("--fp-rates", default="0,0.3", show_default=True, type=_RATES,
              help=_FP_RATES_HELP)
@click.option("--range-m", default=50.0, show_default=True, type=_METRES,
              help="Perception range, metres.")
@click.option("--every", default=12, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--time-limit", "time_limit_s", default=2.0, show_default=True, type=_SECONDS,
              help="Budget per call, seconds.")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_protocol(method: str, backend: str | None, fp_rates: list[float], range_m: float,
                   every: int, time_limit_s: float, out: str | None) -> None:
    """A method on the shared dataset tracks under the evaluation protocol (a sample)."""
    mod = _benchmark_module("bench_protocol")
    try:
        rows = mod.run(method=method, backend=backend, fp_rates=fp_rates, range_m=range_m,
                       every=every, time_limit_s=time_limit_s)
    except FileNotFoundError as exc:
        raise UserError(str(exc)) from exc
    table = mod.to_markdown(rows)
    _emit(table, out)


@bench.command("incremental")
@click.option("--range-m", default=50.0, show_default=True, type=_METRES,
              help="Perception range, metres.")
@click.option("--fp-rates", default="0,0.1,0.3", show_default=True, type=_RATES,
              help=_FP_RATES_HELP)
@click.option("--every", default=1, show_default=True, type=_COUNT,
              help="Every k-th pose (poses lie 1 m apart), a count. The solver is "
                   "stateful: keep 1 for real figures; k > 1 only for quick runs (the car jumps "
                   "k metres per call).")
@click.option("--tracks", "track_ids", default=",".join(str(k) for k in (1, 2, 3, 4, 6, 7)),
              show_default=True, type=_TRACK_IDS,
              help="Comma-separated shared dataset track numbers.")
@click.option("--quick", is_flag=True,
              help="A tiny run: the first track, its first 50 poses; off by default.")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_incremental(range_m: float, fp_rates: list[float], every: int, track_ids: list[int],
                      quick: bool, out: str | None) -> None:
    """Incremental RLD latency per map update and against the kept lane's length."""
    import shlex

    mod = _dataset_benchmark("bench_incremental", "rld bench incremental")
    if mod is None:
        return
    try:
        records = mod.run(range_m=range_m, fp_rates=fp_rates, every=every, tracks=track_ids,
                          quick=quick)
    except FileNotFoundError as exc:
        raise UserError(_os_error(exc)) from exc
    command = "rld bench incremental " + " ".join(shlex.quote(a) for a in sys.argv[3:])
    text = mod.to_markdown(records, range_m, command=command.strip())
    _emit(text, out)


@bench.command("latency")
@click.option("--methods", default="rld,rld-incremental,clc", show_default=True,
              help="Comma-separated method names.")
@click.option("--range-m", default=50.0, show_default=True, type=_METRES,
              help="Perception range, metres.")
@click.option("--fp-rate", default=0.3, show_default=True, type=_RATE,
              help="The share of the map's cones that are false, 0 <= rate < 1.")
@click.option("--every", default=1, show_default=True, type=_COUNT,
              help="Every k-th pose (poses lie 1 m apart), a count. The solvers keep state "
                   "between calls: keep 1 for real figures.")
@click.option("--tracks", "track_ids", default=",".join(str(k) for k in (1, 2, 3, 4, 6, 7)),
              show_default=True, type=_TRACK_IDS,
              help="Comma-separated shared dataset track numbers.")
@click.option("--time-limit", "time_limit_s", default=None, type=_METRES,
              show_default="each method's default",
              help="Budget per call, seconds.")
@click.option("--quick", is_flag=True,
              help="A tiny run: the first track, its first 20 poses; off by default.")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_latency(methods: str, range_m: float, fp_rate: float, every: int,
                  track_ids: list[int], time_limit_s: float | None, quick: bool,
                  out: str | None) -> None:
    """Latency of a reused solver on real maps against the 20 Hz targets (issue 40)."""
    import shlex

    names = [m.strip() for m in methods.split(",") if m.strip()]
    unknown = [m for m in names if m not in METHODS]
    if unknown or not names:
        raise click.BadParameter(f"{unknown or methods!r}: use some of {', '.join(METHODS)}",
                                 param_hint="'--methods'")
    mod = _dataset_benchmark("bench_latency", "rld bench latency")
    if mod is None:
        return
    try:
        records = mod.run(methods=names, range_m=range_m, fp_rate=fp_rate, every=every,
                          tracks=track_ids, time_limit_s=time_limit_s, quick=quick)
    except FileNotFoundError as exc:
        raise UserError(_os_error(exc)) from exc
    command = "rld bench latency " + " ".join(shlex.quote(a) for a in sys.argv[3:])
    _emit(mod.to_markdown(records, range_m, fp_rate, time_limit_s, command=command.strip()),
          out)


@bench.command("clc")
@click.option("--ranges", default="30,50", show_default=True, type=_RANGES, help=_RANGES_HELP)
@click.option("--fp-rates", default="0,0.1,0.3,0.5", show_default=True, type=_RATES,
              help=_FP_RATES_HELP)
@click.option("--every", default=4, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--ranker", default=None, type=click.Choice(["learned", "rld_cost", "longest"]),
              show_default="learned", help="CLC's ranker.")
@click.option("--iterations/--no-iterations", default=True, show_default=True,
              help="Also latency against it_max and map size (fig. 16).")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_clc(ranges: list[float], fp_rates: list[float], every: int, ranker: str | None,
              iterations: bool, out: str | None) -> None:
    """CLC latency, accuracy and completeness on the shared tracks (protocol of DESIGN.md)."""
    mod = _benchmark_module("bench_clc")
    try:
        rows = mod.run(ranges=ranges, fp_rates=fp_rates, every=every, ranker=ranker)
        parts = [mod.to_markdown(rows)]
        if iterations:
            parts.append(mod.iterations_markdown(mod.run_iterations(ranker=ranker)))
    except FileNotFoundError as exc:
        raise UserError(str(exc)) from exc
    ct = mod.compile_time()
    parts.append("\n".join(f"- {k}: import {v['import_s']:.2f} s, first call "
                           f"{v['first_call_s']:.2f} s, second call "
                           f"{1000 * v['second_call_s']:.2f} ms" for k, v in ct.items()))
    text = "\n\n".join(parts)
    _emit(text, out)


@bench.command("clc-failures")
@click.option("--ranges", default="30,50", show_default=True, type=_RANGES, help=_RANGES_HELP)
@click.option("--fp-rates", default="0.1,0.3", show_default=True, type=_RATES,
              help=_FP_RATES_HELP)
@click.option("--seed", "seeds", default="0", show_default=True, type=_SEEDS, help=_SEEDS_HELP)
@click.option("--every", default=1, show_default=True, type=_COUNT, help=_EVERY_HELP)
@click.option("--processes", default=2, show_default=True, type=_COUNT, help=_PROCESSES_HELP)
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help="Also write the Markdown table to this file.")
def bench_clc_failures(ranges: list[float], fp_rates: list[float], seeds: list[int],
                       every: int, processes: int, out: str | None) -> None:
    """Where CLC's critical poses come from: the truth infeasible, the judge preferring the
    wrong lane, or the search never building the truth (benchmarks/bench_clc_failures.py)."""
    mod = _benchmark_module("bench_clc_failures")
    try:
        results = [mod.run(range_m=r, fp_rate=fp, seeds=seeds, every=every,
                           processes=processes)
                   for r in ranges for fp in fp_rates]
    except FileNotFoundError as exc:
        raise UserError(str(exc)) from exc
    _emit(mod.to_markdown(results), out)


@bench.command("paired")
@click.argument("base", type=click.Path(exists=True, file_okay=False))
@click.argument("other", type=click.Path(exists=True, file_okay=False))
@click.option("--method", default="rld", show_default=True,
              help="The method whose records are compared (its name in the records).")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help="Also write the Markdown table to this file.")
def bench_paired(base: str, other: str, method: str, out: str | None) -> None:
    """Two `rld eval --out` folders compared pose by pose: geometric critical rates, poses
    fixed and broken, the paired difference with its 95 % interval, lane lengths
    (benchmarks/bench_paired.py; DESIGN.md, "Choosing and reporting")."""
    mod = _benchmark_module("bench_paired")
    try:
        text = mod.table(mod.load_records(base, method), mod.load_records(other, method))
    except (FileNotFoundError, ValueError) as exc:
        raise UserError(str(exc)) from exc
    _emit(text, out)


def _parse_cells(cells: str) -> list[tuple[float, float]]:
    """``--cells`` "30:0.1,50:0.3" -> [(30.0, 0.1), (50.0, 0.3)] (range in metres > 0, rate
    in [0, 1)); a usage error otherwise."""
    try:
        parsed = [tuple(float(v) for v in c.split(":")) for c in cells.split(",")]
        if any(len(c) != 2 for c in parsed):
            raise ValueError
    except ValueError as exc:
        raise click.BadParameter(f"{cells!r}: expected RANGE_M:FP_RATE,...",
                                 param_hint="'--cells'") from exc
    for r, fp in parsed:
        if not (math.isfinite(r) and r > 0 and 0 <= fp < 1):
            raise click.BadParameter(f"{cells!r}: each range must be > 0 metres and each rate "
                                     f"0 <= rate < 1, got {r:g}:{fp:g}", param_hint="'--cells'")
    return parsed


_CELLS_HELP = ("Comma-separated RANGE_M:FP_RATE cells: perception range in metres (> 0), "
               "false-positive rate (0 <= rate < 1).")


@bench.command("fp-clearance")
@click.option("--clearances", default="0,0.5,1,1.5,2", show_default=True,
              help="Comma-separated least distances of the false positives from the true "
                   "boundary lines, metres (each >= 0; 0: the experiment as it is).")
@click.option("--methods", default="clc,rld", show_default=True,
              help="clc (the protocol on the shared tracks), rld (the paper's experiment).")
@click.option("--cells", default="30:0.1,30:0.3,50:0.3", show_default=True,
              help="CLC's cells. " + _CELLS_HELP)
@click.option("--seed", "seeds", default="0,1,2,3,4", show_default=True, type=_SEEDS,
              help="Comma-separated seeds (integers >= 0), pooled.")
@click.option("--every", default=1, show_default=True, type=_COUNT,
              help="CLC: every k-th pose of each lap (poses lie 1 m apart), a count.")
@click.option("--processes", default=2, show_default=True, type=_COUNT, help=_PROCESSES_HELP)
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
@click.option("--plot", "plot_path", default=None, metavar="FILE", callback=_image_file,
              show_default="none",
              help="Also draw the rates against the clearance to this picture (PNG).")
def bench_fp_clearance(clearances: str, methods: str, cells: str, seeds: list[int], every: int,
                       processes: int, out: str | None, plot_path: str | None) -> None:
    """How much of CLC's and RLD's failures come from false positives near the true
    boundaries: the accuracy experiments rerun with the false positives kept a distance from
    the true lines (benchmarks/bench_fp_clearance.py). An analysis, not a target."""
    mod = _benchmark_module("bench_fp_clearance")
    chosen = {m.strip() for m in methods.split(",") if m.strip()}
    if not chosen or chosen - {"clc", "rld"}:
        raise click.BadParameter(f"{methods!r}: use clc, rld or both", param_hint="'--methods'")
    try:
        cs = mod.parse_clearances(clearances)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--clearances'") from exc
    parsed = _parse_cells(cells)
    try:
        clc_rows = (mod.run_clc(cs, seeds, parsed, every, processes)
                    if "clc" in chosen else [])
        rld_rows = mod.run_rld(cs, seeds) if "rld" in chosen else []
    except (FileNotFoundError, ValueError) as exc:
        raise UserError(str(exc)) from exc
    _emit(mod.to_markdown(clc_rows, rld_rows), out)
    if plot_path:
        try:
            mod.plot(clc_rows, rld_rows, plot_path)
        except OSError as exc:
            raise UserError(_os_error(exc)) from exc
        click.echo(f"wrote {plot_path}")


@bench.command("generator")
@click.option("--sets", default="choosing,reporting", show_default=True,
              help="Comma-separated generated sets (rld.generator.generated_set): choosing, "
                   "reporting.")
@click.option("--clc/--no-clc", "with_clc", default=False, show_default=True,
              help="Also CLC's geometric critical rates on the shared tracks and on the first "
                   "set (a few minutes).")
@click.option("--spread", "spread_blocks", default=0, show_default=True,
              type=click.IntRange(min=0),
              help="Also the KS statistics of this many further sets of 32 generated tracks "
                   "(seeds 4000 on), a count: how much a set's figure owes to luck.")
@click.option("--range-m", default=30.0, show_default=True, type=_METRES,
              help="CLC: perception range, metres.")
@click.option("--fp-rates", default="0,0.3", show_default=True, type=_RATES,
              help="CLC: " + _FP_RATES_HELP)
@click.option("--every", default=4, show_default=True, type=_COUNT,
              help="CLC: " + _EVERY_HELP)
@click.option("--plot", "plot_path", default=None, metavar="FILE", callback=_image_file,
              show_default="none",
              help="Also draw the empirical CDFs (2 x 2) to this picture (PNG).")
@click.option("--out", default=None, metavar="FILE", callback=_out_file, show_default="none",
              help=_OUT_MD_HELP)
def bench_generator(sets: str, with_clc: bool, spread_blocks: int, range_m: float,
                    fp_rates: list[float], every: int, plot_path: str | None,
                    out: str | None) -> None:
    """Do the generated tracks resemble the shared ones? Cone spacing, lane width, turn per
    cone and position noise side by side, with two-sample KS statistics
    (benchmarks/bench_generator.py)."""
    names = [s.strip() for s in sets.split(",") if s.strip()]
    if not names or set(names) - {"choosing", "reporting"}:
        raise click.BadParameter(f"{sets!r}: use choosing, reporting or both",
                                 param_hint="'--sets'")
    mod = _benchmark_module("bench_generator")
    try:
        result = mod.run(names)
        parts = [mod.to_markdown(result)]
        if spread_blocks:
            spread = mod.spread(4000, spread_blocks, 32, shared=result["shared"])
            parts.append(mod.spread_markdown(spread, 4000, 32))
        if with_clc:
            from rld.generator import generated_set

            shared = mod.clc_rates(mod.shared_tracks(), range_m=range_m, fp_rates=fp_rates,
                                   every=every)
            generated = mod.clc_rates(generated_set(names[0]), range_m=range_m,
                                      fp_rates=fp_rates, every=every)
            parts.append(mod.clc_markdown(shared, generated, range_m, names[0]))
    except FileNotFoundError as exc:
        raise UserError(str(exc)) from exc
    _emit("\n\n".join(parts), out)
    if plot_path:
        try:
            mod.plot(result, plot_path)
        except OSError as exc:
            raise UserError(_os_error(exc)) from exc
        click.echo(f"wrote {plot_path}")


@bench.command("startup")
@click.option("--methods", default="rld,rld-incremental,clc,huang", show_default=True,
              help="Comma-separated methods.")
@click.option("--repeats", default=3, show_default=True, type=_COUNT,
              help="Fresh processes per method and phase (cold and warm), a count.")
@click.option("--latency", "n_latency", default=0, show_default=True,
              type=click.IntRange(min=0),
              help="Instead: the median of this many warm solves per method, a count.")
@click.option("--no-shipped", is_flag=True,
              help="Hide the wheel's shipped kernels: cold then compiles every kernel "
                   "(default: off).")
def bench_startup(methods: str, repeats: int, n_latency: int, no_shipped: bool) -> None:
    """Start-up per method (issue 42): a fresh process's import and first solve with an empty
    user kernel cache (cold) and with the cache it left (warm), seconds
    (benchmarks/bench_startup.py)."""
    names = [m.strip() for m in methods.split(",") if m.strip()]
    bad = [m for m in names if m not in METHODS]
    if bad or not names:
        raise click.BadParameter(f"unknown methods {bad}; available: {', '.join(sorted(METHODS))}",
                                 param_hint="'--methods'")
    mod = _benchmark_module("bench_startup")
    mod.NO_SHIPPED[0] = no_shipped
    if n_latency:
        mod.latency(names, n_latency)
    else:
        mod.run(names, repeats)


def _mcap_out(ctx, param, value):
    """Callback of ``rld replay --out``: a writable ``.mcap`` file."""
    value = _out_file(ctx, param, value)
    if value is not None and Path(value).suffix.lower() != ".mcap":
        raise click.BadParameter(f"{value}: expected an .mcap file", ctx=ctx, param=param)
    return value


def _transform_option(ctx, param, value):
    """Callback of ``--transform PARENT,CHILD,X,Y,YAW``: a ``FrameTransform``."""
    if value is None:
        return None
    from rld.ros.convert import FrameTransform

    try:
        return FrameTransform.parse(value)
    except ValueError as exc:
        raise click.BadParameter(str(exc), ctx=ctx, param=param) from exc


@main.command()
@click.argument("in_path", metavar="IN", type=click.Path(exists=True))
@click.option("--cones", "cones_topic", required=True, metavar="TOPIC",
              help="Topic of the cone map: eufs_msgs/msg/ConeArrayWithCovariance (or "
                   "eufs_msgs/msg/ConeArray, geometry_msgs/msg/PoseArray, "
                   "geometry_msgs/msg/PolygonStamped); positions in metres.")
@click.option("--pose", "pose_topic", required=True, metavar="TOPIC",
              help="Topic of the car's pose: nav_msgs/msg/Odometry, "
                   "geometry_msgs/msg/PoseStamped or geometry_msgs/msg/PoseWithCovarianceStamped.")
@click.option("--out", required=True, metavar="OUT.mcap", callback=_mcap_out,
              help="The MCAP to write: the two input topics as recorded and the lanes.")
@click.option("--method", type=click.Choice(sorted(METHODS)), default=DEFAULT_METHOD,
              show_default=True, help=_METHOD_HELP)
@_BACKEND_OPTION
@_TIME_LIMIT_OPTION
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE", help=_PARAM_HELP)
@click.option("--spacing", "spacing_m", default=0.5, show_default=True, type=_METRES,
              help="Spacing of the centreline path's poses, metres.")
@click.option("--transform", default=None, metavar="PARENT,CHILD,X,Y,YAW",
              callback=_transform_option, show_default="none: the pose and the cones in one frame",
              help="Fixed transform between the pose's and the cones' frames: the pose of frame "
                   "CHILD in frame PARENT, x and y in metres, yaw in radians (either way round).")
@click.option("--out-ns", default="/rld", show_default=True, metavar="NAMESPACE",
              help="Namespace of the lane topics: NAMESPACE/centerline, /left, /right "
                   "(nav_msgs/msg/Path) and /markers (visualization_msgs/msg/MarkerArray).")
@click.option("--plot", "plot_path", default=None, metavar="FILE", callback=_image_file,
              show_default="none",
              help="Also draw a lap overview into this picture (PNG, or another format by "
                   "suffix).")
def replay(in_path: str, cones_topic: str, pose_topic: str, out: str, method: str,
           backend: str | None, time_limit_s: float | None, param_items: tuple[str, ...],
           spacing_m: float, transform, out_ns: str, plot_path: str | None) -> None:
    """Replay a recorded drive: the lane at every map message of IN, written to an MCAP.

    IN is a ROS 2 bag: a rosbag2 folder (MCAP or sqlite3) or a bare .mcap or .db3 file. At
    every message on --cones, one solver finds the lane ahead of the latest --pose logged at or
    before it. --out gets both input topics and, under --out-ns, the centreline, the two
    boundaries and markers; Foxglove opens it, and rviz2 shows it through ros2 bag play.
    Skipped messages (no cones, no pose yet, an unknown type, a truncated bag) are logged and
    counted in the summary. Needs pip install 'rld-lanes[ros]' (docs/ros.md)."""
    import importlib.util

    missing = [m for m in ("rosbags", "mcap") if importlib.util.find_spec(m) is None]
    if missing:
        raise UserError(f"rld replay needs {' and '.join(missing)}: pip install "
                        "'rld-lanes[ros]'")
    from tqdm import tqdm

    from rld.ros.bag import BagError
    from rld.ros.convert import FrameMismatch
    from rld.ros.replay import check_namespace
    from rld.ros.replay import replay as run_replay

    params = _params(param_items)
    try:
        check_namespace(out_ns)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="'--out-ns'") from exc
    if Path(out).resolve() == Path(in_path).resolve():
        raise click.BadParameter(f"{out} is the input bag", param_hint="'--out'")

    def log(line: str) -> None:
        tqdm.write(f"rld replay: {line}", file=sys.stderr)

    try:
        result = run_replay(in_path, out, cones_topic, pose_topic, method=method, params=params,
                            backend=backend, spacing_m=spacing_m, time_limit_s=time_limit_s,
                            transform=transform, out_ns=out_ns, progress=True, log=log)
    except FrameMismatch as exc:
        raise UserError(f"{in_path}: {exc} (--transform)") from exc
    except BagError as exc:
        raise UserError(str(exc)) from exc
    except OSError as exc:
        raise UserError(_os_error(exc)) from exc
    except ValueError as exc:
        raise UserError(str(exc)) from exc
    s = result.stats
    click.echo(f"bag         {in_path}: {cones_topic} (maps), {pose_topic} (poses)"
               + (f"; ended early: {result.problem}" if result.problem else ""))
    click.echo(f"method      {method}" + (f" (backend {backend})" if backend else ""))
    click.echo(s.summary())
    click.echo(f"output      {out}: {result.written} messages; lanes on "
               + ", ".join(result.topics.values()))
    if plot_path:
        from rld.ros.plot import plot_replay

        try:
            plot_replay(result, plot_path,
                        title=f"{method} replay of {Path(in_path).name}: {s.maps} maps, "
                              f"{s.found} lanes found, {sum(s.not_found.values())} not found, "
                              f"{sum(s.skipped.values())} skipped")
        except OSError as exc:
            raise UserError(_os_error(exc)) from exc
        click.echo(f"plot        {plot_path}")


if __name__ == "__main__":  # pragma: no cover
    main()

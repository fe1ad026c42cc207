"""The ``rld`` command line: ``rld demo`` and ``rld solve``."""

from __future__ import annotations

import sys
import time

import click

from rld.api import DEFAULT_METHOD, METHODS, solve_lane
from rld.types import Pose


def _parse_pose(text: str) -> Pose:
    try:
        x, y, yaw = (float(v) for v in text.split(","))
    except ValueError as exc:
        msg = f"expected x,y,yaw (metres, metres, radians), got {text!r}"
        raise click.BadParameter(msg) from exc
    return Pose(x, y, yaw)


def _summary(lane, elapsed_ms: float | None = None) -> str:
    from rld import geometry as geo

    lines = [f"status      {lane.status.name}" + (f" ({lane.message})" if lane.message else "")]
    if lane.ok:
        sides = (("left", lane.left, lane.left_xy), ("right", lane.right, lane.right_xy))
        for name, idx, xy in sides:
            lines.append(
                f"{name:<11} {idx.size:3d} cones, {geo.polyline_length(xy, lane.closed):6.1f} m: "
                f"{idx.tolist()}"
            )
        lines.append(f"cost        {lane.cost:.4g}")
        lines.append(f"closed      {lane.closed}")
    t = lane.stats.get("solve_time_s")
    if t is not None:
        lines.append(f"solve time  {1000 * t:.2f} ms")
    return "\n".join(lines)


@click.group(context_settings={"help_option_names": ["-h", "--help"]})
@click.version_option(package_name="rld-lanes")
def main() -> None:
    """rld: find the driving lane of a race track from 2D cone positions."""


@main.command()
@click.option("--seed", default=7, show_default=True, help="Seed of the generated track.")
@click.option("--fp-rate", default=0.2, show_default=True, help="False-positive rate, 0..1.")
@click.option("--range-m", default=30.0, show_default=True, help="Perception range, metres.")
@click.option("--method", type=click.Choice(sorted(METHODS)), default=DEFAULT_METHOD,
              show_default=True)
@click.option("--out", default="lane.png", show_default=True, help="Where to draw the scene.")
def demo(seed: int, fp_rate: float, range_m: float, method: str, out: str) -> None:
    """Solve a built-in example: a generated track, partly mapped, with false positives."""
    from rld.generator import generate_track
    from rld.metrics import score_lane
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
    click.echo(
        f"score       {score.category} (tolerant: {score.category_tolerant}), "
        f"IoU {score.iou:.2f}, IoU20 {score.iou20:.2f}, "
        f"length {score.pred_length_m:.1f} of {score.true_length_m:.1f} m"
    )
    plot_scene(
        frame.cones, lane=lane, pose=frame.pose, gt_left=frame.gt_left, gt_right=frame.gt_right,
        false_positive=frame.is_false_positive,
        title=f"{method} on {track.name}, pose {frame.index}: {score.category}", path=out,
    )
    click.echo(f"plot        {out}")


@main.command()
@click.argument("map_path", metavar="MAP", type=click.Path(exists=True, dir_okay=False))
@click.option("--pose", "pose_text", required=True, help="Car pose x,y,yaw (m, m, rad).")
@click.option("--method", type=click.Choice(sorted(METHODS)), default=DEFAULT_METHOD,
              show_default=True)
@click.option("--plot", "plot_path", default=None, help="Draw the scene into this PNG.")
def solve(map_path: str, pose_text: str, method: str, plot_path: str | None) -> None:
    """Find the lane in MAP (a dataset cone_map_K.yaml or our CSV) ahead of --pose."""
    from rld.tracks import load_map

    pose = _parse_pose(pose_text)
    try:
        track = load_map(map_path)
        lane = solve_lane(track.cones, pose, method=method)
    except ValueError as exc:
        raise click.ClickException(str(exc)) from exc
    click.echo(f"map         {map_path}: {track.cones.shape[0]} cones")
    click.echo(_summary(lane))
    if plot_path:
        from rld.plotting import plot_scene

        gt = (track.left, track.right) if track.left.size else (None, None)
        plot_scene(track.cones, lane=lane, pose=pose, gt_left=gt[0], gt_right=gt[1],
                   title=f"{method}: {lane.status.name}", path=plot_path)
        click.echo(f"plot        {plot_path}")
    if not lane.ok:
        sys.exit(1)


_PARAM_HELP = ("Override a LaneParams field, NAME=VALUE (repeatable), e.g. --param "
               "max_cone_spacing_m=6.0; the run's command line records it.")


def _params(items: tuple[str, ...]):
    """LaneParams from --param NAME=VALUE items (None when there are none)."""
    if not items:
        return None
    from rld.types import LaneParams

    try:
        return LaneParams.from_overrides(items)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--param") from exc


def _emit(text: str, out: str | None) -> None:
    """Print a benchmark's Markdown and, with ``--out``, also write it to that file."""
    click.echo(text)
    if out:
        with open(out, "w") as fh:
            fh.write(text + "\n")


def _benchmark_module(name: str):
    """Import ``benchmarks.NAME`` from the working directory or from this checkout."""
    import importlib
    from pathlib import Path

    for root in (Path.cwd(), Path(__file__).resolve().parents[1]):
        if (root / "benchmarks" / f"{name}.py").exists():
            if str(root) not in sys.path:
                sys.path.insert(0, str(root))
            return importlib.import_module(f"benchmarks.{name}")
    raise click.ClickException(
        "benchmarks/ not found: run `rld bench` from a checkout of the repository"
    )


@main.command("train-ranker")
@click.option("--generated", "n_generated", default=8, show_default=True,
              help="Generated tracks to train on (seeds 1000, 1001, ...).")
@click.option("--train-tracks", default="1,2,3", show_default=True,
              help="Shared dataset tracks to train on (the others are held out).")
@click.option("--fp-rates", default="0,0.1,0.3", show_default=True)
@click.option("--ranges", default="50", show_default=True, help="Perception ranges, metres.")
@click.option("--every", default=4, show_default=True, help="Every k-th pose of each lap.")
@click.option("--epochs", default=200, show_default=True)
@click.option("--max-iterations", default=2500, show_default=True,
              help="CLC's it_max while collecting candidates (the packaged model's; the "
                   "solver's default, 250, gave a worse ranker).")
@click.option("--seed", default=0, show_default=True)
@click.option("--out", default=None, help="Weights file (default: the packaged model).")
def train_ranker(n_generated: int, train_tracks: str, fp_rates: str, ranges: str, every: int,
                 epochs: int, max_iterations: int, seed: int, out: str | None) -> None:
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
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track
    from rld.types import LaneParams

    fps = [float(v) for v in fp_rates.split(",")]
    rs = [float(v) for v in ranges.split(",")]
    folder = find_dataset_dir()
    wanted = [int(v) for v in train_tracks.split(",") if v.strip()]
    shared = {k: load_dataset_track(folder, k) for k in DATASET_TRACKS} if folder else {}
    held = [shared[k] for k in DATASET_TRACKS if k not in wanted and k in shared]
    tracks = [generate_track(1000 + s) for s in range(n_generated)]
    tracks += [shared[k] for k in wanted if k in shared]
    if not tracks:
        raise click.ClickException("no tracks to train on")
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
    path = train.save_ranker(arrays, out or DEFAULT_MODEL, card)
    click.echo(f"wrote {path} and {path.with_suffix('.json')}")
    click.echo(f"mean IoU of the top pick: {scores}")


@main.command("eval")
@click.argument("dataset", required=False, type=click.Path(file_okay=False))
@click.option("--methods", default="rld,clc", show_default=True,
              help="Comma-separated method specs: name or name:option (rld:highs, clc:longest).")
@click.option("--tracks", "track_ids", default=None,
              help="Dataset track numbers (default: all the dataset has).")
@click.option("--generated", "n_generated", default=0, show_default=True,
              help="Also this many generated tracks (seeds 0, 1, ...; see --generated-seed).")
@click.option("--generated-seed", "first_generated", default=0, show_default=True,
              help="Seed of the first generated track (the ranker trains on 1000-1007, "
                   "`rld bench rld-paper` uses 11-15).")
@click.option("--ranges", default="30,50", show_default=True, help="Perception ranges, metres.")
@click.option("--fp-rates", default="0,0.1,0.3,0.5", show_default=True)
@click.option("--every", default=1, show_default=True, help="Every k-th pose of each lap.")
@click.option("--seed", default="0", show_default=True,
              help="Seed of the false positives, or several, comma-separated (0,1,2): the "
                   "tables pool them and a table gives each seed's critical rates.")
@click.option("--processes", default=None, type=int, help="Workers (default: CPU count).")
@click.option("--out", default="eval_out", show_default=True, help="Output folder.")
@click.option("--plot-failures", is_flag=True, help="Draw every critical failure.")
@click.option("--results", "results_page", default=None,
              help="Also write the results page (docs/results.md) here.")
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE", help=_PARAM_HELP)
def eval_cmd(dataset: str | None, methods: str, track_ids: str | None, n_generated: int,
             first_generated: int, ranges: str, fp_rates: str, every: int, seed: str,
             processes: int | None, out: str, plot_failures: bool,
             results_page: str | None, param_items: tuple[str, ...]) -> None:
    """Run the evaluation protocol (DESIGN.md) and write records, tables and plots."""
    import datetime
    import shlex
    from pathlib import Path

    from rld import report
    from rld.generator import generate_track
    from rld.tracks import DATASET_TRACKS, find_dataset_dir, load_dataset_track

    params = _params(param_items)
    try:
        specs = [report.parse_method(m) for m in methods.split(",") if m.strip()]
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--methods") from exc
    folder = Path(dataset) if dataset else find_dataset_dir()
    tracks = []
    if folder is not None and (track_ids or n_generated == 0):
        ids = [int(v) for v in track_ids.split(",")] if track_ids else list(DATASET_TRACKS)
        try:
            tracks += [load_dataset_track(folder, k) for k in ids]
        except FileNotFoundError as exc:
            raise click.ClickException(str(exc)) from exc
    tracks += [generate_track(first_generated + s) for s in range(n_generated)]
    if not tracks:
        raise click.ClickException("no tracks: give a dataset folder (or put the dataset in "
                                   "../shared/data/...) or --generated N")
    try:
        seeds = [int(v) for v in seed.split(",") if v.strip()]
    except ValueError as exc:
        raise click.BadParameter(f"seeds are integers, got {seed!r}",
                                 param_hint="--seed") from exc
    try:
        records = report.evaluate(
            tracks, specs, ranges=[float(v) for v in ranges.split(",")],
            fp_rates=[float(v) for v in fp_rates.split(",")], every=every, seed=seeds,
            processes=processes, params=params,
            plot_failures=str(Path(out) / "failures") if plot_failures else None)
    except ValueError as exc:
        raise click.BadParameter(str(exc)) from exc
    command = "rld eval " + " ".join(shlex.quote(a) for a in sys.argv[2:])
    header = (f"Command: `{command}`. Machine: {report.machine()}. "
              f"Date: {datetime.date.today().isoformat()}. Tracks: "
              f"{', '.join(t.name for t in tracks)}.")
    paths = report.write_outputs(records, out, header=header)
    click.echo(paths["results"].read_text())
    click.echo(f"wrote {out}/: poses.jsonl, summary.json, results.md, "
               + ", ".join(p.name for p in paths["plots"]))
    if results_page:
        import shutil

        page = Path(results_page)
        images = []
        for plot in paths["plots"]:
            target = page.parent / f"{page.stem}_{plot.name}"
            shutil.copyfile(plot, target)
            images.append(target.name)
        page.write_text(report.results_page(paths["rows"], header, images))
        click.echo(f"wrote {results_page} and its images")


@main.group()
def bench() -> None:
    """Run the benchmarks of benchmarks/ (from a checkout) and print their tables."""


@bench.command("rld")
@click.option("--method", type=click.Choice(["rld", "rld-sided"]), default="rld",
              show_default=True)
@click.option("--backends", default="cpsat,highs,cvxpy", show_default=True)
@click.option("--sizes", default="12,16,20,30,40", show_default=True, help="Cones per window.")
@click.option("--tracks", "n_tracks", default=4, show_default=True, help="Generated tracks.")
@click.option("--stride", default=25, show_default=True, help="Every k-th pose of each lap.")
@click.option("--time-limit", "time_limit_s", default=1.0, show_default=True,
              help="Budget per call, seconds.")
@click.option("--out", default=None, help="Also write the Markdown table to this file.")
def bench_rld(method: str, backends: str, sizes: str, n_tracks: int, stride: int,
              time_limit_s: float, out: str | None) -> None:
    """RLD latency per backend and window size, cold and warm-started."""
    mod = _benchmark_module("bench_rld")
    rows = mod.run(sizes=[int(v) for v in sizes.split(",")],
                   backends=[b.strip() for b in backends.split(",")],
                   n_tracks=n_tracks, stride=stride, time_limit_s=time_limit_s, method=method)
    table = mod.to_markdown(rows, time_limit_s)
    click.echo(f"machine: {mod.machine()}")
    _emit(table, out)


@bench.command("budget")
@click.option("--backends", default="cpsat,highs,cvxpy", show_default=True)
@click.option("--sizes", default="30,40", show_default=True, help="Cones per window.")
@click.option("--budgets", default="0.02,0.05,0.2", show_default=True, help="Seconds.")
@click.option("--tracks", "n_tracks", default=4, show_default=True, help="Generated tracks.")
@click.option("--stride", default=25, show_default=True, help="Every k-th pose of each lap.")
@click.option("--out", default=None, help="Also write the Markdown table to this file.")
def bench_budget(backends: str, sizes: str, budgets: str, n_tracks: int, stride: int,
                 out: str | None) -> None:
    """How far past its time budget an RLD call runs, per backend, size and budget."""
    mod = _benchmark_module("bench_rld")
    rows = mod.run_budget(sizes=[int(v) for v in sizes.split(",")],
                          budgets=[float(v) for v in budgets.split(",")],
                          backends=[b.strip() for b in backends.split(",")],
                          n_tracks=n_tracks, stride=stride)
    table = mod.budget_markdown(rows)
    click.echo(f"machine: {mod.machine()}")
    _emit(table, out)


@bench.command("rld-paper")
@click.option("--method", type=click.Choice(["rld", "rld-sided"]), default="rld",
              show_default=True)
@click.option("--backend", default="cpsat", show_default=True)
@click.option("--cones", "n_cones", default=12, show_default=True, help="Cones per window.")
@click.option("--poses", default=60, show_default=True, help="Poses per topology and ratio.")
@click.option("--seeds", default="0,1,2,3,4", show_default=True,
              help="Comma-separated seeds (tracks, noise, false positives), pooled.")
@click.option("--out", default=None, help="Also write the Markdown table to this file.")
@click.option("--param", "param_items", multiple=True, metavar="NAME=VALUE", help=_PARAM_HELP)
def bench_rld_paper(method: str, backend: str, n_cones: int, poses: int, seeds: str,
                    out: str | None, param_items: tuple[str, ...]) -> None:
    """RLD accuracy in the paper's experiment (fig. 7): topologies x false-positive ratios."""
    params = _params(param_items)  # checked here; the benchmark gets the names given
    names = {t.split("=", 1)[0].strip() for t in param_items}
    if "max_cones" in names:
        raise click.BadParameter("the window size is --cones", param_hint="--param")
    overrides = {k: getattr(params, k) for k in names}
    mod = _benchmark_module("bench_rld_paper")
    table = mod.to_markdown(mod.run(backend=backend, n_cones=n_cones, poses=poses,
                                    method=method,
                                    seeds=[int(v) for v in seeds.split(",") if v.strip()],
                                    **overrides))
    _emit(table, out)


@bench.command("protocol")
@click.option("--method", type=click.Choice(sorted(METHODS)), default="rld", show_default=True)
@click.option("--backend", default=None, help="RLD backend (default auto).")
@click.option("--fp-rates", default="0,0.3", show_default=True)
@click.option("--range-m", default=50.0, show_default=True)
@click.option("--every", default=12, show_default=True, help="Every k-th pose of each lap.")
@click.option("--time-limit", "time_limit_s", default=2.0, show_default=True)
@click.option("--out", default=None, help="Also write the Markdown table to this file.")
def bench_protocol(method: str, backend: str | None, fp_rates: str, range_m: float, every: int,
                   time_limit_s: float, out: str | None) -> None:
    """A method on the shared dataset tracks under the evaluation protocol (a sample)."""
    mod = _benchmark_module("bench_protocol")
    try:
        rows = mod.run(method=method, backend=backend,
                       fp_rates=[float(v) for v in fp_rates.split(",")], range_m=range_m,
                       every=every, time_limit_s=time_limit_s)
    except FileNotFoundError as exc:
        raise click.ClickException(str(exc)) from exc
    table = mod.to_markdown(rows)
    _emit(table, out)


@bench.command("incremental")
@click.option("--range-m", default=50.0, show_default=True, help="Perception range, metres.")
@click.option("--fp-rates", default="0,0.1,0.3", show_default=True)
@click.option("--every", default=1, show_default=True,
              help="Every k-th pose. The solver is stateful: keep 1 for real figures; k > 1 "
                   "only for quick runs (the car jumps k metres per call).")
@click.option("--tracks", "track_ids", default=",".join(str(k) for k in (1, 2, 3, 4, 6, 7)),
              show_default=True, help="Shared dataset track numbers.")
@click.option("--quick", is_flag=True, help="A tiny run: the first track, its first 50 poses.")
@click.option("--out", default=None, help="Also write the Markdown tables to this file.")
def bench_incremental(range_m: float, fp_rates: str, every: int, track_ids: str, quick: bool,
                      out: str | None) -> None:
    """Incremental RLD latency per map update and against the kept lane's length."""
    import shlex

    mod = _benchmark_module("bench_incremental")
    if not mod.dataset_available():
        click.echo("rld bench incremental: skipped, the racetrack dataset was not found (set "
                   "RLD_DATASET_DIR or put it in ../shared/data/fsd_racetrack_dataset)", err=True)
        return
    if every < 1:
        raise click.BadParameter("must be >= 1", param_hint="--every")
    try:
        records = mod.run(range_m=range_m, fp_rates=[float(v) for v in fp_rates.split(",")],
                          every=every, tracks=[int(v) for v in track_ids.split(",") if v.strip()],
                          quick=quick)
    except FileNotFoundError as exc:
        raise click.ClickException(str(exc)) from exc
    command = "rld bench incremental " + " ".join(shlex.quote(a) for a in sys.argv[3:])
    text = mod.to_markdown(records, range_m, command=command.strip())
    _emit(text, out)


@bench.command("clc")
@click.option("--ranges", default="30,50", show_default=True, help="Perception ranges, metres.")
@click.option("--fp-rates", default="0,0.1,0.3,0.5", show_default=True)
@click.option("--every", default=4, show_default=True, help="Every k-th pose of each lap.")
@click.option("--ranker", default=None, help="learned (default), rld_cost or longest.")
@click.option("--iterations/--no-iterations", default=True, show_default=True,
              help="Also latency against it_max and map size (fig. 16).")
@click.option("--out", default=None, help="Also write the Markdown tables to this file.")
def bench_clc(ranges: str, fp_rates: str, every: int, ranker: str | None, iterations: bool,
              out: str | None) -> None:
    """CLC latency, accuracy and completeness on the shared tracks (protocol of DESIGN.md)."""
    mod = _benchmark_module("bench_clc")
    try:
        rows = mod.run(ranges=[float(v) for v in ranges.split(",")],
                       fp_rates=[float(v) for v in fp_rates.split(",")], every=every,
                       ranker=ranker)
        parts = [mod.to_markdown(rows)]
        if iterations:
            parts.append(mod.iterations_markdown(mod.run_iterations(ranker=ranker)))
    except FileNotFoundError as exc:
        raise click.ClickException(str(exc)) from exc
    ct = mod.compile_time()
    parts.append("\n".join(f"- {k}: import {v['import_s']:.2f} s, first call "
                           f"{v['first_call_s']:.2f} s, second call "
                           f"{1000 * v['second_call_s']:.2f} ms" for k, v in ct.items()))
    text = "\n\n".join(parts)
    _emit(text, out)



@bench.command("clc-failures")
@click.option("--ranges", default="30,50", show_default=True, help="Perception ranges, metres.")
@click.option("--fp-rates", default="0.1,0.3", show_default=True)
@click.option("--seed", "seeds", default="0", show_default=True,
              help="Comma-separated seeds of the false positives, pooled.")
@click.option("--every", default=1, show_default=True, help="Every k-th pose of each lap.")
@click.option("--processes", default=2, show_default=True)
@click.option("--out", default=None, help="Also write the Markdown table to this file.")
def bench_clc_failures(ranges: str, fp_rates: str, seeds: str, every: int, processes: int,
                       out: str | None) -> None:
    """Where CLC's critical poses come from: the truth infeasible, the judge preferring the
    wrong lane, or the search never building the truth (benchmarks/bench_clc_failures.py)."""
    mod = _benchmark_module("bench_clc_failures")
    try:
        results = [mod.run(range_m=float(r), fp_rate=float(fp),
                           seeds=[int(s) for s in seeds.split(",")], every=every,
                           processes=processes)
                   for r in ranges.split(",") for fp in fp_rates.split(",")]
    except FileNotFoundError as exc:
        raise click.ClickException(str(exc)) from exc
    _emit(mod.to_markdown(results), out)


def _parse_cells(cells: str) -> list[tuple[float, float]]:
    """``--cells`` "30:0.1,50:0.3" -> [(30.0, 0.1), (50.0, 0.3)]; a usage error otherwise."""
    try:
        parsed = [tuple(float(v) for v in c.split(":")) for c in cells.split(",")]
        if any(len(c) != 2 for c in parsed):
            raise ValueError
    except ValueError as exc:
        raise click.BadParameter(f"{cells!r}: expected RANGE_M:FP_RATE,...",
                                 param_hint="--cells") from exc
    return parsed


@bench.command("fp-clearance")
@click.option("--clearances", default="0,0.5,1,1.5,2", show_default=True,
              help="Comma-separated least distances of the false positives from the true "
                   "boundary lines, metres (0: the experiment as it is).")
@click.option("--methods", default="clc,rld", show_default=True,
              help="clc (the protocol on the shared tracks), rld (the paper's experiment).")
@click.option("--cells", default="30:0.1,30:0.3,50:0.3", show_default=True,
              help="CLC's RANGE_M:FP_RATE cells, comma-separated.")
@click.option("--seed", "seeds", default="0,1,2,3,4", show_default=True,
              help="Comma-separated seeds, pooled.")
@click.option("--every", default=1, show_default=True, help="CLC: every k-th pose of each lap.")
@click.option("--processes", default=2, show_default=True)
@click.option("--out", default=None, help="Also write the Markdown tables to this file.")
@click.option("--plot", "plot_path", default=None,
              help="Also draw the rates against the clearance to this PNG.")
def bench_fp_clearance(clearances: str, methods: str, cells: str, seeds: str, every: int,
                       processes: int, out: str | None, plot_path: str | None) -> None:
    """How much of CLC's and RLD's failures come from false positives near the true
    boundaries: the accuracy experiments rerun with the false positives kept a distance from
    the true lines (benchmarks/bench_fp_clearance.py). An analysis, not a target."""
    mod = _benchmark_module("bench_fp_clearance")
    chosen = {m.strip() for m in methods.split(",") if m.strip()}
    if not chosen or chosen - {"clc", "rld"}:
        raise click.BadParameter(f"{methods!r}: use clc, rld or both", param_hint="--methods")
    try:
        cs = mod.parse_clearances(clearances)
    except ValueError as exc:
        raise click.BadParameter(str(exc), param_hint="--clearances") from exc
    parsed = _parse_cells(cells)
    seed_list = [int(s) for s in seeds.split(",") if s.strip()]
    try:
        clc_rows = (mod.run_clc(cs, seed_list, parsed, every, processes)
                    if "clc" in chosen else [])
        rld_rows = mod.run_rld(cs, seed_list) if "rld" in chosen else []
    except (FileNotFoundError, ValueError) as exc:
        raise click.ClickException(str(exc)) from exc
    _emit(mod.to_markdown(clc_rows, rld_rows), out)
    if plot_path:
        mod.plot(clc_rows, rld_rows, plot_path)
        click.echo(f"wrote {plot_path}")


@bench.command("clc-judge")
@click.option("--source", type=click.Choice(["shared", "generated"]), default="shared",
              show_default=True, help="The dataset tracks, or generated ones.")
@click.option("--tracks", default=None,
              help="Comma-separated track ids (shared: default all; generated: their seeds).")
@click.option("--cells", default="30:0.1,30:0.3,50:0.3", show_default=True,
              help="Comma-separated RANGE_M:FP_RATE cells.")
@click.option("--seed", "seeds", default="5", show_default=True,
              help="Comma-separated seeds of the false positives, pooled.")
@click.option("--every", default=1, show_default=True, help="Every k-th pose of each lap.")
@click.option("--fit", "fit_weights", is_flag=True,
              help="Also fit the judge's weights (leave one track out, and on all).")
@click.option("--processes", default=2, show_default=True)
@click.option("--out", default=None, help="Also write the Markdown table to this file.")
def bench_clc_judge(source: str, tracks: str | None, cells: str, seeds: str, every: int,
                    fit_weights: bool, processes: int, out: str | None) -> None:
    """How often CLC's dive judge picks a right lane when it has one, and what weights fitted
    to its decisions would do (benchmarks/bench_clc_judge.py)."""
    mod = _benchmark_module("bench_clc_judge")
    parsed = _parse_cells(cells)
    try:
        result = mod.run(source, [int(t) for t in tracks.split(",")] if tracks else None,
                         parsed, [int(s) for s in seeds.split(",")], every, fit_weights,
                         processes)
    except (FileNotFoundError, ValueError) as exc:
        raise click.ClickException(str(exc)) from exc
    _emit(mod.to_markdown(result), out)


if __name__ == "__main__":  # pragma: no cover
    main()


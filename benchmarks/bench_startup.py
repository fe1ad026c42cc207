"""Start-up cost per method (issue 42, item 3): a fresh process that imports ``rld`` and solves
one lane, once with the user's kernel cache empty (cold: a fresh install, which loads the kernels
its wheel ships, or compiles them without: ``--no-shipped``) and once more with the cache the
cold run left (warm). Each run is its own ``python -c`` process with ``RLD_CACHE_DIR`` set to a new
temporary folder (``NUMBA_CACHE_DIR`` removed, since it would win over ``RLD_CACHE_DIR``).

The frame (track 7, 30 m range, 20 % false positives, a third of the lap) is built once, in a
helper process with its own throwaway cache, and handed to every child as literals: a child only
imports ``rld`` and calls ``solve_lane``, as a car's process would (building a frame through
``rld.simulation`` compiles kernels of its own and would blur the split).

Reported per method, median over ``repeats``: whole-process wall time (interpreter start-up
included) and CPU time (user + system, steadier than the wall time on a busy machine), and
inside the wall time the time to import ``rld`` and the time of the first ``solve_lane``.

    python -m benchmarks.bench_startup [--repeats 3] [--methods rld,rld-incremental,clc,huang]
    python -m benchmarks.bench_startup --latency 50   # steady state: median of 50 solves

``--latency N`` instead reports the hot path: one process per method (its kernels compiled
into the usual cache first), then the median and the minimum of ``N`` repeated ``solve_lane``
calls on the same frame.
"""

from __future__ import annotations

import argparse
import json
import os
import resource
import statistics
import subprocess
import sys
import tempfile
import time

METHODS = ("rld", "rld-incremental", "clc", "huang")

#: Builds the frame and prints it as JSON (cones as a list of [x, y], pose as [x, y, yaw]).
FRAME = """
import json
from rld.generator import generate_track
from rld.simulation import simulate_lap
lap = simulate_lap(generate_track(7), range_m=30, fp_rate=0.2, seed=7)
f = lap.frame(len(lap) // 3)
pose = [float(f.pose.x), float(f.pose.y), float(f.pose.yaw)]
print(json.dumps({"cones": f.cones.tolist(), "pose": pose}))
"""

#: The child: imports rld, solves the frame once, prints its own split as JSON.
CHILD = """
import json, time
t0 = time.perf_counter()
import rld
t1 = time.perf_counter()
lane = rld.solve_lane({cones!r}, {pose!r}, method={method!r})
t2 = time.perf_counter()
print(json.dumps({{"import": t1 - t0, "solve": t2 - t1, "ok": bool(lane.ok)}}))
"""


#: Set by ``--no-shipped``: the children see no shipped kernels (an editable install's case).
NO_SHIPPED: list[bool] = [False]


def _child_env(cache: str) -> dict[str, str]:
    env = dict(os.environ)
    env.pop("NUMBA_CACHE_DIR", None)
    env["RLD_CACHE_DIR"] = cache
    if NO_SHIPPED[0]:
        env["RLD_KERNELS_DIR"] = os.path.join(cache, "no-shipped-kernels")
    return env


def shipped() -> str:
    """Whether the children load shipped kernels (README "Kernels and start-up"), in words."""
    code = "from rld._jit import shipped_dir, shipped_manifest; " \
           "print(shipped_manifest() is not None, shipped_dir())"
    with tempfile.TemporaryDirectory(prefix="rld-startup-") as cache:
        out = subprocess.run([sys.executable, "-c", code], env=_child_env(cache),
                             capture_output=True, text=True, check=True).stdout.strip()
    usable, _, where = out.partition(" ")
    return f"shipped kernels in {where}" if usable == "True" else f"none usable at {where}"


def frame() -> dict:
    """The benchmark's frame, ``{"cones": [[x, y], ...], "pose": [x, y, yaw]}``."""
    with tempfile.TemporaryDirectory(prefix="rld-startup-") as cache:
        out = subprocess.run([sys.executable, "-c", FRAME], env=_child_env(cache),
                             capture_output=True, text=True, check=True)
    return json.loads(out.stdout.strip().splitlines()[-1])


def run_once(method: str, cache: str, data: dict) -> dict[str, float]:
    """One fresh process solving ``data`` once with ``method`` and kernel cache ``cache``."""
    code = CHILD.format(method=method, cones=data["cones"], pose=data["pose"])
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    out = subprocess.run([sys.executable, "-c", code],
                         env=_child_env(cache), capture_output=True, text=True, check=True)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    row = json.loads(out.stdout.strip().splitlines()[-1])
    row["wall"] = wall
    # CPU seconds (user + system) of the child: on a busy machine the wall time grows with
    # the other processes' load, the CPU time much less.
    row["cpu"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return row


#: The floor of any later process: import numba and call one cached one-line kernel.
FLOOR_KERNEL = """
import numba


@numba.njit(cache=True)
def bump(x):
    return x + 1
"""

FLOOR = """
import json, sys, time
t0 = time.perf_counter()
sys.path.insert(0, {folder!r})
import numpy, numba
import floor_kernel
t1 = time.perf_counter()
floor_kernel.bump(1)
t2 = time.perf_counter()
print(json.dumps({{"import": t1 - t0, "solve": t2 - t1, "ok": True}}))
"""


def floor(repeats: int = 3) -> dict[str, float]:
    """The medians (wall, cpu, import, solve seconds) of a later process that only imports numba
    and calls one cached kernel: what no kernel-based method's later process can go below."""
    rows = []
    for _ in range(repeats):
        with tempfile.TemporaryDirectory(prefix="rld-startup-") as folder:
            with open(os.path.join(folder, "floor_kernel.py"), "w") as fh:
                fh.write(FLOOR_KERNEL)
            env = dict(os.environ, NUMBA_CACHE_DIR=os.path.join(folder, "cache"))
            code = FLOOR.format(folder=folder)
            for _ in range(2):  # the first compiles, the second is measured
                before = resource.getrusage(resource.RUSAGE_CHILDREN)
                t0 = time.perf_counter()
                out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True,
                                     text=True, check=True)
                wall = time.perf_counter() - t0
                after = resource.getrusage(resource.RUSAGE_CHILDREN)
            row = json.loads(out.stdout.strip().splitlines()[-1])
            row["wall"] = wall
            row["cpu"] = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
            rows.append(row)
    return {k: statistics.median(r[k] for r in rows) for k in ("wall", "cpu", "import", "solve")}


def run(methods=METHODS, repeats: int = 3) -> dict[str, dict[str, dict[str, float]]]:
    """``{method: {"cold": {...}, "warm": {...}}}``, each the median over ``repeats`` of
    ``wall``, ``cpu``, ``import`` and ``solve`` seconds; prints a Markdown table."""
    data = frame()
    print(f"kernels: {shipped()}")
    result: dict[str, dict[str, dict[str, float]]] = {}
    for m in methods:
        runs: dict[str, list[dict[str, float]]] = {"cold": [], "warm": []}
        for _ in range(repeats):
            with tempfile.TemporaryDirectory(prefix="rld-startup-") as cache:
                runs["cold"].append(run_once(m, cache, data))
                runs["warm"].append(run_once(m, cache, data))
        result[m] = {
            phase: {k: statistics.median(r[k] for r in rows)
                    for k in ("wall", "cpu", "import", "solve")}
            for phase, rows in runs.items()
        }
    print(f"| method | cold wall s | cold CPU s | cold import s | cold solve s | warm wall s "
          f"| warm CPU s | warm import s | warm solve s |  (median of {repeats})")
    print("|---|---:|---:|---:|---:|---:|---:|---:|---:|")
    for m, r in result.items():
        c, w = r["cold"], r["warm"]
        print(f"| {m} | {c['wall']:.2f} | {c['cpu']:.2f} | {c['import']:.2f} | {c['solve']:.2f} "
              f"| {w['wall']:.2f} | {w['cpu']:.2f} | {w['import']:.2f} | {w['solve']:.2f} |")
    f = floor(repeats)
    print(f"| numba floor (one cached one-line kernel) | | | | | {f['wall']:.2f} | {f['cpu']:.2f} "
          f"| {f['import']:.2f} | {f['solve']:.2f} |")
    result["numba-floor"] = {"warm": f}
    return result


LATENCY = """
import json, statistics, time
import rld
cones, pose = {cones!r}, {pose!r}
for _ in range(3):
    rld.solve_lane(cones, pose, method={method!r})
ts = []
for _ in range({n}):
    t0 = time.perf_counter()
    rld.solve_lane(cones, pose, method={method!r})
    ts.append(time.perf_counter() - t0)
print(json.dumps({{"median": statistics.median(ts), "min": min(ts)}}))
"""


def latency(methods=METHODS, n: int = 50) -> dict[str, dict[str, float]]:
    """``{method: {"median", "min"}}`` seconds of ``n`` repeated solves in one warm process
    (the kernels compiled into the default cache folder first); prints a Markdown table."""
    data = frame()
    result = {}
    for m in methods:
        code = LATENCY.format(method=m, cones=data["cones"], pose=data["pose"], n=n)
        out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                             check=True)
        result[m] = json.loads(out.stdout.strip().splitlines()[-1])
    print(f"| method | median ms | min ms |  ({n} solves)")
    print("|---|---:|---:|")
    for m, r in result.items():
        print(f"| {m} | {1e3 * r['median']:.2f} | {1e3 * r['min']:.2f} |")
    return result


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeats", type=int, default=3)
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--latency", type=int, default=0, metavar="N",
                    help="report the median of N warm solves per method instead")
    ap.add_argument("--json", help="also write the result to this file")
    ap.add_argument("--no-shipped", action="store_true",
                    help="hide the shipped kernels: cold = compile everything (editable install)")
    a = ap.parse_args(argv)
    NO_SHIPPED[0] = a.no_shipped
    if a.latency:
        res = latency(a.methods.split(","), a.latency)
    else:
        res = run(a.methods.split(","), a.repeats)
    if a.json:
        with open(a.json, "w") as fh:
            json.dump(res, fh, indent=1)


if __name__ == "__main__":
    main()

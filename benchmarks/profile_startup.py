"""Where a cold start's time goes: every numba compilation of one fresh process that solves
one lane (``benchmarks.bench_startup``'s frame) with an empty kernel cache.

Listens to numba's ``numba:compile`` event (fired only on a cache miss) and reports per kernel:
the number of signatures compiled, the inclusive and the exclusive seconds (a kernel's
compilation includes its callees' when they are compiled for the first time inside it).

    python -m benchmarks.profile_startup [--methods rld,clc] [--top 15]
"""

from __future__ import annotations

import argparse
import json
import subprocess
import sys
import tempfile

from benchmarks.bench_startup import METHODS, _child_env, frame

CHILD = """
import json, time
from numba.core import event as ev

stack, rows = [], []

class L(ev.Listener):
    def on_start(self, event):
        d = event.data["dispatcher"]
        stack.append([time.perf_counter(), 0.0,
                      d.py_func.__module__ + "." + d.py_func.__qualname__])

    def on_end(self, event):
        t0, child, name = stack.pop()
        dt = time.perf_counter() - t0
        if stack:
            stack[-1][1] += dt
        rows.append({{"kernel": name, "sig": str(event.data["args"]), "incl": dt,
                     "excl": dt - child, "parent": stack[-1][2] if stack else ""}})

ev.register("numba:compile", L())
t0 = time.perf_counter()
import rld
t1 = time.perf_counter()
rld.solve_lane({cones!r}, {pose!r}, method={method!r})
t2 = time.perf_counter()
print(json.dumps({{"import": t1 - t0, "solve": t2 - t1, "rows": rows}}))
"""


def profile(method: str, data: dict | None = None) -> dict:
    """``{"import", "solve", "kernels": [{kernel, n_sigs, sigs, incl, excl}, ...]}``, kernels
    sorted by exclusive seconds, descending."""
    data = data or frame()
    with tempfile.TemporaryDirectory(prefix="rld-startup-") as cache:
        code = CHILD.format(method=method, cones=data["cones"], pose=data["pose"])
        out = subprocess.run([sys.executable, "-c", code], env=_child_env(cache),
                             capture_output=True, text=True, check=True)
    res = json.loads(out.stdout.strip().splitlines()[-1])
    per: dict[str, dict] = {}
    for r in res.pop("rows"):
        k = per.setdefault(r["kernel"], {"kernel": r["kernel"], "sigs": [], "incl": 0.0,
                                         "excl": 0.0})
        k["sigs"].append(r["sig"] + (f"  <- {r['parent']}" if r["parent"] else ""))
        k["excl"] += r["excl"]
        k["incl"] = max(k["incl"], r["incl"])
    for k in per.values():
        k["n_sigs"] = len(k["sigs"])
    res["kernels"] = sorted(per.values(), key=lambda k: -k["excl"])
    return res


def main(argv=None) -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--methods", default=",".join(METHODS))
    ap.add_argument("--top", type=int, default=15)
    ap.add_argument("--sigs", action="store_true", help="print every signature")
    a = ap.parse_args(argv)
    data = frame()
    for m in a.methods.split(","):
        res = profile(m, data)
        ks = res["kernels"]
        total = sum(k["excl"] for k in ks)
        print(f"\n### {m}: import {res['import']:.2f} s, first solve {res['solve']:.2f} s, "
              f"{len(ks)} kernels / {sum(k['n_sigs'] for k in ks)} signatures compiled, "
              f"{total:.2f} s compiling")
        print("| kernel | sigs | excl s | incl s |")
        print("|---|---:|---:|---:|")
        for k in ks[:a.top]:
            print(f"| {k['kernel']} | {k['n_sigs']} | {k['excl']:.2f} | {k['incl']:.2f} |")
        if a.sigs:
            for k in ks:
                if k["n_sigs"] > 1:
                    print(k["kernel"], *k["sigs"], sep="\n    ")


if __name__ == "__main__":
    main()

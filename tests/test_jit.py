"""Where the package's numba kernels cache their machine code (``rld._jit``): outside the
installed sources, so uninstalling the package leaves no folder behind (issue 42)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
import textwrap
from pathlib import Path

import numba
from numba.core import config

import clc.search_kernels as sk
import rld.costs_kernels as ck
import rld.geometry_kernels as gk
import rld.huang_kernels as hk
from rld import _jit


def _cache_path(dispatcher) -> Path:
    return Path(dispatcher._cache._cache_path)


def test_every_kernel_module_caches_outside_the_sources():
    for mod, name in ((gk, "turn_angle"), (ck, "angle_costs"), (hk, "evidence_grid"),
                      (sk, "enumerate_pairs")):
        path = _cache_path(getattr(mod, name))
        source_dir = Path(mod.__file__).resolve().parent
        assert source_dir not in path.resolve().parents, (mod.__name__, path)
        assert path.is_relative_to(Path(_jit.cache_dir())), (mod.__name__, path)


def test_numba_setting_is_restored_for_other_code():
    assert config.CACHE_DIR == "" or "NUMBA_CACHE_DIR" in os.environ

    @_jit.njit(cache=True)
    def plus_one(x):
        return x + 1

    assert plus_one(1) == 2
    assert config.CACHE_DIR == "" or "NUMBA_CACHE_DIR" in os.environ

    @numba.njit(cache=True)
    def plus_two(x):
        return x + 2

    # A function of someone else's, defined after ours: numba's own default (next to its source).
    assert not _cache_path(plus_two).is_relative_to(Path(_jit.cache_dir()))


def test_bare_decorator_and_uncached():
    @_jit.njit
    def f(x):
        return 2 * x

    @_jit.njit(cache=False)
    def g(x):
        return 3 * x

    assert f(2) == 4 and g(2) == 6


def test_environment_choices(tmp_path):
    """RLD_CACHE_DIR chooses the folder; a user's NUMBA_CACHE_DIR wins over it."""
    code = textwrap.dedent("""
        import rld.geometry_kernels as gk
        print(gk.turn_angle._cache._cache_path)
    """)
    env = {k: v for k, v in os.environ.items() if k != "NUMBA_CACHE_DIR"}
    env["RLD_CACHE_DIR"] = str(tmp_path / "ours")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True).stdout.strip()
    assert Path(out).is_relative_to(tmp_path / "ours")
    env["NUMBA_CACHE_DIR"] = str(tmp_path / "theirs")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True).stdout.strip()
    assert Path(out).is_relative_to(tmp_path / "theirs")


# --- shipped kernels (README "Kernels and start-up") ------------------------------------------

_KERNEL = """
from rld._jit import njit


@njit(cache=True)
def bump(x):
    return x + {step}
"""

_RUN = """
import json, sys
sys.path.insert(0, {folder!r})
import kern
from rld import _jit
if {build}:
    (_jit.Path({ship!r}) / "manifest.json").write_text(json.dumps(_jit.build_manifest()))
asked = []
load = _jit._ShippedCache.load_overload
_jit._ShippedCache.load_overload = lambda self, *a: asked.append(1) or load(self, *a)
with _jit.host_kernels() if {host} else __import__("contextlib").nullcontext():
    value = kern.bump(1)
print(json.dumps({{"value": value, "hits": sum(kern.bump.stats.cache_hits.values()),
                  "shipped": len(asked)}}))
"""


def _run(tmp_path, *, step=1, build=False, host=False):
    """Run ``kern.bump(1)`` in a fresh process: as the wheel build (generic CPU, into ship/)
    or as a user (user cache in user/, shipped kernels in ship/); returns its value, its cache
    hits and how often the shipped kernels were asked."""
    folder = tmp_path / "src"
    (folder / "kern").mkdir(parents=True, exist_ok=True)
    (folder / "kern" / "__init__.py").write_text(_KERNEL.format(step=step))
    ship, user = tmp_path / "ship", tmp_path / "user"
    env = {k: v for k, v in os.environ.items() if not k.startswith("NUMBA_")}
    env.update(RLD_CACHE_DIR=str(user), RLD_KERNELS_DIR=str(ship))
    if build:
        env.update(NUMBA_CPU_NAME="generic", RLD_BUILD_KERNELS=str(ship))
    code = _RUN.format(folder=str(folder), build=build, ship=str(ship), host=host)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True,
                         check=True).stdout
    return json.loads(out.strip().splitlines()[-1])


def _compiled(folder: Path) -> int:
    return sum(1 for _ in folder.rglob("*.nbc")) if folder.exists() else 0


def test_a_user_process_loads_the_shipped_kernel_instead_of_compiling(tmp_path):
    assert _run(tmp_path, build=True) == {"value": 2, "hits": 0, "shipped": 0}
    assert _compiled(tmp_path / "ship" / "kern") == 1 and _compiled(tmp_path / "user") == 0
    assert _run(tmp_path) == {"value": 2, "hits": 1, "shipped": 1}
    assert _compiled(tmp_path / "user") == 0  # loaded, not compiled nor copied


def test_shipped_kernels_of_another_build_or_source_are_not_used(tmp_path):
    _run(tmp_path, build=True)
    # A manifest that does not match this process (another numpy): compiled here.
    manifest = json.loads((tmp_path / "ship" / "manifest.json").read_text())
    manifest["numpy"] = "0.0"
    (tmp_path / "ship" / "manifest.json").write_text(json.dumps(manifest))
    assert _run(tmp_path) == {"value": 2, "hits": 0, "shipped": 0}
    assert _compiled(tmp_path / "user") == 1
    # An edited source: its new code runs (numba's source hash), compiled into the user cache.
    _run(tmp_path, build=True)
    assert _run(tmp_path, step=5) == {"value": 6, "hits": 0, "shipped": 1}


def test_warmup_compiles_for_this_cpu_what_the_user_cache_lacks(tmp_path):
    _run(tmp_path, build=True)
    assert _run(tmp_path, host=True) == {"value": 2, "hits": 0, "shipped": 0}
    assert _compiled(tmp_path / "user") == 1
    assert _run(tmp_path) == {"value": 2, "hits": 1, "shipped": 0}


def test_the_user_cache_comes_first(tmp_path):
    assert _run(tmp_path) == {"value": 2, "hits": 0, "shipped": 0}  # nothing shipped: compiled
    assert _run(tmp_path, build=True) == {"value": 2, "hits": 0, "shipped": 0}
    assert _run(tmp_path) == {"value": 2, "hits": 1, "shipped": 0}
    assert _compiled(tmp_path / "user") == 1


def test_the_build_requires_what_compiling_the_shipped_kernels_imports():
    """setup.py's build_py runs ``rld.warmup`` in the build environment (pyproject's note)."""
    tomllib = __import__("pytest").importorskip("tomllib")
    project = tomllib.loads((Path(__file__).parents[1] / "pyproject.toml").read_text())
    assert set(project["project"]["dependencies"]) <= set(project["build-system"]["requires"])

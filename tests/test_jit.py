"""Where the package's numba kernels cache their machine code (``rld._jit``): outside the
installed sources, so uninstalling the package leaves no folder behind (issue 42)."""

from __future__ import annotations

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

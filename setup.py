"""Builds the wheel with the package's numba kernels compiled for the generic CPU of the
build machine's architecture (``rld._jit``), so a fresh install's first call loads them
instead of compiling (issue 42). ``RLD_SKIP_KERNELS=1`` builds without them;
``RLD_REQUIRE_KERNELS=1`` fails the build when they cannot be built (CI)."""

import os
import shutil
import subprocess
import sys
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py


class BuildPyWithKernels(build_py):
    """``build_py``, then ``python -m rld._build_kernels`` on the built sources (not for an
    editable install, whose kernels compile on first use into the user cache)."""

    def run(self):
        super().run()
        if self.editable_mode or os.environ.get("RLD_SKIP_KERNELS"):
            return
        lib = Path(self.build_lib).resolve()
        out = lib / "rld" / "_kernels"
        shutil.rmtree(out, ignore_errors=True)  # an earlier build's kernels
        env = {k: v for k, v in os.environ.items()
               if k not in ("NUMBA_CACHE_DIR", "NUMBA_CPU_FEATURES", "NUMBA_DISABLE_JIT")}
        # pip's isolated build environment reaches the child through PYTHONPATH: keep it.
        path = os.pathsep.join(p for p in (str(lib), os.environ.get("PYTHONPATH")) if p)
        env.update(PYTHONPATH=path, NUMBA_CPU_NAME="generic", RLD_BUILD_KERNELS=str(out),
                   MPLBACKEND="Agg")
        done = subprocess.run([sys.executable, "-m", "rld._build_kernels"], env=env, cwd=lib)
        if done.returncode != 0 and os.environ.get("RLD_REQUIRE_KERNELS"):
            raise RuntimeError("rld: building the shipped kernels failed (RLD_REQUIRE_KERNELS)")
        if done.returncode != 0:  # the wheel still works: its kernels compile on first use
            print("rld: building the shipped kernels failed; the package compiles them on "
                  "first use instead", file=sys.stderr)
            shutil.rmtree(out, ignore_errors=True)


setup(cmdclass={"build_py": BuildPyWithKernels})

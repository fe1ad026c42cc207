"""Compile the shipped kernels (``rld._jit``) into a folder: run by ``setup.py``'s ``build_py``
in a child process with ``NUMBA_CPU_NAME=generic`` and ``RLD_BUILD_KERNELS`` set to the folder.

    NUMBA_CPU_NAME=generic RLD_BUILD_KERNELS=OUT python -m rld._build_kernels
"""

from __future__ import annotations

import json
import os
import sys
import time
from pathlib import Path


def main() -> int:
    """Solve ``rld.warmup``'s frames with every method, then write ``manifest.json``."""
    from numba.core import config

    from rld._jit import BUILD_ENV, build_manifest
    from rld.warmup import warmup

    out = os.environ.get(BUILD_ENV)
    if not out or str(config.CPU_NAME).lower() != "generic" or config.CPU_FEATURES:
        print(f"set {BUILD_ENV} and NUMBA_CPU_NAME=generic (and no NUMBA_CPU_FEATURES)",
              file=sys.stderr)
        return 2
    t0 = time.perf_counter()
    seconds = warmup()
    (Path(out) / "manifest.json").write_text(json.dumps(build_manifest(), indent=1) + "\n")
    kernels = sum(1 for _ in Path(out).rglob("*.nbc"))
    print(f"rld: {kernels} compiled kernels in {out} ({time.perf_counter() - t0:.0f} s: "
          + ", ".join(f"{m} {s:.0f} s" for m, s in seconds.items()) + ")")
    return 0


if __name__ == "__main__":
    sys.exit(main())

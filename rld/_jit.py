"""``njit`` for the package's kernel modules: numba's ``njit`` with its on-disk cache kept in a
user cache folder instead of ``__pycache__`` beside the installed sources.

numba's default cache (``cache=True``) writes ``*.nbi`` / ``*.nbc`` files into
``site-packages/rld/__pycache__``; pip does not record them, so uninstalling the package (as
``pip install -e .`` does before an editable install) leaves that folder behind, and Python then
imports ``rld`` as an empty namespace package. Here the cache goes to ``cache_dir()``:
``$NUMBA_CACHE_DIR`` when the user set it (numba's own rule), else ``$RLD_CACHE_DIR``, else
``$XDG_CACHE_HOME/rld/numba`` (``~/.cache/rld/numba``), else a folder in the temp dir. Only
the kernels defined through this decorator are affected: numba's setting is restored after each
definition, so other numba code of the same process keeps numba's defaults.
"""

from __future__ import annotations

import functools
import os
import tempfile
from pathlib import Path

import numba
from numba.core import config

__all__ = ["cache_dir", "njit"]


def _writable(path: Path) -> bool:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(path, os.W_OK)


def cache_dir() -> str:
    """The folder that holds the package's compiled kernels (see the module docstring)."""
    if config.CACHE_DIR:
        return str(config.CACHE_DIR)
    return _own_cache_dir()


@functools.cache
def _own_cache_dir() -> str:
    env = os.environ.get("RLD_CACHE_DIR")
    xdg = os.environ.get("XDG_CACHE_HOME") or str(Path.home() / ".cache")
    for cand in ([env] if env else []) + [str(Path(xdg) / "rld" / "numba")]:
        if _writable(Path(cand)):
            return cand
    user = os.getuid() if hasattr(os, "getuid") else 0
    return str(Path(tempfile.gettempdir()) / f"rld-numba-{user}")


def njit(*args, **options):
    """``numba.njit`` (same arguments) whose ``cache=True`` writes into ``cache_dir()``."""
    if args and callable(args[0]):  # used bare: @njit
        return njit(**options)(args[0])

    def wrap(func):
        if not options.get("cache"):
            return numba.njit(*args, **options)(func)
        previous = config.CACHE_DIR
        # numba picks a function's cache folder when the dispatcher is made (its
        # UserProvidedCacheLocator reads config.CACHE_DIR then), so setting it for the
        # definition alone is enough.
        config.CACHE_DIR = cache_dir()
        try:
            return numba.njit(*args, **options)(func)
        finally:
            config.CACHE_DIR = previous

    return wrap

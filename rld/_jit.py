"""``njit`` for the package's kernels: numba's ``njit`` with its cache in a user folder (never
beside the installed sources), backed by the kernels a wheel ships precompiled for the generic
CPU of its architecture. Lookup order and checks: README "Kernels and start-up"."""

from __future__ import annotations

import contextlib
import functools
import json
import os
import platform
import sys
import tempfile
from pathlib import Path

import numba
import numpy as np
from numba.core import config

try:  # numba's caching internals (stable since numba 0.49; checked by tests/test_jit.py)
    from numba.core.caching import (
        Cache,
        CompileResultCacheImpl,
        _CacheLocator,
        _SourceFileBackedLocatorMixin,
    )
except ImportError:  # pragma: no cover - a numba without them: plain user-folder cache
    Cache = None

__all__ = ["BUILD_ENV", "cache_dir", "host_kernels", "njit", "shipped_dir", "shipped_manifest"]

#: Environment variable naming the folder a wheel build compiles the shipped kernels into.
BUILD_ENV = "RLD_BUILD_KERNELS"


def _writable(path: Path) -> bool:
    try:
        path.mkdir(parents=True, exist_ok=True)
    except OSError:
        return False
    return os.access(path, os.W_OK)


def cache_dir() -> str:
    """The folder that holds the package's kernels compiled on this machine (module docstring)."""
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


def shipped_dir() -> Path:
    """The shipped kernels' folder: ``$RLD_KERNELS_DIR``, else ``rld/_kernels`` (may not exist)."""
    env = os.environ.get("RLD_KERNELS_DIR")
    return Path(env) if env else Path(__file__).resolve().parent / "_kernels"


def build_manifest() -> dict[str, str]:
    """What shipped kernels must match: numba, numpy ``major.minor``, Python, architecture."""
    return {"numba": numba.__version__, "numpy": ".".join(np.__version__.split(".")[:2]),
            "python": f"{sys.version_info[0]}.{sys.version_info[1]}",
            "machine": platform.machine(), "cpu": "generic"}


#: While True (``host_kernels``), kernels missing from the user cache compile for this CPU.
_HOST_ONLY = [False]


@contextlib.contextmanager
def host_kernels():
    """Within: compile what the user cache lacks for this CPU instead of loading the shipped
    generic kernels (``rld warmup``: a car's kernels tuned to its CPU, found first later)."""
    previous, _HOST_ONLY[0] = _HOST_ONLY[0], True
    try:
        yield
    finally:
        _HOST_ONLY[0] = previous


@functools.cache
def shipped_manifest() -> dict[str, str] | None:
    """The shipped kernels' manifest when they exist and match this process, else None."""
    try:
        manifest = json.loads((shipped_dir() / "manifest.json").read_text())
    except (OSError, ValueError):
        return None
    return manifest if manifest == build_manifest() else None


if Cache is not None:

    class _UserLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
        """``cache_dir()``/<numba's per-source-folder subpath>; the build's folder in a build."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            build = os.environ.get(BUILD_ENV)
            if build:  # the wheel build: the shipped layout, one folder per package
                self._path = os.path.join(build, Path(py_file).resolve().parent.name)
            else:
                self._path = os.path.join(cache_dir(), self.get_suitable_cache_subpath(py_file))

        def get_cache_path(self):
            return self._path

    class _ShippedLocator(_SourceFileBackedLocatorMixin, _CacheLocator):
        """``shipped_dir()``/<package>, read only."""

        def __init__(self, py_func, py_file):
            self._py_file = py_file
            self._lineno = py_func.__code__.co_firstlineno
            self._path = str(shipped_dir() / Path(py_file).resolve().parent.name)

        def get_cache_path(self):
            return self._path

        @classmethod
        def from_function(cls, py_func, py_file):
            return cls(py_func, py_file) if os.path.exists(py_file) else None

    class _UserImpl(CompileResultCacheImpl):
        _locator_classes = [_UserLocator]

    class _ShippedImpl(CompileResultCacheImpl):
        _locator_classes = [_ShippedLocator]

    class _UserCache(Cache):
        _impl_class = _UserImpl

    class _ShippedCache(Cache):
        _impl_class = _ShippedImpl

        def _index_key(self, sig, codegen):
            # The build compiled for numba's generic CPU (NUMBA_CPU_NAME=generic, no features).
            sig, _, code = super()._index_key(sig, codegen)
            return sig, (codegen.magic_tuple()[0], "generic", ""), code

        def save_overload(self, sig, data):
            return None

    class KernelCache(_UserCache):
        """The user cache (loads and saves), backed by the shipped kernels (loads only)."""

        def __init__(self, py_func):
            super().__init__(py_func)
            use_shipped = shipped_manifest() is not None and not os.environ.get(BUILD_ENV)
            self._shipped = _ShippedCache(py_func) if use_shipped else None

        def load_overload(self, sig, target_context):
            data = super().load_overload(sig, target_context)
            if data is None and self._shipped is not None and not _HOST_ONLY[0]:
                data = self._shipped.load_overload(sig, target_context)
            return data


def njit(*args, **options):
    """``numba.njit`` (same arguments) whose ``cache=True`` uses ``KernelCache``."""
    if args and callable(args[0]):  # used bare: @njit
        return njit(**options)(args[0])

    def wrap(func):
        if not options.get("cache"):
            return numba.njit(*args, **options)(func)
        if Cache is not None and not config.DISABLE_JIT:
            dispatcher = numba.njit(*args, **{**options, "cache": False})(func)
            if hasattr(dispatcher, "_cache"):
                dispatcher._cache = KernelCache(func)
                return dispatcher
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

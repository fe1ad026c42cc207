"""Shared fixtures: the racetrack dataset (skipped cleanly when ../shared is absent) and the
hypothesis profile (deterministic in CI)."""

from __future__ import annotations

import os

import pytest
from hypothesis import settings

from rld.tracks import find_dataset_dir

settings.register_profile("ci", derandomize=True, deadline=None, print_blob=True)
settings.register_profile("dev", deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")


@pytest.fixture(scope="session")
def dataset_dir():
    path = find_dataset_dir()
    if path is None:
        pytest.skip("racetrack dataset not found (../shared/data/fsd_racetrack_dataset)")
    return path

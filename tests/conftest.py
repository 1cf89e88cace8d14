"""Shared test set-up: rendering runs headless; optimal energies are cached in a temporary directory."""

import os
import tempfile
from typing import Any

import pytest

os.environ.setdefault("SDL_VIDEODRIVER", "dummy")
os.environ.setdefault("SDL_AUDIODRIVER", "dummy")
# One thread per test process (torch reads this when first imported): pytest -n 2 then uses the two cores it is
# given instead of oversubscribing them (a 10 s PPO test took 130 s with torch's default threads on a shared machine).
os.environ.setdefault("OMP_NUM_THREADS", "1")
# The tests never read or write the user's cache of optimal energies (~/.cache/dwr-gym).
os.environ.setdefault("DWR_GYM_CACHE", tempfile.mkdtemp(prefix="dwr-gym-test-cache-"))
# Nor the optima shipped for the default sets: the tests solve what they measure (test_shipped_optima.py reads them).
os.environ.setdefault("DWR_GYM_SHIPPED_OPTIMA", "0")
# Nor the user's Minari datasets (~/.minari/datasets): the docs' snippets write one.
os.environ.setdefault("MINARI_DATASETS_PATH", tempfile.mkdtemp(prefix="dwr-gym-test-minari-"))


@pytest.fixture
def ticking_clock() -> Any:
    """A stand-in for the time module whose clock advances 10 s at each reading, from 0 in each test."""

    class Clock:
        now = 0.0

        @classmethod
        def time(cls) -> float:
            cls.now += 10.0
            return cls.now

    return Clock

"""Shared test set-up: rendering runs headless; optimal energies are cached in a temporary directory."""

import functools
import os
import re
import subprocess
import sys
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


# --- tests marked `own_process` (those that start a local Ray) run in a Python process of their own -------------------
# Ray's driver ends its whole process (exit 1, no traceback) when its local cluster's daemons die, which a loaded CI
# machine can cause: in one process with the other tests, that ended the whole `pytest -m slow` run after 14 of its
# 19 tests without a word. In a child process, the crash fails that one test with the child's output, and a child that
# crashed without a test result (not a test that failed) is run once more, saying so.
OWN_PROCESS = "DWR_GYM_TEST_IN_OWN_PROCESS"
# the cluster's health checks tolerate a machine too busy to answer for a while (Ray's defaults give up after ~15 s)
RAY_PATIENCE = {"RAY_health_check_failure_threshold": "40", "RAY_health_check_timeout_ms": "30000"}


def _run_in_own_process(item: pytest.Item) -> None:
    command = [sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider", "-o", "addopts=", item.nodeid]
    environment = {**os.environ, **RAY_PATIENCE, OWN_PROCESS: "1"}
    outputs = []
    for attempt in (1, 2):
        child = subprocess.run(command, cwd=item.config.rootpath, env=environment, capture_output=True, text=True)
        output = child.stdout + child.stderr
        outputs.append(f"--- attempt {attempt}, exit code {child.returncode} ---\n{output}")
        if child.returncode == 0 and re.search(r"\b1 skipped", output) and "passed" not in output:
            pytest.skip(next((line for line in output.splitlines() if line.startswith("SKIPPED")), "skipped there"))
        if child.returncode == 0:
            if attempt == 2:
                print(f"{item.nodeid}: the first process crashed without a result, the second passed:\n{outputs[0]}")
            return
        if re.search(r"\b\d+ (failed|error)", output):  # a result: the test failed, no second try
            break
    pytest.fail("the test's own process did not pass:\n" + "\n".join(outputs), pytrace=False)


def pytest_collection_modifyitems(config: pytest.Config, items: list[pytest.Item]) -> None:
    if os.environ.get(OWN_PROCESS):
        return
    for item in items:
        if item.get_closest_marker("own_process") is not None:
            item.runtest = functools.partial(_run_in_own_process, item)  # type: ignore[method-assign]

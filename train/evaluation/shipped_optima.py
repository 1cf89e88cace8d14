"""The optima of the default scenario sets, shipped with dwr-gym: a read-only cache with a check.

``dwr-gym compare`` and ``dwr-gym evaluate`` measure every policy against the minimum-energy plan of each episode
(:mod:`train.evaluation.optimum`), some 1,000 CasADi solves with their default sets, minutes on two cores. Their
energies for those default sets are shipped in ``train/optima/`` (one file per problem, as the user's cache is keyed:
the time step, the limits, whether the heading is part of the goal, the cache's version), so that a fresh clone's first
``compare`` solves none of them. They are only a cache:

- a key is read only where the user's own cache has none, and only for the very problem it was solved for (the file's
  name is the user cache's name for that problem, and its ``problem`` record is checked against it);
- ``dwr-gym optimum verify`` solves every shipped plan again and compares the energies (1e-6 relative by default), and
  a test does so for a random sample;
- any other set, n, seed or env is solved as before; ``DWR_GYM_SHIPPED_OPTIMA=0`` turns the shipped ones off.

``python -m benchmarks run ship-optima`` writes the files from the commands' defaults.
"""

from __future__ import annotations

import functools
import json
import math
import os
from pathlib import Path
from typing import Any

#: Where the shipped optima live (package data of ``train``).
SHIPPED_DIR = Path(__file__).resolve().parents[1] / "optima"
#: ``DWR_GYM_SHIPPED_OPTIMA=0`` makes every command solve what the user's cache lacks, as without shipped optima.
SWITCH = "DWR_GYM_SHIPPED_OPTIMA"
PROBLEM_KEYS = ("cache_version", "dt", "u_max", "omega_max", "heading")


class ShippedOptimaError(ValueError):
    """A shipped optimum file that does not hold what it must (a broken install or a hand edit)."""


def shipped_enabled() -> bool:
    """Whether the shipped optima are read (``DWR_GYM_SHIPPED_OPTIMA`` is not ``0``)."""
    return os.environ.get(SWITCH, "1") != "0"


def problem_record(cache_version: int, dt: float, u_max: float, omega_max: float, heading: bool) -> dict[str, Any]:
    """The problem an optimum file was solved for, as the file records it."""
    return dict(
        zip(PROBLEM_KEYS, (cache_version, float(dt), float(u_max), float(omega_max), bool(heading)), strict=True)
    )


def read_shipped(path: Path) -> tuple[dict[str, Any], dict[str, float]]:
    """The problem and the energies by cache key of the shipped file ``path``, checked: every energy finite and >= 0,
    every key four numbers (the start in the goal's frame and T_con)."""
    try:
        data = json.loads(path.read_text())
        problem, energies = data["problem"], data["energies"]
    except (OSError, ValueError, KeyError, TypeError) as error:
        raise ShippedOptimaError(f"{path}: not a shipped optimum file ({error})") from None
    if set(problem) != set(PROBLEM_KEYS):
        raise ShippedOptimaError(f"{path}: its problem has keys {sorted(problem)}, expected {sorted(PROBLEM_KEYS)}")
    for key, energy in energies.items():
        if len(key.split(",")) != 4 or not isinstance(energy, float) or not math.isfinite(energy) or energy < 0:
            raise ShippedOptimaError(
                f"{path}: entry {key!r}: {energy!r} is not an optimum (expected a finite energy >= 0)"
            )
    return problem, energies


@functools.cache
def _shipped(name: str) -> tuple[dict[str, Any], dict[str, float]]:
    """The shipped file ``name``'s problem and energies, read and checked once per process (empty where none)."""
    path = SHIPPED_DIR / name
    return read_shipped(path) if path.is_file() else ({}, {})


def shipped_energies(cache_name: str, problem: dict[str, Any]) -> dict[str, float]:
    """The shipped energies of the user cache file named ``cache_name`` (empty when none is shipped or they are
    turned off), checked to be for ``problem`` (:func:`problem_record`)."""
    if not shipped_enabled():
        return {}
    recorded, energies = _shipped(cache_name)
    if energies and recorded != problem:  # the same file name for another problem: a hash collision or a hand edit
        raise ShippedOptimaError(f"{SHIPPED_DIR / cache_name}: solved for {recorded}, not for {problem}")
    return energies


def shipped_files() -> list[Path]:
    """Every shipped optimum file."""
    return sorted(SHIPPED_DIR.glob("optimal-energy-*.json"))


def write_shipped(path: Path, problem: dict[str, Any], energies: dict[str, float]) -> None:
    """Write a shipped optimum file (sorted keys, so that a rewrite of the same optima is the same file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(json.dumps({"problem": problem, "energies": dict(sorted(energies.items()))}, indent=0) + "\n")


__all__ = [
    "SHIPPED_DIR",
    "SWITCH",
    "ShippedOptimaError",
    "problem_record",
    "read_shipped",
    "shipped_enabled",
    "shipped_energies",
    "shipped_files",
    "write_shipped",
]

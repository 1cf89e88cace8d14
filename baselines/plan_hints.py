"""Which guess wins each planner plan of ``dwr-gym compare``'s defaults, shipped: a fresh clone solves one guess a plan.

A minimum-energy plan is not convex, so :func:`baselines.optimal.solve_minimum_energy` solves it from 2-4 cold guesses
and keeps the cheapest. On a fresh clone (no plan store yet) that search is most of ``compare``'s time beyond a
warm run's: 44 % of its solver time went to guesses that lose. ``baselines/plan_hints.npz`` names, for every plan
of ``compare``'s default sets whose search solved more than one guess, the guess the search keeps; a planner that
meets that very job (:func:`baselines.nmpc.job_key`, bit for bit) solves that guess alone. A solve is a pure function
of its guess, so the plan is the search's to the last bit, and so are the tables. A search in which no guess converges
(some 2 % of them, each guess to its iteration limit) is named with its error, which the planner then returns unsolved.
It is only a cache:

- it is read only by the solver it was recorded with (:func:`solver_digest`: the solver's code and CasADi's version);
  any other solver searches every guess, as does any job it does not name;
- a hinted guess that does not converge falls back to the whole search;
- ``python -m benchmarks run ship-plan-hints --check`` runs ``compare``'s whole search again and compares every
  winner, and a test does so for a sample; ``DWR_GYM_PLAN_HINTS=0`` turns the hints off.

``python -m benchmarks run ship-plan-hints`` writes the file: ``compare`` with every plan solved by the whole search
(no plan store, no hints) and ``DWR_GYM_PLAN_HINTS_RECORD=<dir>``, where each solving process writes the winners.
"""

from __future__ import annotations

import ast
import functools
import hashlib
import json
import os
from pathlib import Path
from typing import NamedTuple

import numpy as np

from baselines.optimal import OptimalControlError, Plan

#: The shipped hints (package data of ``baselines``).
HINTS_PATH = Path(__file__).resolve().with_name("plan_hints.npz")
#: ``DWR_GYM_PLAN_HINTS=0`` makes every plan search all its guesses.
SWITCH = "DWR_GYM_PLAN_HINTS"
#: A directory: each process that solves a plan by the whole search writes its winner there (``ship-plan-hints``).
RECORD = "DWR_GYM_PLAN_HINTS_RECORD"
#: The bytes of a job's key a hint is kept by (of its 32: a clash is 1 in 2^64 per pair).
KEY_BYTES = 16
#: The winner the file records for a search in which no guess converges (its error message is kept beside).
NO_PLAN = 255
#: A hint: the winning guess, or the error of a search that finds no plan.
Hint = int | str


def hints_enabled() -> bool:
    """Whether the shipped hints are read (``DWR_GYM_PLAN_HINTS`` is not ``0``)."""
    return os.environ.get(SWITCH, "1") != "0"


class HintFile(NamedTuple):
    """A hint file's content: the digest of the solver it was recorded with, that solver's CasADi version, the hints."""

    solver: str
    casadi: str
    hints: dict[bytes, Hint]


def read_hints(path: Path) -> HintFile:
    """The solver digest, CasADi version and hints by key prefix of the hint file ``path``."""
    with np.load(path, allow_pickle=False) as data:
        keys, winners, solver, casadi = data["keys"], data["winners"], str(data["solver"]), str(data["casadi"])
        errors = json.loads(str(data["errors"]))
    if keys.shape != (len(winners), KEY_BYTES) or len(errors) != int((winners == NO_PLAN).sum()):
        raise ValueError(f"{path}: not a plan hint file (keys {keys.shape}, winners {winners.shape})")
    hints: dict[bytes, Hint] = {key.tobytes(): int(w) for key, w in zip(keys, winners, strict=True)}
    hints.update({bytes.fromhex(key): message for key, message in errors.items()})
    return HintFile(solver, casadi, hints)


def write_hints(path: Path, solver: str, casadi: str, hints: dict[bytes, Hint]) -> None:
    """Write ``hints`` (by key prefix) recorded with the solver of digest ``solver`` (CasADi ``casadi``) to ``path``,
    sorted by key."""
    keys = sorted(hints)
    winners = np.array([NO_PLAN if isinstance(hints[k], str) else hints[k] for k in keys], dtype=np.uint8)
    errors = {k.hex(): hints[k] for k in keys if isinstance(hints[k], str)}
    np.savez_compressed(path, keys=np.frombuffer(b"".join(keys), dtype=np.uint8).reshape(len(keys), KEY_BYTES),
                        winners=winners, errors=np.array(json.dumps(errors)), solver=np.array(solver),
                        casadi=np.array(casadi))  # fmt: skip


def solver_digest() -> str:
    """What a winner depends on: the solver's code (baselines/optimal.py's syntax tree: its layout and comments do not
    count) and CasADi's version (16 hex digits)."""
    import casadi

    import baselines.optimal

    code = ast.dump(ast.parse(Path(baselines.optimal.__file__).read_text()))
    return hashlib.sha256(f"{code}/{casadi.__version__}".encode()).hexdigest()[:16]


@functools.cache
def _shipped() -> dict[bytes, Hint]:
    """The shipped winners, where they were recorded with this solver (else none), read once per process."""
    if not HINTS_PATH.is_file():
        return {}
    shipped = read_hints(HINTS_PATH)
    return shipped.hints if shipped.solver == solver_digest() else {}


def hint(key: bytes) -> Hint | None:
    """The guess that wins the search of the job with :func:`baselines.nmpc.job_key` ``key`` (or the error of a
    search that finds no plan), where shipped."""
    return _shipped().get(key[:KEY_BYTES]) if hints_enabled() else None


def record(key: bytes, result: Plan | Exception) -> None:
    """Write the winner of a whole search of more than one guess, or the error of one that found no plan, to
    ``$DWR_GYM_PLAN_HINTS_RECORD``, where set."""
    directory = os.environ.get(RECORD)
    if isinstance(result, Plan):
        line = f"{result.candidate}" if result.tried > 1 else ""
    else:
        line = "!" + json.dumps(str(result)) if isinstance(result, OptimalControlError) else ""
    if directory and line:
        with open(Path(directory) / f"{os.getpid()}.txt", "a") as handle:
            handle.write(f"{key[:KEY_BYTES].hex()} {line}\n")


def read_recorded(directory: Path) -> dict[bytes, Hint]:
    """The hints the processes wrote to ``directory`` (:func:`record`); a job met twice has one."""
    hints: dict[bytes, Hint] = {}
    for path in sorted(Path(directory).glob("*.txt")):
        for line in path.read_text().splitlines():
            key, found = line.split(" ", 1)
            hints[bytes.fromhex(key)] = json.loads(found[1:]) if found.startswith("!") else int(found)
    return hints


__all__ = ["HINTS_PATH", "KEY_BYTES", "NO_PLAN", "RECORD", "SWITCH", "HintFile", "hint", "hints_enabled", "read_hints",
           "read_recorded", "record", "solver_digest", "write_hints"]  # fmt: skip

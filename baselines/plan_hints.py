"""Which guess wins each planner plan of ``dwr-gym compare``'s defaults, shipped: a fresh clone solves one guess a plan.

A minimum-energy plan is not convex, so :func:`baselines.optimal.solve_minimum_energy` solves it from 2-4 cold guesses
and keeps the cheapest. On a fresh clone (no plan store yet) that search is most of ``compare``'s time beyond a
warm run's: 44 % of its solver time went to guesses that lose. ``baselines/plan_hints.npz`` names, for every plan
of ``compare``'s default sets whose search solved more than one guess, the guess the search keeps; a planner that
meets that job (:func:`hint_key`: its numbers to 10 significant digits) solves that guess alone. A solve is a pure
function of its guess, so on the machine the file was recorded on the plan is the search's to the last bit, and so are
the tables. A search in which no guess converges (some 2 % of them, each guess to its iteration limit) is named with
its error, which the planner then returns unsolved. It is only a cache:

- why 10 digits, not the job's bits: the planners re-plan from poses their rollouts reached, and numpy's sines and
  cosines differ in the last bits between CPUs (its SIMD code is picked by processor), so on another machine those
  jobs differ from the recorded ones in the 15th-16th digit, and a bit-exact key names few of them. There the hinted
  guess is the search's winner unless two guesses' plans cost nearly the same. A search that found no plan is named
  by the job's bits alone: whether a nearly infeasible problem converges can turn on them. The ``robust`` agent's jobs
  come from its float32 network, whose outputs can differ from CPU to CPU in the 7th digit (MKL's kernels): only the
  machines the file was recorded on have hints for those (``ship-plan-hints --merge`` adds a machine's);
- a re-plan warm-started from the plan before has no winner named (it converges from that start, one guess);

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
import pickle
from pathlib import Path
from typing import Any, NamedTuple

import numpy as np

from baselines.optimal import OptimalControlError, Plan

#: The shipped hints (package data of ``baselines``).
HINTS_PATH = Path(__file__).resolve().with_name("plan_hints.npz")
#: ``DWR_GYM_PLAN_HINTS=0`` makes every plan search all its guesses.
SWITCH = "DWR_GYM_PLAN_HINTS"
#: A directory: each process that solves a plan by the whole search writes its winner there (``ship-plan-hints``).
RECORD = "DWR_GYM_PLAN_HINTS_RECORD"
#: The bytes of a job's digest a hint is kept by (of its 32: a clash is 1 in 2^64 per pair).
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


#: Significant digits of a job's numbers in its :func:`hint_key`.
DIGITS = 10


def _rounded(value: Any) -> Any:
    """``value`` with every float in it to :data:`DIGITS` significant digits (tuples and lists element by element)."""
    if isinstance(value, (float, np.floating)):
        return float(f"{float(value):.{DIGITS}g}")
    if isinstance(value, (tuple, list)):
        return tuple(_rounded(item) for item in value)
    return value


def hint_key(job: dict[str, Any]) -> bytes | None:
    """The key a hint of the :func:`baselines.optimal.solve_minimum_energy` job ``job`` is kept by: a digest of its
    keywords with their numbers to :data:`DIGITS` significant digits (the same job on another CPU, whose numpy differs
    in the last bits, has the same key; a float and a numpy float of one value too); None for a warm-started job,
    which has no hint."""
    if job.get("warm_start") is not None:
        return None
    items = sorted((name, _rounded(value)) for name, value in job.items())
    return hashlib.sha256(pickle.dumps(items, protocol=5)).digest()[:KEY_BYTES]


def hint(job: dict[str, Any], exact: bytes) -> Hint | None:
    """The guess that wins the search of ``job`` (by :func:`hint_key`), or the error of a search that found no plan
    (by ``exact``, the job's :func:`baselines.nmpc.job_key`: whether a nearly infeasible problem converges turns on
    its last bits), where shipped."""
    if not hints_enabled():
        return None
    key = hint_key(job)
    winner = None if key is None else _shipped().get(key)
    if isinstance(winner, int):
        return winner
    error = _shipped().get(exact[:KEY_BYTES])
    return error if isinstance(error, str) else None


def record(job: dict[str, Any], exact: bytes, result: Plan | Exception) -> None:
    """Write the winner of a whole search of more than one guess (by :func:`hint_key`), or the error of one that found
    no plan (by ``exact``, the job's bits), to ``$DWR_GYM_PLAN_HINTS_RECORD``, where set."""
    directory = os.environ.get(RECORD)
    key = hint_key(job)
    if isinstance(result, Plan):
        line = f"{result.candidate}" if result.tried > 1 and key is not None else ""
    else:
        line = "!" + json.dumps(str(result)) if isinstance(result, OptimalControlError) else ""
        key = exact[:KEY_BYTES]
    if directory and line:
        with open(Path(directory) / f"{os.getpid()}.txt", "a") as handle:
            handle.write(f"{key.hex()} {line}\n")  # type: ignore[union-attr]


def read_recorded(directory: Path) -> dict[bytes, Hint]:
    """The hints the processes wrote to ``directory`` (:func:`record`); a job met twice has one."""
    hints: dict[bytes, Hint] = {}
    for path in sorted(Path(directory).glob("*.txt")):
        for line in path.read_text().splitlines():
            key, found = line.split(" ", 1)
            hints[bytes.fromhex(key)] = json.loads(found[1:]) if found.startswith("!") else int(found)
    return hints


__all__ = ["DIGITS", "HINTS_PATH", "KEY_BYTES", "NO_PLAN", "RECORD", "SWITCH", "HintFile", "hint", "hint_key",
           "hints_enabled", "read_hints", "read_recorded", "record", "solver_digest", "write_hints"]  # fmt: skip

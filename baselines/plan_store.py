"""The planners' plans kept on disk: a second ``dwr-gym compare`` (or ``evaluate``) takes the plans the first solved.

``optimal``, ``robust-pt`` and the ``robust`` agent solve a minimum-energy problem each time they plan
(:func:`baselines.optimal.solve_minimum_energy`), thousands per ``compare``, and most of its time goes there. A solve is
a pure function of its job (the same plan to the last bit, whatever was solved before it; :data:`baselines.nmpc._MEMO`
relies on it within one process), so a command that meets a job again, in a later run, may take the plan solved before
instead of solving it: the same rollouts to the last digit, in a fraction of the time (a new agent compared with the
controllers, the same command run again).

:class:`PlanStore` keeps the plans by :func:`baselines.nmpc.job_key` in ``$DWR_GYM_CACHE/plans-<solver>/`` (default
``~/.cache/dwr-gym``), where ``<solver>`` is a digest of :mod:`baselines.optimal`'s and
:mod:`baselines.minimum_energy_nlp`'s source, CasADi's version, :data:`STORE_VERSION` and the code paths' switches
(:data:`CODE_PATH_SWITCHES`): a changed solver, or one on other kernels, never reads another's plans.
Each process writes its new plans to files of its own (``<pid>-<n>.npz``, an atomic replace), every
:data:`FLUSH_EVERY` plans and when the store closes, so an interrupted command keeps what it solved and two commands
may write at once. ``DWR_GYM_PLAN_CACHE=0`` turns it off;
delete the directory to solve afresh (some 3 kB a plan: 56 MB for ``compare``'s defaults, 20,209 plans).
"""

from __future__ import annotations

import hashlib
import json
import os
from collections.abc import Iterator
from contextlib import contextmanager
from pathlib import Path

import numpy as np

from baselines.optimal import InfeasibleArrivalTimeError, OptimalControlError, Plan

#: Bump when what a stored plan holds changes (2: the guess it was solved from and the guesses its search solved).
STORE_VERSION = 2
#: ``DWR_GYM_PLAN_CACHE=0`` turns the store off.
SWITCH = "DWR_GYM_PLAN_CACHE"
#: New plans written to a file of their own once this many are pending (an interruption loses fewer).
FLUSH_EVERY = 500
#: The switches of the numerical libraries' code paths (train.code_paths): a plan is kept per setting of them.
CODE_PATH_SWITCHES = (
    "NPY_DISABLE_CPU_FEATURES",
    "GLIBC_TUNABLES",
    "MKL_CBWR",
    "ONEDNN_MAX_CPU_ISA",
    "ATEN_CPU_CAPABILITY",
)
#: The errors a solve returns, by name: a stored error is raised again as the same class with the same message.
ERRORS = {cls.__name__: cls for cls in (OptimalControlError, InfeasibleArrivalTimeError)}


def solver_digest() -> str:
    """What a stored plan depends on: the search's and the NLP's source, CasADi's version and the store's format (16
    hex digits)."""
    import casadi

    import baselines.minimum_energy_nlp
    import baselines.optimal

    source = b"".join(Path(m.__file__).read_bytes() for m in (baselines.optimal, baselines.minimum_energy_nlp))
    paths = "/".join(os.environ.get(name, "") for name in CODE_PATH_SWITCHES)  # other kernels, other last bits
    return hashlib.sha256(source + f"{casadi.__version__}/{STORE_VERSION}/{paths}".encode()).hexdigest()[:16]


def default_directory() -> Path:
    """``$DWR_GYM_CACHE/plans-<solver_digest>`` (default ``~/.cache/dwr-gym``)."""
    root = Path(os.environ.get("DWR_GYM_CACHE") or Path.home() / ".cache" / "dwr-gym")
    return root / f"plans-{solver_digest()}"


class PlanStore:
    """Plans (or their errors) by job key, read from ``directory`` at first use, new ones written there by
    :meth:`flush` (only by the process that opened the store: a forked child's copy writes nothing until
    :meth:`adopt` makes it its own)."""

    def __init__(self, directory: Path):
        self.directory = Path(directory)
        self._known: dict[bytes, Plan | Exception] | None = None
        self._new: dict[bytes, Plan | Exception] = {}
        self._owner = os.getpid()
        self._files = 0

    def _load(self) -> dict[bytes, Plan | Exception]:
        if self._known is None:
            self._known = {}
            for path in sorted(self.directory.glob("*.npz")):
                try:
                    self._known.update(read_plans(path))
                except (OSError, ValueError, KeyError):
                    continue  # a damaged file: its plans are solved again
        return self._known

    def get(self, key: bytes) -> Plan | Exception | None:
        """The plan of job ``key`` stored before, or None."""
        return self._load().get(key)

    def add(self, key: bytes, result: Plan | Exception) -> None:
        """Keep a result just solved (written by the next :meth:`flush`, at once when enough are pending)."""
        self._load()[key] = result
        self._new[key] = result
        if len(self._new) >= FLUSH_EVERY:
            self.flush()

    def adopt(self) -> None:
        """In a forked child: write the plans this process solves from now on to files of its own (not the parent's
        pending ones, which the parent writes)."""
        self._owner, self._new, self._files = os.getpid(), {}, 0

    def flush(self) -> None:
        """Write the pending plans to a new file of this process (atomic: a reader sees all of it or none)."""
        if not self._new or os.getpid() != self._owner:
            return
        self.directory.mkdir(parents=True, exist_ok=True)
        path = self.directory / f"{os.getpid()}-{self._files}.npz"
        while path.exists():  # a process of the same id before this one
            self._files += 1
            path = self.directory / f"{os.getpid()}-{self._files}.npz"
        write_plans(path, self._new)
        self._files += 1
        self._new = {}


def write_plans(path: Path, results: dict[bytes, Plan | Exception]) -> None:
    """The results as one ``.npz`` of flat arrays (no pickle): keys, each plan's decision vector and numbers, errors."""
    keys = list(results)
    plans = [results[k] for k in keys]
    solutions = [p.solution if isinstance(p, Plan) else np.zeros(0) for p in plans]
    numbers = np.array([[p.interval, p.energy, p.solve_time] if isinstance(p, Plan) else [0.0, 0.0, 0.0]
                        for p in plans], dtype=np.float64).reshape(-1, 3)  # fmt: skip
    counts = np.array([[p.intervals, p.iterations, p.candidate, p.tried] if isinstance(p, Plan) else [-1, 0, -1, 0]
                       for p in plans], dtype=np.int64).reshape(-1, 4)  # fmt: skip
    errors = json.dumps({str(i): [type(p).__name__, str(p)] for i, p in enumerate(plans) if not isinstance(p, Plan)})
    temporary = path.with_name(f".{path.name}.tmp")
    with temporary.open("wb") as handle:
        np.savez(handle, keys=np.frombuffer(b"".join(keys), dtype=np.uint8).reshape(len(keys), -1),
                 lengths=np.array([len(s) for s in solutions], dtype=np.int64),
                 solutions=np.concatenate([np.zeros(0), *solutions]), numbers=numbers, counts=counts,
                 errors=np.array(errors))  # fmt: skip
    os.replace(temporary, path)


def read_plans(path: Path) -> dict[bytes, Plan | Exception]:
    """The results :func:`write_plans` wrote to ``path``: each plan as the solve returned it, to the last bit."""
    with np.load(path, allow_pickle=False) as data:
        keys, lengths, solutions = data["keys"], data["lengths"], data["solutions"]
        numbers, counts, errors = data["numbers"], data["counts"], json.loads(str(data["errors"]))
    ends = np.cumsum(lengths)
    found: dict[bytes, Plan | Exception] = {}
    for i, key in enumerate(keys):
        if str(i) in errors:
            name, message = errors[str(i)]
            found[key.tobytes()] = ERRORS[name](message)
            continue
        solution = solutions[ends[i] - lengths[i] : ends[i]]
        padded = (solution.size - 3) // 5  # 3 (intervals + 1) states and 2 intervals commands
        planned = int(counts[i, 0])
        states = solution[: 3 * (padded + 1)].reshape(padded + 1, 3)
        commands = solution[3 * (padded + 1) :].reshape(padded, 2)
        interval, energy, solve_time = (float(v) for v in numbers[i])
        found[key.tobytes()] = Plan(commands[:planned], states[: planned + 1], interval, energy, int(counts[i, 1]),
                                    solve_time, solution, int(counts[i, 2]), int(counts[i, 3]))  # fmt: skip
    return found


def _casadi_installed() -> bool:
    try:
        import casadi  # noqa: F401
    except ImportError:  # no planner can run: nothing to store
        return False
    return True


def has_plans(directory: Path | None = None) -> bool:
    """Whether the store at ``directory`` (default :func:`default_directory`) holds plans an earlier command wrote;
    False where it is off (``DWR_GYM_PLAN_CACHE=0``) or CasADi is missing: the planners will solve every plan."""
    if os.environ.get(SWITCH, "1") == "0" or not _casadi_installed():
        return False
    return any((directory or default_directory()).glob("*.npz"))


#: The store :class:`baselines.nmpc.PlanPool` reads and adds to: None (the default) keeps plans in memory only.
_OPEN: list[PlanStore] = []


def current() -> PlanStore | None:
    """The store opened by :func:`opened`, if any."""
    return _OPEN[-1] if _OPEN else None


@contextmanager
def opened(directory: Path | None = None) -> Iterator[PlanStore | None]:
    """Planners read plans from and add plans to the store at ``directory`` (default :func:`default_directory`) while
    this runs; what they solved is written when it ends, also by an error or Ctrl-C. Nothing with
    ``DWR_GYM_PLAN_CACHE=0``, or inside another :func:`opened` (the outer one serves)."""
    if os.environ.get(SWITCH, "1") == "0" or _OPEN or not _casadi_installed():
        yield current()
        return
    store = PlanStore(directory or default_directory())
    _OPEN.append(store)
    try:
        yield store
    finally:
        _OPEN.remove(store)
        try:
            store.flush()
        except OSError:  # a full or read-only disk: the plans are solved again next time
            pass


__all__ = ["FLUSH_EVERY", "STORE_VERSION", "SWITCH", "PlanStore", "current", "default_directory", "has_plans",
           "opened"]  # fmt: skip
